//! Model selection (`control.model`, docs/format.md §1) and the combined sliding–rocking
//! first-motion check of the reduced models.
//!
//! The first-motion check is verified against the analytic chart of a block on an incline
//! under a constant horizontal load (Yeung 1991; derived in tests/engine/failure_modes.rs, drawn by
//! `analysis::reference::first_motion_chart`): stable, sliding, toppling (Yeung's dynamic criterion, pivot sticking), and
//! sliding-and-toppling, which no reduced model represents, so `auto` must hand it to the full
//! engine. Binary agreement in every case, each case ≥ 3° from every chart boundary.
use crate::common;
use ashlar::analysis::reduced::{qualify, Modes, Reduced, ReducedParams};
use ashlar::analysis::reference::{first_motion_chart as chart, FirstMotion as Mode};
use ashlar::analysis::run::{run, RunOptions};
use ashlar::motion::{GroundMotion, Sampled, Signal};
use ashlar::scene::generate::{running_bond_wall, WallParams};
use common::*;
use serde_json::{json, Value};

fn column(control: Value) -> Value {
    Column::SEED.default_model().json(control)
}

fn pulse(a: f64) -> GroundMotion {
    rocking_pulse(a)
}

#[test]
fn auto_runs_the_rocking_model_on_a_column_and_says_why() {
    let s = run(
        &parse(&column(json!({ "duration": 2.0, "model": "auto" }))),
        &pulse(5.0),
        &RunOptions::default(),
    )
    .expect("run")
    .summary;
    assert_eq!(s.model, "rocking");
    assert!(
        s.model_reason.contains("auto") && s.model_reason.contains("Housner"),
        "{}",
        s.model_reason
    );
    // Housner's e for b/h = 1/3 (1 − 1.5 sin²α = 0.85), to round-off.
    let alpha = (0.2f64 / 0.6).atan();
    let e = s.diagnostics.restitution.expect("restitution reported");
    assert!((e - (1.0 - 1.5 * alpha.sin().powi(2))).abs() < 1e-12);
}

/// `auto` is the default (chosen from docs/accuracy-vs-speed.md); `"dda"` forces the engine.
#[test]
fn auto_is_the_default_and_dda_forces_the_engine() {
    let summary = |control: Value| {
        run(
            &parse(&column(control)),
            &pulse(5.0),
            &RunOptions::default(),
        )
        .expect("run")
        .summary
    };
    let default = summary(json!({ "duration": 0.1 }));
    assert_eq!(default.model, "rocking", "{}", default.model_reason);
    assert!(
        default.model_reason.contains("auto"),
        "{}",
        default.model_reason
    );
    let forced = summary(json!({ "duration": 0.1, "model": "dda" }));
    assert_eq!(forced.model, "dda");
    assert!(
        forced.model_reason.contains("\"dda\""),
        "{}",
        forced.model_reason
    );
}

#[test]
fn auto_falls_back_to_dda_on_a_wall_naming_why() {
    let spec = running_bond_wall(&WallParams {
        courses: 2,
        blocks_per_course: 2,
        ..Default::default()
    });
    let mut v = serde_json::to_value(&spec).expect("json");
    // Explicit "auto" and the default (which is "auto") alike.
    for control in [
        json!({ "duration": 0.05, "model": "auto" }),
        json!({ "duration": 0.05 }),
    ] {
        v["control"] = control;
        let s = run(&parse(&v), &pulse(1.0), &RunOptions::default())
            .expect("run")
            .summary;
        assert_eq!(s.model, "dda");
        assert!(s.model_reason.contains("free blocks"), "{}", s.model_reason);
    }
}

#[test]
fn forced_rocking_on_a_wall_is_a_clear_error() {
    let spec = running_bond_wall(&WallParams {
        courses: 2,
        blocks_per_course: 2,
        ..Default::default()
    });
    let mut v = serde_json::to_value(&spec).expect("json");
    v["control"] = json!({ "duration": 0.05, "model": "rocking" });
    let e = run(&parse(&v), &pulse(1.0), &RunOptions::default()).expect_err("must refuse");
    let msg = e.to_string();
    assert!(
        msg.contains("control.model") && msg.contains("rocking") && msg.contains("free blocks"),
        "{msg}"
    );
}

