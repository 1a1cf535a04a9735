//! Scene builders shared by the physics tests (each test writes its reference solution itself).
#![allow(dead_code)]
use ashlar::motion::GroundMotion;
use ashlar::scene::{parse_scene, Scene};
use ashlar::simulation::{SimParams, Simulation};
use serde_json::Value;

#[allow(unused_imports)] // each test binary uses a different subset
pub use ashlar::presets::{half_sine, incline, rect, rocking_pulse, scene_json, sine, Column, G};

/// The contact solver the physics suites run with: `ASHLAR_CONTACT_SOLVER=dual cargo test
/// --test engine incline:: …` runs the same benchmarks, against the same references and tolerances, with
/// the dual (penalty-free) solver. Unset: the scene's own choice (default penalty).
pub fn solver_under_test() -> Option<String> {
    std::env::var("ASHLAR_CONTACT_SOLVER").ok()
}

/// True when the suites run with the dual solver.
pub fn dual_under_test() -> bool {
    solver_under_test().as_deref() == Some("dual")
}

pub fn parse(v: &Value) -> Scene {
    let mut v = v.clone();
    if let Some(solver) = solver_under_test() {
        if v["control"].get("contact_solver").is_none() {
            v["control"]["contact_solver"] = Value::String(solver);
        }
    }
    match parse_scene(&v.to_string()) {
        Ok(s) => s,
        Err(e) => panic!("test scene invalid: {e}"),
    }
}

/// Run to `t_end`, calling `probe(sim)` after every step.
pub fn run(sim: &mut Simulation, t_end: f64, mut probe: impl FnMut(&Simulation)) {
    while sim.time() < t_end - 1e-12 {
        if let Err(e) = sim.step(t_end - sim.time()) {
            panic!("simulation failed: {e}");
        }
        probe(sim);
    }
}

pub fn sim(scene: &Scene, motion: &GroundMotion) -> Simulation {
    Simulation::new(scene, motion, SimParams::default())
}

/// Centroid displacement of block `b` from its start, m.
pub fn displacement(sim: &Simulation, b: usize) -> [f64; 2] {
    let g = &sim.geoms()[b];
    [
        g.centroid.x - g.initial_centroid.x,
        g.centroid.y - g.initial_centroid.y,
    ]
}

/// Run until `t_end` or until `stop(sim)` is true; returns whether it stopped early.
pub fn run_until(
    sim: &mut Simulation,
    t_end: f64,
    mut stop: impl FnMut(&Simulation) -> bool,
) -> bool {
    while sim.time() < t_end - 1e-12 {
        if let Err(e) = sim.step(t_end - sim.time()) {
            panic!("simulation failed: {e}");
        }
        if stop(sim) {
            return true;
        }
    }
    false
}

/// The aligned stack of `ashlar::presets::aligned_stack`, parsed.
pub fn aligned_stack(columns: usize, rows: usize) -> Scene {
    parse(&ashlar::presets::aligned_stack(columns, rows))
}

/// Depth of `p` inside the polygon `poly` (either orientation, convex or not), m: the distance
/// to its nearest edge if inside (crossing-number test), 0 outside.
pub fn depth_inside(p: nalgebra::Vector2<f64>, poly: &[nalgebra::Vector2<f64>]) -> f64 {
    let n = poly.len();
    let mut inside = false;
    let mut nearest = f64::INFINITY;
    for i in 0..n {
        let (a, b) = (poly[i], poly[(i + 1) % n]);
        if (a.y > p.y) != (b.y > p.y) {
            let x = a.x + (p.y - a.y) / (b.y - a.y) * (b.x - a.x);
            if x > p.x {
                inside = !inside;
            }
        }
        let ab = b - a;
        let t = ((p - a).dot(&ab) / ab.norm_squared()).clamp(0.0, 1.0);
        nearest = nearest.min((a + t * ab - p).norm());
    }
    if inside {
        nearest
    } else {
        0.0
    }
}

/// Deepest penetration of any block's vertex inside any other block, m, measured geometrically
/// from the blocks' current vertices and edges (independently of the engine's own contact
/// statistics): for every pair whose bounding boxes overlap, the distance from each vertex of
/// one block that lies inside the other to that block's nearest edge ([`depth_inside`]).
pub fn geometric_penetration(sim: &Simulation) -> f64 {
    let boxes: Vec<_> = sim.geoms().iter().map(|g| g.bounds()).collect();
    let mut worst = 0.0f64;
    for (a, ga) in sim.geoms().iter().enumerate() {
        for (b, gb) in sim.geoms().iter().enumerate() {
            let ((la, ha), (lb, hb)) = (boxes[a], boxes[b]);
            if a == b || la.x > hb.x || lb.x > ha.x || la.y > hb.y || lb.y > ha.y {
                continue;
            }
            for p in &ga.vertices {
                worst = worst.max(depth_inside(*p, &gb.vertices));
            }
        }
    }
    worst
}

/// `examples/column.json` as the CLI reads it (no solver override: the file's own choice), the
/// scene of the golden digests and of the PGA-range tests.
pub fn example_column() -> Scene {
    parse_scene(ashlar::presets::EXAMPLE_COLUMN)
        .unwrap_or_else(|e| panic!("examples/column.json: {e}"))
}

/// The PGA-range tests' search: `toppled:column` from `min_g` to 2 g (g = 9.80665 m/s²) with
/// 40 scan points (the CLI's defaults but the start of the range), to 0.01 m/s².
pub fn toppled_column_search(min_g: f64) -> ashlar::analysis::pga::PgaRequest {
    use ashlar::analysis::pga::{Criterion, PgaRequest};
    PgaRequest {
        min: min_g * ashlar::motion::STANDARD_GRAVITY,
        ..PgaRequest::cli_default(vec![Criterion::parse("toppled:column").expect("criterion")])
    }
}

