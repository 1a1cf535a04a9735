//! Independent semi-analytic references of Yagoda-Biran & Hatzor 2015, §3 (docs/verification.md, References), integrated by fixed steps: Housner's
//! rocking column, the rigid-plastic (Newmark) block on an incline, and the block on a shaking
//! foundation (Eq. 17). Used by `ashlar study` and by the physics tests that hold the engine
//! and the reduced models to them.
//!
//! Nothing here shares code with the engine or with `analysis::reduced` (which integrates the
//! same equations adaptively, with event location): agreement is evidence, not tautology. Keep
//! it that way: no imports from the rest of the crate.
//!
//! Units: m, s, rad. Ground acceleration is a function of time (m/s², along +x).

/// A free-standing rigid rectangular column on a rigid base (Housner 1963), rocking about
/// its base corners.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct HousnerColumn {
    /// Half-width b, m.
    pub b: f64,
    /// Half-height h, m.
    pub h: f64,
    /// Gravity, m/s².
    pub g: f64,
    /// Fixed RK4 step, s.
    pub dt: f64,
}

impl HousnerColumn {
    /// The rocking column of Yagoda-Biran & Hatzor 2015, §3.3 (b = 0.2 m, h = 0.6 m, g = 9.81 m/s²) at an RK4 step of 1e-5 s.
    pub const YAGODA_BIRAN_2015: Self = Self {
        b: 0.2,
        h: 0.6,
        g: 9.81,
        dt: 1e-5,
    };
}

/// The rocking reference after a step.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct RockingState {
    /// Steps taken.
    pub step: usize,
    /// Time, s (`step × dt`).
    pub t: f64,
    /// Rotation θ, rad, counter-clockwise positive: a ground accelerating to +x tips the
    /// column back towards −x, θ > 0.
    pub theta: f64,
    /// θ̇, rad/s.
    pub omega: f64,
    /// Impacts (θ crossing zero) so far.
    pub impacts: usize,
    /// Time of the first impact (located within its step), s.
    pub first_impact: Option<f64>,
}

/// Angular speed below which a column that has just impacted is at rest again, rad/s.
const REST_SPEED: f64 = 1e-6;

/// Impacts located within one RK4 step at most; a column that lands more often than this in
/// 1e-5 s is at rest (the rest of the step is dropped).
const IMPACTS_PER_STEP: usize = 8;

/// Precision of a located impact's time, s: 1e-14 s moves θ by |θ̇|·1e-14, far below the
/// round-off of θ for any rocking speed.
const IMPACT_TIME: f64 = 1e-14;

