//! Robustness of the scene and ground-motion JSON readers (docs/stability.md):
//! arbitrary bytes and mutated valid files never panic, and always yield either
//! - a valid model: `Simulation::new` accepts it and a few steps run, each either accepted with
//!   a finite state or refused with a typed diagnostic (never a silent NaN); or
//! - a clear error: a `SceneError` / `MotionError` naming a field (non-empty path and message).
//!
//! Mutations of the examples: numbers → NaN-like strings, huge, tiny, negative, zero; fields
//! removed or duplicated; vertex lists shuffled, truncated or given random coordinates; strings
//! swapped. 256 cases a property (a fixed seed, so CI is reproducible) keep the file to seconds.
use ashlar::motion::{self, GroundMotion};
use ashlar::scene::{parse_scene, Scene};
use ashlar::simulation::{SimParams, Simulation};
use proptest::prelude::*;
use proptest::test_runner::RngSeed;
use serde_json::{json, Value};

fn example(name: &str) -> Value {
    let text = std::fs::read_to_string(format!("{}/examples/{name}", env!("CARGO_MANIFEST_DIR")))
        .expect("example file");
    serde_json::from_str(&text).expect("example is JSON")
}

/// The valid scenes mutated: the two examples and a small generated wall.
fn seeds() -> Vec<Value> {
    let wall = ashlar::scene::generate::running_bond_wall(&ashlar::scene::generate::WallParams {
        courses: 2,
        blocks_per_course: 2,
        ..Default::default()
    });
    vec![
        example("column.json"),
        example("incline.json"),
        serde_json::to_value(&wall).expect("wall serializes"),
    ]
}

/// Steps run on every accepted scene: enough to detect contacts, assemble, solve and integrate
/// a few times; few enough that 256 cases stay fast.
const STEPS: usize = 5;

/// The contract for whatever `parse_scene` returns.
fn check_scene_result(text: &str) {
    match parse_scene(text) {
        Ok(scene) => run_a_few_steps(&scene),
        Err(e) => {
            assert!(!e.path.is_empty(), "error without a field: {e}");
            assert!(!e.message.is_empty(), "error without a message: {e}");
        }
    }
}

fn run_a_few_steps(scene: &Scene) {
    let mut sim = Simulation::new(scene, &GroundMotion::none(), SimParams::default());
    for _ in 0..STEPS {
        match sim.step(1.0) {
            Ok(dt) => {
                assert!(dt.is_finite() && dt > 0.0, "step of {dt} s");
                assert_eq!(
                    sim.first_non_finite_block(),
                    None,
                    "accepted step left a non-finite state at t = {}",
                    sim.time()
                );
            }
            Err(e) => {
                let m = e.to_string();
                assert!(m.contains("t = "), "diagnostic without a time: {m}");
                break;
            }
        }
    }
}

// ---------------------------------------------------------------------------------------------
// Mutations of JSON values

/// Replacement values for a number: NaN-like strings, extremes, signs, wrong types.
fn weird_value(pick: u8, r: f64) -> Value {
    match pick % 14 {
        0 => json!("NaN"),
        1 => json!("inf"),
        2 => json!(-1.0),
        3 => json!(0.0),
        4 => json!(1e308),
        5 => json!(-1e308),
        6 => json!(1e-308),
        7 => json!(null),
        8 => json!([]),
        9 => json!({}),
        10 => json!(true),
        11 => json!(r * 1e6),
        12 => json!(-r),
        _ => json!(u64::MAX),
    }
}

/// Every path (as a list of keys/indices) to a value in `v`.
fn paths(v: &Value, here: &mut Vec<Step>, out: &mut Vec<Vec<Step>>) {
    out.push(here.clone());
    match v {
        Value::Object(m) => {
            for (k, x) in m {
                here.push(Step::Key(k.clone()));
                paths(x, here, out);
                here.pop();
            }
        }
        Value::Array(a) => {
            for (i, x) in a.iter().enumerate() {
                here.push(Step::Index(i));
                paths(x, here, out);
                here.pop();
            }
        }
        _ => {}
    }
}

