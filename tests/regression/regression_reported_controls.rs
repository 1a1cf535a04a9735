//! Regression: `summary.json` reported controls that did not run and numbers without units.
//! `examples/column.json` (a column whose own `block_model` is `"rigid"`, under the default
//! `control.block_model` `"deformable"`) reported `control.block_model: "deformable"`; the
//! reduced model reported `diagnostics.penalty_stiffness: 0.0` (no springs ran), as did nothing
//! distinguish a dual-solver run; `simulated_time` read 2.9999999999999925. Each check below is
//! exact: these are reported settings and a rounding to the nanosecond, not computed physics.
use ashlar::analysis::run::{run, RunOptions};
use ashlar::analysis::run_end::RunEndParams;
use ashlar::motion::from_json;
use ashlar::scene::parse_scene;
use serde_json::{json, Value};

fn column(control: Value) -> Value {
    let mut v: Value =
        serde_json::from_str(include_str!("../../examples/column.json")).expect("scene json");
    v["control"]["duration"] = json!(3.0);
    for (k, x) in control.as_object().expect("object") {
        v["control"][k] = x.clone();
    }
    v
}

/// The run's summary as written to summary.json. The scene's duration is fixed at 3 s and the
/// settling continuation is off, so that the run ends at exactly 3000 × 1 ms of accumulated
/// steps (the rounding under test), not at whatever time the column settles.
fn summary(scene: &Value) -> Value {
    let scene = parse_scene(&scene.to_string()).expect("valid scene");
    let motion: Value =
        serde_json::from_str(include_str!("../../examples/half-sine-pulse.json")).expect("json");
    let opts = RunOptions {
        run_end: Some(RunEndParams {
            max_extension: 0.0,
            ..Default::default()
        }),
        ..Default::default()
    };
    let out = run(&scene, &from_json(&motion).expect("motion"), &opts).expect("run");
    serde_json::to_value(&out.summary).expect("serialize")
}

#[test]
fn the_reduced_model_reports_a_rigid_block_and_no_engine_controls() {
    let s = summary(&column(json!({})));
    assert_eq!(s["model"], "rocking");
    assert_eq!(s["format"], "ashlar.run/2");
    assert_eq!(
        s["control"],
        // `restitution` is honoured by the reduced models (`"housner"`, 0) or sends the scene
        // to the engine, so it is reported with what ran.
        json!({"block_model": "rigid", "duration": 3.0, "model": "auto", "output_interval": 0.01,
               "restitution": "housner"})
    );
    let d = s["diagnostics"].as_object().expect("diagnostics");
    assert!(!d.contains_key("penalty_stiffness"), "{d:?}");
    assert!(!d.contains_key("open_close_iterations_mean"), "{d:?}");
    assert_eq!(s["simulated_time"], json!(3.0));
    assert_eq!(s["units"]["blocks"]["max_rotation"], "rad");
    assert_eq!(s["units"]["pga"], "m/s2");
}

/// A scene without a duration runs for the record's length + 2 s (the half-sine pulse: 0.5 s
/// long, so 2.5 s): that is the duration reported, not the scene's unset `null`.
#[test]
fn the_duration_reported_is_the_one_that_ran() {
    let mut scene = column(json!({}));
    scene["control"]
        .as_object_mut()
        .expect("control")
        .remove("duration");
    let s = summary(&scene);
    assert_eq!(s["control"]["duration"], json!(2.5));
}

#[test]
fn the_engine_reports_the_block_model_the_blocks_used() {
    let s = summary(&column(json!({"model": "dda"})));
    assert_eq!(s["model"], "dda");
    assert_eq!(s["control"]["block_model"], "rigid");
    assert_eq!(s["control"]["penalty_stiffness"], "auto");
    assert!(s["diagnostics"]["penalty_stiffness"]
        .as_f64()
        .is_some_and(|k| k > 0.0));
    // 3 s of adaptive steps: the accumulated time rounded to the nanosecond is exactly 3.
    assert_eq!(s["simulated_time"], json!(3.0));
    // A free block without its own model takes control.block_model; two different models are
    // "mixed".
    // (deformable by name: "auto", the default, would make this stone cap rigid too).
    let mut two = column(json!({"model": "dda", "duration": 0.02, "block_model": "deformable"}));
    let mut cap = two["blocks"][1].clone();
    cap["id"] = json!("cap");
    cap.as_object_mut().expect("block").remove("block_model");
    cap["vertices"] = json!([[-0.2, 1.2], [0.2, 1.2], [0.2, 1.4], [-0.2, 1.4]]);
    two["blocks"].as_array_mut().expect("blocks").push(cap);
    assert_eq!(summary(&two)["control"]["block_model"], "mixed");
}

#[test]
fn the_dual_solver_reports_no_penalty_springs() {
    let s = summary(&column(
        json!({"model": "dda", "contact_solver": "dual", "duration": 0.05}),
    ));
    assert_eq!(s["control"]["contact_solver"], "dual");
    assert!(
        s["control"].get("penalty_stiffness").is_none(),
        "{}",
        s["control"]
    );
    let d = s["diagnostics"].as_object().expect("diagnostics");
    assert!(!d.contains_key("penalty_stiffness"), "{d:?}");
    assert!(!d.contains_key("open_close_iterations_mean"), "{d:?}");
    assert!(d.contains_key("dual_loose_solves"), "{d:?}");
}
