//! Single-contact tests after Li et al. 2018, "Validation tests for discrete element codes using
//! single-contact systems" (T1 and T3; docs/verification.md), adapted to a block on a
//! fixed block: both of the block's bottom corners touch the base, so the contact stiffness
//! seen by the block is twice the per-contact penalty.
//!
//! T1 (normal impact, no gravity): contact duration π√(m/k) (tolerance 1 %: the open–close
//! loop resolves the contact's start and end to one step, 0.1 % of the duration here, and the
//! DDA integrator's numerical damping shortens it slightly) and, with the trapezoidal
//! integrator, rebound speed within 0.5 % of the incoming speed (docs/verification.md's bound).
//!
//! T3 (shear with Coulomb sliding, Eqs. 18–20): stick (harmonic, ω = √(k_s/m)), slide at
//! constant deceleration μg, re-stick about the shifted equilibrium b; the slip time, the
//! re-stick time and the sliding distance within 2 % (docs/verification.md's bound).
use crate::common;
use ashlar::contact::ContactState;
use ashlar::motion::GroundMotion;
use common::*;
use serde_json::json;

fn two_blocks(
    h: f64,
    gap: f64,
    friction: f64,
    control: serde_json::Value,
    gravity: f64,
    vy: f64,
) -> ashlar::scene::Scene {
    let blocks = json!([
        { "id": "base", "material": "stone", "fixed": true, "vertices": [[-3.0, -1.0], [3.0, -1.0], [3.0, 0.0], [-3.0, 0.0]] },
        { "id": "block", "material": "stone", "block_model": "rigid",
          "vertices": [[-1.0, gap], [1.0, gap], [1.0, gap + h], [-1.0, gap + h]] },
    ]);
    let mut v = scene_json(blocks, friction, control);
    v["gravity"] = json!(gravity);
    v["initial"] = json!([{ "block": "block", "velocity": [0.0, vy] }]);
    parse(&v)
}

/// Returns (contact duration, rebound speed) for an impact at 0.5 m/s.
fn impact(integrator: &str) -> (f64, f64, f64) {
    let h = 0.2;
    let p = 2.5e7;
    let scene = two_blocks(
        h,
        1e-4,
        30.0,
        // "contact": this test measures the penalty spring's own impact (duration π√(m/k),
        // rebound), which the default impact law (e = 0) would replace.
        json!({ "time_step": 1e-5, "penalty_stiffness": p, "integrator": integrator, "duration": 0.05, "restitution": "contact" }),
        0.0,
        -0.5,
    );
    let m = 2500.0 * 2.0 * h;
    let expected = std::f64::consts::PI * (m / (2.0 * p)).sqrt();
    let mut s = sim(&scene, &GroundMotion::none());
    let (mut start, mut end) = (None, None);
    run_until(&mut s, 0.05, |s| {
        let closed = s.contacts().contacts.iter().any(|c| c.state.is_closed());
        if closed && start.is_none() {
            start = Some(s.time());
        }
        if !closed && start.is_some() {
            end = Some(s.time());
            return true;
        }
        false
    });
    let (start, end) = (start.expect("contact closed"), end.expect("contact opened"));
    (end - start, s.states()[0].vel[1], expected)
}

#[test]
fn normal_impact_contact_duration_and_rebound() {
    for integrator in ["dda", "trapezoidal"] {
        let (duration, rebound, expected) = impact(integrator);
        eprintln!("{integrator}: contact {duration:.5} s (π√(m/k) = {expected:.5} s, {:+.2e}), rebound {rebound:.7} m/s ({:+.2e})", duration / expected - 1.0, rebound / 0.5 - 1.0);
        assert!(
            (duration - expected).abs() < 0.01 * expected,
            "{integrator}: duration {duration} vs {expected}"
        );
        assert!(
            (duration - expected).abs() < REGRESSION_IMPACT_DURATION * expected,
            "{integrator}: duration {duration} vs {expected}: within 1 % but beyond the regression bound"
        );
        if integrator == "trapezoidal" {
            assert!(
                (rebound - 0.5).abs() < 0.005 * 0.5,
                "rebound speed {rebound}"
            );
            assert!(
                (rebound - 0.5).abs() < REGRESSION_REBOUND * 0.5,
                "rebound speed {rebound}: within 0.5 % but beyond the regression bound"
            );
        }
    }
}

