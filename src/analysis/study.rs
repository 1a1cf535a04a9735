//! Speed against accuracy: sweeps the numerical controls (time step, penalty stiffness, g2,
//! integrator, block model, contact solver) and the model (reduced or full DDA) over the
//! benchmark scenes, measuring for each point the error against an independent reference, the
//! wall time and the solver's effort. Drives `analysis::run`; `ashlar study` prints and plots it.
//!
//! References (each independent of the engine and of the reduced models): closed forms for
//! the incline under gravity; fixed-step rigid-plastic integrations (Δt = 1e-5 s) for the
//! incline under a sine and the shaking foundation (Yagoda-Biran & Hatzor 2015, Eq. 17); Housner's equation by
//! fixed-step RK4 (Δt = 1e-5 s) for the rocking column; for the masonry wall, which has no
//! closed form, a DDA run at the finest setting of the sweep.
//!
//! Split by stage: `study/scenes.rs` (the benchmark scenes), `grid.rs` (the settings swept),
//! `evaluation.rs` (a setting on a scene), `pareto.rs` (front and convergence order),
//! `svg.rs` (plots), `report.rs` (Markdown). This file keeps the types, the restitution fit,
//! the driver `run_study`, `check` and `write_outputs`, and the tests (a third of it).
//! Length (over 600 lines): those tests, which check the driver end to end on the quick grid.
use super::reduced::ode::Tolerance;
use super::reduced::ReducedParams;
use super::reference;
use super::run::{run, RunOptions};
use crate::motion::{self, GroundMotion, Signal};
use crate::presets::{self, incline_blocks, rocking_pulse as pulse};
use crate::record::Frame;
use crate::scene::scene_from_value;
use serde::Serialize;
use serde_json::{json, Value};
use std::path::{Path, PathBuf};
use std::sync::Mutex;
use std::time::Instant;

mod error;
mod evaluation;
mod grid;
mod pareto;
mod report;
mod scenes;
mod svg;

pub use error::StudyError;
use evaluation::*;
use grid::*;
pub use pareto::{convergence_order, dt_series, pareto};
pub use report::report;
use report::{engine_baseline, pct};
pub use scenes::wall_record;
use scenes::*;

const G: f64 = 9.81;
/// Fixed step of the sliding and foundation references, s (the texts of the report say 1e-5 s).
const REF_DT: f64 = 1e-5;
const PI: f64 = std::f64::consts::PI;

/// The repository's folder of recorded ground motions (`data/ground-motions`, with their source
/// and licence), relative to the repository root: `ashlar study`'s default `--ground-motions`;
/// tests and examples join it to `CARGO_MANIFEST_DIR`.
pub const GROUND_MOTIONS_DIR: &str = "data/ground-motions";

/// What to run.
#[derive(Debug, Clone)]
pub struct StudyOptions {
    /// The reduced sweep for CI (minutes in a debug build).
    pub quick: bool,
    /// Directory of the recorded ground motions (the repository's `GROUND_MOTIONS_DIR`).
    pub ground_motions: PathBuf,
    /// Wall-clock budget of one point, s: a point over budget is recorded as such.
    pub point_budget_s: f64,
    /// Print each point as it completes.
    pub verbose: bool,
}

/// The numerical settings of one point.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Setting {
    /// "dda" (the full engine) or "reduced".
    pub model: String,
    pub integrator: String,
    pub block_model: String,
    pub contact_solver: String,
    /// s (the maximum step of the adaptive control).
    pub time_step: f64,
    /// N/m, or `None` for "auto".
    pub penalty_stiffness: Option<f64>,
    /// Shi's g2.
    pub max_displacement_ratio: f64,
    /// Relative tolerance of the reduced models' ODE.
    pub reduced_rtol: Option<f64>,
    /// The project's defaults (no control field given).
    pub defaults: bool,
}

