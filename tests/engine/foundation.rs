//! Block on a shaking foundation (Yagoda-Biran & Hatzor 2015, §3.4, §4.5.3, Eqs. 11–13, 16–17) as a 2D model with
//! `driven_block`: the foundation (16 m long, so the block never reaches its ends) follows d1(t) = A(1 − cos 2πft) exactly; a flat block
//! (2 m × 0.1 m) on top responds through friction μ. Reference: the semi-analytic rules of
//! Eq. 17 integrated with Δt = 1e-5 s (`ashlar::analysis::reference`). Tolerance: docs/verification.md's 3 %, measured as the largest
//! |d2_DDA − d2_ref| over the run relative to the largest |d2_ref| (a pointwise relative error is
//! undefined where the displacement crosses zero).
use crate::common;
use ashlar::analysis::reference::foundation_eq17;
use ashlar::motion::{GroundMotion, Signal};
use common::*;
use serde_json::json;
use std::f64::consts::PI;

/// Semi-analytic response of block 2 (Eq. 17, `ashlar::analysis::reference`, Δt = 1e-5 s),
/// sampled every `every` seconds.
fn reference(a: f64, f: f64, mu: f64, t_end: f64, every: f64) -> Vec<(f64, f64)> {
    let dt = 1e-5;
    foundation_eq17(a, f, mu, G, t_end, dt, (every / dt).round() as usize)
}

fn dda(a: f64, f: f64, mu: f64, t_end: f64, every: f64) -> Vec<(f64, f64)> {
    let w = 2.0 * PI * f;
    let blocks = json!([
        { "id": "foundation", "material": "stone", "vertices": [[-8.0, -0.5], [8.0, -0.5], [8.0, 0.0], [-8.0, 0.0]] },
        { "id": "block", "material": "stone", "block_model": "rigid", "vertices": [[-1.0, 0.0], [1.0, 0.0], [1.0, 0.1], [-1.0, 0.1]] },
    ]);
    // Yagoda-Biran & Hatzor's Table 2 parameters: ρ = 2250 kg/m³, E = 17 GPa, ν = 0.22, g0 = 1e9 N/m,
    // g1 = 1e-4 s, g2 = 0.001. (At Δt = 1e-3 s the 3 Hz case drifts 3.2 % ahead: the DDA
    // integrator's first-order velocity update; see docs/accuracy-vs-speed.md.)
    let mut v = scene_json(
        blocks,
        mu.atan().to_degrees(),
        json!({ "time_step": 1e-4, "max_displacement_ratio": 1e-3, "penalty_stiffness": 1e9, "duration": t_end }),
    );
    v["materials"] =
        json!({ "stone": { "density": 2250.0, "young_modulus": 17.0e9, "poisson_ratio": 0.22 } });
    v["excitation"] = json!({ "type": "driven_block", "block": "foundation" });
    let scene = parse(&v);
    // d1 = A(1 − cos ωt) ⇔ a1 = Aω² cos ωt from rest: a cosine pulse, integrated exactly.
    let motion = GroundMotion::horizontal(Signal::Pulse {
        amplitude: a * w * w,
        period: 1.0 / f,
        cycles: f * t_end + 1.0,
        phase: std::f64::consts::FRAC_PI_2,
    });
    let mut s = sim(&scene, &motion);
    let mut out = vec![(0.0, 0.0)];
    let mut next = every;
    while s.time() < t_end - 1e-12 {
        s.step(next - s.time()).expect("simulation step");
        if s.time() >= next - 1e-9 {
            out.push((s.time(), displacement(&s, 1)[0]));
            next += every;
        }
    }
    out
}

/// Tolerance 3 % of the peak (docs/verification.md); `regression`: a second bound at 5× the
/// error measured 2026-11-25 for the case (penalty, the default; the dual solver measured
/// ≤ 0.37 %, inside every bound), or the tolerance where 5× exceeds it. The impact and contact
/// work on other branches should not move these (no impact here), but re-measure after a change
/// of the contact solve: `cargo test --test engine -- foundation:: --nocapture`.
fn check(a: f64, f: f64, mu: f64, regression: f64) {
    let t_end = 5.0;
    let r = reference(a, f, mu, t_end, 0.01);
    let d = dda(a, f, mu, t_end, 0.01);
    let peak = r.iter().fold(0.0f64, |m, p| m.max(p.1.abs()));
    let worst = r
        .iter()
        .zip(&d)
        .fold(0.0f64, |m, (p, q)| m.max((p.1 - q.1).abs()));
    eprintln!(
        "A={a} f={f} μ={mu}: peak {peak:.4} m, worst deviation {worst:.2e} m ({:.2} %)",
        100.0 * worst / peak
    );
    assert!(
        worst < 0.03 * peak,
        "A={a} f={f} μ={mu}: {worst} vs peak {peak}"
    );
    assert!(
        worst < regression * peak,
        "A={a} f={f} μ={mu}: {:.3} % of peak, within 3 % but beyond the regression bound {:.2} % (find what changed)",
        100.0 * worst / peak,
        100.0 * regression
    );
}

/// Regression bounds, measured 2026-11-25 (% of peak): 2 Hz 0.51, 3 Hz 0.44, 5 Hz 0.58 (A =
/// 0.2 m); 1 Hz: A = 0.3 m 0.69 (5× exceeds the tolerance, which binds), 0.5 m 0.46, 1 m 0.22;
/// A = 0.5 m, 1 Hz: μ = 0.1 0.14, μ = 1 0.69 (tolerance binds).
const REGRESSION_FOUNDATION_2HZ: f64 = 0.026;
const REGRESSION_FOUNDATION_3HZ: f64 = 0.022;
const REGRESSION_FOUNDATION_5HZ: f64 = 0.029;
const REGRESSION_FOUNDATION_A03: f64 = 0.03;
const REGRESSION_FOUNDATION_A05: f64 = 0.023;
const REGRESSION_FOUNDATION_A1: f64 = 0.011;
const REGRESSION_FOUNDATION_MU01: f64 = 0.007;
const REGRESSION_FOUNDATION_MU1: f64 = 0.03;

#[test]
fn amplitude_0_2_m_frequencies_2_3_5_hz() {
    for (f, r) in [
        (2.0, REGRESSION_FOUNDATION_2HZ),
        (3.0, REGRESSION_FOUNDATION_3HZ),
        (5.0, REGRESSION_FOUNDATION_5HZ),
    ] {
        check(0.2, f, 0.6, r);
    }
}

#[test]
fn one_hz_amplitudes_0_3_0_5_1_m() {
    for (a, r) in [
        (0.3, REGRESSION_FOUNDATION_A03),
        (0.5, REGRESSION_FOUNDATION_A05),
        (1.0, REGRESSION_FOUNDATION_A1),
    ] {
        check(a, 1.0, 0.6, r);
    }
}

#[test]
fn one_hz_half_metre_friction_0_1_0_6_1_0() {
    for (mu, r) in [
        (0.1, REGRESSION_FOUNDATION_MU01),
        (0.6, REGRESSION_FOUNDATION_A05),
        (1.0, REGRESSION_FOUNDATION_MU1),
    ] {
        check(0.5, 1.0, mu, r);
    }
}
