//! The full engine (`"model": "dda"`) at its default numerical controls against Housner's
//! equation on real records (docs/accuracy-vs-speed.md, Records): the 0.4 × 1.2 m and the slender 0.25 × 1.5 m column
//! of `analysis::study_records` (φ = 75°, nothing slides; the scenes' default deformable block)
//! under the repository's records (data/ground-motions) scaled to a PGA. Housner:
//! `analysis::reference::housner_rocking` (RK4 at 1e-5 s, no code shared with the engine).
//!
//! Criteria (the issue's): the same stand/fall verdict as Housner wherever Housner's verdict
//! holds at ±3 % of the PGA (checked here, three reference runs), and the peak rotation within
//! 5 % where the column survives with more than 0.02 rad. A column counts as fallen past 1 rad
//! in both (`study_records::FALLEN`). The 5 % tolerance is the figure for peak rotations
//! through impacts; the regression bound is 5× the error measured when the test was written,
//! or the tolerance where that is smaller (said at each point).
//!
//! Which points: every PGA level of a record (0.3–1.0 g), chosen by rule, not by hand. The
//! verdict is checked where Housner's verdict holds at ±3 % of the PGA; the peak where the column
//! survives beyond 0.02 rad and the reference is well conditioned: its peak moves by at most 3 %
//! for ±1 % of the PGA (the rule the rocking frame's record tests assert,
//! tests/engine/multiblock_references/), so a 5 % miss is the engine's and not the record's
//! sensitivity. Each test asserts that it checked at least the points it was written for.
//!
//! Found when this file was written: the default missed the 5 % at Friuli 0.5 g (+36.8 %) and
//! 0.9 g (−14.6 %) on the 0.4 × 1.2 m column; both pass since impacts follow the e = 0 law and
//! are located in time. Friuli 0.5 g (Housner +48 / −25 % for ∓1 % of the PGA) and 0.6 g
//! (−1.18 / −3.31 %, engine +5.49 %) were ignored by hand; the rule now leaves them out.
use ashlar::analysis::study_records::{self as sr, RecordColumn, COLUMNS};
use ashlar::presets::records_dir;
use ashlar::simulation::SimParams;
use serde_json::json;

/// Housner's peak at 0.99 and 1.01 × the PGA relative to its peak `at` the PGA (a fall counts
/// as an infinite move).
fn conditioning(col: &RecordColumn, record: &str, pga: f64, at: f64) -> [f64; 2] {
    [0.99, 1.01].map(|f| {
        let m = sr::load_record(&records_dir(), record, pga * f).expect("record");
        let r = sr::housner(col, &m, sr::run_length(&m), sr::HOUSNER_DT);
        if r.fallen {
            f64::INFINITY
        } else {
            r.peak / at - 1.0
        }
    })
}

/// Every level 0.3–1.0 g of `record` on `col`, each checked by [`check_point`] where the rule
/// of the module's header applies; returns the levels (g) checked for the verdict and for the
/// peak. `regression` per level (5× the error measured when written, or the tolerance).
fn check_levels(
    col: &RecordColumn,
    record: &str,
    regression: &[(f64, f64)],
) -> (Vec<f64>, Vec<f64>) {
    let dir = records_dir();
    let (mut verdicts, mut peaks) = (Vec::new(), Vec::new());
    for k in 3..=10 {
        let pga = k as f64 / 10.0;
        let (housner, robust) = sr::robust_verdict(col, &dir, record, pga).expect("reference");
        let peak = !housner.fallen && housner.peak > 0.02;
        let moves = peak.then(|| conditioning(col, record, pga, housner.peak));
        let well = moves.is_some_and(|m| m.iter().all(|m| m.abs() <= 0.03));
        eprintln!(
            "{} {record} {pga} g: verdict robust {robust}, peak {} (Housner {:.5} rad, ±1 % PGA: {:?})",
            col.name,
            if well { "checked" } else if peak { "ill-conditioned" } else { "not applicable" },
            housner.peak,
            moves
        );
        if !robust {
            continue;
        }
        if well {
            let bound = regression
                .iter()
                .find(|(p, _)| (p - pga).abs() < 1e-9)
                .map_or(0.05, |&(_, b)| b);
            check_point(col, record, pga, Some(bound));
            peaks.push(pga);
        } else {
            check_point(col, record, pga, None);
        }
        verdicts.push(pga);
    }
    (verdicts, peaks)
}

