//! A sliding stack of two squat blocks: rigid-plastic Newmark for the whole stack, no internal
//! slip.
use super::*;

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
    let blocks = ashlar::presets::Stack {
        half_width: 0.5,
        lower_height: 0.3,
        upper_height: 0.3,
        base_half_width: 10.0,
        base_depth: 0.5,
    }
    .blocks("stone", "rigid");
    let v = json!({
        "format": "ashlar.scene/1",
        "gravity": G,
        "materials": { "stone": { "density": 2500.0, "young_modulus": 2.0e10, "poisson_ratio": 0.2 } },
        "joints": { "bed": { "friction_angle": 20.0 }, "inner": { "friction_angle": 45.0 } },
        "interfaces": { "default": "inner", "pairs": [ { "blocks": ["base", "lower"], "joint": "bed" } ] },
        "blocks": blocks,
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
