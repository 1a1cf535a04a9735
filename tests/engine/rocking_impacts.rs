//! Rocking through impacts (docs/impacts-and-multiblock.md): the engine (`"model": "dda"`) is held to
//! Housner's rocking equation *across* impacts, not only up to the first one
//! (`tests/engine/rocking.rs` stops 0.01 s before it).
//!
//! - **Single impacts**: a rigid column released from rest at a tilt θ0 = α/2 rocks back onto
//!   its base; the ratio r of the angular velocities after/before the impact, read from the
//!   energies at the turning points on either side (free of the gravity torque acting while the
//!   penalty springs are closed), is compared with the law the engine is documented against
//!   (docs/pga.md, `examples/rocking_restitution.rs`): Housner's angular-momentum law for a
//!   rectangle, r = 1 − 1.5 sin²α, for h/b = 2, 3, 4, 6.
//! - **Histories through five impacts**: Yagoda-Biran & Hatzor's column (b = 0.2, h = 0.6 m) under Yagoda-Biran & Hatzor's
//!   half-sine pulse (5 m/s², 1 Hz, half a cycle), then free rocking through ≥ 5 impacts; the
//!   engine with the penalty and with the dual contact solver, at default numerical settings,
//!   against an RK4 integration of Housner's equation written here (fixed step 1e-5 s, impact
//!   instants located by bisection, r = 1 − 1.5 sin²α at each) and against the reduced model
//!   (`"model": "rocking"`), which shares no code with this integration.
//!
//! The column is `"block_model": "rigid"` (Housner's equation is a rigid-body model); every
//! numerical control is left at its default except where a test names its Δt.
//!
//! Found when this file was written (each ignored test says its numbers): at the default
//! Δt = 1 ms the engine misses Housner through five impacts (penalty 11.4 %, dual 9.5 % of the
//! peak rotation against 5 %) and at h/b = 2 its restitution is 4–5 % below Housner's; at
//! Δt = 2e-4 s both solvers pass the histories; the dual solver's restitution converges to
//! Housner's with Δt, the penalty solver's does not. With the scenes' default deformable block
//! the histories miss at every Δt tried (5.5–8.8 %).
use crate::common;
use ashlar::analysis::run::{run as run_scene, RunOptions};
use ashlar::motion::GroundMotion;
use common::*;
use serde_json::json;
use std::sync::Mutex;

// ---------------------------------------------------------------------------------------------
// Independent reference: Housner's equation of a rigid rectangle, RK4, restitution at impacts.
// ---------------------------------------------------------------------------------------------

/// A rigid rectangular column of half-width b and half-height h (m) on a rigid base.
#[derive(Clone, Copy)]
struct Column {
    b: f64,
    h: f64,
}

impl Column {
    fn alpha(&self) -> f64 {
        (self.b / self.h).atan()
    }
    fn radius(&self) -> f64 {
        self.b.hypot(self.h)
    }
    /// Housner's frequency parameter p² = 3g/(4R) of a rectangle, 1/s².
    fn p2(&self) -> f64 {
        3.0 * G / (4.0 * self.radius())
    }
    /// Housner's angular-momentum restitution of a rectangle.
    fn housner_r(&self) -> f64 {
        1.0 - 1.5 * self.alpha().sin().powi(2)
    }
}

/// θ̈ on the pivot of side `s` (+1: left corner, θ ≥ 0; −1: right corner, θ ≤ 0) under the
/// horizontal ground acceleration `ag` (m/s², +x). θ counter-clockwise positive: the ground
/// accelerating to +x throws the column back onto its left corner (θ > 0).
fn housner_acc(p2: f64, alpha: f64, s: f64, th: f64, ag: f64) -> f64 {
    -p2 * (s * (alpha - s * th).sin() - ag / G * (alpha - s * th).cos())
}

struct Housner {
    /// (t, θ) at every step.
    samples: Vec<(f64, f64)>,
    /// Instants of the impacts (changes of pivot), s.
    impacts: Vec<f64>,
    overturned: bool,
}

