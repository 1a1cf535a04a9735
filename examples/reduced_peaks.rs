//! The reduced rocking model's peaks on records against two independent answers
//! (docs/accuracy-vs-speed.md, "Reduced models on records", session 33): the points of
//! `examples/handover_study.rs` at 0.90–1.10 × each threshold F (the column of
//! `examples/column.json`, the slender 0.24 × 1.6 m column, and the slender one over the
//! records' first 9 s, under every record in `data/ground-motions/`), where the study compared
//! `auto` against the engine at Δt = 1e-4 s only. At each point:
//! (a) `auto` (the default run; the reduced model where it does not fall back),
//! (h) Housner's equation (`analysis::reference`, RK4 at 1e-5 s with located impacts) over the
//! same simulated time, and at 2e-6 s to show it converged,
//! (c) the engine from t = 0 at Δt = 1e-4 s (`"model": "dda"`),
//! and the conditioning of the point: Housner's peak at 0.99 and 1.01 × the PGA (well
//! conditioned: it moves ≤ 3 %, the records study's rule) and its verdict at 0.97 and 1.03 ×
//! (robust: the same verdict, the rule). Prints one row per point where (c) or (h)
//! stands above 0.02 rad and the counts of peaks within 5 %.
//!
//! Run: `cargo run --release --example reduced_peaks` (7 min at 2 threads on the loaded machine).
use ashlar::analysis::pga::{search, Criterion, PgaRequest};
use ashlar::analysis::reduced::{self, ReducedParams};
use ashlar::analysis::reference::{housner_rocking, HousnerColumn};
use ashlar::analysis::run::{run, RunOptions, Tracker};
use ashlar::motion::GroundMotion;
use ashlar::presets::{self, Column};
use ashlar::scene::{parse_scene, ModelChoice, Scene};
use rayon::prelude::*;
use serde_json::json;

/// The points of handover_study: fractions of the threshold F.
const FACTORS: [f64; 7] = [0.90, 0.95, 0.98, 1.00, 1.02, 1.05, 1.10];
/// Past this |θ| (rad) Housner's column has fallen (the records study's rule).
const FALLEN: f64 = 1.0;

/// Verdict, peak |θ| (rad), model that ran, simulated time (s).
struct Ran {
    fell: bool,
    peak: f64,
    model: String,
    time: f64,
}

fn point(scene: &Scene, gm: &GroundMotion) -> Ran {
    let stop = |tr: &Tracker| tr.final_rotation[0].abs() > std::f64::consts::FRAC_PI_3;
    let opts = RunOptions {
        stop_when: Some(&stop),
        no_trajectory: true,
        ..Default::default()
    };
    let s = run(scene, gm, &opts).expect("run").summary;
    let b = &s.blocks[0];
    Ran {
        fell: b.final_rotation.abs() > 30f64.to_radians(),
        peak: b.max_rotation,
        model: s.model.clone(),
        time: s.simulated_time,
    }
}

/// Housner's peak |θ| (rad) to `t_end` (or the fall) at RK4 step `dt`.
fn housner(col: &HousnerColumn, gm: &GroundMotion, t_end: f64) -> f64 {
    let mut peak = 0.0f64;
    housner_rocking(
        col,
        |t| gm.acceleration(t)[0],
        t_end,
        |s| {
            peak = peak.max(s.theta.abs());
            peak > FALLEN
        },
    );
    peak
}

fn within(x: f64, reference: f64) -> bool {
    (x / reference - 1.0).abs() <= 0.05
}

