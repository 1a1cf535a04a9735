//! Overturning amplitude against pulse frequency (docs/pga.md): full one-cycle sine pulses
//! a(t) = A sin(2πft), 0 ≤ t ≤ 1/f, at f = 0.5, 1, 2 and 4 Hz, for two rigid columns on a fixed
//! base (half-width × half-height 0.2 × 0.6 m and the more slender 0.1 × 0.8 m).
//!
//! Reference: Housner's equation of rocking, θ̈ = −p²[sin(α sgnθ − θ) − (ü_g/g) cos(α sgnθ − θ)]
//! with p² = 3g/(4R), integrated by RK4 (Δt = 1e-4 s) with Housner's restitution
//! r = 1 − 1.5 sin²α applied to the angular velocity at each impact (`ashlar::analysis::reference`,
//! as in tests/engine/rocking.rs).
//! The reference threshold is the lowest overturning amplitude found by a fine scan (3000 points
//! from g tan α to 16 g tan α) and bisection to 1e-4 relative. "Overturned" means what the
//! engine's `toppled` criterion means: |θ| ≥ 60° at any time, or |θ| > 30° at the end of the
//! window (pulse + 3 s).
//!
//! The sweep crosses the jump where the overturning mode changes: the 0.2 × 0.6 column overturns
//! after one impact (mode 2) up to 2 Hz, but at 4 Hz only without impact (mode 1) at about
//! 14 g tan α, so the threshold jumps. The test checks the reference's mode at each case, and
//! that the engine overturns in the same mode at its failing amplitude.
//!
//! Tolerance: the engine's lowest overturning amplitude within 3 % of Housner's (docs/verification.md's
//! bound), searched over [0.5, 1.5] × the reference. Every overturning interval the scan meets
//! is reported; islands (overturning intervals below the main overturning region, the one that
//! reaches 1.5 × Housner) are printed.
//!
//! How the engine's scan stays affordable in a debug build without narrowing the range:
//! - below g tan α a rigid column on a rigid base cannot uplift: one run at 0.999 g tan α
//!   shows the contacts never open (peak rotation < 1e-4 rad, the penalty springs' elastic
//!   tilt); while every contact stays closed the system is linear, so every lower amplitude
//!   gives a proportionally smaller response: no run is needed there;
//! - above it, a coarse grid (steps of 2 % of Housner's threshold) records each run's peak
//!   rotation; an interval is refined to steps of 0.4 % (the narrowest islands seen are ~0.8 %
//!   wide) when its ends differ (one stands, one overturns), or when both stand and either
//!   rocked past half the tipping angle α: far from tipping (both below α/2) an overturning
//!   island would need the response to double within 2 % of amplitude. Between two overturning
//!   points it is not refined: a standing gap there changes neither the lowest overturning
//!   amplitude nor any overturning interval's start;
//! - a run stops once the column has toppled (60°), or, after the pulse (the base then rests),
//!   once its energy above rest is below 90 % of what lifting its centroid over the corner
//!   takes (m g (R − h)): the engine's integrator only dissipates after the excitation ends
//!   (tests/engine/invariants.rs), so it can no longer topple.
//!
//! The lowest overturning amplitude is then bisected to 0.4 % of Housner's.
use crate::common;
use ashlar::analysis::reference::{housner_rocking, HousnerColumn};
use ashlar::motion::{GroundMotion, Signal};
use common::*;
use rayon::prelude::*;
use serde_json::json;

/// Seconds simulated after the pulse ends (both reference and engine). 3 s: a slender column
/// left rocking near its tipping angle can take more than 2 s to fall, and a shorter window
/// breaks the overturning region into narrow islands (seen with 2 s at 4 Hz).
const AFTER: f64 = 3.0;

#[derive(Debug, Clone, Copy)]
struct Column {
    b: f64,
    h: f64,
}

