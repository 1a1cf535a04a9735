//! The rocking frame of Makris & Vassiliou (2013): overturning amplitude, history to the first
//! impact and restitution against the equivalent column.
use super::frame_records::frame_restitution_law;
use super::*;

// ---------------------------------------------------------------------------------------------
// Rocking frame
// ---------------------------------------------------------------------------------------------

/// p̂² of the rocking frame, derived by Lagrange's equations (N columns of mass m, moment of
/// inertia (4/3) m R² about the pivot; the cap of mass M = γ N m translates with the columns'
/// top corners, at distance 2R from the pivots: speed 2Rθ̇, height 2R cos(α − θ)):
/// (4/3 N m + 4M) R² θ̈ = −(N m + 2M) g R [sin(α − θ) − (a_g/g) cos(α − θ)], so
/// p̂² = (3g/4R) (1 + 2γ)/(1 + 3γ), Makris & Vassiliou's result.
pub(super) fn frame_p2(gamma: f64) -> f64 {
    let r = B.hypot(H);
    3.0 * G / (4.0 * r) * (1.0 + 2.0 * gamma) / (1.0 + 3.0 * gamma)
}

/// The frame of `ashlar::presets::RockingFrame::SEED` (columns b = B, h = H centred at
/// x = ±0.8 m, the cap spanning their outer faces, φ = 75°) with cap mass ratio γ.
pub(super) fn frame_scene(gamma: f64, solver: &str) -> ashlar::scene::Scene {
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
