//! The reduced rocking model (`"model": "rocking"`, `analysis::reduced`) against two
//! independent methods on the rocking column of Yagoda-Biran & Hatzor 2015, §3.3 (b = 0.2 m, h = 0.6 m, half-sine
//! pulse a(t) = A sin 2πt for 0 ≤ t ≤ 0.5 s):
//! 1. Housner's equation integrated by fixed-step RK4 (Δt = 1e-5 s) with Housner's
//!    restitution e = 1 − 1.5 sin²α (`ashlar::analysis::reference`, written independently of
//!    the model: fixed step, no event location). Tolerances: rotation history over 2 s
//!    (through the impacts) within 0.5 % of the peak rotation — the reference locates impacts only to its 1e-5 s step, which shifts
//!    θ by ~ω·1e-5 ≈ 1e-5 rad a bounce, 0.005 % of the peak, so 0.5 % leaves a wide margin
//!    while still failing for a wrong restitution (a 1 % change of e moves the second peak by
//!    2 %); overturning amplitude within 0.2 % of the reference (both bisected to 1e-3 m/s²).
//! 2. The full DDA engine on the same scene: rotation until the first impact within 2 % of the
//!    peak (the tolerance of tests/engine/rocking.rs, which holds DDA to the same reference).
use crate::common;
use ashlar::analysis::reference::{half_sine_pulse, housner_history, HousnerColumn};
use ashlar::analysis::run::{run, RunOptions};
use ashlar::motion::GroundMotion;
use common::*;
use serde_json::json;
use std::sync::Mutex;

fn pulse(a: f64) -> GroundMotion {
    rocking_pulse(a)
}

/// Housner by RK4 (`ashlar::analysis::reference`): θ samples every 0.01 s, first impact
/// time, overturned.
fn housner(a: f64, t_end: f64) -> (Vec<f64>, Option<f64>, bool) {
    let r = housner_history(
        &HousnerColumn::YAGODA_BIRAN_2015,
        half_sine_pulse(a),
        t_end,
        1000,
    );
    let theta = r.samples.iter().map(|s| s.1).collect();
    (theta, r.first_impact, r.overturned)
}

fn column(model: &str, duration: f64) -> ashlar::scene::Scene {
    parse(
        &Column::SEED
            .json(json!({ "duration": duration, "model": model, "output_interval": 0.01 })),
    )
}

/// Rotation of the column at every 0.01 s frame, and the summary.
fn rotations(model: &str, a: f64, duration: f64) -> (Vec<f64>, ashlar::analysis::run::Summary) {
    let frames = Mutex::new(Vec::new());
    let record =
        |f: &ashlar::record::Frame| frames.lock().expect("lock").push(f.blocks[1].rotation);
    let opts = RunOptions {
        on_frame: Some(&record),
        ..Default::default()
    };
    let out = run(&column(model, duration), &pulse(a), &opts).expect("run");
    (frames.into_inner().expect("lock"), out.summary)
}

#[test]
fn history_through_impacts_matches_housner_rk4() {
    let (reference, impact, fell) = housner(5.0, 2.0);
    assert!(
        !fell && impact.is_some(),
        "the reference must rock and land"
    );
    let (mut theta, summary) = rotations("rocking", 5.0, 2.0);
    assert_eq!(summary.model, "rocking");
    // The run goes on after its 2 s until the column is at rest (docs/run-end.md): compare the
    // frames up to 2 s, the reference's span.
    assert!(theta.len() >= reference.len());
    theta.truncate(reference.len());
    let peak = reference.iter().fold(0.0f64, |m, t| m.max(t.abs()));
    let worst = theta
        .iter()
        .zip(&reference)
        .fold(0.0f64, |m, (a, b)| m.max((a - b).abs()));
    let impacts = summary.diagnostics.impacts.unwrap_or(0);
    eprintln!(
        "peak {peak:.4} rad, worst |Δθ| {worst:.2e} rad ({:.4} %), {} impacts, {} steps, {:.4} s",
        100.0 * worst / peak,
        impacts,
        summary.steps,
        summary.wall_time_s
    );
    assert!(impacts >= 2, "the column must bounce");
    assert!(worst < 0.005 * peak, "{worst} rad vs peak {peak} rad");
    assert!(
        worst < REGRESSION_REDUCED_HISTORY * peak,
        "{worst} rad vs peak {peak} rad: within 0.5 % but beyond the regression bound (find what changed)"
    );
}

/// Regression bound on the reduced model's history through 70 impacts against the RK4: ~6.5×
/// the 0.0153 % of the peak measured 2026-11-25. (Its overturning amplitude has none beyond
/// the 0.2 % tolerance: it measures +0.000 %, and the bisection resolves 0.018 %. Its history
/// against the engine to the first impact, 0.78 % of 2 %: the tolerance binds.)
const REGRESSION_REDUCED_HISTORY: f64 = 1e-3;

#[test]
fn overturning_amplitude_matches_housner() {
    let bisect = |overturns: &dyn Fn(f64) -> bool| {
        let (mut safe, mut fail) = (4.0, 8.0);
        assert!(!overturns(safe) && overturns(fail));
        while fail - safe > 1e-3 {
            let mid = 0.5 * (safe + fail);
            if overturns(mid) {
                fail = mid;
            } else {
                safe = mid;
            }
        }
        0.5 * (safe + fail)
    };
    let reference = bisect(&|a| housner(a, 4.0).2);
    let reduced = bisect(&|a| rotations("rocking", a, 4.0).1.blocks[0].toppled);
    eprintln!(
        "overturning amplitude: Housner RK4 {reference:.4}, reduced {reduced:.4} m/s² ({:+.3} %)",
        100.0 * (reduced / reference - 1.0)
    );
    assert!((reference - 5.64).abs() < 0.02 * 5.64);
    assert!((reduced - reference).abs() < 0.002 * reference);
}

#[test]
fn toppled_column_lies_on_its_side_like_dda() {
    // Far above the threshold the column falls onto the base: rotation π/2 (rigid body at
    // rest on its face; tolerance 1e-9 rad, the event location's precision) and
    // failure_mode "toppling".
    let (_, s) = rotations("rocking", 9.0, 3.0);
    assert!(s.blocks[0].toppled);
    assert_eq!(s.failure_mode, "toppling");
    assert!(
        (s.blocks[0].final_rotation.abs() - std::f64::consts::FRAC_PI_2).abs() < 1e-9,
        "{}",
        s.blocks[0].final_rotation
    );
}

#[test]
fn history_until_first_impact_matches_dda() {
    let (_, impact, _) = housner(5.0, 2.0);
    let until = ((impact.expect("impact") - 0.01) / 0.01).floor() as usize;
    let (reduced, _) = rotations("rocking", 5.0, 2.0);
    let (dda, s) = rotations("dda", 5.0, until as f64 * 0.01 + 0.001);
    assert_eq!(s.model, "dda");
    let peak = reduced[..until].iter().fold(0.0f64, |m, t| m.max(t.abs()));
    let worst = reduced[..until]
        .iter()
        .zip(&dda)
        .fold(0.0f64, |m, (a, b)| m.max((a - b).abs()));
    eprintln!(
        "reduced vs DDA until the first impact: worst |Δθ| {worst:.2e} rad ({:.3} % of peak)",
        100.0 * worst / peak
    );
    assert!(worst < 0.02 * peak);
}
