//! Where a PGA search's run spends its steps: one run of a scene file under a record scaled to
//! a PGA, with the search's options (`stop_when` the criterion `toppled:BLOCK` decided,
//! `end_when_still`), and one line per window of simulated time (`--window`, s, default 1; the
//! last, partial window too): wall time, steps, Δt cuts by refusal (unconverged loop,
//! displacement limit, overshot contact, accuracy bound: impact / local error), open–close
//! solves, impacts, located steps, the smallest Δt, the watched block's rotation (at the
//! window's end and its largest magnitude in it), and the blocks in motion (speed above
//! `--moving` m/s, default 0.05; the fastest named). `--changes`: a second line a window with
//! the state changes left after the last iteration of every loop that stopped unconverged
//! (refused, or taken at the floor), by kind and joint (`ChangeCounts::last_kind`). docs/pga.md,
//! "The wall's search at its threshold (session 41)" and "(session 42)":
//! `cargo run --release --example wall_threshold -- SCENE RECORD PGA_M_S2 BLOCK [--window S]
//! [--changes]`.
use ashlar::analysis::pga::{evaluate_with_summary, Combine, Criterion};
use ashlar::analysis::run::{run, RunOptions, Tracker};
use ashlar::contact::Mobility;
use ashlar::simulation::Simulation;
use ashlar::solve::open_close::CHANGE_KINDS;
use std::sync::Mutex;
use std::time::Instant;

/// Counters at the start of the current window.
#[derive(Default)]
struct Window {
    start: f64,
    wall: f64,
    steps: u64,
    cuts: u64,
    refusals: [u64; 4],
    solves: u64,
    impacts: u64,
    located: u64,
    taken_unconverged: u64,
    min_dt: f64,
    max_moving: usize,
    /// The watched block's largest |rotation| in the window, rad.
    max_rotation: f64,
    last_kind: [[u64; 2]; 7],
}

impl Window {
    fn at(sim: &Simulation, wall: f64) -> Self {
        let s = sim.stats();
        Self {
            start: sim.time(),
            wall,
            steps: s.steps,
            cuts: s.time_step_cuts,
            refusals: sim.refusals(),
            solves: s.open_close_iterations,
            impacts: s.impacts,
            located: s.located_steps,
            taken_unconverged: s.unconverged_taken,
            min_dt: f64::INFINITY,
            max_moving: 0,
            max_rotation: 0.0,
            last_kind: sim.changes().last_kind,
        }
    }
}

/// The changes left after failing loops' last iterations since `before`, as
/// "kind bed/head" pairs (kinds with none left out).
fn last_changes(sim: &Simulation, before: &[[u64; 2]; 7]) -> String {
    let now = sim.changes().last_kind;
    let mut out = Vec::new();
    for (k, name) in CHANGE_KINDS.iter().enumerate() {
        let (bed, head) = (now[k][0] - before[k][0], now[k][1] - before[k][1]);
        if bed + head > 0 {
            out.push(format!("{name} {bed}/{head}"));
        }
    }
    if out.is_empty() {
        "none".to_string()
    } else {
        out.join(", ")
    }
}

#[path = "support/args.rs"]
mod args;
use args::arg;

