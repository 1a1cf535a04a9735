//! One run, `auto`'s fallback to the full engine started where the reduced model last was
//! within its assumptions: sits between `analysis::run` (which calls it when the reduced model
//! meets a case it does not represent, unless `RunOptions::fallback_from_zero` is set) and the
//! engine loop `run::run_dda`, which it runs on the scene and record from that instant. A run
//! that writes outputs (`ashlar run`, the service's run jobs) takes the same path as a PGA
//! search's run (same engine start, same steps, same verdict) and writes the reduced model's
//! frames before the hand-over and the engine's from it.
//!
//! The state mapping: under a base acceleration the engine solves the block's motion relative
//! to the base, loaded by gravity and −m·a_g(t) only. The reduced model's state at a record
//! sample t₀ (its pose: the block's outline; its centroid velocity and angular velocity) is
//! the engine's initial state of the scene with the block's vertices moved to that outline and
//! that initial velocity, under the record's samples from t₀ on. The reduced model passed t₀
//! within its assumptions (at rest, or rocking with the pivot within friction), so up to t₀
//! the two models describe the same motion, and the engine runs only from the last sample
//! before the case the reduced model does not represent (the pivot slipping). The engine's
//! own start-up differs from a run from t = 0: its penalty contacts start unloaded at t₀ (the
//! block sinks by ~g·Δt²/2, a few µm, in the first step).
use super::reduced::{
    self,
    record::{ReducedError, Resume},
};
use super::run::{
    choose_model, duration, end_summary, reported_control, round_time, run_dda, write_summary,
    FailureParams, ModelPlan, Ran, RunError, RunOptions, RunOutcome, Tracker, Writers,
};
use crate::motion::GroundMotion;
use crate::record::{BlockMotionState, Frame, GroundFrame};
use crate::scene::{Excitation, Scene};
use nalgebra::Vector2;
use std::sync::Mutex;

/// The scene and record from the hand-over `r` on, or `None` when the engine cannot start
/// there (not a base acceleration, a record without a sample at t₀, t₀ = 0, or t₀ at or after
/// the run's duration).
fn shifted(scene: &Scene, motion: &GroundMotion, r: &Resume) -> Option<(Scene, GroundMotion)> {
    let t0 = r.time;
    if scene.excitation != Excitation::BaseAcceleration || t0 <= 0.0 {
        return None;
    }
    let d = duration(scene, motion).ok()?;
    if t0 >= d {
        return None;
    }
    let gm = motion.from_sample_at(t0)?;
    let mut s = scene.clone();
    s.control.duration = scene.control.duration.map(|d| d - t0);
    let block = s.blocks.get_mut(r.free)?;
    if block.vertices.len() != r.outline.len() {
        return None;
    }
    block.vertices.clone_from(&r.outline);
    *s.initial_velocity.get_mut(r.free)? = [r.velocity.x, r.velocity.y, r.omega];
    Some((s, gm))
}

/// The engine's tracker seen from the scene's own start: the free block's rotation and
/// displacement offset by the hand-over's, and their maxima over the engine's steps.
struct Offset {
    seen: Tracker,
    max_rotation: f64,
    max_displacement: f64,
}

/// The stitched outputs of a run that writes frames: the reduced model's frames before the
/// hand-over, then the engine's, through one set of writers; the first write error is kept.
struct Stitched<'a> {
    writers: Option<Writers>,
    error: Option<RunError>,
    opts: &'a RunOptions<'a>,
    /// s, the run's duration (for progress).
    duration: f64,
}

impl Stitched<'_> {
    fn emit(&mut self, f: &Frame) {
        if self.error.is_some() {
            return;
        }
        let progress = (f.time > 0.0).then_some(f.time / self.duration);
        if let Some(w) = &mut self.writers {
            if let Err(e) = w.emit(f, self.opts, progress) {
                self.error = Some(e);
            }
        }
    }
}

