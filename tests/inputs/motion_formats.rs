//! Every record format reads to the values it holds: the six shared records against the PGA
//! table of their README, and small synthetic files of each format (written by
//! tests/fixtures/motion/make_fixtures.py) against the signal they were generated from.
use ashlar::motion::{self, GroundMotion, LoadParams, RecordKind, Signal, Units, STANDARD_GRAVITY};
use std::path::{Path, PathBuf};

fn fixture(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/fixtures/motion")
        .join(name)
}

/// One of the repository's recorded ground motions.
fn recorded(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("data/ground-motions")
        .join(name)
}

fn sampled(gm: &GroundMotion) -> &motion::Sampled {
    match &gm.horizontal {
        Signal::Sampled(s) => s,
        other => panic!("expected a sampled record, got {other:?}"),
    }
}

/// The signal every synthetic fixture holds: 100 sin(0.7 i) e^(−0.05 i), in the file's units.
fn synthetic(i: usize) -> f64 {
    100.0 * (0.7 * i as f64).sin() * (-0.05 * i as f64).exp()
}

/// Recorded ground motions: sample count, time step and PGA as tabulated in their README
/// (data/ground-motions/README.md). PGA must agree to 3 significant
/// digits, i.e. |pga − table| ≤ 0.0005 g, the table's rounding.
#[test]
fn shared_records_match_the_readme_table() {
    let table = [
        ("friuli-1976-tolmezzo-000.at2", 7269, 0.005, 0.351),
        ("northridge-1994-mulholland-009.at2", 2999, 0.01, 0.416),
        ("irpinia-1980-sturno-223.at2", 16392, 0.0024, 0.232),
        (
            "imperial-valley-1979-el-centro-6-233.csv",
            7807,
            0.005,
            0.442,
        ),
        ("loma-prieta-1989-capitola-000.at2", 7991, 0.005, 0.529),
        ("kobe-1995-nishi-akashi-000.csv", 4096, 0.01, 0.509),
    ];
    for (name, npts, dt, pga_g) in table {
        let gm = motion::load_path(&recorded(name)).expect(name);
        let s = sampled(&gm);
        assert_eq!(s.accel.len(), npts, "{name}: samples");
        assert!((s.dt - dt).abs() < 1e-9 * dt, "{name}: dt {} vs {dt}", s.dt);
        let pga = gm.pga() / STANDARD_GRAVITY;
        assert!(
            (pga - pga_g).abs() <= 0.0005,
            "{name}: PGA {pga:.5} g vs table {pga_g} g"
        );
        assert_eq!(gm.meta.original_units, Units::G, "{name}");
        let im = motion::report(&gm);
        assert!(
            (im.pga_original_units - pga).abs() < 1e-12,
            "{name}: PGA in original units"
        );
        assert!(
            gm.provenance.contains(name),
            "{name}: provenance {:?}",
            gm.provenance
        );
    }
}

/// Compare a parsed record with the synthetic signal × `scale` (in m/s² after `to_si`), to the
/// precision the file prints (`tol`, in the file's units).
fn check_synthetic(name: &str, units: Units, scale: f64, dt: f64, tol: f64, kind: RecordKind) {
    let gm = motion::load_path(&fixture(name)).unwrap_or_else(|e| panic!("{name}: {e}"));
    let s = sampled(&gm);
    assert_eq!(s.accel.len(), 23, "{name}: count");
    assert!((s.dt - dt).abs() < 1e-12, "{name}: dt {}", s.dt);
    assert_eq!(gm.meta.original_units, units, "{name}: units");
    assert_eq!(gm.meta.kind, kind, "{name}: kind");
    for (i, a) in s.accel.iter().enumerate() {
        let expected = scale * synthetic(i);
        let got = a / units.to_si();
        assert!(
            (got - expected).abs() <= tol,
            "{name}: sample {i}: {got} vs {expected}"
        );
    }
}

/// Old NGA header `N dt NPTS, DT`, `.dddd E` and `D` exponents, 8 a line, a short last line.
/// Tolerance: 4 significant digits printed → 5e-5 relative of values up to 0.09 g.
#[test]
fn at2_old_header_fortran_numbers() {
    check_synthetic(
        "old_style.at2",
        Units::G,
        1e-3,
        0.01,
        5e-6,
        RecordKind::Processed,
    );
}

/// NGA-West2 header with a trailing comma, CRLF line ends, 5E15.7. Tolerance: 8 digits.
#[test]
fn at2_new_header_crlf() {
    check_synthetic(
        "new_style.at2",
        Units::G,
        1e-3,
        0.01,
        1e-9,
        RecordKind::Processed,
    );
}

/// Semicolons, `# units: cm/s2` comment, a header without units. Tolerance: 5 decimals.
#[test]
fn csv_units_from_comment() {
    check_synthetic(
        "semicolon_units_comment.csv",
        Units::CentimetresPerSecond2,
        1.0,
        0.02,
        5e-6,
        RecordKind::Unknown,
    );
}

