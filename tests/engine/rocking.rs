//! Rocking column (Yagoda-Biran & Hatzor 2015, §3.3): a rigid column of half-width b = 0.2 m and half-height
//! h = 0.6 m on a fixed base, under a half-sine acceleration pulse a(t) = A sin(2πt) for
//! 0 ≤ t ≤ 0.5 s. Reference: Housner's equation of rocking integrated by RK4 (step 1e-5 s) with
//! Housner's restitution at impacts (`ashlar::analysis::reference`, which shares no code with
//! the engine). Tolerances: rotation up to the first impact within 2 % of the peak rotation;
//! overturning amplitude within 2 % (both docs/verification.md's), within 1 % with the dual solver
//! (`ASHLAR_CONTACT_SOLVER=dual`, no penalty stiffness to tune).
use crate::common;
use ashlar::analysis::reference::{half_sine_pulse, housner_history, HousnerColumn};
use ashlar::motion::GroundMotion;
use common::*;
use serde_json::json;

fn pulse(a: f64) -> GroundMotion {
    rocking_pulse(a)
}

/// Housner's equation (`ashlar::analysis::reference`, RK4 at 1e-5 s with Housner's
/// restitution) under the same pulse: (t, θ) every step, the first impact time, and whether it
/// overturned by `t_end`. θ counter-clockwise (the ground accelerating to +x tips the column back
/// towards −x).
fn housner(a: f64, t_end: f64) -> (Vec<(f64, f64)>, Option<f64>, bool) {
    let r = housner_history(
        &HousnerColumn::YAGODA_BIRAN_2015,
        half_sine_pulse(a),
        t_end,
        1,
    );
    (r.samples, r.first_impact, r.overturned)
}

fn column_scene(control: serde_json::Value) -> ashlar::scene::Scene {
    parse(&Column::SEED.json(control))
}

fn dda_overturns(a: f64) -> bool {
    let scene = column_scene(json!({ "duration": 3.0 }));
    let mut s = sim(&scene, &pulse(a));
    // Past 1 rad the column is beyond its tipping angle (0.32 rad) and falling: decided.
    run_until(&mut s, 3.0, |s| s.geoms()[1].rotation.abs() > 1.0)
}

fn threshold(
    mut safe: f64,
    mut fail: f64,
    tol: f64,
    overturns: impl Fn(f64) -> bool,
) -> (f64, f64) {
    assert!(!overturns(safe) && overturns(fail), "bracket does not hold");
    while fail - safe > tol {
        let mid = 0.5 * (safe + fail);
        if overturns(mid) {
            fail = mid;
        } else {
            safe = mid;
        }
    }
    (safe, fail)
}

#[test]
fn rotation_history_matches_housner_until_first_impact() {
    let a = 5.0;
    let (reference, impact, fell) = housner(a, 2.0);
    assert!(!fell);
    let t_impact = impact.expect("the reference rocks and lands");
    let peak = reference.iter().fold(0.0f64, |m, p| m.max(p.1.abs()));
    let scene = column_scene(json!({ "duration": 2.0 }));
    let mut s = sim(&scene, &pulse(a));
    let mut worst: f64 = 0.0;
    run(&mut s, t_impact - 0.01, |s| {
        let k = ((s.time() / 1e-5).round() as usize).min(reference.len() - 1);
        worst = worst.max((s.geoms()[1].rotation - reference[k].1).abs());
    });
    eprintln!("peak θ = {peak:.4} rad, first impact at {t_impact:.3} s, worst |Δθ| = {worst:.2e} rad ({:.2} %)", 100.0 * worst / peak);
    assert!(
        worst < 0.02 * peak,
        "rotation error {worst} rad vs peak {peak} rad"
    );
}

#[test]
fn overturning_amplitude_matches_housner() {
    let (hs, hf) = threshold(4.0, 8.0, 1e-3, |a| housner(a, 4.0).2);
    let housner_a = 0.5 * (hs + hf);
    // Yagoda-Biran & Hatzor 2015, §3.3, quote 5.64 m/s² for this pulse; our independent integration must agree.
    assert!(
        (housner_a - 5.64).abs() < 0.02 * 5.64,
        "reference threshold {housner_a}"
    );
    let (ds, df) = threshold(4.0, 8.0, 0.01, dda_overturns);
    let dda_a = 0.5 * (ds + df);
    eprintln!(
        "overturning amplitude: Housner {housner_a:.3} m/s², DDA {dda_a:.3} m/s² ({:+.2} %)",
        100.0 * (dda_a / housner_a - 1.0)
    );
    // The dual solver has no penalty stiffness to tune: docs/verification.md asks for 1 % there.
    let tol = if dual_under_test() { 0.01 } else { 0.02 };
    assert!((dda_a - housner_a).abs() < tol * housner_a);
    // Regression bound 0.6 %: ~5.5× the +0.11 % measured with either solver (the engine's
    // bisection resolves 0.01 m/s², 0.18 %, so a tighter bound would test the bisection).
    // The rotation history above has none: its 0.81 % is within 2.5× of the 2 % tolerance.
    assert!(
        (dda_a - housner_a).abs() < 6e-3 * housner_a,
        "DDA {dda_a} vs Housner {housner_a}: within the tolerance but above the regression bound 0.6 % (~5.5× today's 0.11 %)"
    );
}
