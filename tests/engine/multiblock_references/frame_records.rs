//! The rocking frame under the recorded ground motions (data/ground-motions): its peak
//! rotation against the equivalent column integrated by RK4 with the frame's impact law.
use super::*;

use super::frame::*;

// ---------------------------------------------------------------------------------------------
// Rocking frame under recorded ground motions
// ---------------------------------------------------------------------------------------------

/// Makris & Vassiliou's (2013) ratio of angular velocities across an impact of the rocking
/// frame, r = (1 − 1.5 sin²α + 3γ cos 2α)/(1 + 3γ) (γ = 0: Housner's column).
pub(super) fn frame_restitution_law(gamma: f64, alpha: f64) -> f64 {
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
