//! Is `auto`'s hand-over to the engine (the default; `RunOptions::fallback_from_zero` turns it off) as accurate as the
//! fallback from t = 0? (docs/speed.md, "Reduced models on records", session 32.) For the
//! bundled column (`examples/column.json`, 0.4 × 1.2 m, φ = 40°) and the slender column of
//! `tests/analysis/pga_honesty.rs` (0.24 × 1.6 m, φ = 75°) under every record in
//! `data/ground-motions/` (and the slender one over the records' first 9 s, as `pga_honesty`
//! runs it), the default search's lowest failing PGA F (`toppled:column`,
//! 0.05–2 g, 40 scan points, 0.01 m/s², fallback from t = 0), then runs at F × `FACTORS`:
//! (a) `auto` with the hand-over, (b) `auto` with the fallback from t = 0, (c) the full engine
//! from t = 0 at Δt = 1e-4 s (`"model": "dda"`, the converged reference of
//! docs/accuracy-vs-speed.md). Every run stops as a search's does once the column passes 60°.
//! Also every other amplitude of that search at which `auto` fell back to the engine (the
//! only runs where (a) and (b) can differ). Prints one table row per point (verdicts, peak |θ| where the column stands, which model
//! ran) and the counts: verdicts of (a) and (b) equal to (c)'s, peaks within 5 % of (c)'s
//! where (c) stands with more than 0.02 rad.
//!
//! Run: `cargo run --release --example handover_study` (about 5 min at 2 threads, loaded).
use ashlar::analysis::pga::{search, Combine, Criterion, PgaRequest};
use ashlar::analysis::run::{run, RunOptions, Summary, Tracker};
use ashlar::motion::GroundMotion;
use ashlar::presets::{self, Column};
use ashlar::scene::{parse_scene, ModelChoice, Scene};
use rayon::prelude::*;
use serde_json::json;

const G: f64 = 9.80665;
/// Amplitudes around the threshold F, as fractions of it.
const FACTORS: [f64; 7] = [0.90, 0.95, 0.98, 1.00, 1.02, 1.05, 1.10];
/// The converged reference step, s (docs/accuracy-vs-speed.md).
const FINE_DT: f64 = 1e-4;

/// Verdict (|θ| > 30° at the end), peak |θ| (rad), model that ran, CPU-free wall time (s).
struct Point {
    fell: bool,
    peak: f64,
    model: String,
    reason: String,
    wall: f64,
}

fn point(scene: &Scene, gm: &GroundMotion, hand_over: bool) -> Point {
    let stop = |tr: &Tracker| tr.final_rotation[0].abs() > std::f64::consts::FRAC_PI_3;
    let opts = RunOptions {
        stop_when: Some(&stop),
        no_trajectory: true,
        fallback_from_zero: !hand_over,
        ..Default::default()
    };
    let t = std::time::Instant::now();
    let s: Summary = run(scene, gm, &opts).expect("run").summary;
    let b = &s.blocks[0];
    Point {
        fell: b.final_rotation.abs() > 30f64.to_radians(),
        peak: b.max_rotation,
        model: s.model.clone(),
        reason: s.model_reason.clone(),
        wall: t.elapsed().as_secs_f64(),
    }
}

