//! Reduced models, outputs: drives a [`Reduced`] model frame by frame and writes the same
//! outputs as a DDA run (summary, histories, trajectory) through `analysis::run`'s writers.
use super::{Modes, Phase, Reduced, ReducedParams, SingleBlock, Violation};
use crate::analysis::run::{
    duration, end_summary, failure_mode, reported_control, round_time, summary_units, BlockSummary,
    Diagnostics, FailureParams, Ran, RunError, RunOptions, RunOutcome, Summary, Tracker, Writers,
    RUN_OUTPUTS_FORMAT,
};
use crate::analysis::run_end;
use crate::motion::GroundMotion;
use crate::record::{
    BlockFrame, BlockMotionState, Frame, FrameBlockKind, GroundFrame, RecordHeader,
};
use crate::scene::Scene;
use nalgebra::Vector2;
use std::sync::atomic::Ordering;
use std::time::Instant;

/// How a reduced run ended when it did not produce an outcome.
#[derive(Debug)]
pub enum ReducedError {
    /// An `Auto` run met a case the reduced models do not represent; where the full engine
    /// may take over without starting again from t = 0 (`None` when the block was never at
    /// rest on a record sample, e.g. under a pulse).
    Violation(Violation, Option<Box<Resume>>),
    Run(RunError),
}

/// Where a reduced run that met a violation can hand over to the full engine: its state at
/// the last record sample it passed within its assumptions ([`super::HandOver`]), in world
/// terms, and what the run had seen up to the violation. Only on a fixed base (under a driven
/// base the engine would need the base's motion at that instant too).
#[derive(Debug, Clone, PartialEq)]
pub struct Resume {
    /// s, a sample of the record.
    pub time: f64,
    /// Scene index of the free block.
    pub free: usize,
    /// The block's outline then, world coordinates, m (the scene's vertex order).
    pub outline: Vec<Vector2<f64>>,
    /// Centroid displacement from the scene's place (m), rotation (rad, counter-clockwise),
    /// centroid velocity (m/s) and angular velocity (rad/s) then.
    pub displacement: Vector2<f64>,
    pub rotation: f64,
    pub velocity: Vector2<f64>,
    pub omega: f64,
    /// Sliding distance up to then, m.
    pub slid: f64,
    /// Largest |rotation| (rad) and centroid displacement (m) at the frames up to the
    /// violation.
    pub max_rotation: f64,
    pub max_displacement: f64,
    /// Steps of the reduced run.
    pub steps: u64,
}

impl From<RunError> for ReducedError {
    fn from(e: RunError) -> Self {
        ReducedError::Run(e)
    }
}

/// World state of the free block: centroid displacement (m), rotation (rad), velocity (m/s),
/// angular velocity (rad/s), outline (m); ground-relative for a fixed base, absolute for a
/// driven one.
struct BlockNow {
    d: Vector2<f64>,
    rotation: f64,
    v: Vector2<f64>,
    omega: f64,
    outline: Vec<[f64; 2]>,
}

/// The free block's state now; its outline only `with_outline` (frames need it, the tracker
/// does not, and a run that writes no frames skips the allocation).
fn block_now(m: &Reduced, with_outline: bool) -> BlockNow {
    let b = &m.block;
    let (d, rotation, v, omega) = m.kinematics();
    let (mut d, mut v) = (b.to_world(d), b.to_world(v));
    let mut shift = Vector2::zeros();
    if b.driven {
        let gs = m.motion.state(m.time);
        shift = Vector2::new(gs[2][0], gs[2][1]);
        d += shift;
        v += Vector2::new(gs[1][0], gs[1][1]);
    }
    let outline = if with_outline {
        m.outline()
            .iter()
            .map(|p| {
                let w = b.origin + b.to_world(*p) + shift;
                [w.x, w.y]
            })
            .collect()
    } else {
        Vec::new()
    };
    BlockNow {
        d,
        rotation,
        v,
        omega,
        outline,
    }
}

fn frame(scene: &Scene, m: &Reduced, now: &BlockNow, failure: &FailureParams) -> Frame {
    let b = &m.block;
    let gs = m.motion.state(m.time);
    let shift = if b.driven {
        Vector2::new(gs[2][0], gs[2][1])
    } else {
        Vector2::zeros()
    };
    let blocks = (0..scene.blocks.len())
        .map(|i| {
            if i == b.free {
                let state = failure.motion_state(
                    now.rotation,
                    now.omega,
                    matches!(m.phase, Phase::Sliding { .. }),
                );
                BlockFrame {
                    x: now.d.x,
                    y: now.d.y,
                    rotation: now.rotation,
                    vx: now.v.x,
                    vy: now.v.y,
                    angular_velocity: now.omega,
                    state,
                    outline: now.outline.clone(),
                }
            } else {
                let (vx, vy) = if b.driven {
                    (gs[1][0], gs[1][1])
                } else {
                    (0.0, 0.0)
                };
                BlockFrame {
                    x: shift.x,
                    y: shift.y,
                    rotation: 0.0,
                    vx,
                    vy,
                    angular_velocity: 0.0,
                    state: BlockMotionState::AtRest,
                    outline: scene.blocks[i]
                        .vertices
                        .iter()
                        .map(|p| [p.x + shift.x, p.y + shift.y])
                        .collect(),
                }
            }
        })
        .collect();
    Frame {
        time: m.time,
        blocks,
        ground: GroundFrame {
            acceleration: gs[0],
            velocity: gs[1],
            displacement: gs[2],
        },
    }
}

