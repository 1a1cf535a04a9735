//! Restitution the user controls (docs/restitution.md): `control.restitution` a
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
use ashlar::analysis::run::{run as run_scene, RunOptions};
use ashlar::motion::GroundMotion;
use ashlar::scene::Scene;
use common::*;
use serde_json::{json, Value};
use std::sync::Mutex;

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
        2500.0 * s.geoms()[1].moments.area,
        2500.0 * s.geoms()[2].moments.area,
    ];
    let p0 = m[1] * V0;
    let mut drift: f64 = 0.0;
    run(&mut s, 0.5, |s| {
        let p = m[1] * s.block_velocity(1)[0] + m[2] * s.block_velocity(2)[0];
        drift = drift.max(((p - p0) / p0).abs());
    });
    (s.block_velocity(1)[0], s.block_velocity(2)[0], drift)
}

/// A rigid column of half-width b, half-height h on a fixed base (φ = 75°: its corners never
/// slip, tan 75° = 3.7 ≫ the friction demand of a rocking impact), tilted by θ0 about its
/// bottom-right corner, released from rest.
fn column(b: f64, h: f64, theta0: f64, control: Value) -> Scene {
    parse(&tilted_column(b, h, theta0, "rigid", control))
}

/// The column's angular velocity just before and just after its first impact (rad/s). Before:
/// at the start of the step whose impact law fired (the velocity the impulse acts on). After:
/// at the end of that step, less the change over the next step (the gravity torque's share
/// within the step, extrapolated linearly: error O(θ⃛ Δt²), below 1e-6 of ω here).
fn engine_rocking_ratio(b: f64, h: f64, control: Value) -> (f64, f64) {
    let theta0 = 0.5 * (b / h).atan();
    let scene = column(b, h, theta0, control);
    let mut s = sim(&scene, &GroundMotion::none());
    first_impact_angular_velocities(&mut s, 1)
}

/// Tolerance 1e-4 × v0 on both velocities: Newton's law is applied exactly (to 1e-12) to the
/// rigid-body unknowns; what remains is the blocks' own elastic response over the following
/// steps, measured at most 3e-5 × v0 (Δt = 1e-2 s; below 1e-6 × v0 at 1e-3 and 1e-4 s). The
/// momentum along x is conserved to round-off (1e-9: the impulses act equal and opposite and
/// the table is frictionless). Before this law the default engine gave e = 0.537, 0.105 and
/// 0.499 at Δt = 1e-4, 1e-3, 1e-2 s (penalty; dual 0.547, 0.101, 0.499).
fn check_two_blocks(solver: &str) {
    for dt in [1e-4, 1e-3, 1e-2] {
        for e in [0.0, 0.5, 1.0] {
            let (va, vb, drift) = two_block_velocities(json!(e), dt, solver);
            let (ea, eb) = (V0 * (1.0 - e) / 2.0, V0 * (1.0 + e) / 2.0);
            eprintln!(
                "{solver} Δt = {dt:e} s, e = {e}: v_A = {va:.7} (Newton {ea}), v_B = {vb:.7} (Newton {eb}) m/s, momentum drift {drift:.1e}"
            );
            assert!(
                (va - ea).abs() <= 1e-4 * V0,
                "{solver} Δt {dt} e {e}: v_A {va} against {ea}"
            );
            assert!(
                (vb - eb).abs() <= 1e-4 * V0,
                "{solver} Δt {dt} e {e}: v_B {vb} against {eb}"
            );
            assert!(
                drift < 1e-9,
                "{solver} Δt {dt} e {e}: momentum drift {drift}"
            );
        }
    }
}

#[test]
fn two_block_impact_obeys_newton_at_every_time_step_penalty() {
    check_two_blocks("penalty");
}

#[test]
fn two_block_impact_obeys_newton_at_every_time_step_dual() {
    check_two_blocks("dual");
}

