//! Two-block stacked column (Psycharis 1990): a lower block (half-sizes b × h1) carrying an
//! upper block of the same width (b × h2) on a fixed base, under a sine pulse. The stack
//! starts to rock as one body on a base corner; when the resultant of the bed joint reaches
//! one of its ends the joint opens and the upper block rocks on the lower one: two degrees of
//! freedom (θ1, θ2), in one of Psycharis's four modes (the signs of θ1 and θ2 − θ1 pick the
//! pivots). Reference written here: the equations of motion of each mode (Lagrange, derived in
//! `both`), RK4 at 1e-5 s, the joint-opening condition checked every step, up to the first
//! impact (either contact closing again), so no impact law enters. The engine
//! (`"model": "dda"`, rigid blocks, default numerical controls, penalty and dual) is compared
//! with it on both rotations until 0.01 s before that impact.
//!
//! Tolerance: 2 % of the peak rotation, as for the single column up to its first impact
//! (`tests/engine/rocking.rs`): the same physics with one more joint. Regression bound: 5× measured
//! where that is tighter (numbers beside the tests).
//!
//! Not represented by the reference (and not met in these cases, where the engine agrees to
//! 0.6 %): the upper block tipping before the stack (asserted absent), sliding (φ = 75°), and
//! loss of contact at a pivot in the two-degree-of-freedom mode (unchecked).
use crate::common;
use ashlar::motion::{GroundMotion, Signal};
use common::*;
use nalgebra::{Matrix2, Vector2};
use serde_json::json;

type V = Vector2<f64>;

fn rot(v: V, th: f64) -> V {
    let (s, c) = th.sin_cos();
    V::new(c * v.x - s * v.y, s * v.x + c * v.y)
}
/// ẑ × v.
fn perp(v: V) -> V {
    V::new(-v.y, v.x)
}
fn cross(a: V, b: V) -> f64 {
    a.x * b.y - a.y * b.x
}

/// The stack (half-width b, half-heights h1 below and h2 above), unit density and thickness.
#[derive(Clone, Copy, Debug)]
struct Stack {
    b: f64,
    h1: f64,
    h2: f64,
}

impl Stack {
    fn m1(&self) -> f64 {
        4.0 * self.b * self.h1
    }
    fn m2(&self) -> f64 {
        4.0 * self.b * self.h2
    }
    fn i1(&self) -> f64 {
        self.m1() * (self.b * self.b + self.h1 * self.h1) / 3.0
    }
    fn i2(&self) -> f64 {
        self.m2() * (self.b * self.b + self.h2 * self.h2) / 3.0
    }
    fn c1(&self) -> V {
        V::new(0.0, self.h1)
    }
    fn c2(&self) -> V {
        V::new(0.0, 2.0 * self.h1 + self.h2)
    }
    /// Base pivot for θ1 of sign s1 (+1: left corner).
    fn p1(&self, s1: f64) -> V {
        V::new(-s1 * self.b, 0.0)
    }
    /// Joint pivot (on the lower block's top) for θ2 − θ1 of sign s2, at rest.
    fn p2(&self, s2: f64) -> V {
        V::new(-s2 * self.b, 2.0 * self.h1)
    }
}

/// The motion's state: at rest; rocking as one body on base corner s1; both blocks rocking
/// (base corner s1, joint corner s2).
#[derive(Clone, Copy, Debug, PartialEq)]
enum Mode {
    Rest,
    Whole { s1: f64 },
    Both { s1: f64, s2: f64 },
}

/// Load per unit mass: gravity and the inertial load of the ground acceleration (m/s²).
fn load(ag: f64) -> V {
    V::new(-ag, -G)
}

