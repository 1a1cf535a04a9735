//! Bad input meets one clear error naming the file, the line and what was expected — never a
//! panic, never a silently shortened record. Each case edits a valid fixture in one place.
use ashlar::motion::{self, MotionError};
use std::path::{Path, PathBuf};

fn fixture(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/fixtures/motion")
        .join(name)
}

/// Write `content` as `name` in a fresh directory and load it.
fn load(name: &str, content: &str) -> Result<motion::GroundMotion, MotionError> {
    let dir = std::env::temp_dir().join(format!(
        "ashlar-bad-{}-{}",
        std::process::id(),
        name.replace('.', "_")
    ));
    std::fs::create_dir_all(&dir).expect("tmp");
    let path = dir.join(name);
    std::fs::write(&path, content).expect("write");
    motion::load_path(&path)
}

fn original(name: &str) -> String {
    std::fs::read_to_string(fixture(name)).expect("fixture")
}

/// The error names the file (origin ends with it), the line, and says `words`.
fn expect_error(
    r: Result<motion::GroundMotion, MotionError>,
    name: &str,
    line: Option<usize>,
    words: &[&str],
) {
    let e = r
        .err()
        .unwrap_or_else(|| panic!("{name}: expected an error"));
    let msg = e.to_string();
    assert!(
        e.origin.ends_with(name),
        "origin {:?} should name {name}",
        e.origin
    );
    assert_eq!(e.line, line, "line in {msg:?}");
    for w in words {
        assert!(msg.contains(w), "{msg:?} should contain {w:?}");
    }
}

fn at2_lines() -> Vec<String> {
    original("new_style.at2")
        .lines()
        .map(|l| l.trim_end_matches('\r').to_string())
        .collect()
}

#[test]
fn nan_and_infinity() {
    let mut l = at2_lines();
    l[5] = l[5].replacen("-2.7319025E-02", "NaN", 1);
    expect_error(
        load("nan.at2", &l.join("\n")),
        "nan.at2",
        Some(6),
        &["non-finite", "NaN"],
    );
    let mut l = at2_lines();
    l[4] = l[4].replacen("6.1279882E-02", "inf", 1);
    expect_error(
        load("inf.at2", &l.join("\n")),
        "inf.at2",
        Some(5),
        &["non-finite"],
    );
    let csv = "time_s,accel_g\n0,0.1\n0.01,Infinity\n";
    expect_error(load("inf.csv", csv), "inf.csv", Some(3), &["non-finite"]);
    // A number too large for f64 parses to infinity: still refused.
    let csv = "time_s,accel_g\n0,0.1\n0.01,1e999\n";
    expect_error(load("huge.csv", csv), "huge.csv", Some(3), &["expected"]);
}

#[test]
fn sample_count_disagrees_with_header() {
    let mut l = at2_lines();
    l[3] = "NPTS=   22, DT=   .0100 SEC,".into();
    expect_error(
        load("more.at2", &l.join("\n")),
        "more.at2",
        Some(9),
        &["more values", "NPTS = 22"],
    );
    let esm = original("synthetic.asc").replace("NDATA: 23", "NDATA: 30");
    expect_error(
        load("short.asc", &esm),
        "short.asc",
        Some(87),
        &["truncated", "NDATA = 30", "23 values"],
    );
}

#[test]
fn truncated_files() {
    // Last line cut: 20 of 23 values.
    let l = at2_lines();
    let cut = l[..l.len() - 1].join("\n");
    expect_error(
        load("cut.at2", &cut),
        "cut.at2",
        Some(8),
        &["truncated", "NPTS = 23", "20 values"],
    );
    // Header cut.
    expect_error(
        load("head.at2", "PEER\nX\n"),
        "head.at2",
        Some(2),
        &["truncated", "4 header lines"],
    );
    // COSMOS cut inside the real header.
    let v2_text = original("synthetic.v2");
    let v2: Vec<&str> = v2_text.lines().collect();
    let cut = v2[..30].join("\n");
    expect_error(
        load("cut.v2", &cut),
        "cut.v2",
        Some(30),
        &["truncated", "real-header"],
    );
    // COSMOS cut inside the data.
    let cut = v2[..v2.len() - 4].join("\n");
    expect_error(
        load("data.v2", &cut),
        "data.v2",
        Some(v2.len() - 4),
        &["truncated", "acceleration value 17 of 23"],
    );
}

#[test]
fn non_uniform_time_column() {
    let csv = "time_s,accel_g\n0,0.1\n0.01,0.2\n0.02,0.3\n0.04,0.1\n0.05,0.0\n0.06,0.0\n";
    expect_error(
        load("gap.csv", csv),
        "gap.csv",
        Some(5),
        &["non-uniform", "expected t ="],
    );
    let csv = "time_s,accel_g\n0,0.1\n0.01,0.2\n0.01,0.3\n";
    expect_error(
        load("dup.csv", csv),
        "dup.csv",
        Some(4),
        &["time must increase"],
    );
}

