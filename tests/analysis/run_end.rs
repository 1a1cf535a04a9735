//! The end of a run (docs/run-end.md): a run goes on after its duration until the structure
//! has settled, so a column left past its tipping angle by a short burst ends toppled, as
//! Housner's equation (integrated here by an independent RK4) says; a structure still moving
//! at the end is never "stable"; a record longer than the run is reported.
use crate::common;

use ashlar::analysis::run::{run, RunOptions, Summary};
use ashlar::analysis::run_end::RunEndParams;
use ashlar::motion::{from_json, GroundMotion};
use ashlar::scene::{ModelChoice, Scene};
use common::{parse, Column, G};
use serde_json::json;
use std::sync::Mutex;

/// Half width and half height of the column (m): the 0.4 × 1.2 m column of
/// examples/column.json, α = atan(1/3) = 18.43°.
const B: f64 = Column::SEED.half_width;
const H: f64 = Column::SEED.half_height;
/// The burst: one cycle of a 1 s sine of 4.5 m/s² (0.46 g).
const AMPLITUDE: f64 = 4.5;
const PERIOD: f64 = 1.0;

/// The column on a 2 m base, friction 60° (μ = 1.73, far above tan α and the friction demand
/// of the fall: the column rocks, it does not slide), run for the burst's length only.
fn column(model: ModelChoice) -> Scene {
    let mut scene = parse(
        &Column::SEED
            .friction(60.0)
            .json(json!({ "duration": PERIOD })),
    );
    scene.control.model = model;
    scene
}

fn burst() -> GroundMotion {
    from_json(&json!({ "horizontal": { "pulse": {
        "shape": "sine", "amplitude": AMPLITUDE, "period": PERIOD, "cycles": 1.0, "units": "m/s2" } } }))
    .expect("pulse")
}

fn ground(t: f64) -> f64 {
    if (0.0..=PERIOD).contains(&t) {
        AMPLITUDE * (2.0 * std::f64::consts::PI * t / PERIOD).sin()
    } else {
        0.0
    }
}

/// Housner's equation of the rectangular column (θ counter-clockwise, ü_g along +x):
/// θ̈ = −p² [sgn θ · sin(α − |θ|) − (ü_g/g) cos(α − |θ|)], p² = 3g/(4R), with his
/// angular-momentum impact law ω⁺ = (1 − 1.5 sin²α) ω⁻ when θ crosses 0. Classic RK4 at 0.1 ms,
/// onsets and impacts located to the step. Returns θ (rad) at `at` and whether |θ| ever
/// exceeds 30° before `until`.
fn housner(at: f64, until: f64) -> (f64, bool) {
    let r = (B * B + H * H).sqrt();
    let alpha = (B / H).atan();
    let p2 = 3.0 * G / (4.0 * r);
    let e = 1.0 - 1.5 * alpha.sin().powi(2);
    let acc = |t: f64, th: f64, side: f64| {
        let s = if th == 0.0 { side } else { th.signum() };
        -p2 * (s * (alpha - th.abs()).sin() - ground(t) / G * (alpha - th.abs()).cos())
    };
    let h = 1e-4;
    let (mut t, mut th, mut w) = (0.0f64, 0.0f64, 0.0f64);
    let mut side = 0.0; // 0: at rest; ±1: rocking on that side
    let mut at_value = f64::NAN;
    let mut toppled = false;
    while t < until {
        if (t - at).abs() < 0.5 * h {
            at_value = th;
        }
        if side == 0.0 {
            let a = ground(t) / G;
            if a.abs() > alpha.tan() {
                side = a.signum();
            } else {
                t += h;
                continue;
            }
        }
        let f = |t: f64, y: [f64; 2]| [y[1], acc(t, y[0], side)];
        let k1 = f(t, [th, w]);
        let k2 = f(t + h / 2.0, [th + h / 2.0 * k1[0], w + h / 2.0 * k1[1]]);
        let k3 = f(t + h / 2.0, [th + h / 2.0 * k2[0], w + h / 2.0 * k2[1]]);
        let k4 = f(t + h, [th + h * k3[0], w + h * k3[1]]);
        let th1 = th + h / 6.0 * (k1[0] + 2.0 * k2[0] + 2.0 * k3[0] + k4[0]);
        let w1 = w + h / 6.0 * (k1[1] + 2.0 * k2[1] + 2.0 * k3[1] + k4[1]);
        t += h;
        if th1 * side < 0.0 {
            // Impact: the other corner lands; rest when the rebound is negligible.
            th = 0.0;
            w = e * w1;
            side = -side;
            if w.abs() < 1e-5 {
                side = 0.0;
                w = 0.0;
            }
        } else {
            th = th1;
            w = w1;
        }
        if th.abs() > 30f64.to_radians() {
            toppled = true;
            break;
        }
    }
    (at_value, toppled)
}

