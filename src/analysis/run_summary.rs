//! Analysis › run › summary: what a run reports (`summary.json`, docs/format.md §3): the
//! per-block results, the solver diagnostics, the summary itself, its units, and the controls
//! it reports as run. Filled by `run.rs` (the engine loop and the reduced models).
use crate::analysis::run_end::{RecordTruncated, RunEvent};
use crate::scene::{ContactSolver, Scene};
use serde::{Deserialize, Serialize};

/// Per-block results (docs/format.md §3).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct BlockSummary {
    pub id: String,
    /// m, largest centroid displacement magnitude over the run.
    pub max_displacement: f64,
    /// m, [x, y] centroid displacement at the end.
    pub final_displacement: [f64; 2],
    /// rad, largest |rotation|.
    pub max_rotation: f64,
    /// rad, counter-clockwise positive.
    pub final_rotation: f64,
    /// |final rotation| > 30°.
    pub toppled: bool,
    /// m, accumulated slip of the block's sliding contacts.
    pub sliding_distance: f64,
    /// The block's model (`"rigid"`, `"deformable"`), only when the free blocks' models or
    /// reasons differ (the summary's `block_model_reason` is then absent).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub block_model: Option<String>,
    /// Why this block got its model (`scene::block_model`), with `block_model`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub block_model_reason: Option<String>,
}

/// Solver diagnostics reported with every run.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, Default)]
pub struct Diagnostics {
    /// N/m, the value used (resolved when "auto"); absent when no penalty springs ran (a
    /// reduced model, or the dual contact solver).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub penalty_stiffness: Option<f64>,
    pub time_step_cuts: u64,
    /// m, deepest penetration seen after a converged step.
    pub max_penetration: f64,
    /// Open–close iterations per step; absent when the open–close iteration did not run (a
    /// reduced model, or the dual contact solver).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub open_close_iterations_mean: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub min_time_step: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub max_time_step: Option<f64>,
    /// Rocking model only: the ratio of angular velocities after/before an impact used.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub restitution: Option<f64>,
    /// Rocking model only: number of impacts (changes of pivot).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub impacts: Option<u64>,
    /// Dual contact solver only: stalled solves accepted under
    /// `control.dual_stall_acceptance` (0 with the default, which accepts none).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub dual_loose_solves: Option<u64>,
    /// Dual contact solver only: m, the largest remaining violation of an accepted stalled
    /// solve (0 when none was accepted).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub dual_loose_residual: Option<f64>,
    /// The run's duration stopped before the end of the record (docs/run-end.md).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub record_truncated: Option<RecordTruncated>,
}

/// The layout of a run's outputs, `summary.json`'s `format`: version 2 added the `units`
/// objects and the unit suffixes of the `histories.csv` header (`time_s`, `<id>.x_m`, ...).
/// A summary without `format` is version 1 (header `time,<id>.x,<id>.y,<id>.rotation`).
pub const RUN_OUTPUTS_FORMAT: &str = "ashlar.run/2";

/// `summary.json` (docs/format.md §3, with the unit of every field).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Summary {
    /// [`RUN_OUTPUTS_FORMAT`]; empty when read from a version-1 summary.
    #[serde(default)]
    pub format: String,
    pub completed: bool,
    /// s, rounded to the nanosecond (the accumulated steps carry float noise below that).
    pub simulated_time: f64,
    pub steps: u64,
    pub wall_time_s: f64,
    /// m/s², peak horizontal ground acceleration applied.
    pub pga: f64,
    pub failure_mode: String,
    pub blocks: Vec<BlockSummary>,
    pub diagnostics: Diagnostics,
    pub model: String,
    pub model_reason: String,
    /// Why the free blocks have the model `control.block_model` reports (`scene::block_model`;
    /// the reduced models: they are rigid-block models). Absent when the free blocks differ:
    /// each block then reports its own (`blocks[].block_model_reason`).
    #[serde(default, skip_serializing_if = "String::is_empty")]
    pub block_model_reason: String,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub stopped_reason: Option<String>,
    /// The controls that ran ([`reported_control`]).
    #[serde(default)]
    pub control: serde_json::Value,
    /// The unit of every numeric field, mirroring the summary's nesting ([`summary_units`]).
    #[serde(default)]
    pub units: serde_json::Value,
    /// Every free block was at rest (or had left the scene) at the end: the outcome cannot
    /// change any more (docs/run-end.md).
    #[serde(default)]
    pub settled: bool,
    /// Blocks retired during the run (docs/run-end.md).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub events: Vec<RunEvent>,
}

