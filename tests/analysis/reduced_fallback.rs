//! `auto`'s fallback to the full engine in a PGA search starts from the reduced model's state
//! at the last record sample it passed within its assumptions (at rest, or rocking with the
//! pivot within friction: the block's pose and velocity, the record from that sample on;
//! the default; `RunOptions::fallback_from_zero` off, `analysis::run_fallback`), not from t = 0. Reference: the
//! full engine run from t = 0 over the whole record (`"model": "dda"`, the run the fallback
//! replaced), at the default Δt (1 ms) and at 0.25 ms.
//!
//! Scene: the 0.4 × 1.2 m column of `examples/column.json` (friction 40°), under records and
//! amplitudes where its pivot slips while rocking (the runs the search's time went to,
//! docs/speed.md "Reduced models on records"). Per case, with a search's early stop (60°):
//! - the run did hand over late (t₀ > 0 in `model_reason`);
//! - the same verdict as the engine from t = 0;
//! - where both overturn, the time the column passes 60° (the run's end) within the distance
//!   between the engine's own runs from t = 0 at 1 ms and 0.25 ms, plus 20 ms. Why: the
//!   reduced model solves the rocking up to t₀ to 1e-10 (its tests: Housner's equation), the
//!   engine from t = 0 with its own Δt error (docs/accuracy-vs-speed.md), so the two may differ
//!   by the engine's Δt error; 20 ms (2–4 record samples) covers the engine's start-up at t₀
//!   (its contacts start unloaded). A wrong state mapping (the record shifted by a sample, the
//!   block's pose or velocity lost, a sign) changes the episode by far more: the first version
//!   of this fallback, starting the engine at the last rest (an earlier, valid state) instead,
//!   ended 1.3 s later than the engine at 1.3 g and failed this check. Measured
//!   (debug build, 2026-11-26): Imperial Valley 0.8 / 1.0 / 1.3 g end at 6.496 / 6.537 /
//!   5.697 s, the engine from t = 0 at 6.480 / 6.537 / 6.011 s and at 0.25 ms at 6.491 / 6.539
//!   / 5.697 s; Irpinia 1.3 g 5.840 s, 5.837 s, 5.840 s.
use crate::common::*;
use ashlar::analysis::run::{run, RunOptions, Tracker};
use ashlar::scene::{parse_scene, ModelChoice, Scene};

const G: f64 = 9.80665;

/// The column under `name` at `g` × g with a search's early stop: (failed, end time s, steps).
fn from_zero(scene: &Scene, name: &str, g: f64) -> (bool, f64, u64) {
    let gm = record(name).scaled_to_pga(g * G);
    let stop = |tr: &Tracker| tr.final_rotation[0].abs() > std::f64::consts::FRAC_PI_3;
    let opts = RunOptions {
        stop_when: Some(&stop),
        no_trajectory: true,
        ..Default::default()
    };
    let s = run(scene, &gm, &opts).expect("engine run").summary;
    (
        s.blocks[0].final_rotation.abs() > 30f64.to_radians(),
        s.simulated_time,
        s.steps,
    )
}

#[test]
fn fallback_from_the_last_rest_matches_the_engine_from_zero() {
    let auto = parse_scene(ashlar::presets::EXAMPLE_COLUMN).expect("scene");
    let mut dda = auto.clone();
    dda.control.model = ModelChoice::Dda;
    let mut fine = dda.clone();
    fine.control.time_step = 2.5e-4;
    let mut checked = 0;
    for name in [
        "imperial-valley-1979-el-centro-6-233.csv",
        "irpinia-1980-sturno-223.at2",
        "northridge-1994-mulholland-009.at2",
    ] {
        for g in [0.8, 1.0, 1.3] {
            let gm = record(name);
            let scaled = gm.scaled_to_pga(g * G);
            let decided = |tr: &Tracker| tr.final_rotation[0].abs() > std::f64::consts::FRAC_PI_3;
            let opts = RunOptions {
                stop_when: Some(&decided),
                no_trajectory: true,
                ..Default::default()
            };
            let s = run(&auto, &scaled, &opts).expect("run").summary;
            let failed = s.blocks[0].final_rotation.abs() > 30f64.to_radians();
            if s.model != "dda" {
                println!("{name} {g} g: {} (no fallback)", s.model);
                continue;
            }
            let t0: f64 = reason_time(&s.model_reason, "ran from t = ")
                .unwrap_or_else(|| panic!("{name} {g} g: no warm start in {:?}", s.model_reason));
            let (f0, end0, steps0) = from_zero(&dda, name, g);
            let (ff, endf, _) = from_zero(&fine, name, g);
            println!(
            "{name} {g} g: t0 = {t0} s; warm: failed {failed} end {:.4} s, {} steps; from 0: failed {f0} end {end0:.4} s, {steps0} steps; fine: failed {ff} end {endf:.4} s",
            s.simulated_time, s.steps
        );
            assert!(t0 > 0.0, "{name} {g} g: started at {t0}");
            assert_eq!(
                failed, f0,
                "{name} {g} g: verdict against the engine from t = 0"
            );
            if failed && f0 && ff {
                let bound = (end0 - endf).abs() + 0.02;
                assert!(
                (s.simulated_time - end0).abs() <= bound,
                "{name} {g} g: passes 60° at {} s, the engine from t = 0 at {end0} s (fine Δt {endf} s; bound {bound} s)",
                s.simulated_time
            );
                checked += 1;
            }
        }
    }
    assert!(checked >= 3, "only {checked} overturning cases compared");
}