fn run_column(model: ModelChoice, end: Option<RunEndParams>) -> (Summary, f64) {
    let scene = column(model);
    let at_end = Mutex::new(f64::NAN);
    let record = |f: &ashlar::record::Frame| {
        if (f.time - PERIOD).abs() < 1e-9 {
            *at_end.lock().expect("lock") = f.blocks[1].rotation;
        }
    };
    let opts = RunOptions {
        on_frame: Some(&record),
        run_end: end,
        ..Default::default()
    };
    let out = run(&scene, &burst(), &opts).expect("run");
    let th = *at_end.lock().expect("lock");
    (out.summary, th)
}

#[test]
fn a_column_left_past_its_tipping_angle_ends_toppled_as_housner_says() {
    let alpha = (B / H).atan();
    let (th_ref, toppled_ref) = housner(PERIOD, 20.0);
    // The case is the one reported (docs/run-end.md): at the end of the burst the column is past its tipping
    // angle but below the 30° of "toppled"; Housner says it falls.
    assert!(
        th_ref.abs() > alpha && th_ref.abs() < 30f64.to_radians(),
        "θ(end of burst) = {th_ref}"
    );
    assert!(toppled_ref, "Housner: the column falls after the burst");

    // The reduced rocking model (forced: late in the fall the pivot's friction demand exceeds
    // even μ = 1.73, a case `auto` hands to the full engine): the state at the end of the burst
    // agrees with the RK4 within 2e-3 rad (the RK4 places the onset to within its 0.1 ms step, which at the
    // ≤ 2 rad/s of this swing is ≤ 2e-4 rad; ten times that is still 0.6 % of the angle), and the
    // run goes on until the column lies on its side.
    let (s, th) = run_column(ModelChoice::Rocking, None);
    eprintln!(
        "Housner θ({PERIOD}) = {th_ref:.5}, reduced {th:.5}; reduced ends at {:.3} s",
        s.simulated_time
    );
    assert_eq!(s.model, "rocking", "{}", s.model_reason);
    assert!(
        (th - th_ref).abs() < 2e-3,
        "reduced θ({PERIOD}) = {th}, Housner {th_ref}"
    );
    assert!(s.blocks[0].toppled, "{s:?}");
    assert_eq!(s.failure_mode, "toppling");
    assert!(s.settled);
    assert!(s.simulated_time > PERIOD, "{}", s.simulated_time);

    // The full engine: the same verdict (the column falls, off the plinth).
    let (s, th) = run_column(ModelChoice::Dda, None);
    eprintln!(
        "dda θ({PERIOD}) = {th:.5}; ends at {:.3} s after {} steps, events {:?}",
        s.simulated_time, s.steps, s.events
    );
    assert!(
        th.signum() == th_ref.signum() && th.abs() > alpha,
        "dda θ({PERIOD}) = {th}"
    );
    assert!(s.blocks[0].toppled, "{s:?}");
    assert!(s.failure_mode.contains("toppling"), "{}", s.failure_mode);
    assert!(s.settled, "{s:?}");
}

#[test]
fn a_structure_still_moving_at_the_end_is_undecided_not_stable() {
    // No continuation: the run stops at the end of the burst with the column at 20°, turning.
    let end = RunEndParams {
        max_extension: 0.0,
        ..Default::default()
    };
    for model in [ModelChoice::Rocking, ModelChoice::Dda] {
        let (s, _) = run_column(model, Some(end));
        assert!(!s.settled, "{model:?}: {s:?}");
        assert!(!s.blocks[0].toppled);
        assert_eq!(s.failure_mode, "undecided", "{model:?}");
        assert!((s.simulated_time - PERIOD).abs() < 1e-9);
    }
}

#[test]
fn a_run_shorter_than_the_record_is_reported() {
    let mut scene = column(ModelChoice::Auto);
    scene.control.duration = Some(0.4);
    let s = run(&scene, &burst(), &RunOptions::default())
        .expect("run")
        .summary;
    let t = s.diagnostics.record_truncated.expect("truncation reported");
    assert_eq!((t.record_duration, t.run_duration), (PERIOD, 0.4));
    let text = serde_json::to_string(&s).expect("json");
    assert!(text.contains("\"record_truncated\""), "{text}");
    // The default duration (record + 2 s) covers the record.
    scene.control.duration = None;
    let s = run(&scene, &burst(), &RunOptions::default())
        .expect("run")
        .summary;
    assert!(s.diagnostics.record_truncated.is_none());
}
