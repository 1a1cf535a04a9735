//! The study's benchmark scenes (stage 1): each scene with its motion, duration, metric and
//! independent reference (docs/accuracy-vs-speed.md).
use super::*;

pub(super) fn material_scene(blocks: Value, friction_deg: f64) -> Value {
    presets::scene_json(blocks, friction_deg, Value::Null)
}

/// Housner's rocking of Yagoda-Biran & Hatzor's (2015) column under its half-sine pulse of amplitude `a` (RK4 at
/// 1e-5 s): (t, θ) every `every` s, overturned by `t_end`, first impact.
pub(super) fn housner(a: f64, t_end: f64, every: f64) -> (Vec<(f64, f64)>, bool, Option<f64>) {
    let col = reference::HousnerColumn::YAGODA_BIRAN_2015;
    let stride = (every / col.dt).round() as usize;
    let r = reference::housner_history(&col, reference::half_sine_pulse(a), t_end, stride);
    (r.samples, r.overturned, r.first_impact)
}

/// The study's column is the reference's.
pub(super) const COL_B: f64 = reference::HousnerColumn::YAGODA_BIRAN_2015.b;
pub(super) const COL_H: f64 = reference::HousnerColumn::YAGODA_BIRAN_2015.h;
const _: () = assert!(
    COL_B == presets::Column::SEED.half_width && COL_H == presets::Column::SEED.half_height
);

/// The reference's column with the scene's default block model.
pub(super) fn column_scene() -> Value {
    presets::Column::SEED.default_model().json(Value::Null)
}

/// The wall's record: Northridge (Mulholland 009) from `ground_motions`, scaled to 0.4 g.
pub fn wall_record(ground_motions: &Path) -> Result<GroundMotion, StudyError> {
    let record = ground_motions.join("northridge-1994-mulholland-009.at2");
    let gm = motion::load_path(&record).map_err(|source| StudyError::Motion {
        path: record.clone(),
        source,
        hint: format!(" (the record is in the repository, {GROUND_MOTIONS_DIR}/)"),
    })?;
    Ok(gm.scaled_to_pga(0.4 * motion::STANDARD_GRAVITY))
}

