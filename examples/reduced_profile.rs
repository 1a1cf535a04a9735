//! Profile of the default PGA search over the 0.4 × 1.2 m column (`examples/column.json`,
//! `toppled:column`, the CLI's default range 0.05–2 g, 40 scan points, tolerance 0.01 m/s²)
//! under every bundled record (docs/speed.md, "Reduced models on records"). The search runs
//! once with the scene's default `model: auto`; then each of its runs is replayed alone on
//! this thread, as the search ran it (early stop once the criterion is decided), and the
//! table lists per run: the amplitude, the verdict, the model that ran (`dda` where `auto`
//! fell back to the full engine, with the reason), the steps and the thread's CPU time.
//!
//! Run: `cargo run --release --example reduced_profile [-- RECORD-NAME-PART]`.
use ashlar::analysis::pga::search;
use ashlar::analysis::run::RunOptions;
use ashlar::motion::load_path;
use ashlar::scene::parse_scene;

#[path = "support/column_search.rs"]
mod column_search;
#[path = "support/thread_cpu.rs"]
mod thread_cpu;
use column_search::{records, replay, request};

fn main() {
    let only = std::env::args().nth(1);
    let scene = parse_scene(ashlar::presets::EXAMPLE_COLUMN).expect("scene");
    let req = request();
    for path in &records(only.as_deref()) {
        let name = path.file_stem().and_then(|s| s.to_str()).unwrap_or("?");
        let gm = load_path(path).expect("record");
        let r = search(&scene, &gm, &req, &RunOptions::default()).expect("search");
        println!(
            "\n### {name}: {} runs, lowest failing PGA {:?} m/s²\n",
            r.runs.len(),
            r.failing_pga
        );
        println!("| PGA (m/s²) | failed | model | steps | rejected | impacts | CPU (ms) | fallback reason |");
        println!("|---|---|---|---|---|---|---|---|");
        let (mut total, mut total_dda, mut n_dda, mut steps_red, mut n_red) =
            (0.0, 0.0, 0, 0u64, 0);
        for run in &r.runs {
            let (failed, s, c) = replay(&scene, &gm, &req, run.pga);
            total += c;
            let why = if s.model == "dda" {
                total_dda += c;
                n_dda += 1;
                s.model_reason
                    .split("not represent (")
                    .nth(1)
                    .and_then(|w| w.split(" at t =").next())
                    .unwrap_or("")
                    .to_string()
            } else {
                steps_red += s.steps;
                n_red += 1;
                String::new()
            };
            println!(
                "| {:.4} | {failed} | {} | {} | {} | {} | {:.2} | {why} |",
                run.pga,
                s.model,
                s.steps,
                s.diagnostics.time_step_cuts,
                s.diagnostics.impacts.unwrap_or(0),
                1e3 * c
            );
        }
        println!(
            "\n{name}: {} runs, CPU {:.1} ms in all; {n_red} reduced ({steps_red} steps, {:.1} ms), {n_dda} fell back to dda ({:.1} ms)",
            r.runs.len(),
            1e3 * total,
            1e3 * (total - total_dda),
            1e3 * total_dda
        );
    }
}
