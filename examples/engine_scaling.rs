//! Cost per step against the number of blocks, for running-bond walls of 100 … 6400 blocks at
//! rest under gravity (Δt = 1 ms). Prints a Markdown table with the fitted exponent between
//! successive sizes. Run: `cargo run --release --example engine_scaling`.
use ashlar::motion::GroundMotion;
use ashlar::scene::validate;
use ashlar::simulation::{SimParams, Simulation};
use std::time::Instant;

fn main() {
    println!("| blocks | unknowns | contacts | steps | s/step | exponent vs previous |");
    println!("|---|---|---|---|---|---|");
    let mut prev: Option<(f64, f64)> = None;
    for (courses, per) in [(10, 10), (20, 20), (40, 40), (80, 80)] {
        let scene = validate(&ashlar::presets::wall(courses, per)).expect("wall");
        let mut sim = Simulation::new(&scene, &GroundMotion::none(), SimParams::default());
        // Warm up: the first steps settle the wall onto its contact springs (contact detection,
        // the symbolic factorization and a few numeric ones); the table is the steady cost.
        for _ in 0..10 {
            sim.step(1.0).expect("step");
        }
        let n = 100;
        let t = Instant::now();
        for _ in 0..n {
            sim.step(1.0).expect("step");
        }
        let per_step = t.elapsed().as_secs_f64() / n as f64;
        let blocks = scene.blocks.len() as f64 - 1.0;
        let exp = prev
            .map(|(b0, s0)| (per_step / s0).ln() / (blocks / b0).ln())
            .map(|e| format!("{e:.2}"))
            .unwrap_or_default();
        println!(
            "| {} | {} | {} | {} | {:.3e} | {} |",
            blocks,
            sim.dofs().n,
            sim.contacts().contacts.len(),
            n,
            per_step,
            exp
        );
        eprintln!(
            "  profile {:?} iterations/step {:.2} {:?} detections {}",
            sim.profile(),
            sim.stats().open_close_iterations as f64 / sim.stats().steps as f64,
            sim.solver_counts(),
            sim.contacts().detections
        );
        prev = Some((blocks, per_step));
    }
}