/// Housner's equation from rest, RK4 at a fixed step `dt`, restitution `r` at each impact
/// (impact instant located to 1e-14 s by bisection on the RK4 sub-step), rest when the column
/// lands slower than 1e-6 rad/s and the load does not lift it.
fn housner(c: Column, r: f64, ag: impl Fn(f64) -> f64, t_end: f64, dt: f64) -> Housner {
    let (p2, alpha) = (c.p2(), c.alpha());
    let rk4 = |t: f64, th: f64, w: f64, s: f64, h: f64| {
        let f = |t: f64, th: f64| housner_acc(p2, alpha, s, th, ag(t));
        let (k1t, k1w) = (w, f(t, th));
        let (k2t, k2w) = (w + 0.5 * h * k1w, f(t + 0.5 * h, th + 0.5 * h * k1t));
        let (k3t, k3w) = (w + 0.5 * h * k2w, f(t + 0.5 * h, th + 0.5 * h * k2t));
        let (k4t, k4w) = (w + h * k3w, f(t + h, th + h * k3t));
        (
            th + h / 6.0 * (k1t + 2.0 * k2t + 2.0 * k3t + k4t),
            w + h / 6.0 * (k1w + 2.0 * k2w + 2.0 * k3w + k4w),
        )
    };
    let (mut t, mut th, mut w) = (0.0f64, 0.0f64, 0.0f64);
    let mut out = Housner {
        samples: vec![(0.0, 0.0)],
        impacts: Vec::new(),
        overturned: false,
    };
    let mut s = 0.0f64; // 0: at rest on the base
    while t < t_end - 1e-12 {
        let h = dt.min(t_end - t);
        if s == 0.0 {
            // At rest: it starts to rock when the load's moment about a corner tips it.
            let a = ag(t + h);
            if a.abs() > G * alpha.tan() {
                s = a.signum();
            }
            t += h;
            out.samples.push((t, 0.0));
            continue;
        }
        let (th1, w1) = rk4(t, th, w, s, h);
        if s * th1 < 0.0 {
            // Crossed the base within the step: locate the impact, apply r, finish the step.
            let (mut lo, mut hi) = (0.0, h);
            while hi - lo > 1e-14 {
                let mid = 0.5 * (lo + hi);
                if s * rk4(t, th, w, s, mid).0 < 0.0 {
                    hi = mid;
                } else {
                    lo = mid;
                }
            }
            let (_, wi) = rk4(t, th, w, s, hi);
            out.impacts.push(t + hi);
            let w_after = r * wi;
            s = -s;
            let (tha, wa) =
                if w_after.abs() < 1e-6 && housner_acc(p2, alpha, s, 0.0, ag(t + hi)) * s <= 0.0 {
                    s = 0.0;
                    (0.0, 0.0)
                } else {
                    rk4(t + hi, 0.0, w_after, s, h - hi)
                };
            th = tha;
            w = wa;
        } else {
            th = th1;
            w = w1;
        }
        t += h;
        out.samples.push((t, th));
        if th.abs() > 1.0 {
            out.overturned = true;
            break;
        }
    }
    out
}

/// θ of the reference at time t, by linear interpolation between its samples (fixed step).
fn at(samples: &[(f64, f64)], dt: f64, t: f64) -> f64 {
    let k = ((t / dt).floor() as usize).min(samples.len() - 2);
    let (t0, a) = samples[k];
    let (t1, b) = samples[k + 1];
    a + (b - a) * ((t - t0) / (t1 - t0)).clamp(0.0, 1.0)
}

// ---------------------------------------------------------------------------------------------
// Scenes
// ---------------------------------------------------------------------------------------------

const SEED: Column = Column { b: 0.2, h: 0.6 };

/// The column standing on a fixed base, rotated clockwise by θ0 about its bottom-right corner
/// (θ0 = 0: upright), with the given controls.
fn column_scene(c: Column, theta0: f64, control: serde_json::Value) -> serde_json::Value {
    column_scene_of(c, theta0, control, "rigid")
}

/// As `column_scene`, with the column's block model ("rigid" or "deformable").
fn column_scene_of(
    c: Column,
    theta0: f64,
    control: serde_json::Value,
    block_model: &str,
) -> serde_json::Value {
    tilted_column(c.b, c.h, theta0, block_model, control)
}