#[derive(Debug, Clone)]
enum Step {
    Key(String),
    Index(usize),
}

fn at<'a>(v: &'a mut Value, path: &[Step]) -> Option<&'a mut Value> {
    let mut cur = v;
    for s in path {
        cur = match s {
            Step::Key(k) => cur.get_mut(k.as_str())?,
            Step::Index(i) => cur.get_mut(*i)?,
        };
    }
    Some(cur)
}

/// Apply one mutation `op` at the `which`-th path of `v`.
fn mutate(v: &mut Value, which: prop::sample::Index, op: u8, pick: u8, r: f64) {
    let mut all = Vec::new();
    paths(v, &mut Vec::new(), &mut all);
    let path = all[which.index(all.len())].clone();
    let (parent_path, last) = match path.split_last() {
        Some((l, p)) => (p.to_vec(), Some(l.clone())),
        None => (Vec::new(), None),
    };
    match op % 6 {
        // Replace the value (numbers, strings, objects alike) by a weird one.
        0 => {
            if let Some(x) = at(v, &path) {
                *x = weird_value(pick, r);
            }
        }
        // Remove the field or array element.
        1 => match (at(v, &parent_path), last) {
            (Some(Value::Object(m)), Some(Step::Key(k))) => {
                m.remove(&k);
            }
            (Some(Value::Array(a)), Some(Step::Index(i))) => {
                a.remove(i);
            }
            _ => {}
        },
        // Duplicate an array element (a repeated vertex, block or sample).
        2 => {
            if let (Some(Value::Array(a)), Some(Step::Index(i))) = (at(v, &parent_path), last) {
                let x = a[i].clone();
                a.insert(i, x);
            }
        }
        // Shuffle an array (vertex order, block order) by rotating and swapping.
        3 => {
            if let Some(Value::Array(a)) = at(v, &path) {
                if a.len() > 1 {
                    let n = a.len();
                    a.rotate_left(pick as usize % n);
                    a.swap(0, (pick as usize / 3) % n);
                }
            }
        }
        // A random coordinate / number somewhere in a numeric leaf.
        4 => {
            if let Some(x) = at(v, &path) {
                if x.is_number() {
                    *x = json!((r - 0.5) * 10f64.powi(pick as i32 % 12 - 4));
                }
            }
        }
        // Rename a key (an unknown field, or a reference to a missing material/joint/block).
        _ => {
            if let Some(x) = at(v, &path) {
                if let Value::String(s) = x {
                    s.push('x');
                } else if let Value::Object(m) = x {
                    if let Some(k) = m.keys().nth(pick as usize % m.len().max(1)).cloned() {
                        let val = m.remove(&k).unwrap_or(Value::Null);
                        m.insert(format!("{k}_typo"), val);
                    }
                }
            }
        }
    }
}

/// The JSON text with one key duplicated (serde_json::Value cannot hold duplicates): the text
/// form of `"density": 2500` becomes `"density": 2500, "density": 2500`.
fn duplicate_a_key(text: &str, pick: usize) -> String {
    let keys: Vec<usize> = text.match_indices("\": ").map(|(i, _)| i).collect();
    if keys.is_empty() {
        return text.to_string();
    }
    let end_key = keys[pick % keys.len()];
    let start = text[..end_key].rfind('"').unwrap_or(0);
    // The value runs to the next ',' or '}' at the same line (flat values only).
    let rest = &text[end_key + 3..];
    let Some(len) = rest.find([',', '}', '\n']) else {
        return text.to_string();
    };
    let pair = format!("{}{}", &text[start..end_key + 3], &rest[..len]);
    format!("{}{}, {}", &text[..start], pair, &text[start..])
}

