//! The reduced sliding model (`"model": "sliding"`: rigid-plastic Newmark integration with
//! Coulomb friction in the contact's frame) against independent references:
//! 1. Incline under gravity, closed form d = ½g(sin α − cos α tan φ)t² (Yagoda-Biran & Hatzor 2015, Eq. 14):
//!    within 1e-6 relative — the model integrates a constant acceleration, so only the ODE
//!    tolerance (1e-10) and the onset location contribute.
//! 2. Incline under a horizontal sine (Yagoda-Biran & Hatzor 2015, Eq. 10), against the fixed-step (1e-5 s)
//!    semi-implicit rigid-plastic integration of `ashlar::analysis::reference` (as in
//!    tests/engine/sliding_newmark.rs):
//!    within 0.1 % — that reference's own first-order stick/slip timing error (≤ 1e-5 s per
//!    transition, a few transitions a cycle) is ~1e-4 of the displacement; docs/verification.md's DDA
//!    bound is 2 %.
//! 3. Shaking foundation (driven block, Yagoda-Biran & Hatzor 2015, Eq. 17 integrated at 1e-6 s): largest
//!    deviation within 0.1 % of the peak. The reference's explicit stick/slip switching makes
//!    a velocity error of up to Δt·Aω² at each reversal (first order): at 1e-5 s the 5 Hz case
//!    deviated by 0.36 %, at 1e-6 s by 0.041 % (measured), so 1e-6 s is used.
//! 4. The full DDA engine on the sine case: within 2 % (docs/verification.md's bound for DDA).
use crate::common;
use ashlar::analysis::reference::{foundation_eq17, newmark_incline};
use ashlar::analysis::run::{run, RunOptions, Summary};
use ashlar::analysis::run_end::RunEndParams;

/// The references give the state at the run's duration: no continuation after it (a block
/// sliding down an incline never settles; docs/run-end.md).
fn at_duration() -> RunOptions<'static> {
    RunOptions {
        run_end: Some(RunEndParams {
            max_extension: 0.0,
            ..Default::default()
        }),
        ..Default::default()
    }
}
use ashlar::motion::{GroundMotion, Signal};
use common::*;
use serde_json::json;
use std::f64::consts::PI;
use std::sync::Mutex;

/// `ashlar::analysis::reference::newmark_incline` under A sin 2πft, fixed step 1e-5 s.
fn newmark_reference(alpha: f64, phi: f64, a: f64, f: f64, t_end: f64) -> f64 {
    newmark_incline(alpha, phi, G, |t| a * (2.0 * PI * f * t).sin(), t_end, 1e-5)
}

fn incline_run(
    model: &str,
    alpha: f64,
    phi: f64,
    motion: &GroundMotion,
    t_end: f64,
) -> (f64, Summary) {
    let (v, d) = incline(
        alpha,
        phi,
        json!({ "duration": t_end, "model": model, "block_model": "rigid", "time_step": 1e-3 }),
    );
    let s = run(&parse(&v), motion, &at_duration())
        .expect("run")
        .summary;
    let u = s.blocks[0].final_displacement;
    (u[0] * d[0] + u[1] * d[1], s)
}

#[test]
fn incline_under_gravity_matches_closed_form() {
    for (alpha, phi) in [(28.0f64, 5.0f64), (28.0, 15.0), (28.0, 25.0), (45.0, 30.0)] {
        let (num, s) = incline_run("sliding", alpha, phi, &GroundMotion::none(), 1.0);
        let (a, f) = (alpha.to_radians(), phi.to_radians());
        let exact = 0.5 * G * (a.sin() - a.cos() * f.tan());
        let err = ((num - exact) / exact).abs();
        eprintln!(
            "α={alpha} φ={phi}: {num:.9} m vs {exact:.9} m, error {err:.1e}, {} steps",
            s.steps
        );
        assert_eq!(s.model, "sliding");
        assert_eq!(s.failure_mode, "sliding");
        assert!(err < 1e-6, "α={alpha} φ={phi}: {err}");
        // Regression bound: ~7× the 1.4e-14 measured 2026-11-25 (round-off).
        assert!(
            err < 1e-13,
            "α={alpha} φ={phi}: {err} beyond the regression bound 1e-13"
        );
    }
}

#[test]
fn stable_incline_does_not_move() {
    // φ > α: friction holds the block; displacement exactly zero (a rigid model has no
    // spring creep), failure_mode "stable".
    let (num, s) = incline_run("sliding", 20.0, 30.0, &GroundMotion::none(), 1.0);
    assert_eq!(num, 0.0);
    assert_eq!(s.failure_mode, "stable");
}

fn sine(a: f64, f: f64) -> GroundMotion {
    GroundMotion::horizontal(Signal::Sine {
        amplitude: a,
        frequency: f,
    })
}

