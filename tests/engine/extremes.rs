//! Numerical stability at the extremes (docs/stability.md). Every knob is swept one at a time, then in hard
//! combinations, and every case must end in one of two asserted ways:
//!
//! - **completed**: the run reached its end time (or its step budget) with
//!   - a finite state after every step;
//!   - bounded energy: E(t) − E(0) − W_ground(t) ≤ `ENERGY_TOL` × (energy scale), where
//!     W_ground = Σ_steps Σ_blocks −m·a_g(t_end)·Δx_c is the work of the inertial load of the base
//!     acceleration (the engine applies a_g at the step end, so this is the work it puts in);
//!   - penetration (measured here, independently of the engine, as the depth of every vertex
//!     inside any other block) below `penetration_tol()` (5 %) of the thinner block;
//! - **diagnostic**: the engine stopped with a typed [`SimError`] whose message says when (t = …),
//!   where (names a block) and what to change (a remedy verb).
//!
//! Never a NaN, never a panic, never a hang: every run has a step budget. The table in
//! docs/stability.md is printed by `cargo test --test engine extremes:: -- --nocapture
//! --test-threads 1` (rows start with `|`).
use ashlar::motion::{GroundMotion, Signal};
use ashlar::scene::{parse_scene, Scene};
use ashlar::simulation::{SimParams, Simulation};
use nalgebra::Vector2;
use serde_json::{json, Value};
use std::time::Instant;

const G: f64 = 9.81;

/// Allowed energy gain beyond the ground work, as a fraction of the energy scale (m·g·h of every
/// free block + |ground work| + initial kinetic energy). The DDA integrator (Newmark β = ½,
/// γ = 1) only dissipates; the only sources of spurious gain are the penalty springs switching on
/// and off within a step (bounded by ½·k·(step penetration)², i.e. by the penetration tolerance)
/// and round-off. 1 % of the scale is far above both in a healthy run and far below what a
/// blow-up produces (which multiplies the energy, not adds a percent).
const ENERGY_TOL: f64 = 1e-2;

/// Allowed penetration as a fraction of the thinner block of the pair, thickness measured as
/// 4·area/perimeter (the side of a square, twice a slab's thickness). This is the engine's own
/// promise (`SimParams::max_penetration_ratio`, 5 %: beyond it the run must stop with
/// `PenaltyTooSoft`); the test checks it with a geometric measure (depth of every vertex inside
/// every other polygon) that does not use the engine's contact list, so a vertex that tunnels
/// through an edge unseen by contact detection is caught too.
fn penetration_tol() -> f64 {
    SimParams::default().max_penetration_ratio
}

// ---------------------------------------------------------------------------------------------
// Scenes

/// Knobs of the standard case: a stack of two blocks (width × height) on a fixed base, shaken
/// horizontally by a sine of `pga_g` g at 2 Hz.
#[derive(Clone)]
struct Knobs {
    /// N/m; `None` is "auto".
    penalty: Option<f64>,
    dt: f64,
    adaptive: bool,
    friction_deg: f64,
    cohesion: f64,
    tensile: f64,
    width: f64,
    height: f64,
    density: f64,
    young: f64,
    pga_g: f64,
    frequency: f64,
    duration: f64,
    budget: u64,
    model: &'static str,
    integrator: &'static str,
    /// `control.restitution`; `None`: the default.
    restitution: Option<&'static str>,
}

impl Default for Knobs {
    fn default() -> Self {
        Self {
            penalty: None,
            dt: 1e-3,
            adaptive: true,
            friction_deg: 35.0,
            cohesion: 0.0,
            tensile: 0.0,
            width: 0.5,
            height: 0.5,
            density: 2500.0,
            young: 2e10,
            pga_g: 0.3,
            frequency: 2.0,
            duration: 0.2,
            budget: 4000,
            model: "rigid",
            integrator: "dda",
            restitution: None,
        }
    }
}

fn rect(x0: f64, y0: f64, w: f64, h: f64) -> Value {
    json!([[x0, y0], [x0 + w, y0], [x0 + w, y0 + h], [x0, y0 + h]])
}