/// θ̈ of the stack rocking as one body on base corner s1 at θ.
fn whole_acc(st: &Stack, s1: f64, th: f64, ag: f64) -> f64 {
    let p = st.p1(s1);
    let (r1, r2) = (st.c1() - p, st.c2() - p);
    let ip = st.i1() + st.m1() * r1.norm_squared() + st.i2() + st.m2() * r2.norm_squared();
    let l = load(ag);
    (st.m1() * cross(rot(r1, th), l) + st.m2() * cross(rot(r2, th), l)) / ip
}

/// Where the bed joint's resultant acts while the stack rocks as one body (θ, ω, θ̈): the
/// coordinate x along the joint from its centre (m, +x along the lower block's top face), and
/// the normal force (N per unit density; > 0 compressive). The joint stays closed while
/// |x| < b and the normal force is positive.
fn joint_resultant(st: &Stack, s1: f64, th: f64, w: f64, acc: f64, ag: f64) -> (f64, f64) {
    let p = st.p1(s1);
    let r2 = rot(st.c2() - p, th);
    let c2 = p + r2;
    let a2 = perp(r2) * acc - r2 * (w * w);
    // Force of the lower block on the upper one, and the moment it must have about c2.
    let f = (a2 - load(ag)) * st.m2();
    let mc = st.i2() * acc;
    let j0 = p + rot(V::new(0.0, 2.0 * st.h1) - p, th);
    let e = rot(V::new(1.0, 0.0), th);
    let normal = cross(e, f);
    ((mc - cross(j0 - c2, f)) / normal, normal)
}

/// (θ̈1, θ̈2) with both blocks rocking, by d'Alembert's principle in the coordinates
/// (θ1, θ2) (θ2 absolute): with A = ẑ×R(θ1)r1, D = ẑ×R(θ1)d, E = ẑ×R(θ2)r2 (r1: base pivot →
/// c1, d: base pivot → joint pivot, r2: joint pivot → c2),
/// [m1|A|² + I1 + m2|D|², m2 D·E; m2 D·E, m2|E|² + I2] θ̈ =
/// [m1 L·A + m2 L·D + m2 θ̇2² D·R(θ2)r2; m2 L·E + m2 θ̇1² E·R(θ1)d].
fn both_acc(st: &Stack, s1: f64, s2: f64, th1: f64, th2: f64, w1: f64, w2: f64, ag: f64) -> V {
    let p1 = st.p1(s1);
    let p2 = st.p2(s2);
    let (r1, d, r2) = (
        rot(st.c1() - p1, th1),
        rot(p2 - p1, th1),
        rot(st.c2() - p2, th2),
    );
    let (a, dd, e) = (perp(r1), perp(d), perp(r2));
    let (m1, m2) = (st.m1(), st.m2());
    let l = load(ag);
    let m = Matrix2::new(
        m1 * a.norm_squared() + st.i1() + m2 * dd.norm_squared(),
        m2 * dd.dot(&e),
        m2 * dd.dot(&e),
        m2 * e.norm_squared() + st.i2(),
    );
    let q = V::new(
        m1 * l.dot(&a) + m2 * l.dot(&dd) + m2 * w2 * w2 * dd.dot(&r2),
        m2 * l.dot(&e) + m2 * w1 * w1 * e.dot(&d),
    );
    m.lu().solve(&q).expect("mass matrix is positive definite")
}

/// Energy of the stack in the `Both` mode under gravity alone (per unit density).
fn both_energy(st: &Stack, s1: f64, s2: f64, y: [f64; 4]) -> f64 {
    let [th1, th2, w1, w2] = y;
    let p1 = st.p1(s1);
    let p2 = st.p2(s2);
    let (r1, d, r2) = (
        rot(st.c1() - p1, th1),
        rot(p2 - p1, th1),
        rot(st.c2() - p2, th2),
    );
    let v1 = perp(r1) * w1;
    let v2 = perp(d) * w1 + perp(r2) * w2;
    let y1 = (p1 + r1).y;
    let y2 = (p1 + d + r2).y;
    0.5 * (st.m1() * v1.norm_squared() + st.i1() * w1 * w1)
        + 0.5 * (st.m2() * v2.norm_squared() + st.i2() * w2 * w2)
        + G * (st.m1() * y1 + st.m2() * y2)
}

