//! Cost of the reduced rocking model against the full engine on the bundled records
//! (docs/accuracy-vs-speed.md, "Reduced models on records"), measured in one run of this program: `examples/column.json` (0.4 × 1.2 m column) under
//! every record in `data/ground-motions/` scaled to 0.3, 0.5, 0.7 and 1.0 g, once with the
//! reduced rocking model (`"model": "rocking"`) and once with the full engine (`"model": "dda"`,
//! the scene's controls); and which model the default (`auto`) runs there (it falls back to the
//! full engine when the run leaves the reduced model's assumptions, e.g. the pivot slips).
//! Prints, per record and PGA, the steps and wall time (median of `REPS` runs; the engine's
//! single run), the ratio, and the peak rotations; then the wall time of a default PGA search
//! (`toppled:column`, 0.05–2 g, tolerance 0.01 m/s², 40 scan points) with the rocking model
//! (median of `REPS`) and with `auto` (one search), on the default thread pool.
//!
//! Run: `cargo run --release --example reduced_speed [-- REPS]` (REPS defaults to 5; the
//! ratios are between two models of the same build, so the debug profile measures them too).
use ashlar::analysis::pga::{search, Combine, Criterion, PgaRequest};
use ashlar::analysis::run::{run, RunOptions, Summary};
use ashlar::motion::{load_path, GroundMotion};
use ashlar::scene::{parse_scene, ModelChoice, Scene};
use std::time::Instant;

const G: f64 = 9.80665;

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

fn timed_run(scene: &Scene, gm: &GroundMotion, reps: usize) -> (f64, Summary) {
    let mut last = None;
    let wall = median(
        (0..reps)
            .map(|_| {
                let t = Instant::now();
                let out = run(scene, gm, &RunOptions::default()).expect("run");
                let dt = t.elapsed().as_secs_f64();
                last = Some(out.summary);
                dt
            })
            .collect(),
    );
    (wall, last.expect("at least one repetition"))
}

fn main() {
    let reps: usize = std::env::args()
        .nth(1)
        .and_then(|a| a.parse().ok())
        .unwrap_or(5)
        .max(1);
    let auto = parse_scene(ashlar::presets::EXAMPLE_COLUMN).expect("scene");
    let mut dda = auto.clone();
    dda.control.model = ModelChoice::Dda;
    let mut rocking = auto.clone();
    rocking.control.model = ModelChoice::Rocking;
    let mut records: Vec<_> = std::fs::read_dir(ashlar::presets::records_dir())
        .expect("records")
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| matches!(p.extension().and_then(|e| e.to_str()), Some("at2" | "csv")))
        .collect();
    records.sort();
    println!("| record | PGA | `auto` runs | rocking steps | rocking wall (ms) | dda steps | dda wall (ms) | dda / rocking | peak θ rocking / dda (rad) |");
    println!("|---|---|---|---|---|---|---|---|---|");
    let mut worst = f64::INFINITY;
    let mut searches = Vec::new();
    for path in &records {
        let name = path.file_stem().and_then(|s| s.to_str()).unwrap_or("?");
        let gm = load_path(path).expect("record");
        for pga in [0.3, 0.5, 0.7, 1.0] {
            let scaled = gm.scaled_to_pga(pga * G);
            let (_, sa) = timed_run(&auto, &scaled, 1);
            let (wr, sr) = timed_run(&rocking, &scaled, reps);
            let (wd, sd) = timed_run(&dda, &scaled, 1);
            let ratio = wd / wr;
            worst = worst.min(ratio);
            println!(
                "| {name} | {pga} g | {} | {} | {:.2} | {} | {:.0} | {:.0}× | {:.4} / {:.4} |",
                sa.model,
                sr.steps,
                1e3 * wr,
                sd.steps,
                1e3 * wd,
                ratio,
                sr.blocks[0].max_rotation,
                sd.blocks[0].max_rotation
            );
        }
        let req = PgaRequest {
            criteria: vec![Criterion::parse("toppled:column").expect("criterion")],
            combine: Combine::All,
            min: 0.05 * G,
            max: 2.0 * G,
            tolerance: 0.01,
            scan_points: 40,
        };
        let mut last = None;
        let wall = median(
            (0..reps)
                .map(|_| {
                    let t = Instant::now();
                    let r = search(&rocking, &gm, &req, &RunOptions::default()).expect("search");
                    let dt = t.elapsed().as_secs_f64();
                    last = Some(r);
                    dt
                })
                .collect(),
        );
        let r = last.expect("a search");
        let t = Instant::now();
        let ra = search(&auto, &gm, &req, &RunOptions::default()).expect("search");
        let wa = t.elapsed().as_secs_f64();
        searches.push((name.to_string(), wall, r, wa, ra));
    }
    println!("\nsmallest dda / rocking wall-time ratio: {worst:.1}×\n");
    println!(
        "PGA search, {} threads (rocking: median of {reps}; auto: one search):\n",
        rayon::current_num_threads()
    );
    println!("| record | rocking: wall (ms) | runs | lowest failing PGA (m/s²) | monotonic | auto: wall (ms) | runs | lowest failing PGA (m/s²) |");
    println!("|---|---|---|---|---|---|---|---|");
    let show = |f: Option<f64>| {
        f.map(|f| format!("{f:.3}"))
            .unwrap_or_else(|| "none".into())
    };
    for (name, wall, r, wa, ra) in &searches {
        println!(
            "| {name} | {:.1} | {} | {} | {} | {:.0} | {} | {} |",
            1e3 * wall,
            r.runs.len(),
            show(r.failing_pga),
            r.monotonic,
            1e3 * wa,
            ra.runs.len(),
            show(ra.failing_pga),
        );
    }
}