impl Setting {
    /// The project's defaults as the study sees them (docs/format.md §1; `scene::Control`).
    fn baseline() -> Self {
        let c = crate::scene::Control::default();
        Self {
            model: "dda".into(),
            integrator: "dda".into(),
            block_model: "deformable".into(),
            contact_solver: "penalty".into(),
            time_step: c.time_step,
            penalty_stiffness: None,
            max_displacement_ratio: c.max_displacement_ratio,
            reduced_rtol: None,
            defaults: false,
        }
    }

    fn label(&self) -> String {
        if self.defaults {
            return "defaults".into();
        }
        if self.model == "reduced" {
            return format!("reduced rtol={:.0e}", self.reduced_rtol.unwrap_or(1e-10));
        }
        format!(
            "{} {} {} dt={:.0e} k={} g2={:.0e}",
            self.integrator,
            self.block_model,
            self.contact_solver,
            self.time_step,
            self.penalty_stiffness
                .map(|k| format!("{k:.0e}"))
                .unwrap_or_else(|| "auto".into()),
            self.max_displacement_ratio
        )
    }

    fn control(&self, duration: f64) -> Value {
        if self.defaults {
            return json!({ "duration": duration });
        }
        let penalty = match self.penalty_stiffness {
            Some(k) => json!(k),
            None => json!("auto"),
        };
        let model = if self.model == "reduced" {
            "auto"
        } else {
            "dda"
        };
        let mut c = json!({
            "duration": duration,
            "time_step": self.time_step,
            "max_displacement_ratio": self.max_displacement_ratio,
            "integrator": self.integrator,
            "block_model": self.block_model,
            "contact_solver": self.contact_solver,
            "penalty_stiffness": penalty,
            "model": model,
        });
        // Long runs at tiny steps need more than the default output cadence allows.
        c["max_steps"] = json!(200_000_000u64);
        c
    }
}

/// One measured point.
#[derive(Debug, Clone, Serialize)]
pub struct Point {
    pub scene: String,
    /// Which sweep the point belongs to ("time_step", "penalty", "g2", "block_model",
    /// "contact_solver", "reduced", "defaults").
    pub sweep: String,
    pub label: String,
    pub setting: Setting,
    /// The model that ran (from the summary).
    pub model_ran: String,
    /// Relative error against the scene's reference (see `Scene::metric`), `None` when the
    /// run failed or was over budget.
    pub error: Option<f64>,
    /// The measured quantity itself (final displacement m, peak |x| m, peak |θ| rad, or the
    /// overturning amplitude m/s²), to compare two settings directly.
    pub value: Option<f64>,
    pub wall_time_s: f64,
    pub steps: u64,
    pub open_close_iterations_mean: f64,
    pub time_step_cuts: u64,
    pub note: String,
}

/// The whole study.
#[derive(Debug, Clone, Serialize)]
pub struct StudyResult {
    pub quick: bool,
    pub scenes: Vec<SceneInfo>,
    pub points: Vec<Point>,
    /// The restitution the rocking column shows, by method: Housner's law, and the constant
    /// coefficient that makes the reduced model best match a DDA run over 2 s (through the
    /// impacts), per integrator.
    pub restitution: Vec<RestitutionFit>,
    /// The unit of every numeric field ([`point_units`]).
    pub units: serde_json::Value,
}

/// One restitution figure.
#[derive(Debug, Clone, Serialize)]
pub struct RestitutionFit {
    pub source: String,
    /// Ratio of angular velocities after/before an impact.
    pub coefficient: f64,
    /// RMS rotation difference (rad) of the best fit over the run.
    pub rms_misfit: f64,
}

