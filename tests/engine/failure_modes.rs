//! Failure-mode chart of a block on an incline (Yagoda-Biran & Hatzor 2015, §3.2; Yeung 1991; Yagoda-Biran and
//! Hatzor 2013): the *first motion* of a rigid rectangular block — stable, sliding, toppling, or
//! sliding and toppling — under gravity and a horizontal pseudo-static force, compared with the
//! analytic chart derived below, case by case. Tolerance: agreement in every case (binary; the
//! published 2D-DDA got 106 of 110), with every case kept at least 2° from every mode boundary.
//!
//! # Set-up and notation
//! Block of width w (along the slope) and height h (normal to it), slenderness
//! δ = atan(w/h), on a fixed incline of angle α descending towards +x, joint friction φ. The
//! pseudo-static force is a constant horizontal ground acceleration a_g = −k·g (ground pushed
//! towards −x), i.e. an inertial load +k·m·g towards +x (down-slope). Weight plus inertia is an
//! effective gravity G = g·√(1+k²) tilted by β = atan k from the vertical towards the down-slope
//! side, so relative to the slope normal it makes the angle ψ = α + β: every criterion below
//! depends on (ψ, δ, φ) only. Slope frame: x down-slope, y along the outward normal; effective
//! gravity per unit mass (G sin ψ, −G cos ψ). Down-slope corner O; the centroid sits at
//! C − O = (−w/2, h/2); L = √(w²+h²); I_C = mL²/12, I_O = mL²/3.
//!
//! # The chart (rigid-body first motion from rest)
//! 1. *Static equilibrium* needs the resultant inside the base (ψ < δ) and within the friction
//!    cone (ψ < φ): then the block is **stable**.
//! 2. *Pure sliding* (no rotation): acceleration a = G(sin ψ − cos ψ tan φ) > 0 needs ψ > φ. In
//!    the frame sliding with the block the effective gravity becomes (G cos ψ tan φ, −G cos ψ),
//!    tilted by exactly φ from the normal, so the block does not rotate iff φ < δ. Hence
//!    **sliding** iff φ < ψ and φ < δ. (The classic static chart calls the part ψ > δ > φ
//!    "sliding and toppling"; the dynamic analysis shows it slides only.)
//! 3. *Pure toppling* about O with O stuck (Yeung's dynamic criterion): at the onset (ω = 0)
//!    the moment about O gives the clockwise angular acceleration
//!    θ̈ = m G (h sin ψ − w cos ψ)/(2 I_O) = 3 G sin(ψ − δ)/(2L),
//!    positive iff ψ > δ. The centroid then accelerates θ̈·(h/2, w/2); Newton's law for C gives
//!    the contact force at O: friction F = m(θ̈ h/2 − G sin ψ) (along x), normal
//!    N = m(G cos ψ + θ̈ w/2). The corner sticks iff |F| ≤ N tan φ, which with t = tan δ,
//!    T = tan ψ reads
//!    tan φ ≥ f(ψ, δ) = [(4t² + 1)T + 3t] / [(t² + 4) + 3tT].
//!    At ψ = δ, f = tan ψ (the static boundary); for ψ > δ, tan δ < f < tan ψ: the block can
//!    topple without slipping even where ψ > φ, which is Yeung's correction. Hence
//!    **toppling** iff ψ > δ and tan φ ≥ f(ψ, δ).
//! 4. Otherwise, ψ > δ and δ ≤ φ < atan f: the corner slips while the block pivots on it
//!    (**sliding and toppling**). With only O in contact and Coulomb friction μN up-slope, the
//!    moment about C is N(μh − w)/2 clockwise, positive iff φ > δ, and
//!    θ̈ = 6 G cos ψ (μh − w) / (L² − 3w(μh − w)),  corner slip acceleration
//!    a_O = G sin ψ − μ(G cos ψ + θ̈ w/2) − θ̈ h/2,
//!    which vanishes exactly at φ = atan f (checked by a test below: the two derivations meet).
//!
//! # Classifying the simulation's first motion
//! Down-slope corner slip s (displacement of corner O along the slope) and rotation θ. Motion is
//! decided when max(|s|, L|θ|) first exceeds `DECIDE` = 1 mm (or at `T_MAX` = 0.4 s: then the
//! block must not have moved by `NOISE` anywhere). At that moment the block slides if
//! |s| > `NOISE` = 0.1 mm and topples if L|θ| > `NOISE`. Why these are safe: penalty-spring
//! deformations under the block's weight are ~1e-8 m, four orders below `NOISE`; in the
//! sliding-and-toppling cases the analytic onset accelerations give min/max of (a_O, L θ̈)
//! ≥ 0.3 for all generated cases (asserted), so the weaker component is ≥ 0.3 mm > `NOISE`;
//! every moving case reaches `DECIDE` in well under `T_MAX` (slowest onset 0.34 m/s² at a 2°
//! margin → 1 mm in < 0.1 s).
use crate::common;
use ashlar::analysis::reference::{first_motion_chart as chart, yeung_f, FirstMotion as Mode};
use ashlar::motion::{GroundMotion, Sampled, Signal};
use common::*;
use serde_json::json;