#[test]
fn incline_under_sine_matches_newmark_reference() {
    for (alpha, phi) in [(20.0f64, 22.0f64), (20.0, 30.0), (20.0, 35.0), (45.0, 50.0)] {
        let a = if alpha == 45.0 { 2.0 } else { 4.0 };
        let reference = newmark_reference(alpha.to_radians(), phi.to_radians(), a, 1.0, 4.0);
        let (num, s) = incline_run("sliding", alpha, phi, &sine(a, 1.0), 4.0);
        let err = ((num - reference) / reference).abs();
        eprintln!("α={alpha} φ={phi}: reduced {num:.6} m, reference {reference:.6} m, error {:.4} %, {} steps, {:.4} s", 100.0 * err, s.steps, s.wall_time_s);
        assert!(reference.abs() > 1e-3);
        assert!(err < 1e-3, "α={alpha} φ={phi}: {err}");
        // Regression bound: ~6× the 4e-6 measured 2026-11-25 (α = 20°, φ = 30° and 45°/50°).
        assert!(
            err < 2.5e-5,
            "α={alpha} φ={phi}: {err} beyond the regression bound 2.5e-5"
        );
    }
}

#[test]
fn incline_under_sine_matches_dda() {
    let (red, _) = incline_run("sliding", 20.0, 30.0, &sine(4.0, 1.0), 4.0);
    let (dda, s) = incline_run("dda", 20.0, 30.0, &sine(4.0, 1.0), 4.0);
    assert_eq!(s.model, "dda");
    let err = ((red - dda) / dda).abs();
    eprintln!("reduced {red:.6} m, DDA {dda:.6} m: {:.3} %", 100.0 * err);
    assert!(err < 0.02);
    // Regression bound: ~5.4× the 0.037 % measured 2026-11-25 (the engine's error; the contact
    // solve is changing on another branch: re-measure after the merge).
    assert!(err < 2e-3, "{err} beyond the regression bound 2e-3");
}

/// `ashlar::analysis::reference::foundation_eq17`, sampled every 0.01 s.
fn foundation_reference(a: f64, f: f64, mu: f64, t_end: f64, dt: f64) -> Vec<f64> {
    let every = (0.01 / dt).round() as usize;
    foundation_eq17(a, f, mu, G, t_end, dt, every)
        .into_iter()
        .map(|(_, x)| x)
        .collect()
}

#[test]
fn shaking_foundation_matches_eq_17() {
    for (a, f, mu) in [(0.2, 2.0, 0.6), (0.2, 5.0, 0.6), (1.0, 1.0, 0.6)] {
        let t_end = 5.0;
        let w = 2.0 * PI * f;
        let blocks = json!([
            { "id": "foundation", "material": "stone", "vertices": [[-8.0, -0.5], [8.0, -0.5], [8.0, 0.0], [-8.0, 0.0]] },
            { "id": "block", "material": "stone", "vertices": [[-1.0, 0.0], [1.0, 0.0], [1.0, 0.1], [-1.0, 0.1]] },
        ]);
        let mut v = scene_json(
            blocks,
            f64::atan(mu).to_degrees(),
            json!({ "duration": t_end, "model": "auto" }),
        );
        v["excitation"] = json!({ "type": "driven_block", "block": "foundation" });
        let motion = GroundMotion::horizontal(Signal::Pulse {
            amplitude: a * w * w,
            period: 1.0 / f,
            cycles: f * t_end + 1.0,
            phase: std::f64::consts::FRAC_PI_2,
        });
        let xs = Mutex::new(Vec::new());
        let rec = |fr: &ashlar::record::Frame| xs.lock().expect("lock").push(fr.blocks[1].x);
        let opts = RunOptions {
            on_frame: Some(&rec),
            ..at_duration()
        };
        let s = run(&parse(&v), &motion, &opts).expect("run").summary;
        assert_eq!(s.model, "sliding", "{}", s.model_reason);
        let xs = xs.into_inner().expect("lock");
        let r = foundation_reference(a, f, mu, t_end, 1e-6);
        let peak = r.iter().fold(0.0f64, |m, x| m.max(x.abs()));
        let worst = xs
            .iter()
            .zip(&r)
            .fold(0.0f64, |m, (p, q)| m.max((p - q).abs()));
        eprintln!(
            "A={a} f={f} μ={mu}: peak {peak:.4} m, worst {worst:.2e} m ({:.4} %)",
            100.0 * worst / peak
        );
        assert_eq!(xs.len(), r.len());
        assert!(worst < 1e-3 * peak, "{worst} vs {peak}");
        // Regression bound ~6× the error measured 2026-11-25 at 1 Hz (0.0019 % of the peak)
        // and 2 Hz (0.0024 %); at 5 Hz (0.0414 %) the 0.1 % tolerance binds.
        let regression = if f < 5.0 { 1.5e-4 } else { 1e-3 };
        assert!(
            worst < regression * peak,
            "{worst} vs {peak}: beyond the regression bound {regression}"
        );
    }
}