/// The `units` object of `summary.json`: each numeric field's unit, nested as the summary is
/// ("1" for a ratio, "count" for a number of events). `pga` is the horizontal peak applied.
pub fn summary_units() -> serde_json::Value {
    serde_json::json!({
        "simulated_time": "s",
        "steps": "count",
        "wall_time_s": "s",
        "pga": "m/s2",
        "blocks": {
            "max_displacement": "m",
            "final_displacement": "m",
            "max_rotation": "rad",
            "final_rotation": "rad",
            "sliding_distance": "m",
        },
        "diagnostics": {
            "penalty_stiffness": "N/m",
            "time_step_cuts": "count",
            "max_penetration": "m",
            "open_close_iterations_mean": "1",
            "min_time_step": "s",
            "max_time_step": "s",
            "restitution": "1",
            "impacts": "count",
            "dual_loose_solves": "count",
            "dual_loose_residual": "m",
            "record_truncated": { "record_duration": "s", "run_duration": "s" },
        },
        "events": { "time": "s" },
        "control": {
            "duration": "s",
            "time_step": "s",
            "max_displacement_ratio": "1",
            "penalty_stiffness": "N/m",
            "dynamic_factor": "1",
            "kinetic_damping_rate": "1/s",
            "output_interval": "s",
            "max_steps": "count",
            "dual_tolerance": "1",
            "dual_stall_acceptance": "1",
            "unconverged_floor": "1",
            "restitution": "1",
        },
    })
}

/// What ran, for [`reported_control`].
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Ran {
    /// The full DDA engine.
    Engine,
    /// A reduced (rigid rocking/sliding) model.
    Reduced,
}

/// The controls a run reports: those that ran. The scene's `control.block_model` is only the
/// default for blocks that do not name their own, so the reported `block_model` is the one the
/// free blocks used (`"mixed"` when they differ); the dual solver has no penalty springs, the
/// penalty solver no dual tolerances; a reduced model treats its block as rigid and uses none
/// of the engine's controls (only `duration`, `output_interval`, `model` and `restitution`).
pub fn reported_control(scene: &Scene, ran: Ran) -> serde_json::Value {
    let mut v = serde_json::to_value(&scene.control).unwrap_or_default();
    let Some(obj) = v.as_object_mut() else {
        return v;
    };
    match ran {
        Ran::Reduced => {
            obj.retain(|k, _| {
                matches!(
                    k.as_str(),
                    "duration" | "output_interval" | "model" | "restitution"
                )
            });
            obj.insert("block_model".into(), "rigid".into());
        }
        Ran::Engine => {
            let mut models = scene.blocks.iter().filter_map(|b| match b.kind {
                crate::scene::BlockKind::Free(m) => Some(m),
                _ => None,
            });
            let first = models.next();
            let name = match first {
                Some(m) if models.all(|x| x == m) => serde_json::to_value(m).unwrap_or_default(),
                Some(_) => "mixed".into(),
                None => serde_json::to_value(scene.control.block_model).unwrap_or_default(),
            };
            obj.insert("block_model".into(), name);
            if scene.control.contact_solver == ContactSolver::Dual {
                obj.remove("penalty_stiffness");
            } else {
                obj.remove("dual_tolerance");
                obj.remove("dual_stall_acceptance");
            }
        }
    }
    v
}