proptest! {
    #![proptest_config(ProptestConfig {
        cases: 256,
        rng_seed: RngSeed::Fixed(20_261_122),
        failure_persistence: None,
        ..ProptestConfig::default()
    })]

    #[test]
    fn arbitrary_bytes_never_panic_the_scene_reader(bytes in proptest::collection::vec(any::<u8>(), 0..400)) {
        check_scene_result(&String::from_utf8_lossy(&bytes));
    }

    /// Arbitrary text built from JSON's own alphabet reaches deeper than random bytes.
    #[test]
    fn json_like_text_never_panics_the_scene_reader(s in "[\\{\\}\\[\\]\",:0-9a-z_\\.\\- ]{0,200}") {
        check_scene_result(&s);
    }

    #[test]
    fn mutated_scenes_are_valid_or_named_errors(
        which_seed in 0usize..3,
        edits in proptest::collection::vec((any::<prop::sample::Index>(), any::<u8>(), any::<u8>(), 0.0f64..1.0), 1..4),
        dup in proptest::option::of(any::<usize>()),
    ) {
        let mut v = seeds().swap_remove(which_seed);
        for (which, op, pick, r) in edits {
            mutate(&mut v, which, op, pick, r);
        }
        let mut text = serde_json::to_string_pretty(&v).expect("serializes");
        if let Some(p) = dup {
            text = duplicate_a_key(&text, p);
        }
        check_scene_result(&text);
    }

    #[test]
    fn arbitrary_json_never_panics_the_motion_reader(v in arb_json()) {
        check_motion(&v);
        check_motion(&json!({ "horizontal": v.clone() }));
        check_motion(&json!({ "horizontal": { "samples": v.clone(), "dt": 0.01 } }));
        check_motion(&json!({ "horizontal": { "pulse": v.clone() } }));
        check_motion(&json!({ "horizontal": { "sine": v.clone() }, "scale": v }));
    }

    /// Never a panic, and rejections name a field.
    #[test]
    fn mutated_motions_never_panic(
        which_seed in 0usize..4,
        edits in proptest::collection::vec((any::<prop::sample::Index>(), any::<u8>(), any::<u8>(), 0.0f64..1.0), 1..4),
    ) {
        let mut v = motion_seeds().swap_remove(which_seed);
        for (which, op, pick, r) in edits {
            mutate(&mut v, which, op, pick, r);
        }
        if let Err(e) = motion::from_json(&v) {
            prop_assert!(e.to_string().contains("motion"), "{}", e);
        }
    }

    /// Accepted motions are finite everywhere (the overflows it found are fixed and kept fixed
    /// by `motion_reader_rejects_non_finite_signals`).
    #[test]
    fn mutated_motions_are_valid_or_named_errors(
        which_seed in 0usize..4,
        edits in proptest::collection::vec((any::<prop::sample::Index>(), any::<u8>(), any::<u8>(), 0.0f64..1.0), 1..4),
    ) {
        let mut v = motion_seeds().swap_remove(which_seed);
        for (which, op, pick, r) in edits {
            mutate(&mut v, which, op, pick, r);
        }
        check_motion(&v);
    }
}

// ---------------------------------------------------------------------------------------------
// Ground motion JSON (docs/format.md §2)

fn motion_seeds() -> Vec<Value> {
    vec![
        example("half-sine-pulse.json"),
        json!({ "horizontal": { "sine": { "amplitude": 0.3, "frequency": 2.0, "units": "g" } } }),
        json!({ "horizontal": { "samples": [0.0, 0.1, -0.2, 0.05, 0.0], "dt": 0.01, "units": "g" },
                "vertical": { "samples": [0.0, 0.01, 0.0], "dt": 0.02 },
                "scale": { "factor": 2.0 } }),
        json!({ "horizontal": { "format": "csv", "content": "time,acc\n0,0\n0.01,0.1\n0.02,-0.1\n0.03,0\n", "units": "g" },
                "scale": { "target_pga": 0.5, "units": "g" } }),
    ]
}

