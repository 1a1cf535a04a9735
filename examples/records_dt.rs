//! Measures the full engine's Δt error on real records (docs/accuracy-vs-speed.md, "Records"): the two columns of
//! `analysis::study_records` under the repository's records scaled to several PGAs, the engine
//! at a list of step controls against Housner's equation (independent RK4) and against the
//! engine at a fixed-step ceiling of 1e-4 s without the impact location (a converged run).
//! Prints one line per (column, record, PGA, control): peak |θ|, fell, error against Housner
//! and against the converged run, steps, cuts, wall time.
//! Run: `cargo run --release --example records_dt -- [records…]` (default: Friuli only);
//! `ASHLAR_LEVELS="0.3 0.5"` picks the PGA levels (g), `ASHLAR_BLOCK=rigid` the block model, `ASHLAR_COLUMNS="0"` the column, `ASHLAR_ROBUST=1` Housner's verdict at ±3 % of the PGA.
use ashlar::analysis::study_records::{self as sr, COLUMNS};
use ashlar::simulation::SimParams;
use serde_json::json;
use std::path::Path;

fn main() {
    let dir = Path::new("data/ground-motions");
    let args: Vec<String> = std::env::args().skip(1).collect();
    let records: Vec<String> = if args.is_empty() {
        vec![sr::RECORDS[0].to_string()]
    } else {
        args
    };
    let levels: Vec<f64> = std::env::var("ASHLAR_LEVELS")
        .unwrap_or_else(|_| "0.3 0.4 0.5 0.6 0.7 0.8 0.9 1.0".into())
        .split_whitespace()
        .filter_map(|s| s.parse().ok())
        .collect();
    let block = std::env::var("ASHLAR_BLOCK").unwrap_or_else(|_| "deformable".into());
    // ASHLAR_VARIANTS: comma-separated list of `old` (the defaults before the rocking step
    // control, `SimParams::rocking_velocity_change` off), `new` (the defaults), `rock:C` (the
    // rocking control at C), `trap` (the trapezoidal integrator, rocking control off), `imp:R` (impact_approach_ratio R), `rot:R`
    // (max_rotation_step R rad, no impact location), `dt:S` (time_step S, no impact location), `hand`
    // (ImpactParams::hand_over_weight with slow_factor 0), `handover` (hand_over_weight alone),
    // `hand4` (`hand` at the converged run's Δt 1e-4 s and params).
    let spec = std::env::var("ASHLAR_VARIANTS").unwrap_or_else(|_| "old,new".into());
    let no_impact = SimParams {
        impact_approach_ratio: None,
        rocking_velocity_change: None,
        ..SimParams::default()
    };
    let variants: Vec<(String, serde_json::Value, SimParams)> = spec
        .split(',')
        .map(|v| {
            let v = v.trim();
            // A `d` prefix runs the variant with the dual contact solver.
            let (dual, v) = match v.strip_prefix('d') {
                Some(rest) if !v.starts_with("dt:") => (true, rest),
                _ => (false, v),
            };
            let num = |p: &str| v[p.len()..].parse::<f64>().expect("variant value");
            let (c, p) = if v == "old" {
                (json!({}), no_impact)
            } else if v == "new" {
                (json!({}), SimParams::default())
            } else if v == "trap" {
                (json!({ "integrator": "trapezoidal" }), no_impact)
            } else if v.starts_with("rock:") {
                let r = num("rock:");
                (
                    json!({}),
                    SimParams {
                        rocking_velocity_change: Some(r),
                        ..SimParams::default()
                    },
                )
            } else if v.starts_with("imp:") {
                let r = num("imp:");
                (
                    json!({}),
                    SimParams {
                        impact_approach_ratio: Some(r),
                        ..SimParams::default()
                    },
                )
            } else if v.starts_with("rot:") {
                let r = num("rot:");
                (
                    json!({}),
                    SimParams {
                        max_rotation_step: Some(r),
                        ..no_impact
                    },
                )
            } else if v.starts_with("err:") {
                let r = num("err:");
                (
                    json!({}),
                    SimParams {
                        local_error_ratio: Some(r),
                        ..no_impact
                    },
                )
            } else if v.starts_with("errimp:") {
                let r = num("errimp:");
                (
                    json!({}),
                    SimParams {
                        local_error_ratio: Some(r),
                        ..SimParams::default()
                    },
                )
            } else if v == "hand" {
                // ImpactParams::hand_over_weight with every landing an impact (slow_factor 0).
                let mut p = SimParams::default();
                p.impact.hand_over_weight = true;
                p.impact.slow_factor = 0.0;
                (json!({}), p)
            } else if v == "hand4" {
                // `hand` at the converged run's Δt = 1e-4 s and its params (no rocking
                // step control beyond the defaults').
                let mut p = SimParams {
                    impact_approach_ratio: None,
                    ..SimParams::default()
                };
                p.impact.hand_over_weight = true;
                p.impact.slow_factor = 0.0;
                (json!({ "time_step": 1e-4 }), p)
            } else if v == "handover" {
                // ImpactParams::hand_over_weight alone (slow landings left to the springs).
                let mut p = SimParams::default();
                p.impact.hand_over_weight = true;
                (json!({}), p)
            } else if v.starts_with("dt:") {
                (json!({ "time_step": num("dt:") }), no_impact)
            } else {
                panic!("unknown variant {v}")
            };
            let mut c = c;
            if dual {
                c["contact_solver"] = json!("dual");
            }
            (format!("{}{v}", if dual { "dual " } else { "" }), c, p)
        })
        .collect();
    let converged = SimParams {
        impact_approach_ratio: None,
        ..SimParams::default()
    };
    println!("column | record | PGA g | control | peak rad | fell | err vs Housner | err vs dt=1e-4 | steps | cuts | wall s");
    // ASHLAR_COLUMNS="0" or "1" picks one of the two columns (default both).
    let columns: Vec<usize> = std::env::var("ASHLAR_COLUMNS")
        .unwrap_or_else(|_| "0 1".into())
        .split_whitespace()
        .filter_map(|s| s.parse().ok())
        .collect();
    for col in columns.iter().map(|&i| &COLUMNS[i]) {
        for rec in &records {
            for &pga in &levels {
                let m = sr::load_record(dir, rec, pga).expect("record");
                let t_end = sr::run_length(&m);
                let h = sr::housner(col, &m, t_end, sr::HOUSNER_DT);
                let ctl = |c: &serde_json::Value| {
                    let mut c = c.clone();
                    c["block_model"] = json!(block);
                    c
                };
                let conv = sr::engine(
                    col,
                    &m,
                    t_end,
                    &ctl(&json!({ "time_step": 1e-4 })),
                    converged,
                )
                .expect("engine");
                // Conditioning: Housner's own peak at ±1 % of the PGA.
                let hp = |f: f64| {
                    let m = sr::load_record(dir, rec, pga * f).expect("record");
                    sr::housner(col, &m, t_end, sr::HOUSNER_DT).peak
                };
                // ASHLAR_ROBUST=1: Housner's verdict at 0.97 and 1.03 × the PGA too (the records
                // study's *robust*), printed as `robust true|false`.
                let robust = if std::env::var("ASHLAR_ROBUST").as_deref() == Ok("1") {
                    let (_, r) = sr::robust_verdict(col, dir, rec, pga).expect("record");
                    format!(" robust {r}")
                } else {
                    String::new()
                };
                println!(
                    "{} | {rec} | {pga:.2} | HOUSNER | {:.5} | {} | ±1 % PGA: {:+.2} % {:+.2} %{robust} | | | |",
                    col.name,
                    h.peak,
                    h.fallen,
                    100.0 * (hp(0.99) / h.peak - 1.0),
                    100.0 * (hp(1.01) / h.peak - 1.0)
                );
                println!(
                    "{} | {rec} | {pga:.2} | dt=1e-4 | {:.5} | {} | {:+.2} % | | {} | {} | {:.2}",
                    col.name,
                    conv.response.peak,
                    conv.response.fallen,
                    100.0 * (conv.response.peak / h.peak - 1.0),
                    conv.steps,
                    conv.cuts,
                    conv.wall
                );
                for (name, c, p) in &variants {
                    let r = sr::engine(col, &m, t_end, &ctl(c), *p).expect("engine");
                    println!(
                        "{} | {rec} | {pga:.2} | {name} | {:.5} | {} | {:+.2} % | {:+.2} % | {} | {} | {:.2}{}",
                        col.name,
                        r.response.peak,
                        r.response.fallen,
                        100.0 * (r.response.peak / h.peak - 1.0),
                        100.0 * (r.response.peak / conv.response.peak - 1.0),
                        r.steps,
                        r.cuts,
                        r.wall,
                        r.failed.map(|f| format!(" FAILED {f}")).unwrap_or_default()
                    );
                }
            }
        }
    }
}
