//! The two work-saving shortcuts of the engine leave the answer unchanged:
//! - the sparse solver reuses the last factorization as a conjugate-gradient preconditioner
//!   and refactors only when that does not converge (`SparseParams::max_reuse_iterations`);
//! - contact detection is skipped while no vertex moved more than a tiny fraction of the
//!   search distance (`ContactParams::reuse_ratio`).
//!
//! Each is checked against the same run with the shortcut switched off (the second method),
//! on a wall large enough for the sparse path (120 unknowns > the dense limit of 96).
use crate::common;

use ashlar::motion::GroundMotion;
use ashlar::scene::generate::{running_bond_wall, WallParams};
use ashlar::scene::{validate, Scene};
use ashlar::simulation::{SimParams, Simulation};
use common::{displacement, sine};

fn wall() -> Scene {
    let mut spec = running_bond_wall(&WallParams {
        courses: 5,
        blocks_per_course: 8,
        ..Default::default()
    });
    spec.control.time_step = Some(1e-3);
    validate(&spec).expect("wall scene")
}

fn run(scene: &Scene, motion: &GroundMotion, params: SimParams, t_end: f64) -> Simulation {
    let mut sim = Simulation::new(scene, motion, params);
    common::run(&mut sim, t_end, |_| {});
    sim
}

/// Largest centroid-position difference between two runs of the same scene, m, and the largest
/// displacement of the first, m.
fn compare(a: &Simulation, b: &Simulation) -> (f64, f64) {
    let (mut diff, mut scale) = (0.0_f64, 0.0_f64);
    for k in 0..a.geoms.len() {
        let (da, db) = (displacement(a, k), displacement(b, k));
        diff = diff.max((da[0] - db[0]).abs()).max((da[1] - db[1]).abs());
        scale = scale.max(da[0].abs()).max(da[1].abs());
    }
    (diff, scale)
}

/// A wall shaken below its sliding threshold (3 m/s² at 2 Hz against tan 35° · g = 6.9 m/s²),
/// 0.5 s: every block moves on its contact springs, contacts stay closed. Reusing the factor changes each solve by at most
/// 1e-12 of the solution (the stopping rule); over 500 smooth steps that stays below 1e-8 of the
/// largest displacement (the allowance: 500 steps × 1e-12 with a margin of 20 for the growth of
/// perturbations through the dynamics).
#[test]
fn reused_factorization_gives_the_refactored_answer() {
    let scene = wall();
    let motion = sine(3.0, 2.0);
    let fresh = SimParams {
        solver: ashlar::solve::SolverParams {
            sparse: ashlar::solve::SparseParams {
                max_reuse_iterations: 0,
                ..Default::default()
            },
            ..Default::default()
        },
        ..Default::default()
    };
    let a = run(&scene, &motion, SimParams::default(), 0.5);
    let b = run(&scene, &motion, fresh, 0.5);
    let (ca, cb) = (a.solver_counts(), b.solver_counts());
    println!("reuse: {ca:?}\nfresh: {cb:?}");
    assert!(a.dofs.n > 96, "the wall must take the sparse path");
    assert!(
        ca.numeric * 5 < cb.numeric,
        "reuse should save most factorizations: {} vs {}",
        ca.numeric,
        cb.numeric
    );
    let (diff, scale) = compare(&a, &b);
    println!("largest difference {diff:.3e} m of {scale:.3e} m");
    assert!(scale > 1e-7, "the wall should deflect: {scale}");
    assert!(
        diff <= 1e-8 * scale,
        "difference {diff} m vs displacement {scale} m"
    );
}

/// A wall at rest for 1 s: with detection skipped while nothing moves, the run detects a
/// handful of times instead of 1000 and ends where the run that detects every step ends
/// (1e-12 m: both see the same contact list, so only round-off may differ).
#[test]
fn skipped_detection_gives_the_detected_answer() {
    let scene = wall();
    let still = GroundMotion::none();
    let mut every_step = SimParams::default();
    every_step.contact.reuse_ratio = 0.0;
    let a = run(&scene, &still, SimParams::default(), 1.0);
    let b = run(&scene, &still, every_step, 1.0);
    println!(
        "detections: {} with reuse, {} without",
        a.contacts.detections, b.contacts.detections
    );
    assert_eq!(b.contacts.detections, b.stats.steps);
    assert!(
        a.contacts.detections * 10 < a.stats.steps,
        "a wall at rest should rarely need detection: {} of {} steps",
        a.contacts.detections,
        a.stats.steps
    );
    let (diff, _) = compare(&a, &b);
    assert!(diff <= 1e-12, "difference {diff} m");
}

