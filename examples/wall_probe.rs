//! Work counters of a 410-block wall over 200 steps at Δt = 1 ms, at rest or shaken (3 m/s²,
//! 2 Hz), with the engine's shortcuts on or off (`plain`: detection every step, a
//! factorization every solve): `cargo run --release --example wall_probe [-- shaken] [plain]`.
use ashlar::motion::{GroundMotion, Signal};
use ashlar::scene::validate;
use ashlar::simulation::{SimParams, Simulation};
use std::time::Instant;
fn main() {
    let shaken = std::env::args().any(|a| a == "shaken");
    let scene = validate(&ashlar::presets::wall(20, 20)).expect("wall");
    let motion = if shaken {
        GroundMotion::horizontal(Signal::Sine {
            amplitude: 3.0,
            frequency: 2.0,
        })
    } else {
        GroundMotion::none()
    };
    let mut params = SimParams::default();
    if std::env::args().any(|a| a == "plain") {
        params.contact.reuse_ratio = 0.0;
        params.solver.sparse.max_reuse_iterations = 0;
    }
    let mut sim = Simulation::new(&scene, &motion, params);
    let t = Instant::now();
    for _ in 0..200 {
        sim.step(1.0).expect("step");
    }
    println!(
        "{:.3} s/200 steps; {:?}; {:?}; detections {}; t {}",
        t.elapsed().as_secs_f64(),
        sim.stats(),
        sim.solver_counts(),
        sim.contacts().detections,
        sim.time()
    );
}