/// `ashlar run`'s path (outputs written, no early stop) and a search's run (nothing written)
/// hand over alike, and the outputs are the two models' frames stitched at t₀. Scene: the
/// column of `examples/column.json` under Imperial Valley at 1.0 g (its pivot slips: the run
/// falls back, measured above).
/// - Same run (exact): the summary with outputs equals the one without (verdict, final and
///   peak rotation, steps, simulated time, model and reason): the two paths share every step.
/// - Stitching (exact): `histories.csv`'s times increase from 0 to the summary's simulated
///   time, the frames before t₀ on the `output_interval` grid, one at t₀; its last rotation is
///   the summary's final rotation and its largest |rotation| is not above the summary's peak.
/// - Against an independent reference: the engine from t = 0 at Δt = 0.25 ms (`"model":
///   "dda"`), frames at the same times up to t₀ + 50 ms. Bound: 10 % of the reference's
///   largest |θ| up to t₀ plus 1 mrad. Why: up to t₀ the
///   stitched history is the reduced model's (Housner's equation), which the converged engine
///   follows to the 5–15 % peak differences of docs/accuracy-vs-speed.md (the engine's impact
///   is not Housner's); after t₀ it is the engine from the handed-over state. A frame offset
///   lost in the stitching (rotation or time not shifted by the hand-over's) is off by the
///   whole rotation at t₀ and fails it. Measured (debug build, 2026-11-26): t₀ = 6.485 s, the
///   column already at −0.866 rad (the pivot slips while it overturns), worst 5.6 mrad.
#[test]
fn a_run_that_writes_outputs_hands_over_like_a_search_run() {
    let auto = parse_scene(ashlar::presets::EXAMPLE_COLUMN).expect("scene");
    let gm = record("imperial-valley-1979-el-centro-6-233.csv").scaled_to_pga(G);
    let dir = std::path::Path::new(env!("CARGO_TARGET_TMPDIR")).join("handover_outputs");
    std::fs::remove_dir_all(&dir).ok();
    let with = run(
        &auto,
        &gm,
        &RunOptions {
            out_dir: Some(&dir),
            ..Default::default()
        },
    )
    .expect("run with outputs")
    .summary;
    let without = run(
        &auto,
        &gm,
        &RunOptions {
            no_trajectory: true,
            ..Default::default()
        },
    )
    .expect("run without outputs")
    .summary;
    assert_eq!(with.model, "dda", "{}", with.model_reason);
    assert_eq!(with.model_reason, without.model_reason);
    let (a, b) = (&with.blocks[0], &without.blocks[0]);
    assert_eq!(
        (a.final_rotation, a.max_rotation, a.toppled),
        (b.final_rotation, b.max_rotation, b.toppled)
    );
    assert_eq!(
        (with.steps, with.simulated_time, &with.failure_mode),
        (without.steps, without.simulated_time, &without.failure_mode)
    );
    let t0: f64 = reason_time(&with.model_reason, "ran from t = ").expect("handed over");
    let rows = history_columns(&dir.join("histories.csv"), &["column.rotation_rad"]);
    assert_whole_history(&rows, with.simulated_time, a.final_rotation);
    let peak = rows.iter().map(|r| r[1].abs()).fold(0.0, f64::max);
    assert!(peak <= a.max_rotation, "{peak} > {}", a.max_rotation);
    let before: Vec<_> = rows.iter().filter(|r| r[0] < t0 - 1e-9).collect();
    for (k, r) in before.iter().enumerate() {
        assert!(
            (r[0] - k as f64 * 0.01).abs() < 1e-9,
            "frame {k} at {}",
            r[0]
        );
    }
    assert!(
        rows.iter().any(|r| (r[0] - t0).abs() < 1e-9),
        "a frame at t0 = {t0}"
    );
    // The independent reference over [0, t0 + 50 ms].
    let mut fine = auto.clone();
    fine.control.model = ModelChoice::Dda;
    fine.control.time_step = 2.5e-4;
    fine.control.output_interval = 0.005;
    let end = t0 + 0.05;
    let frames = std::sync::Mutex::new(Vec::new());
    let keep = |f: &ashlar::record::Frame| {
        if let Ok(mut v) = frames.lock() {
            v.push((f.time, f.blocks[1].rotation));
        }
    };
    let stop = |_: &Tracker| {
        frames
            .lock()
            .map(|v| v.last().is_some_and(|l| l.0 > end))
            .unwrap_or(false)
    };
    run(
        &fine,
        &gm,
        &RunOptions {
            on_frame: Some(&keep),
            stop_when: Some(&stop),
            no_trajectory: true,
            ..Default::default()
        },
    )
    .expect("fine run");
    let reference = frames.into_inner().expect("frames");
    let at = |t: f64| {
        reference
            .iter()
            .find(|r| (r.0 - t).abs() < 1e-6)
            .map(|r| r.1)
    };
    let window: Vec<(f64, f64, f64)> = rows
        .iter()
        .filter(|r| r[0] <= end)
        .filter_map(|r| at(r[0]).map(|x| (r[0], r[1], x)))
        .collect();
    assert!(window.len() > 10, "{} common frames", window.len());
    let scale = window
        .iter()
        .filter(|w| w.0 <= t0 + 1e-9)
        .map(|w| w.2.abs())
        .fold(0.0, f64::max);
    let worst = window.iter().map(|w| (w.1 - w.2).abs()).fold(0.0, f64::max);
    println!("t0 = {t0} s; stitched vs engine at 0.25 ms up to t0 + 50 ms: worst {worst:.5} rad, reference peak {scale:.5} rad");
    assert!(
        worst <= 0.1 * scale + 1e-3,
        "stitched history off the engine at 0.25 ms by {worst} rad (peak {scale})"
    );
    std::fs::remove_dir_all(&dir).ok();
}
