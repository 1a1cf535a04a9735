//! Profile of the engine fallbacks of the default PGA search over the 0.4 × 1.2 m column
//! (`examples/column.json`, `toppled:column`, the CLI's defaults; docs/speed.md, "Session 35"):
//! the search runs once per record, then every run at which `auto` fell back to the full
//! engine is replayed alone on this thread as the search ran it (early stop included), and the
//! table lists per fallback: the amplitude, the verdict, the hand-over time t₀ and the
//! column's rotation and angular velocity there (from `model_reason`), the engine's simulated
//! span (end − t₀), its steps (the summary's, less the reduced part's is not separable: both
//! are listed together), Δt cuts, the smallest step and the thread's CPU.
//!
//! With `GROWTH CUT` after the record part, each fallback is replayed a second time with the
//! engine's `SimParams::growth` and `cut_factor` set to them (a what-if: the search itself keeps
//! the defaults), and the table adds that replay's verdict, end time, steps and CPU.
//!
//! Run: `cargo run --release --example fallback_profile [-- RECORD-NAME-PART [GROWTH CUT]]`.
use ashlar::analysis::pga::{evaluate_with_summary, search, Criterion, PgaRequest};
use ashlar::analysis::run::{self as engine_run, RunOptions, Tracker};
use ashlar::motion::load_path;
use ashlar::scene::parse_scene;
use ashlar::simulation::SimParams;

#[path = "support/thread_cpu.rs"]
mod thread_cpu;
use thread_cpu::cpu;

/// The number after `key` in `text` (e.g. "from t = 6.4850 s": key "from t = ").
fn after(text: &str, key: &str) -> f64 {
    text.split(key)
        .nth(1)
        .and_then(|s| s.split([' ', ',', ')']).next())
        .and_then(|s| s.parse().ok())
        .unwrap_or(f64::NAN)
}

/// `FALLBACK_ENGINE=PGA` (with the record part as the first argument): the engine from t = 0
/// on that record at PGA m/s², stepped as `run_dda` steps it; prints its steps and the step
/// refusals by reason (contact solve not converged, block moved beyond the step limit, a
/// contact overshot, a step-control bound) up to the moment the column first passes 0.6 rad
/// (about where the column searches' fallbacks start) and from there to 60°.
fn engine_refusals(record: &std::path::Path, pga: f64) {
    use ashlar::analysis::run_end;
    let scene = parse_scene(ashlar::presets::EXAMPLE_COLUMN).expect("scene");
    let gm = load_path(record).expect("record").scaled_to_pga(pga);
    let block = scene.block_index("column").expect("column");
    let mut sim = ashlar::simulation::Simulation::new(&scene, &gm, SimParams::default());
    let interval = scene.control.output_interval;
    let mut frame = 0u64;
    let mut at = None;
    let mut min_dt = f64::INFINITY;
    let mut last0 = [[0u64; 2]; 7];
    while sim.time() < 60.0 {
        let next = (frame + 1) as f64 * interval;
        let t = sim.time();
        sim.step(next - t).expect("step");
        if at.is_some() {
            min_dt = min_dt.min(sim.time() - t);
        }
        if sim.time() >= next - 1e-9 * interval {
            frame += 1;
        }
        let rot = sim.geoms()[block].rotation.abs();
        if at.is_none() && rot > 0.6 {
            at = Some((sim.time(), sim.stats().steps, sim.refusals()));
            last0 = sim.changes().last_kind;
        }
        if rot > std::f64::consts::FRAC_PI_3 {
            break;
        }
    }
    let _ = run_end::RunEndParams::default();
    let last1 = sim.changes().last_kind;
    for (k, name) in ashlar::solve::open_close::CHANGE_KINDS.iter().enumerate() {
        let d = [last1[k][0] - last0[k][0], last1[k][1] - last0[k][1]];
        if d != [0, 0] {
            println!(
                "  unconverged after 0.6 rad, {name}: bed {}, head {}",
                d[0], d[1]
            );
        }
    }
    let (t0, s0, r0) = at.unwrap_or((0.0, 0, [0; 4]));
    let r1 = sim.refusals();
    println!(
        "engine from t = 0 at {pga} m/s²: past 0.6 rad at {t0:.4} s after {s0} steps (refusals {r0:?}); past 60° at {:.4} s after {} steps; from 0.6 rad: {} steps, refusals {:?}, shortest step {min_dt:.2e} s",
        sim.time(),
        sim.stats().steps,
        sim.stats().steps - s0,
        [r1[0] - r0[0], r1[1] - r0[1], r1[2] - r0[2], r1[3] - r0[3]]
    );
}

