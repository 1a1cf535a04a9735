//! Several blocks in motion against independent references (docs/impacts-and-multiblock.md). Each reference
//! is written here (RK4 or a rigid-plastic integration), shares no code with the engine, and
//! every engine run sets `"model": "dda"`:
//!
//! - **Rocking frame** (two equal free-standing columns carrying a free cap beam): Makris &
//!   Vassiliou (2013) show that it rocks as one column of the same slenderness α with Housner's
//!   frequency parameter scaled, p̂² = p² (1 + 2γ)/(1 + 3γ), γ = cap mass / total column mass
//!   (derived again in `frame_p2`). Overturning amplitude under Yagoda-Biran & Hatzor's half-sine pulse,
//!   within 2 % (docs/verification.md's tolerance); and its peak rotation under the shared
//!   records (data/ground-motions) against the equivalent column integrated by RK4 with the
//!   frame's impact law, within 5 % (peak rotations through impacts).
//! - **Pier of three stacked blocks** with friction high enough that it moves as one body: its
//!   overturning amplitude equals the monolithic column's (Housner), within 2 %; the test first
//!   checks along the reference motion that every bed joint stays closed and does not slip (the
//!   monolithic assumption holds), then that the engine's blocks do not rotate against each other.
//! - **Sliding stack**: two squat blocks on a base whose joint is weaker than the one between
//!   them, under a sine: rigid-plastic Newmark for the whole stack, no internal slip; final
//!   displacement within 2 % (the tolerance of `tests/engine/sliding_newmark.rs`).
//!
//! Every block is `"block_model": "rigid"` (the references are rigid-body models); numerical
//! controls are at their defaults.
//!
//! Found when this file was written: the engine's restitution of the rocking frame followed no
//! law (−1.0 … −4.6 % from Makris & Vassiliou's) and the dual solver did not converge at the
//! frame's impact at short steps; both pass since the e = 0 impact law (docs/restitution.md).
//! Found next: under Loma Prieta 0.6 g the columns parted (−28.64 %) and the dual solver did
//! not converge on Kobe 0.7 g, because the two columns land a fraction of a step apart and each
//! landing was an impact of its own; both pass since landings within one step are one impact
//! (`ImpactParams::group_landings`). The dual solver then still stalled under Loma Prieta
//! 0.6 g at a cap–column corner pair (a phantom penetration, docs/dual.md); it passes since
//! the dual solver does not assert it. `frame_records_scan` is an exploration and
//! `frame_loma_prieta_*` are diagnoses; they print.
use crate::common;
use ashlar::motion::{GroundMotion, Signal};
use common::*;
use serde_json::json;

// ---------------------------------------------------------------------------------------------
// Reference: Housner's equation of a rigid rectangle (or of the rocking frame), RK4.
// ---------------------------------------------------------------------------------------------

/// Step of the RK4 references, s.
const REF_DT: f64 = 1e-5;

/// θ̈ on the pivot of side `s` (+1: left corner, θ ≥ 0; −1: right corner) under the horizontal
/// ground acceleration `ag` (m/s², +x); θ counter-clockwise positive.
fn rocking_acc(p2: f64, alpha: f64, s: f64, th: f64, ag: f64) -> f64 {
    -p2 * (s * (alpha - s * th).sin() - ag / G * (alpha - s * th).cos())
}

/// One classical RK4 step of θ̈ = f(t, θ) from (θ, θ̇) at t over h: the new (θ, θ̇).
fn rk4_step(f: impl Fn(f64, f64) -> f64, t: f64, th: f64, w: f64, h: f64) -> (f64, f64) {
    let (k1t, k1w) = (w, f(t, th));
    let (k2t, k2w) = (w + 0.5 * h * k1w, f(t + 0.5 * h, th + 0.5 * h * k1t));
    let (k3t, k3w) = (w + 0.5 * h * k2w, f(t + 0.5 * h, th + 0.5 * h * k2t));
    let (k4t, k4w) = (w + h * k3w, f(t + h, th + h * k3t));
    (
        th + h / 6.0 * (k1t + 2.0 * k2t + 2.0 * k3t + k4t),
        w + h / 6.0 * (k1w + 2.0 * k2w + 2.0 * k3w + k4w),
    )
}

/// Yagoda-Biran & Hatzor's half-sine pulse a(t) = A sin(2πt), 0 ≤ t ≤ 0.5 s.
fn pulse_fn(a: f64) -> impl Fn(f64) -> f64 {
    move |t: f64| {
        if (0.0..=0.5).contains(&t) {
            a * (2.0 * std::f64::consts::PI * t).sin()
        } else {
            0.0
        }
    }
}

fn pulse(a: f64) -> GroundMotion {
    rocking_pulse(a)
}

/// What the reference does under a pulse of amplitude `a`.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Outcome {
    /// |θ| passed 1 rad before any impact.
    Overturns,
    /// Landed (first impact) at this time, s.
    Lands(f64),
    /// Never started rocking.
    Rest,
}

/// RK4 of θ̈ = rocking_acc from rest until the first impact or overturning (|θ| > 1 rad), at
/// most 4 s; `visit(t, θ, ω)` after every step while rocking.
fn rock_from_rest(
    p2: f64,
    alpha: f64,
    ag: impl Fn(f64) -> f64,
    mut visit: impl FnMut(f64, f64, f64),
) -> Outcome {
    let h = REF_DT;
    let mut t = 0.0f64;
    let mut s = 0.0f64;
    let (mut th, mut w) = (0.0f64, 0.0f64);
    while t < 4.0 {
        if s == 0.0 {
            let a = ag(t + h);
            t += h;
            if a.abs() > G * alpha.tan() {
                s = a.signum();
            } else if t > 0.5 {
                return Outcome::Rest;
            }
            continue;
        }
        (th, w) = rk4_step(|t, th| rocking_acc(p2, alpha, s, th, ag(t)), t, th, w, h);
        t += h;
        if s * th < 0.0 {
            return Outcome::Lands(t);
        }
        if th.abs() > 1.0 {
            return Outcome::Overturns;
        }
        visit(t, th, w);
    }
    Outcome::Lands(f64::INFINITY)
}

/// Lowest amplitude (m/s²) that overturns, by bisection to 1e-6 relative between `lo` (safe)
/// and `hi` (overturns). The pulse ends at 0.5 s: a column that lands after it rocks freely and,
/// losing energy at the impact (r < 1), cannot overturn afterwards, so "overturns before the
/// first impact" is the whole criterion when the landing comes after 0.5 s (asserted).
fn reference_threshold(p2: f64, alpha: f64, mut lo: f64, mut hi: f64) -> f64 {
    let overturns = |a: f64| match rock_from_rest(p2, alpha, pulse_fn(a), |_, _, _| {}) {
        Outcome::Overturns => true,
        Outcome::Lands(t) => {
            assert!(t > 0.5, "A = {a}: lands during the pulse, at {t} s");
            false
        }
        Outcome::Rest => false,
    };
    assert!(!overturns(lo) && overturns(hi), "reference bracket");
    while hi - lo > 1e-6 * hi {
        let mid = 0.5 * (lo + hi);
        if overturns(mid) {
            hi = mid;
        } else {
            lo = mid;
        }
    }
    0.5 * (lo + hi)
}