fn main() {
    let column = parse_scene(presets::EXAMPLE_COLUMN).expect("column");
    let slender = Column::SLENDER.json(json!({}));
    let slender = parse_scene(&slender.to_string()).expect("slender");
    let mut windowed = slender.clone();
    windowed.control.duration = Some(9.0);
    let scenes = [
        ("column 0.4 x 1.2 m", column),
        ("slender 0.24 x 1.6 m", slender),
        ("slender, 9 s", windowed),
    ];
    let mut names: Vec<String> = std::fs::read_dir(presets::records_dir())
        .expect("data/ground-motions")
        .filter_map(|e| e.ok()?.file_name().into_string().ok())
        .filter(|n| n.ends_with(".at2") || n.ends_with(".csv"))
        .collect();
    names.sort();
    let req = PgaRequest::cli_default(vec![Criterion::parse("toppled:column").expect("criterion")]);
    let mut jobs = Vec::new();
    for (label, scene) in &scenes {
        for name in &names {
            let gm = presets::record(name).expect("record");
            let r = search(scene, &gm, &req, &RunOptions::default()).expect("search");
            let Some(f) = r.failing_pga else { continue };
            for k in FACTORS {
                jobs.push((*label, scene, name.clone(), gm.clone(), k, f * k));
            }
        }
    }
    let rows: Vec<_> = jobs
        .par_iter()
        .map(|(label, scene, name, gm, k, pga)| {
            let scaled = gm.scaled_to_pga(*pga);
            let a = point(scene, &scaled);
            let block = reduced::qualify(scene, &ReducedParams::default()).expect("one block");
            let col = |dt: f64| HousnerColumn {
                b: 0.5 * block.pivots[1],
                h: block.centroid.y,
                g: scene.gravity,
                dt,
            };
            let t_end = a.time;
            let h = housner(&col(1e-5), &scaled, t_end);
            let h_fine = housner(&col(2e-6), &scaled, t_end);
            let near: Vec<f64> = [0.97, 0.99, 1.01, 1.03]
                .iter()
                .map(|f| housner(&col(1e-5), &gm.scaled_to_pga(pga * f), t_end))
                .collect();
            let mut fine = (*scene).clone();
            fine.control.model = ModelChoice::Dda;
            fine.control.time_step = 1e-4;
            let c = point(&fine, &scaled);
            (*label, name.clone(), *k, *pga, a, h, h_fine, near, c)
        })
        .collect();
    println!("| column | record | × F | m/s² | (a) `auto` | model | (h) Housner 1e-5 s / 2e-6 s | (c) engine 1e-4 s | Housner at 0.99 / 1.01 × | conditioned | (a) vs (h) | (c) vs (h) | (a) vs (c) |");
    println!("|---|---|---|---|---|---|---|---|---|---|---|---|---|");
    let show = |fell: bool, p: f64| {
        if fell {
            "falls".to_string()
        } else {
            format!("{p:.4}")
        }
    };
    let rel = |x: f64, r: f64| format!("{:+.1} %", 100.0 * (x / r - 1.0));
    // Counts over the points where the reference stands above 0.02 rad: (a) vs (c) [the
    // hand-over study's count], (a) vs (h), (c) vs (h); and over those that are also robust and
    // well conditioned.
    let (mut n_c, mut ac) = (0, 0);
    let (mut n_h, mut ah, mut ch) = (0, 0, 0);
    let (mut n_w, mut aw, mut cw, mut acw) = (0, 0, 0, 0);
    let (mut verdict_ah, mut verdict_ch, mut n_robust) = (0, 0, 0);
    for (label, name, k, pga, a, h, hf, near, c) in &rows {
        let h_fell = *h > FALLEN;
        let robust = (near[0] > FALLEN) == h_fell && (near[3] > FALLEN) == h_fell;
        if robust {
            n_robust += 1;
            verdict_ah += usize::from(a.fell == h_fell);
            verdict_ch += usize::from(c.fell == h_fell);
        }
        let conditioned = !h_fell
            && near[1] <= FALLEN
            && near[2] <= FALLEN
            && (near[1] / h - 1.0).abs() <= 0.03
            && (near[2] / h - 1.0).abs() <= 0.03;
        if !c.fell && c.peak > 0.02 {
            n_c += 1;
            ac += usize::from(!a.fell && within(a.peak, c.peak));
        }
        if !h_fell && *h > 0.02 {
            n_h += 1;
            ah += usize::from(!a.fell && within(a.peak, *h));
            ch += usize::from(!c.fell && within(c.peak, *h));
            if conditioned && robust {
                n_w += 1;
                aw += usize::from(!a.fell && within(a.peak, *h));
                cw += usize::from(!c.fell && within(c.peak, *h));
                acw += usize::from(!a.fell && !c.fell && within(a.peak, c.peak));
            }
        }
        if (c.fell || c.peak <= 0.02) && (h_fell || *h <= 0.02) {
            continue;
        }
        let vs = |x: &Ran, r: f64, r_fell: bool| {
            if x.fell || r_fell {
                "-".to_string()
            } else {
                rel(x.peak, r)
            }
        };
        println!(
            "| {label} | {name} | {k:.2} | {pga:.3} | {} | {} | {} / {} | {} | {} / {} | {} | {} | {} | {} |",
            show(a.fell, a.peak),
            a.model,
            show(h_fell, *h),
            show(*hf > FALLEN, *hf),
            show(c.fell, c.peak),
            show(near[1] > FALLEN, near[1]),
            show(near[2] > FALLEN, near[2]),
            if conditioned && robust { "yes" } else { "no" },
            vs(a, *h, h_fell),
            vs(c, *h, h_fell),
            vs(a, c.peak, c.fell),
        );
    }
    println!("\npoints {}; peaks within 5 %:", rows.len());
    println!("- (a) `auto` against (c) the engine at 1e-4 s, where (c) stands above 0.02 rad: {ac}/{n_c}");
    println!(
        "- against (h) Housner, where it stands above 0.02 rad: (a) {ah}/{n_h}, (c) {ch}/{n_h}"
    );
    println!("- the same where the point is also robust (verdict at ±3 %) and well conditioned (peak ±3 % at ±1 %): (a) {aw}/{n_w}, (c) {cw}/{n_w}; (a) against (c) {acw}/{n_w}");
    println!("verdict = Housner's where robust: (a) {verdict_ah}/{n_robust}, (c) {verdict_ch}/{n_robust}");
}
