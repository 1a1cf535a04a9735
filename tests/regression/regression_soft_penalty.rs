//! Regression: a penalty stiffness far too soft for the loads completed silently.
//! A 0.5 m rigid block (625 kg) on a fixed base with `penalty_stiffness` = 1e4 N/m sank ~0.12 m
//! into the base and the run reported success. Once a vertex is deeper than the contact search
//! distance, contact detection drops it (`gap < −search`) and the blocks pass through each other
//! unseen. Now a converged step that leaves a penetration deeper than the smaller of
//! `SimParams::max_penetration_ratio` (5 %) of the thinner block and the search distance stops
//! with `SimError::PenaltyTooSoft`, naming the blocks and advising a stiffer penalty; the advice
//! works: the same scene with "auto" completes within the limit.
use crate::common;
use ashlar::motion::GroundMotion;
use ashlar::simulation::SimError;
use common::*;
use serde_json::json;

fn block_on_base(penalty: serde_json::Value) -> ashlar::scene::Scene {
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

/// Steps until the end or the first error; returns the result and the deepest penetration.
fn run_to_end(penalty: serde_json::Value) -> (Result<(), SimError>, f64) {
    let scene = block_on_base(penalty);
    let mut s = sim(&scene, &GroundMotion::none());
    while s.time() < 1.0 - 1e-12 {
        if let Err(e) = s.step(1.0 - s.time()) {
            return (Err(e), s.stats().max_penetration);
        }
    }
    (Ok(()), s.stats().max_penetration)
}

#[test]
fn soft_penalty_stops_with_advice_that_works() {
    let (r, _) = run_to_end(json!(1e4));
    let e = r.expect_err("a 1e4 N/m penalty under a 625 kg block must be refused");
    let msg = e.to_string();
    eprintln!("{msg}");
    let SimError::PenaltyTooSoft {
        depth,
        limit,
        explanation,
        block_a,
        block_b,
        ..
    } = e
    else {
        panic!("expected PenaltyTooSoft, got {e:?}");
    };
    // The limit is at most 5 % of the block's side (0.5 m, the thinner of the two).
    assert!(
        limit <= 0.05 * 0.5 + 1e-15 && depth > limit,
        "depth {depth}, limit {limit}"
    );
    let mut ids = [block_a.as_str(), block_b.as_str()];
    ids.sort_unstable();
    assert_eq!(ids, ["base", "block"]);
    assert!(explanation.contains("control.penalty_stiffness"), "{msg}");
    // Following the advice ("auto": 10·E = 2e11 N/m): completes, penetration within the limit.
    let (r, pen) = run_to_end(json!("auto"));
    assert!(r.is_ok(), "auto penalty fails: {r:?}");
    assert!(pen <= limit, "penetration {pen} m above {limit} m");
}