/// The engine's lowest overturning amplitude, by bisection between 0.98 and 1.02 × the
/// reference's (the bracket must hold: that is the 2 % check), down to a width of 0.02 %
/// (eight halvings), fine enough to measure errors of 0.1 % and set regression bounds on them.
/// Returns (safe, overturning) amplitudes.
fn engine_threshold(reference: f64, mut overturns: impl FnMut(f64) -> bool) -> (f64, f64) {
    let (mut lo, mut hi) = (0.98 * reference, 1.02 * reference);
    let (lo_fell, hi_fell) = (overturns(lo), overturns(hi));
    assert!(
        !lo_fell && hi_fell,
        "the engine's overturning amplitude is not within 2 % of the reference {reference:.4} m/s² (overturns at −2 %: {lo_fell}, at +2 %: {hi_fell})"
    );
    while hi - lo > 0.0002 * reference {
        let mid = 0.5 * (lo + hi);
        if overturns(mid) {
            hi = mid;
        } else {
            lo = mid;
        }
    }
    (lo, hi)
}

/// Runs the engine under the pulse until it is decided: overturned when a watched rotation
/// passes 0.6 rad (beyond every tipping angle here), safe when after the pulse the rotation of
/// the first watched block changes sign (the landing: free rocking cannot overturn it then).
/// `each_step` sees every step.
fn engine_overturns(
    scene: &ashlar::scene::Scene,
    a: f64,
    watched: &[usize],
    mut each_step: impl FnMut(&ashlar::simulation::Simulation),
) -> bool {
    let mut s = sim(scene, &pulse(a));
    let mut sign = 0.0f64;
    let mut fell = false;
    run_until(&mut s, 4.0, |s| {
        each_step(s);
        if watched.iter().any(|&b| s.geoms()[b].rotation.abs() > 0.6) {
            fell = true;
            return true;
        }
        let th = s.geoms()[watched[0]].rotation;
        if th.abs() > 1e-4 {
            if s.time() > 0.5 && sign != 0.0 && th.signum() != sign {
                return true;
            }
            sign = th.signum();
        }
        false
    });
    fell
}

// ---------------------------------------------------------------------------------------------
// Rocking frame
// ---------------------------------------------------------------------------------------------

/// Columns: half-width b, half-height h (Yagoda-Biran & Hatzor's column); cap beam: mass γ × both columns.
const B: f64 = 0.2;
const H: f64 = 0.6;

/// p̂² of the rocking frame, derived by Lagrange's equations (N columns of mass m, moment of
/// inertia (4/3) m R² about the pivot; the cap of mass M = γ N m translates with the columns'
/// top corners, at distance 2R from the pivots: speed 2Rθ̇, height 2R cos(α − θ)):
/// (4/3 N m + 4M) R² θ̈ = −(N m + 2M) g R [sin(α − θ) − (a_g/g) cos(α − θ)], so
/// p̂² = (3g/4R) (1 + 2γ)/(1 + 3γ), Makris & Vassiliou's result.
fn frame_p2(gamma: f64) -> f64 {
    let r = B.hypot(H);
    3.0 * G / (4.0 * r) * (1.0 + 2.0 * gamma) / (1.0 + 3.0 * gamma)
}

/// The frame of `ashlar::presets::RockingFrame::SEED` (columns b = B, h = H centred at
/// x = ±0.8 m, the cap spanning their outer faces, φ = 75°) with cap mass ratio γ.
fn frame_scene(gamma: f64, solver: &str) -> ashlar::scene::Scene {
    let frame = ashlar::presets::RockingFrame::SEED.gamma(gamma);
    assert_eq!((frame.half_width, frame.half_height), (B, H));
    parse(&frame.json(json!({ "model": "dda", "duration": 4.0, "contact_solver": solver })))
}

/// Tolerance 2 % on the overturning amplitude (docs/verification.md). The reference overturns without an
/// impact at its threshold, so the restitution of the frame plays no part.
fn check_frame(gamma: f64, solver: &str, regression: f64) {
    let alpha = (B / H).atan();
    let reference = reference_threshold(frame_p2(gamma), alpha, 3.0, 12.0);
    let column = reference_threshold(frame_p2(0.0), alpha, 3.0, 12.0);
    let scene = frame_scene(gamma, solver);
    let mut worst_sync: f64 = 0.0;
    let (lo, hi) = engine_threshold(reference, |a| {
        engine_overturns(&scene, a, &[1, 2], |s| {
            // The columns rock together and the cap stays level, as the model assumes.
            let (l, r, c) = (
                s.geoms()[1].rotation,
                s.geoms()[2].rotation,
                s.geoms()[3].rotation,
            );
            if l.abs().max(r.abs()) < 0.3 {
                worst_sync = worst_sync.max((l - r).abs()).max(c.abs());
            }
        })
    });
    let engine = 0.5 * (lo + hi);
    let err = engine / reference - 1.0;
    eprintln!(
        "rocking frame γ = {gamma}, {solver}: Makris–Vassiliou {reference:.4} m/s² (single column {column:.4}), engine [{lo:.4}, {hi:.4}] ({:+.3} % ± {:.3} %); largest column mismatch or cap rotation {worst_sync:.2e} rad",
        100.0 * err,
        100.0 * 0.5 * (hi - lo) / reference
    );
    // The frame must differ from the bare column by more than the tolerance, or the test
    // could not tell the two apart.
    assert!((reference / column - 1.0).abs() > 0.03);
    assert!(
        err.abs() < regression,
        "engine {engine} vs reference {reference}: {err} beyond the regression bound {regression}"
    );
}

// Measured (engine bracket midpoint against Makris–Vassiliou): +0.039 % ± 0.008 % for every
// case below, penalty and dual; regression bound 0.25 % (5× the upper end of the measurement).

/// γ = 1 (cap as heavy as both columns): p̂² = 0.75 p².
#[test]
fn rocking_frame_overturning_amplitude_heavy_cap_penalty() {
    check_frame(1.0, "penalty", 0.0025);
}

#[test]
fn rocking_frame_overturning_amplitude_heavy_cap_dual() {
    check_frame(1.0, "dual", 0.0025);
}

/// γ = 0.5: p̂² = 0.8 p².
#[test]
fn rocking_frame_overturning_amplitude_light_cap_penalty() {
    check_frame(0.5, "penalty", 0.0025);
}