const DECIDE: f64 = 1.0e-3;
const NOISE: f64 = 1.0e-4;
const T_MAX: f64 = 0.4;
/// Block diagonal, m (w = L sin δ, h = L cos δ).
const L: f64 = 0.6;
/// Margin kept from every boundary, degrees.
const MARGIN: f64 = 2.0;

/// The mode if it is the same everywhere within ±`MARGIN` of (ψ, δ, φ) (checked on a 5×5×5
/// lattice; the boundaries are smooth and monotone, so this keeps the case ≥ 2° from them).
fn robust_mode(psi: f64, delta: f64, phi: f64) -> Option<Mode> {
    let m = MARGIN.to_radians();
    let mode = chart(psi, delta, phi);
    let steps = [-1.0, -0.5, 0.0, 0.5, 1.0];
    for a in steps {
        for b in steps {
            for c in steps {
                if chart(psi + a * m, delta + b * m, phi + c * m) != mode {
                    return None;
                }
            }
        }
    }
    Some(mode)
}

/// Onset accelerations (corner slip a_O in m/s², L·θ̈ in m/s²) of sliding and toppling.
fn sliding_toppling_onset(psi: f64, delta: f64, phi: f64, g_eff: f64) -> (f64, f64) {
    let (w, h, mu) = (L * delta.sin(), L * delta.cos(), phi.tan());
    let theta_dd = 6.0 * g_eff * psi.cos() * (mu * h - w) / (L * L - 3.0 * w * (mu * h - w));
    let n = g_eff * psi.cos() + theta_dd * w / 2.0;
    let a_o = g_eff * psi.sin() - mu * n - theta_dd * h / 2.0;
    (a_o, L * theta_dd)
}

#[derive(Debug, Clone, Copy)]
struct Case {
    alpha: f64,
    k: f64,
    delta: f64,
    phi: f64,
    expected: Mode,
}

impl Case {
    fn psi(&self) -> f64 {
        self.alpha + self.k.atan().to_degrees()
    }
}

/// SplitMix64: a fixed, dependency-free generator so the case list is the same on every run.
struct Rng(u64);
impl Rng {
    fn next(&mut self) -> f64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^= z >> 31;
        (z >> 11) as f64 / (1u64 << 53) as f64
    }
    fn uniform(&mut self, lo: f64, hi: f64) -> f64 {
        lo + (hi - lo) * self.next()
    }
}

/// `per_mode` cases of each mode: α ∈ [0°, 45°], k ∈ {0, 0.1, 0.2, 0.3, 0.5}, δ ∈ [6°, 60°],
/// φ ∈ [5°, 75°], ψ ≤ 70°, drawn at random (fixed seed) and kept only if ≥ 2° from boundaries.
fn cases(per_mode: usize) -> Vec<Case> {
    let mut rng = Rng(0x00A5_41A2);
    let mut out: Vec<Case> = Vec::new();
    let mut count = [0usize; 4];
    let ks = [0.0f64, 0.1, 0.2, 0.3, 0.5];
    while count.iter().any(|&c| c < per_mode) {
        let alpha = rng.uniform(0.0, 45.0);
        let k = ks[((rng.next() * ks.len() as f64) as usize).min(ks.len() - 1)];
        let delta = rng.uniform(6.0, 60.0);
        let phi = rng.uniform(5.0, 75.0);
        let psi = alpha + k.atan().to_degrees();
        if psi > 70.0 {
            continue;
        }
        let Some(mode) = robust_mode(psi.to_radians(), delta.to_radians(), phi.to_radians()) else {
            continue;
        };
        let slot = mode as usize;
        if count[slot] < per_mode {
            count[slot] += 1;
            out.push(Case {
                alpha,
                k,
                delta,
                phi,
                expected: mode,
            });
        }
    }
    out
}