/// Accepted motions give finite accelerations, velocities and displacements and a finite PGA;
/// rejected ones name a field.
fn check_motion(v: &Value) {
    match motion::from_json(v) {
        Ok(gm) => {
            assert!(
                gm.pga().is_finite(),
                "accepted motion with PGA {}",
                gm.pga()
            );
            for t in [0.0, 0.013, 0.5, 3.0, 100.0] {
                for x in gm.state(t).iter().flatten() {
                    assert!(
                        x.is_finite(),
                        "accepted motion non-finite at t = {t}: {gm:?}"
                    );
                }
            }
        }
        Err(e) => {
            let m = e.to_string();
            assert!(m.contains("motion"), "motion error without a field: {m}");
        }
    }
}

fn arb_json() -> impl Strategy<Value = Value> {
    let leaf = prop_oneof![
        Just(Value::Null),
        any::<bool>().prop_map(Value::from),
        any::<f64>()
            .prop_map(|x| serde_json::Number::from_f64(x).map_or(Value::Null, Value::Number)),
        (-1e3f64..1e3).prop_map(Value::from),
        "[a-z_]{0,8}".prop_map(Value::from),
        prop_oneof![
            Just("g"),
            Just("m/s2"),
            Just("sine"),
            Just("csv"),
            Just("NaN")
        ]
        .prop_map(Value::from),
    ];
    leaf.prop_recursive(3, 24, 6, |inner| {
        prop_oneof![
            proptest::collection::vec(inner.clone(), 0..6).prop_map(Value::Array),
            proptest::collection::btree_map(
                prop_oneof![
                    prop::sample::select(vec![
                        "horizontal",
                        "vertical",
                        "scale",
                        "amplitude",
                        "period",
                        "frequency",
                        "cycles",
                        "samples",
                        "dt",
                        "units",
                        "factor",
                        "target_pga",
                        "pulse",
                        "sine",
                    ])
                    .prop_map(String::from),
                    "[a-z]{1,6}",
                ],
                inner,
                0..5,
            )
            .prop_map(|m| Value::Object(m.into_iter().collect())),
        ]
    })
}

/// Deterministic regression cases found while writing the fuzzers (kept so they run every time).
#[test]
fn scene_reader_edge_cases() {
    for text in [
        "",
        "{}",
        "null",
        "[]",
        "{\"format\": \"ashlar.scene/1\"}",
        "{\"format\": \"ashlar.scene/1\", \"materials\": {}, \"joints\": {}, \"blocks\": []}",
    ] {
        check_scene_result(text);
    }
}

/// Bugs found by `mutated_motions_are_valid_or_named_errors`, fixed in src/motion/json.rs: `from_json`
/// accepted
/// - a steady sine of frequency 1e308 Hz: ω = 2π·f overflows to inf and `state(0)` is NaN;
/// - an amplitude of 1e308 in g: × 9.81 overflows to inf (PGA inf).
///
/// It now checks that `amplitude × units` and `2π·frequency` (and `2π/period`) are finite.
#[test]
fn motion_reader_rejects_non_finite_signals() {
    for v in [
        json!({ "horizontal": { "sine": { "amplitude": 0.3, "frequency": 1e308, "units": "g" } } }),
        json!({ "horizontal": { "sine": { "amplitude": 1e308, "frequency": 2.0, "units": "g" } } }),
        json!({ "horizontal": { "pulse": { "amplitude": 1e308, "period": 1.0, "units": "g" } } }),
    ] {
        check_motion(&v);
    }
}

/// The unmutated seeds are valid and run: the "valid model" branch of the properties is live.
#[test]
fn seeds_are_valid_and_run() {
    for v in seeds() {
        let scene = parse_scene(&v.to_string()).unwrap_or_else(|e| panic!("seed invalid: {e}"));
        run_a_few_steps(&scene);
    }
    for v in motion_seeds() {
        let gm = motion::from_json(&v).unwrap_or_else(|e| panic!("motion seed invalid: {e}"));
        assert!(gm.pga() > 0.0);
        check_motion(&v);
    }
}
