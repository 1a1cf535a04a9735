//! `ashlar pga` over several records (issue 6): a directory, a comma-separated list and a
//! `.list` file all run the per-record searches and write result.json, fragility.json and
//! fragility.svg; bad input exits non-zero with one message naming what was wrong.
use serde_json::{json, Value};
use std::path::{Path, PathBuf};
use std::process::Command;

fn temp(tag: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("ashlar-pga-cli-{tag}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).expect("temp dir");
    d
}

fn scene() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("examples/column.json")
}

/// Three half-sine pulse records of periods 0.8, 1 and 1.25 s, and a README that is not a record.
fn records(dir: &Path) -> Vec<PathBuf> {
    let mut out = Vec::new();
    for t in [0.8, 1.0, 1.25] {
        let p = dir.join(format!("pulse-{t}.json"));
        let m = json!({"horizontal": {"pulse": {"amplitude": 1.0, "period": t, "cycles": 0.5, "units": "m/s2"}}});
        std::fs::write(&p, m.to_string()).expect("write record");
        out.push(p);
    }
    std::fs::write(dir.join("README.md"), "not a record").expect("write");
    out
}

fn pga(motion: &str, out: &Path, extra: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_ashlar"))
        .arg("pga")
        .arg(scene())
        .args(["--motion", motion, "--criterion", "toppled:column"])
        // The full engine: the default `auto` would run the reduced rocking model on the column.
        .args(["--model", "dda"])
        .args([
            "--min",
            "2",
            "--max",
            "10",
            "--tolerance",
            "0.2",
            "--scan-points",
            "4",
        ])
        .args(extra)
        .arg("--out")
        .arg(out)
        .output()
        .expect("run ashlar")
}

fn read(p: &Path) -> Value {
    serde_json::from_str(&std::fs::read_to_string(p).expect("read")).expect("json")
}

#[test]
fn directory_list_and_list_file_give_one_fragility() {
    let dir = temp("records");
    let paths = records(&dir);
    let out = dir.join("out-dir");
    let o = pga(dir.to_str().expect("utf-8"), &out, &[]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let r = read(&out.join("result.json"));
    assert_eq!(r["records"].as_array().map(Vec::len), Some(3));
    assert_eq!(r["records"][0]["motion"], "pulse-0.8.json");
    let f = read(&out.join("fragility.json"));
    assert_eq!(f["fragility"], r["fragility"]);
    assert!(f["fragility"]["median"]
        .as_f64()
        .is_some_and(|m| m > 2.0 && m < 10.0));
    let svg = std::fs::read_to_string(out.join("fragility.svg")).expect("svg");
    assert!(svg.contains("Probability of failure") && svg.contains("PGA (m/s²)"));

    // The same records as a comma-separated list and as a .list file: the same answer.
    let list = paths
        .iter()
        .map(|p| p.to_str().expect("utf-8"))
        .collect::<Vec<_>>()
        .join(",");
    let out2 = dir.join("out-list");
    assert!(pga(&list, &out2, &[]).status.success());
    // The same records in another order (the directory is read sorted by name): the same curve,
    // to the optimiser's resolution.
    let same = |a: &Value, b: &Value| {
        for k in ["median", "beta"] {
            let (x, y) = (
                a[k].as_f64().expect("number"),
                b[k].as_f64().expect("number"),
            );
            assert!((x / y - 1.0).abs() < 1e-6, "{k}: {x} vs {y}");
        }
    };
    same(
        &read(&out2.join("result.json"))["fragility"],
        &r["fragility"],
    );
    let lf = dir.join("records.list");
    std::fs::write(
        &lf,
        "# the three pulses\npulse-0.8.json\n\npulse-1.json\npulse-1.25.json\n",
    )
    .expect("write list");
    let out3 = dir.join("out-file");
    let o = pga(lf.to_str().expect("utf-8"), &out3, &["--fit", "binary"]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let b = read(&out3.join("result.json"));
    assert_eq!(b["fragility"]["method"], "mle_binary");
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn bad_input_is_one_clear_message() {
    let dir = temp("bad");
    let out = dir.join("out");
    let cases: [(&str, &[&str], &str); 4] = [
        (dir.to_str().expect("utf-8"), &[], "holds no record"),
        (
            "/nonexistent/a.at2,/nonexistent/b.at2",
            &[],
            "/nonexistent/a.at2",
        ),
        ("/nonexistent/a.at2", &["--combine", "most"], "combine"),
        ("/nonexistent/a.at2", &["--fit", "bayes"], "fit"),
    ];
    for (motion, extra, want) in cases {
        let o = pga(motion, &out, extra);
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(!o.status.success(), "{motion} {extra:?} must fail");
        assert!(err.contains(want), "{motion} {extra:?}: {err}");
        assert_eq!(err.trim().lines().count(), 1, "one line: {err}");
    }
    std::fs::remove_dir_all(&dir).ok();
}
