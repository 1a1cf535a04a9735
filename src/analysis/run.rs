//! One run of a scene under a ground motion: drives the simulation to the end, records frames
//! (histories, trajectory), classifies the outcome and writes `summary.json` (docs/format.md §3).
//!
//! Length (over 600 lines): one run from start to end reads in order here (the model choice,
//! the engine loop with its frames and their writers, the summary filled from the tracker);
//! what a run reports is `run_summary.rs`, its end `run_end.rs`, the reduced models `reduced/`.
use crate::analysis::reduced::{
    self, record::ReducedError, Modes, ReducedParams, Restitution, SingleBlock,
};
use crate::analysis::run_end::{self, RunEndParams, RunEvent, SettleWatch};
use crate::contact::{ContactState, Mobility};
use crate::motion::GroundMotion;
pub use crate::record::histories::round_time;
use crate::record::histories::HistoryWriter;
use crate::record::mcap::{McapParams, McapRecorder};
use crate::record::RecordError;
use crate::record::{
    BlockFrame, BlockMotionState, Frame, FrameBlockKind, GroundFrame, RecordHeader,
};
use crate::scene::{ContactSolver, ModelChoice, Scene};
use crate::simulation::{SimError, SimParams, Simulation};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::Instant;

pub use crate::analysis::run_summary::{
    reported_control, summary_units, BlockSummary, Diagnostics, Ran, Summary, RUN_OUTPUTS_FORMAT,
};

/// Hooks a caller (CLI, service worker, PGA search) passes to a run.
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
    /// Stop early once this returns true for the running summary (PGA search: the criterion
    /// is decided). The summary then has `stopped_reason: "decided"`.
    pub stop_when: Option<&'a (dyn Fn(&Tracker) -> bool + Sync)>,
    /// Engine knobs (defaults when `None`).
    pub sim_params: Option<SimParams>,
    /// Called with every recorded frame (studies compare histories without files).
    pub on_frame: Option<&'a (dyn Fn(&Frame) + Sync)>,
    /// Knobs of the reduced models (defaults when `None`).
    pub reduced_params: Option<ReducedParams>,
    /// Knobs of the end of the run: settling, continuation cap (defaults when `None`).
    pub run_end: Option<RunEndParams>,
    /// When `auto`'s reduced model meets a case it does not represent, the full engine starts
    /// from the reduced model's state at the last record sample it passed within its
    /// assumptions (`analysis::run_fallback`; a run that writes frames gets the reduced
    /// model's before that sample, the engine's after). Set this to start it at t = 0 instead
    /// (as before session 32; as accurate against the engine at Δt = 1e-4 s, 2–4× the CPU:
    /// docs/speed.md). Runs and PGA searches take the same default (the search's runs use
    /// it), so a run at a bracket end reproduces the search's verdict.
    pub fallback_from_zero: bool,
    /// After such a hand-over, once the engine's block is at rest on its base again, the
    /// reduced model takes the run back from there (`analysis::run_fallback::HandBackParams`;
    /// `None`: the defaults, on).
    pub hand_back: Option<super::run_fallback::HandBackParams>,
    /// End a full-engine run before its duration once the ground is still for the rest of the
    /// run and the structure has stayed settled under it for `RunEndParams::settle_window`
    /// (`run_end::may_end_still`; `stopped_reason` "settled, ground still"). Set by the PGA
    /// search's runs, whose verdict cannot change from there (a run at PGA 0, the lattice's
    /// first point, ends once the structure has settled under gravity); `ashlar run` and the
    /// service's runs keep their full length (their histories and final state are outputs).
    pub end_when_still: bool,
    /// Called after every step of a full-engine run; returning true ends the run there with
    /// `stopped_reason` "handed back" (set by `analysis::run_fallback` only).
    pub engine_at_rest: Option<&'a (dyn Fn(&Simulation) -> bool + Sync)>,
}