fn scene_with(k: &Knobs, blocks: Value) -> Value {
    let mut control = json!({
        "time_step": k.dt,
        "adaptive_time_step": k.adaptive,
        "duration": k.duration,
        "max_steps": k.budget,
        "integrator": k.integrator,
    });
    if let Some(p) = k.penalty {
        control["penalty_stiffness"] = json!(p);
    }
    if let Some(r) = k.restitution {
        control["restitution"] = json!(r);
    }
    json!({
        "format": "ashlar.scene/1",
        "gravity": G,
        "materials": { "m": { "density": k.density, "young_modulus": k.young, "poisson_ratio": 0.2 } },
        "joints": { "j": { "friction_angle": k.friction_deg, "cohesion": k.cohesion, "tensile_strength": k.tensile } },
        "blocks": blocks,
        "control": control,
    })
}

/// Two blocks stacked on a fixed base three times as wide as a block.
fn stack(k: &Knobs) -> Value {
    let (w, h) = (k.width, k.height);
    let base_h = 0.5 * w.min(h).max(0.1 * w.max(h));
    scene_with(
        k,
        json!([
            { "id": "base", "material": "m", "fixed": true, "vertices": rect(-1.5 * w, -base_h, 3.0 * w, base_h) },
            { "id": "lower", "material": "m", "block_model": k.model, "vertices": rect(-0.5 * w, 0.0, w, h) },
            { "id": "upper", "material": "m", "block_model": k.model, "vertices": rect(-0.5 * w, h, w, h) },
        ]),
    )
}

fn motion(k: &Knobs) -> GroundMotion {
    if k.pga_g == 0.0 {
        GroundMotion::none()
    } else {
        GroundMotion::horizontal(Signal::Sine {
            amplitude: k.pga_g * G,
            frequency: k.frequency,
        })
    }
}

fn parse(v: &Value) -> Scene {
    parse_scene(&v.to_string()).unwrap_or_else(|e| panic!("case scene invalid: {e}"))
}

// ---------------------------------------------------------------------------------------------
// Independent penetration measure

// The depth of a vertex inside a polygon: `common::depth_inside`, shared with the invariant
// tests.
use crate::common::depth_inside;

/// 4·area / perimeter, m.
fn dims(v: &[Vector2<f64>]) -> f64 {
    let n = v.len();
    let (mut area2, mut perimeter) = (0.0, 0.0);
    for k in 0..n {
        let (a, b) = (v[k], v[(k + 1) % n]);
        area2 += a.x * b.y - a.y * b.x;
        perimeter += (b - a).norm();
    }
    2.0 * area2.abs() / perimeter
}

/// Deepest vertex-in-block penetration over all block pairs, as a fraction of the smaller
/// block dimension of the pair. Bounding boxes prune pairs (the 1000-block case).
fn penetration_ratio(s: &Simulation) -> (f64, f64) {
    let boxes: Vec<_> = s.geoms().iter().map(|g| g.bounds()).collect();
    let (mut worst_ratio, mut worst_depth) = (0.0f64, 0.0f64);
    for a in 0..s.geoms().len() {
        for b in 0..s.geoms().len() {
            if a == b {
                continue;
            }
            let (la, ha) = boxes[a];
            let (lb, hb) = boxes[b];
            if la.x > hb.x || lb.x > ha.x || la.y > hb.y || lb.y > ha.y {
                continue;
            }
            let scale = dims(&s.geoms()[a].vertices).min(dims(&s.geoms()[b].vertices));
            for p in &s.geoms()[a].vertices {
                let d = depth_inside(*p, &s.geoms()[b].vertices);
                worst_depth = worst_depth.max(d);
                worst_ratio = worst_ratio.max(d / scale);
            }
        }
    }
    (worst_ratio, worst_depth)
}

// ---------------------------------------------------------------------------------------------
// Driver

#[derive(Debug)]
struct Outcome {
    name: String,
    /// `None`: completed (to the end time or the step budget); `Some(message)`: diagnostic.
    diagnostic: Option<String>,
    steps: u64,
    time: f64,
    /// max over steps of (E − E0 − W_ground) / scale.
    energy_growth: f64,
    /// Largest penetration / smaller block dimension of the pair.
    penetration: f64,
    penetration_m: f64,
    non_finite: bool,
    wall_s: f64,
}