/// Open the writers of a run that hands over at `r.time` and write the reduced model's frames
/// before it: the reduced run is replayed (it is deterministic, and milliseconds against the
/// engine's part) with its frames before t₀ kept. `None` when the scene has no reduced plan
/// (it then had no hand-over either).
fn open_stitched<'a>(
    scene: &Scene,
    motion: &GroundMotion,
    opts: &'a RunOptions<'a>,
    r: &Resume,
) -> Result<Option<Mutex<Stitched<'a>>>, RunError> {
    let rparams = opts.reduced_params.unwrap_or_default();
    let ModelPlan::Reduced {
        block,
        modes,
        reason,
    } = choose_model(scene, &rparams)?
    else {
        return Ok(None);
    };
    let mut hdr = reduced::record::header(scene, &block, motion, opts, "dda")?;
    hdr.metadata.insert(
        "solver".into(),
        reported_control(scene, Ran::Engine).to_string(),
    );
    hdr.metadata.insert(
        "hand_over".into(),
        format!(
            "frames before t = {} s from the reduced model, from there the full DDA engine",
            r.time
        ),
    );
    let out = Mutex::new(Stitched {
        writers: Some(Writers::open(opts.out_dir, &hdr, opts.no_trajectory)?),
        error: None,
        opts,
        duration: duration(scene, motion)?,
    });
    let t0 = r.time;
    let keep = |f: &Frame| {
        if f.time < t0 - 1e-9 {
            if let Ok(mut o) = out.lock() {
                o.emit(f);
            }
        }
    };
    let replay = RunOptions {
        cancel: opts.cancel,
        history_blocks: opts.history_blocks.clone(),
        on_frame: Some(&keep),
        reduced_params: opts.reduced_params,
        run_end: opts.run_end,
        ..Default::default()
    };
    match reduced::record::run(scene, motion, &replay, *block, modes, rparams, &reason) {
        Ok(_) | Err(ReducedError::Violation(..)) => Ok(Some(out)),
        Err(ReducedError::Run(e)) => Err(e),
    }
}

/// An engine frame of the run from t₀ seen from the scene's start: time from the record's
/// start, the free block's displacement and rotation from its place in the scene, the ground
/// as the whole record has it there.
fn from_scene_start(
    f: &Frame,
    r: &Resume,
    motion: &GroundMotion,
    failure: &FailureParams,
) -> Frame {
    let mut f = f.clone();
    f.time += r.time;
    if let Some(b) = f.blocks.get_mut(r.free) {
        b.x += r.displacement.x;
        b.y += r.displacement.y;
        b.rotation += r.rotation;
        // The engine judged toppling from t₀'s pose; the rule is re-applied to the rotation
        // from the scene's (sliding as the engine saw it).
        b.state = failure.motion_state(
            b.rotation,
            b.angular_velocity,
            b.state == BlockMotionState::Sliding,
        );
    }
    let gs = motion.state(f.time);
    f.ground = GroundFrame {
        acceleration: gs[0],
        velocity: gs[1],
        displacement: gs[2],
    };
    f
}

