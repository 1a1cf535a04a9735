//! Engine throughput (criterion). Run: `cargo bench --bench engine`.
//! - `rocking_column_1000_steps`: one rigid column rocking on a plinth under a 5 m/s² half-sine
//!   pulse (the target, docs/speed.md: ≥ 200,000 steps/s on one core: 1000 steps in ≤ 5 ms).
//! - `wall_400_blocks_1000_steps`: a 20-course running-bond wall (410 blocks) at Δt = 1 ms
//!   under gravity (the target, docs/speed.md: < 1 s); the same with the engine's shortcuts off (contact
//!   detection skipped while nothing moves, the last factorization reused as a preconditioner).
//!   The shaken wall is measured by `examples/wall_probe.rs` (a criterion run would take minutes).
use ashlar::motion::GroundMotion;
use ashlar::presets::rocking_pulse;
use ashlar::scene::generate::column;
use ashlar::scene::validate;
use ashlar::simulation::{SimParams, Simulation};
use criterion::{criterion_group, criterion_main, Criterion};
use std::hint::black_box;

fn steps(sim: &mut Simulation, n: usize) {
    for _ in 0..n {
        if sim.step(f64::INFINITY).is_err() {
            panic!("benchmark scene failed");
        }
    }
}

fn rocking_column(c: &mut Criterion) {
    let mut spec = column(0.2, 0.6, 40.0);
    spec.control.duration = Some(10.0);
    spec.control.time_step = Some(1e-3);
    let scene = validate(&spec).expect("column scene");
    let pulse = rocking_pulse(5.0);
    c.bench_function("rocking_column_1000_steps", |b| {
        b.iter(|| {
            let mut sim = Simulation::new(&scene, &pulse, SimParams::default());
            steps(&mut sim, 1000);
            black_box(sim.geoms()[1].rotation)
        })
    });
}

fn wall(c: &mut Criterion) {
    let mut spec = ashlar::presets::wall(20, 20);
    spec.control.duration = Some(10.0);
    let scene = validate(&spec).expect("wall scene");
    let mut group = c.benchmark_group("wall");
    group.sample_size(10);
    group.bench_function("wall_400_blocks_1000_steps", |b| {
        b.iter(|| {
            let mut sim = Simulation::new(&scene, &GroundMotion::none(), SimParams::default());
            steps(&mut sim, 1000);
            black_box(sim.time())
        })
    });
    // The same wall with both shortcuts off (detection every step, a factorization every
    // solve): what they save, measured in the same run.
    let mut plain = SimParams::default();
    plain.contact.reuse_ratio = 0.0;
    plain.solver.sparse.max_reuse_iterations = 0;
    group.bench_function("wall_400_blocks_1000_steps_no_shortcuts", |b| {
        b.iter(|| {
            let mut sim = Simulation::new(&scene, &GroundMotion::none(), plain);
            steps(&mut sim, 1000);
            black_box(sim.time())
        })
    });
    group.finish();
}

criterion_group!(benches, rocking_column, wall);
criterion_main!(benches);
