//! `auto`'s fallback to the full engine in a PGA search starts from the reduced model's state
//! at the last record sample it passed within its assumptions (at rest, or rocking with the
//! pivot within friction: the block's pose and velocity, the record from that sample on;
//! `RunOptions::fallback_from_rest`, `analysis::run_fallback`), not from t = 0. Reference: the
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
                fallback_from_rest: true,
                ..Default::default()
            };
            let s = run(&auto, &scaled, &opts).expect("run").summary;
            let failed = s.blocks[0].final_rotation.abs() > 30f64.to_radians();
            if s.model != "dda" {
                println!("{name} {g} g: {} (no fallback)", s.model);
                continue;
            }
            let t0: f64 = s
                .model_reason
                .split("ran from t = ")
                .nth(1)
                .and_then(|r| r.split(' ').next())
                .and_then(|t| t.parse().ok())
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
