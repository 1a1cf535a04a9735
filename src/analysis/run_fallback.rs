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
//!
//! The hand-back ([`HandBackParams`]): once the engine's block is at rest on its base again,
//! the run goes back to `analysis::run::run` on the scene from the next record sample (the
//! block moved along its base by its slip), and that part is reported offset by the block's
//! displacement and rotation then, its frames into the same outputs.
//!
//! Length (over 600 lines): the hand-over and the hand-back are one chain of offsets (times,
//! the block's pose, the tracker's maxima, the stitched frames, the summary) read together; the
//! engine loop is `run.rs`'s, the reduced model's `reduced/record.rs`.
use super::reduced::{
    self,
    record::{ReducedError, Resume},
    Modes, ReducedParams, SingleBlock,
};
use super::run::{
    choose_model, duration, end_summary, reported_control, round_time, run_dda, write_summary,
    FailureParams, ModelPlan, Ran, RunError, RunOptions, RunOutcome, Tracker, Writers, HANDED_BACK,
};
use crate::contact::ContactState;
use crate::motion::GroundMotion;
use crate::record::{BlockMotionState, Frame, GroundFrame};
use crate::scene::{Excitation, Scene};
use crate::simulation::Simulation;
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
    /// s, the time of the last frame written: a handed-back part's frames start after it.
    last: f64,
}

