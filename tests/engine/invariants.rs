//! Invariants of the engine (docs/verification.md), each against a law rather than a
//! reference run:
//! - a dry-stone running-bond wall at rest under gravity stays at rest (≤ 0.1 mm in 10 s, the
//!   docs/verification.md's bound, and a regression bound at ~7× today's measured motion);
//! - a block bouncing under the trapezoidal rule keeps its energy: ≤ 1 % loss in 10 impacts,
//!   and never a gain beyond round-off between flights (frictionless and φ = 10°; all run, none
//!   ignored: the gain was fixed by the release correction, see
//!   `bounce_never_gains_energy_under_the_trapezoidal_rule`);
//! - the system matrix that `Simulation::step` solved (`Simulation::solved_system`) is
//!   symmetric and the step's increments solve it;
//! - penetration, measured geometrically here (vertices inside other blocks,
//!   `common::geometric_penetration`, not the engine's own statistic), stays below the engine's
//!   stated tolerance;
//! - random small stacks at rest never gain energy under the (dissipative) DDA integrator.
use crate::common;
use ashlar::assembly::BlockSystem;
use ashlar::motion::GroundMotion;
use ashlar::scene::Scene;
use ashlar::simulation::{SimParams, Simulation};
use ashlar::solve::{LinearSolver, SolverParams};
use common::*;
use proptest::prelude::*;
use proptest::test_runner::RngSeed;
use serde_json::{json, Value};

// ---------------------------------------------------------------------------------------------
// Scenes

/// Running-bond wall: `courses` courses of `per_course` blocks (bw × bh, m), half blocks at both
/// ends of every odd course, on a fixed foundation. Returns the block list (foundation first).
/// Not `presets::wall`: the same bond, but this foundation is 0.3 m deep (the template's 0.5 m),
/// the stones take the scene's block model and the edges are computed, not summed, so the
/// coordinates differ in the last bits; the bounds below were measured on this wall.
fn wall_blocks(courses: usize, per_course: usize, bw: f64, bh: f64) -> Value {
    let length = per_course as f64 * bw;
    let rect = |x0: f64, y0: f64, x1: f64, y1: f64| json!([[x0, y0], [x1, y0], [x1, y1], [x0, y1]]);
    let mut blocks = vec![
        json!({ "id": "foundation", "material": "stone", "fixed": true,
        "vertices": rect(-0.5, -0.3, length + 0.5, 0.0) }),
    ];
    for c in 0..courses {
        let (y0, y1) = (c as f64 * bh, (c + 1) as f64 * bh);
        let mut edges = vec![0.0];
        if c % 2 == 1 {
            edges.push(0.5 * bw);
            for k in 1..per_course {
                edges.push((k as f64 + 0.5) * bw);
            }
        } else {
            for k in 1..per_course {
                edges.push(k as f64 * bw);
            }
        }
        edges.push(length);
        for (k, x) in edges.windows(2).enumerate() {
            blocks.push(json!({ "id": format!("c{c}b{k}"), "material": "stone", "vertices": rect(x[0], y0, x[1], y1) }));
        }
    }
    Value::Array(blocks)
}

fn max_vertex_motion(s: &Simulation, start: &[Vec<nalgebra::Vector2<f64>>]) -> f64 {
    let mut m: f64 = 0.0;
    for (g, v0) in s.geoms().iter().zip(start) {
        for (p, q) in g.vertices.iter().zip(v0) {
            m = m.max((p - q).norm());
        }
    }
    m
}

fn penetration_tolerance(s: &Simulation) -> f64 {
    s.params().penetration_ratio * s.max_step_displacement()
}

// ---------------------------------------------------------------------------------------------
// Wall at rest

