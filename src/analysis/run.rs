//! One run of a scene under a ground motion, with outputs written to a directory.
use crate::motion::GroundMotion;
use crate::scene::Scene;
use serde::{Deserialize, Serialize};
use std::path::Path;
use std::sync::atomic::AtomicBool;

/// Per-block results (FORMAT.md §3).
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
    /// m, path length of sliding along contacts.
    pub sliding_distance: f64,
}

/// Solver diagnostics reported with every run.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, Default)]
pub struct Diagnostics {
    /// N/m, the value used (resolved when "auto").
    pub penalty_stiffness: f64,
    pub time_step_cuts: u64,
    /// m, deepest penetration seen.
    pub max_penetration: f64,
    pub open_close_iterations_mean: f64,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub min_time_step: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub max_time_step: Option<f64>,
}

/// `summary.json` (FORMAT.md §3).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Summary {
    pub completed: bool,
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
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub stopped_reason: Option<String>,
    /// The controls actually used.
    #[serde(default)]
    pub control: serde_json::Value,
}

/// Hooks a caller (CLI, service worker) passes to a run.
#[derive(Default)]
pub struct RunOptions<'a> {
    /// Where `summary.json`, `histories.csv` and `trajectory.mcap` go; `None` writes nothing.
    pub out_dir: Option<&'a Path>,
    /// Set to true to stop the run at the next step (the outputs stay valid, shorter).
    pub cancel: Option<&'a AtomicBool>,
    /// Called with simulated time / duration in [0, 1], at most every output frame.
    pub progress: Option<&'a (dyn Fn(f64) + Sync)>,
    /// Block ids whose histories are written (`None`: every free block).
    pub history_blocks: Option<Vec<String>>,
    /// Skip writing `trajectory.mcap`.
    pub no_trajectory: bool,
}

/// How a run can fail (the message names where).
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum RunError {
    #[error("{0}")]
    Invalid(String),
    #[error("simulation failed: {0}")]
    Simulation(String),
    #[error("writing outputs: {0}")]
    Io(String),
}

/// Outcome of a run that was not an error.
#[derive(Debug, Clone)]
pub struct RunOutcome {
    pub summary: Summary,
    pub cancelled: bool,
}

/// Run `scene` under `motion`. Provisional until the engine lands: fails with a clear error.
pub fn run(scene: &Scene, motion: &GroundMotion, opts: &RunOptions) -> Result<RunOutcome, RunError> {
    let _ = (scene, motion, opts);
    Err(RunError::Simulation("the engine is not wired yet".into()))
}