/// The constant restitution coefficient with which the reduced rocking model best reproduces
/// `theta` (rotation at 0.01 s frames of the column under the 5 m/s² pulse): a scan of e in
/// steps of 0.0025 over [0.5, 1].
fn fit_restitution(theta: &[f64], duration: f64) -> Result<(f64, f64), StudyError> {
    let mut v = column_scene();
    v["control"] = json!({ "duration": duration, "model": "rocking", "output_interval": 0.01 });
    let scene = scene_from_value(&v)?;
    let mut best = (f64::NAN, f64::INFINITY);
    for i in 0..=200 {
        let e = 0.5 + 0.0025 * i as f64;
        let reduced = ReducedParams {
            restitution: super::reduced::Restitution::Coefficient(e),
            ..ReducedParams::default()
        };
        let red = pulse_rotations(&scene, None, Some(reduced))?;
        let n = red.len().min(theta.len()).max(1);
        let rms = (red
            .iter()
            .zip(theta)
            .map(|(a, b)| (a - b).powi(2))
            .sum::<f64>()
            / n as f64)
            .sqrt();
        if rms < best.1 {
            best = (e, rms);
        }
    }
    Ok(best)
}

/// The column's rotation (rad) at every output frame of `scene` under the study's 5 m/s² pulse,
/// with the engine's or the reduced model's params given.
fn pulse_rotations(
    scene: &crate::scene::Scene,
    sim_params: Option<crate::simulation::SimParams>,
    reduced_params: Option<ReducedParams>,
) -> Result<Vec<f64>, StudyError> {
    let frames = Mutex::new(Vec::new());
    let record = |f: &Frame| {
        if let Ok(mut fr) = frames.lock() {
            fr.push(f.blocks[1].rotation);
        }
    };
    let opts = RunOptions {
        on_frame: Some(&record),
        sim_params,
        reduced_params,
        ..Default::default()
    };
    run(scene, &pulse(5.0), &opts)?;
    Ok(frames.into_inner().unwrap_or_default())
}

fn restitution_study(quick: bool) -> Result<Vec<RestitutionFit>, StudyError> {
    let alpha = (COL_B / COL_H).atan();
    let mut out = vec![RestitutionFit {
        source: "Housner's law, 1 − 1.5 sin²α (the reduced model's default)".into(),
        coefficient: 1.0 - 1.5 * alpha.sin().powi(2),
        rms_misfit: 0.0,
    }];
    for integ in ["dda", "trapezoidal"] {
        for block_model in ["rigid", "deformable"] {
            if quick && block_model == "deformable" {
                continue;
            }
            out.push(fitted_restitution(integ, block_model, None)?);
        }
    }
    Ok(out)
}

/// The fitted restitution of the DDA column under the study's pulse over 2 s (see
/// [`StudyResult::restitution`]) with the given integrator and block model, and `sim_params`
/// (`None`: the defaults; e.g. an `ImpactParams` knob to compare, `examples/restitution_fit.rs`).
pub fn fitted_restitution(
    integ: &str,
    block_model: &str,
    sim_params: Option<crate::simulation::SimParams>,
) -> Result<RestitutionFit, StudyError> {
    let duration = 2.0;
    let mut v = column_scene();
    v["control"] = json!({ "duration": duration, "model": "dda", "integrator": integ, "block_model": block_model, "output_interval": 0.01 });
    let scene = scene_from_value(&v)?;
    let theta = pulse_rotations(&scene, sim_params, None)?;
    let (e, rms) = fit_restitution(&theta, duration)?;
    Ok(RestitutionFit {
        source: format!(
            "DDA ({integ} integrator, {block_model} blocks, other controls at defaults), fitted"
        ),
        coefficient: e,
        rms_misfit: rms,
    })
}

/// A benchmark scene as reported.
#[derive(Debug, Clone, Serialize)]
pub struct SceneInfo {
    pub name: String,
    pub description: String,
    pub metric: String,
    pub reference: String,
    /// Unit of the scene's points' `value`: m, rad or m/s2.
    pub value_unit: String,
}

impl Metric {
    /// Unit of the measured quantity (`Point::value`).
    fn value_unit(&self) -> &'static str {
        match self {
            Metric::FinalAlong { .. } | Metric::HistoryX { .. } | Metric::Finest { .. } => "m",
            Metric::Rotation { .. } => "rad",
            Metric::Overturning { .. } => "m/s2",
        }
    }
}