/// Housner's equation of rocking, θ̈ = (3/4R)[−g sin(α sgnθ − θ) + ü_g cos(α sgnθ − θ)]
/// (R = √(b² + h²), α = atan(b/h)), under the ground acceleration `ground(t)`.
///
/// The column rests until |ü_g| > g tan α (the instant located within the step) and then tips
/// with the sign of ü_g; each step is classical RK4 of `dt`. When θ crosses zero within a step, the impact is located in it by
/// bisection on RK4 sub-steps from the step's start (to 1e-14 s); there θ = 0 and θ̇ is scaled
/// by Housner's restitution e = 1 − 1.5 sin²α, and the rest of the step is integrated on the new
/// pivot (more impacts in it are located the same way). The column is at rest again if
/// |θ̇| < 1e-6 rad/s after an impact.
///
/// Why located: with the impact put at the step's end (as this function did until session 33)
/// each impact errs by up to one step in time, a first-order error that a run of small
/// impacts amplifies. On records the reference then did not converge at 1e-5 s: the 0.4 × 1.2 m
/// column under Loma Prieta at 5.371 m/s² peaked at 0.0568 rad at 1e-5 s, 0.2955 at 1e-6 s and
/// 0.2978 at 2e-7 s (docs/accuracy-vs-speed.md, "Reduced models on records").
///
/// `observe` sees the state after every step (resting ones too) and returns `true` to stop,
/// e.g. once the column has overturned: the equation means nothing past |θ| = π/2. Runs
/// `round(t_end / dt)` steps at most; returns the last state.
pub fn housner_rocking(
    col: &HousnerColumn,
    ground: impl Fn(f64) -> f64,
    t_end: f64,
    mut observe: impl FnMut(&RockingState) -> bool,
) -> RockingState {
    let r = col.b.hypot(col.h);
    let alpha = (col.b / col.h).atan();
    let k = 3.0 / (4.0 * r);
    let e = 1.0 - 1.5 * alpha.sin().powi(2);
    let g = col.g;
    let dt = col.dt;
    let mut sgn = 0.0f64;
    let acc = |t: f64, th: f64, sgn: f64| {
        k * (-g * (alpha * sgn - th).sin() + ground(t) * (alpha * sgn - th).cos())
    };
    // One classical RK4 step of `h` from (t, θ, θ̇) on the pivot of sign `sgn`.
    let rk4 = |t: f64, th: f64, w: f64, h: f64, sgn: f64| {
        let f = |t: f64, th: f64, w: f64| (w, acc(t, th, sgn));
        let (k1t, k1w) = f(t, th, w);
        let (k2t, k2w) = f(t + h / 2.0, th + h / 2.0 * k1t, w + h / 2.0 * k1w);
        let (k3t, k3w) = f(t + h / 2.0, th + h / 2.0 * k2t, w + h / 2.0 * k2w);
        let (k4t, k4w) = f(t + h, th + h * k3t, w + h * k3w);
        (
            th + h / 6.0 * (k1t + 2.0 * k2t + 2.0 * k3t + k4t),
            w + h / 6.0 * (k1w + 2.0 * k2w + 2.0 * k3w + k4w),
        )
    };
    let mut s = RockingState::default();
    let n = (t_end / dt).round() as usize;
    for i in 0..n {
        let t = i as f64 * dt;
        let (mut tt, mut left) = (t, dt);
        if sgn == 0.0 {
            let threshold = g * alpha.tan();
            if ground(t).abs() > threshold {
                sgn = ground(t).signum();
            } else if ground(t + dt).abs() > threshold {
                // The onset within the step, located like an impact (at the step's start it
                // would err by up to a step: a second-order error in θ).
                let hi = first_true(t, t + dt, |x| ground(x).abs() > threshold);
                sgn = ground(hi).signum();
                tt = hi;
                left = t + dt - hi;
            }
        }
        for _ in 0..IMPACTS_PER_STEP {
            if sgn == 0.0 || left <= 0.0 {
                break;
            }
            let (th, w) = (s.theta, s.omega);
            let (nth, nw) = rk4(tt, th, w, left, sgn);
            if nth * sgn >= 0.0 {
                s.theta = nth;
                s.omega = nw;
                break;
            }
            // θ crosses zero within the sub-step: the shortest sub-step after which it has.
            let hi = first_true(0.0, left, |h| rk4(tt, th, w, h, sgn).0 * sgn < 0.0);
            let w_before = rk4(tt, th, w, hi, sgn).1;
            tt += hi;
            left -= hi;
            s.impacts += 1;
            s.first_impact.get_or_insert(tt);
            s.theta = 0.0;
            s.omega = w_before * e;
            sgn = s.omega.signum();
            if s.omega.abs() < REST_SPEED {
                sgn = 0.0;
                s.omega = 0.0;
            }
        }
        s.step = i + 1;
        s.t = (i + 1) as f64 * dt;
        if observe(&s) {
            break;
        }
    }
    s
}

/// The smallest x in (lo, hi] at which `holds` does, by bisection to [`IMPACT_TIME`] (it does
/// not at `lo`, it does at `hi`): where the reference locates an onset or an impact.
fn first_true(mut lo: f64, mut hi: f64, holds: impl Fn(f64) -> bool) -> f64 {
    while hi - lo > IMPACT_TIME {
        let mid = 0.5 * (lo + hi);
        if mid <= lo || mid >= hi {
            break;
        }
        if holds(mid) {
            hi = mid;
        } else {
            lo = mid;
        }
    }
    hi
}