/// The record header of a reduced run (`model`: what the metadata names; `analysis::run_fallback`
/// writes a hand-over run's outputs under it too).
pub(crate) fn header(
    scene: &Scene,
    b: &SingleBlock,
    motion: &GroundMotion,
    opts: &RunOptions,
    model: &str,
) -> Result<RecordHeader, RunError> {
    if let Some(ids) = &opts.history_blocks {
        for id in ids {
            if scene.block_index(id) != Some(b.free) {
                return Err(RunError::HistoryBlock { id: id.clone() });
            }
        }
    }
    let history_blocks = match &opts.history_blocks {
        Some(ids) if ids.is_empty() => Vec::new(),
        _ => vec![b.free],
    };
    let mut metadata = std::collections::BTreeMap::new();
    metadata.insert(
        "scene".into(),
        serde_json::to_string(&scene.spec).unwrap_or_default(),
    );
    metadata.insert("motion_provenance".into(), motion.provenance.clone());
    metadata.insert("motion_scale".into(), format!("{}", motion.scale));
    metadata.insert("pga_m_s2".into(), format!("{}", motion.pga()));
    metadata.insert(
        "solver".into(),
        reported_control(scene, Ran::Reduced).to_string(),
    );
    metadata.insert("model".into(), model.into());
    metadata.insert("code_version".into(), env!("CARGO_PKG_VERSION").into());
    Ok(RecordHeader {
        block_ids: scene.blocks.iter().map(|b| b.id.clone()).collect(),
        block_kinds: (0..scene.blocks.len())
            .map(|i| {
                if i == b.free {
                    FrameBlockKind::Free
                } else if b.driven {
                    FrameBlockKind::Driven
                } else {
                    FrameBlockKind::Fixed
                }
            })
            .collect(),
        history_blocks,
        metadata,
    })
}

fn track(tr: &mut Tracker, now: &BlockNow, slid: f64) {
    tr.final_displacement[0] = [now.d.x, now.d.y];
    tr.final_rotation[0] = now.rotation;
    tr.max_displacement[0] = tr.max_displacement[0].max(now.d.norm());
    tr.max_rotation[0] = tr.max_rotation[0].max(now.rotation.abs());
    tr.sliding_distance[0] = slid;
}

/// The model name a finished reduced run reports: the motion it showed, or for a block that
/// never moved the one that would start first under a growing horizontal load.
fn model_name(m: &Reduced) -> &'static str {
    match m.modes {
        Modes::Rocking => "rocking",
        Modes::Sliding => "sliding",
        Modes::Auto => {
            if m.stats.first_rocking.is_some() {
                "rocking"
            } else if m.stats.first_sliding.is_some() {
                "sliding"
            } else if m.block.mu > m.block.slenderness(0).min(m.block.slenderness(1)).tan() {
                "rocking"
            } else {
                "sliding"
            }
        }
    }
}

/// Has the block settled? At rest, or lying on another face: exact states of the model, which
/// no longer change once the ground is still (the energy bound of the full engine,
/// `RunEndParams::settle_energy_ratio`, is for a model that has no such states).
fn settled(m: &Reduced) -> bool {
    matches!(m.phase, Phase::Rest | Phase::Fallen { .. })
}

