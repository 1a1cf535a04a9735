//! `auto`'s hand-back (`analysis::run_fallback::HandBackParams`): after the hand-over to the
//! full engine, once the engine's block is at rest on its base again, the reduced model takes
//! the run back from the next record sample, the block's slip and rotation then kept as its
//! new reference.
//!
//! Scene: a squat block 0.6 × 0.8 m (tan α = 0.75) with φ = 40° on a plinth, under the Kobe
//! record (Nishi-Akashi) at 16.621 m/s², the scene's duration cut to 14 s to keep the
//! reference affordable. Its pivot loses contact at t ≈ 8.98 s (the engine takes over), it
//! slides a little, lands and is at rest again by t ≈ 9.9 s (handed back), then rocks again
//! under the record's tail in the reduced model.
//!
//! Reference (independent of the hand-back): the engine run through from the same hand-over
//! to the end at Δt = 0.25 ms (`HandBackParams::enabled` off, `control.time_step` 2.5e-4 s: the
//! reduced part before the hand-over does not use the step, so the hand-over is the same).
//! Checks and tolerances:
//! - the run did hand back (`model_reason`), and took fewer steps than the engine run through
//!   at the default step;
//! - the same verdict (`failure_mode`, toppled) as the reference;
//! - peak rotation within 5 % of the reference's (the accuracy target for peaks), over
//!   the whole run and over the frames after the hand-back alone (where the block rocks again:
//!   the reduced model's part against the engine's);
//! - residual: final rotation within 1e-3 rad of the reference's (the hand-back's rotation
//!   bound: the block is handed back only when flat within it); final displacement within the
//!   default-step engine's own distance to the reference plus 10 % of the slip (the hand-back
//!   keeps the engine's slip as its reference, and pure rocking returns the block to it; a slip
//!   lost at the hand-back is off by all of it).
//!
//! Measured (debug build, 2026-11-26): handed back at 9.91 s; 3587 steps against 7160 run
//! through (21803 at 0.25 ms); peak 0.15268 rad all three, after the hand-back 0.00897 rad both;
//! final slip −0.6013 mm, −0.6004 mm run through, −0.5997 mm reference.
//! - The run's displacement right after the hand-back equals the engine's at the hand-back
//!   (exact up to 1e-9 m): the reduced part is offset by it.
//! - Outputs: the run writing `histories.csv` equals the run writing none (exact), and its
//!   times increase from 0 to the summary's end with its last rotation the summary's.
use crate::common::*;
use ashlar::analysis::run::{run, RunOptions, Summary};
use ashlar::analysis::run_fallback::HandBackParams;
use ashlar::presets::Column;
use ashlar::scene::{parse_scene, Scene};
use serde_json::json;
use std::sync::Mutex;

fn squat() -> Scene {
    let json = Column {
        half_width: 0.3,
        half_height: 0.4,
        ..Column::SEED
    }
    .friction(40.0)
    .json(json!({ "duration": 14.0 }));
    parse_scene(&json.to_string()).expect("scene")
}

fn go(scene: &Scene, pga: f64, back: bool, out: Option<&std::path::Path>) -> Summary {
    go_frames(scene, pga, back, out, None)
}

fn go_frames(
    scene: &Scene,
    pga: f64,
    back: bool,
    out: Option<&std::path::Path>,
    frames: Option<&(dyn Fn(&ashlar::record::Frame) + Sync)>,
) -> Summary {
    let gm = record("kobe-1995-nishi-akashi-000.csv").scaled_to_pga(pga);
    run(
        scene,
        &gm,
        &RunOptions {
            out_dir: out,
            on_frame: frames,
            no_trajectory: true,
            hand_back: Some(HandBackParams {
                enabled: back,
                ..Default::default()
            }),
            ..Default::default()
        },
    )
    .expect("run")
    .summary
}