/// The engine's controls: `"model": "dda"`, the contact solver, every other numerical control at
/// its default unless a time step is given.
fn controls(solver: &str, duration: f64, dt: Option<f64>) -> serde_json::Value {
    let mut c = json!({ "model": "dda", "duration": duration, "contact_solver": solver });
    if let Some(dt) = dt {
        c["time_step"] = json!(dt);
    }
    c
}

fn seed_pulse(a: f64) -> GroundMotion {
    rocking_pulse(a)
}

fn seed_pulse_fn(a: f64) -> impl Fn(f64) -> f64 {
    move |t: f64| {
        if (0.0..=0.5).contains(&t) {
            a * (2.0 * std::f64::consts::PI * t).sin()
        } else {
            0.0
        }
    }
}

// ---------------------------------------------------------------------------------------------
// (a) single impacts
// ---------------------------------------------------------------------------------------------

/// The engine's restitution at one impact of a column released from rest at θ0: r² is the ratio
/// of the potential-energy drops from the turning points on either side of the impact to the
/// upright position, (cos(α − θ1) − cos α)/(cos(α − θ0) − cos α) for a rigid column rocking
/// freely (θ1: the turning point after the impact).
fn engine_restitution(c: Column, theta0: f64, solver: &str, dt: Option<f64>) -> f64 {
    let v = column_scene(c, theta0, controls(solver, 3.0, dt));
    let scene = parse(&v);
    let mut s = sim(&scene, &GroundMotion::none());
    let alpha = c.alpha();
    // The accumulated rotation is θ0 (counter-clockwise) when upright again; past it the
    // column tilts onto its other corner up to θ1 = max rotation − θ0, where ω changes sign.
    let (mut hit, mut peak) = (false, f64::NEG_INFINITY);
    let done = run_until(&mut s, 3.0, |s| {
        let th = s.geoms()[1].rotation;
        let w = s.block_velocity(1)[2];
        if !hit {
            hit = th >= theta0;
            false
        } else {
            peak = peak.max(th);
            w < 0.0
        }
    });
    assert!(
        done,
        "h/b = {}: no turning point after the impact",
        c.h / c.b
    );
    let theta1 = peak - theta0;
    (((alpha - theta1).cos() - alpha.cos()) / ((alpha - theta0).cos() - alpha.cos())).sqrt()
}

/// Tolerance 1 % on r (no published number; chosen before measuring): over the five
/// impacts of the history tests an error δ per impact compounds to ≈ 5δ in the angular
/// velocity, which must stay within their 5 % tolerance. `regression`: a second bound at about
/// 5× the error measured when the test was written; where 5× the measured error exceeds the
/// tolerance, the tolerance is the only bound (said at each call).
fn check_restitution(solver: &str, dt: Option<f64>, slenderness: &[f64], regression: f64) {
    let mut worst: f64 = 0.0;
    for &hb in slenderness {
        let c = Column {
            b: 0.2,
            h: 0.2 * hb,
        };
        let r = engine_restitution(c, 0.5 * c.alpha(), solver, dt);
        let e = r / c.housner_r() - 1.0;
        eprintln!(
            "{solver} Δt = {dt:?}: h/b = {hb}: engine r = {r:.5}, Housner 1 − 1.5 sin²α = {:.5} ({:+.3} %)",
            c.housner_r(),
            100.0 * e
        );
        worst = worst.max(e.abs());
    }
    eprintln!(
        "{solver} Δt = {dt:?}: worst |Δr/r| = {:.3} %",
        100.0 * worst
    );
    assert!(
        worst < 0.01,
        "{solver}: restitution off Housner's by {worst}"
    );
    assert!(
        worst < regression,
        "{solver}: restitution error {worst} beyond the regression bound {regression} (find what changed)"
    );
}

// Measured at the default Δt = 1 ms (Δr/r): penalty −0.477 %, −0.710 %, −0.155 % and dual
// −0.447 %, −0.707 %, −0.132 % at h/b = 3, 4, 6. 5× the worst (3.5 %) is above the tolerance:
// the 1 % tolerance is the only bound.

#[test]
fn single_impact_restitution_penalty_default() {
    check_restitution("penalty", None, &[3.0, 4.0, 6.0], 0.01);
}

