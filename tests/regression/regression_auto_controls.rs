//! What broke: `"model": "auto"` ran the reduced models while dropping controls of the scene
//! that change the physics. With `kinetic_damping_rate: 5` on a block pushed along a
//! frictionless floor, `auto` ran the reduced sliding model undamped (1.0000 m where
//! `"model": "dda"` gives the damped 0.32 m). And for squat blocks `model_reason` printed a
//! negative restitution (e = −0.4851) as if Housner's impact law applied.
//!
//! Now every physics control is either represented by the reduced model or sends the scene to
//! the full engine with the reason (one test per control below; the numerical controls of the
//! engine are reported as not applying), and a squat block's impact is said to end the rocking.
use crate::common;

use ashlar::analysis::run::{run, RunError, RunOptions, Summary};
use ashlar::analysis::run_end::RunEndParams;
use ashlar::motion::GroundMotion;
use ashlar::scene::{ModelChoice, Scene};
use common::{parse, rect, scene_json};
use serde_json::{json, Value};

/// Initial speed of the pushed block, m/s, and the run's duration, s.
const V0: f64 = 1.0;
const T: f64 = 1.0;

/// A 0.5 × 0.5 m block pushed at `V0` along a frictionless fixed floor, with `control`.
fn pushed_block(control: Value) -> Scene {
    let mut v = scene_json(
        json!([
            { "id": "floor", "material": "stone", "fixed": true, "vertices": rect(-5.0, -1.0, 20.0, 0.0) },
            { "id": "block", "material": "stone", "block_model": "rigid", "vertices": rect(0.0, 0.0, 0.5, 0.5) }
        ]),
        0.0,
        control,
    );
    v["initial"] = json!([{ "block": "block", "velocity": [V0, 0.0] }]);
    parse(&v)
}

/// Run without the continuation after the duration (the block on a frictionless floor only
/// stops through damping), so the distance is the one at `T`.
fn run_to_t(scene: &Scene, model: ModelChoice) -> Result<Summary, RunError> {
    let mut scene = scene.clone();
    scene.control.model = model;
    let opts = RunOptions {
        run_end: Some(RunEndParams {
            max_extension: 0.0,
            ..Default::default()
        }),
        no_trajectory: true,
        ..Default::default()
    };
    run(&scene, &GroundMotion::none(), &opts).map(|o| o.summary)
}

#[test]
fn kinetic_damping_sends_auto_to_the_engine() {
    let c = 5.0;
    let scene = pushed_block(json!({ "duration": T, "kinetic_damping_rate": c }));
    let auto = run_to_t(&scene, ModelChoice::Auto).expect("auto");
    let dda = run_to_t(&scene, ModelChoice::Dda).expect("dda");
    assert_eq!(auto.model, "dda", "{}", auto.model_reason);
    assert!(
        auto.model_reason.contains("kinetic_damping_rate"),
        "{}",
        auto.model_reason
    );
    let x = auto.blocks[0].final_displacement[0];
    assert_eq!(x, dda.blocks[0].final_displacement[0]);
    // Closed form of v̇ = −c v: x(T) = v0/c (1 − e^{−cT}) = 0.19865 m. The engine applies the
    // decay once per step (Δt = 1 ms), a first-order approximation: 1 % covers cΔt = 0.5 %.
    let exact = V0 / c * (1.0 - (-c * T).exp());
    assert!((x - exact).abs() < 1e-2 * exact, "{x} vs {exact}");
    // Undamped, the reduced model runs and slides V0·T.
    let free = run_to_t(&pushed_block(json!({ "duration": T })), ModelChoice::Auto).expect("run");
    assert_eq!(free.model, "sliding", "{}", free.model_reason);
    assert!((free.blocks[0].final_displacement[0] - V0 * T).abs() < 1e-9);
    // A forced reduced model refuses the control, naming it.
    let err = run_to_t(&scene, ModelChoice::Sliding).expect_err("refused");
    assert!(err.to_string().contains("kinetic_damping_rate"), "{err}");
}

#[test]
fn a_dynamic_factor_sends_auto_to_the_engine() {
    let scene = pushed_block(json!({ "duration": T, "dynamic_factor": 0.5 }));
    let auto = run_to_t(&scene, ModelChoice::Auto).expect("auto");
    let dda = run_to_t(&scene, ModelChoice::Dda).expect("dda");
    assert_eq!(auto.model, "dda", "{}", auto.model_reason);
    assert!(
        auto.model_reason.contains("dynamic_factor"),
        "{}",
        auto.model_reason
    );
    assert_eq!(
        auto.blocks[0].final_displacement,
        dda.blocks[0].final_displacement
    );
    // Velocity halved at every step: the block stops within a few steps, far short of V0·T.
    assert!(auto.blocks[0].final_displacement[0] < 0.01 * V0 * T);
    let err = run_to_t(&scene, ModelChoice::Rocking).expect_err("refused");
    assert!(err.to_string().contains("dynamic_factor"), "{err}");
}

#[test]
fn the_engine_numerical_controls_are_reported_as_not_applying() {
    let scene =
        pushed_block(json!({ "duration": T, "time_step": 1e-4, "integrator": "trapezoidal" }));
    let s = run_to_t(&scene, ModelChoice::Auto).expect("run");
    assert_eq!(s.model, "sliding");
    assert!(
        s.model_reason
            .contains("numerical controls the scene sets (time_step, integrator) do not apply"),
        "{}",
        s.model_reason
    );
}

#[test]
fn the_step_budget_binds_the_reduced_model_too() {
    let scene = pushed_block(json!({ "duration": T, "max_steps": 10 }));
    let s = run_to_t(&scene, ModelChoice::Auto).expect("run");
    assert_eq!(s.model, "sliding");
    assert!(!s.completed);
    assert!(
        s.stopped_reason
            .as_deref()
            .is_some_and(|r| r.contains("max_steps")),
        "{s:?}"
    );
}

#[test]
fn a_squat_block_is_not_given_a_negative_restitution() {
    // 1.2 × 0.5 m: α = atan(0.6/0.25) = 67.4°, 1 − 1.5 sin²α = −0.2781.
    let scene = parse(&scene_json(
        json!([
            { "id": "base", "material": "stone", "fixed": true, "vertices": rect(-2.0, -0.5, 2.0, 0.0) },
            { "id": "slab", "material": "stone", "block_model": "rigid", "vertices": rect(-0.6, 0.0, 0.6, 0.5) }
        ]),
        80.0,
        json!({ "duration": 0.5 }),
    ));
    let s = run(&scene, &GroundMotion::none(), &RunOptions::default())
        .expect("run")
        .summary;
    let r = &s.model_reason;
    assert!(r.contains("does not apply to a block this squat"), "{r}");
    assert!(r.contains("e = 0"), "{r}");
    assert!(!r.contains("e = -"), "{r}");
}