/// Run the full engine from the hand-over `r` (or from t = 0 when it cannot start there) and
/// report the run as a whole: times from the record's start, the block's rotation and
/// displacement from its place in the scene, its maxima over the reduced part and the
/// engine's part. A run that writes frames gets the reduced model's frames before t₀ and the
/// engine's from t₀ (at t₀ + k × `output_interval`), so that `ashlar run` and a PGA search
/// take the same path and reach the same verdict.
pub(crate) fn from_rest(
    scene: &Scene,
    motion: &GroundMotion,
    opts: &RunOptions,
    reason: String,
    r: &Resume,
) -> Result<RunOutcome, RunError> {
    let Some((s, gm)) = shifted(scene, motion, r) else {
        return run_dda(scene, motion, opts, reason);
    };
    let frames = opts.out_dir.is_some() || opts.on_frame.is_some();
    let stitched = if frames {
        match open_stitched(scene, motion, opts, r)? {
            Some(w) => Some(w),
            None => return run_dda(scene, motion, opts, reason),
        }
    } else {
        None
    };
    let t0 = r.time;
    let reason = format!(
        "{reason} from t = {t0:.4} s, the last record sample the reduced model passed within its assumptions (rotation {:.4} rad, angular velocity {:.4} rad/s), with the record from there on",
        r.rotation, r.omega
    );
    let id = scene.blocks[r.free].id.clone();
    let d0 = r.displacement;
    let offset = Mutex::new(Offset {
        seen: Tracker::default(),
        max_rotation: r.max_rotation,
        max_displacement: r.max_displacement,
    });
    let inner = opts.stop_when;
    let watch = |tr: &Tracker| -> bool {
        let Ok(mut o) = offset.lock() else {
            return false;
        };
        let o = &mut *o;
        let t = &mut o.seen;
        t.free.clone_from(&tr.free);
        t.ids.clone_from(&tr.ids);
        t.max_displacement.clone_from(&tr.max_displacement);
        t.max_rotation.clone_from(&tr.max_rotation);
        t.sliding_distance.clone_from(&tr.sliding_distance);
        t.final_displacement.clone_from(&tr.final_displacement);
        t.final_rotation.clone_from(&tr.final_rotation);
        if let Some(k) = t.ids.iter().position(|i| *i == id) {
            t.final_rotation[k] += r.rotation;
            t.final_displacement[k][0] += d0.x;
            t.final_displacement[k][1] += d0.y;
            t.sliding_distance[k] += r.slid;
            let d = t.final_displacement[k];
            o.max_rotation = o.max_rotation.max(t.final_rotation[k].abs());
            o.max_displacement = o.max_displacement.max(Vector2::new(d[0], d[1]).norm());
            t.max_rotation[k] = o.max_rotation;
            t.max_displacement[k] = o.max_displacement;
        }
        inner.is_some_and(|f| f(t))
    };
    let failure = FailureParams::default();
    let engine_frame = |f: &Frame| {
        if let Some(Ok(mut o)) = stitched.as_ref().map(|m| m.lock()) {
            o.emit(&from_scene_start(f, r, motion, &failure));
        }
    };
    let sub = RunOptions {
        out_dir: None,
        cancel: opts.cancel,
        progress: opts.progress.filter(|_| !frames),
        history_blocks: opts.history_blocks.clone(),
        no_trajectory: opts.no_trajectory,
        stop_when: Some(&watch),
        sim_params: opts.sim_params,
        on_frame: frames.then_some(&engine_frame as &(dyn Fn(&Frame) + Sync)),
        reduced_params: opts.reduced_params,
        run_end: opts.run_end,
        fallback_from_zero: false,
    };
    let mut out = run_dda(&s, &gm, &sub, reason)?;
    if let Some(m) = stitched {
        let mut o = m.into_inner().unwrap_or_else(|e| e.into_inner());
        if let Some(e) = o.error.take() {
            return Err(e);
        }
        if let Some(w) = o.writers.take() {
            w.finish()?;
        }
    }
    // A panic inside `watch` would have ended the run above; the data is whole either way.
    let o = offset.into_inner().unwrap_or_else(|e| e.into_inner());
    let sum = &mut out.summary;
    sum.simulated_time = round_time(sum.simulated_time + t0);
    sum.steps += r.steps;
    sum.pga = motion.pga();
    if let Some(b) = sum.blocks.iter_mut().find(|b| b.id == id) {
        b.final_rotation += r.rotation;
        b.final_displacement[0] += d0.x;
        b.final_displacement[1] += d0.y;
        b.max_rotation = o.max_rotation;
        b.max_displacement = o.max_displacement;
        b.sliding_distance += r.slid;
        b.toppled = b.final_rotation.abs() > failure.toppled_rotation;
    }
    for e in &mut sum.events {
        e.time = round_time(e.time + t0);
    }
    let events = std::mem::take(&mut sum.events);
    let settled = sum.settled;
    end_summary(sum, settled, events, duration(scene, motion)?, motion);
    if let Some(dir) = opts.out_dir {
        write_summary(dir, sum)?;
    }
    Ok(out)
}
