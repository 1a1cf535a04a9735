//! Block on an incline under horizontal sinusoidal ground acceleration (Yagoda-Biran & Hatzor 2015, §3.1.2 Eq. 10,
//! §4.1.3): Newmark-type sliding. Reference: an independent rigid-plastic integration
//! (`ashlar::analysis::reference`: semi-implicit Euler, Δt = 1e-5 s, stick/slip switching with
//! the exact friction law, both sliding directions). Tolerance: final displacement within 2 % (docs/verification.md's bound).
//! Regression bound 3e-3 (0.3 %): ~7.5× the largest error measured today over the cases, 0.040 %
//! (dual solver; 0.037 % penalty: `cargo test --test engine sliding_newmark:: -- --nocapture`, and with
//! `ASHLAR_CONTACT_SOLVER=dual`), so that a drift is caught long before the 2 %.
use crate::common;
use ashlar::analysis::reference::newmark_incline;
use common::*;
use serde_json::json;

/// Down-slope displacement of a rigid block on an incline α (down-slope towards +x) with
/// friction φ under horizontal ground acceleration a_g(t) = A sin(2πft), relative to the ground
/// (`ashlar::analysis::reference::newmark_incline`, fixed step 1e-5 s).
fn newmark_reference(alpha: f64, phi: f64, a: f64, f: f64, t_end: f64) -> f64 {
    let sine = |t: f64| a * (2.0 * std::f64::consts::PI * f * t).sin();
    newmark_incline(alpha, phi, G, sine, t_end, 1e-5)
}

fn dda(alpha_deg: f64, phi_deg: f64, a: f64, f: f64, t_end: f64) -> f64 {
    let (v, d) = incline(
        alpha_deg,
        phi_deg,
        json!({ "time_step": 1e-3, "block_model": "rigid", "duration": t_end }),
    );
    let scene = parse(&v);
    let mut s = sim(&scene, &sine(a, f));
    run(&mut s, t_end, |_| {});
    let u = displacement(&s, 1);
    u[0] * d[0] + u[1] * d[1]
}

fn check(alpha: f64, phi: f64, a: f64, f: f64, t_end: f64) {
    let reference = newmark_reference(alpha.to_radians(), phi.to_radians(), a, f, t_end);
    let num = dda(alpha, phi, a, f, t_end);
    let err = ((num - reference) / reference).abs();
    eprintln!(
        "α={alpha} φ={phi} A={a} f={f}: DDA {num:.5} m, Newmark {reference:.5} m, error {:.3} %",
        100.0 * err
    );
    assert!(reference.abs() > 1e-3, "the case must slide");
    assert!(err < 0.02, "α={alpha} φ={phi}: error {err}");
    assert!(
        err < 3e-3,
        "α={alpha} φ={phi}: error {err} within 2 % but above the regression bound 3e-3 (~7.5× today's 0.04 %): find what changed"
    );
}

#[test]
fn twenty_degree_incline_kamai_hatzor() {
    // A = 4 m/s² exceeds the down-slope yield acceleration g·tan(φ−α) for every φ.
    for phi in [22.0, 30.0, 35.0] {
        check(20.0, phi, 4.0, 1.0, 4.0);
    }
}

#[test]
fn forty_five_degree_incline_3d_dda_case() {
    check(45.0, 50.0, 2.0, 1.0, 4.0);
}
