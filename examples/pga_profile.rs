//! Profile of a PGA search's runs (docs/speed.md, "The drum column's search"): for each
//! amplitude, the full engine's run as `pga` runs it (same loop as `analysis::run`, no frames),
//! split at the end of the record and at the moment the criterion's block is past 30°, with
//! steps, Δt cuts, open–close solves per step, CPU seconds and the engine's stage profile.
//!
//! `cargo run --release --example pga_profile -- SCENE.json RECORD BLOCK PGA[,PGA…] [--no-stop]`
//! (RECORD: a path; PGA in m/s²). Without `--no-stop` a run ends as `pga` ends it (the block
//! past 60°, or settled after the record); with it, as `ashlar run` ends it. Single-threaded, so
//! its CPU seconds are the run's own.
use ashlar::analysis::run::duration;
use ashlar::analysis::run_end::{self, RunEndParams, SettleWatch};
use ashlar::simulation::{SimParams, Simulation};
use std::time::Duration;

/// CPU seconds of this process (user time); 0 where `getrusage` is not available.
#[cfg(unix)]
fn cpu() -> f64 {
    nix::sys::resource::getrusage(nix::sys::resource::UsageWho::RUSAGE_SELF)
        .map(|u| {
            let t = u.user_time();
            t.tv_sec() as f64 + t.tv_usec() as f64 * 1e-6
        })
        .unwrap_or(0.0)
}

#[cfg(not(unix))]
fn cpu() -> f64 {
    0.0
}

/// Counters at a moment of the run.
#[derive(Clone, Copy, Default)]
struct Mark {
    time: f64,
    steps: u64,
    cuts: u64,
    solves: u64,
    cpu: f64,
}

fn mark(sim: &Simulation, cpu0: f64) -> Mark {
    Mark {
        time: sim.time(),
        steps: sim.stats().steps,
        cuts: sim.stats().time_step_cuts,
        solves: sim.stats().open_close_iterations,
        cpu: cpu() - cpu0,
    }
}

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    if args.len() < 4 {
        eprintln!("usage: pga_profile SCENE.json RECORD BLOCK PGA[,PGA…] [--no-stop]");
        std::process::exit(2);
    }
    let scene = ashlar::scene::parse_scene(&std::fs::read_to_string(&args[0]).expect("scene"))
        .expect("scene parses");
    let record = ashlar::motion::load_path(std::path::Path::new(&args[1])).expect("record");
    let block = scene.block_index(&args[2]).expect("block id");
    let pgas: Vec<f64> = args[3]
        .split(',')
        .map(|s| s.parse().expect("PGA"))
        .collect();
    let stop = !args.iter().any(|a| a == "--no-stop");
    let record_end = record.duration().unwrap_or(0.0);
    println!(
        "pga m/s2 | outcome | end s | steps | cuts | solves/step | cpu s | after record: s, steps, cpu s | \
         block past 30° at s | after that: steps, cpu s | detect/assemble/solve/integrate cpu s"
    );
    let mut total = Mark::default();
    for pga in pgas {
        let gm = record.scaled_to_pga(pga);
        let cpu0 = cpu();
        let dur = duration(&scene, &gm).expect("duration");
        let end = RunEndParams::default();
        let cap = run_end::cap(dur, &gm, &end);
        let floor = run_end::retirement_floor(&scene);
        let mut sim = Simulation::new(&scene, &gm, SimParams::default());
        let mut watch = SettleWatch::default();
        let interval = scene.control.output_interval;
        let mut frame_index = 0u64;
        let (mut at_record, mut at_fallen) = (None, None);
        let mut outcome = "survived";
        // `PGA_PROFILE_TIMELINE=S`: print the counters every S seconds of simulated time.
        let every: Option<f64> = std::env::var("PGA_PROFILE_TIMELINE")
            .ok()
            .and_then(|s| s.parse().ok());
        let mut next_line = every.unwrap_or(f64::INFINITY);
        while sim.time() < cap - 1e-12 {
            let next =
                ((frame_index + 1) as f64 * interval).min(run_end::horizon(sim.time(), dur, cap));
            if let Err(e) = sim.step(next - sim.time()) {
                outcome = "error";
                eprintln!("{pga}: {e}");
                break;
            }
            run_end::retire_fallen(&mut sim, floor);
            let settled = watch.update(
                sim.time(),
                run_end::all_quiet(&sim, &end),
                end.settle_window,
            );
            if at_record.is_none() && sim.time() >= record_end {
                at_record = Some(mark(&sim, cpu0));
            }
            let rot = sim.geoms()[block].rotation.abs();
            if sim.time() >= next_line {
                let m = mark(&sim, cpu0);
                println!(
                    "  t {:.1} s: {} steps, {} cuts, {:.2} solves/step so far, {:.2} cpu s, rotation {:.4}",
                    m.time,
                    m.steps,
                    m.cuts,
                    m.solves as f64 / m.steps.max(1) as f64,
                    m.cpu,
                    rot
                );
                next_line += every.unwrap_or(f64::INFINITY);
            }
            if at_fallen.is_none() && rot > 30f64.to_radians() {
                at_fallen = Some(mark(&sim, cpu0));
            }
            if sim.time() >= next - 1e-9 * interval {
                frame_index += 1;
                if run_end::may_end(sim.time(), dur, settled) {
                    break;
                }
            }
            if stop && rot > std::f64::consts::FRAC_PI_3 {
                break;
            }
        }
        if sim.geoms()[block].rotation.abs() > 30f64.to_radians() {
            outcome = "fell";
        }
        let m = mark(&sim, cpu0);
        let after = |a: Option<Mark>| match a {
            Some(a) => format!(
                "{:.2}, {}, {:.2}",
                m.time - a.time,
                m.steps - a.steps,
                m.cpu - a.cpu
            ),
            None => "-".into(),
        };
        let p = sim.profile();
        let s = |d: Duration| d.as_secs_f64();
        println!(
            "{pga:.4} | {outcome} | {:.2} | {} | {} | {:.2} | {:.2} | {} | {} | {} | {:.2}/{:.2}/{:.2}/{:.2}",
            m.time,
            m.steps,
            m.cuts,
            m.solves as f64 / m.steps.max(1) as f64,
            m.cpu,
            after(at_record),
            at_fallen.map_or("-".into(), |a| format!("{:.2}", a.time)),
            at_fallen.map_or("-".into(), |a| format!(
                "{}, {:.2}",
                m.steps - a.steps,
                m.cpu - a.cpu
            )),
            s(p.detect),
            s(p.assemble),
            s(p.solve),
            s(p.integrate),
        );
        let fallen: Vec<String> = (0..sim.geoms().len())
            .filter(|&b| sim.dofs().free_index[b].is_some())
            .filter(|&b| sim.retired()[b] || sim.geoms()[b].rotation.abs() > 30f64.to_radians())
            .map(|b| {
                let g = &sim.geoms()[b];
                format!(
                    "{}{} ({:.0}°, dy {:.2} m)",
                    sim.scene().blocks[b].id,
                    if sim.retired()[b] { " retired" } else { "" },
                    g.rotation.to_degrees(),
                    g.centroid.y - g.initial_centroid.y
                )
            })
            .collect();
        if !fallen.is_empty() {
            println!("  fallen at the end: {}", fallen.join(", "));
        }
        total.steps += m.steps;
        total.cuts += m.cuts;
        total.cpu += m.cpu;
    }
    println!(
        "total: {} steps, {} cuts, {:.2} cpu s",
        total.steps, total.cuts, total.cpu
    );
}
