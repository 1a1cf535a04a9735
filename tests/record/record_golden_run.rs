//! Golden digests of a real recording: `examples/column.json` under
//! `examples/half-sine-pulse.json`, recorded by `analysis::run`, once by the full engine
//! (`"model": "dda"`, tests/fixtures/record/column_run.digest) and once with the scene's default
//! model (`"auto"`: the reduced rocking model, column_run_auto.digest).
//! Both are deterministic (no threads, no hash-order dependence, IEEE arithmetic), so the
//! bytes of `trajectory.mcap` and `histories.csv` are too. A change of either digest means
//! the physics or the recording changed; if intended, regenerate with
//!   ASHLAR_BLESS=1 cargo test --test record record_golden_run::
//! and commit the fixtures.
use ashlar::analysis::run::{run, RunOptions};
use ashlar::motion::from_json;
use ashlar::scene::{parse_scene, ModelChoice};
use sha2::Digest;
use std::path::Path;

fn digest(path: &Path) -> String {
    let bytes = std::fs::read(path).expect("read output");
    let hash: String = sha2::Sha256::digest(&bytes)
        .iter()
        .map(|b| format!("{b:02x}"))
        .collect();
    format!(
        "{} size {} sha256 {hash}\n",
        path.file_name().and_then(|n| n.to_str()).unwrap_or("?"),
        bytes.len()
    )
}

#[test]
fn golden_digest_of_the_column_example_run() {
    check_golden(Some(ModelChoice::Dda), "dda", "column_run.digest");
}

#[test]
fn golden_digest_of_the_column_example_run_with_the_default_model() {
    check_golden(None, "rocking", "column_run_auto.digest");
}

/// Run the example with `model` (None: the scene's default), check which model ran, and
/// compare the digests of its outputs with `tests/fixtures/record/<fixture>`.
fn check_golden(model: Option<ModelChoice>, expect_ran: &str, fixture: &str) {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let mut scene =
        parse_scene(&std::fs::read_to_string(root.join("examples/column.json")).expect("scene"))
            .expect("valid scene");
    if let Some(m) = model {
        scene.control.model = m;
    }
    let motion_json: serde_json::Value = serde_json::from_str(
        &std::fs::read_to_string(root.join("examples/half-sine-pulse.json")).expect("motion"),
    )
    .expect("json");
    let motion = from_json(&motion_json).expect("motion");
    let out =
        std::env::temp_dir().join(format!("ashlar-golden-{}-{expect_ran}", std::process::id()));
    let opts = RunOptions {
        out_dir: Some(&out),
        ..Default::default()
    };
    let outcome = run(&scene, &motion, &opts).expect("run");
    assert!(outcome.summary.completed);
    assert_eq!(
        outcome.summary.model, expect_ran,
        "{}",
        outcome.summary.model_reason
    );
    let actual = digest(&out.join("trajectory.mcap")) + &digest(&out.join("histories.csv"));
    std::fs::remove_dir_all(&out).ok();
    let fixture = root.join("tests/fixtures/record").join(fixture);
    if std::env::var("ASHLAR_BLESS").is_ok_and(|v| v == "1") {
        std::fs::write(&fixture, &actual).expect("write digest");
        return;
    }
    let expected = std::fs::read_to_string(&fixture).unwrap_or_else(|e| {
        panic!(
            "{}: {e} (generate it with ASHLAR_BLESS=1)",
            fixture.display()
        )
    });
    assert_eq!(
        actual, expected,
        "recorded bytes changed; see this test's comment"
    );
}