#[test]
fn a_block_at_rest_again_is_handed_back_and_ends_as_the_engine_run_through() {
    let scene = squat();
    let pga = 16.621;
    // (time s, rotation rad) of every frame.
    let (fa, fr) = (Mutex::new(Vec::new()), Mutex::new(Vec::new()));
    let keep = |v: &Mutex<Vec<(f64, f64)>>, f: &ashlar::record::Frame| {
        if let Ok(mut v) = v.lock() {
            v.push((f.time, f.blocks[1].rotation));
        }
    };
    let (ka, kr) = (
        |f: &ashlar::record::Frame| keep(&fa, f),
        |f: &ashlar::record::Frame| keep(&fr, f),
    );
    let a = go_frames(&scene, pga, true, None, Some(&ka));
    let through = go(&scene, pga, false, None);
    let mut fine = scene.clone();
    fine.control.time_step = 2.5e-4;
    let reference = go_frames(&fine, pga, false, None, Some(&kr));
    let t1: f64 = reason_time(&a.model_reason, "; at t = ").expect("hand-back time");
    let after = |v: Mutex<Vec<(f64, f64)>>| {
        v.into_inner()
            .expect("frames")
            .iter()
            .filter(|f| f.0 > t1)
            .map(|f| f.1.abs())
            .fold(0.0, f64::max)
    };
    let (pa, pr) = (after(fa), after(fr));
    println!("peak after the hand-back at {t1} s: {pa:.5} rad, reference {pr:.5} rad");
    assert!(
        pr > 1e-3,
        "the block rocks again after the hand-back ({pr} rad)"
    );
    assert!(
        (pa / pr - 1.0).abs() <= 0.05,
        "peak after the hand-back {pa} against {pr}"
    );
    let (ba, bt, br) = (&a.blocks[0], &through.blocks[0], &reference.blocks[0]);
    println!(
        "hand-back: {} steps, {} peak {:.5} final θ {:.3e} d {:?}\nthrough:   {} steps, {} peak {:.5} final θ {:.3e} d {:?}\nreference: {} steps, {} peak {:.5} final θ {:.3e} d {:?}\n{}",
        a.steps, a.failure_mode, ba.max_rotation, ba.final_rotation, ba.final_displacement,
        through.steps, through.failure_mode, bt.max_rotation, bt.final_rotation, bt.final_displacement,
        reference.steps, reference.failure_mode, br.max_rotation, br.final_rotation, br.final_displacement,
        a.model_reason
    );
    assert!(a.model_reason.contains("handed back"), "{}", a.model_reason);
    assert!(!through.model_reason.contains("handed back"));
    assert!(a.steps < through.steps, "{} ≥ {}", a.steps, through.steps);
    assert_eq!(a.failure_mode, reference.failure_mode);
    assert_eq!(ba.toppled, br.toppled);
    assert!(
        (ba.max_rotation / br.max_rotation - 1.0).abs() <= 0.05,
        "peak {} against {}",
        ba.max_rotation,
        br.max_rotation
    );
    assert!((ba.final_rotation - br.final_rotation).abs() <= 1e-3);
    let dist = |p: [f64; 2], q: [f64; 2]| (p[0] - q[0]).hypot(p[1] - q[1]);
    let own = dist(bt.final_displacement, br.final_displacement);
    let off = dist(ba.final_displacement, br.final_displacement);
    let slip = ba.final_displacement[0].abs();
    assert!(
        off <= own + 0.1 * slip,
        "final displacement {off} m from the reference (engine at 1 ms: {own} m; slip {slip} m)"
    );
}

/// The slip at the hand-back is the reduced part's reference, exactly; and `ashlar run`'s path
/// (outputs written) is the search's (none written).
#[test]
fn the_hand_back_keeps_the_slip_and_stitches_the_outputs() {
    let scene = squat();
    let pga = 16.621;
    let dir = std::path::Path::new(env!("CARGO_TARGET_TMPDIR")).join("hand_back_outputs");
    std::fs::remove_dir_all(&dir).ok();
    let with = go(&scene, pga, true, Some(&dir));
    let without = go(&scene, pga, true, None);
    assert_eq!(with.model_reason, without.model_reason);
    assert_eq!(
        (with.steps, with.simulated_time, &with.failure_mode),
        (without.steps, without.simulated_time, &without.failure_mode)
    );
    let (a, b) = (&with.blocks[0], &without.blocks[0]);
    assert_eq!(
        (a.final_rotation, a.max_rotation, a.final_displacement),
        (b.final_rotation, b.max_rotation, b.final_displacement)
    );
    let t1: f64 = reason_time(&with.model_reason, "; at t = ").expect("hand-back time");
    let rows = history_columns(
        &dir.join("histories.csv"),
        &["column.rotation_rad", "column.x_m"],
    );
    assert_whole_history(&rows, with.simulated_time, a.final_rotation);
    // Across the hand-back the block is at rest: its displacement continues (the slip kept),
    // the engine's last frame before and the reduced model's first after within 1e-9 m.
    let before = rows
        .iter()
        .rev()
        .find(|r| r[0] < t1 - 1e-9)
        .expect("before");
    let after = rows.iter().find(|r| r[0] >= t1 - 1e-9).expect("after");
    println!("hand-back at {t1} s: before {before:?}, after {after:?}");
    assert!(
        before[2].abs() > 1e-5,
        "the block slipped before the hand-back"
    );
    assert!(
        (after[2] - before[2]).abs() < 1e-9 + 1e-3 * (after[0] - before[0]),
        "slip lost: {before:?} → {after:?}"
    );
    std::fs::remove_dir_all(&dir).ok();
}