/// One of the repository's recorded ground motions by file name (data/ground-motions).
pub fn record(name: &str) -> GroundMotion {
    ashlar::presets::record(name).unwrap_or_else(|e| panic!("{name}: {e}"))
}

/// The scene templates, in the order `ashlar scene --list` and `GET /v1/templates` list them
/// (docs/templates.md).
pub const TEMPLATE_NAMES: [&str; 7] = [
    "drum-column",
    "colonnade",
    "arch",
    "wall",
    "buttressed-wall",
    "obelisk",
    "pyramid",
];

/// The `name` of each template in a JSON list of templates.
pub fn listed_names(list: &Value) -> Vec<&str> {
    list.as_array()
        .expect("a list of templates")
        .iter()
        .filter_map(|t| t["name"].as_str())
        .collect()
}

/// A column of half-width `b` and half-height `h` (m) on a fixed base 4 m wide and 0.5 m deep,
/// turned clockwise by `theta0` (rad) about its bottom-right corner (θ0 = 0: upright), as released
/// from a tilt; `block_model` "rigid" or "deformable", the scene's `control` as given. φ = 75°:
/// its pivot never slips (tan 75° = 3.7 ≫ the friction demand of rocking). Blocks `base`, then
/// `column` (block 1). The rocking-impact tests: restitution, rocking impacts, the trapezoidal
/// rule's impact regression.
pub fn tilted_column(b: f64, h: f64, theta0: f64, block_model: &str, control: Value) -> Value {
    let (co, si) = (theta0.cos(), theta0.sin());
    let rot = |x: f64, y: f64| {
        let dx = x - b;
        [b + co * dx + si * y, -si * dx + co * y]
    };
    let v = [rot(-b, 0.0), rot(b, 0.0), rot(b, 2.0 * h), rot(-b, 2.0 * h)];
    let blocks = serde_json::json!([
        { "id": "base", "material": "stone", "fixed": true, "vertices": rect(-2.0, -0.5, 2.0, 0.0) },
        { "id": "column", "material": "stone", "block_model": block_model, "vertices": v },
    ]);
    scene_json(blocks, 75.0, control)
}

/// Block `block`'s angular velocity just before and just after the first impact within 2 s
/// (rad/s). Before: at the start of the step whose impact law fired (the velocity the impulse
/// acts on). After: at the end of that step, less the change over the next step (the gravity
/// torque's share within the step, extrapolated linearly: error O(θ⃛ Δt²)).
pub fn first_impact_angular_velocities(s: &mut Simulation, block: usize) -> (f64, f64) {
    let mut before = None;
    let mut history = Vec::new();
    while s.time() < 2.0 && history.len() < 2 {
        let w0 = s.block_velocity(block)[2];
        let n0 = s.stats().impacts;
        s.step(f64::INFINITY).expect("step");
        if before.is_some() {
            history.push(s.block_velocity(block)[2]);
        } else if s.stats().impacts > n0 {
            before = Some(w0);
            history.push(s.block_velocity(block)[2]);
        }
    }
    let before = before.expect("no impact within 2 s");
    (before, 2.0 * history[0] - history[1])
}

/// The fields of `ashlar motion`'s JSON report (docs/format.md §3), which `POST
/// /v1/motions/inspect` gives too: written here once, independently of the code that builds it.
pub const MOTION_REPORT_FIELDS: [&str; 12] = [
    "npts",
    "dt",
    "duration",
    "original_units",
    "pga",
    "pgv",
    "pgd",
    "arias_intensity",
    "significant_duration_5_95",
    "cav",
    "mean_period",
    "spectrum",
];

/// The time, s, written after `marker` in a run's `model_reason` (e.g. "ran from t = " for
/// the hand-over, "; at t = " for the hand-back); `None` when the reason has no such time.
pub fn reason_time(reason: &str, marker: &str) -> Option<f64> {
    reason
        .split(marker)
        .nth(1)
        .and_then(|r| r.split(' ').next())
        .and_then(|t| t.parse().ok())
}

/// Rows of `histories.csv` as [time, the named columns in order…] (each name as in the
/// header, e.g. "column.rotation_rad"); panics naming a column the header lacks.
pub fn history_columns(path: &std::path::Path, names: &[&str]) -> Vec<Vec<f64>> {
    let csv = std::fs::read_to_string(path).expect("histories");
    let mut lines = csv.lines();
    let head: Vec<&str> = lines.next().expect("header").split(',').collect();
    let cols: Vec<usize> = names
        .iter()
        .map(|name| {
            head.iter()
                .position(|h| h == name)
                .unwrap_or_else(|| panic!("{name} in {head:?}"))
        })
        .collect();
    lines
        .map(|l| {
            let v: Vec<f64> = l.split(',').map(|x| x.parse().expect("number")).collect();
            std::iter::once(v[0])
                .chain(cols.iter().map(|&c| v[c]))
                .collect()
        })
        .collect()
}

/// A stitched history is whole: it starts at t = 0, its times increase, it ends at the run's
/// simulated time (within 1e-9 s) and its last rotation (row[1]) is the summary's, exactly.
pub fn assert_whole_history(rows: &[Vec<f64>], simulated_time: f64, final_rotation: f64) {
    assert_eq!(rows[0][0], 0.0);
    assert!(rows.windows(2).all(|w| w[1][0] > w[0][0]), "times increase");
    let last = rows.last().expect("rows");
    assert!((last[0] - simulated_time).abs() < 1e-9, "{last:?}");
    assert_eq!(last[1], final_rotation);
}