/// Newton's law at a rectangle's landing corner, solved here: with the centroid velocity v and
/// angular velocity ω, the landing corner at r = (b, −h) from the centroid (rocking on the
/// corner at (−b, −h), ω⁻ < 0 as the corner comes down; here mirrored), an impulse P at it
/// gives m Δv = P, I Δω = r × P; no slip (v_corner,x⁺ = 0) and v_corner,y⁺ = −e v_corner,y⁻ with
/// v_corner,y⁻ = 2bω⁻ give (4R²/3) ω⁺ = (R²/3 + h² − b² − 2eb²) ω⁻, i.e.
/// ω⁺/ω⁻ = 1 − 3/2 (1 + e) sin²α.
fn newton_rocking_ratio(b: f64, h: f64, e: f64) -> f64 {
    let r2 = b * b + h * h;
    (r2 / 3.0 + h * h - b * b - 2.0 * e * b * b) / (4.0 * r2 / 3.0)
}

/// The formula above is the published Housner law at e = 0 (a check of the derivation, not of
/// the engine).
#[test]
fn newton_rocking_ratio_is_housners_law_at_zero() {
    for hb in [2.0, 3.0, 5.0] {
        let (b, h): (f64, f64) = (0.2, 0.2 * hb);
        let housner = 1.0 - 1.5 * (b / h).atan().sin().powi(2);
        assert!((newton_rocking_ratio(b, h, 0.0) - housner).abs() < 1e-14);
        let sa2 = (b / h).atan().sin().powi(2);
        assert!((newton_rocking_ratio(b, h, 0.7) - (1.0 - 1.5 * 1.7 * sa2)).abs() < 1e-14);
    }
}

/// Tolerance 0.1 % on ω⁺/ω⁻: the impulse is exact; what is left is the measurement's
/// extrapolation over one step and the Newmark velocity of the steps around the impact (the
/// pivot's gap closed within a step turns into a velocity 2 g0/Δt): measured ≤ 0.044 % (h/b = 3
/// and 5, e = 0 and 0.5, penalty and dual, Δt = 1 ms default and 1e-4 s; largest dual h/b = 3
/// e = 0.5 at 1 ms). Before the step before an impact was split (`located_step`), a 0.43 Δt
/// step left the pivot approaching at 1e-3 m/s: −0.125 % (dual). Before this law the engine's
/// own impacts at the default Δt were 0.5–0.7 % off Housner's at h/b = 3–6 and 4–5 % at h/b = 2
/// (tests/engine/rocking_impacts.rs). h/b = 2: see `rocking_impact_ratio_stocky_column`.
fn check_rocking(solver: &str) {
    for hb in [3.0, 5.0] {
        let (b, h): (f64, f64) = (0.2, 0.2 * hb);
        for dt in [None, Some(1e-4)] {
            for e in [0.0, 0.5] {
                let mut c = json!({ "model": "dda", "duration": 2.0, "contact_solver": solver,
                                    "restitution": e });
                if let Some(dt) = dt {
                    c["time_step"] = json!(dt);
                }
                let (w0, w1) = engine_rocking_ratio(b, h, c);
                let (r, expect) = (w1 / w0, newton_rocking_ratio(b, h, e));
                eprintln!(
                    "{solver} h/b = {hb}, Δt = {dt:?}, e = {e}: ω⁻ = {w0:.5}, ω⁺ = {w1:.5} rad/s, ratio {r:.5} against {expect:.5} ({:+.4} %)",
                    100.0 * (r / expect - 1.0)
                );
                assert!(
                    (r / expect - 1.0).abs() < 1e-3,
                    "{solver} h/b {hb} e {e}: {r} against {expect}"
                );
            }
        }
    }
}

#[test]
fn rocking_impact_ratio_follows_the_requested_restitution_penalty() {
    check_rocking("penalty");
}

#[test]
fn rocking_impact_ratio_follows_the_requested_restitution_dual() {
    check_rocking("dual");
}

