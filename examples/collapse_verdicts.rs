//! A collapse verdict (`toppled:BLOCK`) under one engine configuration, for comparing the
//! default, the unconverged floor and the tight run by verdict (docs/contact-solve.md §26).
//!
//! `cargo run --release --example collapse_verdicts -- --scene WALL.json --record FILE --pga G
//!  --block ID --variant default|floor:R|floor-hold:R|tight [--duration S] [--limit S]
//!  [--floor-penetration F] [--floor-iterations N]`
//!
//! `--scene`: a scene file (`ashlar scene wall --set length=6 --set height=3 --set openings=0`).
//! `--record`: a record of `data/ground-motions`, scaled to `--pga` g. `--variant`: `default`
//! (`SimParams::default()`), `floor:R` (`unconverged_floor_ratio` R, as in session 37: without
//! `unconverged_floor_hold`), `floor-hold:R` (with it), `tight` (the tight reference of `shaken_walls --reference`: fixed
//! Δt 1e-4 s, the legacy open–close loop to 200 iterations). The run stops once the block has
//! fallen (|rotation| > 60°, as `ashlar pga` decides) or at its end (`--duration`, default the
//! record + 2 s, then the run-end extension); `--limit S` cancels it after S s of wall time.
//! The floor variants take session 39's penetration bound and iteration cap (§28) unless
//! `--floor-penetration inf --floor-iterations 0` (session 38's floor).
//! One line: the verdict (|final rotation| > 30°), the failure mode, the first frame time with
//! |rotation| > 30°, how many free blocks toppled and the first frame any did, steps, cuts, min Δt, max penetration, where and why the run ended, its
//! wall time (CPU: run it under `/usr/bin/time`).
use ashlar::analysis::run::{run, RunOptions, Tracker};
use ashlar::motion;
use ashlar::presets;
use ashlar::record::Frame;
use ashlar::simulation::SimParams;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Mutex;

/// |rotation| beyond which a block has fallen and the verdict cannot change (`ashlar pga`'s
/// early stop, 60°).
const FALLEN: f64 = std::f64::consts::FRAC_PI_3;
/// |rotation| of the verdict `toppled` (docs/format.md, 30°).
const TOPPLED: f64 = std::f64::consts::FRAC_PI_6;

#[path = "support/args.rs"]
mod args;
use args::arg;

