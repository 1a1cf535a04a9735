//! The dual solver against a second method: the penalty method in its stiff limit. Rigid
//! contact (the dual form) is what penalty DDA tends to as its spring stiffness k grows, so on
//! a scene where nothing slides or opens, the penalty runs at k = 1e14 and 1e16 N/m bracket the
//! limit, and the dual run at a tight tolerance must sit on it.
//!
//! The scene is the accuracy study's masonry wall (3 courses of 0.6 × 0.3 m blocks, φ = 35°,
//! Northridge Mulholland 009 scaled to 0.4 g; docs/accuracy-vs-speed.md). With tan φ = 0.70 >
//! 0.4 nothing slides: the top block moves by a few tenths of a micrometre, through the
//! compliance of its contacts and blocks. That motion is what the study's error measures, which
//! is why the study's penalty reference (k = "auto" = 2e11 N/m) sits 21 % from the stiff limit
//! and why the dual's default tolerance (1e-9 × half the block size, 3.4e-10 m a step) is
//! visible there (docs/dual.md, "The wall").
use ashlar::analysis::run::{run, RunOptions};
use ashlar::analysis::study::{wall_record, GROUND_MOTIONS_DIR};
use ashlar::motion::GroundMotion;
use ashlar::presets::study_wall_json;
use ashlar::record::Frame;
use ashlar::scene::scene_from_value;
use serde_json::{json, Value};
use std::sync::Mutex;

const DURATION: f64 = 3.0;

fn wall_and_record() -> (Value, GroundMotion) {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join(GROUND_MOTIONS_DIR);
    let gm = wall_record(&dir).expect("the wall's record (data/ground-motions)");
    (study_wall_json(), gm)
}

/// Horizontal displacement history (t, x) of the top block, every output frame.
fn top_block(solver: &str, penalty: Option<f64>, dual_tolerance: Option<f64>) -> Vec<(f64, f64)> {
    let (mut v, gm) = wall_and_record();
    let top = v["blocks"].as_array().map(|b| b.len() - 1).expect("blocks");
    v["control"] = json!({ "duration": DURATION, "time_step": 1e-3,
        "max_displacement_ratio": 1e-3, "contact_solver": solver, "model": "dda" });
    if let Some(k) = penalty {
        v["control"]["penalty_stiffness"] = json!(k);
    }
    if let Some(t) = dual_tolerance {
        v["control"]["dual_tolerance"] = json!(t);
    }
    let scene = scene_from_value(&v).expect("valid scene");
    let frames = Mutex::new(Vec::new());
    let record = |f: &Frame| {
        frames
            .lock()
            .expect("frames")
            .push((f.time, f.blocks[top].x))
    };
    let opts = RunOptions {
        on_frame: Some(&record),
        ..Default::default()
    };
    let out = run(&scene, &gm, &opts).expect("run");
    assert!(
        out.summary.completed,
        "{solver}: {:?}",
        out.summary.stopped_reason
    );
    assert_eq!(
        out.summary.diagnostics.time_step_cuts, 0,
        "{solver}: Δt was cut"
    );
    frames.into_inner().expect("frames")
}

/// Largest |a − b| over the common frames, m.
fn distance(a: &[(f64, f64)], b: &[(f64, f64)]) -> f64 {
    assert_eq!(a.len(), b.len(), "same output frames");
    a.iter()
        .zip(b)
        .map(|(p, q)| {
            assert!((p.0 - q.0).abs() < 1e-9, "frame times differ");
            (p.1 - q.1).abs()
        })
        .fold(0.0, f64::max)
}

#[test]
fn dual_sits_on_the_penalty_methods_stiff_limit() {
    let stiff = top_block("penalty", Some(1e14), None);
    let stiffer = top_block("penalty", Some(1e16), None);
    let dual = top_block("dual", None, Some(1e-13));
    let peak = stiffer.iter().map(|p| p.1.abs()).fold(0.0, f64::max);
    // The motion is real but tiny: tenths of a micrometre.
    assert!(peak > 1e-7 && peak < 1e-6, "peak {peak:e} m");
    let penalty_spread = distance(&stiff, &stiffer);
    let dual_off = distance(&dual, &stiffer);
    eprintln!(
        "peak {peak:.4e} m; penalty k = 1e14 vs 1e16: {:.4} %; dual (1e-13) vs penalty 1e16: {:.4} %",
        100.0 * penalty_spread / peak,
        100.0 * dual_off / peak
    );
    // Error budget of the comparison, each part stated:
    // - the penalty run at 1e16 is within O(1/k) of the limit: its distance is at most the
    //   spread between 1e14 and 1e16 (the spread shrinks ~100× per 100× in k);
    // - the dual leaves a residual of at most its tolerance a step, 1e-13 × the smallest half
    //   block size (0.3354 m), accumulated over the 3000 steps at worst.
    let dual_budget = 3000.0 * 1e-13 * 0.3354;
    let budget = penalty_spread + dual_budget;
    assert!(
        dual_off <= budget,
        "dual vs penalty's stiff limit: {dual_off:.3e} m > budget {budget:.3e} m (penalty spread {penalty_spread:.3e}, dual {dual_budget:.3e})"
    );
    // The budget itself is small against the motion, so the check is sharp: 0.2 % of the peak.
    assert!(
        budget < 2e-3 * peak,
        "budget {budget:e} m against peak {peak:e} m"
    );
}
