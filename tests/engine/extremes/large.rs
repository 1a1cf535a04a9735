//! Extremes of size (the ~1000-block wall and pile) and through the run entry point (what
//! the CLI and the service call).
use super::*;

// ---------------------------------------------------------------------------------------------
// Large models

/// ~1000-block dry-stone wall (20 courses × 50 blocks) at rest, then under 0.5 g: 20 steps
/// each (a step of the shaken wall takes ~1 s in the test profile on a loaded 2-core machine), energy and penetration checked every 5 steps (the O(n²)-pruned penetration
/// measure is the expensive part here).
#[test]
fn thousand_block_wall() {
    use ashlar::scene::generate::{running_bond_wall, WallParams};
    let spec = running_bond_wall(&WallParams {
        courses: 20,
        blocks_per_course: 50,
        block_length: 0.4,
        block_height: 0.2,
        ..Default::default()
    });
    let mut v = serde_json::to_value(&spec).expect("spec serializes");
    v["control"] = json!({ "time_step": 1e-3, "duration": 0.05, "max_steps": 20 });
    let scene = parse(&v);
    assert!(scene.blocks.len() >= 1000, "{} blocks", scene.blocks.len());
    for (name, pga) in [
        ("1010-block wall at rest", 0.0),
        ("1010-block wall, 0.5 g", 0.5),
    ] {
        let k = Knobs { pga_g: pga, ..k() };
        let o = drive(name, &scene, &motion(&k), 5);
        if explore() {
            print_row(&o);
        } else {
            check(&o, Complete);
        }
    }
}

/// ~1000 loose blocks dropped in a grid with gaps onto a floor: many contacts open and close at
/// once: the lowest row lands after ~14 ms, the run stops at 30 ms or 60 steps.
#[test]
fn thousand_block_pile() {
    let mut blocks = vec![
        json!({ "id": "floor", "material": "m", "fixed": true, "vertices": rect(-1.0, -0.5, 42.0, 0.5) }),
    ];
    for r in 0..25 {
        for c in 0..40 {
            let x = c as f64 * 1.0 + if r % 2 == 1 { 0.3 } else { 0.0 };
            let y = 0.001 + r as f64 * 0.502;
            blocks.push(json!({ "id": format!("p{r}_{c}"), "material": "m", "block_model": "rigid", "vertices": rect(x, y, 0.8, 0.5) }));
        }
    }
    let k = Knobs {
        duration: 0.03,
        budget: 60,
        pga_g: 0.0,
        ..k()
    };
    let scene = parse(&scene_with(&k, Value::Array(blocks)));
    let o = drive("1000-block pile dropped", &scene, &motion(&k), 10);
    if explore() {
        print_row(&o);
    } else {
        check(&o, Complete);
    }
}

// ---------------------------------------------------------------------------------------------
// Through the run entry point (what the CLI and the service call)

/// The step budget stops a run cleanly (a shortened but valid summary, the reason given), every
/// number in the summary is finite, and an engine diagnostic arrives as the run's error message.
#[test]
fn run_entry_point_budget_summary_and_diagnostic() {
    use ashlar::analysis::run::{run, RunError, RunOptions};
    let k = Knobs {
        dt: 1e-5,
        adaptive: false,
        duration: 10.0,
        budget: 300,
        pga_g: 5.0,
        ..k()
    };
    let scene = parse(&stack(&k));
    let out = run(&scene, &motion(&k), &RunOptions::default()).expect("budgeted run");
    let s = &out.summary;
    println!(
        "| run entry point, budget 300 steps | stopped: {:?} | – | – | {} | {:.3e} s | {:.2} s |",
        s.stopped_reason, s.steps, s.simulated_time, s.wall_time_s
    );
    assert_eq!(s.steps, 300);
    assert!(
        s.stopped_reason
            .as_deref()
            .is_some_and(|r| r.contains("control.max_steps")),
        "{:?}",
        s.stopped_reason
    );
    let text = serde_json::to_string(s).expect("summary serializes");
    let v: Value = serde_json::from_str(&text).expect("summary is JSON");
    assert_all_finite(&v, "summary");

    let soft = Knobs {
        penalty: Some(1e4),
        ..Knobs::default()
    };
    let scene = parse(&stack(&soft));
    match run(&scene, &motion(&soft), &RunOptions::default()) {
        Err(RunError::Simulation(e)) => {
            let m = e.to_string();
            println!("| run entry point, penalty 1e4 N/m | error: {m} | – | – | – | – | – |");
            assert_useful_diagnostic("run entry point", &m);
        }
        other => panic!("expected a simulation error, got {other:?}"),
    }
}

/// serde_json writes non-finite floats as null: a null where a number belongs is a NaN leak.
fn assert_all_finite(v: &Value, path: &str) {
    match v {
        Value::Number(n) => assert!(n.as_f64().is_some_and(f64::is_finite), "{path} = {n}"),
        Value::Array(a) => a
            .iter()
            .enumerate()
            .for_each(|(i, x)| assert_all_finite(x, &format!("{path}[{i}]"))),
        Value::Object(m) => m.iter().for_each(|(k, x)| {
            if !(x.is_null() && ["stopped_reason"].contains(&k.as_str())) {
                assert!(!x.is_null(), "{path}.{k} is null (a non-finite number?)");
                assert_all_finite(x, &format!("{path}.{k}"));
            }
        }),
        _ => {}
    }
}

/// Found when the default impact law became Newton's with e = 0: the needle of
/// `hard_combinations` (1:500, friction 89°, 50 g) under the default law completed its 0.2 s
/// with E − E₀ − W_ground = 4.03 × the energy scale. Gone since impacts are located in time
/// and a landing corner is found before it lands (docs/restitution.md): measured −1.2e-9 of
/// the scale, penetration 2.1e-7 of the block. On the rocking column the mechanism was seen
/// (the impulse at the step start stopped the corner up to a step's travel above its edge, or
/// it was found already 85 µm deep and the contact threw the block off); on the needle it was
/// not isolated. The bound is the suite's own (`ENERGY_TOL`).
#[test]
fn needle_under_the_default_impact_law_keeps_energy_bounded() {
    run_cases(vec![(
        "needle 1:500 + friction 89° + 50 g, default impact law",
        Knobs {
            width: 0.01,
            height: 5.0,
            friction_deg: 89.0,
            pga_g: 50.0,
            ..k()
        },
        Complete,
    )]);
}
