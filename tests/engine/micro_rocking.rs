//! Micro-rocking against Housner's impact law (issue #20; docs/accuracy-vs-speed.md,
//! "Micro-rocking: the landing corner takes the weight (session 35)"): a slender rigid column
//! released from a tilt of 15 µrad rocks freely on a fixed base, every landing slower than the
//! engine's settling threshold 2gΔt (corner at ≤ 1.5 mm/s against 1.96 mm/s at Δt = 1e-4 s).
//! The per-landing ratio r = |θ̇⁺|/|θ̇⁻| of the engine with `ImpactParams::hand_over_weight`
//! (and every landing an impact, `slow_factor` 0) is held to Housner's angular-momentum law for
//! a rectangle, r = 1 − 1.5 sin²α, a closed form that shares nothing with the engine.
//!
//! θ̇ on either side of a landing is fitted by least squares on [−2, −0.3] ms before and
//! [1.5, 3] ms after it and extrapolated to it (`analysis::reference::landings`, as
//! `examples/reduced_history.rs` measures):
//! in free rocking at 15 µrad gravity's torque is constant to 1e-4 within a half-cycle, so
//! θ̇ is linear there and the fit drops it exactly, and the contact's ringing after the
//! landing falls outside the windows.
//!
//! The penalty contact solver is pinned (also under `ASHLAR_CONTACT_SOLVER=dual`): the knob
//! hands over the springs' stored force, which the dual solver does not have. Measured with the
//! dual solver for the record: mean r 0.9623 with the knob (two landings at 0.918 and 0.939),
//! 0.9380 without. (Since session 38 the dual solver runs without the hand-over whatever the
//! knobs, `ImpactParams::without_hand_over`.)
use crate::common::*;
use ashlar::analysis::reference::{landings, Landing};
use ashlar::assembly::restitution::ImpactParams;
use ashlar::motion::GroundMotion;
use ashlar::simulation::{SimParams, Simulation};
use serde_json::json;

/// The slender column of the micro-rocking study: half-width 0.12 m, half-height 0.8 m
/// (α = 8.5°, Housner's r = 0.9670).
const B: f64 = 0.12;
const H: f64 = 0.8;
/// Release tilt, rad: the first landing at θ̇ ≈ √(2 p² sin α θ0) = 6.4e-3 rad/s, the corner
/// at 2bθ̇ = 1.5 mm/s, below the settling threshold 2gΔt = 1.96 mm/s at Δt = 1e-4 s.
const THETA0: f64 = 1.5e-5;
const DT: f64 = 1e-4;

/// The engine's per-landing ratios over the first 0.1 s (each landing: |θ̇⁺|/|θ̇⁻|) and the
/// fastest landing's |θ̇⁻| (rad/s), with the impact knobs given.
fn landing_ratios(impact: ImpactParams) -> (Vec<f64>, f64) {
    let v = tilted_column(
        B,
        H,
        THETA0,
        "rigid",
        json!({ "model": "dda", "duration": 0.1, "time_step": DT, "contact_solver": "penalty" }),
    );
    let scene = parse(&v);
    let params = SimParams {
        impact,
        ..SimParams::default()
    };
    let mut s = Simulation::new(&scene, &GroundMotion::none(), params);
    // θ relative to upright (the column starts rotated by −θ0), and θ̇.
    let mut hist = Vec::new();
    run(&mut s, 0.1, |s| {
        hist.push((
            s.time(),
            s.geoms()[1].rotation - THETA0,
            s.block_velocity(1)[2],
        ))
    });
    let found = landings(&hist, 0.0, 0.1);
    let fastest = found.iter().fold(0.0f64, |a, l| a.max(l.before));
    let ratios = found.iter().map(Landing::ratio).collect();
    (ratios, fastest)
}

fn housner_r() -> f64 {
    let alpha = (B / H).atan();
    1.0 - 1.5 * alpha.sin().powi(2)
}

/// Tolerance 0.5 % on the mean r (chosen before measuring with the knob): the default engine's
/// slow landings lose 1.6 % more of θ̇ than Housner's law under Loma Prieta (session 34), the
/// fit's own error on Housner's history was ≤ 0.25 %, so 0.5 % separates a pivot that hands
/// the weight over from one that rings. Every landing is also held to 1 %.
#[test]
fn slow_landings_keep_housners_ratio_with_the_hand_over() {
    // The knobs before session 38 (no hand-over), then session 35's law.
    let mut impact = ImpactParams {
        hand_over_weight: false,
        hand_over_below: None,
        ..ImpactParams::default()
    };
    let (off, _) = landing_ratios(impact);
    impact.hand_over_weight = true;
    impact.slow_factor = 0.0;
    let (on, fastest) = landing_ratios(impact);
    let rh = housner_r();
    let mean = |v: &[f64]| v.iter().sum::<f64>() / v.len() as f64;
    eprintln!("Housner r = {rh:.5}; hand-over: {on:.5?} (mean {:.5}); default knobs: {off:.5?} (mean {:.5})", mean(&on), mean(&off));
    assert_housners_ratio(&on, fastest);
}

/// Slow landings only (the corner below 2gΔt at every landing measured), at least five, their
/// mean r within 0.5 % of Housner's and each within 1 % (the tolerances' reasons above).
fn assert_housners_ratio(on: &[f64], fastest: f64) {
    let rh = housner_r();
    assert!(
        2.0 * B * fastest < 2.0 * 9.81 * DT,
        "a landing at {fastest} rad/s is not slow"
    );
    assert!(on.len() >= 5, "only {} landings measured", on.len());
    let e = on.iter().sum::<f64>() / on.len() as f64 / rh - 1.0;
    assert!(
        e.abs() < 0.005,
        "mean r off Housner's by {:.3} %",
        100.0 * e
    );
    for r in on {
        assert!(
            (r / rh - 1.0).abs() < 0.01,
            "a landing's r {r} off Housner's {rh}"
        );
    }
}

/// The hand-over with its own threshold (`ImpactParams::hand_over_below`, session 37): with
/// `slow_factor` left at its default 2, the landings of free micro-rocking are pivot landings
/// (the other corner carries the weight), so the knob alone must make them impacts and hand the
/// weight over, and give Housner's r to the same tolerances as the test above (same reasons);
/// without it (`hand_over_weight` alone, session 35) they are the springs' and the mean r is
/// the default knobs' (checked: it fails the 0.5 %, so the test can tell the two apart).
#[test]
fn pivot_landings_keep_housners_ratio_with_the_hand_overs_own_threshold() {
    let mut impact = ImpactParams {
        hand_over_weight: true,
        hand_over_below: None,
        ..ImpactParams::default()
    };
    let rh = housner_r();
    let mean = |v: &[f64]| v.iter().sum::<f64>() / v.len() as f64;
    let (alone, _) = landing_ratios(impact);
    impact.hand_over_below = Some(2.0);
    let (on, fastest) = landing_ratios(impact);
    eprintln!(
        "Housner r = {rh:.5}; own threshold 2: {on:.5?} (mean {:.5}); hand-over alone: {alone:.5?} (mean {:.5})",
        mean(&on),
        mean(&alone)
    );
    assert!(
        (mean(&alone) / rh - 1.0).abs() >= 0.005,
        "the hand-over alone already meets the tolerance: the test cannot tell the knob's effect"
    );
    assert_housners_ratio(&on, fastest);
}