#[test]
fn single_impact_restitution_dual_default() {
    check_restitution("dual", None, &[3.0, 4.0, 6.0], 0.01);
}

/// The stocky column at the default Δt: measured −0.156 % (penalty), −0.124 % (dual) with
/// located impacts and the landing corner found before it lands (contact/vertex_edge.rs);
/// before: −4.00 % (the corner was found 85 µm deep, after landing). 5× the worst is 0.8 %.
#[test]
fn single_impact_restitution_stocky_default() {
    check_restitution("dual", None, &[2.0], 0.008);
    check_restitution("penalty", None, &[2.0], 0.008);
}

/// The dual solver's rigid impact approaches Housner's instantaneous one as Δt shrinks:
/// measured at Δt = 1e-4 s −0.168 %, −0.184 %, −0.022 %, −0.043 % at h/b = 2, 3, 4, 6;
/// regression bound 5× the worst, 0.92 %.
#[test]
fn single_impact_restitution_dual_converges_with_time_step() {
    check_restitution("dual", Some(1e-4), &[2.0, 3.0, 4.0, 6.0], 0.0092);
}

/// The penalty solver's impact does not approach Housner's law as Δt shrinks: at Δt = 1e-4 s
/// the stocky column keeps more energy than Housner's law allows (the penalty springs resolve
/// the impact over several steps and give part of it back).
#[test]
fn single_impact_restitution_penalty_small_time_step() {
    check_restitution("penalty", Some(1e-4), &[2.0, 3.0, 4.0, 6.0], 0.01);
}

// ---------------------------------------------------------------------------------------------
// (b) histories through ≥ 5 impacts
// ---------------------------------------------------------------------------------------------

const A_PULSE: f64 = 5.0;
const REF_DT: f64 = 1e-5;

/// The reference history through the pulse and the following free rocking, with the window
/// of the comparison: up to midway between the fifth and sixth impacts.
fn reference_history() -> (Housner, f64, f64) {
    let reference = housner(SEED, SEED.housner_r(), seed_pulse_fn(A_PULSE), 6.0, REF_DT);
    assert!(!reference.overturned);
    assert!(
        reference.impacts.len() >= 6,
        "the reference has {} impacts",
        reference.impacts.len()
    );
    let t_end = 0.5 * (reference.impacts[4] + reference.impacts[5]);
    let peak = reference
        .samples
        .iter()
        .fold(0.0f64, |m, p| m.max(p.1.abs()));
    (reference, t_end, peak)
}

/// Largest |θ − θ_ref| over the window, and the number of pivot changes of the run.
fn compare(history: &[(f64, f64)], reference: &Housner, t_end: f64) -> (f64, usize) {
    let mut worst: f64 = 0.0;
    let mut changes = 0;
    let mut last = 0.0f64;
    for &(t, th) in history.iter().filter(|p| p.0 <= t_end + 1e-9) {
        worst = worst.max((th - at(&reference.samples, REF_DT, t)).abs());
        // Sign changes of θ beyond 1e-4 rad count as impacts (ignores contact chatter).
        if th.abs() > 1e-4 {
            if last != 0.0 && th.signum() != last {
                changes += 1;
            }
            last = th.signum();
        }
    }
    {
        // Error and peak between successive reference impacts (how the error grows).
        let mut edges = vec![0.0];
        edges.extend(reference.impacts.iter().cloned().filter(|&t| t < t_end));
        edges.push(t_end);
        for w in edges.windows(2) {
            let e = history
                .iter()
                .filter(|p| p.0 >= w[0] && p.0 < w[1])
                .map(|&(t, th)| (th - at(&reference.samples, REF_DT, t)).abs())
                .fold(0.0f64, f64::max);
            let pk = history
                .iter()
                .filter(|p| p.0 >= w[0] && p.0 < w[1])
                .map(|p| p.1.abs())
                .fold(0.0f64, f64::max);
            let pr = reference
                .samples
                .iter()
                .filter(|p| p.0 >= w[0] && p.0 < w[1])
                .map(|p| p.1.abs())
                .fold(0.0f64, f64::max);
            eprintln!(
                "  [{:.3},{:.3}] max err {:.2e}  peak eng {:.5} ref {:.5}",
                w[0], w[1], e, pk, pr
            );
        }
    }
    (worst, changes)
}