/// The frame's rotation history under a pulse 10 % below its overturning amplitude, up to
/// 0.01 s before the first impact (the peak rotation is on the way): tolerance 2 % of the peak
/// rotation (as `tests/engine/rocking.rs` for the single column); regression bound 5× measured.
fn frame_history(solver: &str) {
    let (gamma, alpha) = (1.0, (B / H).atan());
    let p2 = frame_p2(gamma);
    let a = 0.9 * reference_threshold(p2, alpha, 3.0, 12.0);
    let mut reference = vec![(0.0, 0.0)];
    let landing = match rock_from_rest(p2, alpha, pulse_fn(a), |t, th, _| reference.push((t, th))) {
        Outcome::Lands(t) => t,
        o => panic!("reference: {o:?}"),
    };
    let peak = reference.iter().fold(0.0f64, |m, p| m.max(p.1.abs()));
    let scene = frame_scene(gamma, solver);
    let mut s = sim(&scene, &pulse(a));
    let mut worst: f64 = 0.0;
    let mut engine_peak: f64 = 0.0;
    run(&mut s, landing - 0.01, |s| {
        let th = s.geoms()[1].rotation;
        // Reference samples every REF_DT from its onset; before it the column is at rest.
        let k = reference
            .partition_point(|p| p.0 < s.time())
            .min(reference.len() - 1);
        worst = worst.max((th - reference[k].1).abs());
        engine_peak = engine_peak.max(th.abs());
    });
    eprintln!(
        "rocking frame history, {solver}, A = {a:.4} m/s²: peak θ reference {peak:.5}, engine {engine_peak:.5} rad; landing {landing:.3} s; worst |Δθ| = {worst:.2e} rad ({:.3} % of peak)",
        100.0 * worst / peak
    );
    assert!(worst < 0.02 * peak);
    assert!(worst < REGRESSION_FRAME_HISTORY * peak);
}

/// Measured 0.807 % of the peak (penalty), 0.736 % (dual); 5× that exceeds the tolerance: the
/// tolerance binds.
const REGRESSION_FRAME_HISTORY: f64 = 0.02;

#[test]
fn rocking_frame_history_to_first_impact_penalty() {
    frame_history("penalty");
}

#[test]
fn rocking_frame_history_to_first_impact_dual() {
    frame_history("dual");
}

/// The frame released from rest tilted by θ0 (columns rotated clockwise about their
/// bottom-right corners, the cap translated with their top-left corners, on which it rests):
/// the engine's ratio of angular velocities across the first impact, from the turning points on
/// either side (the frame is one degree of freedom with the column's potential shape, so
/// r² = (cos(α − θ1) − cos α)/(cos(α − θ0) − cos α) as for one column).
fn frame_restitution(gamma: f64, solver: &str, dt: Option<f64>) -> f64 {
    frame_restitution_from(gamma, solver, dt, 0.5)
}

/// `frame_restitution` released from θ0 = `fraction` × α.
fn frame_restitution_from(gamma: f64, solver: &str, dt: Option<f64>, fraction: f64) -> f64 {
    let alpha = (B / H).atan();
    let theta0 = fraction * alpha;
    let (co, si) = (theta0.cos(), theta0.sin());
    let column = |xc: f64| {
        let pivot = xc + B;
        let rot = |x: f64, y: f64| {
            let (dx, dy) = (x - pivot, y);
            [pivot + co * dx + si * dy, -si * dx + co * dy]
        };
        json!([
            rot(xc - B, 0.0),
            rot(xc + B, 0.0),
            rot(xc + B, 2.0 * H),
            rot(xc - B, 2.0 * H)
        ])
    };
    // The top-left corner of the column at x = 0.8 after the rotation carries the cap.
    let top_left = |xc: f64| {
        let pivot = xc + B;
        let (dx, dy) = (-2.0 * B, 2.0 * H);
        (pivot + co * dx + si * dy, -si * dx + co * dy)
    };
    let (x_shift, y_cap) = {
        let (x, y) = top_left(0.8);
        (x - (0.8 - B), y)
    };
    let column_area = 2.0 * (2.0 * B) * (2.0 * H);
    let (x0, x1) = (-0.8 - B + x_shift, 0.8 + B + x_shift);
    let t = gamma * column_area / (x1 - x0);
    let mut control = json!({ "model": "dda", "duration": 3.0, "contact_solver": solver });
    if let Some(dt) = dt {
        control["time_step"] = json!(dt);
    }
    let blocks = json!([
        { "id": "base", "material": "stone", "fixed": true, "vertices": rect(-3.0, -0.5, 3.0, 0.0) },
        { "id": "left", "material": "stone", "block_model": "rigid", "vertices": column(-0.8) },
        { "id": "right", "material": "stone", "block_model": "rigid", "vertices": column(0.8) },
        { "id": "cap", "material": "stone", "block_model": "rigid", "vertices": rect(x0, y_cap, x1, y_cap + t) },
    ]);
    let scene = parse(&scene_json(blocks, 75.0, control));
    let mut s = sim(&scene, &GroundMotion::none());
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
    assert!(done, "no turning point after the impact");
    let theta1 = peak - theta0;
    (((alpha - theta1).cos() - alpha.cos()) / ((alpha - theta0).cos() - alpha.cos())).sqrt()
}

/// The engine's restitution of the rocking frame against Makris & Vassiliou's law,
/// r = (1 − 1.5 sin²α + 3γ cos 2α)/(1 + 3γ), at the default Δt; tolerance 1 % as for the single
/// column (`tests/engine/rocking_impacts.rs`). Their law rests on an assumption about the cap's
/// momentum at the impact (it is not derived from a full impact model), so a miss is not by
/// itself an engine bug; but the engine's value depends on the solver and on Δt (below), so it
/// follows no law at all.
#[test]
fn rocking_frame_restitution_makris_vassiliou() {
    let alpha = (B / H).atan();
    let mut worst: f64 = 0.0;
    for gamma in [0.5, 1.0] {
        let mv = (1.0 - 1.5 * alpha.sin().powi(2) + 3.0 * gamma * (2.0 * alpha).cos())
            / (1.0 + 3.0 * gamma);
        for solver in ["penalty", "dual"] {
            let r = frame_restitution(gamma, solver, None);
            let e = r / mv - 1.0;
            eprintln!(
                "frame γ = {gamma}, {solver}: engine r = {r:.5}, Makris–Vassiliou {mv:.5} ({:+.3} %), single column {:.5}",
                100.0 * e,
                1.0 - 1.5 * alpha.sin().powi(2)
            );
            worst = worst.max(e.abs());
        }
    }
    assert!(worst < 0.01, "{worst}");
}

