//! PGA search with a displacement criterion (docs/pga.md): a rigid block on a 20° incline (friction
//! angle 30°) under a steady horizontal sine of 1 Hz for 3 s; criterion
//! `displacement:block:0.05` (residual centroid displacement ≥ 5 cm).
//!
//! Reference: an independent rigid-plastic Newmark integration (`ashlar::analysis::reference`:
//! semi-implicit Euler, Δt = 1e-5 s, stick/slip with the exact Coulomb law, both directions;
//! tests/engine/sliding_newmark.rs checks the engine's displacement histories against it),
//! and a direct bisection on its final displacement to 1e-5 relative.
//!
//! Tolerance: the engine's threshold (midpoint of a 0.01 m/s² bracket) within 2 % of the
//! reference threshold (docs/verification.md's bound). The bracket must also be honest: a full run (no
//! early stop) at `safe_pga` moves the block less than 5 cm, at `failing_pga` at least 5 cm.
use crate::common;
use ashlar::analysis::pga::{search, Combine, Criterion, PgaRequest};
use ashlar::analysis::reference::newmark_incline;
use ashlar::analysis::run::{run as run_scene, RunOptions};
use common::*;
use serde_json::json;

const ALPHA: f64 = 20.0;
const PHI: f64 = 30.0;
const F: f64 = 1.0;
const T_END: f64 = 3.0;
const LIMIT: f64 = 0.05;

/// Final down-slope displacement (m) of the rigid block relative to the ground under
/// a_g(t) = A sin(2πFt).
fn newmark(a: f64) -> f64 {
    let sine = |t: f64| a * (2.0 * std::f64::consts::PI * F * t).sin();
    newmark_incline(ALPHA.to_radians(), PHI.to_radians(), G, sine, T_END, 1e-5)
}

#[test]
fn displacement_threshold_matches_newmark_bisection() {
    let (mut lo, mut hi) = (0.5, 5.0);
    assert!(newmark(lo).abs() < LIMIT && newmark(hi).abs() >= LIMIT);
    while hi - lo > 1e-5 * hi {
        let m = 0.5 * (lo + hi);
        if newmark(m).abs() >= LIMIT {
            hi = m;
        } else {
            lo = m;
        }
    }
    let reference = 0.5 * (lo + hi);

    let (v, _) = incline(
        ALPHA,
        PHI,
        // The engine is measured here ("auto" would run the reduced Newmark model).
        json!({ "time_step": 1e-3, "block_model": "rigid", "duration": T_END, "model": "dda" }),
    );
    let scene = parse(&v);
    let criterion = format!("displacement:block:{LIMIT}");
    let req = PgaRequest {
        criteria: vec![Criterion::parse(&criterion).expect("criterion")],
        combine: Combine::All,
        min: 0.5,
        max: 5.0,
        tolerance: 0.01,
        scan_points: 8,
        resolution: None,
        scan: ashlar::analysis::pga::ScanOrder::Full,
    };
    let unit = sine(1.0, F);
    let r = search(&scene, &unit, &req, &RunOptions::default()).expect("search");
    let (s, f) = (r.safe_pga.expect("safe"), r.failing_pga.expect("failing"));
    let dda = 0.5 * (s + f);
    eprintln!(
        "displacement {LIMIT} m: Newmark threshold {reference:.4} m/s², DDA bracket [{s:.4}, {f:.4}] ({:+.2} %), {} runs, monotonic {}",
        100.0 * (dda / reference - 1.0),
        r.runs.len(),
        r.monotonic
    );
    assert!(f - s <= 0.01 + 1e-12);
    assert!((dda / reference - 1.0).abs() < 0.02);
    // Regression bound: 5× the +0.13 % measured 2026-11-25 (the bracket is 0.44 % wide).
    assert!(
        (dda / reference - 1.0).abs() < REGRESSION_PGA_INCLINE,
        "within 2 % but beyond the regression bound {REGRESSION_PGA_INCLINE} (find what changed)"
    );

    // Honesty with full runs (no early stop).
    let moved = |pga: f64| {
        let out = run_scene(&scene, &unit.scaled_to_pga(pga), &RunOptions::default()).expect("run");
        let d = out.summary.blocks[0].final_displacement;
        d[0].hypot(d[1])
    };
    let (ds, df) = (moved(s), moved(f));
    eprintln!("full runs: {ds:.4} m at safe_pga, {df:.4} m at failing_pga");
    assert!(ds < LIMIT && df >= LIMIT);
}

/// Regression bound on the displacement-criterion PGA against Newmark: 5× the +0.13 % measured
/// 2026-11-25 (`cargo test --test analysis -- pga_incline --nocapture`).
const REGRESSION_PGA_INCLINE: f64 = 0.0065;