/// The `units` object of `points.json`: each numeric field of a point (`value` in its scene's
/// `value_unit`); "1" marks a ratio.
fn point_units() -> serde_json::Value {
    serde_json::json!({
        "setting": {
            "time_step": "s",
            "penalty_stiffness": "N/m",
            "max_displacement_ratio": "1",
            "reduced_rtol": "1",
        },
        "error": "1",
        "value": "scenes[].value_unit",
        "wall_time_s": "s",
        "steps": "count",
        "open_close_iterations_mean": "1",
        "time_step_cuts": "count",
        "restitution": { "coefficient": "1", "rms_misfit": "rad" },
    })
}

/// What a run is measured by.
enum Metric {
    /// Final displacement of block 1 along `dir`, against `exact` (m).
    FinalAlong { dir: [f64; 2], exact: f64 },
    /// Largest |x − x_ref| over the frames, relative to the largest |x_ref| (histories of
    /// block 1's x at the frame times).
    HistoryX { reference: Vec<(f64, f64)> },
    /// Largest |θ − θ_ref| until `until` (s), relative to the peak |θ_ref|.
    Rotation {
        reference: Vec<(f64, f64)>,
        until: f64,
    },
    /// Overturning amplitude of the half-sine pulse, m/s², against `exact`.
    Overturning { exact: f64, tolerance: f64 },
    /// Largest |x − x_ref| of the top block over the frames relative to its peak |x_ref|,
    /// the reference being a run at `reference` (computed first).
    Finest { observed: usize, reference: Setting },
}

struct Bench {
    name: String,
    description: String,
    scene: Value,
    motion: GroundMotion,
    duration: f64,
    metric: Metric,
    reference_text: String,
    metric_text: String,
    /// Whether the reduced models apply (a single block on a base).
    reducible: bool,
}

/// Run the study.
pub fn run_study(opts: &StudyOptions) -> Result<StudyResult, StudyError> {
    let benches = benches(opts)?;
    let mut points = Vec::new();
    let mut scenes = Vec::new();
    for bench in &benches {
        scenes.push(SceneInfo {
            name: bench.name.clone(),
            description: bench.description.clone(),
            metric: bench.metric_text.clone(),
            reference: bench.reference_text.clone(),
            value_unit: bench.metric.value_unit().into(),
        });
        let reference_frames = match &bench.metric {
            Metric::Finest {
                observed,
                reference,
            } => {
                let mut budget_opts = opts.clone();
                budget_opts.point_budget_s = opts.point_budget_s * 20.0;
                let m = run_once(
                    bench,
                    reference,
                    &bench.motion,
                    *observed,
                    budget_opts.point_budget_s,
                    None,
                )?;
                if opts.verbose {
                    eprintln!(
                        "{}: reference run {:.1} s, {} steps",
                        bench.name, m.summary.wall_time_s, m.summary.steps
                    );
                }
                Some(m.frames.iter().map(|f| (f.0, f.1)).collect::<Vec<_>>())
            }
            _ => None,
        };
        for (sweep, setting) in settings(bench, opts.quick) {
            let p = match evaluate(bench, &setting, reference_frames.as_deref(), opts) {
                Ok(ev) => Point {
                    scene: bench.name.clone(),
                    sweep,
                    label: setting.label(),
                    model_ran: ev.summary.model.clone(),
                    error: ev.error,
                    value: ev.value,
                    wall_time_s: ev.wall,
                    steps: ev.steps,
                    open_close_iterations_mean: ev
                        .summary
                        .diagnostics
                        .open_close_iterations_mean
                        .unwrap_or(0.0),
                    time_step_cuts: ev.summary.diagnostics.time_step_cuts,
                    note: ev.note,
                    setting,
                },
                Err(e) => Point {
                    scene: bench.name.clone(),
                    sweep,
                    label: setting.label(),
                    model_ran: String::new(),
                    error: None,
                    value: None,
                    wall_time_s: 0.0,
                    steps: 0,
                    open_close_iterations_mean: 0.0,
                    time_step_cuts: 0,
                    note: format!("not run: {e}"),
                    setting,
                },
            };
            if opts.verbose {
                eprintln!(
                    "{:20} {:15} {:55} err {:>10} wall {:8.3} s steps {:8} {}",
                    p.scene,
                    p.sweep,
                    p.label,
                    p.error
                        .map(|e| format!("{:.3e}", e))
                        .unwrap_or_else(|| "-".into()),
                    p.wall_time_s,
                    p.steps,
                    p.note
                );
            }
            points.push(p);
        }
    }
    let restitution = restitution_study(opts.quick)?;
    if opts.verbose {
        for r in &restitution {
            eprintln!(
                "restitution: {} = {:.4} (RMS misfit {:.2e} rad)",
                r.source, r.coefficient, r.rms_misfit
            );
        }
    }
    Ok(StudyResult {
        quick: opts.quick,
        scenes,
        points,
        restitution,
        units: point_units(),
    })
}

