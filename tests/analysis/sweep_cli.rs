//! `ashlar sweep`: a manifest's lines run one by one (as a Slurm array or Kubernetes indexed
//! job would), then `--collect` builds the report. Checked against independent facts: each
//! line's verdict for `toppled:column` must equal the summary's own `toppled` flag (computed by
//! the run from the final rotation, docs/format.md §3), the applied PGA must be the line's
//! amplitude, and the report's bracket must follow from the verdicts by the PGA search's rules
//! (recomputed here by hand).
use serde_json::{json, Value};
use std::path::Path;
use std::process::Command;

fn ashlar(args: &[&str], env: &[(&str, &str)]) -> (bool, String, String) {
    let mut c = Command::new(env!("CARGO_BIN_EXE_ashlar"));
    c.args(args);
    for (k, v) in env {
        c.env(k, v);
    }
    let out = c.output().expect("run ashlar");
    (
        out.status.success(),
        String::from_utf8_lossy(&out.stdout).into_owned(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

fn setup(dir: &Path) {
    std::fs::create_dir_all(dir).expect("dir");
    let mut scene: Value =
        serde_json::from_str(include_str!("../../examples/column.json")).expect("scene");
    scene["control"]["duration"] = json!(2.0);
    // The full engine: the default `auto` would run the reduced rocking model on this column.
    scene["control"]["model"] = json!("dda");
    std::fs::write(dir.join("column.json"), scene.to_string()).expect("scene");
    std::fs::copy("examples/half-sine-pulse.json", dir.join("pulse.json")).expect("record");
    // Amplitudes from 1 to 9 m/s²: small ones leave the column standing, large ones topple it.
    // Written in each accepted form: a bare JSON number (m/s²) and strings with units.
    let lines: Vec<String> = [json!(1.0), json!("9m/s2"), json!("300gal")]
        .iter()
        .map(|a| {
            json!({"scene": "column.json", "record": "pulse.json", "amplitude": a, "criterion": "toppled:column"})
                .to_string()
        })
        .collect();
    std::fs::write(dir.join("m.jsonl"), lines.join("\n") + "\n\n").expect("manifest");
}

#[test]
fn lines_then_collect() {
    let dir = std::env::temp_dir().join(format!("ashlar-sweep-{}", uuid::Uuid::new_v4()));
    setup(&dir);
    let m = dir.join("m.jsonl");
    let out = dir.join("out");
    let (m, out_s) = (m.to_str().expect("utf8"), out.to_str().expect("utf8"));
    // Line 0 by flag, line 1 as a Slurm array task, line 2 as a Kubernetes indexed pod.
    let runs = [
        ashlar(
            &[
                "sweep",
                m,
                "--index",
                "0",
                "--out",
                out_s,
                "--no-trajectory",
            ],
            &[],
        ),
        ashlar(
            &["sweep", m, "--out", out_s, "--no-trajectory"],
            &[("SLURM_ARRAY_TASK_ID", "1")],
        ),
        ashlar(
            &["sweep", m, "--out", out_s, "--no-trajectory"],
            &[("JOB_COMPLETION_INDEX", "2")],
        ),
    ];
    for (ok, _, err) in &runs {
        assert!(ok, "{err}");
    }
    let amplitudes = [1.0, 9.0, 3.0];
    let mut verdicts = Vec::new();
    for (k, a) in amplitudes.iter().enumerate() {
        let d = out.join(format!("{k:06}"));
        let line: Value =
            serde_json::from_str(&std::fs::read_to_string(d.join("line.json")).expect("line"))
                .expect("json");
        let summary: Value = serde_json::from_str(
            &std::fs::read_to_string(d.join("summary.json")).expect("summary"),
        )
        .expect("json");
        assert_eq!(summary["model"], "dda", "line {k} ran the full engine");
        let toppled = summary["blocks"]
            .as_array()
            .expect("blocks")
            .iter()
            .find(|b| b["id"] == "column")
            .expect("column")["toppled"]
            .as_bool()
            .expect("bool");
        assert_eq!(line["failed"].as_bool(), Some(toppled), "line {k}");
        // Scaling a half-sine pulse to a PGA is exact up to rounding.
        let pga = line["pga"].as_f64().expect("pga");
        assert!(
            (pga - a).abs() <= 1e-12 * a,
            "line {k}: pga {pga} for amplitude {a}"
        );
        assert!(d.join("histories.csv").exists() && !d.join("trajectory.mcap").exists());
        verdicts.push((*a, toppled));
    }
    assert!(
        verdicts.iter().any(|v| v.1) && verdicts.iter().any(|v| !v.1),
        "the amplitudes straddle the threshold: {verdicts:?}"
    );
    let (ok, stdout, err) = ashlar(&["sweep", "--collect", out_s, "--with-manifest", m], &[]);
    assert!(ok, "{err}");
    let report: Value = serde_json::from_str(&stdout).expect("report");
    assert_eq!(
        report,
        serde_json::from_str::<Value>(
            &std::fs::read_to_string(out.join("report.json")).expect("file")
        )
        .expect("json")
    );
    assert_eq!(report["lines"], 3);
    assert_eq!(report["missing"], json!([]));
    let g = &report["groups"][0];
    assert_eq!(g["lines"], json!([0, 2, 1]), "sorted by amplitude");
    // By hand: the lowest toppling amplitude, and the highest standing one below it.
    verdicts.sort_by(|a, b| a.0.total_cmp(&b.0));
    let failing = verdicts.iter().find(|v| v.1).map(|v| v.0);
    let safe = verdicts
        .iter()
        .filter(|v| !v.1 && failing.is_none_or(|f| v.0 < f))
        .map(|v| v.0)
        .fold(None, |m: Option<f64>, p| Some(m.map_or(p, |m| m.max(p))));
    assert_eq!(g["result"]["failing_pga"].as_f64(), failing);
    assert_eq!(g["result"]["safe_pga"].as_f64(), safe);
    assert_eq!(g["result"]["criterion"], "toppled:column");
    assert_eq!(g["result"]["units"], "m/s2");

    // Missing lines are named; bad input names the line.
    std::fs::remove_dir_all(out.join("000001")).expect("remove");
    let (ok, _, err) = ashlar(&["sweep", "--collect", out_s, "--with-manifest", m], &[]);
    assert!(!ok && err.contains("[1]"), "{err}");
    let (ok, _, err) = ashlar(&["sweep", m, "--index", "3", "--out", out_s], &[]);
    assert!(!ok && err.contains("has 3 lines"), "{err}");
    std::fs::write(
        dir.join("bad.jsonl"),
        "{\"scene\": \"column.json\", \"amplitude\": \"loud\"}\n",
    )
    .expect("write");
    let bad = dir.join("bad.jsonl");
    let (ok, _, err) = ashlar(
        &[
            "sweep",
            bad.to_str().expect("utf8"),
            "--index",
            "0",
            "--out",
            out_s,
        ],
        &[],
    );
    assert!(
        !ok && err.contains("line 1") && err.contains("amplitude"),
        "{err}"
    );
    // A string amplitude without units is refused (0.3 g or 0.3 m/s²?).
    std::fs::write(
        &bad,
        "{\"scene\": \"column.json\", \"amplitude\": \"0.3\"}\n",
    )
    .expect("write");
    let (ok, _, err) = ashlar(
        &[
            "sweep",
            bad.to_str().expect("utf8"),
            "--index",
            "0",
            "--out",
            out_s,
        ],
        &[],
    );
    assert!(
        !ok && err.contains("line 1") && err.contains("0.3 has no units"),
        "{err}"
    );
    std::fs::remove_dir_all(dir).ok();
}
