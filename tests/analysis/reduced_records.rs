//! The reduced rocking model on real records (docs/accuracy-vs-speed.md: its integrator steps from sample to
//! sample of the record instead of across them) against Housner's equation integrated
//! independently by fixed-step RK4 at Δt = 1e-5 s (`ashlar::analysis::reference`, impacts
//! located within the step since session 33; before, each was put at the step's end) under the
//! same record. (At Δt = 1e-4 s, printed too: with impacts at the step's end it was not
//! converged on records, its peak on Friuli at 0.5 g 44 % below its own 1e-5 s value.)
//!
//! Column b = 0.2 m, h = 0.6 m (α = 18.4°), friction 75° (it never slides), forced
//! `"model": "rocking"`, under Friuli 1976 Tolmezzo, Northridge 1994 Mulholland and Kobe 1995
//! Nishi-Akashi (`data/ground-motions/`) scaled to 0.3, 0.5 and 0.7 g, over the record's length.
//! Checks, per case:
//! - the same verdict (overturned or not);
//! - where it stands and rocks past 0.01 rad: peak |θ| within 0.5 % of the reference. Both
//!   solve the same equation; measured 0.033 % at most (Kobe 0.7 g, 99 impacts). It was 5 %
//!   while the reference put each impact at the end of its step (ω·1e-5 s in θ per impact),
//!   which a rocking history through ~90 impacts amplified (Friuli 0.5 g: 4.4 % off); the
//!   reference now locates impacts (session 33), and 0.5 % is the bound of the next test.
use crate::common;
use ashlar::analysis::reference::{housner_rocking, HousnerColumn};
use ashlar::analysis::run::{run, RunOptions};
use common::*;
use serde_json::json;

const COLUMN: HousnerColumn = HousnerColumn {
    b: 0.2,
    h: 0.6,
    g: G,
    dt: 1e-4,
};

fn scene(duration: f64) -> ashlar::scene::Scene {
    parse(
        &Column::SEED
            .json(json!({ "duration": duration, "model": "rocking", "output_interval": 0.01 })),
    )
}

#[test]
fn peak_rotation_on_records_matches_housner_rk4() {
    let alpha = (COLUMN.b / COLUMN.h).atan();
    let mut worst: f64 = 0.0;
    let mut compared = 0;
    for name in [
        "friuli-1976-tolmezzo-000.at2",
        "northridge-1994-mulholland-009.at2",
        "kobe-1995-nishi-akashi-000.csv",
    ] {
        let gm = record(name);
        let length = gm.duration().expect("a record has a length");
        for g_units in [0.3, 0.5, 0.7] {
            let scaled = gm.scaled_to_pga(g_units * 9.80665);
            let mut peak_ref: f64 = 0.0;
            let end = housner_rocking(
                &COLUMN,
                |t| scaled.acceleration(t)[0],
                length,
                |s| {
                    peak_ref = peak_ref.max(s.theta.abs());
                    s.theta.abs() > std::f64::consts::FRAC_PI_2
                },
            );
            let fell_ref = end.theta.abs() > alpha;
            let mut peak_fine: f64 = 0.0;
            housner_rocking(
                &HousnerColumn { dt: 1e-5, ..COLUMN },
                |t| scaled.acceleration(t)[0],
                length,
                |s| {
                    peak_fine = peak_fine.max(s.theta.abs());
                    s.theta.abs() > std::f64::consts::FRAC_PI_2
                },
            );
            let out = run(&scene(length), &scaled, &RunOptions::default()).expect("run");
            let s = &out.summary;
            assert_eq!(s.model, "rocking");
            let peak = s.blocks[0].max_rotation;
            let fell = s.blocks[0].final_rotation.abs() > alpha;
            // The fine reference is the one held to; the 1e-4 s one is printed (with impacts
            // at the step's end it put Friuli 0.5 g's peak 44 % low; located, it agrees).
            let coarse = peak_ref;
            let peak_ref = peak_fine;
            let diff = (peak - peak_ref) / peak_ref.max(1e-12);
            eprintln!(
                "{name} {g_units} g: peak θ reduced {peak:.5} rad, RK4 1e-5 s {peak_ref:.5} rad ({:+.3} %), RK4 1e-4 s {coarse:.5} rad, overturned {fell} / {fell_ref}, {} steps, {} impacts, steps {:?}..{:?} s",
                100.0 * diff,
                s.steps,
                s.diagnostics.impacts.unwrap_or(0),
                s.diagnostics.min_time_step,
                s.diagnostics.max_time_step,
            );
            assert_eq!(fell, fell_ref, "{name} at {g_units} g: verdicts differ");
            if !fell && peak_ref > 0.01 {
                compared += 1;
                worst = worst.max(diff.abs());
                assert!(
                    diff.abs() < 5e-3,
                    "{name} at {g_units} g: peak {peak} rad against {peak_ref} rad"
                );
            }
        }
    }
    eprintln!(
        "largest peak-rotation difference over {compared} standing cases: {:.3} %",
        100.0 * worst
    );
    assert!(
        compared >= 3,
        "too few rocking cases to compare ({compared})"
    );
}

