//! Is `auto`'s fallback to the engine as accurate as the engine run through? (docs/speed.md,
//! "Reduced models on records", sessions 32 and 33.) For the bundled column
//! (`examples/column.json`, 0.4 × 1.2 m, φ = 40°), the slender column of
//! `tests/analysis/pga_honesty.rs` (0.24 × 1.6 m, φ = 75°; also over the records' first 9 s, as
//! `pga_honesty` runs it) and a squat block (0.6 × 0.8 m, φ = 40°: the scene where the
//! hand-back acts) under every record in `data/ground-motions/`: the default search's lowest
//! failing PGA F (`toppled:column`, 0.05–2 g, 40 scan points, 0.01 m/s²), runs at F ×
//! `FACTORS`, and every other amplitude of that search at which `auto` fell back to the engine
//! (the only runs where the variants can differ; for a block standing up to 2 g, only these).
//! Variants: (a) `auto` as by default: the hand-over to the engine at the reduced model's last
//! valid sample, and the hand-back to the reduced model once the engine's block is at rest
//! again (`analysis::run_fallback::HandBackParams`); (h) the hand-over without the hand-back
//! (session 32's default); (b) the fallback from t = 0; (c) the full engine from t = 0 at
//! Δt = 1e-4 s (`"model": "dda"`, the converged reference of docs/accuracy-vs-speed.md).
//! Every run stops as a search's does once the column passes 60°. Prints one table row per
//! point (verdicts, peak |θ| where the block stands, which model ran) and the counts per
//! variant: verdicts equal to (c)'s (over all points and where `auto` fell back), peaks within
//! 5 % of (c)'s where (c) stands with more than 0.02 rad.
//!
//! Run: `cargo run --release --example handover_study` (about 10 min at 2 threads, loaded).
use ashlar::analysis::pga::{search, Criterion, PgaRequest};
use ashlar::analysis::run::{run, RunOptions, Summary, Tracker};
use ashlar::analysis::run_fallback::HandBackParams;
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

/// How `auto` falls back: the default (hand-over, then hand-back once the block is at rest),
/// the hand-over without the hand-back, or the engine from t = 0.
#[derive(Clone, Copy, PartialEq)]
enum Fallback {
    HandBack,
    HandOver,
    FromZero,
}

