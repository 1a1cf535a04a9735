//! Rocking column (seed 000 §3.3): a rigid column of half-width b = 0.2 m and half-height
//! h = 0.6 m on a fixed base, under a half-sine acceleration pulse a(t) = A sin(2πt) for
//! 0 ≤ t ≤ 0.5 s. Reference: Housner's equation of rocking integrated here by RK4 (step 1e-5 s)
//! with Housner's restitution at impacts. Tolerances: rotation up to the first impact within
//! 2 % of the peak rotation; overturning amplitude within 2 % (both from the issue), within 1 %
//! with the dual solver (`ASHLAR_CONTACT_SOLVER=dual`, no penalty stiffness to tune).
mod common;
use ashlar::motion::{GroundMotion, Signal};
use common::*;
use serde_json::json;

const B: f64 = 0.2;
const H: f64 = 0.6;

fn pulse(a: f64) -> GroundMotion {
    GroundMotion::horizontal(Signal::Pulse {
        amplitude: a,
        period: 1.0,
        cycles: 0.5,
        phase: 0.0,
    })
}

fn ground(a: f64, t: f64) -> f64 {
    if (0.0..=0.5).contains(&t) {
        a * (2.0 * std::f64::consts::PI * t).sin()
    } else {
        0.0
    }
}

/// Housner: θ̈ = (3/4R)[−g sin(α sgnθ − θ) + ü_g cos(α sgnθ − θ)], θ counter-clockwise (the
/// ground accelerating to +x tips the column back towards −x, i.e. counter-clockwise).
/// Returns samples (t, θ), the first impact time, and whether it overturned by `t_end`.
fn housner(a: f64, t_end: f64) -> (Vec<(f64, f64)>, Option<f64>, bool) {
    let r = (B * B + H * H).sqrt();
    let alpha = (B / H).atan();
    let k = 3.0 / (4.0 * r);
    let e = 1.0 - 1.5 * alpha.sin().powi(2);
    let acc = |t: f64, th: f64, sgn: f64| {
        k * (-G * (alpha * sgn - th).sin() + ground(a, t) * (alpha * sgn - th).cos())
    };
    let (mut t, mut th, mut w) = (0.0, 0.0, 0.0);
    let dt = 1e-5;
    let mut out = vec![(0.0, 0.0)];
    let mut first_impact = None;
    let mut sgn = 0.0;
    while t < t_end {
        if sgn == 0.0 {
            // At rest on the base until the ground acceleration exceeds g·tan α.
            let ug = ground(a, t);
            if ug.abs() > G * alpha.tan() {
                sgn = ug.signum();
            } else {
                t += dt;
                out.push((t, 0.0));
                continue;
            }
        }
        let f = |t: f64, th: f64, w: f64| (w, acc(t, th, sgn));
        let (k1t, k1w) = f(t, th, w);
        let (k2t, k2w) = f(t + dt / 2.0, th + dt / 2.0 * k1t, w + dt / 2.0 * k1w);
        let (k3t, k3w) = f(t + dt / 2.0, th + dt / 2.0 * k2t, w + dt / 2.0 * k2w);
        let (k4t, k4w) = f(t + dt, th + dt * k3t, w + dt * k3w);
        let nth = th + dt / 6.0 * (k1t + 2.0 * k2t + 2.0 * k3t + k4t);
        let nw = w + dt / 6.0 * (k1w + 2.0 * k2w + 2.0 * k3w + k4w);
        t += dt;
        if nth * sgn < 0.0 {
            first_impact.get_or_insert(t);
            th = 0.0;
            w = nw * e;
            sgn = w.signum();
            if w.abs() < 1e-6 {
                sgn = 0.0;
                w = 0.0;
            }
        } else {
            th = nth;
            w = nw;
        }
        out.push((t, th));
        if th.abs() > std::f64::consts::FRAC_PI_2 {
            return (out, first_impact, true);
        }
    }
    (out, first_impact, false)
}

fn column_scene(control: serde_json::Value) -> ashlar::scene::Scene {
    let blocks = json!([
        { "id": "base", "material": "stone", "fixed": true, "vertices": [[-1.0, -0.5], [1.0, -0.5], [1.0, 0.0], [-1.0, 0.0]] },
        { "id": "column", "material": "stone", "block_model": "rigid",
          "vertices": [[-B, 0.0], [B, 0.0], [B, 2.0 * H], [-B, 2.0 * H]] },
    ]);
    parse(&scene_json(blocks, 75.0, control))
}

fn dda_overturns(a: f64) -> bool {
    let scene = column_scene(json!({ "duration": 3.0 }));
    let mut s = sim(&scene, &pulse(a));
    // Past 1 rad the column is beyond its tipping angle (0.32 rad) and falling: decided.
    run_until(&mut s, 3.0, |s| s.geoms[1].rotation.abs() > 1.0)
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
        let k = ((s.time / 1e-5).round() as usize).min(reference.len() - 1);
        worst = worst.max((s.geoms[1].rotation - reference[k].1).abs());
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
    // The issue quotes 5.64 m/s² for this pulse; our independent integration must agree.
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
    // The dual solver has no penalty stiffness to tune: the issue asks for 1 % there.
    let tol = if dual_under_test() { 0.01 } else { 0.02 };
    assert!((dda_a - housner_a).abs() < tol * housner_a);
}