/// 5 courses × 6 blocks (0.4 × 0.2 m, deformable, φ = 30°) on a fixed foundation, gravity only,
/// 10 s at Δt = 1 ms. Law: a wall in static equilibrium stays put. Tolerance 0.1 mm (the
/// docs/verification.md): the elastic settlement under self-weight is ~1e-6 m (σ ≈ ρgH = 25 kPa over
/// E = 20 GPa in 1 m) and penalty-spring compression ~1e-7 m, so 0.1 mm can only be exceeded by
/// creep, drift or a spurious mechanism. Penetration must stay below the engine's tolerance
/// (penetration_ratio × the largest step displacement).
#[test]
fn running_bond_wall_stays_at_rest_for_10_s() {
    let scene = parse(&scene_json(
        wall_blocks(5, 6, 0.4, 0.2),
        30.0,
        // Deformable by name: the claim is about deformable blocks (the default is "auto").
        json!({ "time_step": 1e-3, "duration": 10.0, "block_model": "deformable" }),
    ));
    let mut s = sim(&scene, &GroundMotion::none());
    let start: Vec<_> = s.geoms().iter().map(|g| g.vertices.clone()).collect();
    let mut worst: f64 = 0.0;
    let mut penetration: f64 = 0.0;
    run(&mut s, 10.0, |s| {
        worst = worst.max(max_vertex_motion(s, &start));
        penetration = penetration.max(geometric_penetration(s));
    });
    let tol = penetration_tolerance(&s);
    eprintln!(
        "wall: {} blocks, {} steps ({} cuts), largest vertex motion {worst:.3e} m (docs/verification.md's bound 1e-4 m, regression bound {WALL_REST_REGRESSION:e} m), geometric penetration {penetration:.3e} m (engine's statistic {:.3e} m; tolerance {tol:.3e} m)",
        scene.blocks.len(),
        s.stats().steps,
        s.stats().time_step_cuts,
        s.stats().max_penetration
    );
    assert!(
        worst <= 1e-4,
        "a block moved {worst} m (docs/verification.md's bound 1e-4 m)"
    );
    assert!(
        worst <= WALL_REST_REGRESSION,
        "a block moved {worst} m: within docs/verification.md's 1e-4 m but above the regression bound {WALL_REST_REGRESSION} m (~7× the measured motion): find what changed"
    );
    assert!(
        penetration <= tol,
        "geometric penetration {penetration} m above tolerance {tol} m"
    );
    // Regression bound 3e-7 m: ~10× the 3.0e-8 m measured with the penalty solver (the
    // springs' compression under the wall's weight; 2.8e-10 m with dual); the engine's
    // tolerance above is 5.5e-4 m.
    assert!(
        penetration <= 3e-7,
        "geometric penetration {penetration} m within the tolerance but above the regression bound 3e-7 m"
    );
}

/// Regression bound on the wall at rest's largest vertex motion, m: ~7× the 7.6e-7 m measured
/// (penalty solver, `cargo test --test engine invariants:: running_bond -- --nocapture`): the elastic
/// settlement under self-weight plus the springs' compression. docs/verification.md's bound, 1e-4 m, is
/// 130× the measurement; this one catches a drift long before it.
const WALL_REST_REGRESSION: f64 = 5e-6;

// ---------------------------------------------------------------------------------------------
// Bouncing block

const DROP: f64 = 2.0e-3;

/// A rigid 0.2 × 0.2 m block (100 kg) held `DROP` above a fixed slab, frictionless.
fn bouncing_scene(integrator: &str, dt: f64, friction_deg: f64) -> Scene {
    let blocks = json!([
        { "id": "slab", "material": "stone", "fixed": true, "vertices": [[-0.5, -0.3], [0.5, -0.3], [0.5, 0.0], [-0.5, 0.0]] },
        { "id": "block", "material": "stone", "block_model": "rigid",
          "vertices": [[-0.1, DROP], [0.1, DROP], [0.1, DROP + 0.2], [-0.1, DROP + 0.2]] },
    ]);
    // Penalty 1e8 N/m per contact: the flat impact on two springs lasts π√(m/2k) ≈ 2.2 ms, i.e.
    // ~110 steps of 2e-5 s ("small against the contact duration"); the peak penetration
    // v/ω ≈ 0.2/1414 ≈ 1.4e-4 m sits well inside the tolerance 0.3 × 0.005 × 0.56 m ≈ 8e-4 m.
    parse(&scene_json(
        blocks,
        friction_deg,
        // Penalty by name: these checks are about the springs' energy (the dual solver's rigid
        // contact is refused with the trapezoidal rule, and its impacts are checked in
        // dual_seed.rs), so the suite's dual rerun keeps them on the penalty solver.
        // "contact": these invariants are about the penalty spring's own bounce (energy kept
        // through elastic impacts), which the default impact law (e = 0) would absorb.
        json!({ "time_step": dt, "adaptive_time_step": false, "penalty_stiffness": 1.0e8, "restitution": "contact",
                "contact_solver": "penalty",
                "max_displacement_ratio": 0.005, "integrator": integrator, "duration": 1.0 }),
    ))
}