#[test]
fn time_step_not_positive() {
    let mut l = at2_lines();
    l[3] = "NPTS=   23, DT=   0.0 SEC".into();
    expect_error(
        load("zero.at2", &l.join("\n")),
        "zero.at2",
        Some(4),
        &["DT must be > 0"],
    );
    let esm = original("synthetic.asc").replace(
        "SAMPLING_INTERVAL_S: 0.010000",
        "SAMPLING_INTERVAL_S: -0.01",
    );
    expect_error(
        load("neg.asc", &esm),
        "neg.asc",
        Some(29),
        &["SAMPLING_INTERVAL_S must be > 0"],
    );
    let v2 = original("synthetic.v2").replacen("       5.000000", "       0.000000", 1);
    expect_error(
        load("dt.v2", &v2),
        "dt.v2",
        Some(38),
        &["real-header value 61", "> 0 ms"],
    );
    let csv = "time_s,accel_g\n0.02,0.1\n0.01,0.2\n";
    expect_error(
        load("back.csv", csv),
        "back.csv",
        Some(3),
        &["time must increase"],
    );
}

#[test]
fn empty_records() {
    expect_error(
        load("empty.csv", "# nothing\ntime_s,accel_g\n"),
        "empty.csv",
        None,
        &["empty record"],
    );
    let mut l = at2_lines();
    l.truncate(3);
    l.push("NPTS=    0, DT=   .0100 SEC".into());
    expect_error(
        load("empty.at2", &l.join("\n")),
        "empty.at2",
        Some(4),
        &["empty record"],
    );
    expect_error(
        load("nothing.v2", ""),
        "nothing.v2",
        Some(1),
        &["truncated"],
    );
}

#[test]
fn unknown_units() {
    let esm = original("synthetic.asc").replace("UNITS: cm/s^2", "UNITS: counts");
    expect_error(
        load("counts.asc", &esm),
        "counts.asc",
        Some(33),
        &["unknown units", "counts"],
    );
    let v2 = original("synthetic.v2").replace("units=cm/sec2(04)", "units=in/sec2(07)");
    expect_error(
        load("inch.v2", &v2),
        "inch.v2",
        Some(48),
        &["unknown units", "in/sec2"],
    );
    expect_error(
        load("nounits.csv", "t,a\n0,1\n0.01,2\n"),
        "nounits.csv",
        None,
        &["unknown units"],
    );
    let csv = "# units: furlongs\nt,a\n0,1\n0.01,2\n";
    expect_error(
        load("furlong.csv", csv),
        "furlong.csv",
        Some(1),
        &["unknown units", "furlongs"],
    );
}

#[test]
fn wrong_kind_of_file() {
    let mut l = at2_lines();
    l[2] = "VELOCITY TIME SERIES IN UNITS OF CM/S".into();
    expect_error(
        load("vel.at2", &l.join("\n")),
        "vel.at2",
        Some(3),
        &["velocity"],
    );
    let mut l = at2_lines();
    l[3] = "23 points at 0.01".into();
    expect_error(
        load("hdr.at2", &l.join("\n")),
        "hdr.at2",
        Some(4),
        &["NPTS="],
    );
    let e = motion::load_path(Path::new("record.xyz")).expect_err("extension");
    assert!(e.to_string().contains("unknown record extension"), "{e}");
    let e = motion::load_path(Path::new("/nonexistent/r.at2")).expect_err("missing file");
    assert!(
        e.to_string().starts_with("/nonexistent/r.at2") && e.to_string().contains("cannot read"),
        "{e}"
    );
    let csv = "t,a_g\n0,1,2\n";
    expect_error(
        load("cols.csv", csv),
        "cols.csv",
        Some(2),
        &["expected 2 columns"],
    );
}

/// Processing asked of the wrong record, or with bad knobs.
#[test]
fn processing_misuse() {
    use motion::{HighPass, LoadParams, ProcessParams};
    let hp = |corner_hz| LoadParams {
        process: ProcessParams {
            highpass: Some(HighPass {
                corner_hz,
                order: 4,
            }),
            ..Default::default()
        },
        ..Default::default()
    };
    let e =
        motion::load_path_with(&fixture("synthetic.v2"), &hp(0.1)).expect_err("processed record");
    assert!(e.to_string().contains("already processed"), "{e}");
    let e =
        motion::load_path_with(&fixture("synthetic.v1"), &hp(200.0)).expect_err("above Nyquist");
    assert!(e.to_string().contains("Nyquist"), "{e}");
    let e =
        motion::load_path_with(&fixture("synthetic.v1"), &hp(-1.0)).expect_err("negative corner");
    assert!(e.to_string().contains("> 0 Hz"), "{e}");
}

/// JSON errors name the field.
#[test]
fn json_fields() {
    let cases = [
        (
            serde_json::json!({"horizontal": {"format": "sac", "content": ""}}),
            "motion.horizontal.format",
        ),
        (
            serde_json::json!({"horizontal": {"samples": [], "dt": 0.01}}),
            "motion.horizontal.samples",
        ),
        (
            serde_json::json!({"horizontal": {"samples": [1.0], "dt": 0.0}}),
            "motion.horizontal.dt",
        ),
        (
            serde_json::json!({"horizontal": {"format": "csv", "content": "t,a\n0,1\n0.1,2\n"}}),
            "motion.horizontal.content",
        ),
        (
            // The typed reader (`MotionSpec`) names the member itself, not only its component.
            serde_json::json!({"horizontal": {"samples": [1.0], "dt": 0.01, "units": "furlong"}}),
            "motion.horizontal.units",
        ),
        (serde_json::json!({"horizontl": null}), "motion.horizontl"),
    ];
    for (v, origin) in cases {
        let e = motion::from_json(&v).expect_err("bad json");
        assert_eq!(e.origin, origin, "{e}");
    }
}