/// Half-cycles of a rocking history of (t s, θ rad, θ̇ rad/s) samples: (start time s, |θ̇| at
/// the start rad/s, peak |θ| rad) of each run of one sign of θ. A sample with |θ| ≤ 1e-5 rad
/// counts as at rest (neither sign), so rest between two half-cycles of the same sign does not
/// split them. Used to compare histories half-cycle by half-cycle (docs/accuracy-vs-speed.md).
pub fn half_cycles(h: &[(f64, f64, f64)]) -> Vec<(f64, f64, f64)> {
    let still = 1e-5;
    let mut out: Vec<(f64, f64, f64)> = Vec::new();
    let mut sign = 0.0f64;
    for &(t, th, w) in h {
        let s = if th.abs() > still { th.signum() } else { 0.0 };
        if s != 0.0 && s != sign {
            out.push((t, w.abs(), th.abs()));
        }
        if s != 0.0 {
            sign = s;
        }
        if let Some(last) = out.last_mut() {
            if s == sign && s != 0.0 {
                last.2 = last.2.max(th.abs());
            }
        }
    }
    out
}

/// One landing of a rocking history ([`landings`]): the sign change of θ and |θ̇| on either
/// side of it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Landing {
    /// s.
    pub time: f64,
    /// |θ̇| just before and just after, rad/s.
    pub before: f64,
    pub after: f64,
}

impl Landing {
    /// The landing's ratio r = |θ̇⁺|/|θ̇⁻| (Housner's 1 − 1.5 sin²α for a rectangle).
    pub fn ratio(&self) -> f64 {
        self.after / self.before
    }
}

/// The fit windows of [`landings`], s from the landing: θ̇ is fitted on [t − 2 ms, t − 0.3 ms]
/// before it and on [t + 1.5 ms, t + 3 ms] after it. In free rocking at small θ gravity's
/// torque is constant within a half-cycle, so θ̇ is linear there and the fit drops its change
/// exactly; the contact's ringing after a landing (a few tenths of a ms for a penalty corner)
/// falls before the second window.
pub const LANDING_FIT_BEFORE: (f64, f64) = (3e-4, 2e-3);
pub const LANDING_FIT_AFTER: (f64, f64) = (1.5e-3, 3e-3);

/// The landings of a rocking history of (t s, θ rad, θ̇ rad/s) samples in time order whose
/// sign change of θ (linearly interpolated) lies within [t0, t1] s: θ̇ on either side fitted by
/// least squares on the windows [`LANDING_FIT_BEFORE`] and [`LANDING_FIT_AFTER`] and
/// extrapolated to the landing. A landing is skipped where a window reaches within 0.1 ms of
/// the neighbouring landing or of the history's first or last sample, or holds fewer than three
/// samples. Measured on Housner's own history: r within ±0.015 of 1 − 1.5 sin²α
/// (docs/accuracy-vs-speed.md, "Micro-rocking").
pub fn landings(h: &[(f64, f64, f64)], t0: f64, t1: f64) -> Vec<Landing> {
    let (before, after) = (LANDING_FIT_BEFORE, LANDING_FIT_AFTER);
    let (Some(first), Some(last)) = (h.first(), h.last()) else {
        return Vec::new();
    };
    let crossings: Vec<f64> = h
        .windows(2)
        .filter(|w| w[0].1 != 0.0 && (w[0].1 > 0.0) != (w[1].1 > 0.0))
        .map(|w| w[0].0 + (w[1].0 - w[0].0) * w[0].1 / (w[0].1 - w[1].1))
        .collect();
    // θ̇ on [a, b] by least squares, at `at`.
    let fit = |a: f64, b: f64, at: f64| {
        let p: Vec<(f64, f64)> = h
            .iter()
            .filter(|x| x.0 >= a && x.0 <= b)
            .map(|x| (x.0, x.2))
            .collect();
        let n = p.len() as f64;
        let mx = p.iter().map(|x| x.0).sum::<f64>() / n;
        let my = p.iter().map(|x| x.1).sum::<f64>() / n;
        let sxx: f64 = p.iter().map(|x| (x.0 - mx).powi(2)).sum();
        let sxy: f64 = p.iter().map(|x| (x.0 - mx) * (x.1 - my)).sum();
        (p.len() >= 3 && sxx > 0.0).then(|| my + sxy / sxx * (at - mx))
    };
    let mut out = Vec::new();
    for (k, &t) in crossings.iter().enumerate() {
        if t < t0 || t > t1 {
            continue;
        }
        let prev = if k > 0 { crossings[k - 1] } else { first.0 };
        let next = crossings.get(k + 1).copied().unwrap_or(last.0);
        if t - prev < before.1 + 1e-4 || next - t < after.1 + 1e-4 {
            continue;
        }
        if let (Some(wb), Some(wa)) = (
            fit(t - before.1, t - before.0, t),
            fit(t + after.0, t + after.1, t),
        ) {
            out.push(Landing {
                time: t,
                before: wb.abs(),
                after: wa.abs(),
            });
        }
    }
    out
}

