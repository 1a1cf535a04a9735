//! Regression (fixed): open–close chatter at zero or near-zero Coulomb limit.
//!
//! Symptom: a block landing on a fixed slab with friction angle 0 stalls at the first impact:
//! every step needs time-step cuts, Δt collapses to ~1e-13 s and simulated time stops
//! advancing (found by tests/engine/invariants.rs, frictionless bounce). With φ = 1° the same happens
//! at a stick–slip transition during the 10th impact (Δt → 1e-20 s).
//!
//! Fixed by hysteresis in the stick–slip transitions (`OpenCloseParams::hysteresis`), by not
//! counting direction flips of frictionless sliding contacts, and by a Δt floor
//! (`SimParams::min_dt`) below which the step fails with `SimError::NotConverged`.
//!
//! Cause as found (src/solve/open_close.rs, `update_state`, lines ~109–124): with a shear limit
//! of 0 (φ = 0, unbonded) a locked contact turns Sliding{dir: s.signum()} on any round-off
//! shear, and a sliding contact turns Locked as soon as `slip * dir < 0`, again on round-off;
//! a direction flip also counts as a change. The loop never settles, the step is cut
//! (src/simulation/mod.rs ~194–198), and since a step is accepted after at most `max_cuts` cuts
//! with no floor on Δt for non-convergence, Δt shrinks step after step instead of the run
//! failing with `SimError::NotConverged`. Suggested fix: hysteresis (Sliding → Locked only when
//! slip·dir < −ε, Locked → Sliding only when |f| > limit + ε, ε ~ 1e-12 × k·length); with a
//! zero limit keep the contact Sliding and do not count direction flips; and fail (typed
//! error) when Δt falls below `SimParams::min_dt` because of non-convergence.
//!
//! Test: 0.1 s of a 0.2 m block dropped 2 mm onto a frictionless slab, Δt = 1e-4 s fixed. The
//! run must take no more than 2× the nominal 1000 steps (a few cuts at impact are fine; the
//! stall takes millions) and reach t = 0.1 s. The step budget keeps the test from hanging.
use crate::common;
use ashlar::motion::GroundMotion;
use common::*;
use serde_json::json;

fn drop_on_slab(friction_deg: f64) -> (f64, u64) {
    let drop = 2.0e-3;
    let blocks = json!([
        { "id": "slab", "material": "stone", "fixed": true, "vertices": [[-0.5, -0.3], [0.5, -0.3], [0.5, 0.0], [-0.5, 0.0]] },
        { "id": "block", "material": "stone", "block_model": "rigid",
          "vertices": [[-0.1, drop], [0.1, drop], [0.1, drop + 0.2], [-0.1, drop + 0.2]] },
    ]);
    let scene = parse(&scene_json(
        blocks,
        friction_deg,
        json!({ "time_step": 1e-4, "duration": 0.1 }),
    ));
    let mut s = sim(&scene, &GroundMotion::none());
    while s.time() < 0.1 - 1e-12 && s.stats().steps < 2000 {
        if let Err(e) = s.step(0.1 - s.time()) {
            panic!("simulation failed: {e}");
        }
    }
    (s.time(), s.stats().steps)
}

#[test]
fn frictionless_landing_does_not_stall() {
    let (t, steps) = drop_on_slab(0.0);
    assert!(t >= 0.1 - 1e-12, "stalled at t = {t} s after {steps} steps");
}

/// The same landing with φ = 30° runs normally: isolates the zero limit as the trigger.
#[test]
fn landing_with_friction_does_not_stall() {
    let (t, steps) = drop_on_slab(30.0);
    assert!(t >= 0.1 - 1e-12, "stalled at t = {t} s after {steps} steps");
}