/// The target of the defaults: what a user gets without setting any control must be within
/// 1 % of an independent reference on every benchmark (docs/accuracy-vs-speed.md's accuracy target, the one the
/// report's Decisions and docs/accuracy-vs-speed.md measure the defaults against).
pub const DEFAULTS_TARGET: f64 = 0.01;

/// How far the default reduced model's error may exceed the full engine's at the default
/// settings on the same scene: 1e-4 (0.01 percentage points). The claim that justifies
/// `"model": "auto"` as the default is "never less accurate than the engine"; the slack only
/// absorbs a tie on the overturning bisection's grid (both searches bisect the same bracket to
/// the same tolerance, so their values are quantised alike) and round-off. Measured margins
/// (`ashlar study --quick --check`) are printed by the check.
pub const REDUCED_VS_ENGINE_SLACK: f64 = 1e-4;

/// What `ashlar study --check` (CI's study stage) asserts of a study, one line per failure:
/// - every point has an error value (a point that failed, ran over its budget or could not be
///   compared is a failure, not a count);
/// - every `defaults` point is within [`DEFAULTS_TARGET`] of its reference;
/// - on every scene with a `reduced` sweep (the single-block benchmarks), the defaults ran a
///   reduced model (`auto` chose it) and its error is not above the full engine's at the default
///   settings by more than [`REDUCED_VS_ENGINE_SLACK`]; on the others the defaults ran `dda`.
///
/// On success, returns one line per scene with the measured figures.
pub fn check(result: &StudyResult) -> Result<Vec<String>, Vec<String>> {
    let mut failures = Vec::new();
    let mut report = Vec::new();
    for p in &result.points {
        if !p.error.is_some_and(f64::is_finite) {
            failures.push(format!(
                "{} / {} / {}: no error value (model ran {:?}; note: {})",
                p.scene,
                p.sweep,
                p.label,
                p.model_ran,
                if p.note.is_empty() { "-" } else { &p.note }
            ));
        }
    }
    for scene in &result.scenes {
        let name = scene.name.as_str();
        let Some(d) = result
            .points
            .iter()
            .find(|p| p.scene == name && p.sweep == "defaults")
        else {
            failures.push(format!("{name}: no defaults point"));
            continue;
        };
        let reducible = result
            .points
            .iter()
            .any(|p| p.scene == name && p.sweep == "reduced");
        let Some(e) = d.error.filter(|e| e.is_finite()) else {
            continue; // already reported above
        };
        if e > DEFAULTS_TARGET {
            failures.push(format!(
                "{name}: the defaults (model {}) are {} from the reference, above the {} target",
                d.model_ran,
                pct(Some(e)),
                pct(Some(DEFAULTS_TARGET))
            ));
        }
        let engine = engine_baseline(result, name).and_then(|p| p.error);
        if reducible {
            if !matches!(d.model_ran.as_str(), "rocking" | "sliding") {
                failures.push(format!(
                    "{name}: a single-block benchmark, but the defaults ran {:?}, not a reduced model",
                    d.model_ran
                ));
            }
            match engine {
                Some(f) if e > f + REDUCED_VS_ENGINE_SLACK => failures.push(format!(
                    "{name}: the default reduced model ({}, error {e:.3e}) is less accurate than the full engine at the default settings (error {f:.3e}) by more than {REDUCED_VS_ENGINE_SLACK:e}",
                    d.model_ran
                )),
                Some(_) => {}
                None => failures.push(format!(
                    "{name}: no error for the full engine at the default settings to compare the reduced model with"
                )),
            }
        } else if d.model_ran != "dda" {
            failures.push(format!(
                "{name}: a multi-block benchmark, but the defaults ran {:?}, not the full engine",
                d.model_ran
            ));
        }
        report.push(format!(
            "{name}: defaults ({}) error {e:.3e} (target {DEFAULTS_TARGET:e}); full engine at default settings {}",
            d.model_ran,
            engine.map_or("-".to_string(), |f| format!("{f:.3e}"))
        ));
    }
    if failures.is_empty() {
        Ok(report)
    } else {
        Err(failures)
    }
}