fn main() {
    let a: Vec<String> = std::env::args().collect();
    let (scene_path, record, pga, block) = (&a[1], &a[2], &a[3], &a[4]);
    let window: f64 = arg("--window").map_or(1.0, |v| v.parse().expect("--window"));
    let moving: f64 = arg("--moving").map_or(0.05, |v| v.parse().expect("--moving"));
    let pga: f64 = pga.parse().expect("PGA, m/s²");
    let text = std::fs::read_to_string(scene_path).expect("scene file");
    let scene = ashlar::scene::parse_scene(&text).expect("scene");
    let motion = ashlar::motion::load_path(std::path::Path::new(record)).expect("record (.at2, …)");
    let watched = scene
        .block_index(block)
        .expect("BLOCK: a block id of the scene");
    let criterion = Criterion::parse(&format!("toppled:{block}")).expect("criterion");
    if std::env::args().any(|x| x == "--verdict-only") {
        // The search's own entry point, for the verdict and the summary alone.
        let (failed, s) = evaluate_with_summary(
            &scene,
            &motion,
            std::slice::from_ref(&criterion),
            Combine::All,
            pga,
            None,
        )
        .expect("run");
        println!("verdict failed={failed}; {:?}", s.stopped_reason);
        return;
    }
    let gm = motion.scaled_to_pga(pga);
    let changes = std::env::args().any(|x| x == "--changes");
    let t0 = Instant::now();
    // The open window, and its line as of the last step (printed at the run's end if the
    // window is then still open).
    let state: Mutex<(Option<Window>, Option<String>)> = Mutex::new((None, None));
    let hook = |sim: &Simulation| {
        let mut st = state.lock().expect("lock");
        let wall = t0.elapsed().as_secs_f64();
        // The first window starts at the run's start (every counter 0, time 0), so the
        // windows' steps add up to the run's.
        let win = st.0.get_or_insert_with(|| Window {
            min_dt: f64::INFINITY,
            ..Default::default()
        });
        win.min_dt = win.min_dt.min(sim.dt());
        win.max_rotation = win.max_rotation.max(sim.geoms()[watched].rotation.abs());
        let mut n_moving = 0;
        let mut fastest = (0.0f64, usize::MAX);
        for b in 0..sim.geoms().len() {
            if sim.mobility()[b] != Mobility::Free || sim.retired()[b] {
                continue;
            }
            let v = sim.block_velocity(b);
            let speed = v[0].hypot(v[1]);
            if speed > moving {
                n_moving += 1;
            }
            if speed > fastest.0 {
                fastest = (speed, b);
            }
        }
        win.max_moving = win.max_moving.max(n_moving);
        let s = sim.stats();
        let r = sim.refusals();
        let g = &sim.geoms()[watched];
        let d = g.centroid - g.initial_centroid;
        let mut line = format!(
            "t {:6.2}–{:6.2} s | wall {:7.1} s (+{:6.1}) | steps {:5} cuts {:4} [unconv {:4} moved {:3} overshot {:3} accuracy {:4}] | solves/step {:5.2} | floor-taken {:3} | impacts {:4} located {:4} | min dt {:.2e} | {} rot {:+7.2}° (max |{:.2}|°) d ({:+.3},{:+.3}) m | moving>{moving} m/s: max {} (fastest {} {:.3} m/s)",
            win.start,
            sim.time(),
            wall,
            wall - win.wall,
            s.steps - win.steps,
            s.time_step_cuts - win.cuts,
            r[0] - win.refusals[0],
            r[1] - win.refusals[1],
            r[2] - win.refusals[2],
            r[3] - win.refusals[3],
            (s.open_close_iterations - win.solves) as f64 / (s.steps - win.steps).max(1) as f64,
            s.unconverged_taken - win.taken_unconverged,
            s.impacts - win.impacts,
            s.located_steps - win.located,
            win.min_dt,
            block,
            g.rotation.to_degrees(),
            win.max_rotation.to_degrees(),
            d.x,
            d.y,
            win.max_moving,
            if fastest.1 == usize::MAX {
                "-".to_string()
            } else {
                sim.scene().blocks[fastest.1].id.clone()
            },
            fastest.0,
        );
        if changes {
            line += &format!(
                "\n    left after failing loops' last iteration (bed/head): {}",
                last_changes(sim, &win.last_kind)
            );
        }
        if sim.time() >= win.start + window - 1e-9 {
            println!("{line}");
            *st = (Some(Window::at(sim, wall)), None);
        } else {
            st.1 = Some(line);
        }
        false
    };
    let decided = |tr: &Tracker| {
        tr.index_of(block)
            .is_some_and(|k| tr.final_rotation[k].abs() > std::f64::consts::FRAC_PI_3)
    };
    let opts = RunOptions {
        stop_when: Some(&decided),
        no_trajectory: true,
        end_when_still: true,
        engine_at_rest: Some(&hook),
        ..Default::default()
    };
    let out = run(&scene, &gm, &opts).expect("run");
    if let Some(line) = state.lock().expect("lock").1.take() {
        // The last, partial window (to the last step the hook saw).
        println!("{line}");
    }
    let s = &out.summary;
    let b = s.blocks.iter().find(|b| &b.id == block).expect("block");
    println!(
        "end: {:?}; wall {:.1} s; {:?}; {} final rotation {:.2}° (toppled: > 30°)",
        s.stopped_reason,
        t0.elapsed().as_secs_f64(),
        s.diagnostics,
        block,
        b.final_rotation.to_degrees()
    );
}
