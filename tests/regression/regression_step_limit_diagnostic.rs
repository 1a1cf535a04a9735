//! What broke: a step refused because a block would move farther than the step's displacement
//! limit, at the last time-step cut allowed, ended the run with "open–close did not converge
//! … contact between blocks "?" and "?"": the penalty solver's wording (also under the dual
//! solver, where the pile of examples/pile.rs met it after an accepted stalled solve), and no
//! block named, although the solver had converged and the limit was the cause. It now stops
//! with `SimError::StepTooLarge`, naming the block, how far it would move and the limit.
use crate::common;
use ashlar::motion::GroundMotion;
use ashlar::simulation::{SimError, SimParams, Simulation};
use common::*;
use serde_json::json;

/// A 1 m block thrown sideways at 1000 m/s high above a fixed floor: 1 m in the first 1 ms
/// step, against a limit of 0.01 × the model's half size. `min_dt` = 0.5 ms forbids the cut
/// that would resolve it, so the first step is refused for good.
#[test]
fn a_step_over_the_displacement_limit_names_the_block() {
    for solver in ["penalty", "dual"] {
        let blocks = json!([
            { "id": "floor", "material": "stone", "fixed": true,
              "vertices": [[-5.0, -1.0], [5.0, -1.0], [5.0, 0.0], [-5.0, 0.0]] },
            { "id": "flyer", "material": "stone",
              "vertices": [[0.0, 3.0], [1.0, 3.0], [1.0, 4.0], [0.0, 4.0]] },
        ]);
        let mut v = scene_json(
            blocks,
            30.0,
            json!({ "time_step": 1e-3, "max_displacement_ratio": 0.01, "contact_solver": solver }),
        );
        v["initial"] = json!([{ "block": "flyer", "velocity": [1000.0, 0.0] }]);
        let scene = parse(&v);
        let params = SimParams {
            min_dt: 5e-4,
            ..SimParams::default()
        };
        let mut sim = Simulation::new(&scene, &GroundMotion::none(), params);
        let limit = sim.max_step_displacement();
        let err = sim.step(1.0).expect_err("a 1 m step was accepted");
        eprintln!("{solver}: {err}");
        match &err {
            SimError::StepTooLarge {
                block,
                moved,
                limit: l,
                cuts,
                ..
            } => {
                assert_eq!(block, "flyer");
                assert_eq!(*l, limit);
                assert!(*moved > limit);
                // v·Δt = 1 m; gravity adds ½gΔt² ≈ 5e-6 m across it.
                assert!((moved - 1.0).abs() < 1e-4, "moved {moved} m");
                assert_eq!(*cuts, 1);
            }
            other => panic!("{solver}: expected StepTooLarge, got {other:?}"),
        }
        assert!(err.to_string().contains("\"flyer\""), "{err}");
    }
}