fn main() {
    let scene_path = arg("--scene").expect("--scene FILE");
    let text = std::fs::read_to_string(&scene_path).expect("--scene: readable");
    let mut scene = ashlar::scene::parse_scene(&text).expect("--scene: a valid scene");
    let pga: f64 = arg("--pga").map_or(1.0, |v| v.parse().expect("--pga"));
    let record = arg("--record").unwrap_or_else(|| "northridge-1994-mulholland-009.at2".into());
    let gm = presets::record(&record)
        .expect("--record: a record of data/ground-motions")
        .scaled_to_pga(pga * motion::STANDARD_GRAVITY);
    let block = arg("--block").expect("--block ID");
    let variant = arg("--variant").unwrap_or_else(|| "default".into());
    let mut params = SimParams::default();
    if variant == "tight" {
        scene.control.time_step = 1e-4;
        scene.control.adaptive_time_step = false;
        params.open_close = ashlar::solve::open_close::OpenCloseParams::legacy();
        params.open_close.max_iterations = 200;
    } else if let Some(r) = variant.strip_prefix("floor-hold:") {
        params.unconverged_floor_ratio = Some(r.parse().expect("floor-hold:R"));
        params.unconverged_floor_hold = true;
    } else if let Some(r) = variant.strip_prefix("floor:") {
        params.unconverged_floor_ratio = Some(r.parse().expect("floor:R"));
        params.unconverged_floor_hold = false;
    } else {
        assert_eq!(
            variant, "default",
            "--variant default|floor:R|floor-hold:R|tight"
        );
    }
    // `--floor-penetration F`, `--floor-iterations N`: the floor's penetration bound and its
    // iteration limit (`SimParams::unconverged_floor_penetration`, `…_iterations`, §28; 0: the
    // loop's own limit).
    if let Some(f) = arg("--floor-penetration") {
        params.unconverged_floor_penetration = f.parse().expect("--floor-penetration");
    }
    if let Some(n) = arg("--floor-iterations") {
        let n: usize = n.parse().expect("--floor-iterations");
        params.unconverged_floor_iterations = (n > 0).then_some(n);
    }
    if let Some(d) = arg("--duration") {
        scene.control.duration = Some(d.parse().expect("--duration"));
    }
    let k = scene
        .blocks
        .iter()
        .position(|b| b.id == block)
        .expect("--block: a block of the scene");
    let toppled_at = Mutex::new(None::<f64>);
    // The first frame with any free block past 30° (the wall's first toppled stone).
    let first_any = Mutex::new(None::<f64>);
    let free: Vec<usize> = scene
        .blocks
        .iter()
        .enumerate()
        .filter(|(_, b)| matches!(b.kind, ashlar::scene::BlockKind::Free(_)))
        .map(|(i, _)| i)
        .collect();
    let on_frame = |f: &Frame| {
        if f.blocks[k].rotation.abs() > TOPPLED {
            let mut t = toppled_at.lock().expect("frame lock");
            t.get_or_insert(f.time);
        }
        if free.iter().any(|&i| f.blocks[i].rotation.abs() > TOPPLED) {
            let mut t = first_any.lock().expect("frame lock");
            t.get_or_insert(f.time);
        }
    };
    let fallen = |tr: &Tracker| {
        tr.index_of(&block)
            .is_some_and(|i| tr.final_rotation[i].abs() > FALLEN)
    };
    let cancel = AtomicBool::new(false);
    let limit: Option<f64> = arg("--limit").map(|v| v.parse().expect("--limit"));
    let start = std::time::Instant::now();
    let done = AtomicBool::new(false);
    let summary = std::thread::scope(|s| {
        if let Some(l) = limit {
            let (cancel, done) = (&cancel, &done);
            s.spawn(move || {
                while start.elapsed().as_secs_f64() < l && !done.load(Ordering::Relaxed) {
                    std::thread::sleep(std::time::Duration::from_millis(200));
                }
                cancel.store(true, Ordering::Relaxed);
            });
        }
        let opts = RunOptions {
            no_trajectory: true,
            on_frame: Some(&on_frame),
            stop_when: Some(&fallen),
            cancel: Some(&cancel),
            sim_params: Some(params),
            ..Default::default()
        };
        let out = run(&scene, &gm, &opts);
        done.store(true, Ordering::Relaxed);
        out
    });
    let wall = start.elapsed().as_secs_f64();
    match summary {
        Err(e) => {
            println!("| {record} | {pga} g | {variant} | error: {e} | | | | | | | {wall:.1} s |")
        }
        Ok(out) => {
            let s = out.summary;
            let b = s
                .blocks
                .iter()
                .find(|b| b.id == block)
                .expect("block summary");
            let at = toppled_at
                .lock()
                .expect("frame lock")
                .map_or("—".into(), |t| format!("{t:.2} s"));
            let any = first_any
                .lock()
                .expect("frame lock")
                .map_or("—".into(), |t| format!("{t:.2} s"));
            let fallen = s.blocks.iter().filter(|b| b.toppled).count();
            println!(
                "| {record} | {pga} g | {variant} | {} | {} | {at} | {fallen} toppled, first at {any} | {} | {} | {:.1e} | {:.2e} m | t = {:.3} s, {} | {wall:.1} s |",
                if b.toppled { "toppled" } else { "standing" },
                s.failure_mode,
                s.steps,
                s.diagnostics.time_step_cuts,
                s.diagnostics.min_time_step.unwrap_or(f64::NAN),
                s.diagnostics.max_penetration,
                s.simulated_time,
                if out.cancelled {
                    "cancelled (--limit)".to_string()
                } else {
                    s.stopped_reason.unwrap_or_else(|| "completed".into())
                },
            );
        }
    }
}
