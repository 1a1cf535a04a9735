//! Several observations at one site (docs/observations.md; `analysis::observations`): two
//! free-standing columns on one base, 4 m apart so that neither can fall on the other, under
//! the half-sine pulse of the engine issue (1 s period, rescaled by the search).
//!
//! Column A is the rocking column of tests/analysis/pga_search.rs (0.4 × 1.2 m), whose
//! overturning amplitude is Housner's 5.64 m/s² (independent RK4 in tests/engine/rocking.rs);
//! column B is stockier (0.6 × 1.2 m, tan α = 0.5), so it cannot even start rocking below
//! g·tan α = 4.905 m/s² (Housner's uplift condition), and overturns well above A.
//!
//! - "A fell, B stands": the lower bound is A's threshold, within the 2 % of pga_search.rs, and
//!   the interval is consistent (B's bound lies above it).
//! - "B fell, A stands" is physically inconsistent: the interval must come out empty.
//!
//! The fallen-A observation is written in the JSON damage syntax (`analysis::criteria`), so the
//! search also runs through a damage criterion.
use crate::common;
use ashlar::analysis::observations::{site_interval, Observation};
use ashlar::analysis::pga::{Combine, Criterion, PgaRequest};
use ashlar::analysis::run::RunOptions;
use ashlar::motion::GroundMotion;
use common::*;
use serde_json::json;

fn site() -> ashlar::scene::Scene {
    let blocks = json!([
        { "id": "base", "material": "stone", "fixed": true, "vertices": rect(-2.0, -0.5, 6.0, 0.0) },
        { "id": "A", "material": "stone", "block_model": "rigid", "vertices": rect(-0.2, 0.0, 0.2, 1.2) },
        { "id": "B", "material": "stone", "block_model": "rigid", "vertices": rect(3.7, 0.0, 4.3, 1.2) },
    ]);
    parse(&scene_json(
        blocks,
        75.0,
        json!({ "duration": 3.0, "model": "dda" }),
    ))
}

fn pulse() -> GroundMotion {
    rocking_pulse(1.0)
}

fn obs(text: &str, observed: bool) -> Observation {
    Observation {
        criterion: Criterion::parse(text).unwrap_or_else(|e| panic!("{text}: {e}")),
        observed,
    }
}

fn request() -> PgaRequest {
    PgaRequest {
        criteria: Vec::new(),
        combine: Combine::All,
        min: 2.0,
        max: 12.0,
        tolerance: 0.02,
        scan_points: 6,
        resolution: None,
        scan: ashlar::analysis::pga::ScanOrder::Full,
    }
}

#[test]
fn one_fallen_one_standing_brackets_the_pga_and_the_reverse_is_inconsistent() {
    let scene = site();
    let housner = 5.64;
    let a_fell = obs(r#"{"kind":"fallen","blocks":["A"]}"#, true);
    let b_stands = obs("toppled:B", false);
    let r = site_interval(
        &scene,
        &pulse(),
        &[a_fell, b_stands],
        &request(),
        &RunOptions::default(),
    )
    .unwrap_or_else(|e| panic!("{e}"));
    eprintln!("A fell, B stands: {r:?}");
    assert!(r.consistent, "{r:?}");
    assert!(
        r.lower <= housner * 1.02 && r.lower + 0.02 >= housner * 0.98,
        "lower bound {} vs Housner's {housner} for A",
        r.lower
    );
    assert!(r.upper > 0.5 * G, "B cannot topple below g tan α: {r:?}");

    let b_fell = obs("toppled:B", true);
    let a_stands = obs("toppled:A", false);
    let r = site_interval(
        &scene,
        &pulse(),
        &[b_fell, a_stands],
        &request(),
        &RunOptions::default(),
    )
    .unwrap_or_else(|e| panic!("{e}"));
    eprintln!("B fell, A stands: {r:?}");
    assert!(!r.consistent, "B falls only above A's threshold: {r:?}");
    assert!(r.upper <= housner * 1.02, "{r:?}");
}