fn main() {
    if let Ok(p) = std::env::var("FALLBACK_ENGINE") {
        let part = std::env::args().nth(1).expect("record part");
        let path = std::fs::read_dir(ashlar::presets::records_dir())
            .expect("records")
            .filter_map(|e| e.ok().map(|e| e.path()))
            .find(|x| x.to_string_lossy().contains(&part))
            .expect("record");
        engine_refusals(&path, p.parse().expect("PGA"));
        return;
    }
    let args: Vec<String> = std::env::args().skip(1).collect();
    let only = args.first().filter(|a| !a.is_empty()).cloned();
    let what_if = match (args.get(1), args.get(2)) {
        (Some(g), Some(c)) => Some(SimParams {
            growth: g.parse().expect("GROWTH"),
            cut_factor: c.parse().expect("CUT"),
            ..Default::default()
        }),
        _ => None,
    };
    let (mut all_cpu, mut all_cpu_if, mut all_steps, mut all_steps_if) = (0.0, 0.0, 0u64, 0u64);
    let scene = parse_scene(ashlar::presets::EXAMPLE_COLUMN).expect("scene");
    let mut records: Vec<_> = std::fs::read_dir(ashlar::presets::records_dir())
        .expect("records")
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| matches!(p.extension().and_then(|e| e.to_str()), Some("at2" | "csv")))
        .filter(|p| {
            only.as_deref()
                .is_none_or(|o| p.to_string_lossy().contains(o))
        })
        .collect();
    records.sort();
    let req = PgaRequest::cli_default(vec![Criterion::parse("toppled:column").expect("criterion")]);
    println!("| record | PGA (m/s²) | failed | t₀ (s) | θ₀ (rad) | ω₀ (rad/s) | engine span (s) | end θ (rad) | steps | cuts | min Δt (s) | CPU (ms) | what-if: failed, end (s), steps, CPU (ms) |");
    println!("|---|---|---|---|---|---|---|---|---|---|---|---|---|");
    for path in &records {
        let name = path.file_stem().and_then(|s| s.to_str()).unwrap_or("?");
        let gm = load_path(path).expect("record");
        let r = search(&scene, &gm, &req, &RunOptions::default()).expect("search");
        let (mut n, mut span, mut steps, mut cpu_all) = (0, 0.0, 0u64, 0.0);
        for run in &r.runs {
            let c0 = cpu();
            let (failed, s) =
                evaluate_with_summary(&scene, &gm, &req.criteria, req.combine, run.pga, None)
                    .expect("run");
            let c = cpu() - c0;
            if s.model != "dda" {
                continue;
            }
            let t0 = after(&s.model_reason, "from t = ");
            let th0 = after(&s.model_reason, "(rotation ");
            let w0 = after(&s.model_reason, "angular velocity ");
            let end = s
                .blocks
                .iter()
                .find(|b| b.id == "column")
                .map_or(f64::NAN, |b| b.final_rotation);
            let alt = what_if.map(|p| {
                let gm1 = gm.scaled_to_pga(run.pga);
                let stop = |tr: &Tracker| {
                    tr.index_of("column")
                        .is_some_and(|k| tr.final_rotation[k].abs() > std::f64::consts::FRAC_PI_3)
                };
                let opts = RunOptions {
                    stop_when: Some(&stop),
                    no_trajectory: true,
                    sim_params: Some(p),
                    ..Default::default()
                };
                let c0 = cpu();
                let o = engine_run::run(&scene, &gm1, &opts).expect("what-if run");
                let c = cpu() - c0;
                all_cpu_if += c;
                all_steps_if += o.summary.steps;
                let b = o
                    .summary
                    .blocks
                    .iter()
                    .find(|b| b.id == "column")
                    .expect("column");
                format!(
                    "{}, {:.4}, {}, {:.2}",
                    b.final_rotation.abs() > 30f64.to_radians(),
                    o.summary.simulated_time,
                    o.summary.steps,
                    1e3 * c
                )
            });
            all_cpu += c;
            all_steps += s.steps;
            n += 1;
            span += s.simulated_time - t0;
            steps += s.steps;
            cpu_all += c;
            println!(
                "| {name} | {:.4} | {failed} | {t0:.4} | {th0:.4} | {w0:.4} | {:.4} | {end:.4} | {} | {} | {:.2e} | {:.2} | {} |",
                run.pga,
                s.simulated_time - t0,
                s.steps,
                s.diagnostics.time_step_cuts,
                s.diagnostics.min_time_step.unwrap_or(f64::NAN),
                1e3 * c,
                alt.unwrap_or_default()
            );
        }
        println!(
            "| **{name}** | {} runs, lowest failing {:?} | | | | | **{span:.3}** | | **{steps}** | | | **{:.1}** ({n} fallbacks) |",
            r.runs.len(),
            r.failing_pga,
            1e3 * cpu_all
        );
    }
    if what_if.is_some() {
        println!(
            "\nall fallbacks: steps {all_steps} → {all_steps_if}, CPU {:.1} → {:.1} ms",
            1e3 * all_cpu,
            1e3 * all_cpu_if
        );
    }
}