/// Run the reduced model of `scene` (already qualified as `block`) under `motion`. `reason`
/// is the start of `model_reason`; the run appends what happened.
pub fn run(
    scene: &Scene,
    motion: &GroundMotion,
    opts: &RunOptions,
    block: SingleBlock,
    modes: Modes,
    params: ReducedParams,
    reason: &str,
) -> Result<RunOutcome, ReducedError> {
    let wall = Instant::now();
    let duration = duration(scene, motion)?;
    let failure = FailureParams::default();
    // The run goes on after `duration` while the block moves, up to the cap.
    let cap = run_end::cap(duration, motion, &opts.run_end.unwrap_or_default());
    let mut m = Reduced::new(block, motion, params, modes);
    let provisional = match modes {
        Modes::Rocking => "rocking",
        Modes::Sliding => "sliding",
        Modes::Auto => "auto",
    };
    let hdr = header(scene, &m.block, motion, opts, provisional)?;
    let mut writers = Writers::open(opts.out_dir, &hdr, opts.no_trajectory)?;
    let mut tr = Tracker {
        free: vec![m.block.free],
        ids: vec![scene.blocks[m.block.free].id.clone()],
        max_displacement: vec![0.0],
        max_rotation: vec![0.0],
        sliding_distance: vec![0.0],
        final_displacement: vec![[0.0; 2]],
        final_rotation: vec![0.0],
    };
    let interval = scene.control.output_interval;
    let mut frame_index: u64 = 0;
    let now = block_now(&m, true);
    writers.emit(&frame(scene, &m, &now, &failure), opts, None)?;
    let mut stopped_reason = None;
    let mut cancelled = false;
    while m.time < cap - 1e-12 {
        if opts.cancel.is_some_and(|c| c.load(Ordering::Relaxed)) {
            cancelled = true;
            stopped_reason = Some("cancelled".to_string());
            break;
        }
        if m.stats.steps >= scene.control.max_steps {
            stopped_reason = Some(format!(
                "step budget of {} steps reached (control.max_steps)",
                scene.control.max_steps
            ));
            break;
        }
        let next =
            ((frame_index + 1) as f64 * interval).min(run_end::horizon(m.time, duration, cap));
        if let Err(v) = m.advance(next) {
            writers.finish()?;
            let resume = m.hand_over.filter(|_| !m.block.driven).map(|h| {
                let mut then = m.clone();
                then.time = h.time;
                then.phase = h.phase;
                then.slip = h.slip;
                let now = block_now(&then, true);
                Box::new(Resume {
                    time: h.time,
                    free: m.block.free,
                    outline: now
                        .outline
                        .iter()
                        .map(|p| Vector2::new(p[0], p[1]))
                        .collect(),
                    displacement: now.d,
                    rotation: now.rotation,
                    velocity: now.v,
                    omega: now.omega,
                    slid: h.slid,
                    max_rotation: tr.max_rotation[0],
                    max_displacement: tr.max_displacement[0],
                    steps: m.stats.steps,
                })
            });
            return Err(ReducedError::Violation(v, resume));
        }
        frame_index += 1;
        let wanted = writers.wants_frames(opts);
        let now = block_now(&m, wanted);
        track(&mut tr, &now, m.slid);
        if wanted {
            writers.emit(
                &frame(scene, &m, &now, &failure),
                opts,
                Some(m.time / duration),
            )?;
        } else if let Some(p) = opts.progress {
            p((m.time / duration).min(1.0));
        }
        if opts.stop_when.is_some_and(|f| f(&tr)) {
            stopped_reason = Some("decided".to_string());
            break;
        }
        if run_end::may_end(m.time, duration, settled(&m)) {
            break;
        }
    }
    writers.finish()?;
    let model = model_name(&m);
    let mut why = reason.to_string();
    if let Some(t) = m.stats.first_rocking {
        why += &format!("; rocking started at t = {t:.4} s");
    }
    if let Some(t) = m.stats.first_sliding {
        why += &format!("; sliding started at t = {t:.4} s");
    }
    if m.stats.first_rocking.is_none() && m.stats.first_sliding.is_none() {
        why += "; the block did not move";
    }
    if matches!(m.phase, Phase::Fallen { .. }) {
        why += "; it overturned onto another face";
    }
    if let Some(v) = m.violations.first() {
        why += &format!(
            "; WARNING: outside the forced model's assumptions: {} ({} such events)",
            v.what,
            m.violations.len()
        );
    }
    let blocks = vec![BlockSummary {
        id: tr.ids[0].clone(),
        max_displacement: tr.max_displacement[0],
        final_displacement: tr.final_displacement[0],
        max_rotation: tr.max_rotation[0],
        final_rotation: tr.final_rotation[0],
        toppled: tr.final_rotation[0].abs() > failure.toppled_rotation,
        sliding_distance: tr.sliding_distance[0],
        block_model: None,
        block_model_reason: None,
    }];
    let st = &m.stats;
    let restitution = super::rocking::restitution(&m.block, 0, params.restitution);
    let mut summary = Summary {
        format: RUN_OUTPUTS_FORMAT.into(),
        completed: stopped_reason.is_none() && m.time >= duration - 1e-9,
        simulated_time: round_time(m.time),
        steps: st.steps,
        wall_time_s: wall.elapsed().as_secs_f64(),
        pga: motion.pga(),
        failure_mode: failure_mode(&blocks, &failure).into(),
        blocks,
        diagnostics: Diagnostics {
            time_step_cuts: st.rejected_steps,
            max_penetration: 0.0,
            // The steps the ODE's error control chose (absent when the block never moved:
            // the at-rest state takes no time step).
            min_time_step: st.min_dt.is_finite().then_some(st.min_dt),
            max_time_step: (st.max_dt > 0.0).then_some(st.max_dt),
            restitution: (model == "rocking").then_some(restitution),
            impacts: (model == "rocking").then_some(st.impacts),
            ..Default::default()
        },
        model: model.into(),
        model_reason: why,
        block_model_reason: "the reduced models are rigid-block models".into(),
        stopped_reason,
        control: reported_control(scene, Ran::Reduced),
        units: summary_units(),
        settled: false,
        events: Vec::new(),
    };
    end_summary(&mut summary, settled(&m), Vec::new(), duration, motion);
    if let Some(dir) = opts.out_dir {
        crate::analysis::run::write_summary(dir, &summary)?;
    }
    Ok(RunOutcome { summary, cancelled })
}
