//! `ashlar motion RECORD [--svg FILE]`: the JSON has exactly the docs/format.md §3 fields (plus the
//! documented extensions) and the SVG is written.
use crate::common::MOTION_REPORT_FIELDS;
use ashlar::cli::motion::{report_json, MotionArgs};
use ashlar::motion::RecordArgs;
use std::path::PathBuf;

fn args(record: &str) -> MotionArgs {
    MotionArgs {
        record: PathBuf::from(concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/tests/fixtures/motion/"
        ))
        .join(record),
        svg: None,
        record_options: RecordArgs::default(),
        highpass: None,
        order: 4,
        baseline: "none".into(),
        damping: 0.05,
    }
}

/// `args` for one of the repository's recorded ground motions (data/ground-motions).
fn recorded(name: &str) -> MotionArgs {
    MotionArgs {
        record: PathBuf::from(concat!(env!("CARGO_MANIFEST_DIR"), "/data/ground-motions"))
            .join(name),
        ..args("")
    }
}

#[test]
fn json_fields_and_svg() {
    let svg = std::env::temp_dir().join(format!("ashlar-spectrum-{}.svg", std::process::id()));
    let mut a = recorded("friuli-1976-tolmezzo-000.at2");
    a.svg = Some(svg.clone());
    let json: serde_json::Value =
        serde_json::from_str(&report_json(&a).expect("report")).expect("json");
    for key in MOTION_REPORT_FIELDS {
        assert!(json.get(key).is_some(), "missing {key}");
    }
    for key in ["damping", "periods", "psa"] {
        assert!(
            json["spectrum"].get(key).is_some(),
            "missing spectrum.{key}"
        );
    }
    assert_eq!(json["npts"], 7269);
    assert_eq!(json["original_units"], "g");
    let text = std::fs::read_to_string(&svg).expect("svg written");
    assert!(text.starts_with("<svg") && text.contains("<polyline"));
}

#[test]
fn options_and_errors() {
    let mut a = recorded("kobe-1995-nishi-akashi-000.csv");
    a.record_options.pga = Some("0.5g".into());
    let json: serde_json::Value =
        serde_json::from_str(&report_json(&a).expect("report")).expect("json");
    assert!((json["pga"].as_f64().expect("pga") - 0.5 * 9.80665).abs() < 1e-9);
    // Units of every numeric field; the PGA also in g (1e-12: one division).
    assert_eq!(json["units"]["pga"], "m/s2");
    assert_eq!(json["units"]["arias_intensity"], "m/s");
    assert_eq!(json["units"]["spectrum"]["periods"], "s");
    assert!((json["pga_g"].as_f64().expect("pga_g") - 0.5).abs() < 1e-12);
    // Bare numbers are refused (0.5 g or 0.5 m/s²?), naming the option and both readings.
    let mut a = recorded("kobe-1995-nishi-akashi-000.csv");
    a.record_options.pga = Some("0.5".into());
    let e = report_json(&a).expect_err("bare --pga").to_string();
    assert!(
        e.starts_with("--pga \"0.5\"") && e.contains("0.5g") && e.contains("0.5m/s2"),
        "{e}"
    );
    let mut a = recorded("kobe-1995-nishi-akashi-000.csv");
    a.record_options.units.units = Some("furlongs".into());
    assert!(report_json(&a)
        .expect_err("units")
        .to_string()
        .starts_with("--units"));
    // `--units` reads a CSV that names none; it must agree with one that does.
    let mut a = args("semicolon_units_comment.csv");
    a.record_options.units.units = Some("g".into());
    let e = report_json(&a).expect_err("conflict").to_string();
    assert!(e.contains("units conflict"), "{e}");
    let mut a = args("synthetic.v1");
    a.highpass = Some(0.5);
    a.baseline = "linear".into();
    assert!(report_json(&a).is_ok());
    let mut a = args("synthetic.v2");
    a.highpass = Some(0.5);
    let e = report_json(&a).expect_err("processed").to_string();
    assert!(
        e.contains("synthetic.v2") && e.contains("already processed"),
        "{e}"
    );
    let mut a = args("synthetic.v2");
    a.baseline = "cubic".into();
    assert!(report_json(&a)
        .expect_err("baseline")
        .to_string()
        .contains("--baseline"));
}