/// Diagnosis of the Loma Prieta miss (prints; ignored): the frame's restitution from small
/// releases, as in the record's small rocking before the engine leaves the reference.
#[test]
#[ignore = "diagnosis: prints the frame's restitution from small releases against Makris–Vassiliou's"]
fn frame_restitution_small_releases() {
    let alpha = (B / H).atan();
    let mv = frame_restitution_law(1.0, alpha);
    for fraction in [0.5, 0.2, 0.1, 0.05, 0.025] {
        for dt in [None, Some(2e-4)] {
            let r = frame_restitution_from(1.0, "penalty", dt, fraction);
            eprintln!(
                "frame γ = 1, penalty, Δt {dt:?}, θ0 = {fraction} α: r = {r:.5} against {mv:.5} ({:+.3} %)",
                100.0 * (r / mv - 1.0)
            );
        }
    }
}

/// The dual solver at the frame's impact with a shorter step: it must complete.
#[test]
fn rocking_frame_impact_dual_short_step() {
    frame_restitution(1.0, "dual", Some(5e-4));
    frame_restitution(0.5, "dual", Some(1e-4));
}

// ---------------------------------------------------------------------------------------------
// Pier of stacked blocks moving as one body
// ---------------------------------------------------------------------------------------------

/// Three blocks 0.4 × 0.4 m stacked into Yagoda-Biran & Hatzor's column (b = 0.2, h = 0.6 m).
const COURSES: usize = 3;

/// Along the monolithic column's motion on its pivot (θ, ω, θ̈ at t), is every bed joint closed
/// (the resultant of the part above inside the joint, compressive) and stuck (friction demand
/// below μ)? Returns the smallest margin: min over joints of the resultant's distance to the
/// joint's ends over the joint width, and the largest friction demand |F_t|/F_n.
fn joint_margins(s: f64, th: f64, w: f64, acc: f64, ag: f64) -> (f64, f64) {
    // Body frame: pivot at the origin, the column along x ∈ [0, 2b] (pivot side first), y up;
    // the rotation is s·θ ≥ 0 towards the pivot's side, mirrored for the right pivot so one
    // formula serves both.
    let (phi, phid, phidd) = (s * th, s * w, s * acc);
    // Load per unit mass (gravity and −a_g) in the body frame, mirrored for s = −1.
    let (lx, ly) = (-s * ag, -G);
    let (c, sn) = (phi.cos(), phi.sin());
    // Body components of a world vector rotated by −φ about z (mirror: the body rotates
    // counter-clockwise towards −x as φ grows on the left pivot).
    let l = (c * lx + sn * ly, -sn * lx + c * ly);
    let course = 2.0 * H / COURSES as f64;
    let (mut margin, mut demand) = (f64::INFINITY, 0.0f64);
    for k in 1..COURSES {
        let yk = k as f64 * course;
        // Part above the joint: mass per unit density, centroid, inertia about it.
        let height = 2.0 * H - yk;
        let m = 2.0 * B * height;
        let cx = B;
        let cy = yk + 0.5 * height;
        let ic = m * ((2.0 * B).powi(2) + height.powi(2)) / 12.0;
        // Acceleration of the centroid in the body frame: φ̈ ẑ×c − φ̇² c.
        let (ax, ay) = (
            -phidd * cy - phid * phid * cx,
            phidd * cx - phid * phid * cy,
        );
        let (ft, fn_) = (m * (ax - l.0), m * (ay - l.1));
        // Moments about the joint's pivot-side end Q0 = (0, yk).
        let (qx, qy) = (0.0, yk);
        let inertia = phidd * (ic + m * (cx * cx + cy * cy) - m * (qx * cx + qy * cy))
            + phid * phid * m * (qx * cy - qy * cx);
        let load = m * ((cx - qx) * l.1 - (cy - qy) * l.0);
        let x_star = (inertia - load) / fn_;
        if fn_ <= 0.0 {
            return (f64::NEG_INFINITY, f64::INFINITY);
        }
        margin = margin.min(x_star.min(2.0 * B - x_star) / (2.0 * B));
        demand = demand.max(ft.abs() / fn_);
    }
    (margin, demand)
}

fn pier_scene(solver: &str) -> ashlar::scene::Scene {
    // `ashlar::presets::Pier::SEED`: φ = 75° (μ = 3.7), far above the friction demand found
    // along the reference (asserted).
    let pier = ashlar::presets::Pier::SEED;
    assert_eq!(
        (pier.half_width, pier.half_height, pier.courses),
        (B, H, COURSES)
    );
    parse(&pier.json(json!({ "model": "dda", "duration": 4.0, "contact_solver": solver })))
}

/// Tolerance 2 % on the overturning amplitude (docs/verification.md, as for the monolithic column in
/// `tests/engine/rocking.rs`).
fn check_pier(solver: &str, regression: f64) {
    let alpha = (B / H).atan();
    let p2 = 3.0 * G / (4.0 * B.hypot(H));
    let reference = reference_threshold(p2, alpha, 3.0, 12.0);
    // The monolithic assumption along the reference motions on both sides of the threshold,
    // until the column has tipped past α (from there it falls whatever the joints do).
    let (mut margin, mut demand) = (f64::INFINITY, 0.0f64);
    for a in [0.98 * reference, 1.02 * reference] {
        let ag = pulse_fn(a);
        rock_from_rest(p2, alpha, &ag, |t, th, w| {
            if th.abs() < alpha {
                let s = th.signum();
                let acc = rocking_acc(p2, alpha, s, th, ag(t));
                let (m, d) = joint_margins(s, th, w, acc, ag(t));
                margin = margin.min(m);
                demand = demand.max(d);
            }
        });
    }
    eprintln!("pier: along the monolithic motion, smallest joint margin {margin:.3} of the width, largest friction demand {demand:.3}");
    assert!(
        margin > 0.0 && demand < 75f64.to_radians().tan(),
        "the pier would not move as one body: the reference does not apply"
    );
    let scene = pier_scene(solver);
    let mut opening: f64 = 0.0;
    let (lo, hi) = engine_threshold(reference, |a| {
        engine_overturns(&scene, a, &[1], |s| {
            if s.geoms()[1].rotation.abs() < alpha {
                for k in 2..=COURSES {
                    opening = opening.max((s.geoms()[k].rotation - s.geoms()[1].rotation).abs());
                }
            }
        })
    });
    let engine = 0.5 * (lo + hi);
    let err = engine / reference - 1.0;
    eprintln!(
        "pier of {COURSES} blocks, {solver}: Housner {reference:.4} m/s², engine [{lo:.4}, {hi:.4}] ({:+.3} % ± {:.3} %); largest rotation between courses {opening:.2e} rad",
        100.0 * err,
        100.0 * 0.5 * (hi - lo) / reference
    );
    assert!(
        err.abs() < regression,
        "engine {engine} vs reference {reference}: {err} beyond the regression bound {regression}"
    );
}