/// Housner (`ashlar::analysis::reference`, RK4 at 1e-4 s) with the engine's `toppled`
/// verdict. Returns (overturned, impacts before the verdict).
fn housner(c: Column, a: f64, f: f64) -> (bool, usize) {
    let t_pulse = 1.0 / f;
    let ground = |t: f64| {
        if t <= t_pulse {
            a * (2.0 * std::f64::consts::PI * f * t).sin()
        } else {
            0.0
        }
    };
    let col = HousnerColumn {
        b: c.b,
        h: c.h,
        g: G,
        dt: 1e-4,
    };
    let end = housner_rocking(&col, ground, t_pulse + AFTER, |s| {
        s.theta.abs() >= std::f64::consts::FRAC_PI_3
    });
    // Stopped at 60°, or past 30° at the end of the window.
    (end.theta.abs() > std::f64::consts::FRAC_PI_6, end.impacts)
}

/// Lowest overturning amplitude of the reference, and its mode (impacts before overturning).
/// The scan is fine (steps of 0.005 g tan α) because the overturning set has narrow islands:
/// the slender column at 0.5 Hz overturns (after 3 impacts) for 1.35–1.365 m/s², then stands
/// again up to 1.39 m/s²; a coarse scan steps over such an island. Scanned in parallel chunks,
/// in order, up to the first chunk that overturns.
fn housner_threshold(c: Column, f: f64) -> (f64, usize) {
    let gt = G * c.b / c.h;
    let n = 3000;
    let grid: Vec<f64> = (0..n)
        .map(|k| gt * (1.0 + 15.0 * k as f64 / (n - 1) as f64))
        .collect();
    let mut k = None;
    for (ci, chunk) in grid.chunks(128).enumerate() {
        let fell: Vec<bool> = chunk.par_iter().map(|&a| housner(c, a, f).0).collect();
        if let Some(j) = fell.iter().position(|&x| x) {
            k = Some(ci * 128 + j);
            break;
        }
    }
    let k = k.expect("the reference overturns in the scanned range");
    assert!(k > 0, "the reference overturns at g tan α already");
    let (mut s, mut fl) = (grid[k - 1], grid[k]);
    while fl - s > 1e-4 * fl {
        let m = 0.5 * (s + fl);
        if housner(c, m, f).0 {
            fl = m;
        } else {
            s = m;
        }
    }
    (fl, housner(c, fl, f).1)
}

fn scene(c: Column, f: f64) -> ashlar::scene::Scene {
    let blocks = json!([
        { "id": "base", "material": "stone", "fixed": true, "vertices": [[-1.0, -0.5], [1.0, -0.5], [1.0, 0.0], [-1.0, 0.0]] },
        { "id": "column", "material": "stone", "block_model": "rigid",
          "vertices": [[-c.b, 0.0], [c.b, 0.0], [c.b, 2.0 * c.h], [-c.b, 2.0 * c.h]] },
    ]);
    // Friction angle 85° (μ = 11.4): Housner's model has no sliding, and the stocky column's
    // 4 Hz threshold (~4.6 g) would make a 75° joint (μ = 3.7) slide.
    // Δt: 1 ms (the default) up to 1 Hz, 0.1 ms for the short pulses (2 and 4 Hz). Measured
    // (`cargo run --example pga_probe -- 0.2 0.6 F A...`): at the default 1 ms the 4 Hz pulse of
    // ~4.6 g puts the stocky column's threshold 2.4 % low, overturning after an impact that
    // Housner's model (and the engine at Δt ≤ 2e-4 s) does not have; at 2 Hz the outcome just
    // above the threshold flips between amplitudes 0.1 m/s² apart at Δt = 1e-3 and 5e-4 s (safe
    // islands from the impact's resolution) and settles at 1e-4 s. A time-discretisation error
    // of the engine near mode-2 thresholds, not a difference of restitution: the engine's
    // effective restitution matches Housner's 1 − 1.5 sin²α within 0.5 %
    // (`cargo run --example rocking_restitution`).
    let dt = if f >= 2.0 { 1e-4 } else { 1e-3 };
    parse(&scene_json(
        blocks,
        85.0,
        // The engine is what this test measures; the default ("auto") would run the reduced
        // rocking model, which tests/analysis/reduced_rocking.rs checks against Housner.
        json!({ "duration": 1.0 / f + AFTER, "time_step": dt, "model": "dda" }),
    ))
}