fn engine_history_of(
    solver: &str,
    t_end: f64,
    dt: Option<f64>,
    block_model: &str,
) -> Vec<(f64, f64)> {
    let v = column_scene_of(SEED, 0.0, controls(solver, t_end, dt), block_model);
    let scene = parse(&v);
    let mut s = sim(&scene, &seed_pulse(A_PULSE));
    let mut out = vec![(0.0, 0.0)];
    run(&mut s, t_end, |s| {
        out.push((s.time(), s.geoms()[1].rotation))
    });
    out
}

fn reduced_history(t_end: f64) -> Vec<(f64, f64)> {
    let v = column_scene(
        SEED,
        0.0,
        json!({ "model": "rocking", "duration": t_end, "output_interval": 1e-3 }),
    );
    let scene = parse(&v);
    let frames = Mutex::new(Vec::new());
    let on_frame = |f: &ashlar::record::Frame| {
        frames
            .lock()
            .expect("frames")
            .push((f.time, f.blocks[1].rotation))
    };
    let opts = RunOptions {
        on_frame: Some(&on_frame),
        ..Default::default()
    };
    let outcome = run_scene(&scene, &seed_pulse(A_PULSE), &opts).expect("reduced run");
    assert_eq!(outcome.summary.model, "rocking");
    frames.into_inner().expect("frames")
}

/// Tolerance 5 % of the peak rotation (docs/verification.md's figure for rotations through impacts): the
/// engine's impact lasts a few steps of penalty contact (or one step of the dual's rigid one),
/// where Housner's is instantaneous, and its restitution differs slightly from Housner's; both
/// shift the later impacts, where the column turns at its fastest. `regression`: about 5× the
/// error measured when the test was written, or the tolerance where that is smaller.
fn check_history(solver: &str, dt: Option<f64>, regression: f64) {
    check_history_of(solver, dt, regression, "rigid");
}

fn check_history_of(solver: &str, dt: Option<f64>, regression: f64, block_model: &str) {
    let (reference, t_end, peak) = reference_history();
    let history = engine_history_of(solver, t_end, dt, block_model);
    let (worst, changes) = compare(&history, &reference, t_end);
    eprintln!(
        "{solver} {block_model} Δt = {dt:?}: peak θ = {peak:.4} rad, {} reference impacts to t = {t_end:.3} s (at {:?}), engine pivot changes {changes}, worst |Δθ| = {worst:.3e} rad ({:.3} % of peak)",
        reference.impacts.iter().filter(|&&t| t <= t_end).count(),
        reference.impacts.iter().take(6).map(|t| (t * 1e3).round() / 1e3).collect::<Vec<_>>(),
        100.0 * worst / peak
    );
    assert_eq!(changes, 5, "{solver}: the engine's impacts in the window");
    assert!(
        worst < 0.05 * peak,
        "{solver}: rotation error {worst} rad vs peak {peak} rad"
    );
    assert!(
        worst < regression * peak,
        "{solver}: rotation error {:.3} % of peak beyond the regression bound {:.3} % (find what changed)",
        100.0 * worst / peak,
        100.0 * regression
    );
}

// Measured worst |Δθ| / peak through five impacts (Δt = 1e-3, 5e-4, 2e-4, 1e-4 s):
// penalty 11.38 %, 5.86 %, 2.21 %, 12.70 %; dual 9.54 %, 2.68 %, 0.53 %, 3.98 %. Before the
// first impact the error is 0.9e-3 rad at 1 ms (0.8 % of peak); it grows at every impact
// (dual, 1 ms: 0.9e-3, 3.9e-3, 8.1e-3, 1.09e-2 rad after impacts 0…3), the engine's turning
// points falling below Housner's (0.0745 against 0.0757 rad after the first impact).

/// Measured 2.97 % with the impacts located in time (ImpactParams::window/margin); 9.43 %
/// with the impulse at the start of the step the impact fell in, 11.38 % with the contacts'
/// own impacts (docs/restitution.md). 5× exceeds the tolerance, which binds.
#[test]
fn history_through_five_impacts_penalty_default() {
    check_history("penalty", None, 0.05);
}