fn point(scene: &Scene, gm: &GroundMotion, how: Fallback) -> Point {
    let stop = |tr: &Tracker| tr.final_rotation[0].abs() > std::f64::consts::FRAC_PI_3;
    let opts = RunOptions {
        stop_when: Some(&stop),
        no_trajectory: true,
        fallback_from_zero: how == Fallback::FromZero,
        hand_back: Some(HandBackParams {
            enabled: how == Fallback::HandBack,
            ..Default::default()
        }),
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
    let slender = Column::SLENDER.json(json!({}));
    let slender = parse_scene(&slender.to_string()).expect("slender");
    let mut names: Vec<String> = std::fs::read_dir(presets::records_dir())
        .expect("data/ground-motions")
        .filter_map(|e| e.ok()?.file_name().into_string().ok())
        .filter(|n| n.ends_with(".at2") || n.ends_with(".csv"))
        .collect();
    names.sort();
    let squat = Column {
        half_width: 0.3,
        half_height: 0.4,
        ..Column::SEED
    }
    .friction(40.0)
    .json(json!({}));
    let squat = parse_scene(&squat.to_string()).expect("squat");
    // The slender column as `pga_honesty` runs it: the records' first 9 s.
    let mut windowed = slender.clone();
    windowed.control.duration = Some(9.0);
    let scenes = [
        ("column 0.4 x 1.2 m", column),
        ("slender 0.24 x 1.6 m", slender),
        ("slender, 9 s", windowed),
        // A squat block (tan α = 0.75 below μ = 0.84): its pivot lifts off at small rotations
        // under strong shaking, the engine takes over, and the block comes to rest again: the
        // runs where the hand-back acts (it never does on the columns above: every fallback
        // there is a column already overturning).
        ("squat 0.6 x 0.8 m", squat),
    ];
    let criteria = vec![Criterion::parse("toppled:column").expect("criterion")];
    let req = PgaRequest::cli_default(criteria);
    let mut jobs = Vec::new();
    for (label, scene) in &scenes {
        for name in &names {
            let gm = presets::record(name).expect("record");
            let r = search(scene, &gm, &req, &RunOptions::default()).expect("search");
            // F, or (a block that stands up to 2 g) 1 m/s², so that "× F" is the PGA itself.
            let f = match r.failing_pga {
                Some(f) => {
                    println!("{label} / {name}: F = {f:.4} m/s² ({:.3} g)", f / G);
                    for k in FACTORS {
                        jobs.push((*label, scene.clone(), name.clone(), gm.clone(), k, f * k));
                    }
                    f
                }
                None => {
                    println!("{label} / {name}: stands up to 2 g; the scan's fallbacks only");
                    1.0
                }
            };
            // Every amplitude of the search at which `auto` fell back to the engine (where the
            // hand-over can change anything), but those already above.
            let mut fell_back = 0;
            for run in &r.runs {
                let k = run.pga / f;
                if FACTORS.iter().any(|x| (x - k).abs() < 1e-9) {
                    continue;
                }
                if point(scene, &gm.scaled_to_pga(run.pga), Fallback::FromZero).model == "dda" {
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
            let a = point(scene, &scaled, Fallback::HandBack);
            let h = point(scene, &scaled, Fallback::HandOver);
            let b = point(scene, &scaled, Fallback::FromZero);
            let mut fine = scene.clone();
            fine.control.model = ModelChoice::Dda;
            fine.control.time_step = FINE_DT;
            let c = point(&fine, &scaled, Fallback::FromZero);
            (*label, name.clone(), *k, *pga, a, h, b, c)
        })
        .collect();
    println!("\n| column | record | PGA (× F) | m/s² | (c) engine 1e-4 s | (a) hand-back | (h) hand-over only | (b) from t = 0 | model (a) | wall (a) / (h) / (b) / (c), s |");
    println!("|---|---|---|---|---|---|---|---|---|---|");
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
    // Counts per variant (a, h, b): verdict = (c) over all points and where `auto` fell back
    // (as (h) saw it), peak within 5 % of (c) where (c) stands above 0.02 rad.
    let mut verdicts = [0usize; 3];
    let mut at_fallbacks = [0usize; 3];
    let mut peaks = [0usize; 3];
    let (mut n, mut np, mut fellback, mut fpn, mut handed_back) = (0, 0, 0, 0, 0);
    let within = |p: &Point, c: &Point| !p.fell && (p.peak / c.peak - 1.0).abs() <= 0.05;
    for (label, name, k, pga, a, h, b, c) in &rows {
        n += 1;
        let fb = h.model == "dda";
        fellback += usize::from(fb);
        let back = a.reason.contains("handed back");
        handed_back += usize::from(back);
        let stands = !c.fell && c.peak > 0.02;
        np += usize::from(stands);
        fpn += usize::from(stands && fb);
        for (i, p) in [a, h, b].into_iter().enumerate() {
            verdicts[i] += usize::from(p.fell == c.fell);
            at_fallbacks[i] += usize::from(fb && p.fell == c.fell);
            peaks[i] += usize::from(stands && within(p, c));
        }
        let c_text = if c.fell {
            "falls".to_string()
        } else {
            format!("stands {:.4}", c.peak)
        };
        println!(
            "| {label} | {name} | {k:.2} | {pga:.3} | {c_text} | {} | {} | {} | {}{} | {:.3} / {:.3} / {:.3} / {:.3} |",
            show(a, c),
            show(h, c),
            show(b, c),
            a.model,
            if back { " (handed back)" } else if fb { " (handed over)" } else { "" },
            a.wall,
            h.wall,
            b.wall,
            c.wall
        );
    }
    // Where (a) and (h) disagree: is the reference's verdict robust (the same at 0.97 and
    // 1.03 × the PGA, the condition for requiring a verdict)?
    for (label, name, k, pga, a, h, b, c) in &rows {
        if a.fell == h.fell && a.fell == b.fell {
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
                let p = point(&fine, &gm.scaled_to_pga(pga * f), Fallback::FromZero);
                if p.fell {
                    format!("{f} × PGA: falls")
                } else {
                    format!("{f} × PGA: stands {:.4}", p.peak)
                }
            })
            .collect();
        let v = |p: &Point| if p.fell { "falls" } else { "stands" };
        println!(
            "\n{label} / {name} at {k:.3} F ({pga:.3} m/s²): (a) {}, (h) {}, (b) {}, (c) {}; (c) at {}",
            v(a),
            v(h),
            v(b),
            v(c),
            side.join(", ")
        );
    }
    println!(
        "\npoints {n}; `auto` fell back to the engine at {fellback} ((a) handed back at {handed_back})"
    );
    println!("| | verdicts agree | at fallbacks | peaks within 5 % |");
    println!("|---|---|---|---|");
    for (i, what) in [
        "(a) hand-over + hand-back",
        "(h) hand-over only",
        "(b) from t = 0",
    ]
    .into_iter()
    .enumerate()
    {
        println!(
            "| {what} | {} / {n} | {} / {fellback} | {} / {np} |",
            verdicts[i], at_fallbacks[i], peaks[i]
        );
    }
    println!("(peaks where `auto` fell back: {fpn} of the {np})");
}