/// A block sliding down a 28° incline with φ = 10° for 0.5 s moves every step, so
/// detection runs every step and the shortcut is inert: the runs agree to round-off (1e-12 m).
#[test]
fn moving_blocks_are_detected_every_step() {
    let (spec, _) = common::incline(28.0, 10.0, serde_json::json!({ "time_step": 1e-3 }));
    let scene = common::parse(&spec);
    let still = GroundMotion::none();
    let mut every_step = SimParams::default();
    every_step.contact.reuse_ratio = 0.0;
    let a = run(&scene, &still, SimParams::default(), 0.5);
    let b = run(&scene, &still, every_step, 0.5);
    println!(
        "detections: {} of {} steps",
        a.contacts.detections, a.stats.steps
    );
    assert!(
        a.contacts.detections * 10 > a.stats.steps * 9,
        "a sliding block skipped detection: {} of {} steps",
        a.contacts.detections,
        a.stats.steps
    );
    let (diff, scale) = compare(&a, &b);
    println!("largest difference {diff:.3e} m of {scale:.3e} m");
    assert!(scale > 0.1, "the block should slide: {scale}");
    assert!(diff <= 1e-12, "difference {diff} m");
}

/// The shortcut on a shaken wall (README: "identical to round-off on a shaken wall"): the wall
/// of the factor-reuse test under a 2 Hz sine of 6 m/s², just below its sliding threshold
/// (tan 35° · g = 6.9 m/s²), 0.5 s. At 3 m/s² no vertex ever moves past the shortcut's
/// threshold (1e-3 of min(search distance, angle tolerance × shortest edge), ~3e-7 m here), so
/// detection would run once and the comparison would test nothing; at 6 m/s² the blocks rock
/// on their springs and the run re-detects about one step in ten (measured: 204 detections in
/// 2111 steps). Asserted: some steps detect and some skip. Bound: a skipped detection keeps the
/// list a detection would have found (same contacts, states and reference points; only the
/// thresholds differ, by 0.2 % of themselves), so the runs may differ only by round-off
/// carried through the steps: 1e-8 of the largest displacement, the allowance of the
/// factor-reuse test above. Measured: 0 (bit-identical).
///
/// Not asserted, measured (this test at 8 m/s², above the sliding threshold; 57 000 steps with
/// Δt cuts): the runs differ by 9.0 mm of 19.4 mm, and so do two runs that both detect every
/// step but differ only in the factor reuse (a change of ≤ 1e-12 of each solve): 7.1 mm. A
/// sliding wall's response is sensitive to round-off; there the shortcut changes the answer by
/// as much as round-off does, not "identically".
#[test]
fn skipped_detection_on_a_shaken_wall_gives_the_detected_answer() {
    let scene = wall();
    let motion = sine(6.0, 2.0);
    let mut every_step = SimParams::default();
    every_step.contact.reuse_ratio = 0.0;
    let a = run(&scene, &motion, SimParams::default(), 0.5);
    let b = run(&scene, &motion, every_step, 0.5);
    println!(
        "shaken wall: detections {} of {} steps with the shortcut, {} of {} without; contacts at the end {} and {}",
        a.contacts.detections,
        a.stats.steps,
        b.contacts.detections,
        b.stats.steps,
        a.contacts.contacts.len(),
        b.contacts.contacts.len()
    );
    assert_eq!(b.contacts.detections, b.stats.steps);
    assert!(
        a.contacts.detections > 10 && a.contacts.detections < a.stats.steps,
        "{} detections in {} steps: the shortcut must both skip and re-detect, else the comparison tests nothing",
        a.contacts.detections,
        a.stats.steps
    );
    let (diff, scale) = compare(&a, &b);
    println!(
        "largest difference {diff:.3e} m of {scale:.3e} m ({:.2e} of it; bound 1e-8)",
        diff / scale
    );
    assert!(scale > 1e-7, "the wall should deflect: {scale}");
    assert!(
        diff <= 1e-8 * scale,
        "difference {diff} m vs displacement {scale} m"
    );
}
