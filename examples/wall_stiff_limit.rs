//! The accuracy study's masonry wall (docs/accuracy-vs-speed.md) under both contact solvers:
//! the penalty method at growing stiffness k and the dual solver at growing tightness, each
//! compared with the penalty runs at k = 1e14 N/m (within 0.05 % of the stiff limit) at
//! Δt = 1e-4 and 1e-3 s. Prints the table of docs/dual.md, "The wall".
//!
//! `cargo run --release --example wall_stiff_limit [-- DURATION_S]` (default 8 s, as the study).
use ashlar::analysis::run::{run, RunOptions};
use ashlar::analysis::study::{wall_record, GROUND_MOTIONS_DIR};
use ashlar::presets::study_wall_json;
use ashlar::record::Frame;
use ashlar::scene::scene_from_value;
use serde_json::json;
use std::sync::Mutex;

/// One run's settings: solver, penalty stiffness (N/m; `None`: "auto"), Δt (s, also g2), dual
/// tolerance (× half block size; `None`: the default).
type Setting = (&'static str, Option<f64>, f64, Option<f64>);

/// Top block's horizontal displacement history (t, x) and the run's wall time.
fn history(s: Setting, duration: f64) -> Result<(Vec<(f64, f64)>, f64), String> {
    let (solver, k, dt, tol) = s;
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join(GROUND_MOTIONS_DIR);
    let gm = wall_record(&dir).map_err(|e| e.to_string())?;
    let mut v = study_wall_json();
    let top = v["blocks"].as_array().map_or(0, |b| b.len() - 1);
    v["control"] = json!({ "duration": duration, "time_step": dt,
        "max_displacement_ratio": dt, "contact_solver": solver, "model": "dda",
        "max_steps": 200_000_000u64 });
    if let Some(k) = k {
        v["control"]["penalty_stiffness"] = json!(k);
    }
    if let Some(t) = tol {
        v["control"]["dual_tolerance"] = json!(t);
    }
    let scene = scene_from_value(&v).map_err(|e| e.to_string())?;
    let frames = Mutex::new(Vec::new());
    let record = |f: &Frame| {
        if let Ok(mut fr) = frames.lock() {
            fr.push((f.time, f.blocks[top].x));
        }
    };
    let start = std::time::Instant::now();
    let opts = RunOptions {
        on_frame: Some(&record),
        ..Default::default()
    };
    let out = run(&scene, &gm, &opts).map_err(|e| e.to_string())?;
    if !out.summary.completed {
        return Err(format!("{solver}: {:?}", out.summary.stopped_reason));
    }
    let frames = frames.into_inner().map_err(|e| e.to_string())?;
    Ok((frames, start.elapsed().as_secs_f64()))
}

/// Largest |a − b| over the common frames, relative to the peak |b|.
fn error(a: &[(f64, f64)], b: &[(f64, f64)]) -> f64 {
    let peak = b.iter().fold(0.0f64, |m, p| m.max(p.1.abs()));
    let worst = a
        .iter()
        .zip(b)
        .fold(0.0f64, |m, (p, q)| m.max((p.1 - q.1).abs()));
    worst / peak
}

fn main() -> Result<(), String> {
    let duration: f64 = match std::env::args().nth(1) {
        Some(s) => s.parse().map_err(|e| format!("duration {s}: {e}"))?,
        None => 8.0,
    };
    let settings: [Setting; 12] = [
        ("penalty", Some(1e14), 1e-4, None),
        ("penalty", Some(1e14), 1e-3, None),
        ("penalty", None, 1e-4, None),
        ("penalty", Some(1e12), 1e-4, None),
        ("penalty", Some(1e16), 1e-3, None),
        ("dual", None, 1e-4, None),
        ("dual", None, 1e-4, Some(1e-11)),
        ("dual", None, 1e-4, Some(1e-13)),
        ("dual", None, 1e-3, None),
        ("dual", None, 1e-3, Some(1e-11)),
        ("dual", None, 1e-3, Some(1e-13)),
        ("penalty", None, 1e-3, None),
    ];
    let mut runs = Vec::new();
    for s in settings {
        runs.push((s, history(s, duration)?));
    }
    let (fine, coarse) = (&runs[0].1 .0, &runs[1].1 .0);
    println!("| solver | k (N/m) | Δt (s) | dual tolerance | peak x (m) | vs stiff, Δt = 1e-4 | vs stiff, Δt = 1e-3 | wall (s) |");
    println!("|---|---|---|---|---|---|---|---|");
    for ((solver, k, dt, tol), (h, wall)) in &runs {
        let peak = h.iter().fold(0.0f64, |m, p| m.max(p.1.abs()));
        let k = k.map_or("auto".into(), |k| format!("{k:.0e}"));
        let k = if *solver == "dual" { "—".into() } else { k };
        let tol = match (solver, tol) {
            (&"dual", None) => "1e-9 (default)".into(),
            (_, Some(t)) => format!("{t:.0e}"),
            _ => "—".into(),
        };
        println!(
            "| {solver} | {k} | {dt:.0e} | {tol} | {peak:.3e} | {:.3} % | {:.3} % | {wall:.1} |",
            100.0 * error(h, fine),
            100.0 * error(h, coarse)
        );
    }
    Ok(())
}