struct Reference {
    /// (t, θ1, θ2) every step.
    samples: Vec<(f64, f64, f64)>,
    /// When the joint opened, and on which corner.
    opened: Option<(f64, f64)>,
    /// First impact (a contact closing again), s.
    impact: Option<f64>,
}

const REF_DT: f64 = 1e-5;

/// The reference from rest under `ag` up to the first impact or `t_end`.
fn reference(st: &Stack, ag: &impl Fn(f64) -> f64, t_end: f64) -> Reference {
    let h = REF_DT;
    let mut out = Reference {
        samples: vec![(0.0, 0.0, 0.0)],
        opened: None,
        impact: None,
    };
    let mut mode = Mode::Rest;
    let mut y = [0.0f64; 4]; // θ1, θ2, ω1, ω2
    let mut t = 0.0;
    while t < t_end - 1e-12 {
        let f = |mode: Mode, t: f64, y: [f64; 4]| -> [f64; 4] {
            match mode {
                Mode::Rest => [0.0; 4],
                Mode::Whole { s1 } => {
                    let a = whole_acc(st, s1, y[0], ag(t));
                    [y[2], y[2], a, a]
                }
                Mode::Both { s1, s2 } => {
                    let a = both_acc(st, s1, s2, y[0], y[1], y[2], y[3], ag(t));
                    [y[2], y[3], a.x, a.y]
                }
            }
        };
        if mode == Mode::Rest {
            let a = ag(t + h);
            let s1 = a.signum();
            if a != 0.0 && s1 * whole_acc(st, s1, 0.0, a) > 0.0 {
                let (x, n) = joint_resultant(st, s1, 0.0, 0.0, 0.0, a);
                assert!(
                    x.abs() < st.b && n > 0.0,
                    "the upper block would tip before the stack: not this reference's case"
                );
                mode = Mode::Whole { s1 };
            }
            t += h;
            out.samples.push((t, 0.0, 0.0));
            continue;
        }
        let k1 = f(mode, t, y);
        let add = |y: [f64; 4], k: [f64; 4], c: f64| {
            [
                y[0] + c * k[0],
                y[1] + c * k[1],
                y[2] + c * k[2],
                y[3] + c * k[3],
            ]
        };
        let k2 = f(mode, t + 0.5 * h, add(y, k1, 0.5 * h));
        let k3 = f(mode, t + 0.5 * h, add(y, k2, 0.5 * h));
        let k4 = f(mode, t + h, add(y, k3, h));
        for i in 0..4 {
            y[i] += h / 6.0 * (k1[i] + 2.0 * k2[i] + 2.0 * k3[i] + k4[i]);
        }
        t += h;
        out.samples.push((t, y[0], y[1]));
        match mode {
            Mode::Whole { s1 } => {
                if s1 * y[0] < 0.0 {
                    out.impact = Some(t);
                    break;
                }
                let acc = whole_acc(st, s1, y[0], ag(t));
                let (x, n) = joint_resultant(st, s1, y[0], y[2], acc, ag(t));
                assert!(n > 0.0, "the upper block would jump at {t}");
                if x.abs() >= st.b {
                    let s2 = -x.signum();
                    out.opened = Some((t, s2));
                    mode = Mode::Both { s1, s2 };
                }
            }
            Mode::Both { s1, s2 } => {
                if s1 * y[0] < 0.0 || s2 * (y[1] - y[0]) < 0.0 {
                    out.impact = Some(t);
                    break;
                }
            }
            Mode::Rest => {}
        }
        if y[0].abs() > 1.0 || y[1].abs() > 1.0 {
            break;
        }
    }
    out
}