/// The benchmark scenes.
pub(super) fn benches(opts: &StudyOptions) -> Result<Vec<Bench>, StudyError> {
    let every: f64 = 0.01;
    let mut out = Vec::new();
    // 1. Incline under gravity (Yagoda-Biran & Hatzor 2015, Eq. 14).
    let (alpha, phi, t_end) = (28.0f64, 20.0f64, 1.0);
    let (blocks, d) = incline_blocks(alpha);
    let exact = 0.5
        * G
        * (alpha.to_radians().sin() - alpha.to_radians().cos() * phi.to_radians().tan())
        * t_end
        * t_end;
    out.push(Bench {
        name: "incline-gravity".into(),
        description: format!("1 × 0.5 m block on a {alpha}° incline, φ = {phi}°, sliding from rest under gravity for {t_end} s"),
        scene: material_scene(blocks, phi),
        motion: GroundMotion::none(),
        duration: t_end,
        metric: Metric::FinalAlong { dir: d, exact },
        reference_text: format!("closed form d = ½g(sin α − cos α tan φ)t² = {exact:.6} m (Yagoda-Biran & Hatzor 2015, Eq. 14)"),
        metric_text: "relative error of the final down-slope displacement".into(),
        reducible: true,
    });
    // 2. Incline under a horizontal sine (Yagoda-Biran & Hatzor 2015, Eq. 10).
    let (alpha, phi, a, f, t_end) = (20.0f64, 30.0f64, 4.0, 1.0, 4.0);
    let (blocks, d) = incline_blocks(alpha);
    let sine = |t: f64| a * (2.0 * PI * f * t).sin();
    let exact =
        reference::newmark_incline(alpha.to_radians(), phi.to_radians(), G, sine, t_end, REF_DT);
    out.push(Bench {
        name: "incline-sine".into(),
        description: format!("the same block on a {alpha}° incline, φ = {phi}°, under a horizontal sine {a} m/s² at {f} Hz for {t_end} s"),
        scene: material_scene(blocks, phi),
        motion: GroundMotion::horizontal(Signal::Sine { amplitude: a, frequency: f }),
        duration: t_end,
        metric: Metric::FinalAlong { dir: d, exact },
        reference_text: format!("rigid-plastic (Newmark) integration, fixed step 1e-5 s, exact stick/slip: {exact:.6} m"),
        metric_text: "relative error of the final down-slope displacement".into(),
        reducible: true,
    });
    // 3. Shaking foundation (Yagoda-Biran & Hatzor 2015, Eq. 17), driven block.
    let (a, f, mu, t_end) = (0.2f64, 2.0f64, 0.6f64, if opts.quick { 2.0 } else { 5.0 });
    let w = 2.0 * PI * f;
    let mut scene = material_scene(
        json!([
            { "id": "foundation", "material": "stone", "vertices": [[-8.0, -0.5], [8.0, -0.5], [8.0, 0.0], [-8.0, 0.0]] },
            { "id": "block", "material": "stone", "vertices": [[-1.0, 0.0], [1.0, 0.0], [1.0, 0.1], [-1.0, 0.1]] },
        ]),
        mu.atan().to_degrees(),
    );
    scene["excitation"] = json!({ "type": "driven_block", "block": "foundation" });
    out.push(Bench {
        name: "foundation".into(),
        description: format!("2 × 0.1 m block on a foundation moving as A(1 − cos 2πft), A = {a} m, f = {f} Hz, μ = {mu}, {t_end} s"),
        scene,
        motion: GroundMotion::horizontal(Signal::Pulse {
            amplitude: a * w * w,
            period: 1.0 / f,
            cycles: f * t_end + 1.0,
            phase: std::f64::consts::FRAC_PI_2,
        }),
        duration: t_end,
        metric: Metric::HistoryX {
            reference: reference::foundation_eq17(a, f, mu, G, t_end, REF_DT, (every / REF_DT).round() as usize),
        },
        reference_text: "Yagoda-Biran & Hatzor 2015, Eq. 17 integrated at a fixed step of 1e-5 s".into(),
        metric_text: "largest |x − x_ref| over the run relative to the largest |x_ref|".into(),
        reducible: true,
    });
    // 4. Rocking column, history until the first impact (Yagoda-Biran & Hatzor 2015, §3.3).
    let (reference, _, impact) = housner(5.0, 2.0, every);
    let until = impact.unwrap_or(2.0) - 0.01;
    out.push(Bench {
        name: "rocking-history".into(),
        description: format!("column 0.4 × 1.2 m on a fixed base, half-sine pulse 5 m/s², period 1 s; rotation until the first impact ({until:.2} s)"),
        scene: column_scene(),
        motion: pulse(5.0),
        duration: until + 0.005,
        metric: Metric::Rotation { reference, until },
        reference_text: "Housner's equation, RK4 at a fixed step of 1e-5 s".into(),
        metric_text: "largest |θ − θ_ref| until the first impact relative to the peak |θ_ref|".into(),
        reducible: true,
    });
    // 5. Rocking column, overturning amplitude.
    let exact = overturning(|a| housner(a, 4.0, 0.1).1, 1e-3);
    out.push(Bench {
        name: "rocking-overturning".into(),
        description: "the same column: smallest half-sine amplitude that overturns it".into(),
        scene: column_scene(),
        motion: pulse(1.0),
        duration: 3.0,
        metric: Metric::Overturning { exact, tolerance: if opts.quick { 0.05 } else { 0.01 } },
        reference_text: format!("Housner's equation (RK4, 1e-5 s) bisected to 1e-3 m/s²: {exact:.3} m/s²"),
        metric_text: "relative error of the overturning amplitude (bisection to the stated tolerance)".into(),
        reducible: true,
    });
    // 6. Masonry wall under a recorded ground motion (data/ground-motions).
    let gm = wall_record(&opts.ground_motions)?;
    let scene = presets::study_wall_json();
    let observed = scene["blocks"].as_array().map(|b| b.len() - 1).unwrap_or(1);
    let duration = if opts.quick { 3.0 } else { 8.0 };
    let mut reference = Setting::baseline();
    reference.time_step = 1e-4;
    reference.max_displacement_ratio = 1e-4;
    out.push(Bench {
        name: "wall".into(),
        description: format!("running-bond dry-stone wall, 3 courses of 0.6 × 0.3 m blocks, Northridge (Mulholland 009) scaled to 0.4 g, first {duration} s"),
        scene,
        motion: gm,
        duration,
        metric: Metric::Finest { observed, reference },
        reference_text: "DDA at the finest setting of the sweep (Δt = 1e-4 s, g2 = 1e-4, other controls at defaults)".into(),
        metric_text: "largest |x − x_ref| of the top block relative to its peak |x_ref|".into(),
        reducible: false,
    });
    Ok(out)
}
