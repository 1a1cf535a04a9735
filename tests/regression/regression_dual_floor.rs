//! What broke: the floor for non-converging steps (`SimParams::unconverged_floor_ratio`, a
//! scene's `control.unconverged_floor`) with `contact_solver: "dual"` panicked (index out of
//! bounds in `block_increment`): at the floor an unconverged dual solve went on to the step's
//! checks, whose displacement check reads increments the dual solve never wrote (found by
//! running `tests/engine/dual_stall.rs` with the floor on, session 39).
//!
//! Fixed: the floor is the penalty solver's only (an unconverged dual solve has no iterate to
//! take), so under the dual solver a non-converging step is cut as without the floor, and a
//! scene asking for both is refused naming `control.unconverged_floor`. Checked here: the
//! starved dual solve of `dual_stall.rs` ends with the same typed `DualNotConverged` diagnostic
//! with the floor as without it, and the scene refusal.
use crate::common;
use ashlar::motion::GroundMotion;
use ashlar::scene::{parse_scene, BlockKind, BlockModel, Restitution};
use ashlar::simulation::{SimError, SimParams, Simulation};
use common::*;
use serde_json::json;

/// `dual_stall.rs`'s scene: a frictionless 3 × 3 stack, its top middle block thrown down at
/// 1 m/s, deformable, the impact left to the contact.
fn struck_stack() -> ashlar::scene::Scene {
    let mut stack = aligned_stack(3, 3);
    stack.control.restitution = Restitution::Contact;
    for b in &mut stack.blocks {
        if let BlockKind::Free(m) = &mut b.kind {
            *m = BlockModel::Deformable;
        }
    }
    stack
}

/// The dual solver with no iteration at all (every solve stalls), with or without the floor.
fn run(floor: Option<f64>) -> Result<Simulation, SimError> {
    let mut p = SimParams::default();
    p.dual.max_cg_iterations = 0;
    p.dual.max_iterations = 0;
    p.unconverged_floor_ratio = floor;
    let mut s = Simulation::new(&struck_stack(), &GroundMotion::none(), p);
    while s.time() < 0.06 - 1e-12 {
        s.step(0.06 - s.time())?;
    }
    Ok(s)
}

#[test]
fn the_floor_leaves_an_unconverged_dual_solve_to_the_cuts() {
    let diagnostic = |r: Result<Simulation, SimError>| match r {
        Err(SimError::DualNotConverged {
            cuts,
            block_a,
            block_b,
            ..
        }) => (cuts, block_a, block_b),
        Err(other) => panic!("expected DualNotConverged, got {other:?}"),
        Ok(s) => panic!(
            "a solver without iterations converged ({} steps)",
            s.stats().steps
        ),
    };
    let without = diagnostic(run(None));
    let with = diagnostic(run(Some(0.1)));
    assert_eq!(with, without, "the floor changed the dual solver's run");
}

#[test]
fn a_scene_asking_for_the_floor_with_the_dual_solver_is_refused() {
    let blocks = json!([
        { "id": "slab", "material": "stone", "fixed": true,
          "vertices": [[-0.5, -0.3], [0.5, -0.3], [0.5, 0.0], [-0.5, 0.0]] },
        { "id": "block", "material": "stone",
          "vertices": [[-0.1, 0.0], [0.1, 0.0], [0.1, 0.2], [-0.1, 0.2]] },
    ]);
    let scene = scene_json(
        blocks,
        30.0,
        json!({ "contact_solver": "dual", "unconverged_floor": 0.1 }),
    );
    let text = parse_scene(&scene.to_string())
        .expect_err("refused")
        .to_string();
    assert!(
        text.contains("control.unconverged_floor") && text.contains("penalty"),
        "{text}"
    );
}