fn pulse(f: f64) -> GroundMotion {
    GroundMotion::horizontal(Signal::Pulse {
        amplitude: 1.0,
        period: 1.0 / f,
        cycles: 1.0,
        phase: 0.0,
    })
}

/// Impacts (sign changes of the rotation past 1e-3 rad) before the engine's column passes 60°.
fn dda_mode(c: Column, f: f64, a: f64) -> usize {
    let sc = scene(c, f);
    let gm = pulse(f).scaled_to_pga(a);
    let mut s = sim(&sc, &gm);
    let (mut last_sign, mut impacts) = (0.0f64, 0);
    run_until(&mut s, 1.0 / f + AFTER, |s| {
        let th = s.geoms()[1].rotation;
        if th.abs() > 1e-3 {
            if last_sign != 0.0 && th.signum() != last_sign {
                impacts += 1;
            }
            last_sign = th.signum();
        }
        th.abs() >= std::f64::consts::FRAC_PI_3
    });
    impacts
}

/// One engine run at amplitude `a` (m/s²): (toppled by the `toppled` criterion's rule, peak
/// |θ| / α). Stops early as the module text says.
fn engine(c: Column, f: f64, a: f64) -> (bool, f64) {
    let sc = scene(c, f);
    let gm = pulse(f).scaled_to_pga(a);
    let mut s = sim(&sc, &gm);
    let alpha = (c.b / c.h).atan();
    let (t_pulse, t_end) = (1.0 / f, 1.0 / f + AFTER);
    let mass = 2500.0 * 4.0 * c.b * c.h;
    let tip_energy = mass * G * ((c.b * c.b + c.h * c.h).sqrt() - c.h);
    let e0 = s.energy().total();
    let mut peak: f64 = 0.0;
    let mut toppled = false;
    run_until(&mut s, t_end, |s| {
        let th = s.geoms()[1].rotation.abs();
        peak = peak.max(th);
        if th >= std::f64::consts::FRAC_PI_3 {
            toppled = true;
            return true;
        }
        s.time() > t_pulse && s.energy().total() - e0 < 0.9 * tip_energy
    });
    let end = s.geoms()[1].rotation.abs();
    (
        toppled || (s.time() >= t_end - 1e-9 && end > std::f64::consts::FRAC_PI_6),
        peak / alpha,
    )
}

