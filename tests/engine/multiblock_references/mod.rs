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

/// Columns: half-width b, half-height h (Yagoda-Biran & Hatzor's column); the
/// frame's columns and the pier's.
const B: f64 = 0.2;
const H: f64 = 0.6;

mod frame;
mod frame_records;
mod pier;
mod sliding_stack;