/// The three worst points of the hand-over study (docs/accuracy-vs-speed/handover.md: the
/// reduced model's peak 493 %, 107 % and −72 % off the engine at Δt = 1e-4 s) against Housner's
/// equation by RK4 at 1e-5 s with located impacts (`analysis::reference`), run as `auto` runs
/// them (the reduced rocking model; it does not fall back here). The reference is shown
/// converged at each point (within 0.1 % of itself at 5e-6 s).
///
/// Tolerance 0.5 % on the peak, with the same verdict: both solve the same equation, and the
/// measured difference is below 0.01 %. These points are ill-conditioned (±1 % of the PGA moves
/// Housner's peak by 15–130 %), so any answer that is not the same solution misses by tens of
/// percent: the reference with impacts put at the step's end (as it was until session 33) by
/// −81 % at the first point, the engine at 1e-4 s by −83 %, −67 % and +93 %. 0.5 % is an order
/// below the 5 % target and tells "the same solution" from "another".
#[test]
fn worst_hand_over_points_match_converged_housner() {
    let slender = || parse(&Column::SLENDER.json(json!({})));
    let column = ashlar::scene::parse_scene(ashlar::presets::EXAMPLE_COLUMN).expect("column");
    let mut windowed = slender();
    windowed.control.duration = Some(9.0);
    let points = [
        (column, "loma-prieta-1989-capitola-000.at2", 5.371),
        (slender(), "imperial-valley-1979-el-centro-6-233.csv", 2.515),
        (windowed, "loma-prieta-1989-capitola-000.at2", 3.610),
    ];
    for (scene, name, pga) in points {
        let gm = record(name).scaled_to_pga(pga);
        let s = run(&scene, &gm, &RunOptions::default())
            .expect("run")
            .summary;
        assert_eq!(s.model, "rocking", "{name}: {}", s.model_reason);
        let peak = s.blocks[0].max_rotation;
        let fell = s.blocks[0].final_rotation.abs() > 1.0;
        let v = &scene.blocks[1].vertices;
        let (b, h) = (0.5 * (v[1].x - v[0].x), 0.5 * (v[2].y - v[1].y));
        let housner = |dt: f64| {
            let mut p: f64 = 0.0;
            housner_rocking(
                &HousnerColumn {
                    b,
                    h,
                    g: scene.gravity,
                    dt,
                },
                |t| gm.acceleration(t)[0],
                s.simulated_time,
                |st| {
                    p = p.max(st.theta.abs());
                    p > 1.0
                },
            );
            p
        };
        let (reference, finer) = (housner(1e-5), housner(5e-6));
        eprintln!(
            "{name} at {pga} m/s² (b {b}, h {h}): reduced {peak:.6} rad, Housner 1e-5 s {reference:.6} ({:+.4} %), 5e-6 s {finer:.6}",
            100.0 * (peak / reference - 1.0)
        );
        assert!(
            ((reference / finer) - 1.0).abs() < 1e-3,
            "{name}: the reference is not converged ({reference} at 1e-5 s, {finer} at 5e-6 s)"
        );
        assert_eq!(fell, reference > 1.0, "{name}: verdicts differ");
        assert!(
            (peak / reference - 1.0).abs() < 5e-3,
            "{name} at {pga} m/s²: peak {peak} rad against Housner's {reference} rad"
        );
    }
}
