//! Block sliding on an incline under gravity (Yagoda-Biran & Hatzor 2015, §3.1.2, §4.1.1–4.1.2, Eqs. 14–15).
//! Reference: d(t) = ½ g (sin α − cos α tan φ) t² + v0 t, written here independently.
//! Tolerance: 1 % relative error from t = 0.2 s on (docs/verification.md's bound; the published 2D-DDA
//! reached 8 % at φ = 25°). Each test also has a regression bound at ~7.5× the largest error
//! measured today over its cases with either contact solver (`cargo test --test engine incline:: --
//! --nocapture`, and with `ASHLAR_CONTACT_SOLVER=dual`), so that a drift is caught long before
//! the tolerance: a wrong constant of gravity (9.80665 against the scene's 9.81, 0.034 %) fails
//! them, and passed the 1 % bound alone.
use crate::common;
use ashlar::motion::GroundMotion;
use common::*;
use serde_json::json;

fn check(alpha: f64, phi: f64, v0: f64, t_end: f64, from: f64) -> f64 {
    let (mut v, d) = incline(
        alpha,
        phi,
        json!({ "time_step": 1e-3, "block_model": "rigid", "duration": t_end }),
    );
    if v0 != 0.0 {
        v["initial"] = json!([{ "block": "block", "velocity": [v0 * d[0], v0 * d[1]] }]);
    }
    let scene = parse(&v);
    let mut s = sim(&scene, &GroundMotion::none());
    let (a, f) = (alpha.to_radians(), phi.to_radians());
    let acc = G * (a.sin() - a.cos() * f.tan());
    let mut worst: f64 = 0.0;
    run(&mut s, t_end, |s| {
        if s.time() >= from - 1e-9 {
            let u = displacement(s, 1);
            let num = u[0] * d[0] + u[1] * d[1];
            let exact = 0.5 * acc * s.time() * s.time() + v0 * s.time();
            worst = worst.max(((num - exact) / exact).abs());
        }
    });
    worst
}

/// docs/verification.md's tolerance, and the regression bound `regression` (see the module text).
fn assert_bounds(case: &str, e: f64, regression: f64) {
    eprintln!(
        "{case}: worst relative error {e:.2e} (tolerance 1e-2, regression bound {regression:.1e})"
    );
    assert!(
        e < 0.01,
        "{case}: relative error {e} above docs/verification.md's 1 %"
    );
    assert!(
        e < regression,
        "{case}: relative error {e} within 1 % but above the regression bound {regression:e}: find what changed"
    );
}

/// Regression bound 2e-5: measured worst 1.1e-6 (penalty) and 2.6e-6 (dual), both at φ = 25°.
#[test]
fn block_on_28_degree_incline_from_rest() {
    for phi in [5.0, 10.0, 15.0, 20.0, 25.0] {
        let e = check(28.0, phi, 0.0, 1.0, 0.2);
        assert_bounds(&format!("α=28 φ={phi}"), e, 2e-5);
    }
}

/// Regression bound 1e-5: measured worst 2.1e-7 (penalty, φ = 30°) and 1.3e-6 (dual, φ = 10°).
#[test]
fn block_on_45_degree_incline_from_rest() {
    for phi in [10.0, 20.0, 30.0] {
        let e = check(45.0, phi, 0.0, 1.0, 0.2);
        assert_bounds(&format!("α=45 φ={phi}"), e, 1e-5);
    }
}

/// Regression bound 1.5e-6: measured worst 3.0e-8 (penalty) and 2.0e-7 (dual, v0 = 0.01).
#[test]
fn block_on_45_degree_incline_with_initial_velocity() {
    for v0 in [0.01, 0.1, 1.0] {
        let e = check(45.0, 30.0, v0, 1.0, 0.5);
        assert_bounds(&format!("α=45 φ=30 v0={v0}"), e, 1.5e-6);
    }
}