/// Run `scene` under `motion` to its duration or step budget (`control.max_steps`), checking
/// energy and penetration every `check_every` steps (1 for small scenes).
fn drive(name: &str, scene: &Scene, motion: &GroundMotion, check_every: u64) -> Outcome {
    let wall = Instant::now();
    let duration = scene.control.duration.expect("cases set a duration");
    let budget = scene.control.max_steps;
    let mut s = Simulation::new(scene, motion, SimParams::default());
    let masses: Vec<f64> = s
        .dofs()
        .block_of
        .iter()
        .map(|&b| s.geoms()[b].moments.area * scene.materials[scene.blocks[b].material].density)
        .collect();
    let heights: f64 = s
        .dofs()
        .block_of
        .iter()
        .zip(&masses)
        .map(|(&b, m)| {
            let (lo, hi) = s.geoms()[b].bounds();
            m * scene.gravity * (hi.y - lo.y)
        })
        .sum();
    let e0 = s.energy().total();
    let mut scale = heights + s.energy().kinetic;
    let (mut work, mut growth, mut pen, mut pen_m) = (0.0, f64::NEG_INFINITY, 0.0f64, 0.0f64);
    let mut diagnostic = None;
    let mut non_finite = false;
    while s.time() < duration * (1.0 - 1e-12) && s.stats().steps < budget {
        let before: Vec<Vector2<f64>> = s
            .dofs()
            .block_of
            .iter()
            .map(|&b| s.geoms()[b].centroid)
            .collect();
        if let Err(e) = s.step(duration - s.time()) {
            diagnostic = Some(e.to_string());
            break;
        }
        if s.first_non_finite_block().is_some() {
            non_finite = true;
            break;
        }
        let ag = s.motion().acceleration(s.time());
        for (f, &b) in s.dofs().block_of.iter().enumerate() {
            let du = s.geoms()[b].centroid - before[f];
            let dw = -masses[f] * (ag[0] * du.x + ag[1] * du.y);
            work += dw;
            scale += dw.abs();
        }
        if s.stats().steps % check_every == 0 {
            let e = s.energy().total();
            if !e.is_finite() {
                non_finite = true;
                break;
            }
            growth = growth.max((e - e0 - work) / scale);
            let (r, d) = penetration_ratio(&s);
            pen = pen.max(r);
            pen_m = pen_m.max(d);
        }
    }
    Outcome {
        name: name.into(),
        diagnostic,
        steps: s.stats().steps,
        time: s.time(),
        energy_growth: if growth.is_finite() { growth } else { 0.0 },
        penetration: pen,
        penetration_m: pen_m,
        non_finite,
        wall_s: wall.elapsed().as_secs_f64(),
    }
}

fn print_row(o: &Outcome) {
    let outcome = match &o.diagnostic {
        None => "completed".to_string(),
        Some(m) => format!("diagnostic: {m}"),
    };
    println!(
        "| {} | {} | {:.2e} | {:.2e} ({:.1e} m) | {} | {:.3e} s | {:.2} s |",
        o.name, outcome, o.energy_growth, o.penetration, o.penetration_m, o.steps, o.time, o.wall_s
    );
}

/// What a case must end in.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Expect {
    /// Must complete with bounded energy and penetration.
    Complete,
    /// Must stop with a typed diagnostic.
    Diagnostic,
}

/// The universal checks, then the case's expected outcome.
fn check(o: &Outcome, expect: Expect) {
    print_row(o);
    assert!(
        !o.non_finite,
        "{}: non-finite state after an accepted step",
        o.name
    );
    match (&o.diagnostic, expect) {
        (None, Expect::Complete) => {
            assert!(
                o.energy_growth <= ENERGY_TOL,
                "{}: energy grew by {:.3e} of the scale beyond the ground work",
                o.name,
                o.energy_growth
            );
            assert!(
                o.penetration <= penetration_tol(),
                "{}: penetration {:.3e} of the block size ({:.3e} m)",
                o.name,
                o.penetration,
                o.penetration_m
            );
        }
        (Some(m), Expect::Diagnostic) => assert_useful_diagnostic(&o.name, m),
        (d, e) => panic!("{}: expected {e:?}, got {d:?} ({o:?})", o.name),
    }
}

/// A diagnostic says when, where and what to change, and carries no NaN.
fn assert_useful_diagnostic(name: &str, m: &str) {
    assert!(m.contains("t = "), "{name}: diagnostic without a time: {m}");
    assert!(
        m.contains("block"),
        "{name}: diagnostic names no block: {m}"
    );
    assert!(
        ["reduce", "raise", "try", "check", "lower", "increase"]
            .iter()
            .any(|w| m.contains(w)),
        "{name}: diagnostic says nothing to change: {m}"
    );
    assert!(!m.contains("NaN") && !m.contains("inf"), "{name}: {m}");
    assert!(
        !m.contains("\"?\""),
        "{name}: diagnostic with an unknown block: {m}"
    );
}

fn case(name: &str, k: &Knobs, expect: Expect) -> Outcome {
    let scene = parse(&stack(k));
    let o = drive(name, &scene, &motion(k), 1);
    check(&o, expect);
    o
}