/// Returns the reference's mode (impacts before overturning).
fn check(c: Column, f: f64) -> usize {
    let started = std::time::Instant::now();
    let (ha, h_impacts) = housner_threshold(c, f);
    let gt = G * c.b / c.h;
    // No uplift below g tan α (see the module text).
    let lo = (0.5 * ha).max(gt);
    if 0.5 * ha < gt {
        let (fell, peak) = engine(c, f, 0.999 * gt);
        let alpha = (c.b / c.h).atan();
        assert!(
            !fell && peak * alpha < 1e-4,
            "b×h {}×{} f {f} Hz: the column rocks below g tan α (peak {:.2e} rad)",
            c.b,
            c.h,
            peak * alpha
        );
    }
    // Coarse grid, refined where the column came near tipping; in order, up to 1.5 × Housner.
    let hi = 1.5 * ha;
    let coarse: Vec<f64> = {
        let n = ((hi - lo) / (0.02 * ha)).ceil() as usize;
        (0..=n)
            .map(|k| lo + (hi - lo) * k as f64 / n as f64)
            .collect()
    };
    let coarse_runs: Vec<(bool, f64)> = coarse.par_iter().map(|&a| engine(c, f, a)).collect();
    let mut runs: Vec<(f64, bool, f64)> = Vec::new();
    for k in 0..coarse.len() {
        if k > 0 {
            let (a0, a1) = (coarse[k - 1], coarse[k]);
            let ((f0, p0), (f1, p1)) = (coarse_runs[k - 1], coarse_runs[k]);
            let near = !f0 && !f1 && p0.max(p1) >= 0.5;
            if near || f0 != f1 {
                let m = ((a1 - a0) / (0.004 * ha)).ceil() as usize;
                let fine: Vec<f64> = (1..m)
                    .map(|j| a0 + (a1 - a0) * j as f64 / m as f64)
                    .collect();
                let out: Vec<(bool, f64)> = fine.par_iter().map(|&a| engine(c, f, a)).collect();
                runs.extend(fine.iter().zip(out).map(|(&a, (fl, p))| (a, fl, p)));
            }
        }
        runs.push((coarse[k], coarse_runs[k].0, coarse_runs[k].1));
    }
    // Overturning intervals, at the scan's resolution.
    let mut intervals: Vec<(f64, f64)> = Vec::new();
    let mut open: Option<f64> = None;
    for w in 0..runs.len() {
        let (a, fell, _) = runs[w];
        match (fell, open) {
            (true, None) => open = Some(a),
            (false, Some(start)) => {
                intervals.push((start, runs[w - 1].0));
                open = None;
            }
            _ => {}
        }
    }
    if let Some(start) = open {
        intervals.push((start, runs[runs.len() - 1].0));
    }
    let first = *intervals.first().unwrap_or_else(|| {
        panic!(
            "b×h {}×{} f {f} Hz: the engine never overturns up to 1.5 × Housner",
            c.b, c.h
        )
    });
    let islands = &intervals[..intervals.len() - 1];
    // Bisect the lowest overturning amplitude between the last standing run below it and it.
    let below = runs
        .iter()
        .rev()
        .find(|r| r.0 < first.0)
        .map_or(lo, |r| r.0);
    assert!(
        first.0 > lo,
        "b×h {}×{} f {f} Hz: the engine overturns at the bottom of the scan, {lo:.3} m/s²",
        c.b,
        c.h
    );
    let (mut s, mut fl) = (below, first.0);
    while fl - s > 0.004 * ha {
        let m = 0.5 * (s + fl);
        if engine(c, f, m).0 {
            fl = m;
        } else {
            s = m;
        }
    }
    let da = 0.5 * (s + fl);
    let d_impacts = dda_mode(c, f, fl);
    let err = da / ha - 1.0;
    let line = format!(
        "b×h {}×{} f {f} Hz: Housner {ha:.3} m/s² ({:.2} g tanα, {h_impacts} impacts), DDA lowest overturning [{s:.3}, {fl:.3}] ({d_impacts} impacts), {:+.2} %; scan [{lo:.3}, {:.3}] m/s² in {} runs, overturning intervals {intervals:.3?}, islands below the main region: {}; {:.0} s",
        c.b,
        c.h,
        ha / gt,
        100.0 * err,
        hi,
        runs.len(),
        if islands.is_empty() { "none".to_string() } else { format!("{islands:.3?}") },
        started.elapsed().as_secs_f64()
    );
    eprintln!("{line}");
    assert!(err.abs() < 0.03, "{line}");
    assert!(
        err.abs() < REGRESSION_SWEEP,
        "within 3 % but beyond the regression bound {REGRESSION_SWEEP} (find what changed): {line}"
    );
    assert_eq!(
        h_impacts == 0,
        d_impacts == 0,
        "overturning mode differs: {line}"
    );
    h_impacts
}

#[test]
fn stocky_column_frequency_sweep_with_mode_jump() {
    let c = Column { b: 0.2, h: 0.6 };
    let modes: Vec<usize> = [0.5, 1.0, 2.0, 4.0].iter().map(|&f| check(c, f)).collect();
    // The jump: with an impact up to 2 Hz, without one at 4 Hz.
    assert!(modes[2] > 0 && modes[3] == 0, "modes {modes:?}");
}

#[test]
fn slender_column_frequency_sweep() {
    let c = Column { b: 0.1, h: 0.8 };
    for f in [0.5, 1.0, 2.0, 4.0] {
        check(c, f);
    }
}

/// Regression bound on the engine's lowest overturning amplitude against Housner's, every
/// frequency and column: 5× the largest error measured 2026-11-25, +0.22 % (stocky column at
/// 0.5 and 1 Hz; the others −0.09 … +0.17 %). The engine's bracket is ~0.4 % wide, so a bound
/// much tighter would test the bisection. The impact law is being changed on another branch:
/// re-measure after the merge (`cargo test --test analysis -- pga_frequency_sweep --nocapture`).
const REGRESSION_SWEEP: f64 = 0.011;