/// The reduced rocking model's ratio across its first impact, read from its frames (1e-4 s
/// apart) extrapolated linearly to the impact instant from either side, under a half-sine
/// pulse 1.5 × the uplift acceleration g tan α (1 Hz, half a cycle).
fn reduced_rocking_ratio(b: f64, h: f64, control: Value) -> (f64, String) {
    let column = Column {
        half_width: b,
        half_height: h,
        base_half_width: 2.0,
        ..Column::SEED
    };
    let scene = parse(&column.json(control));
    let pulse = rocking_pulse(1.5 * G * b / h);
    let frames = Mutex::new(Vec::new());
    let on_frame = |f: &ashlar::record::Frame| {
        let c = &f.blocks[1];
        frames
            .lock()
            .expect("frames")
            .push((f.time, c.rotation, c.angular_velocity))
    };
    let opts = RunOptions {
        on_frame: Some(&on_frame),
        ..Default::default()
    };
    let outcome = run_scene(&scene, &pulse, &opts).expect("reduced run");
    let f = frames.into_inner().expect("frames");
    let k = (1..f.len())
        .find(|&k| f[k - 1].1 != 0.0 && f[k - 1].1.signum() != f[k].1.signum() && f[k].1 != 0.0)
        .expect("an impact");
    assert!(k >= 2 && k + 1 < f.len());
    // Impact instant by linear interpolation of θ between the frames around it.
    let (t0, th0, _) = f[k - 1];
    let (t1, th1, _) = f[k];
    let t = t0 + (t1 - t0) * th0 / (th0 - th1);
    let before = f[k - 1].2 + (f[k - 1].2 - f[k - 2].2) / (t0 - f[k - 2].0) * (t - t0);
    let after = f[k].2 - (f[k + 1].2 - f[k].2) / (f[k + 1].0 - t1) * (t1 - t);
    (after / before, outcome.summary.model.clone())
}

/// The reduced model by default and with `"restitution": 0` follows Housner's law, the engine
/// with 0 follows it too (above); tolerance 0.1 % as for the engine: the reduced model's
/// impact is exact, the frames' linear extrapolation over 1e-4 s leaves ≈ θ⃛Δt² ≪ 1e-4.
#[test]
fn reduced_rocking_model_follows_housner_by_default_and_at_zero() {
    for hb in [3.0, 5.0] {
        let (b, h): (f64, f64) = (0.2, 0.2 * hb);
        let housner = 1.0 - 1.5 * (b / h).atan().sin().powi(2);
        for restitution in [None, Some(json!("housner")), Some(json!(0.0))] {
            let mut c = json!({ "model": "rocking", "duration": 1.5, "output_interval": 1e-4 });
            if let Some(r) = &restitution {
                c["restitution"] = r.clone();
            }
            let (r, model) = reduced_rocking_ratio(b, h, c);
            eprintln!(
                "reduced h/b = {hb}, restitution {restitution:?}: ratio {r:.6} against Housner {housner:.6} ({:+.4} %)",
                100.0 * (r / housner - 1.0)
            );
            assert_eq!(model, "rocking");
            assert!(
                (r / housner - 1.0).abs() < 1e-3,
                "h/b {hb}: {r} against {housner}"
            );
        }
    }
}