/// Set EXTREMES_EXPLORE=1 to print every row without asserting (used to draft the table).
fn explore() -> bool {
    std::env::var_os("EXTREMES_EXPLORE").is_some()
}

fn run_cases(cases: Vec<(&str, Knobs, Expect)>) {
    for (name, k, expect) in cases {
        if explore() {
            let scene = parse(&stack(&k));
            print_row(&drive(name, &scene, &motion(&k), 1));
        } else {
            case(name, &k, expect);
        }
    }
}

fn k() -> Knobs {
    Knobs::default()
}

use Expect::{Complete, Diagnostic};

// ---------------------------------------------------------------------------------------------
// One knob at a time

#[test]
fn penalty_stiffness_sweep() {
    run_cases(vec![
        (
            "penalty 1e4 N/m",
            Knobs {
                penalty: Some(1e4),
                ..k()
            },
            Diagnostic,
        ),
        (
            "penalty 1e6 N/m",
            Knobs {
                penalty: Some(1e6),
                ..k()
            },
            Diagnostic,
        ),
        (
            "penalty 1e8 N/m",
            Knobs {
                penalty: Some(1e8),
                ..k()
            },
            Complete,
        ),
        (
            "penalty 1e10 N/m",
            Knobs {
                penalty: Some(1e10),
                ..k()
            },
            Complete,
        ),
        (
            "penalty 1e12 N/m",
            Knobs {
                penalty: Some(1e12),
                ..k()
            },
            Complete,
        ),
        (
            "penalty 1e15 N/m",
            Knobs {
                penalty: Some(1e15),
                ..k()
            },
            Complete,
        ),
    ]);
}

#[test]
fn time_step_sweep() {
    run_cases(vec![
        ("Δt 1e-7 s", Knobs { dt: 1e-7, ..k() }, Complete),
        ("Δt 1e-5 s", Knobs { dt: 1e-5, ..k() }, Complete),
        ("Δt 1e-3 s", Knobs { dt: 1e-3, ..k() }, Complete),
        ("Δt 1e-2 s", Knobs { dt: 1e-2, ..k() }, Complete),
        (
            "Δt 0.1 s (adaptive)",
            Knobs {
                dt: 0.1,
                duration: 2.0,
                ..k()
            },
            Complete,
        ),
        (
            "Δt 0.1 s (fixed)",
            Knobs {
                dt: 0.1,
                adaptive: false,
                duration: 2.0,
                ..k()
            },
            Complete,
        ),
    ]);
}

#[test]
fn friction_sweep() {
    run_cases(vec![
        (
            "friction 0°",
            Knobs {
                friction_deg: 0.0,
                ..k()
            },
            Complete,
        ),
        (
            "friction 10°",
            Knobs {
                friction_deg: 10.0,
                ..k()
            },
            Complete,
        ),
        (
            "friction 45°",
            Knobs {
                friction_deg: 45.0,
                ..k()
            },
            Complete,
        ),
        (
            "friction 80°",
            Knobs {
                friction_deg: 80.0,
                ..k()
            },
            Complete,
        ),
        (
            "friction 89°",
            Knobs {
                friction_deg: 89.0,
                ..k()
            },
            Complete,
        ),
    ]);
}

#[test]
fn cohesion_and_tension_sweep() {
    run_cases(vec![
        (
            "cohesion 1e4 Pa",
            Knobs {
                cohesion: 1e4,
                ..k()
            },
            Complete,
        ),
        (
            "cohesion 1e8 Pa",
            Knobs {
                cohesion: 1e8,
                ..k()
            },
            Complete,
        ),
        (
            "tensile 1e4 Pa",
            Knobs {
                tensile: 1e4,
                ..k()
            },
            Complete,
        ),
        (
            "tensile 1e8 Pa",
            Knobs {
                tensile: 1e8,
                ..k()
            },
            Complete,
        ),
        (
            "cohesion + tensile 1e8 Pa, 5 g",
            Knobs {
                cohesion: 1e8,
                tensile: 1e8,
                pga_g: 5.0,
                ..k()
            },
            Complete,
        ),
    ]);
}

