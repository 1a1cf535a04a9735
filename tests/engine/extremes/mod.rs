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
    let blocks = ashlar::presets::Stack {
        half_width: 0.5 * w,
        lower_height: h,
        upper_height: h,
        base_half_width: 1.5 * w,
        base_depth: 0.5 * w.min(h).max(0.1 * w.max(h)),
    }
    .blocks("m", k.model);
    scene_with(k, blocks)
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

mod combinations;
mod large;
mod one_knob;
