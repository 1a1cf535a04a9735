//! The floor of the cuts for a non-converging open–close loop
//! (`SimParams::unconverged_floor_ratio`, opt-in, docs/contact-solve.md §24) on a wall shaken
//! to collapse: the 105-stone wall of `ashlar scene wall --set length=6 --set height=3 --set
//! openings=0` under Northridge (Mulholland 009) scaled to a PGA of 1.0 g, from 7.70 s (the
//! wall dropped onto its springs there, 0.25 s before the loop starts failing) to 8.03 s.
//! Without the floor the loop's refusals ratchet Δt down to 1e-8…1e-5 s (§24: 8,435 steps
//! over 8.00–8.05 s alone); with it, at most `1 / floor` steps a second plus the impact law's
//! located steps. No closed form exists for the collapse: the checks are the step count (the
//! mend), the steps before the first failing loop bit-identical to the default's (the floor
//! touches nothing else), and the penetration (the unconverged iterates taken must not let
//! stones sink into each other).
use ashlar::motion::{self, GroundMotion};
use ashlar::scene::Scene;
use ashlar::simulation::{SimParams, Simulation};
use serde_json::Value;
use std::collections::BTreeMap;

const START: f64 = 7.70;
const END: f64 = 8.03;
/// The floor, as a fraction of Δt = 1 ms: the tight reference's 0.1 ms (§24).
const FLOOR: f64 = 0.1;

fn wall() -> Scene {
    let given: BTreeMap<String, Value> = [("length", "6"), ("height", "3"), ("openings", "0")]
        .into_iter()
        .map(|(k, v)| (k.to_string(), Value::String(v.to_string())))
        .collect();
    ashlar::scene::templates::build("wall", &given)
        .expect("the wall template")
        .1
}

fn record() -> GroundMotion {
    ashlar::presets::record("northridge-1994-mulholland-009.at2")
        .expect("the repository's Northridge record")
        .scaled_to_pga(motion::STANDARD_GRAVITY)
}

/// Steps from `START` until `end`, or until `max_steps`; returns the simulation.
fn run(
    scene: &Scene,
    gm: &GroundMotion,
    params: SimParams,
    end: f64,
    max_steps: u64,
) -> Simulation {
    let mut sim = Simulation::new(scene, gm, params);
    sim.set_time(START);
    while sim.time() < end - 1e-12 && sim.stats().steps < max_steps {
        sim.step(end - sim.time()).expect("step");
    }
    sim
}

fn digest(sim: &Simulation) -> Vec<u64> {
    sim.geoms()
        .iter()
        .flat_map(|g| {
            g.vertices
                .iter()
                .flat_map(|v| [v.x.to_bits(), v.y.to_bits()])
        })
        .collect()
}

#[test]
fn the_floor_keeps_a_collapsing_wall_from_crawling_at_tiny_steps() {
    let scene = wall();
    let gm = record();
    let floored = SimParams {
        unconverged_floor_ratio: Some(FLOOR),
        ..Default::default()
    };
    let sim = run(&scene, &gm, floored, END, u64::MAX);
    let s = sim.stats();
    // The mend. Bound: the floor's own count, (END − START)/(FLOOR × 1 ms) = 3,300 steps.
    // Measured: 719 steps with the floor (29 cuts, 300 unconverged steps taken; 712 steps and
    // 167 cuts without `unconverged_floor_hold`, §24/§26); the default 5,195 steps (363 cuts,
    // Δt down to 7.5e-8 s), so it fails without the floor.
    let bound = ((END - START) / (FLOOR * scene.control.time_step)).round() as u64;
    assert!(
        s.steps <= bound,
        "{} steps over {START}–{END} s with the floor (bound {bound})",
        s.steps
    );
    assert!(s.unconverged_taken > 0, "the floor was never reached");
    // Penetration: the unconverged iterates taken must not let stones sink in. Measured
    // 1.74e-6 m with the floor (1.77e-6 m without the hold), 1.59e-6 m for the default (converged steps) over the same
    // window; bound 5e-6 m, about 3× the default's: deeper would be the taken iterates
    // pushing stones into each other's springs, not the springs' compliance under impact.
    assert!(
        s.max_penetration <= 5e-6,
        "max penetration {:.3e} m",
        s.max_penetration
    );
    // Where the loop's cuts stay above the floor, the floor changes nothing: over the first
    // 150 steps from 7.70 s (the drop onto the springs, cut twice: 1 ms → 0.3 → 0.09 ms) the
    // default and a run with the floor at 0.05 (0.05 ms, below those cuts) are bit-identical.
    let a = run(&scene, &gm, SimParams::default(), END, 150);
    let low = SimParams {
        unconverged_floor_ratio: Some(0.05),
        ..Default::default()
    };
    let b = run(&scene, &gm, low, END, 150);
    assert!(a.stats().min_dt > 0.05 * scene.control.time_step);
    assert_eq!(b.stats().unconverged_taken, 0);
    assert_eq!(digest(&a), digest(&b));
}

/// The scene's `control.unconverged_floor` (what CLI and service users set) is the engine's
/// knob: over the window a scene with the control and default `SimParams` is bit-identical to
/// the caller's `unconverged_floor_ratio` (and takes unconverged steps), and a scene's 0 turns
/// a caller's floor off (bit-identical to the default, no step taken unconverged).
#[test]
fn the_scene_control_sets_the_floor() {
    let gm = record();
    let plain = wall();
    let mut with = wall();
    with.control.unconverged_floor = Some(FLOOR);
    let mut off = wall();
    off.control.unconverged_floor = Some(0.0);
    let floored = SimParams {
        unconverged_floor_ratio: Some(FLOOR),
        ..Default::default()
    };
    let by_params = run(&plain, &gm, floored, END, u64::MAX);
    let by_scene = run(&with, &gm, SimParams::default(), END, u64::MAX);
    assert!(by_params.stats().unconverged_taken > 0, "the floor acts");
    assert_eq!(
        by_scene.stats().unconverged_taken,
        by_params.stats().unconverged_taken
    );
    assert_eq!(digest(&by_scene), digest(&by_params));
    let none = run(&plain, &gm, SimParams::default(), END, u64::MAX);
    let turned_off = run(&off, &gm, floored, END, u64::MAX);
    assert_eq!(turned_off.stats().unconverged_taken, 0);
    assert_eq!(turned_off.stats().steps, none.stats().steps);
    assert_eq!(digest(&turned_off), digest(&none));
}
