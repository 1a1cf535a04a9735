//! What broke (session 31): with `auto`'s fallback handed over to the engine at the reduced
//! model's last valid record sample in the PGA search's runs but started at t = 0 in `ashlar
//! run`, the search bracketed the slender column under Friuli (9 s window) at (6.9123,
//! 6.9325] m/s² and a full run at 6.9325 did not topple it. Now both take the same path
//! (`analysis::run_fallback`): at the amplitudes around that bracket, the search's evaluation
//! (early stop once decided) and a full run (no early stop, outputs written as `ashlar run`
//! writes them) give the same verdict, and at least one of them is a handed-over run (else
//! this test would not test the hand-over).
//!
//! Exact check (no tolerance): both are deterministic and share every step up to the early
//! stop.
use crate::common::*;
use ashlar::analysis::pga::{evaluate, Criterion};
use ashlar::analysis::run::{run, RunOptions};
use serde_json::json;

#[test]
fn a_full_run_gives_the_search_verdict_where_auto_hands_over() {
    let scene = parse(&Column::SLENDER.json(json!({ "duration": 9.0 })));
    let gm = record("friuli-1976-tolmezzo-000.at2");
    let criteria = [Criterion::parse("toppled:column").expect("criterion")];
    let dir = std::path::Path::new(env!("CARGO_TARGET_TMPDIR")).join("regression_handover");
    let mut handed_over = 0;
    for pga in [6.9123, 6.9325, 6.95, 7.0] {
        let searched = evaluate(&scene, &gm, &criteria, pga, None).expect("evaluate");
        let out = run(
            &scene,
            &gm.scaled_to_pga(pga),
            &RunOptions {
                out_dir: Some(&dir),
                no_trajectory: true,
                ..Default::default()
            },
        )
        .expect("run")
        .summary;
        let full = out.blocks[0].final_rotation.abs() > 30f64.to_radians();
        println!(
            "{pga} m/s²: search {searched}, full run {full} ({}: {})",
            out.model, out.model_reason
        );
        assert_eq!(searched, full, "{pga} m/s²: {}", out.model_reason);
        handed_over += usize::from(out.model_reason.contains("ran from t = "));
    }
    std::fs::remove_dir_all(&dir).ok();
    assert!(handed_over > 0, "no run handed over");
}
