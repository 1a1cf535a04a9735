//! Regression: a phantom penetration stopped the 1700-block pile at step 187 with
//! `PenaltyTooSoft` ("a vertex of b40_21 3.8 cm inside b40_20, already this deep when its
//! contact was found") and made 1:500 needles gain energy before stopping. Two blocks face to
//! face with a relative rotation of 2.7e-3 rad (above the entrance criterion's 1e-3 rad angle
//! tolerance): the right block's top-left vertex sits 0.08 mm *outside* the left block, but
//! the face it touches was rejected by the entrance criterion and the left block's bottom edge,
//! whose line the vertex is 7.8 cm beyond, was taken instead: a closed contact 7.8 cm deep.
//! The geometry is the pile's at the failing step (the right block moved 2 µm right so the
//! scene validator sees no overlap at the start). Fails without the fix in
//! contact/vertex_edge.rs (`PenaltyTooSoft` at the first step).
use crate::common;
use ashlar::motion::GroundMotion;
use ashlar::simulation::{SimParams, Simulation};
use common::*;
use serde_json::json;

#[test]
fn outside_vertex_is_not_found_deep_inside_its_neighbour() {
    let blocks = json!([
        { "id": "left", "material": "stone", "fixed": true, "vertices": [
            [8.000053556221753, 8.203145931882563], [8.40004252152172, 8.20388651421613],
            [8.399674955454675, 8.403885594805596], [7.999685990154714, 8.403145012472004]] },
        { "id": "right", "material": "stone", "vertices": [
            [8.400144628141174, 8.081631594985907], [8.800115730516161, 8.081974148666433],
            [8.799950423706624, 8.281977137748559], [8.39997932133163, 8.281634584068032]] },
    ]);
    // g2 = 0.1 makes the search distance (2.5 × g2 × the model's half size ≈ 0.1 m) reach the
    // bottom edge 7.8 cm away, as the pile's larger model did at its g2.
    let scene = parse(&scene_json(
        blocks,
        0.0,
        json!({ "duration": 0.01, "max_displacement_ratio": 0.1 }),
    ));
    let mut sim = Simulation::new(&scene, &GroundMotion::none(), SimParams::default());
    for _ in 0..5 {
        if let Err(e) = sim.step(1.0) {
            panic!("{e}");
        }
    }
    // The right block falls freely past the left one's face; no contact claims a depth
    // beyond round-off of the 0.2 mm face overlap.
    assert!(
        sim.stats().max_penetration < 1e-3,
        "max penetration {:.3e} m",
        sim.stats().max_penetration
    );
}