/// Energy of the flight phases between impacts (J, datum: the block touching the slab), up to
/// `impacts` impacts; also returns the simulation and the deepest geometric penetration over
/// the steps (m, `common::geometric_penetration`).
fn bounce(
    integrator: &str,
    dt: f64,
    friction_deg: f64,
    impacts: usize,
) -> (f64, Vec<f64>, Simulation, f64) {
    let scene = bouncing_scene(integrator, dt, friction_deg);
    let mut s = sim(&scene, &GroundMotion::none());
    let m = 2500.0 * 0.04;
    let touch_y = s.geoms()[1].centroid.y - DROP;
    let rel = |s: &Simulation| s.energy().total() - m * G * touch_y;
    let e0 = rel(&s);
    let mut flights = Vec::new();
    let mut in_contact = false;
    let mut flight_steps = 0;
    let mut penetration: f64 = 0.0;
    while flights.len() < impacts {
        assert!(s.time() < 2.0, "only {} impacts in 2 s", flights.len());
        // 10 impacts take ~0.45 s, i.e. ~23 000 steps of 2e-5 s: a step count far beyond that
        // means the time step collapsed (see tests/regression/regression_contact_chatter.rs).
        assert!(
            s.stats().steps < 200_000,
            "time step collapsed: t = {} s after {} steps, Δt = {:.2e} s",
            s.time(),
            s.stats().steps,
            s.dt()
        );
        if let Err(e) = s.step(dt) {
            panic!("simulation failed: {e}");
        }
        penetration = penetration.max(geometric_penetration(&s));
        let closed = s.contacts().contacts.iter().any(|c| c.state.is_closed());
        if closed {
            in_contact = true;
            flight_steps = 0;
        } else if in_contact {
            flight_steps += 1;
            // The first free step still carries the contact acceleration of the previous step
            // (trapezoidal a₀); from the second one on the flight energy is exactly constant.
            if flight_steps == 2 {
                flights.push(rel(&s));
                in_contact = false;
            }
        }
    }
    (e0, flights, s, penetration)
}

/// Law: without friction or damping, the trapezoidal rule (β = 1/4, γ = 1/2) conserves the
/// energy of a linear spring–mass system exactly; what remains is the error of switching the
/// penalty springs on and off inside a step. Tolerances: ≤ 1 % loss over 10 impacts (the
/// docs/verification.md); with `strict`, never a gain above 1e-6 of the drop energy between successive
/// flights (flight energy is exactly constant under gravity alone; 1e-6 leaves room for
/// round-off of m·g·y, ~1e-13 relative, and nothing else). Penetration below the engine's
/// tolerance.
fn check_bounce(friction_deg: f64, strict: bool) {
    let (e0, flights, s, penetration) = bounce("trapezoidal", 2e-5, friction_deg, 10);
    eprintln!("φ = {friction_deg}°: drop energy {e0:.6} J; flight energy after each impact, relative change:");
    for (k, e) in flights.iter().enumerate() {
        eprintln!("  impact {:2}: {:+.3e}", k + 1, e / e0 - 1.0);
    }
    let tol_pen = penetration_tolerance(&s);
    eprintln!(
        "geometric penetration {penetration:.3e} m (engine's statistic {:.3e} m; tolerance {tol_pen:.3e} m), {} steps, {} cuts",
        s.stats().max_penetration, s.stats().steps, s.stats().time_step_cuts
    );
    let mut previous = e0;
    for (k, &e) in flights.iter().enumerate() {
        assert!(
            e >= 0.99 * e0,
            "impact {}: lost {:.3} % of the energy",
            k + 1,
            100.0 * (1.0 - e / e0)
        );
        if strict {
            assert!(
                e <= previous + 1e-6 * e0,
                "impact {}: energy rose from {previous} J to {e} J",
                k + 1
            );
        }
        previous = e;
    }
    assert!(
        penetration <= tol_pen,
        "geometric penetration {penetration} m above tolerance {tol_pen} m"
    );
}

/// docs/verification.md's case: friction angle exactly 0, loss ≤ 1 % over 10 impacts.
#[test]
fn frictionless_bounce_keeps_energy_under_the_trapezoidal_rule() {
    check_bounce(0.0, false);
}

/// Friction angle exactly 0, never a gain beyond round-off: see the φ = 10° case below.
#[test]
fn frictionless_bounce_never_gains_energy_under_the_trapezoidal_rule() {
    check_bounce(0.0, true);
}