#[test]
fn cohesive_joint_and_gap_disqualify() {
    let mut v = column(json!({ "duration": 0.05, "model": "auto" }));
    v["joints"]["j"]["cohesion"] = json!(1000.0);
    let s = run(&parse(&v), &pulse(1.0), &RunOptions::default())
        .expect("run")
        .summary;
    assert_eq!(s.model, "dda");
    assert!(s.model_reason.contains("cohesion"), "{}", s.model_reason);
    let mut v = column(json!({ "duration": 0.05, "model": "sliding" }));
    v["blocks"][1]["vertices"] = json!([[-0.2, 0.01], [0.2, 0.01], [0.2, 1.21], [-0.2, 1.21]]);
    let e = run(&parse(&v), &pulse(1.0), &RunOptions::default()).expect_err("gap");
    assert!(e.to_string().contains("does not rest"), "{e}");
}

#[test]
fn reduced_run_writes_the_same_outputs_as_dda() {
    let dir = std::env::temp_dir().join(format!("ashlar-reduced-out-{}", std::process::id()));
    // Frames up to the duration only (no continuation after it; docs/run-end.md).
    let opts = RunOptions {
        out_dir: Some(&dir),
        run_end: Some(ashlar::analysis::run_end::RunEndParams {
            max_extension: 0.0,
            ..Default::default()
        }),
        ..Default::default()
    };
    let s = run(
        &parse(&column(
            json!({ "duration": 1.0, "model": "rocking", "output_interval": 0.1 }),
        )),
        &pulse(5.0),
        &opts,
    )
    .expect("run")
    .summary;
    let csv = std::fs::read_to_string(dir.join("histories.csv")).expect("histories");
    let lines: Vec<&str> = csv.lines().collect();
    assert!(
        lines[0].starts_with("time_s,column.x_m,column.y_m,column.rotation_rad"),
        "{}",
        lines[0]
    );
    assert_eq!(lines.len(), 1 + 11, "header and frames at 0, 0.1, …, 1.0 s");
    let summary: Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("summary.json")).expect("summary"))
            .expect("json");
    assert_eq!(summary["model"], "rocking");
    assert_eq!(summary["blocks"][0]["id"], "column");
    let mcap = std::fs::read(dir.join("trajectory.mcap")).expect("mcap");
    assert!(mcap.starts_with(b"\x89MCAP0\r\n"));
    assert!(s.completed);
    std::fs::remove_dir_all(&dir).ok();
}

// ---- First motion against Yeung's chart ----

/// (α, k, δ, φ) in degrees / g; the reduced models' verdict on the first motion.
fn reduced_first_motion(alpha: f64, k: f64, delta: f64, phi: f64) -> Result<Mode, String> {
    let a = alpha.to_radians();
    let d = [a.cos(), -a.sin()];
    let n = [a.sin(), a.cos()];
    let l = 0.6;
    let (w, h) = (l * delta.to_radians().sin(), l * delta.to_radians().cos());
    let p = |s: f64, t: f64| json!([s * d[0] + t * n[0], s * d[1] + t * n[1]]);
    let blocks = json!([
        { "id": "slope", "material": "stone", "fixed": true, "vertices": [p(-1.5, 0.0), p(2.5, 0.0), p(2.5, -0.5), p(-1.5, -0.5)] },
        { "id": "block", "material": "stone", "block_model": "rigid", "vertices": [p(0.0, 0.0), p(w, 0.0), p(w, h), p(0.0, h)] },
    ]);
    let scene = parse(&scene_json(
        blocks,
        phi,
        json!({ "duration": 0.3, "model": "auto" }),
    ));
    let motion = if k == 0.0 {
        GroundMotion::none()
    } else {
        GroundMotion::horizontal(Signal::Sampled(Sampled::new(0.01, vec![-k * G; 101])))
    };
    let params = ReducedParams::default();
    let block = qualify(&scene, &params).map_err(|e| e.to_string())?;
    let mut m = Reduced::new(block, &motion, params, Modes::Auto);
    // First motion, as in tests/engine/failure_modes.rs: decided once the corner slip or L·|θ|
    // exceeds 1 mm (later changes of mode are not what the chart describes).
    let mut t = 0.0;
    while t < 0.3 - 1e-12 {
        t += 1e-3;
        if let Err(v) = m.advance(t) {
            return if v.what.contains("together") {
                Ok(Mode::SlidingToppling)
            } else {
                Err(v.what)
            };
        }
        let (_, rot, _, _) = m.kinematics();
        if m.slid > 1e-3 || l * rot.abs() > 1e-3 {
            break;
        }
    }
    Ok(match (m.stats.first_rocking, m.stats.first_sliding) {
        (None, None) => Mode::Stable,
        (Some(_), None) => Mode::Toppling,
        (None, Some(_)) => Mode::Sliding,
        (Some(_), Some(_)) => Mode::SlidingToppling,
    })
}

