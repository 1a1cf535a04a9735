//! Evaluating one setting on one scene (stage 3): runs, the error against the reference, the
//! wall time and the solver's effort.
use super::*;

/// Bisection of the overturning amplitude in [2, 12] m/s² to `tol`.
pub(super) fn overturning(overturns: impl Fn(f64) -> bool, tol: f64) -> f64 {
    let (mut safe, mut fail) = (2.0, 12.0);
    if overturns(safe) || !overturns(fail) {
        return f64::NAN;
    }
    while fail - safe > tol {
        let mid = 0.5 * (safe + fail);
        if overturns(mid) {
            fail = mid;
        } else {
            safe = mid;
        }
    }
    0.5 * (safe + fail)
}

/// Outcome of one run: frames of the observed block (t, x, y, θ) and the summary.
pub(super) struct Measured {
    pub(super) frames: Vec<(f64, f64, f64, f64)>,
    pub(super) summary: crate::analysis::run::Summary,
    pub(super) over_budget: bool,
}

pub(super) fn run_once(
    bench: &Bench,
    setting: &Setting,
    motion: &GroundMotion,
    observed: usize,
    budget: f64,
    stop_rotation: Option<f64>,
) -> Result<Measured, StudyError> {
    let mut v = bench.scene.clone();
    v["control"] = setting.control(bench.duration);
    let scene = scene_from_value(&v)?;
    let frames = Mutex::new(Vec::new());
    let record = |f: &Frame| {
        let b = &f.blocks[observed];
        if let Ok(mut fr) = frames.lock() {
            fr.push((f.time, b.x, b.y, b.rotation));
        }
    };
    let start = Instant::now();
    let stop = |tr: &crate::analysis::run::Tracker| {
        start.elapsed().as_secs_f64() > budget
            || stop_rotation.is_some_and(|r| tr.max_rotation.iter().any(|m| *m > r))
    };
    let reduced_params = setting.reduced_rtol.map(|rtol| ReducedParams {
        tolerance: Tolerance {
            rtol,
            atol: rtol * 1e-2,
        },
        ..ReducedParams::default()
    });
    // The benchmarks' references are states at the benchmark's duration (a block still sliding
    // down its incline, a column's rotation at 3 s): no settling continuation after it.
    let opts = RunOptions {
        on_frame: Some(&record),
        stop_when: Some(&stop),
        reduced_params,
        run_end: Some(crate::analysis::run_end::RunEndParams {
            max_extension: 0.0,
            ..Default::default()
        }),
        ..Default::default()
    };
    let out = run(&scene, motion, &opts)?;
    let over_budget =
        start.elapsed().as_secs_f64() > budget && out.summary.stopped_reason.is_some();
    Ok(Measured {
        frames: frames.into_inner().unwrap_or_default(),
        summary: out.summary,
        over_budget,
    })
}

pub(super) fn history_error(
    frames: &[(f64, f64, f64, f64)],
    reference: &[(f64, f64)],
    pick: impl Fn(&(f64, f64, f64, f64)) -> f64,
    until: f64,
) -> Option<f64> {
    let peak = reference
        .iter()
        .filter(|p| p.0 <= until + 1e-9)
        .fold(0.0f64, |m, p| m.max(p.1.abs()));
    let mut worst = 0.0f64;
    let mut n = 0;
    for f in frames.iter().filter(|f| f.0 <= until + 1e-9) {
        // Reference samples are on the same 0.01 s grid.
        let k = (f.0 / 0.01).round() as usize;
        let Some(r) = reference.get(k) else { continue };
        if (r.0 - f.0).abs() > 1e-6 {
            continue;
        }
        worst = worst.max((pick(f) - r.1).abs());
        n += 1;
    }
    (n > 0 && peak > 0.0).then_some(worst / peak)
}

pub(super) struct Evaluated {
    pub(super) error: Option<f64>,
    pub(super) value: Option<f64>,
    pub(super) summary: crate::analysis::run::Summary,
    pub(super) note: String,
    pub(super) wall: f64,
    pub(super) steps: u64,
}