/// Loss ≤ 1 % over 10 impacts with φ = 10° (the impact is normal, so friction can only take
/// energy away): guards the 1 % bound and the penetration tolerance.
#[test]
fn bounce_loses_at_most_one_percent_in_10_impacts() {
    check_bounce(10.0, false);
}

/// "Never gains" at 1e-6 with φ = 10°. This failed before the release correction: the
/// trapezoidal step carried a₀ across contact switches, so in the step where a spring opens the
/// work ½(F₀ + F₁)·D still included the spring force F₀ = −k·g₀ that no longer acts, adding
/// ½k|g₀|g₁ (+7.5e-5 of the drop energy after the first impact, +3.3e-4 after ten). The engine
/// now keeps only the discrete-gradient share λ = |g₀|/(|g₀| + g₁) of F₀ in a releasing step
/// (`contact_springs::release_load`); what remains is the closing step's small loss.
#[test]
fn bounce_never_gains_energy_under_the_trapezoidal_rule() {
    check_bounce(10.0, true);
}

// ---------------------------------------------------------------------------------------------
// Symmetry of the system matrix

/// The system matrix the last step solved (`Simulation::solved_system`), as a dense matrix.
/// The engine stores one off-diagonal block per coupled pair (`off[p]` = K_ab, a < b) and its
/// solvers read K_ba as K_abᵀ: that is the matrix they solve, so it is the one built here. Its
/// off-diagonal symmetry is therefore structural; what can break is a diagonal block (mass,
/// elasticity, contact springs) and whether the step's increments solve this matrix, both
/// checked below.
fn solved_matrix(s: &Simulation) -> Vec<Vec<f64>> {
    let sys = s.solved_system();
    let n = s.dofs().n;
    let mut k = vec![vec![0.0; n]; n];
    for f in 0..s.dofs().block_of.len() {
        let o = s.dofs().offset[f];
        for r in 0..s.dofs().ndof[f] {
            for c in 0..s.dofs().ndof[f] {
                k[o + r][o + c] = sys.diag[f][(r, c)];
            }
        }
    }
    for (p, &(a, b)) in sys.pairs.iter().enumerate() {
        let (oa, ob) = (s.dofs().offset[a], s.dofs().offset[b]);
        for r in 0..s.dofs().ndof[a] {
            for c in 0..s.dofs().ndof[b] {
                k[oa + r][ob + c] = sys.off[p][(r, c)];
                k[ob + c][oa + r] = sys.off[p][(r, c)];
            }
        }
    }
    k
}

/// Two states with closed contacts and deformable blocks (6 unknowns each): the running-bond
/// wall settled for 0.05 s (33 blocks, 192 unknowns: the sparse path by default) and a block
/// sliding down a 45° incline with φ = 20° for 0.2 s (sliding contacts).
fn mixed_states() -> Vec<Simulation> {
    let wall = parse(&scene_json(
        wall_blocks(5, 6, 0.4, 0.2),
        30.0,
        // Penalty by name (also in the suite's dual rerun): the springs are what this checks.
        // Deformable by name: the states carry 6 unknowns a block (the default is "auto").
        json!({ "time_step": 1e-3, "duration": 1.0, "contact_solver": "penalty", "block_model": "deformable" }),
    ));
    let mut w = Simulation::new(&wall, &GroundMotion::none(), SimParams::default());
    run(&mut w, 0.05, |_| {});
    let (v, _) = incline(
        45.0,
        20.0,
        // Deformable by name: the states carry 6 unknowns a block (the default is "auto").
        json!({ "time_step": 1e-3, "duration": 1.0, "contact_solver": "penalty", "block_model": "deformable" }),
    );
    let mut i = Simulation::new(&parse(&v), &GroundMotion::none(), SimParams::default());
    run(&mut i, 0.2, |_| {});
    vec![w, i]
}

