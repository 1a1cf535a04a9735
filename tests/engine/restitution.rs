//! Restitution the user controls (issue 20 §6, issue 25 "Impacts"): `control.restitution` a
//! number e makes every impact of the full engine obey Newton's law, whatever Δt and contact
//! solver; the default `"housner"` keeps Housner's rocking law in both models.
//!
//! References, each written here from first principles (no engine code):
//! - **Two-block collinear impact**: block A (1 m × 1 m) at v0 = 0.8 m/s strikes an equal block
//!   B at rest on a frictionless table. Newton's law with momentum conservation gives
//!   v_A = v0 (1 − e)/2, v_B = v0 (1 + e)/2.
//! - **Rocking impact**: a rigid rectangle (half-width b, half-height h, R² = b² + h²,
//!   I = m R²/3 about its centroid) rocking about one bottom corner lands on the other with
//!   angular velocity ω⁻. An impulse at the landing corner that stops its slip and leaves its
//!   normal velocity at −e times the approach, the old pivot free to lift, gives (impulse–momentum
//!   for the translation and the rotation, solved in the comment of `rocking_ratio`)
//!   ω⁺/ω⁻ = 1 − 3/2 (1 + e) sin²α, α = atan(b/h); e = 0 is Housner's 1 − 3/2 sin²α.
use crate::common;
use ashlar::motion::GroundMotion;
use ashlar::scene::Scene;
use common::*;
use serde_json::{json, Value};

const V0: f64 = 0.8;

/// Block A (1 m × 1 m) at `V0` towards block B (same) at rest 0.05 m away, both on a fixed
/// frictionless table; fixed Δt (not adaptive) so that Δt is the one under test.
fn two_blocks(restitution: Value, dt: f64, solver: &str) -> Scene {
    let blocks = json!([
        { "id": "table", "material": "stone", "fixed": true, "vertices": rect(-5.0, -1.0, 10.0, 0.0) },
        { "id": "A", "material": "stone", "vertices": rect(0.0, 0.0, 1.0, 1.0) },
        { "id": "B", "material": "stone", "vertices": rect(1.05, 0.0, 2.05, 1.0) },
    ]);
    let mut v = scene_json(
        blocks,
        0.0,
        json!({ "model": "dda", "time_step": dt, "adaptive_time_step": false,
                "max_displacement_ratio": 0.01, "contact_solver": solver, "duration": 0.5,
                "restitution": restitution }),
    );
    v["initial"] = json!([{ "block": "A", "velocity": [V0, 0.0] }]);
    parse(&v)
}

/// Velocities of A and B (m/s, along x) 0.5 s after A set off (the impact is at 0.0625 s), and
/// the worst relative drift of the momentum along x over the run.
fn two_block_velocities(restitution: Value, dt: f64, solver: &str) -> (f64, f64, f64) {
    let scene = two_blocks(restitution, dt, solver);
    let mut s = sim(&scene, &GroundMotion::none());
    let m = [
        0.0,
        2500.0 * s.geoms[1].moments.area,
        2500.0 * s.geoms[2].moments.area,
    ];
    let p0 = m[1] * V0;
    let mut drift: f64 = 0.0;
    run(&mut s, 0.5, |s| {
        let p = m[1] * s.block_velocity(1)[0] + m[2] * s.block_velocity(2)[0];
        drift = drift.max(((p - p0) / p0).abs());
    });
    (s.block_velocity(1)[0], s.block_velocity(2)[0], drift)
}

#[test]
fn measure_two_blocks() {
    for solver in ["penalty", "dual"] {
        for dt in [1e-4, 1e-3, 1e-2] {
            for r in [json!("housner"), json!(0.0), json!(0.5), json!(1.0)] {
                let (va, vb, d) = two_block_velocities(r.clone(), dt, solver);
                eprintln!(
                    "{solver} dt={dt} r={r}: vA={va:.6} vB={vb:.6} e={:.6} drift={d:.2e}",
                    (vb - va) / V0
                );
            }
        }
    }
}

/// A rigid column of half-width b, half-height h on a fixed base (φ = 75°: its corners never
/// slip, tan 75° = 3.7 ≫ the friction demand of a rocking impact), tilted by θ0 about its
/// bottom-right corner, released from rest.
fn column(b: f64, h: f64, theta0: f64, control: Value) -> Scene {
    let (co, si) = (theta0.cos(), theta0.sin());
    let rot = |x: f64, y: f64| {
        let dx = x - b;
        [b + co * dx + si * y, -si * dx + co * y]
    };
    let v = [rot(-b, 0.0), rot(b, 0.0), rot(b, 2.0 * h), rot(-b, 2.0 * h)];
    let blocks = json!([
        { "id": "base", "material": "stone", "fixed": true, "vertices": rect(-2.0, -0.5, 2.0, 0.0) },
        { "id": "column", "material": "stone", "block_model": "rigid", "vertices": v },
    ]);
    parse(&scene_json(blocks, 75.0, control))
}

/// The column's angular velocity just before and just after its first impact (rad/s). Before:
/// at the start of the step whose impact law fired (the velocity the impulse acts on). After:
/// at the end of that step, less the change over the next step (the gravity torque's share
/// within the step, extrapolated linearly: error O(θ⃛ Δt²), below 1e-6 of ω here).
fn engine_rocking_ratio(b: f64, h: f64, control: Value) -> (f64, f64) {
    let theta0 = 0.5 * (b / h).atan();
    let scene = column(b, h, theta0, control);
    let mut s = sim(&scene, &GroundMotion::none());
    let mut before = None;
    let mut history = Vec::new();
    while s.time < 2.0 && history.len() < 2 {
        let w0 = s.block_velocity(1)[2];
        let n0 = s.stats.impacts;
        s.step(f64::INFINITY).expect("step");
        if before.is_some() {
            history.push(s.block_velocity(1)[2]);
        } else if s.stats.impacts > n0 {
            before = Some(w0);
            history.push(s.block_velocity(1)[2]);
        }
    }
    let before = before.expect("no impact within 2 s");
    let after = 2.0 * history[0] - history[1];
    (before, after)
}

#[test]
fn measure_rocking() {
    for hb in [3.0, 5.0] {
        let (b, h): (f64, f64) = (0.2, 0.2 * hb);
        let sa2 = (b / h).atan().sin().powi(2);
        for solver in ["penalty", "dual"] {
            for dt in [None, Some(1e-4)] {
                for e in [0.0, 0.5] {
                    let mut c = json!({ "model": "dda", "duration": 3.0, "contact_solver": solver, "restitution": e });
                    if let Some(dt) = dt {
                        c["time_step"] = json!(dt);
                    }
                    let (w0, w1) = engine_rocking_ratio(b, h, c);
                    let r = w1 / w0;
                    let rref = 1.0 - 1.5 * (1.0 + e) * sa2;
                    eprintln!("h/b={hb} {solver} dt={dt:?} e={e}: w-={w0:.5} w+={w1:.5} r={r:.5} ref={rref:.5} err={:+.3}%", 100.0*(r/rref-1.0));
                }
            }
        }
    }
}
