//! Regression (fixed): the dual solver stalled on a phantom penetration beside an edge's end.
//!
//! Symptom: the rocking frame (`presets::RockingFrame`, γ = 1) under Loma Prieta (Capitola
//! 000) at 0.6 g with `"contact_solver": "dual"` stopped at 6.397 s with `did not converge`
//! at the right column–cap contact (2 Δt cuts to 1.6e-9 s, 20,000 iterations, violation
//! 3.5e-8 m), where the penalty solver completes.
//!
//! Cause as found (a temporary print of the contacts when the solve failed):
//! the cap's bottom corners and the columns' top outer corners coincide at rest. Rocking, the
//! right column's top corner was 87 µm beyond the end of the cap's bottom edge, outside the
//! cap, and 0.36 µm below that edge's line; detection keeps such a vertex (a vertex–vertex
//! approach) with the signed distance to the line as its gap, and the solve had to undo a
//! penetration that did not exist.
//!
//! Fixed in `solve::dual::gap::terms_of`: such a contact (ξ outside [0, 1], vertex outside the
//! edge's block, deeper than 10× the solve's tolerance) gets g0 = 0 (docs/dual.md). This test
//! runs the frame past the stall, to 6.6 s, and asserts that it completes with the columns
//! together (mismatch measured 5.7e-5 rad over the whole record; bound 1e-3 rad as in
//! `regression_simultaneous_landings`).
use crate::common::*;
use serde_json::json;

#[test]
fn the_dual_frame_passes_the_cap_corner_pair() {
    let frame = ashlar::presets::RockingFrame::SEED.gamma(1.0);
    let scene =
        parse(&frame.json(json!({ "model": "dda", "duration": 6.6, "contact_solver": "dual" })));
    let motion = ashlar::analysis::study_records::load_record(
        &ashlar::presets::records_dir(),
        "loma-prieta-1989-capitola-000.at2",
        0.6,
    )
    .expect("record");
    let mut s = sim(&scene, &motion);
    let mut worst = 0.0f64;
    while s.time() < 6.6 - 1e-12 {
        if let Err(e) = s.step(6.6 - s.time()) {
            panic!("the dual frame stopped at {:.6} s: {e}", s.time());
        }
        let (l, r) = (s.geoms()[1].rotation, s.geoms()[2].rotation);
        worst = worst.max((l - r).abs());
    }
    eprintln!("dual frame to 6.6 s: column mismatch {worst:.2e} rad");
    assert!(worst < 1e-3, "the columns parted by {worst} rad");
}