#[test]
fn aspect_ratio_sweep() {
    run_cases(vec![
        (
            "slab 1:50",
            Knobs {
                width: 5.0,
                height: 0.1,
                ..k()
            },
            Complete,
        ),
        (
            "slab 1:500",
            Knobs {
                width: 5.0,
                height: 0.01,
                ..k()
            },
            Complete,
        ),
        (
            "needle 1:50",
            Knobs {
                width: 0.1,
                height: 5.0,
                ..k()
            },
            Complete,
        ),
        (
            "needle 1:500",
            Knobs {
                width: 0.01,
                height: 5.0,
                ..k()
            },
            // Completes since the narrow phase stopped taking phantom penetrations of
            // vertices outside the edge block (contact/vertex_edge.rs): before, a vertex was
            // "found" 1.1 cm deep and the run stopped with `PenaltyTooSoft` after the energy
            // had grown by 2.8 × the scale. Energy and penetration are checked as for every
            // completed case.
            Complete,
        ),
    ]);
}

#[test]
fn block_size_sweep() {
    run_cases(vec![
        (
            "size 1 mm",
            Knobs {
                width: 1e-3,
                height: 1e-3,
                ..k()
            },
            Complete,
        ),
        (
            "size 1 cm",
            Knobs {
                width: 1e-2,
                height: 1e-2,
                ..k()
            },
            Complete,
        ),
        (
            "size 10 m",
            Knobs {
                width: 10.0,
                height: 10.0,
                ..k()
            },
            Complete,
        ),
        (
            "size 100 m",
            Knobs {
                width: 100.0,
                height: 100.0,
                ..k()
            },
            Complete,
        ),
    ]);
}

#[test]
fn density_sweep() {
    run_cases(vec![
        (
            "density 1 kg/m³",
            Knobs {
                density: 1.0,
                ..k()
            },
            Complete,
        ),
        (
            "density 1e5 kg/m³",
            Knobs {
                density: 1e5,
                ..k()
            },
            Complete,
        ),
    ]);
}

#[test]
fn young_modulus_sweep() {
    run_cases(vec![
        (
            "E 1e5 Pa (deformable, auto penalty)",
            Knobs {
                young: 1e5,
                model: "deformable",
                ..k()
            },
            Diagnostic,
        ),
        (
            "E 1e7 Pa (deformable)",
            Knobs {
                young: 1e7,
                model: "deformable",
                ..k()
            },
            Complete,
        ),
        (
            "E 1e13 Pa (deformable)",
            Knobs {
                young: 1e13,
                model: "deformable",
                ..k()
            },
            Complete,
        ),
        ("E 1e13 Pa (rigid)", Knobs { young: 1e13, ..k() }, Complete),
    ]);
}

#[test]
fn pga_sweep() {
    run_cases(vec![
        ("PGA 0", Knobs { pga_g: 0.0, ..k() }, Complete),
        ("PGA 1 g", Knobs { pga_g: 1.0, ..k() }, Complete),
        ("PGA 5 g", Knobs { pga_g: 5.0, ..k() }, Complete),
        ("PGA 20 g", Knobs { pga_g: 20.0, ..k() }, Complete),
        ("PGA 50 g", Knobs { pga_g: 50.0, ..k() }, Complete),
    ]);
}

#[test]
fn quiet_scene_for_1e4_s() {
    run_cases(vec![(
        "quiet stack, 1e4 s at Δt ≤ 1 s",
        Knobs {
            pga_g: 0.0,
            dt: 1.0,
            duration: 1e4,
            budget: 20_000,
            ..k()
        },
        Complete,
    )]);
}

// ---------------------------------------------------------------------------------------------
// Hard combinations