/// The simulation's first motion: (mode, corner slip m, rotation rad, time s).
fn simulate(case: &Case) -> (Mode, f64, f64, f64) {
    let a = case.alpha.to_radians();
    let d = [a.cos(), -a.sin()];
    let n = [a.sin(), a.cos()];
    let delta = case.delta.to_radians();
    let (w, h) = (L * delta.sin(), L * delta.cos());
    let p = |s: f64, t: f64| json!([s * d[0] + t * n[0], s * d[1] + t * n[1]]);
    let blocks = json!([
        { "id": "slope", "material": "stone", "fixed": true,
          "vertices": [p(-1.5, 0.0), p(2.5, 0.0), p(2.5, -0.5), p(-1.5, -0.5)] },
        { "id": "block", "material": "stone", "block_model": "rigid",
          "vertices": [p(0.0, 0.0), p(w, 0.0), p(w, h), p(0.0, h)] },
    ]);
    let scene = parse(&scene_json(
        blocks,
        case.phi,
        json!({ "time_step": 1e-3, "duration": T_MAX }),
    ));
    // Constant horizontal ground acceleration −k·g for longer than the run (1 s).
    let motion = if case.k == 0.0 {
        GroundMotion::none()
    } else {
        GroundMotion::horizontal(Signal::Sampled(Sampled::new(0.01, vec![-case.k * G; 101])))
    };
    let mut s = sim(&scene, &motion);
    let corner0 = s.geoms()[1].vertices[1];
    let measure = |s: &ashlar::simulation::Simulation| {
        let c = s.geoms()[1].vertices[1] - corner0;
        (c.x * d[0] + c.y * d[1], s.geoms()[1].rotation)
    };
    run_until(&mut s, T_MAX, |s| {
        let (slip, rot) = measure(s);
        slip.abs().max(L * rot.abs()) > DECIDE
    });
    let (slip, rot) = measure(&s);
    let mode = match (slip.abs() > NOISE, L * rot.abs() > NOISE) {
        (false, false) => Mode::Stable,
        (true, false) => Mode::Sliding,
        (false, true) => Mode::Toppling,
        (true, true) => Mode::SlidingToppling,
    };
    (mode, slip, rot, s.time())
}

#[test]
fn reference_chart_derivations_agree_at_their_boundaries() {
    // Two independent derivations must meet: the stuck-corner toppling analysis (Yeung's f)
    // and the slipping-corner analysis (sliding and toppling). At tan φ = f the slipping
    // corner's acceleration vanishes; at φ = δ the rotation of the slipping block vanishes; at
    // ψ = δ Yeung's f equals tan ψ. Tolerance 1e-9 (round-off of a few operations).
    for psi_deg in [30.0, 45.0, 60.0, 70.0] {
        for delta_deg in [6.0, 15.0, 25.0] {
            let (psi, delta) = (f64::to_radians(psi_deg), f64::to_radians(delta_deg));
            let phi_y = yeung_f(psi, delta).atan();
            let (a_o, _) = sliding_toppling_onset(psi, delta, phi_y, G);
            assert!(
                a_o.abs() < 1e-9 * G,
                "ψ={psi_deg} δ={delta_deg}: a_O = {a_o} at Yeung's boundary"
            );
            let (_, l_theta) = sliding_toppling_onset(psi, delta, delta, G);
            assert!(l_theta.abs() < 1e-9 * G, "rotation at φ = δ: {l_theta}");
            assert!(
                phi_y > delta && phi_y < psi,
                "Yeung's boundary lies between δ and ψ"
            );
        }
        let t = f64::to_radians(psi_deg);
        assert!((yeung_f(t, t) - t.tan()).abs() < 1e-12);
    }
}

#[test]
fn first_motion_matches_the_chart_in_every_case() {
    let cases = cases(30);
    assert!(cases.len() >= 100);
    let mut wrong = Vec::new();
    let mut static_chart_differs = 0;
    for c in &cases {
        let (psi, delta, phi) = (
            c.psi().to_radians(),
            c.delta.to_radians(),
            c.phi.to_radians(),
        );
        if c.expected == Mode::SlidingToppling {
            let (a_o, l_theta) =
                sliding_toppling_onset(psi, delta, phi, G * (1.0 + c.k * c.k).sqrt());
            assert!(
                a_o > 0.0 && l_theta > 0.0,
                "{c:?}: inconsistent onset {a_o} {l_theta}"
            );
            assert!(
                a_o.min(l_theta) / a_o.max(l_theta) > 0.3,
                "{c:?}: one component too weak for the classifier"
            );
        }
        // For the record: how many cases the classic static chart (ψ vs φ, ψ vs δ) gets wrong.
        let classic = match (psi > phi, psi > delta) {
            (false, false) => Mode::Stable,
            (true, false) => Mode::Sliding,
            (false, true) => Mode::Toppling,
            (true, true) => Mode::SlidingToppling,
        };
        if classic != c.expected {
            static_chart_differs += 1;
        }
        let (got, slip, rot, t) = simulate(c);
        if got != c.expected {
            wrong.push(format!(
                "α={:.1}° k={:.1} (ψ={:.1}°) δ={:.1}° φ={:.1}°: expected {:?}, DDA {:?} (slip {:.2e} m, θ {:.2e} rad at t={:.3} s)",
                c.alpha,
                c.k,
                c.psi(),
                c.delta,
                c.phi,
                c.expected,
                got,
                slip,
                rot,
                t
            ));
        }
    }
    eprintln!(
        "{} cases ({} where the classic static chart would differ): {} agree, {} disagree",
        cases.len(),
        static_chart_differs,
        cases.len() - wrong.len(),
        wrong.len()
    );
    assert!(
        wrong.is_empty(),
        "first motion disagrees with the chart:\n{}",
        wrong.join("\n")
    );
}
