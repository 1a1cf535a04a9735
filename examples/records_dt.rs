//! Measures the full engine's Δt error on real records (docs/accuracy-vs-speed.md, "Records"): the two columns of
//! `analysis::study_records` under the repository's records scaled to several PGAs, the engine
//! at a list of step controls against Housner's equation (independent RK4) and against the
//! engine at a fixed-step ceiling of 1e-4 s without the impact location (a converged run).
//! Prints one line per (column, record, PGA, control): peak |θ|, fell, error against Housner
//! and against the converged run, steps, cuts, wall time.
//! Run: `cargo run --release --example records_dt -- [records…]` (default: Friuli only);
//! `ASHLAR_LEVELS="0.3 0.5"` picks the PGA levels (g), `ASHLAR_BLOCK=rigid` the block model, `ASHLAR_COLUMNS="0"` the column, `ASHLAR_ROBUST=1` Housner's verdict at ±3 % of the PGA.
//! The HOUSNER line gives Housner's own peak at ±1 % of the PGA and flags `ill-conditioned` a peak
//! target where it moves by more than `study_records::ILL_CONDITIONED` (5 %).
//! `ASHLAR_CONDITION=1` replaces the comparison by the conditioning of each point (docs/accuracy-vs-speed.md,
//! "The last misses, conditioned"): Housner's peak on a grid of PGA × (0.94 … 1.06) and the
//! engine's (default controls) at PGA × (1 ± 0.01), (1 ± 0.03), with the PGA shift that takes
//! Housner's curve onto each engine point.
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
    // `hand4` (`hand` at the converged run's Δt 1e-4 s and params), `hslow:F` (hand_over_weight
    // with its own threshold, `ImpactParams::hand_over_below` = F; the default since session 38
    // is `hslow:2`), `prehand` (the defaults before session 38: no hand-over).
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
                p.impact.hand_over_below = None;
                p.impact.slow_factor = 0.0;
                (json!({}), p)
            } else if v == "prehand" {
                // The defaults before session 38: no hand-over.
                let mut p = SimParams::default();
                p.impact.hand_over_weight = false;
                p.impact.hand_over_below = None;
                (json!({}), p)
            } else if v == "hand4" {
                // `hand` at the converged run's Δt = 1e-4 s and its params (no rocking
                // step control beyond the defaults').
                let mut p = SimParams {
                    impact_approach_ratio: None,
                    ..SimParams::default()
                };
                p.impact.hand_over_weight = true;
                p.impact.hand_over_below = None;
                p.impact.slow_factor = 0.0;
                (json!({ "time_step": 1e-4 }), p)
            } else if v == "handover" {
                // ImpactParams::hand_over_weight alone (slow landings left to the springs).
                let mut p = SimParams::default();
                p.impact.hand_over_weight = true;
                p.impact.hand_over_below = None;
                (json!({}), p)
            } else if v.starts_with("hslow:") {
                // The hand-over only for pivot landings slower than F g Δt, which are impacts
                // however slow; the rest at the defaults.
                let mut p = SimParams::default();
                p.impact.hand_over_weight = true;
                p.impact.hand_over_below = Some(num("hslow:"));
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
    let condition = std::env::var("ASHLAR_CONDITION").as_deref() == Ok("1");
    for col in columns.iter().map(|&i| &COLUMNS[i]) {
        for rec in &records {
            for &pga in &levels {
                if condition {
                    conditioning(col, dir, rec, pga, &block);
                    continue;
                }
                let m = sr::load_record(dir, rec, pga).expect("record");
                let t_end = sr::run_length(&m);
                let h = sr::housner(col, &m, t_end, sr::HOUSNER_DT);
                let ctl = |c: &serde_json::Value| {
                    let mut c = c.clone();
                    c["block_model"] = json!(block);
                    c
                };
                // ASHLAR_SKIP_CONVERGED=1 leaves the 1e-4 s run out (its columns then read
                // against the first variant): it takes most of the study's time.
                let skip = std::env::var("ASHLAR_SKIP_CONVERGED").as_deref() == Ok("1");
                let conv = if skip {
                    let (_, c, p) = &variants[0];
                    sr::engine(col, &m, t_end, &ctl(c), *p)
                } else {
                    sr::engine(
                        col,
                        &m,
                        t_end,
                        &ctl(&json!({ "time_step": 1e-4 })),
                        converged,
                    )
                }
                .expect("engine");
                // Conditioning: Housner's own peak at ±1 % of the PGA, and the study's flag.
                let hp = |f: f64| {
                    let m = sr::load_record(dir, rec, pga * f).expect("record");
                    sr::housner(col, &m, t_end, sr::HOUSNER_DT)
                };
                let near = [hp(0.99), hp(1.01)];
                let ill = sr::ill_conditioned_peak(&h, sr::spread_of(&h, &near));
                // ASHLAR_ROBUST=1: Housner's verdict at 0.97 and 1.03 × the PGA too (the records
                // study's *robust*), printed as `robust true|false`.
                let robust = if std::env::var("ASHLAR_ROBUST").as_deref() == Ok("1") {
                    let (_, r) = sr::robust_verdict(col, dir, rec, pga).expect("record");
                    format!(" robust {r}")
                } else {
                    String::new()
                };
                println!(
                    "{} | {rec} | {pga:.2} | HOUSNER | {:.5} | {} | ±1 % PGA: {:+.2} % {:+.2} %{robust}{} | | | |",
                    col.name,
                    h.peak,
                    h.fallen,
                    100.0 * (near[0].peak / h.peak - 1.0),
                    100.0 * (near[1].peak / h.peak - 1.0),
                    if ill { " ill-conditioned" } else { "" }
                );
                println!(
                    "{} | {rec} | {pga:.2} | {} | {:.5} | {} | {:+.2} % | | {} | {} | {:.2}",
                    col.name,
                    if skip {
                        "first variant (1e-4 s skipped)"
                    } else {
                        "dt=1e-4"
                    },
                    conv.response.peak,
                    conv.response.fallen,
                    100.0 * (conv.response.peak / h.peak - 1.0),
                    conv.steps,
                    conv.cuts,
                    conv.wall
                );
                for (i, (name, c, p)) in variants.iter().enumerate() {
                    let r = if skip && i == 0 {
                        conv.clone()
                    } else {
                        sr::engine(col, &m, t_end, &ctl(c), *p).expect("engine")
                    };
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

/// Housner's grid for the PGA shift: PGA × (1 + k·0.5 %), k = −12 … 12 (so an engine point at
/// ±3 % can be matched up to a further ±3 %).
const SHIFT_STEP: f64 = 0.005;
const SHIFT_HALF: i32 = 12;
/// The engine's factors: the ±1 % and ±3 % of the verdict rule, and the point itself.
const ENGINE_FACTORS: [f64; 5] = [0.97, 0.99, 1.0, 1.01, 1.03];

/// A response as a number on one axis: the peak, or +∞ once fallen (a fall is beyond every
/// standing peak).
fn level(r: &sr::Response) -> f64 {
    if r.fallen {
        f64::INFINITY
    } else {
        r.peak
    }
}

/// The PGA factor nearest to `f0` at which Housner's curve `h` (factor, level; ascending in
/// factor) takes the value `y`: linear between two standing neighbours, the midpoint between a
/// standing and a fallen one (a fall is reached somewhere in that interval), the grid point for
/// equal falls. `None` if the curve does not take `y` on the grid.
fn pga_match(h: &[(f64, f64)], y: f64, f0: f64) -> Option<f64> {
    let mut best: Option<f64> = None;
    let mut take = |f: f64| {
        if best.is_none_or(|b| (f - f0).abs() < (b - f0).abs()) {
            best = Some(f);
        }
    };
    for &(f, v) in h {
        if v == y {
            take(f);
        }
    }
    for w in h.windows(2) {
        let ((fa, a), (fb, b)) = (w[0], w[1]);
        if (a - y) * (b - y) >= 0.0 && !(a.is_infinite() || b.is_infinite()) {
            continue;
        }
        if a.is_finite() && b.is_finite() {
            take(fa + (y - a) / (b - a) * (fb - fa));
        } else if a.is_finite() != b.is_finite() && y > a.min(b) {
            take(0.5 * (fa + fb));
        }
    }
    best
}

fn show(r: &sr::Response) -> String {
    if r.fallen {
        "falls".into()
    } else {
        format!("{:.5}", r.peak)
    }
}

/// ASHLAR_CONDITION=1: how well posed the point is (see the module doc).
fn conditioning(col: &sr::RecordColumn, dir: &Path, rec: &str, pga: f64, block: &str) {
    let housner_at = |f: f64| {
        let m = sr::load_record(dir, rec, pga * f).expect("record");
        sr::housner(col, &m, sr::run_length(&m), sr::HOUSNER_DT)
    };
    let grid: Vec<(f64, sr::Response)> = (-SHIFT_HALF..=SHIFT_HALF)
        .map(|k| {
            let f = 1.0 + f64::from(k) * SHIFT_STEP;
            (f, housner_at(f))
        })
        .collect();
    let curve: Vec<(f64, f64)> = grid.iter().map(|(f, r)| (*f, level(r))).collect();
    let at = |f: f64| {
        &grid
            .iter()
            .find(|(g, _)| (g - f).abs() < 1e-9)
            .expect("grid point")
            .1
    };
    let mid = at(1.0);
    // Housner's own spread: the largest relative change of its peak within ±1 % and ±3 %.
    let spread = |w: f64| {
        let near: Vec<sr::Response> = grid
            .iter()
            .filter(|(f, _)| (f - 1.0).abs() <= w + 1e-9)
            .map(|(_, r)| *r)
            .collect();
        sr::spread_of(mid, &near)
    };
    let pct = |x: f64| {
        if x.is_finite() {
            format!("{:.1} %", 100.0 * x)
        } else {
            "verdict flips".into()
        }
    };
    println!(
        "CONDITION {} | {rec} | {pga:.2} g | Housner {} | spread ±1 %: {} | ±3 %: {}",
        col.name,
        show(mid),
        pct(spread(0.01)),
        pct(spread(0.03))
    );
    let housner_row: Vec<String> = grid
        .iter()
        .filter(|(f, _)| (f - 1.0).abs() <= 0.03 + 1e-9)
        .map(|(f, r)| format!("{f:.3}:{}", show(r)))
        .collect();
    println!("  Housner {}", housner_row.join(" "));
    // Housner's band over ±3 %: the lowest and highest level (a fall is +∞).
    let band = grid
        .iter()
        .filter(|(f, _)| (f - 1.0).abs() <= 0.03 + 1e-9)
        .map(|(_, r)| level(r))
        .fold((f64::INFINITY, 0.0f64), |(lo, hi), v| {
            (lo.min(v), hi.max(v))
        });
    let mut worst: f64 = 0.0;
    for f in ENGINE_FACTORS {
        let m = sr::load_record(dir, rec, pga * f).expect("record");
        let ctl = json!({ "block_model": block });
        let e =
            sr::engine(col, &m, sr::run_length(&m), &ctl, SimParams::default()).expect("engine");
        let h = at(f);
        let err = if e.response.fallen || h.fallen {
            if e.response.fallen == h.fallen {
                "same verdict".to_string()
            } else {
                "verdict differs".to_string()
            }
        } else {
            format!("{:+.1} %", 100.0 * (e.response.peak / h.peak - 1.0))
        };
        let shift = pga_match(&curve, level(&e.response), f).map(|g| g / f - 1.0);
        worst = worst.max(shift.map_or(f64::INFINITY, f64::abs));
        // The engine's level against Housner's band over ±3 % of the PGA: 0 inside it, else
        // the relative distance to its nearer edge.
        let y = level(&e.response);
        let outside = if y < band.0 {
            format!("{:+.1} % below", 100.0 * (y / band.0 - 1.0))
        } else if y > band.1 {
            format!("{:+.1} % above", 100.0 * (y / band.1 - 1.0))
        } else {
            "inside".into()
        };
        println!(
            "  engine × {f:.2}: {} ({err} vs Housner × {f:.2}); Housner's curve reaches it at a PGA shift of {}; Housner's ±3 % band: {outside}",
            show(&e.response),
            shift.map_or("none on Housner's grid (PGA × 0.94–1.06)".into(), |s| format!("{:+.2} %", 100.0 * s))
        );
    }
    println!(
        "  largest PGA shift over the five engine points: {}",
        if worst.is_finite() {
            format!("{:.2} %", 100.0 * worst)
        } else {
            "beyond the grid".into()
        }
    );
}