/// The ground motion of Yagoda-Biran & Hatzor 2015, §3.3: ü_g = A sin 2πt for 0 ≤ t ≤ 0.5 s (one half-sine of a 1 s
/// period), then 0; A in m/s².
pub fn half_sine_pulse(a: f64) -> impl Fn(f64) -> f64 {
    move |t| {
        if (0.0..=0.5).contains(&t) {
            a * (2.0 * std::f64::consts::PI * t).sin()
        } else {
            0.0
        }
    }
}

/// A sampled rocking history.
#[derive(Debug, Clone, PartialEq)]
pub struct RockingHistory {
    /// (t, θ) at t = 0 and after every `stride` steps, s and rad.
    pub samples: Vec<(f64, f64)>,
    /// |θ| passed π/2 (the integration stops there).
    pub overturned: bool,
    /// Time of the first impact (located within its step), s.
    pub first_impact: Option<f64>,
}

/// [`housner_rocking`] until `t_end` or until the column overturns (|θ| > π/2), sampled every
/// `stride` steps.
pub fn housner_history(
    col: &HousnerColumn,
    ground: impl Fn(f64) -> f64,
    t_end: f64,
    stride: usize,
) -> RockingHistory {
    let stride = stride.max(1);
    let over = |s: &RockingState| s.theta.abs() > std::f64::consts::FRAC_PI_2;
    let mut samples = vec![(0.0, 0.0)];
    let end = housner_rocking(col, ground, t_end, |s| {
        if s.step % stride == 0 {
            samples.push((s.t, s.theta));
        }
        over(s)
    });
    RockingHistory {
        samples,
        overturned: over(&end),
        first_impact: end.first_impact,
    }
}

/// Down-slope displacement (m) relative to the ground of a rigid-plastic block on an incline
/// at `alpha` (rad; down-slope towards +x) with friction angle `phi` (rad), under the
/// horizontal ground acceleration `ground(t)` (Yagoda-Biran & Hatzor 2015, Eq. 10, Newmark's sliding block).
///
/// Per unit mass the drive along the slope is g sin α − ü_g cos α (the inertial load is
/// −ü_g) and the normal pressure max(0, g cos α + ü_g sin α). Semi-implicit fixed steps of
/// `dt` with the exact friction law in both sliding directions; friction never reverses the
/// motion within a step (the block sticks when its velocity crosses zero). The stick/slip
/// timing is first order in `dt`. Runs `round(t_end / dt)` steps.
pub fn newmark_incline(
    alpha: f64,
    phi: f64,
    g: f64,
    ground: impl Fn(f64) -> f64,
    t_end: f64,
    dt: f64,
) -> f64 {
    let (sa, ca, mu) = (alpha.sin(), alpha.cos(), phi.tan());
    let (mut s, mut v) = (0.0f64, 0.0f64);
    let n = (t_end / dt).round() as usize;
    for i in 0..n {
        let ag = ground(i as f64 * dt);
        let drive = g * sa - ag * ca;
        let fric = mu * (g * ca + ag * sa).max(0.0);
        let acc = if v > 0.0 {
            drive - fric
        } else if v < 0.0 {
            drive + fric
        } else if drive.abs() > fric {
            drive - fric * drive.signum()
        } else {
            0.0
        };
        let nv = v + acc * dt;
        let nv = if v != 0.0 && nv * v < 0.0 { 0.0 } else { nv };
        s += 0.5 * (v + nv) * dt;
        v = nv;
    }
    s
}