#[test]
fn first_motion_matches_yeungs_chart() {
    // Cases chosen ≥ 3° from every boundary of the chart (checked below on a lattice).
    let cases = [
        (10.0, 0.0, 30.0, 40.0),
        (20.0, 0.1, 40.0, 35.0),
        (25.0, 0.0, 45.0, 15.0),
        (30.0, 0.2, 50.0, 20.0),
        (20.0, 0.0, 10.0, 60.0),
        (30.0, 0.3, 15.0, 70.0),
        (35.0, 0.2, 12.0, 55.0),
        (30.0, 0.5, 6.0, 15.0),
        (35.0, 0.5, 14.0, 20.0),
        (45.0, 0.2, 6.0, 15.0),
    ];
    let mut seen = std::collections::HashSet::new();
    for (alpha, k, delta, phi) in cases {
        let psi = alpha + f64::atan(k).to_degrees();
        let r = f64::to_radians;
        let expected = chart(r(psi), r(delta), r(phi));
        for dp in [-3.0, 0.0, 3.0] {
            for dd in [-3.0, 0.0, 3.0] {
                for df in [-3.0, 0.0, 3.0] {
                    assert_eq!(
                        chart(r(psi + dp), r(delta + dd), r(phi + df)),
                        expected,
                        "case too close to a boundary: {alpha} {k} {delta} {phi}"
                    );
                }
            }
        }
        let got = reduced_first_motion(alpha, k, delta, phi).expect("reduced run");
        eprintln!(
            "α={alpha} k={k} δ={delta} φ={phi} (ψ={psi:.1}): chart {expected:?}, reduced {got:?}"
        );
        assert_eq!(got, expected, "α={alpha} k={k} δ={delta} φ={phi}");
        seen.insert(expected as u8);
    }
    assert_eq!(seen.len(), 4, "every mode of the chart is exercised");
}

/// `ashlar run --model` overrides the scene's `control.model`; a bad name is refused naming
/// the flag and the accepted values.
#[test]
fn cli_model_flag_overrides_the_default() {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
    let out = std::env::temp_dir().join(format!("ashlar-model-flag-{}", std::process::id()));
    let run = |extra: &[&str]| {
        std::process::Command::new(env!("CARGO_BIN_EXE_ashlar"))
            .arg("run")
            .arg(root.join("examples/column.json"))
            // No record: the example sets no duration (docs/run-end.md).
            .args(["--duration", "1", "--no-trajectory", "--out"])
            .arg(&out)
            .args(extra)
            .output()
            .expect("run ashlar")
    };
    let model_of = |o: std::process::Output| {
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        let v: Value = serde_json::from_slice(&o.stdout).expect("summary json");
        v["model"].as_str().unwrap_or_default().to_string()
    };
    assert_eq!(model_of(run(&[])), "rocking");
    assert_eq!(model_of(run(&["--model", "dda"])), "dda");
    let bad = run(&["--model", "fem"]);
    assert!(!bad.status.success());
    let msg = String::from_utf8_lossy(&bad.stderr);
    assert!(msg.contains("--model") && msg.contains("dda"), "{msg}");
    std::fs::remove_dir_all(&out).ok();
}
