//! Cost of the reduced rocking model against the full engine on the bundled records
//! (docs/speed.md, "Reduced models on records"), measured in one run of this program:
//! `examples/column.json` (0.4 × 1.2 m column) under every record in `data/ground-motions/`
//! scaled to 0.3, 0.5, 0.7 and 1.0 g, once with the reduced rocking model (`"model":
//! "rocking"`) and once with the full engine (`"model": "dda"`, the scene's controls), each a
//! full run as `ashlar run` makes it, on this thread. Times are wall times, the minimum of
//! `REPS` repetitions (the run least disturbed by the machine's other processes). Prints per record and PGA the steps, the times and their
//! ratio, and which model the default (`auto`) runs there (it falls back to the full engine
//! when the run leaves the reduced model's assumptions, e.g. the pivot slips).
//!
//! Then, per record, the default PGA search (`toppled:column`, 0.05–2 g, 40 scan points,
//! tolerance 0.01 m/s², the CLI's defaults): its wall time on the default thread pool (min of
//! `REPS`) with `auto` and forced to rocking; and, replaying the `auto` search's runs one by
//! one on this thread, how many of them fell back to the full engine and the CPU time of the
//! reduced runs and of the fallbacks (sums of tick-counted CPU time over the search's runs).
//!
//! Run: `cargo run --release --example reduced_speed [-- REPS]` (REPS defaults to 5).
use ashlar::analysis::pga::{evaluate_with_summary, search, Criterion, PgaRequest, PgaResult};
use ashlar::analysis::run::{run, RunOptions, Summary};
use ashlar::motion::{load_path, GroundMotion};
use ashlar::scene::{parse_scene, ModelChoice, Scene};
use std::time::Instant;

const G: f64 = 9.80665;

#[path = "support/thread_cpu.rs"]
mod thread_cpu;
use thread_cpu::cpu;

/// Minimum over `reps` of the wall time of one full run on this thread, and the run's summary
/// (the thread's CPU count moves in 4 ms ticks on this kernel, too coarse for a 1 ms run; the
/// minimum of several wall times is the run undisturbed by the machine's other processes).
fn timed_run(scene: &Scene, gm: &GroundMotion, reps: usize) -> (f64, Summary) {
    let mut best = f64::INFINITY;
    let mut last = None;
    for _ in 0..reps {
        let t = Instant::now();
        let out = run(scene, gm, &RunOptions::default()).expect("run");
        best = best.min(t.elapsed().as_secs_f64());
        last = Some(out.summary);
    }
    (best, last.expect("at least one repetition"))
}

/// Minimum over `reps` of a search's wall time on the default pool, and its result.
fn timed_search(
    scene: &Scene,
    gm: &GroundMotion,
    req: &PgaRequest,
    reps: usize,
) -> (f64, PgaResult) {
    let mut best = f64::INFINITY;
    let mut last = None;
    for _ in 0..reps {
        let t = Instant::now();
        let r = search(scene, gm, req, &RunOptions::default()).expect("search");
        best = best.min(t.elapsed().as_secs_f64());
        last = Some(r);
    }
    (best, last.expect("at least one repetition"))
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
    let req = PgaRequest::cli_default(vec![Criterion::parse("toppled:column").expect("criterion")]);
    println!("Full runs on one thread, wall time, min of {reps}:\n");
    println!("| record | PGA | `auto` runs | rocking steps | rocking (ms) | dda steps | dda (ms) | dda / rocking | peak θ rocking / dda (rad) |");
    println!("|---|---|---|---|---|---|---|---|---|");
    let mut per_record = Vec::new();
    let mut searches = Vec::new();
    for path in &records {
        let name = path.file_stem().and_then(|s| s.to_str()).unwrap_or("?");
        let gm = load_path(path).expect("record");
        let mut worst = f64::INFINITY;
        let (mut sum_r, mut sum_d) = (0.0, 0.0);
        for pga in [0.3, 0.5, 0.7, 1.0] {
            let scaled = gm.scaled_to_pga(pga * G);
            let (_, sa) = timed_run(&auto, &scaled, 1);
            let (wr, sr) = timed_run(&rocking, &scaled, reps);
            let (wd, sd) = timed_run(&dda, &scaled, reps.min(3));
            let ratio = wd / wr;
            worst = worst.min(ratio);
            sum_r += wr;
            sum_d += wd;
            println!(
                "| {name} | {pga} g | {} | {} | {:.3} | {} | {:.1} | {:.0}× | {:.4} / {:.4} |",
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
        per_record.push((name.to_string(), worst, sum_d / sum_r));
        let (wa, ra) = timed_search(&auto, &gm, &req, reps);
        let (wr, rr) = timed_search(&rocking, &gm, &req, reps);
        // The auto search's runs replayed one at a time: which model each ran, its CPU time.
        let (mut n_dda, mut cpu_red, mut cpu_dda, mut steps_red) = (0, 0.0, 0.0, 0u64);
        let mut reasons = std::collections::BTreeSet::new();
        for r in &ra.runs {
            let c = cpu();
            let (_, s) = evaluate_with_summary(&auto, &gm, &req.criteria, req.combine, r.pga, None)
                .expect("run");
            let c = cpu() - c;
            if s.model == "dda" {
                n_dda += 1;
                cpu_dda += c;
                if let Some(w) = s
                    .model_reason
                    .split("not represent (")
                    .nth(1)
                    .and_then(|w| w.split(" at t =").next())
                {
                    reasons.insert(w.to_string());
                }
            } else {
                cpu_red += c;
                steps_red += s.steps;
            }
        }
        searches.push((
            name.to_string(),
            wa,
            ra,
            wr,
            rr,
            (n_dda, cpu_red, cpu_dda, steps_red, reasons),
        ));
    }
    println!("\nPer record (the four PGAs): smallest and overall dda / rocking time ratio:\n");
    println!("| record | smallest ratio | total dda / total rocking |");
    println!("|---|---|---|");
    for (name, worst, all) in &per_record {
        println!("| {name} | {worst:.1}× | {all:.1}× |");
    }
    println!(
        "\nPGA search, {} threads, wall time min of {reps}; the auto search's runs replayed on one thread:\n",
        rayon::current_num_threads()
    );
    println!("| record | auto: wall (ms) | runs | lowest failing PGA (m/s²) | fell back to dda | CPU of reduced runs (ms, steps) | CPU of fallbacks (ms) | rocking: wall (ms) | runs | lowest failing PGA (m/s²) |");
    println!("|---|---|---|---|---|---|---|---|---|---|");
    let show = |f: Option<f64>| {
        f.map(|f| format!("{f:.3}"))
            .unwrap_or_else(|| "none".into())
    };
    let mut reasons_all = std::collections::BTreeSet::new();
    for (name, wa, ra, wr, rr, (n_dda, cpu_red, cpu_dda, steps_red, reasons)) in &searches {
        println!(
            "| {name} | {:.1} | {} | {} | {n_dda} | {:.1} ({steps_red}) | {:.1} | {:.1} | {} | {} |",
            1e3 * wa,
            ra.runs.len(),
            show(ra.failing_pga),
            1e3 * cpu_red,
            1e3 * cpu_dda,
            1e3 * wr,
            rr.runs.len(),
            show(rr.failing_pga),
        );
        reasons_all.extend(reasons.iter().cloned());
    }
    println!("\nWhy `auto` fell back: {reasons_all:?}");
}