/// A coefficient above 0 makes the landing corner bounce, which the reduced model does not
/// represent: `auto` runs the full engine and says why; `"rocking"` is refused with the reason.
#[test]
fn restitution_above_zero_sends_auto_to_the_engine() {
    let (b, h) = (0.2, 0.6);
    let (ratio, model) = reduced_rocking_ratio(
        b,
        h,
        json!({ "model": "auto", "duration": 1.5, "output_interval": 1e-4, "restitution": 0.5 }),
    );
    assert_eq!(model, "dda");
    // The engine's first impact under the pulse: the same law as from a release at rest.
    let expect = newton_rocking_ratio(b, h, 0.5);
    eprintln!("auto with e = 0.5: the engine ran, ratio {ratio:.5} against Newton {expect:.5}");
    let blocks = json!([
        { "id": "base", "material": "stone", "fixed": true, "vertices": rect(-2.0, -0.5, 2.0, 0.0) },
        { "id": "column", "material": "stone", "block_model": "rigid", "vertices": rect(-b, 0.0, b, 2.0 * h) },
    ]);
    let forced = parse(&scene_json(
        blocks,
        75.0,
        json!({ "model": "rocking", "duration": 1.0, "restitution": 0.5 }),
    ));
    let err = run_scene(&forced, &GroundMotion::none(), &RunOptions::default())
        .expect_err("a forced rocking model must refuse e = 0.5");
    let text = err.to_string();
    assert!(text.contains("control.restitution"), "{text}");
}

/// The stocky column (h/b = 2, Δt = 1 ms, e = 0), tolerance 0.1 % as in `check_rocking`:
/// measured +0.0046 % (penalty) and +0.0091 % (dual). Before the located impact's step was
/// split (`assembly::restitution::located_step`) and the landing corner's hover closed within
/// the next step, the dual solver gave +0.14 %; before the corner was found before it lands,
/// ratio 0.021 (found 85 µm deep, the contact threw the column off).
#[test]
fn rocking_impact_ratio_stocky_column() {
    for solver in ["penalty", "dual"] {
        let c = json!({ "model": "dda", "duration": 2.0, "contact_solver": solver, "restitution": 0.0 });
        let (w0, w1) = engine_rocking_ratio(0.2, 0.4, c);
        let expect = newton_rocking_ratio(0.2, 0.4, 0.0);
        assert!(
            (w1 / w0 / expect - 1.0).abs() < 1e-3,
            "{solver}: {} against {expect}",
            w1 / w0
        );
    }
}

/// The default `"housner"` is Newton's law with e = 0 in the full engine (docs/restitution.md): the two
/// equal blocks leave together at v0/2 at every Δt (tolerance 1e-4 × v0 as in
/// `check_two_blocks`); `"contact"` leaves the impact to the contacts, whose rebound at 1 ms
/// (e ≈ 0.10, measured before the law) differs from it by ≈ 0.05 × v0, far above 1e-2 × v0.
#[test]
fn default_housner_is_newton_at_zero_and_contact_is_the_contacts_own() {
    for solver in ["penalty", "dual"] {
        for dt in [1e-4, 1e-3, 1e-2] {
            let (va, vb, _) = two_block_velocities(json!("housner"), dt, solver);
            eprintln!("{solver} Δt = {dt:e} s, housner: v_A = {va:.7}, v_B = {vb:.7} m/s (Newton e = 0: {})", V0 / 2.0);
            assert!(
                (va - V0 / 2.0).abs() <= 1e-4 * V0,
                "{solver} Δt {dt}: v_A {va}"
            );
            assert!(
                (vb - V0 / 2.0).abs() <= 1e-4 * V0,
                "{solver} Δt {dt}: v_B {vb}"
            );
        }
        let (va, vb, _) = two_block_velocities(json!("contact"), 1e-3, solver);
        eprintln!("{solver} Δt = 1e-3 s, contact: v_A = {va:.7}, v_B = {vb:.7} m/s");
        assert!(
            (vb - va).abs() > 1e-2 * V0,
            "{solver}: \"contact\" gave Newton's e = 0 (v_A {va}, v_B {vb}): the law was not bypassed"
        );
    }
}

/// `"contact"` is the full engine's own contact response, which the reduced models do not
/// represent: `auto` runs the full engine.
#[test]
fn contact_restitution_sends_auto_to_the_engine() {
    let (_, model) = reduced_rocking_ratio(
        0.2,
        0.6,
        json!({ "model": "auto", "duration": 1.5, "output_interval": 1e-4, "restitution": "contact" }),
    );
    assert_eq!(model, "dda");
}