/// Relative speed below which the block and the foundation move together, m/s.
const STUCK_SPEED: f64 = 1e-12;

/// Yagoda-Biran & Hatzor 2015, Eq. 17: displacement x₂ (m) of a block resting with friction coefficient `mu` on
/// a foundation that moves as d₁ = A(1 − cos ωt), ω = 2πf, from rest.
///
/// Fixed steps of `dt`: while stuck the block follows the foundation as long as the
/// foundation's acceleration is within μg; while slipping it accelerates at ±μg towards the
/// foundation's velocity, and sticks when the relative velocity would change sign within the
/// step. The stick/slip timing is first order in `dt` (a velocity error of up to dt·Aω² at
/// each reversal). Returns (t, x₂) at t = 0 and every `every` steps, `round(t_end / dt)` steps.
pub fn foundation_eq17(
    a: f64,
    f: f64,
    mu: f64,
    g: f64,
    t_end: f64,
    dt: f64,
    every: usize,
) -> Vec<(f64, f64)> {
    let w = 2.0 * std::f64::consts::PI * f;
    let limit = mu * g;
    let (mut x2, mut v2) = (0.0f64, 0.0f64);
    let mut out = vec![(0.0, 0.0)];
    let n = (t_end / dt).round() as usize;
    let every = every.max(1);
    for i in 0..n {
        let t = i as f64 * dt;
        let v1 = a * w * (w * t).sin();
        let a1 = a * w * w * (w * t).cos();
        let rel = v1 - v2;
        let stuck = rel.abs() < STUCK_SPEED;
        let acc = if stuck {
            a1.clamp(-limit, limit)
        } else {
            limit * rel.signum()
        };
        let mut nv = v2 + acc * dt;
        let nv1 = a * w * (w * (t + dt)).sin();
        let reverses = !stuck && (nv1 - nv) * rel < 0.0;
        let stays_stuck = stuck && a1.abs() <= limit;
        if reverses || stays_stuck {
            nv = nv1;
        }
        x2 += 0.5 * (v2 + nv) * dt;
        v2 = nv;
        if (i + 1) % every == 0 {
            out.push(((i + 1) as f64 * dt, x2));
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    const G: f64 = 9.81;

    /// A rest inside a run of one sign does not split it; a change of sign does: two
    /// half-cycles, each with its start speed and peak (exact: the peaks are samples).
    #[test]
    fn half_cycles_split_on_sign_and_bridge_rest() {
        let h = [
            (0.0, 0.0, 0.0),
            (0.1, 0.02, 0.5),
            (0.2, 0.05, 0.1),
            (0.3, 0.0, -0.4),
            (0.4, 0.03, 0.2),
            (0.5, -0.01, -0.6),
            (0.6, -0.04, -0.1),
        ];
        let c = half_cycles(&h);
        assert_eq!(c, vec![(0.1, 0.5, 0.05), (0.5, 0.6, 0.04)]);
    }

    /// A synthetic history with landings of known ratio: θ̇ linear in t on either side of each
    /// landing (slope 0.3 rad/s², as gravity's torque gives) and, just after it, a ringing of
    /// half the approach speed that the after-window must miss. Samples every 0.1 ms, each
    /// landing halfway between two (θ changes sign there, θ = ± the time to the nearest
    /// landing). The landings near 10 and 40 ms have r = 0.9 and 0.8: the fit is exact to
    /// round-off (bound 1e-9); the ones near 25 and 27 ms are too close to each other to fit
    /// and are skipped, and the bounds [t0, t1] leave out the one near 55 ms.
    #[test]
    fn landings_recover_known_ratios() {
        let dt = 1e-4;
        // Landing times (s), ratios, approach speeds (rad/s).
        let land: Vec<(f64, f64, f64)> = [(100, 0.9, 0.02), (250, 0.7, 0.02), (270, 0.7, 0.02)]
            .into_iter()
            .chain([(400, 0.8, 0.03), (550, 0.5, 0.01)])
            .map(|(i, r, w)| ((f64::from(i) - 0.5) * dt, r, w))
            .collect();
        let slope = 0.3;
        let h: Vec<(f64, f64, f64)> = (0..=700)
            .map(|i| {
                let t = f64::from(i) * dt;
                // Landings passed so far: θ's sign alternates from one to the next.
                let k = land.iter().filter(|l| l.0 < t).count();
                let sign = if k % 2 == 0 { 1.0 } else { -1.0 };
                let to_next = land.get(k).map_or(f64::INFINITY, |l| l.0 - t);
                let from_prev = if k > 0 {
                    t - land[k - 1].0
                } else {
                    f64::INFINITY
                };
                let omega = if from_prev < to_next {
                    // Leaving landing k − 1 at r·ω⁻, with the ringing.
                    let (tl, r, w) = land[k - 1];
                    let s = t - tl;
                    let ring = if s < 1e-3 {
                        0.5 * w * (s * 2e4).sin()
                    } else {
                        0.0
                    };
                    sign * r * w + slope * s + ring
                } else {
                    // Approaching landing k at ω⁻.
                    let (tl, _, w) = land[k];
                    -sign * w + slope * (t - tl)
                };
                (t, sign * to_next.min(from_prev), omega)
            })
            .collect();
        let found = landings(&h, 0.0, 0.05);
        let times: Vec<f64> = found.iter().map(|l| l.time).collect();
        assert_eq!(found.len(), 2, "landings at {times:?}");
        for (l, (tl, r, w)) in found.iter().zip([land[0], land[3]]) {
            assert!((l.time - tl).abs() < 1e-12, "{l:?}");
            assert!((l.before - w).abs() < 1e-9 * w, "{l:?}");
            assert!((l.ratio() - r).abs() < 1e-9, "{l:?} against r = {r}");
        }
    }

    /// Under gravity alone the incline has the closed form d = ½g(sin α − cos α tan φ)t²
    /// (Yagoda-Biran & Hatzor 2015, Eq. 14); the semi-implicit steps with the trapezoidal position update
    /// integrate a constant acceleration exactly, so only round-off remains (1e-9 relative).
    #[test]
    fn incline_under_gravity_is_the_closed_form() {
        let (alpha, phi) = (30f64.to_radians(), 20f64.to_radians());
        let d = newmark_incline(alpha, phi, G, |_| 0.0, 1.0, 1e-4);
        let exact = 0.5 * G * (alpha.sin() - alpha.cos() * phi.tan());
        assert!(((d - exact) / exact).abs() < 1e-9, "{d} vs {exact}");
        // Below the friction angle it does not move.
        assert_eq!(newmark_incline(phi, alpha, G, |_| 0.0, 1.0, 1e-4), 0.0);
    }

    /// A column below g tan α never leaves its base; and the free rocking of a column
    /// released from rest conserves energy between impacts (RK4 at 1e-5 s: 1e-9 relative).
    #[test]
    fn rocking_rests_below_the_threshold_and_conserves_energy_in_flight() {
        let col = HousnerColumn {
            b: 0.2,
            h: 0.6,
            g: G,
            dt: 1e-5,
        };
        let low = 0.99 * G * col.b / col.h;
        let end = housner_rocking(&col, |_| low, 1.0, |_| false);
        assert_eq!((end.theta, end.omega, end.step), (0.0, 0.0, 100_000));
        // A 0.05 s kick above the threshold, then free rocking: E = ½Iθ̇² + mgR cos(α − θ)
        // per unit m with I = 4R²/3 (about the corner) is constant until the first impact.
        let (r, alpha) = (col.b.hypot(col.h), (col.b / col.h).atan());
        let energy = |s: &RockingState| {
            0.5 * (4.0 * r * r / 3.0) * s.omega.powi(2) + G * r * (alpha - s.theta).cos()
        };
        let mut flight = Vec::new();
        let kick = |t: f64| if t < 0.05 { 2.0 * G } else { 0.0 };
        housner_rocking(&col, kick, 2.0, |s| {
            if s.t > 0.05 + 2.0 * col.dt && s.impacts == 0 {
                flight.push(energy(s));
            }
            s.impacts > 0 || s.theta.abs() > std::f64::consts::FRAC_PI_2
        });
        assert!(flight.len() > 100, "no free flight: {}", flight.len());
        let (lo, hi) = flight
            .iter()
            .fold((f64::MAX, f64::MIN), |(a, b), &x| (a.min(x), b.max(x)));
        assert!((hi - lo) / hi < 1e-9, "energy drifts {}", (hi - lo) / hi);
    }

    /// With impacts located inside the step the reference converges at RK4's order through
    /// impacts: a column rocked by a half-sine pulse (YB 2015's column, A = 1.5 g tan α), then
    /// rocking freely through several impacts to t = 3 s. The state's error against a run at
    /// 1e-6 s must fall at least 8× per halving of the step from 2e-3 s (fourth order gives
    /// 16×; impacts put at the step's end, as before session 33, give 2×).
    #[test]
    fn located_impacts_converge_at_fourth_order() {
        let col = |dt: f64| HousnerColumn {
            dt,
            ..HousnerColumn::YAGODA_BIRAN_2015
        };
        let a = 1.5 * G * (0.2f64 / 0.6);
        let at = |dt: f64| housner_rocking(&col(dt), half_sine_pulse(a), 3.0, |_| false);
        let exact = at(1e-6);
        assert!(exact.impacts >= 4, "only {} impacts", exact.impacts);
        let err = |dt: f64| {
            let s = at(dt);
            assert_eq!(s.impacts, exact.impacts, "dt {dt}");
            (s.theta - exact.theta).abs() + 0.1 * (s.omega - exact.omega).abs()
        };
        let e: Vec<f64> = [2e-3, 1e-3, 5e-4].into_iter().map(err).collect();
        for w in e.windows(2) {
            assert!(w[0] / w[1] > 8.0, "errors {e:?}");
        }
    }

    /// A foundation shaken well below μg carries the block with it: x₂ = d₁ = A(1 − cos ωt).
    #[test]
    fn foundation_below_the_friction_limit_carries_the_block() {
        let (a, f, mu) = (0.001, 1.0, 0.6);
        let w = 2.0 * std::f64::consts::PI * f;
        for (t, x2) in foundation_eq17(a, f, mu, G, 2.0, 1e-5, 1000) {
            let d1 = a * (1.0 - (w * t).cos());
            assert!((x2 - d1).abs() < 1e-12, "t {t}: {x2} vs {d1}");
        }
    }
}

/// First motion from rest of a rigid rectangular block on a fixed incline under gravity and a
/// constant horizontal load (Yeung 1991; Yagoda-Biran and Hatzor 2013), as the chart of
/// [`first_motion_chart`] classifies it.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum FirstMotion {
    Stable,
    Sliding,
    Toppling,
    SlidingToppling,
}

/// Yeung's toppling criterion: the friction coefficient tan φ the down-slope corner needs to
/// stick at the onset of toppling, f(ψ, δ) = [(4t² + 1)T + 3t] / [(t² + 4) + 3tT] with
/// t = tan δ, T = tan ψ (dimensionless; angles in rad). Derived, and checked against the
/// slipping-pivot analysis, in tests/engine/failure_modes.rs.
pub fn yeung_f(psi: f64, delta: f64) -> f64 {
    let (t, tt) = (delta.tan(), psi.tan());
    ((4.0 * t * t + 1.0) * tt + 3.0 * t) / ((t * t + 4.0) + 3.0 * t * tt)
}

/// The failure-mode chart (angles in rad): `psi` is the angle of the effective gravity (weight
/// plus the horizontal inertial load) from the slope normal, `delta` = atan(width / height) the
/// block's slenderness, `phi` the joint's friction angle. Stable inside the base and the
/// friction cone; toppling where ψ > δ and the pivot sticks (tan φ ≥ [`yeung_f`]); sliding
/// where φ < ψ and φ < δ; sliding and toppling otherwise.
pub fn first_motion_chart(psi: f64, delta: f64, phi: f64) -> FirstMotion {
    if psi < delta {
        if psi < phi {
            FirstMotion::Stable
        } else {
            FirstMotion::Sliding
        }
    } else if phi.tan() >= yeung_f(psi, delta) {
        FirstMotion::Toppling
    } else if phi < delta {
        FirstMotion::Sliding
    } else {
        FirstMotion::SlidingToppling
    }
}
