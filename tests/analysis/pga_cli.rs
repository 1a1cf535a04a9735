//! `ashlar pga` over several records (docs/pga.md): a directory, a comma-separated list and a
//! `.list` file all run the per-record searches and write result.json, fragility.json and
//! fragility.svg; bad input exits non-zero with one message naming what was wrong.
//! The record options shared by `run`, `pga` and `motion` (docs/format.md, "Record options"): `--units` for a CSV
//! record without units, amplitudes with explicit units, bare numbers refused.
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
    pga_in(motion, out, ["2m/s2", "10m/s2", "0.2m/s2"], extra)
}

/// `pga` with `--min`, `--max` and `--tolerance` as given.
fn pga_in(motion: &str, out: &Path, range: [&str; 3], extra: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_ashlar"))
        .arg("pga")
        .arg(scene())
        .args(["--motion", motion, "--criterion", "toppled:column"])
        // The full engine: the default `auto` would run the reduced rocking model on the column.
        .args(["--model", "dda"])
        .args([
            "--min",
            range[0],
            "--max",
            range[1],
            "--tolerance",
            range[2],
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

/// `ashlar run examples/column.json` with `args`, no trajectory, into `out`.
fn run_column(out: &Path, args: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_ashlar"))
        .arg("run")
        .arg(scene())
        .args(["--no-trajectory", "--out"])
        .arg(out)
        .args(args)
        .output()
        .expect("run ashlar")
}

/// A 1 s half-sine pulse of peak 1 (units not named) sampled every 10 ms, as a two-column CSV
/// whose header names no units.
fn csv_without_units(dir: &Path) -> PathBuf {
    let mut text = String::from("time,acceleration\n");
    for k in 0..=50 {
        let t = k as f64 * 0.01;
        text += &format!("{t},{}\n", (std::f64::consts::PI * t / 0.5).sin().max(0.0));
    }
    let p = dir.join("pulse.csv");
    std::fs::write(&p, text).expect("write csv");
    p
}

fn stderr_line(o: &std::process::Output) -> String {
    let err = String::from_utf8_lossy(&o.stderr).trim().to_string();
    assert!(!o.status.success(), "must fail");
    assert_eq!(err.lines().count(), 1, "one line: {err}");
    err
}

#[test]
fn run_and_pga_read_a_csv_without_units_given_units() {
    let dir = temp("csv-units");
    let csv = csv_without_units(&dir);
    let csv = csv.to_str().expect("utf-8");
    let out = dir.join("out");
    // Without --units: refused, saying how to name them.
    let err = stderr_line(&run_column(&out, &["--motion", csv]));
    assert!(
        err.contains("unknown units") && err.contains("--units g|m/s2|cm/s2"),
        "{err}"
    );
    // --units cm/s2: a peak of 1 cm/s² (exact: the factor 0.01 applied to the sample 1.0).
    let o = run_column(&out, &["--motion", csv, "--units", "cm/s2"]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let s = read(&out.join("summary.json"));
    assert_eq!(s["pga"].as_f64(), Some(0.01));
    // `pga` takes the same --units.
    let o = pga(csv, &dir.join("pga-out"), &["--units", "g"]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let err = stderr_line(&pga(csv, &dir.join("pga-out"), &["--units", "furlongs"]));
    assert!(err.contains("--units \"furlongs\""), "{err}");
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn run_pga_takes_explicit_units_and_refuses_bare_numbers() {
    let dir = temp("run-pga");
    let pulse = records(&dir)[1].to_str().expect("utf-8").to_string();
    let out = dir.join("out");
    // Each accepted spelling gives its value in m/s²; compared to 1e-12 relative (one
    // multiplication by the unit factor, one by the record's scale).
    for (text, expect) in [
        ("0.4g", 0.4 * 9.80665),
        ("0.4G", 0.4 * 9.80665),
        ("4m/s2", 4.0),
        ("4 m/s²", 4.0),
        ("392gal", 3.92),
    ] {
        let o = run_column(&out, &["--motion", &pulse, "--pga", text]);
        assert!(
            o.status.success(),
            "{text}: {}",
            String::from_utf8_lossy(&o.stderr)
        );
        let got = read(&out.join("summary.json"))["pga"]
            .as_f64()
            .expect("pga");
        assert!(
            (got / expect - 1.0).abs() < 1e-12,
            "{text}: {got} vs {expect}"
        );
    }
    // A bare number: refused, suggesting both readings.
    let err = stderr_line(&run_column(&out, &["--motion", &pulse, "--pga", "0.4"]));
    assert!(
        err.contains("--pga \"0.4\"") && err.contains("0.4g") && err.contains("0.4m/s2"),
        "{err}"
    );
    let err = stderr_line(&run_column(
        &out,
        &["--motion", &pulse, "--pga", "4 furlongs"],
    ));
    assert!(err.contains("unknown units \"furlongs\""), "{err}");
    let err = stderr_line(&run_column(&out, &["--motion", &pulse, "--pga", "-1g"]));
    assert!(err.contains("≥ 0"), "{err}");
    let err = stderr_line(&run_column(&out, &["--motion", &pulse, "--scale", "NaN"]));
    assert!(err.contains("--scale"), "{err}");
    // --pga and --scale together: clap refuses the pair.
    let o = run_column(&out, &["--motion", &pulse, "--pga", "1g", "--scale", "2"]);
    assert!(!o.status.success());
    // The search's range and tolerance: bare numbers refused, each naming its option.
    for (k, (flag, bare)) in [("--min", "2"), ("--max", "10"), ("--tolerance", "0.2")]
        .into_iter()
        .enumerate()
    {
        let mut range = ["2m/s2", "10m/s2", "0.2m/s2"];
        range[k] = bare;
        let err = stderr_line(&pga_in(&pulse, &dir.join("pga-out"), range, &[]));
        assert!(
            err.contains(&format!("{flag} \"{bare}\"")) && err.contains("has no units"),
            "{err}"
        );
    }
    // The search in g gives the same bracket as in m/s² (the same amplitudes, converted).
    let o = pga_in(&pulse, &dir.join("g"), ["0.2g", "1g", "0.02g"], &[]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let r = read(&dir.join("g/result.json"));
    assert_eq!(r["units"], "m/s2");
    let runs = r["runs"].as_array().expect("runs");
    // 4 scan points over 0.2–1 g ask for 0.267 g; the lattice is the tolerance 0.02 g × 2³ =
    // 0.16 g = 1.569064 m/s², so the scan starts at floor(0.2 g / 0.16 g) × 0.16 g.
    let h = 0.02 * 9.80665 * 8.0;
    let resolution = r["resolution"].as_f64().expect("resolution");
    assert!((resolution / h - 1.0).abs() < 1e-12, "{resolution} vs {h}");
    assert!(
        runs.iter()
            .any(|x| (x["pga"].as_f64().expect("pga") - h).abs() < 1e-12),
        "the scan starts at 0.16 g = 1.569064 m/s²: {runs:?}"
    );
    std::fs::remove_dir_all(&dir).ok();
}