/// Write `points.json`, `points.csv` and the SVG plots into `dir`.
pub fn write_outputs(result: &StudyResult, dir: &Path) -> Result<Vec<PathBuf>, StudyError> {
    std::fs::create_dir_all(dir).map_err(|e| StudyError::io(dir, e))?;
    let io = |p: &Path, text: &str| std::fs::write(p, text).map_err(|e| StudyError::io(p, e));
    let mut written = Vec::new();
    let json = serde_json::to_string_pretty(result)?;
    let p = dir.join("points.json");
    io(&p, &(json + "\n"))?;
    written.push(p);
    let mut csv = String::from("scene,sweep,label,model_ran,integrator,block_model,contact_solver,time_step_s,penalty_stiffness_N_per_m,max_displacement_ratio,reduced_rtol,error,wall_time_s,steps,open_close_iterations_mean,time_step_cuts,note\n");
    for p in &result.points {
        let s = &p.setting;
        csv += &format!(
            "{},{},\"{}\",{},{},{},{},{},{},{},{},{},{:.6},{},{:.3},{},\"{}\"\n",
            p.scene,
            p.sweep,
            p.label,
            p.model_ran,
            s.integrator,
            s.block_model,
            s.contact_solver,
            s.time_step,
            s.penalty_stiffness
                .map(|k| k.to_string())
                .unwrap_or_else(|| "auto".into()),
            s.max_displacement_ratio,
            s.reduced_rtol.map(|r| r.to_string()).unwrap_or_default(),
            p.error.map(|e| format!("{e:.6e}")).unwrap_or_default(),
            p.wall_time_s,
            p.steps,
            p.open_close_iterations_mean,
            p.time_step_cuts,
            p.note.replace('"', "'")
        );
    }
    let p = dir.join("points.csv");
    io(&p, &csv)?;
    written.push(p);
    for scene in &result.scenes {
        let pts: Vec<&Point> = result
            .points
            .iter()
            .filter(|p| p.scene == scene.name)
            .collect();
        let p = dir.join(format!("pareto-{}.svg", scene.name));
        io(&p, &svg::pareto(&scene.name, &pts))?;
        written.push(p);
        let p = dir.join(format!("convergence-{}.svg", scene.name));
        io(&p, &svg::convergence(&scene.name, &pts))?;
        written.push(p);
    }
    Ok(written)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn point(wall: f64, error: Option<f64>) -> Point {
        Point {
            scene: "s".into(),
            sweep: "time_step".into(),
            label: String::new(),
            setting: Setting::baseline(),
            model_ran: "dda".into(),
            error,
            value: None,
            wall_time_s: wall,
            steps: 0,
            open_close_iterations_mean: 0.0,
            time_step_cuts: 0,
            note: String::new(),
        }
    }

    #[test]
    fn pareto_keeps_only_points_nobody_beats_on_both() {
        let pts = [
            point(1.0, Some(0.1)),
            point(2.0, Some(0.2)), // slower and worse than the first: dominated
            point(3.0, Some(0.01)),
            point(0.5, None), // failed: not on the front
            point(4.0, Some(0.001)),
        ];
        let refs: Vec<&Point> = pts.iter().collect();
        assert_eq!(pareto(&refs), vec![0, 2, 4]);
    }

    /// A study of two scenes as the quick study makes them: a single-block scene (defaults ran
    /// the reduced model, a `reduced` sweep, the engine's baseline point) and a wall (defaults
    /// ran the engine).
    fn study(rocking_default: f64, engine: f64, wall_default: Option<f64>) -> StudyResult {
        let mk = |scene: &str, sweep: &str, model: &str, setting: Setting, e: Option<f64>| Point {
            scene: scene.into(),
            sweep: sweep.into(),
            model_ran: model.into(),
            setting,
            ..point(1.0, e)
        };
        let mut defaults = Setting::baseline();
        defaults.defaults = true;
        let info = |name: &str| SceneInfo {
            name: name.into(),
            description: String::new(),
            metric: String::new(),
            reference: String::new(),
            value_unit: String::new(),
        };
        StudyResult {
            quick: true,
            units: point_units(),
            scenes: vec![info("rocking"), info("wall")],
            points: vec![
                mk(
                    "rocking",
                    "defaults",
                    "rocking",
                    defaults.clone(),
                    Some(rocking_default),
                ),
                mk(
                    "rocking",
                    "time_step",
                    "dda",
                    Setting::baseline(),
                    Some(engine),
                ),
                mk(
                    "rocking",
                    "reduced",
                    "rocking",
                    Setting::baseline(),
                    Some(1e-9),
                ),
                mk("wall", "defaults", "dda", defaults, wall_default),
            ],
            restitution: Vec::new(),
        }
    }

    #[test]
    fn the_check_passes_a_good_study_and_names_every_failure() {
        assert!(check(&study(1e-4, 5e-3, Some(6e-3))).is_ok());
        // A point without an error value fails (it is not merely counted).
        let e = check(&study(1e-4, 5e-3, None)).expect_err("missing error");
        assert!(
            e.iter()
                .any(|l| l.contains("wall") && l.contains("no error value")),
            "{e:?}"
        );
        // Defaults above the 1 % target.
        let e = check(&study(1e-4, 5e-3, Some(0.02))).expect_err("above target");
        assert!(
            e.iter().any(|l| l.contains("wall") && l.contains("target")),
            "{e:?}"
        );
        // The reduced default less accurate than the engine (beyond the slack).
        let e = check(&study(4e-3, 1e-3, Some(6e-3))).expect_err("reduced worse");
        assert!(e.iter().any(|l| l.contains("less accurate")), "{e:?}");
        // The slack: a tie on the bisection grid passes.
        assert!(check(&study(1e-3 + 0.5e-4, 1e-3, Some(6e-3))).is_ok());
        // A single-block scene whose defaults ran the engine: `auto` did not choose.
        let mut s = study(1e-4, 5e-3, Some(6e-3));
        s.points[0].model_ran = "dda".into();
        let e = check(&s).expect_err("auto did not choose");
        assert!(e.iter().any(|l| l.contains("not a reduced model")), "{e:?}");
    }

    #[test]
    fn convergence_order_recovers_a_power_law() {
        // e = 3 Δt²: slope exactly 2 (to round-off, 1e-12); points under the floor ignored.
        let pts: Vec<(f64, f64)> = [1e-2, 1e-3, 1e-4, 1e-5]
            .iter()
            .map(|&h: &f64| (h, 3.0 * h * h))
            .collect();
        let o = convergence_order(&pts, 1e-9).expect("order");
        assert!((o - 2.0).abs() < 1e-12, "{o}");
        assert_eq!(convergence_order(&pts[..1], 1e-9), None);
    }
}