pub(super) fn evaluate(
    bench: &Bench,
    setting: &Setting,
    reference_frames: Option<&[(f64, f64)]>,
    opts: &StudyOptions,
) -> Result<Evaluated, StudyError> {
    let budget = opts.point_budget_s;
    match &bench.metric {
        Metric::Overturning { exact, tolerance } => {
            // Each bisection run stops once the column passes 1 rad (beyond its 0.32 rad
            // tipping angle: decided).
            let t0 = Instant::now();
            let mut steps = 0;
            let mut last = None;
            let mut failure = None;
            let mut overturns = |a: f64| {
                if failure.is_some() || t0.elapsed().as_secs_f64() > budget {
                    failure.get_or_insert_with(|| "over budget".to_string());
                    return false;
                }
                match run_once(bench, setting, &pulse(a), 1, budget, Some(1.0)) {
                    Ok(m) => {
                        steps += m.summary.steps;
                        let fell = m.summary.blocks[0].max_rotation > 1.0;
                        last = Some(m.summary);
                        fell
                    }
                    Err(e) => {
                        failure = Some(e.to_string());
                        false
                    }
                }
            };
            let (mut safe, mut fail) = OVERTURN_BRACKET;
            let bracket = widen_bracket(&mut overturns, &mut safe, &mut fail);
            while bracket && fail - safe > *tolerance {
                let mid = 0.5 * (safe + fail);
                if overturns(mid) {
                    fail = mid;
                } else {
                    safe = mid;
                }
            }
            let summary = last.ok_or_else(|| {
                StudyError::NoRun(failure.clone().unwrap_or_else(|| "no run".into()))
            })?;
            let wall = t0.elapsed().as_secs_f64();
            if let Some(f) = failure {
                return Ok(Evaluated {
                    error: None,
                    value: None,
                    summary,
                    note: f,
                    wall,
                    steps,
                });
            }
            if !bracket {
                return Ok(Evaluated {
                    error: None,
                    value: None,
                    summary,
                    note: format!(
                        "no overturning change in [{}, {}] m/s²",
                        OVERTURN_BRACKET.0 / WIDEN_LIMIT,
                        OVERTURN_BRACKET.1 * WIDEN_LIMIT
                    ),
                    wall,
                    steps,
                });
            }
            let found = 0.5 * (safe + fail);
            Ok(Evaluated {
                error: Some(((found - exact) / exact).abs()),
                value: Some(found),
                summary,
                note: format!("overturning amplitude {found:.3} m/s²"),
                wall,
                steps,
            })
        }
        metric => {
            let observed = match metric {
                Metric::Finest { observed, .. } => *observed,
                _ => 1,
            };
            let m = run_once(bench, setting, &bench.motion, observed, budget, None)?;
            let wall = m.summary.wall_time_s;
            let steps = m.summary.steps;
            if m.over_budget || !m.summary.completed {
                let note = if m.over_budget {
                    format!(
                        "over the {budget} s budget at t = {:.2} s",
                        m.summary.simulated_time
                    )
                } else {
                    m.summary.stopped_reason.clone().unwrap_or_default()
                };
                return Ok(Evaluated {
                    error: None,
                    value: None,
                    summary: m.summary,
                    note,
                    wall,
                    steps,
                });
            }
            let peak = |pick: fn(&(f64, f64, f64, f64)) -> f64, until: f64| {
                m.frames
                    .iter()
                    .filter(|f| f.0 <= until + 1e-9)
                    .fold(0.0f64, |a, f| a.max(pick(f).abs()))
            };
            let mut value = None;
            let error = match metric {
                Metric::FinalAlong { dir, exact } => {
                    let d = m
                        .summary
                        .blocks
                        .iter()
                        .find(|b| b.id == "block")
                        .map(|b| b.final_displacement)
                        .unwrap_or([0.0; 2]);
                    let along = d[0] * dir[0] + d[1] * dir[1];
                    value = Some(along);
                    Some(((along - exact) / exact).abs())
                }
                Metric::HistoryX { reference } => {
                    value = Some(peak(|f| f.1, f64::INFINITY));
                    history_error(&m.frames, reference, |f| f.1, f64::INFINITY)
                }
                Metric::Rotation { reference, until } => {
                    value = Some(peak(|f| f.3, *until));
                    history_error(&m.frames, reference, |f| f.3, *until)
                }
                Metric::Finest { .. } => {
                    value = Some(peak(|f| f.1, f64::INFINITY));
                    reference_frames
                        .and_then(|r| history_error(&m.frames, r, |f| f.1, f64::INFINITY))
                }
                Metric::Overturning { .. } => None,
            };
            Ok(Evaluated {
                error,
                value,
                summary: m.summary,
                note: String::new(),
                wall,
                steps,
            })
        }
    }
}

/// m/s², the first bracket of the overturning-amplitude search: around the exact amplitudes of
/// the study's pulses (5–6 m/s²), so a setting near the answer costs no extra runs.
const OVERTURN_BRACKET: (f64, f64) = (4.0, 8.0);
/// How far the bracket may widen (down by this factor from its lower end, up by it from its upper
/// end) when a coarse setting overturns below it or not at all within it: a point far from the
/// answer then gets its (large) error value instead of none.
const WIDEN_LIMIT: f64 = 8.0;

/// Make `[safe, fail]` a bracket (`safe` stands, `fail` overturns), doubling outwards from the
/// first one up to [`WIDEN_LIMIT`]; false when none is found (or a run failed: `overturns` then
/// answers false and the caller reports the failure).
fn widen_bracket(overturns: &mut impl FnMut(f64) -> bool, safe: &mut f64, fail: &mut f64) -> bool {
    let (low, high) = (
        OVERTURN_BRACKET.0 / WIDEN_LIMIT,
        OVERTURN_BRACKET.1 * WIDEN_LIMIT,
    );
    if overturns(*safe) {
        *fail = *safe;
        while *safe / 2.0 >= low {
            *safe /= 2.0;
            if !overturns(*safe) {
                return true;
            }
            *fail = *safe;
        }
        return false;
    }
    while !overturns(*fail) {
        *safe = *fail;
        if *fail * 2.0 > high {
            return false;
        }
        *fail *= 2.0;
    }
    true
}