// Measured: +0.039 % ± 0.008 % with both solvers (largest rotation between courses 6e-6 rad
// penalty, 2e-9 rad dual); regression bound 0.25 %.

#[test]
fn pier_moves_as_one_body_penalty() {
    check_pier("penalty", 0.0025);
}

#[test]
fn pier_moves_as_one_body_dual() {
    check_pier("dual", 0.0025);
}

/// The joint check itself, on closed forms: at rest every resultant is at mid-joint (margin
/// 0.5); at the onset of rocking (a_g = g tan α, no motion yet) the resultant of the part of
/// height H_a above a joint sits (H_a/2) tan α from mid-joint towards the pivot, margin
/// 0.5 − H_a/(4h): 1/6 at the lower joint (H_a = 0.8 m), the smaller; friction demand tan α.
#[test]
fn joint_margins_closed_forms() {
    let (m, d) = joint_margins(1.0, 0.0, 0.0, 0.0, 0.0);
    assert!((m - 0.5).abs() < 1e-12 && d < 1e-12, "{m} {d}");
    let ag = G * B / H;
    for s in [1.0, -1.0] {
        let (m, d) = joint_margins(s, 0.0, 0.0, 0.0, s * ag);
        assert!((m - 1.0 / 6.0).abs() < 1e-12, "{m}");
        assert!((d - B / H).abs() < 1e-12, "{d}");
    }
    // Past the onset with the whole column's angular acceleration the joints still carry it,
    // but a load twice the onset's with no rotation would open the lower joint (the check can
    // fail).
    let (m, _) = joint_margins(1.0, 0.0, 0.0, 0.0, 2.5 * ag);
    assert!(m < 0.0, "{m}");
}

// ---------------------------------------------------------------------------------------------
// Sliding stack
// ---------------------------------------------------------------------------------------------