fn sine_pulse(a: f64, f: f64) -> (impl Fn(f64) -> f64, GroundMotion) {
    let period = 1.0 / f;
    (
        move |t: f64| {
            if (0.0..=period).contains(&t) {
                a * (2.0 * std::f64::consts::PI * f * t).sin()
            } else {
                0.0
            }
        },
        GroundMotion::horizontal(Signal::Pulse {
            amplitude: a,
            period,
            cycles: 1.0,
            phase: 0.0,
        }),
    )
}

/// Checks of the reference itself. (1) With equal blocks rocking as one, θ̈ is Housner's for
/// the monolithic column, −p² [sin(α − θ) − (a_g/g) cos(α − θ)] (to round-off). (2) In the
/// two-degree-of-freedom mode under gravity alone, the energy is conserved by the RK4
/// integration (1e-9 relative over 0.3 s), so the mass matrix and the velocity terms are
/// consistent with the energy written independently in `both_energy`.
#[test]
fn reference_checks() {
    let st = Stack {
        b: 0.2,
        h1: 0.3,
        h2: 0.3,
    };
    let (r, alpha) = (0.2f64.hypot(0.6), (0.2f64 / 0.6).atan());
    let p2 = 3.0 * G / (4.0 * r);
    for (th, ag) in [(0.05, 3.0), (0.2, -4.0), (0.01, 0.0)] {
        let housner = -p2 * ((alpha - th).sin() - ag / G * (alpha - th).cos());
        let acc = whole_acc(&st, 1.0, th, ag);
        assert!(
            (acc - housner).abs() < 1e-12 * housner.abs(),
            "{acc} {housner}"
        );
    }
    let st = Stack {
        b: 0.2,
        h1: 0.2,
        h2: 0.4,
    };
    let (s1, s2) = (1.0, 1.0);
    let mut y = [0.05f64, 0.12, 0.3, -0.2];
    let e0 = both_energy(&st, s1, s2, y);
    let h = REF_DT;
    let f = |y: [f64; 4]| {
        let a = both_acc(&st, s1, s2, y[0], y[1], y[2], y[3], 0.0);
        [y[2], y[3], a.x, a.y]
    };
    let add = |y: [f64; 4], k: [f64; 4], c: f64| {
        [
            y[0] + c * k[0],
            y[1] + c * k[1],
            y[2] + c * k[2],
            y[3] + c * k[3],
        ]
    };
    for _ in 0..30000 {
        let k1 = f(y);
        let k2 = f(add(y, k1, 0.5 * h));
        let k3 = f(add(y, k2, 0.5 * h));
        let k4 = f(add(y, k3, h));
        for i in 0..4 {
            y[i] += h / 6.0 * (k1[i] + 2.0 * k2[i] + 2.0 * k3[i] + k4[i]);
        }
    }
    let e1 = both_energy(&st, s1, s2, y);
    eprintln!(
        "energy drift over 0.3 s: {:.1e} (state {y:?})",
        (e1 - e0) / e0
    );
    assert!(((e1 - e0) / e0).abs() < 1e-9);
    // The motion was a real two-degree-of-freedom one.
    assert!((y[1] - y[0] - 0.07).abs() > 1e-3);
}

fn stack_scene(st: &Stack, solver: &str, duration: f64) -> ashlar::scene::Scene {
    let blocks = ashlar::presets::Stack {
        half_width: st.b,
        lower_height: 2.0 * st.h1,
        upper_height: 2.0 * st.h2,
        base_half_width: 2.0,
        base_depth: 0.5,
    }
    .blocks("stone", "rigid");
    // φ = 75°: no joint slips (the reference has no sliding).
    parse(&scene_json(
        blocks,
        75.0,
        json!({ "model": "dda", "duration": duration, "contact_solver": solver }),
    ))
}

