//! Block sliding on an incline under gravity (seed 000 §3.1.2, §4.1.1–4.1.2, Eqs. 14–15).
//! Reference: d(t) = ½ g (sin α − cos α tan φ) t² + v0 t, written here independently.
//! Tolerance: 1 % relative error from t = 0.2 s on (the bound; the published 2D-DDA
//! reached 8 % at φ = 25°).
mod common;
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
        if s.time >= from - 1e-9 {
            let u = displacement(s, 1);
            let num = u[0] * d[0] + u[1] * d[1];
            let exact = 0.5 * acc * s.time * s.time + v0 * s.time;
            worst = worst.max(((num - exact) / exact).abs());
        }
    });
    worst
}

#[test]
fn block_on_28_degree_incline_from_rest() {
    for phi in [5.0, 10.0, 15.0, 20.0, 25.0] {
        let e = check(28.0, phi, 0.0, 1.0, 0.2);
        eprintln!("α=28 φ={phi}: worst relative error {e:.2e}");
        assert!(e < 0.01, "φ = {phi}: relative error {e}");
    }
}

#[test]
fn block_on_45_degree_incline_from_rest() {
    for phi in [10.0, 20.0, 30.0] {
        let e = check(45.0, phi, 0.0, 1.0, 0.2);
        eprintln!("α=45 φ={phi}: worst relative error {e:.2e}");
        assert!(e < 0.01, "φ = {phi}: relative error {e}");
    }
}

#[test]
fn block_on_45_degree_incline_with_initial_velocity() {
    for v0 in [0.01, 0.1, 1.0] {
        let e = check(45.0, 30.0, v0, 1.0, 0.5);
        eprintln!("α=45 φ=30 v0={v0}: worst relative error {e:.2e}");
        assert!(e < 0.01, "v0 = {v0}: relative error {e}");
    }
}