#[test]
fn hard_combinations() {
    run_cases(vec![
        (
            "soft penalty 1e6 + 50 g",
            Knobs {
                penalty: Some(1e6),
                pga_g: 50.0,
                ..k()
            },
            Diagnostic,
        ),
        (
            "penalty 1e15 + Δt 1e-7",
            Knobs {
                penalty: Some(1e15),
                dt: 1e-7,
                ..k()
            },
            Complete,
        ),
        (
            "penalty 1e15 + Δt 0.1 + 5 g",
            Knobs {
                penalty: Some(1e15),
                dt: 0.1,
                pga_g: 5.0,
                duration: 1.0,
                ..k()
            },
            Complete,
        ),
        (
            "needle 1:500 + friction 89° + 50 g",
            Knobs {
                width: 0.01,
                height: 5.0,
                friction_deg: 89.0,
                pga_g: 50.0,
                // "contact": the penalty contact's own impacts on a needle. Completes since a
                // landing corner is found before it lands (contact/vertex_edge.rs): before, the
                // vertex entered between detections and the run stopped with the penetration
                // diagnostic (3.3e-3 m at t = 0.0542 s). Energy and penetration are checked as
                // for every completed case (measured −1.2e-9 of the scale, 2.1e-7 of the block).
                restitution: Some("contact"),
                ..k()
            },
            Complete,
        ),
        (
            "slab 1:500 + friction 0° + 20 g",
            Knobs {
                width: 5.0,
                height: 0.01,
                friction_deg: 0.0,
                pga_g: 20.0,
                ..k()
            },
            Complete,
        ),
        (
            "1 mm + 1e5 kg/m³ + penalty 1e15",
            Knobs {
                width: 1e-3,
                height: 1e-3,
                density: 1e5,
                penalty: Some(1e15),
                ..k()
            },
            Complete,
        ),
        (
            "100 m + 1 kg/m³ + penalty 1e4",
            Knobs {
                width: 100.0,
                height: 100.0,
                density: 1.0,
                penalty: Some(1e4),
                ..k()
            },
            Complete,
        ),
        (
            "100 m + 1e5 kg/m³ + 50 g",
            Knobs {
                width: 100.0,
                height: 100.0,
                density: 1e5,
                pga_g: 50.0,
                ..k()
            },
            Complete,
        ),
        (
            "cohesion 1e8 + 50 g + Δt 0.1",
            Knobs {
                cohesion: 1e8,
                tensile: 1e8,
                pga_g: 50.0,
                dt: 0.1,
                duration: 1.0,
                ..k()
            },
            Complete,
        ),
        (
            "E 1e5 deformable + 20 g",
            Knobs {
                young: 1e5,
                model: "deformable",
                pga_g: 20.0,
                ..k()
            },
            Diagnostic,
        ),
        (
            "E 1e13 deformable + Δt 0.1 fixed",
            Knobs {
                young: 1e13,
                model: "deformable",
                dt: 0.1,
                adaptive: false,
                duration: 1.0,
                ..k()
            },
            Complete,
        ),
        (
            "trapezoidal + 50 g + friction 0°",
            Knobs {
                integrator: "trapezoidal",
                pga_g: 50.0,
                friction_deg: 0.0,
                ..k()
            },
            Complete,
        ),
    ]);
}

// ---------------------------------------------------------------------------------------------
// Degenerate contact geometry

fn geometry_case(name: &str, blocks: Value, k: &Knobs, expect: Expect) {
    let scene = parse(&scene_with(k, blocks));
    let o = drive(name, &scene, &motion(k), 1);
    if explore() {
        print_row(&o);
    } else {
        check(&o, expect);
    }
}

fn base() -> Value {
    json!({ "id": "base", "material": "m", "fixed": true, "vertices": rect(-2.0, -0.5, 4.0, 0.5) })
}

#[test]
fn single_vertex_contacts() {
    let k = Knobs {
        duration: 0.3,
        pga_g: 0.0,
        ..k()
    };
    // A square standing on one corner (a vertex on an edge): it must fall over, not hang.
    let diamond = json!([[0.0, 0.0], [0.35, 0.35], [0.0, 0.7], [-0.35, 0.35]]);
    geometry_case(
        "diamond on its corner",
        json!([base(), { "id": "diamond", "material": "m", "block_model": "rigid", "vertices": diamond }]),
        &k,
        Complete,
    );
    // A triangle apex down, tilted a little so it is not perfectly balanced.
    geometry_case(
        "triangle apex down",
        json!([base(), { "id": "tri", "material": "m", "block_model": "rigid", "vertices": [[0.0, 0.0], [0.3, 0.5], [-0.25, 0.5]] }]),
        &k,
        Complete,
    );
    // Vertex on vertex: a block whose bottom-left corner sits exactly on the top-right corner of
    // the block below (no edge in common).
    geometry_case(
        "vertex on vertex (corner to corner)",
        json!([
            base(),
            { "id": "a", "material": "m", "block_model": "rigid", "vertices": rect(-0.5, 0.0, 0.5, 0.5) },
            { "id": "b", "material": "m", "block_model": "rigid", "vertices": rect(0.0, 0.5, 0.5, 0.5) },
        ]),
        &k,
        Complete,
    );
    // Two diamonds touching tip to tip, the upper one balanced on the lower one's top vertex.
    geometry_case(
        "tip on tip (diamond on diamond)",
        json!([
            base(),
            { "id": "low", "material": "m", "block_model": "rigid", "vertices": rect(-0.3, 0.0, 0.6, 0.3) },
            { "id": "top", "material": "m", "block_model": "rigid", "vertices": [[0.0, 0.3], [0.2, 0.5], [0.0, 0.7], [-0.2, 0.5]] },
        ]),
        &k,
        Complete,
    );
}