/// The engine at its defaults against Housner at one point; returns the peak error relative
/// to Housner's peak (0 where the column falls). `regression`: the peak's regression bound, or
/// `None` to check the verdict only (a point where the peak is ill-conditioned).
fn check_point(col: &RecordColumn, record: &str, pga: f64, regression: Option<f64>) -> f64 {
    let dir = records_dir();
    let (housner, robust) = sr::robust_verdict(col, &dir, record, pga).expect("reference");
    let m = sr::load_record(&dir, record, pga).expect("record");
    let run = sr::engine(
        col,
        &m,
        sr::run_length(&m),
        // Deformable by name: the points and bounds below were measured with the deformable
        // block, the default when this was written. With rigid blocks (what "auto" now
        // chooses for it, docs/format.md) the 0.4 × 1.2 m column under Friuli at 0.5 / 0.9 g is −7.6 % off
        // Housner's peak at one of them (5 % tolerance): not yet understood.
        &json!({ "block_model": "deformable" }),
        SimParams::default(),
    )
    .expect("scene");
    assert!(run.failed.is_none(), "engine failed: {:?}", run.failed);
    let e = &run.response;
    let err = if housner.fallen || e.fallen {
        0.0
    } else {
        e.peak / housner.peak - 1.0
    };
    eprintln!(
        "{} {record} {pga} g: Housner {:?} (verdict robust at ±3 %: {robust}), engine {:?}, peak error {:+.2} %, {} steps",
        col.name,
        housner,
        e,
        100.0 * err,
        run.steps
    );
    assert!(
        robust,
        "the point was chosen where Housner's verdict is robust"
    );
    assert_eq!(e.fallen, housner.fallen, "verdict differs from Housner's");
    let Some(regression) = regression else {
        return err;
    };
    if !housner.fallen && housner.peak > 0.02 {
        let moves = conditioning(col, record, pga, housner.peak);
        assert!(
            moves.iter().all(|m| m.abs() <= 0.03),
            "the point was chosen where Housner's peak moves ≤ 3 % for ±1 % of the PGA: {moves:?}"
        );
        assert!(err.abs() <= 0.05, "peak off Housner's by {err}");
        assert!(
            err.abs() <= regression,
            "peak error {err} beyond the regression bound {regression} (find what changed)"
        );
    }
    err
}

/// The 0.4 × 1.2 m column under Friuli at every level the rule admits. Measured (deformable
/// block, Δt 1 ms): 0.7 / 0.8 / 0.9 g +0.12 / +0.10 / +0.11 % (regression bounds 5×, rounded up
/// to 1 %: the impact law's and the located impacts' own changes move these by ~0.5 %);
/// 0.5 / 0.6 / 1.0 g left out by the rule (Housner +48 / −25 %, −1.2 / −3.3 %, +5.7 / −11.8 %
/// for ∓1 % of the PGA; with impacts located in the reference, session 33: +43 / −29 %,
/// −1.9 / −4.1 %, +5.7 / −11.8 %, and the engine there +1.6, +4.7, −1.1 % off its peak).
#[test]
fn squat_column_friuli_every_admitted_level() {
    let (verdicts, peaks) = check_levels(
        &COLUMNS[0],
        "friuli-1976-tolmezzo-000.at2",
        &[(0.7, 0.01), (0.8, 0.01), (0.9, 0.01)],
    );
    for p in [0.7, 0.8, 0.9] {
        assert!(peaks.contains(&p), "the rule must admit {p} g: {peaks:?}");
    }
    assert_eq!(verdicts.len(), 8, "verdicts checked at {verdicts:?}");
}

/// Northridge at 0.5 g topples the 0.4 × 1.2 m column (Housner's verdict the same at ±3 %).
#[test]
fn squat_column_northridge_falls_like_housner() {
    check_point(
        &COLUMNS[0],
        "northridge-1994-mulholland-009.at2",
        0.5,
        Some(0.05),
    );
}

/// The slender column under Friuli at 0.3 g: measured −1.94 % (tolerance binds).
#[test]
fn slender_column_friuli_within_5pct() {
    check_point(&COLUMNS[1], "friuli-1976-tolmezzo-000.at2", 0.3, Some(0.05));
}

/// The rocking step control (`SimParams::rocking_velocity_change`, off by default: see its
/// default's comment) does what it says: the 0.4 × 1.2 m column under Friuli at 0.6 g, with the
/// control at c = 0.005, never steps longer than c·Ω/θ̈_g while it rocks (|θ̇| > 0.01 rad/s, so
/// Ω is above the 1e-3 rad/s floor), with Ω ≤ the largest |θ̇| so far and
/// θ̈_g = 3·g·(b cos θ − h sin |θ|)/(4·R²) the closed form of gravity's angular acceleration
/// about a corner of a b × h half-size rectangle turned by θ (R² = b² + h²); the bound never
/// goes below 5 % of Δt. Margin 1e-6: the deformable block's strain (~1e-7) changes b and h.
#[test]
fn rocking_step_control_bounds_the_step() {
    use ashlar::scene::scene_from_value;
    use ashlar::simulation::Simulation;
    let col = &COLUMNS[0];
    let c = 0.005;
    let params = SimParams {
        rocking_velocity_change: Some(c),
        ..SimParams::default()
    };
    let m = sr::load_record(&records_dir(), "friuli-1976-tolmezzo-000.at2", 0.6).expect("record");
    let scene = scene_from_value(&sr::column_scene(col, &json!({}))).expect("scene");
    let dt0 = scene.control.time_step;
    let mut sim = Simulation::new(&scene, &m, params);
    let (mut peak_w, mut rocking_steps) = (0.0f64, 0);
    while sim.time() < 7.0 {
        let w = sim.block_velocity(1)[2].abs();
        peak_w = peak_w.max(w);
        let th = sim.geoms()[1].rotation.abs();
        let theta_g = 3.0 * sr::G * (col.b * th.cos() - col.h * th.sin())
            / (4.0 * (col.b * col.b + col.h * col.h));
        let dt = sim.step(7.0 - sim.time()).expect("step");
        if w > 0.01 {
            rocking_steps += 1;
            let bound = (c * peak_w / theta_g).max(0.05 * dt0);
            assert!(
                dt <= bound * (1.0 + 1e-6),
                "t = {}: step {dt} beyond the rocking bound {bound} (|θ̇| {w}, peak {peak_w})",
                sim.time()
            );
        }
    }
    assert!(
        rocking_steps > 1000,
        "the column rocked ({rocking_steps} steps)"
    );
    assert!(peak_w > 0.3, "the column rocked (peak |θ̇| {peak_w})");
}