/// How a run can fail, by cause; each message names where (docs/architecture.md, "Errors").
#[derive(Debug, thiserror::Error)]
pub enum RunError {
    /// The scene gives no `control.duration` and the motion has no record length to take it
    /// from.
    #[error("control.duration: required when the ground motion has no record length")]
    NoDuration,
    /// A history block asked for (`RunOptions::history_blocks`) is not a free block.
    #[error("history block {id:?}: no free block with that id")]
    HistoryBlock { id: String },
    /// A PGA search, multi-record search or site analysis asked for something it cannot do.
    #[error(transparent)]
    Search(#[from] super::pga::SearchError),
    /// A multi-record search's request fails on one record.
    #[error("record {record:?}: {source}")]
    RecordSearch {
        record: String,
        #[source]
        source: super::pga::SearchError,
    },
    /// The caller's cancel flag stopped a search between its runs (the text is what the
    /// service's job shows).
    #[error("cancelled")]
    Cancelled,
    /// `control.model` forces a reduced model (`"rocking"`, `"sliding"`) that cannot represent
    /// the scene; `why` says what disqualifies it.
    #[error("control.model: the scene does not qualify for the reduced {model:?} model: {why}")]
    ModelNotApplicable {
        model: &'static str,
        why: super::reduced::NotReducible,
    },
    /// The engine stopped with a typed diagnostic saying when, where and what to change.
    #[error("simulation failed: {0}")]
    Simulation(#[from] SimError),
    /// The engine stopped on one record of a multi-record PGA search.
    #[error("simulation failed: record {record:?}: {source}")]
    RecordSimulation {
        record: String,
        #[source]
        source: SimError,
    },
    /// Writing a record file (`histories.csv`, `trajectory.mcap`) failed.
    #[error("writing outputs: {0}")]
    Record(#[from] RecordError),
    /// Creating the output directory or writing `summary.json` in it failed.
    #[error("writing outputs: {}: {source}", dir.display())]
    Output {
        dir: PathBuf,
        #[source]
        source: std::io::Error,
    },
}

impl RunError {
    /// A failure to create `dir` or write into it.
    pub(crate) fn output(dir: &Path, source: std::io::Error) -> Self {
        RunError::Output {
            dir: dir.to_path_buf(),
            source,
        }
    }
}

/// Outcome of a run that was not an error.
#[derive(Debug, Clone)]
pub struct RunOutcome {
    pub summary: Summary,
    pub cancelled: bool,
}

/// Thresholds of the outcome classification. Each default says why.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FailureParams {
    /// |rotation| beyond which a block has toppled: docs/format.md fixes 30°.
    pub toppled_rotation: f64,
    /// Sliding distance (m) that counts as sliding: 1 mm is above the contact springs'
    /// elastic slip and below any displacement an archaeologist would record.
    pub sliding_distance: f64,
    /// Fraction of free blocks that must topple or slide for "collapse".
    pub collapse_fraction: f64,
    /// Angular speed (rad/s) above which a block is drawn as rocking.
    pub rocking_speed: f64,
}

impl Default for FailureParams {
    fn default() -> Self {
        Self {
            toppled_rotation: 30f64.to_radians(),
            sliding_distance: 1e-3,
            collapse_fraction: 0.5,
            rocking_speed: 1e-2,
        }
    }
}

impl FailureParams {
    /// What a free block is drawn as in a frame: toppled past `toppled_rotation` (rad, from
    /// its place in the scene), else rocking above `rocking_speed` (rad/s), else sliding if its
    /// model says so, else at rest. One rule for the engine's, the reduced model's and a
    /// handed-over run's frames.
    pub fn motion_state(
        &self,
        rotation: f64,
        angular_velocity: f64,
        sliding: bool,
    ) -> BlockMotionState {
        if rotation.abs() > self.toppled_rotation {
            BlockMotionState::Toppled
        } else if angular_velocity.abs() > self.rocking_speed {
            BlockMotionState::Rocking
        } else if sliding {
            BlockMotionState::Sliding
        } else {
            BlockMotionState::AtRest
        }
    }
}

/// Running per-block extremes, updated after every step.
#[derive(Debug, Clone, Default)]
pub struct Tracker {
    /// Scene indices of the free blocks, in scene order.
    pub free: Vec<usize>,
    pub max_displacement: Vec<f64>,
    pub max_rotation: Vec<f64>,
    pub sliding_distance: Vec<f64>,
    pub final_displacement: Vec<[f64; 2]>,
    pub final_rotation: Vec<f64>,
    pub ids: Vec<String>,
}

impl Tracker {
    fn new(sim: &Simulation) -> Self {
        let free: Vec<usize> = (0..sim.geoms().len())
            .filter(|&b| sim.mobility()[b] == Mobility::Free)
            .collect();
        let n = free.len();
        Self {
            ids: free
                .iter()
                .map(|&b| sim.scene().blocks[b].id.clone())
                .collect(),
            free,
            max_displacement: vec![0.0; n],
            max_rotation: vec![0.0; n],
            sliding_distance: vec![0.0; n],
            final_displacement: vec![[0.0; 2]; n],
            final_rotation: vec![0.0; n],
        }
    }

    fn update(&mut self, sim: &Simulation) {
        for (k, &b) in self.free.iter().enumerate() {
            let g = &sim.geoms()[b];
            let d = g.centroid - g.initial_centroid;
            self.final_displacement[k] = [d.x, d.y];
            self.final_rotation[k] = g.rotation;
            self.max_displacement[k] = self.max_displacement[k].max(d.norm());
            self.max_rotation[k] = self.max_rotation[k].max(g.rotation.abs());
        }
        // Slip of sliding contacts, charged to the block(s) that carry unknowns; the largest
        // slip of a block's contacts in the step (contacts of one face slide together).
        let mut step_slip = vec![0.0f64; sim.geoms().len()];
        for c in &sim.contacts().contacts {
            if let ContactState::Sliding { .. } = c.state {
                let s = c.slip.abs();
                step_slip[c.vertex_block] = step_slip[c.vertex_block].max(s);
                step_slip[c.edge_block] = step_slip[c.edge_block].max(s);
            }
        }
        for (k, &b) in self.free.iter().enumerate() {
            self.sliding_distance[k] += step_slip[b];
        }
    }

    /// Index among free blocks of a block id.
    pub fn index_of(&self, id: &str) -> Option<usize> {
        self.ids.iter().position(|i| i == id)
    }
}

/// Resolve the run's duration (s).
pub fn duration(scene: &Scene, motion: &GroundMotion) -> Result<f64, RunError> {
    match (scene.control.duration, motion.duration()) {
        (Some(d), _) => Ok(d),
        (None, Some(r)) => Ok(r + 2.0),
        (None, None) => Err(RunError::NoDuration),
    }
}

/// The model a run uses, decided from the scene alone (docs/format.md §1 `control.model`).
#[derive(Debug, Clone)]
pub enum ModelPlan {
    /// The full DDA engine, and why.
    Dda(String),
    /// A reduced model of the single block, which motions it may use, and why.
    Reduced {
        block: Box<SingleBlock>,
        modes: Modes,
        reason: String,
    },
}

/// Which model runs, and why (a forced reduced model on a scene it cannot represent is an
/// error naming the reason).
pub fn choose_model(scene: &Scene, params: &ReducedParams) -> Result<ModelPlan, RunError> {
    let law = match params.restitution {
        Restitution::Housner => "Housner's angular-momentum impact law",
        Restitution::Coefficient(_) => "a given restitution coefficient",
    };
    let describe = |b: &SingleBlock, modes: Modes| {
        let e = reduced::rocking::restitution(b, 0, params.restitution);
        let (a0, a1) = (b.slenderness(0), b.slenderness(1));
        let raw = reduced::rocking::housner_ratio(b, 0);
        let impact = if params.restitution == Restitution::Housner && raw < 0.0 {
            format!(
                "{law} does not apply to a block this squat (it gives {raw:.4} < 0: the angular momentum about the landing corner would turn the block back into its base, so it does not rock onto that corner): an impact ends the rocking, e = 0"
            )
        } else {
            format!(
                "{law}, e = {e:.4} (1 − 1.5 sin²α = {:.4} for a rectangle)",
                1.0 - 1.5 * a0.sin().powi(2)
            )
        };
        let rock = format!(
            "Housner's rocking equation (slenderness α = {:.2}°/{:.2}°) with {impact}",
            a0.to_degrees(),
            a1.to_degrees(),
        );
        let slide = format!(
            "rigid-plastic Newmark sliding (μ = tan φ = {:.4}, contact slope {:.2}°)",
            b.mu,
            b.slope.to_degrees()
        );
        match modes {
            Modes::Rocking => rock,
            Modes::Sliding => slide,
            Modes::Auto => format!("{rock}, or {slide}, whichever the first-motion check starts"),
        }
    };
    match scene.control.model {
        ModelChoice::Dda => Ok(ModelPlan::Dda(
            "control.model is \"dda\": the full DDA engine".into(),
        )),
        ModelChoice::Auto => match reduced::qualify(scene, params) {
            Ok(b) => {
                let reason = format!(
                    "control.model is \"auto\" and the scene is one rigid block on a {} base: {}{}",
                    if b.driven { "driven" } else { "fixed" },
                    describe(&b, Modes::Auto),
                    reduced::engine_controls_note(scene)
                );
                Ok(ModelPlan::Reduced {
                    block: Box::new(b),
                    modes: Modes::Auto,
                    reason,
                })
            }
            Err(why) => Ok(ModelPlan::Dda(format!(
                "control.model is \"auto\" but no reduced model represents the scene ({why}): the full DDA engine ran"
            ))),
        },
        ModelChoice::Rocking | ModelChoice::Sliding => {
            let (name, modes) = if scene.control.model == ModelChoice::Rocking {
                ("rocking", Modes::Rocking)
            } else {
                ("sliding", Modes::Sliding)
            };
            let b = reduced::qualify(scene, params)
                .map_err(|why| RunError::ModelNotApplicable { model: name, why })?;
            let reason = format!(
                "control.model is \"{name}\": {}{}",
                describe(&b, modes),
                reduced::engine_controls_note(scene)
            );
            Ok(ModelPlan::Reduced {
                block: Box::new(b),
                modes,
                reason,
            })
        }
    }
}

pub(crate) struct Writers {
    histories: Option<HistoryWriter<std::io::BufWriter<std::fs::File>>>,
    mcap: Option<McapRecorder>,
}

impl Writers {
    pub(crate) fn open(
        out: Option<&Path>,
        header: &RecordHeader,
        no_trajectory: bool,
    ) -> Result<Self, RunError> {
        let Some(dir) = out else {
            return Ok(Self {
                histories: None,
                mcap: None,
            });
        };
        std::fs::create_dir_all(dir).map_err(|e| RunError::output(dir, e))?;
        let histories = Some(HistoryWriter::create(&dir.join("histories.csv"), header)?);
        let mcap = if no_trajectory {
            None
        } else {
            Some(McapRecorder::create(
                &dir.join("trajectory.mcap"),
                header,
                &McapParams::default(),
            )?)
        };
        Ok(Self { histories, mcap })
    }

    pub(crate) fn write(&mut self, frame: &Frame) -> Result<(), RunError> {
        if let Some(h) = &mut self.histories {
            h.write_frame(frame)?;
        }
        if let Some(m) = &mut self.mcap {
            m.write_frame(frame)?;
        }
        Ok(())
    }

    /// Record one frame, hand it to the caller's `on_frame` and report `progress` (0..1, none
    /// for the initial frame): the per-frame duties of every run loop, DDA or reduced.
    /// Does [`Writers::emit`] use the frame (a file to write, or `opts.on_frame`)? A run
    /// without either (a PGA search's runs) need not build its frames.
    pub(crate) fn wants_frames(&self, opts: &RunOptions) -> bool {
        self.histories.is_some() || self.mcap.is_some() || opts.on_frame.is_some()
    }

    pub(crate) fn emit(
        &mut self,
        frame: &Frame,
        opts: &RunOptions,
        progress: Option<f64>,
    ) -> Result<(), RunError> {
        self.write(frame)?;
        if let Some(cb) = opts.on_frame {
            cb(frame);
        }
        if let (Some(p), Some(x)) = (opts.progress, progress) {
            p(x.min(1.0));
        }
        Ok(())
    }

    pub(crate) fn finish(self) -> Result<(), RunError> {
        if let Some(h) = self.histories {
            h.finish()?;
        }
        if let Some(m) = self.mcap {
            m.finish()?;
        }
        Ok(())
    }
}

/// Run `scene` under `motion`.
pub fn run(
    scene: &Scene,
    motion: &GroundMotion,
    opts: &RunOptions,
) -> Result<RunOutcome, RunError> {
    let rparams = opts.reduced_params.unwrap_or_default();
    match choose_model(scene, &rparams)? {
        ModelPlan::Dda(reason) => run_dda(scene, motion, opts, reason),
        ModelPlan::Reduced {
            block,
            modes,
            reason,
        } => match reduced::record::run(scene, motion, opts, *block, modes, rparams, &reason) {
            Ok(outcome) => Ok(outcome),
            Err(ReducedError::Run(e)) => Err(e),
            Err(ReducedError::Violation(v, resume)) => {
                let reason = format!(
                    "control.model is \"auto\" and the scene is one block on a base, but the first-motion check found a case the reduced models do not represent ({}): the full DDA engine ran",
                    v.what
                );
                match resume.filter(|_| !opts.fallback_from_zero) {
                    Some(r) => super::run_fallback::from_rest(scene, motion, opts, reason, &r),
                    None => run_dda(scene, motion, opts, reason),
                }
            }
        },
    }
}

/// `stopped_reason` of an engine run ended by `RunOptions::engine_at_rest`.
pub(crate) const HANDED_BACK: &str = "handed back";

/// `stopped_reason` of an engine run ended by `RunOptions::end_when_still`.
pub const SETTLED_STILL: &str = "settled, ground still";

/// Run the full DDA engine.
pub(crate) fn run_dda(
    scene: &Scene,
    motion: &GroundMotion,
    opts: &RunOptions,
    model_reason: String,
) -> Result<RunOutcome, RunError> {
    let wall = Instant::now();
    let model = "dda".to_string();
    let duration = duration(scene, motion)?;
    let params = opts.sim_params.unwrap_or_default();
    let failure = FailureParams::default();
    let end = opts.run_end.unwrap_or_default();
    // The run goes on after `duration` while the structure moves, up to the cap.
    let cap = run_end::cap(duration, motion, &end);
    let floor = run_end::retirement_floor(scene);
    let still = opts
        .end_when_still
        .then(|| run_end::still_from(scene, motion))
        .flatten();
    let mut events = Vec::new();
    let mut watch = SettleWatch::default();
    let mut settled = false;
    let mut sim = Simulation::new(scene, motion, params);
    let header = header(&sim, motion, opts)?;
    let mut writers = Writers::open(opts.out_dir, &header, opts.no_trajectory)?;
    let mut tracker = Tracker::new(&sim);
    let interval = scene.control.output_interval;
    let mut frame_index: u64 = 0;
    writers.emit(&frame(&sim, &failure), opts, None)?;
    let mut stopped_reason = None;
    let mut cancelled = false;
    let mut sim_error = None;
    while sim.time() < cap - 1e-12 {
        if opts.cancel.is_some_and(|c| c.load(Ordering::Relaxed)) {
            cancelled = true;
            stopped_reason = Some("cancelled".to_string());
            break;
        }
        if sim.stats().steps >= scene.control.max_steps {
            stopped_reason = Some(format!(
                "step budget of {} steps reached (control.max_steps)",
                scene.control.max_steps
            ));
            break;
        }
        let next_frame =
            ((frame_index + 1) as f64 * interval).min(run_end::horizon(sim.time(), duration, cap));
        if let Err(e) = sim.step(next_frame - sim.time()) {
            sim_error = Some(e);
            break;
        }
        events.extend(run_end::retire_fallen(&mut sim, floor));
        tracker.update(&sim);
        settled = watch.update(
            sim.time(),
            run_end::all_quiet(&sim, &end),
            end.settle_window,
        );
        if run_end::may_end_still(still, watch.quiet_since(), sim.time(), end.settle_window)
            && sim.time() < duration
        {
            stopped_reason = Some(SETTLED_STILL.to_string());
            break;
        }
        if sim.time() >= next_frame - 1e-9 * interval {
            frame_index += 1;
            writers.emit(&frame(&sim, &failure), opts, Some(sim.time() / duration))?;
            if run_end::may_end(sim.time(), duration, settled) {
                break;
            }
        }
        if opts.stop_when.is_some_and(|f| f(&tracker)) {
            stopped_reason = Some("decided".to_string());
            break;
        }
        if opts.engine_at_rest.is_some_and(|f| f(&sim)) {
            stopped_reason = Some(HANDED_BACK.to_string());
            break;
        }
    }
    writers.finish()?;
    if let Some(e) = sim_error {
        return Err(RunError::Simulation(e));
    }
    let mut summary = summarize(
        &sim,
        &tracker,
        motion,
        &failure,
        wall.elapsed().as_secs_f64(),
        stopped_reason,
        model,
        model_reason,
        duration,
    );
    end_summary(&mut summary, settled, events, duration, motion);
    if let Some(dir) = opts.out_dir {
        write_summary(dir, &summary)?;
    }
    Ok(RunOutcome { summary, cancelled })
}

/// Write `summary.json` into `dir` (pretty JSON and a final newline).
pub(crate) fn write_summary(dir: &Path, summary: &Summary) -> Result<(), RunError> {
    let text = serde_json::to_string_pretty(summary)
        .map_err(|e| RunError::output(dir, std::io::Error::other(e)))?;
    std::fs::write(dir.join("summary.json"), text + "\n").map_err(|e| RunError::output(dir, e))
}

fn header(
    sim: &Simulation,
    motion: &GroundMotion,
    opts: &RunOptions,
) -> Result<RecordHeader, RunError> {
    let scene = sim.scene();
    let history_blocks = match &opts.history_blocks {
        None => (0..scene.blocks.len())
            .filter(|&b| sim.mobility()[b] == Mobility::Free)
            .collect(),
        Some(ids) => ids
            .iter()
            .map(|id| {
                scene
                    .block_index(id)
                    .filter(|&b| sim.mobility()[b] == Mobility::Free)
                    .ok_or_else(|| RunError::HistoryBlock { id: id.clone() })
            })
            .collect::<Result<Vec<_>, _>>()?,
    };
    let mut metadata = std::collections::BTreeMap::new();
    metadata.insert(
        "scene".into(),
        serde_json::to_string(&scene.spec).unwrap_or_default(),
    );
    metadata.insert("motion_provenance".into(), motion.provenance.clone());
    metadata.insert("motion_scale".into(), format!("{}", motion.scale));
    metadata.insert("pga_m_s2".into(), format!("{}", motion.pga()));
    // The controls that run (as summary.json reports them), and the springs only when the
    // penalty solver uses them.
    metadata.insert(
        "solver".into(),
        reported_control(scene, Ran::Engine).to_string(),
    );
    if scene.control.contact_solver != ContactSolver::Dual {
        metadata.insert(
            "penalty_stiffness".into(),
            format!("{}", sim.springs().normal),
        );
    }
    metadata.insert("code_version".into(), env!("CARGO_PKG_VERSION").into());
    Ok(RecordHeader {
        block_ids: scene.blocks.iter().map(|b| b.id.clone()).collect(),
        block_kinds: sim
            .mobility()
            .iter()
            .map(|m| match m {
                Mobility::Fixed => FrameBlockKind::Fixed,
                Mobility::Driven => FrameBlockKind::Driven,
                Mobility::Free => FrameBlockKind::Free,
            })
            .collect(),
        history_blocks,
        metadata,
    })
}

fn frame(sim: &Simulation, failure: &FailureParams) -> Frame {
    let mut sliding = vec![false; sim.geoms().len()];
    for c in &sim.contacts().contacts {
        if let ContactState::Sliding { .. } = c.state {
            sliding[c.vertex_block] = true;
            sliding[c.edge_block] = true;
        }
    }
    let blocks = sim
        .geoms()
        .iter()
        .enumerate()
        .map(|(b, g)| {
            let d = g.centroid - g.initial_centroid;
            let v = sim.block_velocity(b);
            let state = if sim.mobility()[b] != Mobility::Free {
                BlockMotionState::AtRest
            } else {
                failure.motion_state(g.rotation, v[2], sliding[b])
            };
            BlockFrame {
                x: d.x,
                y: d.y,
                rotation: g.rotation,
                vx: v[0],
                vy: v[1],
                angular_velocity: v[2],
                state,
                outline: g.vertices.iter().map(|p| [p.x, p.y]).collect(),
            }
        })
        .collect();
    let gs = sim.motion().state(sim.time());
    Frame {
        time: sim.time(),
        blocks,
        ground: GroundFrame {
            acceleration: gs[0],
            velocity: gs[1],
            displacement: gs[2],
        },
    }
}

/// The end of the run in its summary: settled, the verdict of a structure still moving,
/// retirement events (retired blocks fell off the structure: they count as toppled), a
/// truncated record.
pub(crate) fn end_summary(
    summary: &mut Summary,
    settled: bool,
    events: Vec<RunEvent>,
    duration: f64,
    motion: &GroundMotion,
) {
    for e in &events {
        if let Some(b) = summary.blocks.iter_mut().find(|b| b.id == e.block) {
            b.toppled = true;
        }
    }
    let mode = failure_mode(&summary.blocks, &FailureParams::default());
    summary.failure_mode = run_end::verdict(mode, settled).into();
    summary.settled = settled;
    summary.events = events;
    summary.diagnostics.record_truncated = run_end::truncation(duration, motion);
    // The duration that ran (the scene's, or the record's length + 2 s when it sets none),
    // not the scene's unset `null`: the reported controls are those that ran.
    if let Some(control) = summary.control.as_object_mut() {
        control.insert("duration".into(), round_time(duration).into());
    }
}

/// Classify the outcome from the per-block results.
pub fn failure_mode(blocks: &[BlockSummary], failure: &FailureParams) -> &'static str {
    let n = blocks.len().max(1) as f64;
    let toppled = blocks.iter().filter(|b| b.toppled).count();
    let slid = blocks
        .iter()
        .filter(|b| b.sliding_distance > failure.sliding_distance)
        .count();
    let moved = blocks
        .iter()
        .filter(|b| b.toppled || b.sliding_distance > failure.sliding_distance)
        .count();
    if blocks.len() > 1 && moved as f64 / n > failure.collapse_fraction && toppled > 0 {
        "collapse"
    } else if toppled > 0
        && blocks
            .iter()
            .any(|b| b.toppled && b.sliding_distance > failure.sliding_distance)
    {
        "sliding_toppling"
    } else if toppled > 0 {
        "toppling"
    } else if slid > 0 {
        "sliding"
    } else {
        "stable"
    }
}

#[allow(clippy::too_many_arguments)]
fn summarize(
    sim: &Simulation,
    tr: &Tracker,
    motion: &GroundMotion,
    failure: &FailureParams,
    wall: f64,
    stopped_reason: Option<String>,
    model: String,
    model_reason: String,
    duration: f64,
) -> Summary {
    let blocks: Vec<BlockSummary> = (0..tr.free.len())
        .map(|k| BlockSummary {
            id: tr.ids[k].clone(),
            max_displacement: tr.max_displacement[k],
            final_displacement: tr.final_displacement[k],
            max_rotation: tr.max_rotation[k],
            final_rotation: tr.final_rotation[k],
            toppled: tr.final_rotation[k].abs() > failure.toppled_rotation,
            sliding_distance: tr.sliding_distance[k],
            block_model: None,
            block_model_reason: None,
        })
        .collect();
    let mut blocks = blocks;
    let scene = sim.scene();
    let common =
        crate::scene::block_model::scene_summary(&scene.blocks, &scene.block_model_reasons);
    if common.is_none() {
        for (b, &i) in blocks.iter_mut().zip(&tr.free) {
            if let crate::scene::BlockKind::Free(m) = scene.blocks[i].kind {
                b.block_model = serde_json::to_value(m)
                    .ok()
                    .and_then(|v| v.as_str().map(String::from));
                b.block_model_reason = Some(scene.block_model_reasons[i].clone());
            }
        }
    }
    let block_model_reason = common.map(|(_, r)| r).unwrap_or_default();
    let st = &sim.stats();
    let dual = sim.scene().control.contact_solver == ContactSolver::Dual;
    Summary {
        format: RUN_OUTPUTS_FORMAT.into(),
        completed: stopped_reason.is_none() && sim.time() >= duration - 1e-9,
        simulated_time: round_time(sim.time()),
        steps: st.steps,
        wall_time_s: wall,
        pga: motion.pga(),
        failure_mode: failure_mode(&blocks, failure).into(),
        blocks,
        diagnostics: Diagnostics {
            penalty_stiffness: (!dual).then_some(sim.springs().normal),
            time_step_cuts: st.time_step_cuts,
            max_penetration: st.max_penetration,
            open_close_iterations_mean: (!dual).then_some(if st.steps > 0 {
                st.open_close_iterations as f64 / st.steps as f64
            } else {
                0.0
            }),
            min_time_step: (st.steps > 0).then_some(st.min_dt),
            max_time_step: (st.steps > 0).then_some(st.max_dt),
            dual_loose_solves: dual.then_some(st.dual_loose_solves),
            dual_loose_residual: dual.then_some(st.dual_loose_residual),
            ..Default::default()
        },
        model,
        model_reason,
        block_model_reason,
        stopped_reason,
        control: reported_control(sim.scene(), Ran::Engine),
        units: summary_units(),
        settled: false,
        events: Vec::new(),
    }
}