impl Stitched<'_> {
    fn emit(&mut self, f: &Frame) {
        if self.error.is_some() || f.time <= self.last + 1e-9 {
            return;
        }
        self.last = f.time;
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
            "frames before t = {} s from the reduced model, from there the full DDA engine{}",
            r.time,
            if opts.hand_back.unwrap_or_default().enabled {
                // Written before the run knows whether it will hand back.
                " (and the reduced model again from each hand-back summary.json's model_reason names)"
            } else {
                ""
            }
        ),
    );
    let out = Mutex::new(Stitched {
        writers: Some(Writers::open(opts.out_dir, &hdr, opts.no_trajectory)?),
        error: None,
        opts,
        duration: duration(scene, motion)?,
        last: f64::NEG_INFINITY,
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

/// Where a part of the run started, seen from the scene's start: the time (s), the free
/// block's centroid displacement (m) and rotation (rad) from its place in the scene then.
#[derive(Debug, Clone, Copy)]
struct Shift {
    time: f64,
    free: usize,
    displacement: Vector2<f64>,
    rotation: f64,
}

impl Shift {
    fn of(r: &Resume) -> Self {
        Shift {
            time: r.time,
            free: r.free,
            displacement: r.displacement,
            rotation: r.rotation,
        }
    }
}

/// A frame of a part of the run that started at `r` (the engine from t₀, or the reduced model
/// from a hand-back) seen from the scene's start: time from the record's start, the free
/// block's displacement and rotation from its place in the scene, the ground as the whole
/// record has it there.
fn from_scene_start(f: &Frame, r: &Shift, motion: &GroundMotion, failure: &FailureParams) -> Frame {
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

/// Knobs of the hand-back: once the engine's block is at rest on its base again, the reduced
/// model takes the run back (docs/speed.md, "Reduced models on records"). Each default says why.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct HandBackParams {
    /// Hand back at all (on: as accurate as the engine run through, measured by
    /// `examples/handover_study.rs`; off: the engine runs from the hand-over to the end).
    pub enabled: bool,
    /// |rotation| (rad) from the block's place in the scene below which it stands flat: 1e-3
    /// rad is 0.3 % of the bundled column's tipping angle (0.32 rad), so the reduced model's
    /// flat start moves its tipping threshold by less than that, and it is above the tilt
    /// the engine's penalty contacts leave at rest (µm of penetration over the base width).
    pub rotation: f64,
    /// |angular velocity| (rad/s) below which the block is at rest: 1e-3 rad/s moves a 1 m
    /// column's top by 1 mm/s, and over the window below by 0.05 mm; the reduced model takes
    /// it as 0 (a landing block at 1e-5 rad/s is at rest for it).
    pub angular_velocity: f64,
    /// |centroid velocity| (m/s) below which the block is at rest: 1e-3 m/s, the same 0.05 mm
    /// over the window (the 1 mm that counts as sliding is twenty times that).
    pub velocity: f64,
    /// s the block must stay at rest before it is handed back: 0.05 s is 50 of the engine's
    /// default steps and several record samples, so a block passing through the upright
    /// between two rocking half-cycles (at rest for no step) is not taken for one at rest.
    pub window: f64,
}

impl Default for HandBackParams {
    fn default() -> Self {
        Self {
            enabled: true,
            rotation: 1e-3,
            angular_velocity: 1e-3,
            velocity: 1e-3,
            window: 0.05,
        }
    }
}

/// Is the engine's block `free` at rest on its base `base`: both of its bottom corners (two
/// or more of its vertices) in contact with the base, no contact sliding, its rotation from
/// the scene (`rotation0`: at the engine's start) and its velocities within `p`?
fn at_rest(sim: &Simulation, free: usize, base: usize, rotation0: f64, p: &HandBackParams) -> bool {
    let g = &sim.geoms()[free];
    let [vx, vy, omega] = sim.block_velocity(free);
    if (rotation0 + g.rotation).abs() > p.rotation
        || omega.abs() > p.angular_velocity
        || vx.hypot(vy) > p.velocity
    {
        return false;
    }
    let mut closed = 0;
    for c in &sim.contacts().contacts {
        if c.vertex_block != free && c.edge_block != free {
            continue;
        }
        match c.state {
            ContactState::Sliding { .. } => return false,
            ContactState::Locked if c.vertex_block == free && c.edge_block == base => closed += 1,
            _ => {}
        }
    }
    closed >= 2
}

/// The engine's block at rest at a record sample: where the reduced model takes the run back.
struct Back {
    /// The scene with the block moved along its base by the slip so far (flat on it, at rest)
    /// and the run's remaining duration and step budget, and the record from the sample on.
    scene: Scene,
    motion: GroundMotion,
    /// The sample's time and the block's displacement and rotation from its place in the
    /// scene, as the engine left them (the reduced model's new reference: its part is
    /// reported offset by them).
    shift: Shift,
    /// Sliding distance up to then, m.
    slid: f64,
}

/// The hand-back at the record sample `t` (s from the record's start), the engine's block
/// displaced by `d` (m) and rotated by `rotation` (rad) from its place in the scene; `None`
/// where the reduced model is not valid there: the moved block does not qualify (off its
/// base), or a motion starts at once under the load at `t` (the engine's block at rest is at
/// the edge of moving; the engine keeps it).
fn hand_back_at(
    scene: &Scene,
    motion: &GroundMotion,
    block: &SingleBlock,
    rparams: &ReducedParams,
    t: f64,
    d: Vector2<f64>,
    rotation: f64,
) -> Option<(Scene, GroundMotion, Shift)> {
    let dur = duration(scene, motion).ok()?;
    if t <= 0.0 || t >= dur - 1e-9 {
        return None;
    }
    let gm = motion.from_sample_at(t)?;
    let mut s = scene.clone();
    s.control.duration = scene.control.duration.map(|d| d - t);
    let slip = block.t * d.dot(&block.t);
    for v in &mut s.blocks.get_mut(block.free)?.vertices {
        *v += slip;
    }
    *s.initial_velocity.get_mut(block.free)? = [0.0; 3];
    let ModelPlan::Reduced {
        block: b,
        modes: Modes::Auto,
        ..
    } = choose_model(&s, rparams).ok()?
    else {
        return None;
    };
    reduced::stays_at_rest(&b, &gm, 0.0).then_some((
        s,
        gm,
        Shift {
            time: t,
            free: block.free,
            displacement: d,
            rotation,
        },
    ))
}

/// The engine's watch for a hand-back: the block at rest for `window`, then the next record
/// sample at which it still is and the reduced model is valid (`hand_back_at`).
#[derive(Default)]
struct RestWatch {
    /// Engine time (s) the block came to rest, and the sample (engine time) to hand back at.
    since: Option<f64>,
    target: Option<f64>,
    back: Option<Back>,
}

/// Run the full engine from the hand-over `r` (or from t = 0 when it cannot start there) and
/// report the run as a whole: times from the record's start, the block's rotation and
/// displacement from its place in the scene, its maxima over the reduced part and the
/// engine's part. A run that writes frames gets the reduced model's frames before t₀ and the
/// engine's from t₀ (at t₀ + k × `output_interval`), so that `ashlar run` and a PGA search
/// take the same path and reach the same verdict. Once the engine's block is at rest on its
/// base again ([`HandBackParams`]), the run is handed back to the reduced model at the next
/// record sample (`analysis::run::run` on the scene from there: it may hand over again), its
/// part offset by the block's displacement and rotation then.
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
    let engine_shift = Shift::of(r);
    let engine_frame = |f: &Frame| {
        if let Some(Ok(mut o)) = stitched.as_ref().map(|m| m.lock()) {
            o.emit(&from_scene_start(f, &engine_shift, motion, &failure));
        }
    };
    // The hand-back: only for a reduced plan of the scene (it had one: it handed over).
    let rparams = opts.reduced_params.unwrap_or_default();
    let hb = opts.hand_back.unwrap_or_default();
    let plan = match choose_model(scene, &rparams)? {
        ModelPlan::Reduced { block, .. } if hb.enabled => Some(block),
        _ => None,
    };
    let rest = Mutex::new(RestWatch::default());
    let engine_dur = duration(&s, &gm)?;
    let at_rest_hook = |sim: &Simulation| -> bool {
        let (Some(b), Ok(mut w)) = (plan.as_ref(), rest.lock()) else {
            return false;
        };
        let te = sim.time();
        if !at_rest(sim, b.free, b.base, r.rotation, &hb) {
            *w = RestWatch::default();
            return false;
        }
        let since = *w.since.get_or_insert(te);
        if te - since < hb.window - 1e-12 {
            return false;
        }
        let target = *w.target.get_or_insert_with(|| gm.next_kink(te));
        if target >= engine_dur - 1e-9 || te < target - 1e-12 {
            return false;
        }
        let g = &sim.geoms()[b.free];
        let d = d0 + (g.centroid - g.initial_centroid);
        match hand_back_at(
            scene,
            motion,
            b,
            &rparams,
            t0 + target,
            d,
            r.rotation + g.rotation,
        ) {
            Some((scene, motion, shift)) => {
                let slid = offset
                    .lock()
                    .ok()
                    .and_then(|o| {
                        let k = o.seen.ids.iter().position(|i| *i == id)?;
                        Some(o.seen.sliding_distance[k])
                    })
                    .unwrap_or(r.slid);
                w.back = Some(Back {
                    scene,
                    motion,
                    shift,
                    slid,
                });
                true
            }
            None => {
                // Not valid here: the block must come to rest again (a new window).
                *w = RestWatch::default();
                false
            }
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
        // The hand-over's engine runs to its end in a search as in `ashlar run` (the same
        // path, the same verdict: pga_honesty); the hand-back ends it at rest instead.
        end_when_still: false,
        hand_back: opts.hand_back,
        engine_at_rest: plan
            .is_some()
            .then_some(&at_rest_hook as &(dyn Fn(&Simulation) -> bool + Sync)),
    };
    let mut out = run_dda(&s, &gm, &sub, reason)?;
    let back = match out.summary.stopped_reason.as_deref() {
        Some(HANDED_BACK) => rest.into_inner().unwrap_or_else(|e| e.into_inner()).back,
        _ => None,
    };
    {
        let sum = &mut out.summary;
        sum.simulated_time = round_time(sum.simulated_time + t0);
        sum.steps += r.steps;
        for e in &mut sum.events {
            e.time = round_time(e.time + t0);
        }
    }
    // The reduced model's part after a hand-back, its frames into the same outputs.
    let handed = match back {
        Some(back) => {
            let o = offset.lock().unwrap_or_else(|e| e.into_inner());
            let (max_rotation, max_displacement) = (o.max_rotation, o.max_displacement);
            drop(o);
            Some(hand_back(
                opts,
                &back,
                &out.summary,
                motion,
                stitched.as_ref(),
                (max_rotation, max_displacement),
            )?)
        }
        None => None,
    };
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
    sum.pga = motion.pga();
    if let Some(b) = sum.blocks.iter_mut().find(|b| b.id == id) {
        b.final_rotation += r.rotation;
        b.final_displacement[0] += d0.x;
        b.final_displacement[1] += d0.y;
        b.max_rotation = o.max_rotation;
        b.max_displacement = o.max_displacement;
        b.sliding_distance += r.slid;
    }
    let mut settled = sum.settled;
    let mut events = std::mem::take(&mut sum.events);
    if let Some(h) = handed {
        out.cancelled = h.cancelled;
        settled = h.merge(sum, &id, &mut events);
    }
    if let Some(b) = sum.blocks.iter_mut().find(|b| b.id == id) {
        b.toppled = b.final_rotation.abs() > failure.toppled_rotation;
    }
    end_summary(sum, settled, events, duration(scene, motion)?, motion);
    if let Some(dir) = opts.out_dir {
        write_summary(dir, sum)?;
    }
    Ok(out)
}

/// The reduced model's part of a run handed back at `back`, seen from the scene's start.
struct HandedBack {
    shift: Shift,
    /// The part's summary (its own times and the block's motion from the hand-back).
    summary: crate::analysis::run::Summary,
    cancelled: bool,
    /// Largest |rotation| (rad) and centroid displacement (m) over the whole run so far.
    max_rotation: f64,
    max_displacement: f64,
    /// Sliding distance before the hand-back, m.
    slid: f64,
}

impl HandedBack {
    /// Fold the part into the summary of the run up to the hand-back (`sum`: times from the
    /// record's start, the block's motion from its place in the scene); returns whether the
    /// run settled.
    fn merge(
        self,
        sum: &mut crate::analysis::run::Summary,
        id: &str,
        events: &mut Vec<crate::analysis::run_end::RunEvent>,
    ) -> bool {
        let h = self.summary;
        let t = self.shift.time;
        sum.simulated_time = round_time(t + h.simulated_time);
        sum.steps += h.steps;
        sum.wall_time_s += h.wall_time_s;
        sum.completed = h.completed;
        sum.stopped_reason = h.stopped_reason;
        sum.diagnostics.time_step_cuts += h.diagnostics.time_step_cuts;
        sum.diagnostics.max_penetration = sum
            .diagnostics
            .max_penetration
            .max(h.diagnostics.max_penetration);
        if let (Some(b), Some(p)) = (
            sum.blocks.iter_mut().find(|b| b.id == id),
            h.blocks.iter().find(|b| b.id == id),
        ) {
            let d = self.shift.displacement;
            b.final_rotation = p.final_rotation + self.shift.rotation;
            b.final_displacement = [p.final_displacement[0] + d.x, p.final_displacement[1] + d.y];
            let fd = Vector2::new(b.final_displacement[0], b.final_displacement[1]);
            b.max_rotation = self.max_rotation.max(b.final_rotation.abs());
            b.max_displacement = self.max_displacement.max(fd.norm());
            b.sliding_distance = self.slid + p.sliding_distance;
        }
        sum.model_reason += &format!(
            "; at t = {t:.4} s the block was at rest on its base again (rotation {:.2e} rad): handed back to the reduced model [{}, times from the hand-back: {}]",
            self.shift.rotation, h.model, h.model_reason
        );
        events.extend(h.events.into_iter().map(|mut e| {
            e.time = round_time(e.time + t);
            e
        }));
        h.settled
    }
}

/// Run the reduced model (`analysis::run::run`, `auto`: it may hand over again) on the scene
/// and record from the hand-back `back`, its frames into `stitched` and its tracker into the
/// caller's early stop, both seen from the scene's start. `seen`: the summary of the run up
/// to the hand-back (for the remaining step budget); `max`: its largest |rotation| (rad) and
/// centroid displacement (m).
fn hand_back(
    opts: &RunOptions,
    back: &Back,
    seen: &crate::analysis::run::Summary,
    motion: &GroundMotion,
    stitched: Option<&Mutex<Stitched>>,
    max: (f64, f64),
) -> Result<HandedBack, RunError> {
    let shift = back.shift;
    let id = back.scene.blocks[shift.free].id.clone();
    let mut scene = back.scene.clone();
    scene.control.max_steps = scene.control.max_steps.saturating_sub(seen.steps);
    let failure = FailureParams::default();
    let maxima = Mutex::new(max);
    let outer = opts.stop_when;
    let slid = back.slid;
    let watch = |tr: &Tracker| -> bool {
        let mut t = tr.clone();
        if let Some(k) = t.ids.iter().position(|i| *i == id) {
            t.final_rotation[k] += shift.rotation;
            t.final_displacement[k][0] += shift.displacement.x;
            t.final_displacement[k][1] += shift.displacement.y;
            t.sliding_distance[k] += slid;
            let d = t.final_displacement[k];
            if let Ok(mut m) = maxima.lock() {
                m.0 = m.0.max(t.final_rotation[k].abs());
                m.1 = m.1.max(Vector2::new(d[0], d[1]).norm());
                t.max_rotation[k] = m.0;
                t.max_displacement[k] = m.1;
            }
        }
        outer.is_some_and(|f| f(&t))
    };
    let frame = |f: &Frame| {
        if let Some(Ok(mut o)) = stitched.map(|m| m.lock()) {
            o.emit(&from_scene_start(f, &shift, motion, &failure));
        }
    };
    let total = duration(&scene, &back.motion)? + shift.time;
    let progress = |p: f64| {
        if let Some(f) = opts.progress {
            f(((shift.time + p * (total - shift.time)) / total).min(1.0));
        }
    };
    let sub = RunOptions {
        out_dir: None,
        cancel: opts.cancel,
        progress: (opts.progress.is_some() && stitched.is_none())
            .then_some(&progress as &(dyn Fn(f64) + Sync)),
        history_blocks: opts.history_blocks.clone(),
        no_trajectory: opts.no_trajectory,
        stop_when: Some(&watch),
        sim_params: opts.sim_params,
        on_frame: stitched
            .is_some()
            .then_some(&frame as &(dyn Fn(&Frame) + Sync)),
        reduced_params: opts.reduced_params,
        run_end: opts.run_end,
        fallback_from_zero: false,
        end_when_still: false,
        hand_back: opts.hand_back,
        engine_at_rest: None,
    };
    let out = super::run::run(&scene, &back.motion, &sub)?;
    let (max_rotation, max_displacement) = maxima.into_inner().unwrap_or_else(|e| e.into_inner());
    Ok(HandedBack {
        shift,
        summary: out.summary,
        cancelled: out.cancelled,
        max_rotation,
        max_displacement,
        slid,
    })
}