/// Rigid-plastic Newmark sliding of one rigid body on a level base (friction μ) under the
/// horizontal ground acceleration a_g(t), from the relative velocity v0 (m/s): ü = −a_g − μ g
/// sign(u̇) while sliding, stuck while |a_g| ≤ μ g. Steps of 1e-5 s integrate the relative
/// acceleration by Simpson's rule (exact for a quadratic a_g within a step); the onset and the
/// stop of each slip are located by bisection. Returns the displacement relative to the ground
/// at `t_end` (m, +x).
fn newmark_level(mu: f64, ag: impl Fn(f64) -> f64, t_end: f64, v0: f64) -> f64 {
    let h = 1e-5f64;
    let (mut t, mut u, mut v) = (0.0f64, 0.0f64, v0);
    // Sliding direction, 0 when stuck.
    let mut dir = if v0 == 0.0 { 0.0 } else { v0.signum() };
    while t < t_end - 1e-12 {
        let step = h.min(t_end - t);
        if dir == 0.0 {
            if ag(t + step).abs() <= mu * G {
                t += step;
                continue;
            }
            let (mut lo, mut hi) = (t, t + step);
            if ag(lo).abs() > mu * G {
                hi = lo;
            }
            for _ in 0..60 {
                let mid = 0.5 * (lo + hi);
                if ag(mid).abs() > mu * G {
                    hi = mid;
                } else {
                    lo = mid;
                }
            }
            t = hi;
            dir = -ag(hi).signum();
            continue;
        }
        let rel = |s: f64| -ag(s) - mu * G * dir;
        let advance = |s: f64| {
            let (a0, am, a1) = (rel(t), rel(t + 0.5 * s), rel(t + s));
            (
                u + v * s + s * s / 6.0 * (a0 + 2.0 * am),
                v + s / 6.0 * (a0 + 4.0 * am + a1),
            )
        };
        let (u1, v1) = advance(step);
        if v1 * dir > 0.0 {
            (u, v, t) = (u1, v1, t + step);
            continue;
        }
        let (mut lo, mut hi) = (0.0, step);
        for _ in 0..60 {
            let mid = 0.5 * (lo + hi);
            if advance(mid).1 * dir > 0.0 {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        u = advance(hi).0;
        (v, dir, t) = (0.0, 0.0, t + hi);
    }
    u
}

/// The Newmark reference on closed forms: under a constant a_g = a0 > μg the body slips at
/// d = −(a0 − μg): u = d t²/2; thrown at v0 with no ground motion it stops after |v0|/μg at
/// u = v0|v0|/(2μg) and stays. Tolerance 1e-9 relative: far below the regression bounds the
/// reference is used with.
#[test]
fn newmark_level_closed_forms() {
    let (mu, a0, t) = (0.364, 6.0, 0.3);
    let exact = -0.5 * (a0 - mu * G) * t * t;
    let u = newmark_level(mu, |_| a0, t, 0.0);
    let e1 = (u / exact - 1.0).abs();
    let v0 = -1.0f64;
    let exact2 = v0 * v0.abs() / (2.0 * mu * G);
    let u2 = newmark_level(mu, |_| 0.0, 1.0, v0);
    let e2 = (u2 / exact2 - 1.0).abs();
    eprintln!(
        "Newmark reference: {u:.9} vs {exact:.9} m ({e1:.1e}); {u2:.9} vs {exact2:.9} m ({e2:.1e})"
    );
    assert!(e1 < 1e-9 && e2 < 1e-9, "{e1} {e2}");
}

/// Two blocks 1.0 × 0.3 m stacked on a fixed base; the base joint φ = 20° (μ = 0.364), the joint
/// between them φ = 45°: while the stack slides its acceleration is μ g, which the upper joint
/// carries with margin (μ_int = 1 > 0.364), so the stack slides as one body; tan α = 0.5/0.3 ≫ μ:
/// it does not rock.
fn stack_scene(solver: &str, duration: f64) -> ashlar::scene::Scene {
    let v = json!({
        "format": "ashlar.scene/1",
        "gravity": G,
        "materials": { "stone": { "density": 2500.0, "young_modulus": 2.0e10, "poisson_ratio": 0.2 } },
        "joints": { "bed": { "friction_angle": 20.0 }, "inner": { "friction_angle": 45.0 } },
        "interfaces": { "default": "inner", "pairs": [ { "blocks": ["base", "lower"], "joint": "bed" } ] },
        "blocks": [
            { "id": "base", "material": "stone", "fixed": true, "vertices": rect(-10.0, -0.5, 10.0, 0.0) },
            { "id": "lower", "material": "stone", "block_model": "rigid", "vertices": rect(-0.5, 0.0, 0.5, 0.3) },
            { "id": "upper", "material": "stone", "block_model": "rigid", "vertices": rect(-0.5, 0.3, 0.5, 0.6) },
        ],
        "control": { "model": "dda", "duration": duration, "contact_solver": solver },
    });
    parse(&v)
}

/// Tolerance 2 % on the final displacement (as `tests/engine/sliding_newmark.rs`); internal slip
/// below 1 % of it (the stack must slide as one body).
fn check_stack(solver: &str, regression: f64) {
    // Two and a half cycles of a 1 Hz sine of 5 m/s² (μg = 3.57 m/s²): five slip phases,
    // alternating, the odd half cycle leaving a net displacement.
    let (a, t_end) = (5.0, 4.0);
    let mu = 20f64.to_radians().tan();
    let ag = |t: f64| {
        if (0.0..=2.5).contains(&t) {
            a * (2.0 * std::f64::consts::PI * t).sin()
        } else {
            0.0
        }
    };
    let reference = newmark_level(mu, ag, t_end, 0.0);
    let scene = stack_scene(solver, t_end);
    let motion = GroundMotion::horizontal(Signal::Pulse {
        amplitude: a,
        period: 1.0,
        cycles: 2.5,
        phase: 0.0,
    });
    let mut s = sim(&scene, &motion);
    let mut internal: f64 = 0.0;
    run(&mut s, t_end, |s| {
        let (l, u) = (displacement(s, 1), displacement(s, 2));
        internal = internal.max((u[0] - l[0]).abs());
    });
    let (l, u) = (displacement(&s, 1), displacement(&s, 2));
    let err = (l[0] - reference) / reference;
    eprintln!(
        "sliding stack, {solver}: Newmark {reference:.7} m, engine lower {:.7} m, upper {:.7} m ({:+.2e}); largest slip between the blocks {internal:.2e} m; rotations {:.1e}, {:.1e} rad",
        l[0],
        u[0],
        err,
        s.geoms()[1].rotation,
        s.geoms()[2].rotation
    );
    assert!(reference.abs() > 0.01, "the case must slide");
    assert!(err.abs() < 0.02, "{solver}: {err}");
    assert!(
        internal < 0.01 * reference.abs(),
        "internal slip {internal}"
    );
    assert!(
        err.abs() < regression,
        "{solver}: {err} beyond the regression bound {regression}"
    );
}

// Measured: penalty +6.7e-7, dual −6.3e-5 (slip between the blocks 2.2e-8 m, 5.4e-8 m);
// regression bounds 5× those.

#[test]
fn sliding_stack_penalty() {
    check_stack("penalty", 3.4e-6);
}

#[test]
fn sliding_stack_dual() {
    check_stack("dual", 3.2e-4);
}

// ---------------------------------------------------------------------------------------------
// Rocking frame under recorded ground motions
// ---------------------------------------------------------------------------------------------

/// Makris & Vassiliou's (2013) ratio of angular velocities across an impact of the rocking
/// frame, r = (1 − 1.5 sin²α + 3γ cos 2α)/(1 + 3γ) (γ = 0: Housner's column).
fn frame_restitution_law(gamma: f64, alpha: f64) -> f64 {
    (1.0 - 1.5 * alpha.sin().powi(2) + 3.0 * gamma * (2.0 * alpha).cos()) / (1.0 + 3.0 * gamma)
}

/// Rotation (rad) past which the frame counts as fallen, in the reference and in the engine
/// (as `analysis::study_records::FALLEN` for the single column).
const FRAME_FALLEN: f64 = 1.0;

/// The equivalent single column of the frame (slenderness α, p̂² = `frame_p2`) under the
/// ground acceleration `ag` (m/s², +x), RK4 at `REF_DT` from rest to `t_end`: at rest until
/// |a_g| > g tan α (the frame's uplift condition is the column's: p̂² multiplies both terms),
/// tipping with the sign of a_g; when θ crosses zero the step ends at θ = 0 with θ̇ scaled by
/// the frame's impact law (`frame_restitution_law`), and the frame rests again below 1e-6 rad/s.
/// Impacts are located only to the step (1e-5 s), so an impact's timing error is below 1e-5 s.
/// Returns (peak |θ|, fallen).
fn frame_record_reference(
    gamma: f64,
    ag: impl Fn(f64) -> f64,
    t_end: f64,
    visit: impl FnMut(f64, f64),
) -> (f64, bool) {
    let r = frame_restitution_law(gamma, (B / H).atan());
    column_record_reference(frame_p2(gamma), r, ag, t_end, visit)
}

/// The RK4 of `frame_record_reference` for any p² (s⁻²) and ratio of angular velocities `r`
/// across an impact.
fn column_record_reference(
    p2: f64,
    r: f64,
    ag: impl Fn(f64) -> f64,
    t_end: f64,
    mut visit: impl FnMut(f64, f64),
) -> (f64, bool) {
    let alpha = (B / H).atan();
    let h = REF_DT;
    let (mut th, mut w, mut s) = (0.0f64, 0.0f64, 0.0f64);
    let mut peak = 0.0f64;
    let n = (t_end / h).round() as usize;
    for i in 0..n {
        let t = i as f64 * h;
        if s == 0.0 {
            let a = ag(t);
            if a.abs() > G * alpha.tan() {
                s = a.signum();
            } else {
                continue;
            }
        }
        let (nth, nw) = rk4_step(|t, th| rocking_acc(p2, alpha, s, th, ag(t)), t, th, w, h);
        if nth * s < 0.0 {
            th = 0.0;
            w = nw * r;
            s = w.signum();
            if w.abs() < 1e-6 {
                (w, s) = (0.0, 0.0);
            }
        } else {
            (th, w) = (nth, nw);
        }
        peak = peak.max(th.abs());
        visit(t + h, th);
        if peak > FRAME_FALLEN {
            return (peak, true);
        }
    }
    (peak, false)
}

/// A shared record (data/ground-motions) scaled to `pga` g.
fn frame_record(name: &str, pga: f64) -> GroundMotion {
    ashlar::analysis::study_records::load_record(&ashlar::presets::records_dir(), name, pga)
        .expect("record")
}

/// The engine's frame (`frame_scene`: `"model": "dda"`, rigid blocks, default controls) under
/// the record to `t_end` or until a column passes `FRAME_FALLEN`; returns (peak |θ| of the left
/// column, fallen, largest column mismatch or cap rotation while |θ| < 0.3 rad).
fn frame_record_engine(
    gamma: f64,
    solver: &str,
    motion: &GroundMotion,
    t_end: f64,
) -> (f64, bool, f64) {
    let scene = frame_scene(gamma, solver);
    let mut s = sim(&scene, motion);
    let (mut peak, mut sync) = (0.0f64, 0.0f64);
    let fell = run_until(&mut s, t_end, |s| {
        let (l, r, c) = (
            s.geoms()[1].rotation,
            s.geoms()[2].rotation,
            s.geoms()[3].rotation,
        );
        peak = peak.max(l.abs());
        if l.abs().max(r.abs()) < 0.3 {
            sync = sync.max((l - r).abs()).max(c.abs());
        }
        l.abs().max(r.abs()) > FRAME_FALLEN
    });
    (peak, fell, sync)
}

/// Scan (ignored; prints): the reference's peak rotation of the γ = 1 frame on every shared
/// record at 0.1–1.0 g, and its change at ±1 % of the PGA, to choose the test's points.
#[test]
#[ignore = "exploration: prints the reference's peaks to choose the points of frame_peak_rotation_under_records"]
fn frame_records_scan() {
    for rec in ashlar::analysis::study_records::RECORDS {
        for k in 1..=10 {
            let pga = 0.1 * k as f64;
            let at = |f: f64| {
                let m = frame_record(rec, pga * f);
                let t_end = m.duration().unwrap_or(10.0) + 2.0;
                frame_record_reference(1.0, |t| m.acceleration(t)[0], t_end, |_, _| {})
            };
            let (mid, lo, hi) = (at(1.0), at(0.99), at(1.01));
            eprintln!(
                "{rec} {pga:.1} g: peak {:.4} fallen {} | -1 %: {:.4} {} | +1 %: {:.4} {}",
                mid.0, mid.1, lo.0, lo.1, hi.0, hi.1
            );
        }
    }
}

/// The frame's peak rotation under a record at `pga` g against the equivalent column with the
/// frame's impact law; returns the relative error of the peak. Tolerance 5 % (peak
/// rotations through impacts; the single column's `tests/engine/records_housner.rs` uses the
/// same figure). The points are chosen where the reference is well conditioned (asserted): the
/// frame survives with a peak above 0.02 rad, and its peak moves by at most 3 % for ±1 % of
/// the PGA and for ±1 % of the impact law's r (the tolerance of the frame's restitution test
/// above), so a 5 % miss is the engine's and not the record's sensitivity. Friuli 0.9 g fails
/// that (r × 0.99 moves the peak −17.8 %) and is left out although the engine meets it (−0.75 %).
fn frame_record_point(gamma: f64, solver: &str, record: &str, pga: f64, regression: f64) -> f64 {
    let law = frame_restitution_law(gamma, (B / H).atan());
    let reference_at = |f_pga: f64, f_r: f64| {
        let m = frame_record(record, pga * f_pga);
        let t_end = m.duration().unwrap_or(10.0) + 2.0;
        column_record_reference(
            frame_p2(gamma),
            law * f_r,
            |t| m.acceleration(t)[0],
            t_end,
            |_, _| {},
        )
    };
    let (reference, fallen) = reference_at(1.0, 1.0);
    assert!(
        !fallen && reference > 0.02,
        "{record} {pga} g: the frame must survive beyond 0.02 rad ({reference})"
    );
    for (f_pga, f_r) in [(0.99, 1.0), (1.01, 1.0), (1.0, 0.99), (1.0, 1.01)] {
        let (p, fl) = reference_at(f_pga, f_r);
        assert!(
            !fl && (p / reference - 1.0).abs() <= 0.03,
            "{record} {pga} g: the reference is ill-conditioned here ({p} rad at {f_pga} × PGA, {f_r} × r)"
        );
    }
    let m = frame_record(record, pga);
    let t_end = m.duration().unwrap_or(10.0) + 2.0;
    let (peak, fell, sync) = frame_record_engine(gamma, solver, &m, t_end);
    let err = peak / reference - 1.0;
    eprintln!(
        "rocking frame γ = {gamma}, {solver}, {record} {pga} g: reference peak {reference:.5} rad, engine {peak:.5} rad ({:+.2} %), fallen {fell}; column mismatch or cap rotation {sync:.1e} rad",
        100.0 * err
    );
    assert!(
        !fell,
        "the engine's frame fell where the reference survives"
    );
    assert!(err.abs() <= 0.05, "peak off the reference by {err}");
    assert!(
        err.abs() <= regression,
        "peak error {err} beyond the regression bound {regression} (find what changed)"
    );
    err
}

const FRIULI: &str = "friuli-1976-tolmezzo-000.at2";
const KOBE: &str = "kobe-1995-nishi-akashi-000.csv";
const LOMA_PRIETA: &str = "loma-prieta-1989-capitola-000.at2";

// Regression bounds of the frame's peak under records: 5× the error measured 2026-11-26 (10×
// where it is below 0.05 %), dev test profile, default Δt = 1 ms, rigid blocks, e = 0 default
// impacts, landings within a step grouped into one impact (`ImpactParams::group_landings`,
// which moved every point: re-set then). Re-measure after a change of the impact law or the
// time-step control (`cargo test --test engine -- frame_peak_rotation --nocapture`).

/// Penalty, Friuli 0.7 g: measured +0.11 % (+0.41 % before landings were grouped).
const REGRESSION_FRAME_FRIULI_07_PENALTY: f64 = 0.0055;
/// Penalty, Kobe 0.5 g: measured +0.017 % (−0.48 % before).
const REGRESSION_FRAME_KOBE_05_PENALTY: f64 = 0.002;
/// Penalty, Kobe 0.7 g: measured +0.32 % (+0.10 % before).
const REGRESSION_FRAME_KOBE_07_PENALTY: f64 = 0.016;
/// Penalty, Loma Prieta 0.6 g: measured −0.35 % (−28.64 % before: the columns parted).
const REGRESSION_FRAME_LOMA_PRIETA_06_PENALTY: f64 = 0.018;
/// Dual, Friuli 0.7 g: measured +0.16 % (+0.55 % before).
const REGRESSION_FRAME_FRIULI_07_DUAL: f64 = 0.008;
/// Dual, Kobe 0.5 g: measured −0.017 % (−0.31 % before).
const REGRESSION_FRAME_KOBE_05_DUAL: f64 = 0.002;
/// Dual, Kobe 0.7 g: measured +0.36 % (did not converge before).
const REGRESSION_FRAME_KOBE_07_DUAL: f64 = 0.018;
/// Dual, Loma Prieta 0.6 g: measured −0.25 % (stalled at a cap–column corner pair before).
const REGRESSION_FRAME_LOMA_PRIETA_06_DUAL: f64 = 0.013;

/// Loma Prieta 0.6 g is well conditioned (±1 % of PGA: −0.02 / −0.03 %; ±1 % of r: −2.3 /
/// +2.2 %). It failed by −28.64 % until landings within one step were grouped into one impact:
/// the columns land 0.1–0.3 Δt apart, each landing stopped one column alone, and the frame's
/// columns parted (0.11 rad; `frame_loma_prieta_landings` prints the landings,
/// docs/impacts-and-multiblock.md).
#[test]
fn frame_peak_rotation_under_records_penalty() {
    frame_record_point(
        1.0,
        "penalty",
        FRIULI,
        0.7,
        REGRESSION_FRAME_FRIULI_07_PENALTY,
    );
    frame_record_point(1.0, "penalty", KOBE, 0.5, REGRESSION_FRAME_KOBE_05_PENALTY);
    frame_record_point(1.0, "penalty", KOBE, 0.7, REGRESSION_FRAME_KOBE_07_PENALTY);
    frame_record_point(
        1.0,
        "penalty",
        LOMA_PRIETA,
        0.6,
        REGRESSION_FRAME_LOMA_PRIETA_06_PENALTY,
    );
}

/// Kobe 0.7 g did not converge (the left column–cap contact) until landings were grouped;
/// Loma Prieta 0.6 g then still stalled at the right column–cap corner pair, a phantom
/// penetration of a corner beside the cap's end (a temporary print of
/// the contacts showed it; docs/dual.md), until the dual solver stopped asserting it.
#[test]
fn frame_peak_rotation_under_records_dual() {
    frame_record_point(1.0, "dual", FRIULI, 0.7, REGRESSION_FRAME_FRIULI_07_DUAL);
    frame_record_point(1.0, "dual", KOBE, 0.5, REGRESSION_FRAME_KOBE_05_DUAL);
    frame_record_point(1.0, "dual", KOBE, 0.7, REGRESSION_FRAME_KOBE_07_DUAL);
    frame_record_point(
        1.0,
        "dual",
        LOMA_PRIETA,
        0.6,
        REGRESSION_FRAME_LOMA_PRIETA_06_DUAL,
    );
}

/// Diagnosis of the Loma Prieta miss (prints; ignored): do the columns slide on the base
/// (the pivot corner's horizontal drift) or the cap on the columns?
#[test]
#[ignore = "diagnosis: prints the pivots' slip of the frame under Loma Prieta 0.6 g"]
fn frame_loma_prieta_slip() {
    let m = frame_record(LOMA_PRIETA, 0.6);
    let scene = frame_scene(1.0, "penalty");
    let mut s = sim(&scene, &m);
    let corner = |s: &ashlar::simulation::Simulation, b: usize, local: [f64; 2]| {
        let g = &s.geoms()[b];
        let (c, sn) = (g.rotation.cos(), g.rotation.sin());
        let (dx, dy) = (
            local[0] - g.initial_centroid.x,
            local[1] - g.initial_centroid.y,
        );
        [
            g.centroid.x + c * dx - sn * dy,
            g.centroid.y + sn * dx + c * dy,
        ]
    };
    let (mut slip, mut slip_before, mut cap_slip) = (0.0f64, 0.0f64, 0.0f64);
    let (mut first_mm, mut first_tenth) = (f64::NAN, f64::NAN);
    run(&mut s, 12.0, |s| {
        for (b, xc) in [(1usize, -0.8), (2, 0.8)] {
            for x0 in [xc - B, xc + B] {
                let p = corner(s, b, [x0, 0.0]);
                if p[1] < 1e-4 {
                    slip = slip.max((p[0] - x0).abs());
                    if s.time() < 6.2 {
                        slip_before = slip_before.max((p[0] - x0).abs());
                    }
                    if first_tenth.is_nan() && (p[0] - x0).abs() > 1e-4 {
                        first_tenth = s.time();
                        let states: Vec<String> = s
                            .contacts()
                            .contacts
                            .iter()
                            .filter(|c| (c.vertex_block == 0) != (c.edge_block == 0))
                            .map(|c| format!("{}-{}: {:?}", c.vertex_block, c.edge_block, c.state))
                            .collect();
                        eprintln!(
                            "t = {:.4} s, θ = {:.5} / {:.5} rad, velocities (vx, vy, ω) left {:.4?}, right {:.4?}, cap {:.4?}; base contacts {states:?}",
                            s.time(),
                            s.geoms()[1].rotation,
                            s.geoms()[2].rotation,
                            s.block_velocity(1),
                            s.block_velocity(2),
                            s.block_velocity(3)
                        );
                    }
                    if first_mm.is_nan() && (p[0] - x0).abs() > 1e-3 {
                        first_mm = s.time();
                    }
                }
            }
        }
        // The cap against the left column's top-left corner (it translates with it in the model).
        let top = corner(s, 1, [-0.8 - B, 2.0 * H]);
        let cap = corner(s, 3, [-0.8 - B, 2.0 * H]);
        cap_slip = cap_slip.max((cap[0] - top[0]).abs());
    });
    eprintln!(
        "Loma Prieta 0.6 g, penalty, to 12 s: largest horizontal drift of a grounded bottom corner {slip:.2e} m ({slip_before:.2e} m before 6.2 s); cap against the left column's top-left corner {cap_slip:.2e} m; drift first above 0.1 mm at {first_tenth:.3} s, above 1 mm at {first_mm:.3} s"
    );
}

/// Diagnosis of the Loma Prieta miss (prints; ignored): when does each column's base corner
/// land (a base contact closes), and how far apart are the two columns' landings?
#[test]
#[ignore = "diagnosis: prints the columns' landing times under Loma Prieta 0.6 g"]
fn frame_loma_prieta_landings() {
    let m = frame_record(LOMA_PRIETA, 0.6);
    let scene = frame_scene(1.0, "penalty");
    let mut s = sim(&scene, &m);
    let t_end = 6.3;
    let closed = |s: &ashlar::simulation::Simulation| -> Vec<(usize, usize, bool)> {
        s.contacts()
            .contacts
            .iter()
            .filter(|c| (c.vertex_block == 0) != (c.edge_block == 0))
            .map(|c| {
                (
                    c.vertex_block.max(c.edge_block),
                    c.vertex,
                    c.state.is_closed(),
                )
            })
            .collect()
    };
    let mut before = closed(&s);
    let mut impacts = 0;
    let mut last_landing = [f64::NAN; 3];
    run(&mut s, t_end, |s| {
        let now = closed(s);
        let stats = s.stats();
        let new_impacts = stats.impacts - impacts;
        impacts = stats.impacts;
        for &(b, v, c) in &now {
            let was = before.iter().find(|x| x.0 == b && x.1 == v).map(|x| x.2);
            if c && was == Some(false) {
                last_landing[b] = s.time();
                let other = if b == 1 { 2 } else { 1 };
                eprintln!(
                    "t = {:.6} s (dt {:.2e}): column {b} lands on vertex {v}; column {other} last landed {:.6} s; θ {:.6} / {:.6}, ω {:.5} / {:.5}, cap ω {:.5}; impacts this step {new_impacts}",
                    s.time(),
                    s.dt(),
                    last_landing[other],
                    s.geoms()[1].rotation,
                    s.geoms()[2].rotation,
                    s.block_velocity(1)[2],
                    s.block_velocity(2)[2],
                    s.block_velocity(3)[2],
                );
            }
        }
        before = now;
    });
    let (l, r) = (s.geoms()[1].rotation, s.geoms()[2].rotation);
    eprintln!(
        "at {t_end} s: θ {l:.6} / {r:.6}, mismatch {:.2e}",
        (l - r).abs()
    );
}