#[test]
fn collinear_edges_and_tiny_overlaps() {
    let k = Knobs {
        duration: 0.2,
        ..k()
    };
    // A row of three blocks with collinear top and bottom edges, a lintel spanning two joints:
    // the lintel's bottom edge is collinear with the row's top edges, the row's corners lie on
    // the lintel's edge.
    geometry_case(
        "collinear row + lintel over two joints",
        json!([
            base(),
            { "id": "r0", "material": "m", "block_model": "rigid", "vertices": rect(-0.9, 0.0, 0.6, 0.4) },
            { "id": "r1", "material": "m", "block_model": "rigid", "vertices": rect(-0.3, 0.0, 0.6, 0.4) },
            { "id": "r2", "material": "m", "block_model": "rigid", "vertices": rect(0.3, 0.0, 0.6, 0.4) },
            { "id": "lintel", "material": "m", "block_model": "rigid", "vertices": rect(-0.6, 0.4, 1.2, 0.2) },
        ]),
        &k,
        Complete,
    );
    // A block whose vertical side is collinear with the base's end (flush edges).
    geometry_case(
        "flush with the base's end",
        json!([base(), { "id": "b", "material": "m", "block_model": "rigid", "vertices": rect(1.5, 0.0, 0.5, 0.5) }]),
        &k,
        Complete,
    );
    // Overlap below validation's rounding tolerance (1e-6 of the block): accepted, and the springs
    // push the blocks apart within the first steps.
    geometry_case(
        "initial overlap 1e-7 m",
        json!([
            base(),
            { "id": "b", "material": "m", "block_model": "rigid", "vertices": rect(-0.25, -1e-7, 0.5, 0.5) },
        ]),
        &k,
        Complete,
    );
    geometry_case(
        "initial gap 1e-9 m",
        json!([
            base(),
            { "id": "b", "material": "m", "block_model": "rigid", "vertices": rect(-0.25, 1e-9, 0.5, 0.5) },
        ]),
        &k,
        Complete,
    );
    // Overlap beyond the tolerance: a scene error naming both blocks, before any step.
    let bad = scene_with(
        &k,
        json!([
            base(),
            { "id": "sunk", "material": "m", "block_model": "rigid", "vertices": rect(-0.25, -1e-3, 0.5, 0.5) },
        ]),
    );
    let e = parse_scene(&bad.to_string()).expect_err("1 mm overlap must be rejected");
    let m = e.to_string();
    println!("| initial overlap 1e-3 m | scene error: {m} | – | – | 0 | – | – |");
    assert!(
        m.contains("sunk") && m.contains("base") && m.contains("overlap"),
        "{m}"
    );
}

// ---------------------------------------------------------------------------------------------
// Large models

/// ~1000-block dry-stone wall (20 courses × 50 blocks) at rest, then under 0.5 g: 20 steps
/// each (a step of the shaken wall takes ~1 s in the test profile on a loaded 2-core machine), energy and penetration checked every 5 steps (the O(n²)-pruned penetration
/// measure is the expensive part here).
#[test]
fn thousand_block_wall() {
    use ashlar::scene::generate::{running_bond_wall, WallParams};
    let spec = running_bond_wall(&WallParams {
        courses: 20,
        blocks_per_course: 50,
        block_length: 0.4,
        block_height: 0.2,
        ..Default::default()
    });
    let mut v = serde_json::to_value(&spec).expect("spec serializes");
    v["control"] = json!({ "time_step": 1e-3, "duration": 0.05, "max_steps": 20 });
    let scene = parse(&v);
    assert!(scene.blocks.len() >= 1000, "{} blocks", scene.blocks.len());
    for (name, pga) in [
        ("1010-block wall at rest", 0.0),
        ("1010-block wall, 0.5 g", 0.5),
    ] {
        let k = Knobs { pga_g: pga, ..k() };
        let o = drive(name, &scene, &motion(&k), 5);
        if explore() {
            print_row(&o);
        } else {
            check(&o, Complete);
        }
    }
}