#[test]
fn shear_stick_slide_restick() {
    let h = 0.002;
    let p = 1.0e6;
    let mu: f64 = 0.6;
    let m = 2500.0 * 2.0 * h;
    let scene = two_blocks(
        h,
        0.0,
        mu.atan().to_degrees(),
        json!({ "time_step": 1e-5, "penalty_stiffness": p, "duration": 0.1 }),
        G,
        0.0,
    );
    let mut s = sim(&scene, &GroundMotion::none());
    let kt = 2.0 * s.springs().shear;
    let w = (kt / m).sqrt();
    let x1 = mu * m * G / kt;
    let v0 = 2.0 * x1 * w;
    // Settle the normal springs under gravity first: the block starts on undeformed springs and
    // would bounce on them. Kinetic damping at 900 1/s (≈ 2ω of the vertical mode, critical)
    // for 20 ms, then none, then launch.
    s.set_kinetic_damping_rate(900.0);
    run(&mut s, 0.02, |_| {});
    s.set_kinetic_damping_rate(0.0);
    let x_start = displacement(&s, 1)[0];
    s.states_mut()[0].vel[0] = v0;
    s.states_mut()[0].vel[1] = 0.0;
    let t0 = s.time();
    let ts1 = (x1 * w / v0).asin() / w;
    let vs1 = v0 * (w * ts1).cos();
    let ts4 = ts1 + vs1 / (mu * G);
    let b = vs1 * vs1 / (2.0 * mu * G);
    let (mut slip_at, mut restick_at) = (None, None);
    run_until(&mut s, t0 + ts4 + 0.05, |s| {
        let sliding = s
            .contacts()
            .contacts
            .iter()
            .filter(|c| matches!(c.state, ContactState::Sliding { .. }))
            .count();
        if sliding == 2 && slip_at.is_none() {
            slip_at = Some(s.time() - t0);
        }
        if slip_at.is_some() && sliding == 0 && restick_at.is_none() {
            restick_at = Some(s.time() - t0);
        }
        false
    });
    let x_end = displacement(&s, 1)[0] - x_start;
    let (slip_at, restick_at) = (slip_at.expect("slid"), restick_at.expect("re-stuck"));
    eprintln!("slip at {slip_at:.5} s (ref {ts1:.5}, {:+.2e}), re-stick at {restick_at:.5} s (ref {ts4:.5}, {:+.2e}), mean position after {x_end:.4e} m (ref b = {b:.4e} m)", slip_at / ts1 - 1.0, restick_at / ts4 - 1.0);
    assert!((slip_at - ts1).abs() < 0.02 * ts1);
    assert!((restick_at - ts4).abs() < 0.02 * ts4);
    assert!(
        (restick_at - ts4).abs() < REGRESSION_RESTICK * ts4,
        "re-stick at {restick_at} vs {ts4}: within 2 % but beyond the regression bound"
    );
    // After re-sticking the block oscillates about b with amplitude x1; sample the mean over
    // whole periods through the equilibrium position.
    let period = 2.0 * std::f64::consts::PI / w;
    let mut sum = 0.0;
    let mut n = 0.0;
    let t_mean = s.time();
    run(&mut s, t_mean + 4.0 * period, |s| {
        sum += displacement(s, 1)[0] - x_start;
        n += 1.0;
    });
    let mean = sum / n;
    eprintln!(
        "mean position after re-stick {mean:.5e} m vs b = {b:.5e} m ({:+.2e})",
        mean / b - 1.0
    );
    assert!(
        (mean - b).abs() < 0.02 * b,
        "sliding distance {mean} vs {b}"
    );
    assert!(
        (mean - b).abs() < REGRESSION_SLIDE_DISTANCE * b,
        "sliding distance {mean} vs {b}: within 2 % but beyond the regression bound"
    );
}

// Regression bounds (5× the error measured 2026-11-25; the contact solve is being changed on
// another branch: re-measure after the merge with `cargo test --test engine -- single_contact::
// --nocapture`). The slip instant has none: its measured error, +0.475 %, is within 5× of the
// 2 % tolerance, which binds.
/// Contact duration against π√(m/k), both integrators: measured −6.85e-4 (one step of 1e-5 s), both.
const REGRESSION_IMPACT_DURATION: f64 = 0.0036;
/// Trapezoidal rebound speed against 0.5 m/s: measured +1.1e-13 (round-off; ~9×).
const REGRESSION_REBOUND: f64 = 1e-12;
/// Re-stick instant against Eq. 20: measured +6.4e-4.
const REGRESSION_RESTICK: f64 = 0.0032;
/// Mean position after re-stick against b: measured −3.36e-3.
const REGRESSION_SLIDE_DISTANCE: f64 = 0.017;