/// COSMOS V2: 13 text lines, 100-value headers, Δt = 5 ms at real index 61, F10.5 fields that
/// touch, a velocity block after the acceleration that must be ignored. Tolerance: 5 decimals.
#[test]
fn cosmos_v2_touching_fields() {
    check_synthetic(
        "synthetic.v2",
        Units::CentimetresPerSecond2,
        10.0,
        0.005,
        5e-6,
        RecordKind::Processed,
    );
}

/// COSMOS V1 (uncorrected → raw), `units=cm/s^2 (4)`, 10F8.3 touching fields. Tolerance: 3 decimals.
#[test]
fn cosmos_v1_is_raw() {
    check_synthetic(
        "synthetic.v1",
        Units::CentimetresPerSecond2,
        10.0,
        0.005,
        5e-4,
        RecordKind::Raw,
    );
}

/// ESM ASCII with the full header; PROCESSING names a procedure → processed. Tolerance: 7 digits.
#[test]
fn esm_full_header() {
    check_synthetic(
        "synthetic.asc",
        Units::CentimetresPerSecond2,
        1.0,
        0.01,
        1e-4,
        RecordKind::Processed,
    );
}

/// The same AT2 text embedded in docs/format.md §2 JSON reads to the same record, and JSON errors
/// inside embedded content name the JSON field and the content line.
#[test]
fn json_embedded_formats_match_files() {
    for (file, format) in [
        ("new_style.at2", "at2"),
        ("synthetic.v2", "cosmos"),
        ("synthetic.asc", "esm"),
        ("semicolon_units_comment.csv", "csv"),
    ] {
        let content = std::fs::read_to_string(fixture(file)).expect("fixture");
        let v = serde_json::json!({"horizontal": {"format": format, "content": content}, "scale": {"factor": 2.0}});
        let gm = motion::from_json(&v).unwrap_or_else(|e| panic!("{file}: {e}"));
        let direct = motion::load_path(&fixture(file)).expect(file);
        assert_eq!(sampled(&gm), sampled(&direct), "{file}");
        assert_eq!(gm.scale, 2.0);
        assert_eq!(gm.meta.original_units, direct.meta.original_units);
    }
    let v = serde_json::json!({"horizontal": {"format": "at2", "content": "a\nb\nc\nNPTS= 2, DT= 0.01 SEC\n0.1 oops\n"}});
    let e = motion::from_json(&v).expect_err("bad value");
    assert_eq!(e.origin, "motion.horizontal.content");
    assert_eq!(e.line, Some(5));
}

/// A docs/format.md §2 JSON file through load_path: target PGA in g, a cosine pulse.
#[test]
fn json_file_with_pulse_and_target_pga() {
    let dir = std::env::temp_dir().join(format!("ashlar-motion-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("tmp");
    let path = dir.join("pulse.json");
    std::fs::write(
        &path,
        r#"{"horizontal": {"pulse": {"shape": "cosine", "amplitude": 1.0, "period": 0.5, "cycles": 2, "units": "g"}},
            "scale": {"target_pga": 0.3, "units": "g"}}"#,
    )
    .expect("write");
    let gm = motion::load_path(&path).expect("json file");
    assert!((gm.pga() - 0.3 * STANDARD_GRAVITY).abs() < 1e-12);
    assert_eq!(gm.meta.kind, RecordKind::Analytic);
    assert!(gm.provenance.contains("pulse.json"));
}

/// Units given by the caller must agree with the file's, and a CSV without units in the file
/// takes the caller's.
#[test]
fn caller_units() {
    let dir = std::env::temp_dir().join(format!("ashlar-motion-units-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("tmp");
    let path = dir.join("plain.csv");
    std::fs::write(&path, "time,acc\n0,1\n0.01,2\n0.02,-3\n").expect("write");
    let p = LoadParams {
        units: Some(Units::CentimetresPerSecond2),
        ..LoadParams::default()
    };
    let gm = motion::load_path_with(&path, &p).expect("units given");
    assert!((gm.pga() - 0.03).abs() < 1e-15);
    let p = LoadParams {
        units: Some(Units::MetresPerSecond2),
        ..LoadParams::default()
    };
    let e = motion::load_path_with(&fixture("synthetic.v2"), &p).expect_err("conflict");
    assert!(e.to_string().contains("units conflict"), "{e}");
}

/// A multi-channel COSMOS file (two channels, as CESMD free-field files hold three) reads the
/// first channel and says so in the provenance.
#[test]
fn cosmos_multichannel_reads_first_channel() {
    let one = std::fs::read_to_string(fixture("synthetic.v2")).expect("fixture");
    let two = one.replace("0.00000 612.79882", "0.00000 999.00000");
    let dir = std::env::temp_dir().join(format!("ashlar-motion-multi-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("tmp");
    let path = dir.join("two.v2");
    std::fs::write(&path, format!("{one}{two}")).expect("write");
    let gm = motion::load_path(&path).expect("two channels");
    assert!(
        (sampled(&gm).accel[1] / 0.01 - 612.79882).abs() < 1e-9,
        "first channel's values"
    );
    assert!(
        gm.provenance.contains("channel 1 of 2"),
        "{}",
        gm.provenance
    );
}
