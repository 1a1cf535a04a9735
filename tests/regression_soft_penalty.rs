//! Regression (issue 8): a penalty stiffness far too soft for the loads completed silently.
//! A 0.5 m rigid block (625 kg) on a fixed base with `penalty_stiffness` = 1e4 N/m sank ~0.3 m
//! (60 % of its side) into the base, and the run reported success: a solution of overlapping
//! blocks presented as an answer. Now a converged step that leaves a vertex deeper than
//! `SimParams::max_penetration_ratio` (5 %) of the thinner block stops with
//! `SimError::PenaltyTooSoft`, naming the blocks and the stiffness to use; and that advice works:
//! the same scene at the advised stiffness completes within the limit.
mod common;
use ashlar::motion::GroundMotion;
use ashlar::simulation::SimError;
use common::*;
use serde_json::json;

fn block_on_base(penalty: f64) -> ashlar::scene::Scene {
    let blocks = json!([
        { "id": "base", "material": "stone", "fixed": true, "vertices": [[-1.0, -0.5], [1.0, -0.5], [1.0, 0.0], [-1.0, 0.0]] },
        { "id": "block", "material": "stone", "block_model": "rigid", "vertices": [[-0.25, 0.0], [0.25, 0.0], [0.25, 0.5], [-0.25, 0.5]] },
    ]);
    parse(&scene_json(
        blocks,
        30.0,
        json!({ "time_step": 1e-3, "penalty_stiffness": penalty, "duration": 1.0 }),
    ))
}

/// Steps until the end or the first error.
fn run_to_end(penalty: f64) -> (Result<(), SimError>, f64) {
    let scene = block_on_base(penalty);
    let mut s = sim(&scene, &GroundMotion::none());
    while s.time < 1.0 - 1e-12 {
        if let Err(e) = s.step(1.0 - s.time) {
            return (Err(e), s.stats.max_penetration);
        }
    }
    (Ok(()), s.stats.max_penetration)
}

#[test]
fn soft_penalty_stops_with_advice_that_works() {
    let (r, _) = run_to_end(1e4);
    let e = r.expect_err("a 1e4 N/m penalty under a 625 kg block must be refused");
    let msg = e.to_string();
    eprintln!("{msg}");
    let SimError::PenaltyTooSoft {
        depth,
        thickness,
        needed,
        block_a,
        block_b,
        ..
    } = e
    else {
        panic!("expected PenaltyTooSoft, got {e:?}");
    };
    // Side 0.5 m for both blocks' 4A/P: the square block (0.5) is thinner than the base (≈0.67).
    assert!((thickness - 0.5).abs() < 1e-12, "thickness {thickness}");
    assert!(depth > 0.05 * 0.5, "depth {depth}");
    let mut ids = [block_a.as_str(), block_b.as_str()];
    ids.sort_unstable();
    assert_eq!(ids, ["base", "block"]);
    assert!(msg.contains("control.penalty_stiffness"), "{msg}");
    // The advised stiffness (penetration ∝ 1/k under the same load) with a factor 2 of margin
    // for the dynamic overshoot of the first contact: completes, within the limit.
    let (r, pen) = run_to_end(2.0 * needed);
    assert!(r.is_ok(), "advised stiffness {needed} still fails: {r:?}");
    assert!(pen <= 0.05 * 0.5, "penetration {pen} m");
}