/// The engine against the reference up to 0.01 s before the first impact; returns the error
/// relative to the peak rotation.
fn check(st: Stack, a: f64, f: f64, solver: &str, expect_opening: bool, regression: f64) {
    let (ag, motion) = sine_pulse(a, f);
    let r = reference(&st, &ag, 3.0);
    let impact = r.impact.expect("the reference lands within 3 s");
    assert_eq!(r.opened.is_some(), expect_opening, "{:?}", r.opened);
    let peak = r
        .samples
        .iter()
        .fold(0.0f64, |m, p| m.max(p.1.abs()).max(p.2.abs()));
    let scene = stack_scene(&st, solver, impact);
    let mut s = sim(&scene, &motion);
    let (mut worst, mut worst_rel): (f64, f64) = (0.0, 0.0);
    let mut engine_opened = None;
    run(&mut s, impact - 0.01, |s| {
        let k = ((s.time() / REF_DT).round() as usize).min(r.samples.len() - 1);
        let (t1, t2) = (s.geoms()[1].rotation, s.geoms()[2].rotation);
        worst = worst
            .max((t1 - r.samples[k].1).abs())
            .max((t2 - r.samples[k].2).abs());
        // The relative rotation of the upper block (the joint's opening), the quantity the
        // monolithic model would get wrong.
        worst_rel = worst_rel.max(((t2 - t1) - (r.samples[k].2 - r.samples[k].1)).abs());
        if engine_opened.is_none() && (t2 - t1).abs() > 1e-3 {
            engine_opened = Some(s.time());
        }
    });
    let rel_peak = r
        .samples
        .iter()
        .fold(0.0f64, |m, p| m.max((p.2 - p.1).abs()));
    eprintln!(
        "stack h1 = {}, h2 = {}, {a} m/s² at {f} Hz, {solver}: joint opens at {:?} (engine: relative rotation 1e-3 rad at {engine_opened:?}), first impact {impact:.4} s; peak θ {peak:.4} rad, peak θ2 − θ1 {rel_peak:.4} rad; worst |Δθ| {worst:.2e} rad ({:.3} % of peak), worst |Δ(θ2 − θ1)| {worst_rel:.2e} rad",
        st.h1,
        st.h2,
        r.opened,
        100.0 * worst / peak
    );
    assert_eq!(
        engine_opened.is_some(),
        expect_opening,
        "{solver}: the engine's joint opening"
    );
    assert!(
        worst < 0.02 * peak,
        "{solver}: {worst} rad against peak {peak}"
    );
    assert!(
        worst < regression * peak,
        "{solver}: {:.3} % of peak beyond the regression bound {:.3} %",
        100.0 * worst / peak,
        100.0 * regression
    );
}

// Measured worst |Δθ| / peak: equal blocks (penalty) 0.576 %; tall top block 2 Hz penalty
// 0.210 %, dual 0.254 %; 4 Hz penalty 0.505 %, dual 0.507 %. Regression bounds 5× those where
// that is below the 2 % tolerance (2 Hz: 1.05 %, 1.3 %), otherwise the tolerance binds.

const EQUAL: Stack = Stack {
    b: 0.2,
    h1: 0.3,
    h2: 0.3,
};
const TALL_TOP: Stack = Stack {
    b: 0.2,
    h1: 0.2,
    h2: 0.4,
};

#[test]
fn equal_blocks_rock_as_one_penalty() {
    check(EQUAL, 10.0, 2.0, "penalty", false, 0.02);
}

#[test]
fn joint_opens_two_hertz_penalty() {
    check(TALL_TOP, 14.0, 2.0, "penalty", true, 0.0105);
}

#[test]
fn joint_opens_two_hertz_dual() {
    check(TALL_TOP, 14.0, 2.0, "dual", true, 0.013);
}

#[test]
fn joint_opens_four_hertz_penalty() {
    check(TALL_TOP, 20.0, 4.0, "penalty", true, 0.02);
}

#[test]
fn joint_opens_four_hertz_dual() {
    check(TALL_TOP, 20.0, 4.0, "dual", true, 0.02);
}