/// Law: DDA's system comes from minimising a quadratic potential (inertia, elasticity,
/// springs), so its matrix is symmetric. Checked on the matrix `Simulation::step` itself solved
/// (read through `Simulation::solved_system` after one more step of each state; penalty solver,
/// the one that assembles springs into the system), not on one rebuilt here: (1) every
/// diagonal block (mass, elastic, contact springs) is symmetric to 1e-12 of the largest entry
/// (round-off); (2) the step's own increments solve it: ‖K·x − f‖ ≤ 1e-8 ‖K‖‖x‖ + 1e-8 ‖f‖
/// (the sparse path may reuse a factor and refine, hence not round-off); (3) the solver, dense
/// and sparse, solves exactly this matrix for unit loads: residual ≤ 1e-8 ‖K‖‖x‖ (a
/// factorization reading the wrong triangle or a misplaced transpose would leave O(1)
/// residuals); (4) reciprocity (Maxwell–Betti) of the solution operator: x_i(e_j) = x_j(e_i)
/// to 1e-8 relative.
#[test]
fn system_matrix_is_symmetric_and_is_what_the_solver_solves() {
    for mut s in mixed_states() {
        check_symmetry(&mut s);
    }
}

fn check_symmetry(s: &mut Simulation) {
    assert_eq!(
        s.scene().control.contact_solver,
        ashlar::scene::ContactSolver::Penalty,
        "this check reads the penalty solver's system (the dual solver assembles no springs)"
    );
    let states: Vec<_> = s.contacts().contacts.iter().map(|c| c.state).collect();
    let sliding = states
        .iter()
        .filter(|st| matches!(st, ashlar::contact::ContactState::Sliding { .. }))
        .count();
    let locked = states
        .iter()
        .filter(|st| matches!(st, ashlar::contact::ContactState::Locked))
        .count();
    eprintln!(
        "{} contacts: {locked} locked, {sliding} sliding",
        states.len()
    );
    assert!(locked + sliding > 0, "the check needs closed contacts");
    if let Err(e) = s.step(1e-3) {
        panic!("step failed: {e}");
    }
    let sys = s.solved_system();
    let k = solved_matrix(s);
    let n = k.len();
    let kmax = k.iter().flatten().fold(0.0f64, |m, v| m.max(v.abs()));
    for f in 0..s.dofs().block_of.len() {
        for r in 0..6 {
            for c in 0..6 {
                let (a, b) = (sys.diag[f][(r, c)], sys.diag[f][(c, r)]);
                assert!(
                    (a - b).abs() <= 1e-12 * kmax,
                    "block {f}: K[{r},{c}] = {a} but K[{c},{r}] = {b}"
                );
            }
        }
    }
    // (2) The step's increments solve the step's matrix.
    let x = s.solved_increments();
    assert_eq!(x.len(), n);
    let xnorm = x.iter().map(|v| v * v).sum::<f64>().sqrt();
    let mut fnorm = 0.0f64;
    let mut worst = 0.0f64;
    for (f, _) in s.dofs().block_of.iter().enumerate() {
        let o = s.dofs().offset[f];
        for r in 0..s.dofs().ndof[f] {
            let kx: f64 = k[o + r].iter().zip(x).map(|(a, b)| a * b).sum();
            let rhs = sys.rhs[f][r];
            fnorm += rhs * rhs;
            worst = worst.max((kx - rhs).abs());
        }
    }
    let bound = 1e-8 * (kmax * xnorm + fnorm.sqrt());
    eprintln!("step's own solve: largest residual {worst:.2e} (bound {bound:.2e})");
    assert!(
        worst <= bound,
        "the step's increments do not solve the step's matrix: residual {worst} > {bound}"
    );
    for dense_limit in [usize::MAX, 0] {
        let mut solver = LinearSolver::new(SolverParams {
            dense_limit,
            ..Default::default()
        });
        let mut unit = copy_system(sys);
        let probes: Vec<usize> = (0..n).step_by((n / 12).max(1)).collect();
        let mut cols = Vec::new();
        for &j in &probes {
            set_unit_rhs(&mut unit, s, j);
            let mut x = Vec::new();
            if let Err(e) = solver.solve(&unit, s.dofs(), &mut x) {
                panic!("solve failed: {e}");
            }
            let xnorm = x.iter().map(|v| v * v).sum::<f64>().sqrt();
            for (r, row) in k.iter().enumerate() {
                let kx: f64 = row.iter().zip(&x).map(|(a, b)| a * b).sum();
                let res = kx - if r == j { 1.0 } else { 0.0 };
                assert!(
                    res.abs() <= 1e-8 * kmax * xnorm,
                    "dense_limit {dense_limit}: residual {res} in row {r} for load {j}"
                );
            }
            cols.push(x);
        }
        for (a, &i) in probes.iter().enumerate() {
            for (b, &j) in probes.iter().enumerate() {
                let (xij, xji) = (cols[b][i], cols[a][j]);
                let scale = cols[a][i].abs().max(cols[b][j].abs());
                assert!(
                    (xij - xji).abs() <= 1e-8 * scale,
                    "reciprocity: x_{i}(e_{j}) = {xij}, x_{j}(e_{i}) = {xji}"
                );
            }
        }
    }
}

