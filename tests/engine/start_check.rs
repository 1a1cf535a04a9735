//! The cheaper start of a reused-factor solve (`SparseParams::start_check_samples`, default 2,
//! docs/contact-solve.md §19) accepts a start when `start_check_margin`·ρ·max|r₀| meets the
//! tolerance, ρ = max|z₀|/max|r₀| sampled on the same factor: a heuristic, not a bound. Checked
//! against the exact test it replaces (the second method): with `start_check_audit` every
//! accepted start also computes z₀, and none may fail the exact test (tolerance 0 misses: one
//! miss means the accepted solution is one the solver would have iterated on). When there is
//! none, the run is the run without the check to the bit (an exactly accepted start returns
//! the same x), which is checked too.
//!
//! The scene is the 105-stone running-bond wall of `examples/shaken_walls.rs` under the
//! Northridge record (Mulholland 009) scaled to 0.3 g, Δt = 1 ms: 300 steps at rest (where
//! factors live long and the check accepts most starts), 300 from the record's start (quiet
//! shaking) and 200 from 0.2 s before its peak (the strong part, refactored often).
use ashlar::motion::{self, GroundMotion};
use ashlar::scene::{validate, Scene};
use ashlar::simulation::{SimParams, Simulation};

fn run(scene: &Scene, gm: &GroundMotion, start: f64, steps: usize, samples: usize) -> Simulation {
    let mut params = SimParams::default();
    params.solver.sparse.start_check_samples = samples;
    params.solver.sparse.start_check_audit = true;
    let mut sim = Simulation::new(scene, gm, params);
    sim.set_time(start);
    for _ in 0..steps {
        sim.step(f64::INFINITY).expect("step");
    }
    sim
}

#[test]
fn the_start_check_accepts_no_start_the_exact_test_rejects() {
    let scene = validate(&ashlar::presets::wall(10, 10)).expect("wall scene");
    let gm = ashlar::presets::shaken_wall_record().expect("the repository's Northridge record");
    let peak = (motion::peak_time(&gm, 1e-3) - 0.2_f64).max(0.0);
    let rest = GroundMotion::none();
    let mut accepted = 0;
    for (gm, start, steps) in [(&rest, 0.0, 300), (&gm, 0.0, 300), (&gm, peak, 200)] {
        let with = run(&scene, gm, start, steps, 2);
        let c = with.solver_counts();
        println!(
            "start {start:.3} s, {steps} steps: {} factorizations, {} starts accepted by the \
             estimate, {} rejected by the exact test",
            c.numeric, c.start_skips, c.start_check_misses
        );
        assert_eq!(
            c.start_check_misses, 0,
            "accepted starts the exact test rejects"
        );
        accepted += c.start_skips;
        let without = run(&scene, gm, start, steps, 0);
        assert_eq!(without.solver_counts().start_skips, 0);
        for (a, b) in with.geoms().iter().zip(without.geoms()) {
            for (p, q) in a.vertices.iter().zip(&b.vertices) {
                assert!(
                    p.x.to_bits() == q.x.to_bits() && p.y.to_bits() == q.y.to_bits(),
                    "the run with the check differs from the run without"
                );
            }
        }
    }
    // Not vacuous: the check must have accepted starts.
    assert!(accepted > 0, "the check accepted no start");
}