/// Measured 3.52 % with located impacts (7.59 % before them, 9.54 % with the contacts' own
/// impacts); the tolerance binds.
#[test]
fn history_through_five_impacts_dual_default() {
    check_history("dual", None, 0.05);
}

/// At Δt = 2e-4 s: measured 2.21 % (5× exceeds the tolerance: the tolerance binds).
#[test]
fn history_through_five_impacts_penalty_dt_2e4() {
    check_history("penalty", Some(2e-4), 0.05);
}

/// At Δt = 2e-4 s: measured 0.53 %, regression bound 2.7 %.
#[test]
fn history_through_five_impacts_dual_dt_2e4() {
    check_history("dual", Some(2e-4), 0.027);
}

/// Convergence in Δt is not monotonic: at 1e-4 s both solvers are worse than at 2e-4 s.
#[test]
fn history_through_five_impacts_small_time_step() {
    check_history("dual", Some(1e-4), 0.05);
    check_history("penalty", Some(1e-4), 0.05);
}

/// The scenes' default block model is deformable (6 unknowns a block): the column's elastic
/// strains take part in the impact. Housner's equation is a rigid-body model; the stone's strain
/// under self-weight is 1e-6, so the tolerance is the rigid column's.
/// Measured with located impacts: 2.75 % (penalty) and 2.04 % (dual) at the default Δt, 0.38 %
/// and 0.40 % at 2e-4 s (9.09 % at the default before them); the tolerance binds.
#[test]
fn history_through_five_impacts_deformable() {
    check_history_of("penalty", None, 0.05, "deformable");
    check_history_of("dual", None, 0.05, "deformable");
    check_history_of("penalty", Some(2e-4), 0.05, "deformable");
    check_history_of("dual", Some(2e-4), 0.05, "deformable");
}

/// The reduced model (`"model": "rocking"`, Dormand–Prince with event location, Housner's law)
/// against the RK4 reference written here: two integrations of one equation, so the
/// tolerance is 0.1 % of the peak (integration and output-sampling error only; the frames are
/// 1 ms apart and the reference is interpolated linearly between 1e-5 s samples).
#[test]
fn reduced_model_through_five_impacts() {
    let (reference, t_end, peak) = reference_history();
    let history = reduced_history(t_end);
    let (worst, changes) = compare(&history, &reference, t_end);
    eprintln!(
        "reduced: worst |Δθ| = {worst:.3e} rad ({:.4} % of peak), pivot changes {changes}",
        100.0 * worst / peak
    );
    assert_eq!(changes, 5);
    assert!(worst < 1e-3 * peak, "reduced model off by {worst} rad");
    // Regression bound: measured 1.09e-9 rad (1e-8 of the peak); 5× that.
    assert!(worst < 5e-8 * peak, "reduced model drifted: {worst} rad");
}

/// The reference itself: with r = 1 it conserves energy through impacts (free rocking from the
/// end of the pulse), so its integration and impact location are right.
#[test]
fn reference_conserves_energy_with_unit_restitution() {
    let c = SEED;
    let rr = housner(c, 1.0, seed_pulse_fn(A_PULSE), 4.0, REF_DT);
    assert!(rr.impacts.len() >= 3);
    // Energy per unit m R² ∝ (ω²·(2/3) + (g/R)·cos(α − |θ|)) ; the turning points after the pulse
    // all reach the same |θ| when no energy is lost.
    let mut peaks = Vec::new();
    let s = &rr.samples;
    for k in 1..s.len() - 1 {
        if s[k].0 > 0.5 && s[k].1.abs() > s[k - 1].1.abs() && s[k].1.abs() >= s[k + 1].1.abs() {
            peaks.push(s[k].1.abs());
        }
    }
    let (lo, hi) = peaks
        .iter()
        .fold((f64::INFINITY, 0.0f64), |(a, b), &p| (a.min(p), b.max(p)));
    eprintln!("turning points with r = 1: {peaks:?}");
    assert!(peaks.len() >= 3 && hi - lo < 1e-6 * hi, "{lo} … {hi}");
}