/// A copy of the assembled matrix whose right-hand side the probes overwrite.
fn copy_system(sys: &BlockSystem) -> BlockSystem {
    let mut out = BlockSystem::default();
    out.set_pattern(sys.pairs.clone());
    out.diag.clone_from(&sys.diag);
    out.off.clone_from(&sys.off);
    out.rhs.clone_from(&sys.rhs);
    out
}

/// Right-hand side e_j (unit load on global unknown j).
fn set_unit_rhs(sys: &mut BlockSystem, s: &Simulation, j: usize) {
    for r in &mut sys.rhs {
        *r = ashlar::geometry::Vec6::zeros();
    }
    for f in 0..s.dofs().block_of.len() {
        let o = s.dofs().offset[f];
        if j >= o && j < o + s.dofs().ndof[f] {
            sys.rhs[f][j - o] = 1.0;
        }
    }
}

// ---------------------------------------------------------------------------------------------
// Stacks at rest (property test)

/// Blocks stacked on a fixed base: widths 0.3–1.0 m, heights 0.2–0.6 m, each centred within
/// ±5 % of the narrowest width of the one below's centre line, so the resultant of everything
/// above any joint stays at least 35 % of the narrowest width inside it: statically stable.
fn stack_scene(dims: &[(f64, f64, f64)]) -> Scene {
    let wmin = dims.iter().fold(f64::INFINITY, |m, d| m.min(d.0));
    let mut blocks = vec![json!({ "id": "base", "material": "stone", "fixed": true,
        "vertices": [[-1.0, -0.3], [1.0, -0.3], [1.0, 0.0], [-1.0, 0.0]] })];
    let (mut y, mut cx) = (0.0, 0.0);
    for (k, &(w, h, off)) in dims.iter().enumerate() {
        cx += off * wmin;
        blocks.push(json!({ "id": format!("b{k}"), "material": "stone",
            "vertices": [[cx - w / 2.0, y], [cx + w / 2.0, y], [cx + w / 2.0, y + h], [cx - w / 2.0, y + h]] }));
        y += h;
    }
    parse(&scene_json(
        Value::Array(blocks),
        30.0,
        json!({ "time_step": 1e-3, "duration": 0.5, "integrator": "dda" }),
    ))
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 6, rng_seed: RngSeed::Fixed(20_261_122), failure_persistence: None, ..ProptestConfig::default() })]
    /// Law: with the DDA integrator (β = 1/2, γ = 1) a step with fixed contact linearization
    /// dissipates (the work of the end-of-step forces is at most the drop of a convex
    /// potential), so total energy (kinetic + gravity + strain + springs) never rises above its
    /// start. Asserted: max over the run of E(t) ≤ E(0) + 1e-9·W·H (W the stack's weight, H its
    /// height: the energy of lifting it by a nanometre, far above round-off). Single steps do
    /// rise a little (up to ~3e-3 J, from re-linearizing the contacts each step; printed), but
    /// the net change over 0.5 s is a loss of 3e-3…3e-2 J in the seeded cases.
    #[test]
    fn stacks_at_rest_never_gain_energy(dims in prop::collection::vec((0.3f64..1.0, 0.2f64..0.6, -0.05f64..0.05), 2..=4)) {
        let scene = stack_scene(&dims);
        let mut s = sim(&scene, &GroundMotion::none());
        let weight: f64 = dims.iter().map(|d| 2500.0 * d.0 * d.1 * G).sum();
        let height: f64 = dims.iter().map(|d| d.1).sum();
        let tol = 1e-9 * weight * height;
        let mut previous = s.energy().total();
        let e0 = previous;
        let mut worst_rise: f64 = f64::NEG_INFINITY;
        let mut highest = e0;
        run(&mut s, 0.5, |s| {
            let e = s.energy().total();
            highest = highest.max(e);
            worst_rise = worst_rise.max(e - previous);
            previous = e;
        });
        eprintln!("stack of {}: largest one-step rise {worst_rise:.2e} J, net change {:.2e} J (tolerance {tol:.2e} J)", dims.len(), previous - e0);
        prop_assert!(highest <= e0 + tol, "energy rose from {e0} J to {highest} J");
    }
}