/// ~1000 loose blocks dropped in a grid with gaps onto a floor: many contacts open and close at
/// once: the lowest row lands after ~14 ms, the run stops at 30 ms or 60 steps.
#[test]
fn thousand_block_pile() {
    let mut blocks = vec![
        json!({ "id": "floor", "material": "m", "fixed": true, "vertices": rect(-1.0, -0.5, 42.0, 0.5) }),
    ];
    for r in 0..25 {
        for c in 0..40 {
            let x = c as f64 * 1.0 + if r % 2 == 1 { 0.3 } else { 0.0 };
            let y = 0.001 + r as f64 * 0.502;
            blocks.push(json!({ "id": format!("p{r}_{c}"), "material": "m", "block_model": "rigid", "vertices": rect(x, y, 0.8, 0.5) }));
        }
    }
    let k = Knobs {
        duration: 0.03,
        budget: 60,
        pga_g: 0.0,
        ..k()
    };
    let scene = parse(&scene_with(&k, Value::Array(blocks)));
    let o = drive("1000-block pile dropped", &scene, &motion(&k), 10);
    if explore() {
        print_row(&o);
    } else {
        check(&o, Complete);
    }
}

// ---------------------------------------------------------------------------------------------
// Through the run entry point (what the CLI and the service call)

/// The step budget stops a run cleanly (a shortened but valid summary, the reason given), every
/// number in the summary is finite, and an engine diagnostic arrives as the run's error message.
#[test]
fn run_entry_point_budget_summary_and_diagnostic() {
    use ashlar::analysis::run::{run, RunError, RunOptions};
    let k = Knobs {
        dt: 1e-5,
        adaptive: false,
        duration: 10.0,
        budget: 300,
        pga_g: 5.0,
        ..k()
    };
    let scene = parse(&stack(&k));
    let out = run(&scene, &motion(&k), &RunOptions::default()).expect("budgeted run");
    let s = &out.summary;
    println!(
        "| run entry point, budget 300 steps | stopped: {:?} | – | – | {} | {:.3e} s | {:.2} s |",
        s.stopped_reason, s.steps, s.simulated_time, s.wall_time_s
    );
    assert_eq!(s.steps, 300);
    assert!(
        s.stopped_reason
            .as_deref()
            .is_some_and(|r| r.contains("control.max_steps")),
        "{:?}",
        s.stopped_reason
    );
    let text = serde_json::to_string(s).expect("summary serializes");
    let v: Value = serde_json::from_str(&text).expect("summary is JSON");
    assert_all_finite(&v, "summary");

    let soft = Knobs {
        penalty: Some(1e4),
        ..Knobs::default()
    };
    let scene = parse(&stack(&soft));
    match run(&scene, &motion(&soft), &RunOptions::default()) {
        Err(RunError::Simulation(e)) => {
            let m = e.to_string();
            println!("| run entry point, penalty 1e4 N/m | error: {m} | – | – | – | – | – |");
            assert_useful_diagnostic("run entry point", &m);
        }
        other => panic!("expected a simulation error, got {other:?}"),
    }
}

/// serde_json writes non-finite floats as null: a null where a number belongs is a NaN leak.
fn assert_all_finite(v: &Value, path: &str) {
    match v {
        Value::Number(n) => assert!(n.as_f64().is_some_and(f64::is_finite), "{path} = {n}"),
        Value::Array(a) => a
            .iter()
            .enumerate()
            .for_each(|(i, x)| assert_all_finite(x, &format!("{path}[{i}]"))),
        Value::Object(m) => m.iter().for_each(|(k, x)| {
            if !(x.is_null() && ["stopped_reason"].contains(&k.as_str())) {
                assert!(!x.is_null(), "{path}.{k} is null (a non-finite number?)");
                assert_all_finite(x, &format!("{path}.{k}"));
            }
        }),
        _ => {}
    }
}

/// Found when the default impact law became Newton's with e = 0: the needle of
/// `hard_combinations` (1:500, friction 89°, 50 g) under the default law completed its 0.2 s
/// with E − E₀ − W_ground = 4.03 × the energy scale. Gone since impacts are located in time
/// and a landing corner is found before it lands (docs/restitution.md): measured −1.2e-9 of
/// the scale, penetration 2.1e-7 of the block. On the rocking column the mechanism was seen
/// (the impulse at the step start stopped the corner up to a step's travel above its edge, or
/// it was found already 85 µm deep and the contact threw the block off); on the needle it was
/// not isolated. The bound is the suite's own (`ENERGY_TOL`).
#[test]
fn needle_under_the_default_impact_law_keeps_energy_bounded() {
    run_cases(vec![(
        "needle 1:500 + friction 89° + 50 g, default impact law",
        Knobs {
            width: 0.01,
            height: 5.0,
            friction_deg: 89.0,
            pga_g: 50.0,
            ..k()
        },
        Complete,
    )]);
}