fn main() {
    let column = parse_scene(presets::EXAMPLE_COLUMN).expect("column");
    let slender = Column {
        half_width: 0.12,
        half_height: 0.8,
        ..Column::SEED
    }
    .json(json!({}));
    let slender = parse_scene(&slender.to_string()).expect("slender");
    let mut names: Vec<String> = std::fs::read_dir(presets::records_dir())
        .expect("data/ground-motions")
        .filter_map(|e| e.ok()?.file_name().into_string().ok())
        .filter(|n| n.ends_with(".at2") || n.ends_with(".csv"))
        .collect();
    names.sort();
    // The slender column as `pga_honesty` runs it: the records' first 9 s.
    let mut windowed = slender.clone();
    windowed.control.duration = Some(9.0);
    let scenes = [
        ("column 0.4 x 1.2 m", column),
        ("slender 0.24 x 1.6 m", slender),
        ("slender, 9 s", windowed),
    ];
    let criteria = vec![Criterion::parse("toppled:column").expect("criterion")];
    let req = PgaRequest {
        criteria,
        combine: Combine::All,
        min: 0.05 * G,
        max: 2.0 * G,
        tolerance: 0.01,
        scan_points: 40,
    };
    let mut jobs = Vec::new();
    for (label, scene) in &scenes {
        for name in &names {
            let gm = presets::record(name).expect("record");
            let r = search(scene, &gm, &req, &RunOptions::default()).expect("search");
            let Some(f) = r.failing_pga else {
                println!("{label} / {name}: stands up to 2 g, no points");
                continue;
            };
            println!("{label} / {name}: F = {f:.4} m/s² ({:.3} g)", f / G);
            for k in FACTORS {
                jobs.push((*label, scene.clone(), name.clone(), gm.clone(), k, f * k));
            }
            // Every amplitude of the search at which `auto` fell back to the engine (where the
            // hand-over can change anything), but those already above.
            let mut fell_back = 0;
            for run in &r.runs {
                let k = run.pga / f;
                if FACTORS.iter().any(|x| (x - k).abs() < 1e-9) {
                    continue;
                }
                if point(scene, &gm.scaled_to_pga(run.pga), false).model == "dda" {
                    jobs.push((*label, scene.clone(), name.clone(), gm.clone(), k, run.pga));
                    fell_back += 1;
                }
            }
            println!(
                "  {fell_back} more amplitudes of its {} runs fell back",
                r.runs.len()
            );
        }
    }
    let rows: Vec<_> = jobs
        .par_iter()
        .map(|(label, scene, name, gm, k, pga)| {
            let scaled = gm.scaled_to_pga(*pga);
            let a = point(scene, &scaled, true);
            let b = point(scene, &scaled, false);
            let mut fine = scene.clone();
            fine.control.model = ModelChoice::Dda;
            fine.control.time_step = FINE_DT;
            let c = point(&fine, &scaled, false);
            (*label, name.clone(), *k, *pga, a, b, c)
        })
        .collect();
    println!("\n| column | record | PGA (× F) | m/s² | (c) engine 1e-4 s | (a) hand-over | (b) from t = 0 | model (a) | wall (a) / (b) / (c), s |");
    println!("|---|---|---|---|---|---|---|---|---|");
    let show = |p: &Point, c: &Point| {
        if p.fell {
            "falls".to_string()
        } else if c.fell || c.peak <= 0.02 {
            format!("stands {:.4}", p.peak)
        } else {
            format!(
                "stands {:.4} ({:+.1} %)",
                p.peak,
                100.0 * (p.peak / c.peak - 1.0)
            )
        }
    };
    let (mut n, mut va, mut vb, mut np, mut pa, mut pb, mut fellback) = (0, 0, 0, 0, 0, 0, 0);
    let (mut fa, mut fb, mut fpn, mut fpa, mut fpb) = (0, 0, 0, 0, 0);
    for (label, name, k, pga, a, b, c) in &rows {
        n += 1;
        va += usize::from(a.fell == c.fell);
        vb += usize::from(b.fell == c.fell);
        let handed = a.reason.contains("ran from t = ");
        fellback += usize::from(a.model == "dda");
        if !c.fell && c.peak > 0.02 {
            np += 1;
            pa += usize::from(!a.fell && (a.peak / c.peak - 1.0).abs() <= 0.05);
            pb += usize::from(!b.fell && (b.peak / c.peak - 1.0).abs() <= 0.05);
        }
        if a.model == "dda" {
            fa += usize::from(a.fell == c.fell);
            fb += usize::from(b.fell == c.fell);
            if !c.fell && c.peak > 0.02 {
                fpn += 1;
                fpa += usize::from(!a.fell && (a.peak / c.peak - 1.0).abs() <= 0.05);
                fpb += usize::from(!b.fell && (b.peak / c.peak - 1.0).abs() <= 0.05);
            }
        }
        let c_text = if c.fell {
            "falls".to_string()
        } else {
            format!("stands {:.4}", c.peak)
        };
        println!(
            "| {label} | {name} | {k:.2} | {pga:.3} | {c_text} | {} | {} | {}{} | {:.3} / {:.3} / {:.3} |",
            show(a, c),
            show(b, c),
            a.model,
            if handed { " (handed over)" } else { "" },
            a.wall,
            b.wall,
            c.wall
        );
    }
    // Where (a) and (b) disagree: is the reference's verdict robust (the same at 0.97 and
    // 1.03 × the PGA, the condition for requiring a verdict)?
    for (label, name, k, pga, a, b, c) in &rows {
        if a.fell == b.fell {
            continue;
        }
        let (_, scene, _, gm, _, _) = jobs
            .iter()
            .find(|j| j.0 == *label && j.2 == *name && j.5 == *pga)
            .expect("job");
        let mut fine = scene.clone();
        fine.control.model = ModelChoice::Dda;
        fine.control.time_step = FINE_DT;
        let side: Vec<String> = [0.97, 1.03]
            .par_iter()
            .map(|f| {
                let p = point(&fine, &gm.scaled_to_pga(pga * f), false);
                if p.fell {
                    format!("{f} × PGA: falls")
                } else {
                    format!("{f} × PGA: stands {:.4}", p.peak)
                }
            })
            .collect();
        println!(
            "\n{label} / {name} at {k:.3} F ({pga:.3} m/s²): (a) {}, (b) {}, (c) {}; (c) at {}",
            if a.fell { "falls" } else { "stands" },
            if b.fell { "falls" } else { "stands" },
            if c.fell { "falls" } else { "stands" },
            side.join(", ")
        );
    }
    println!(
        "\nwhere `auto` fell back ({fellback} points): verdict = reference: (a) {fa}, (b) {fb}; peak within 5 %: (a) {fpa}/{fpn}, (b) {fpb}/{fpn}"
    );
    println!(
        "points {n}; `auto` fell back to the engine at {fellback}; verdict = reference: (a) hand-over {va}/{n}, (b) from t = 0 {vb}/{n}; peak within 5 % of the reference where it stands above 0.02 rad: (a) {pa}/{np}, (b) {pb}/{np}"
    );
}
