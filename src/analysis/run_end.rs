//! How a run ends (analysis, beside `run`): the run's length against the record's, the
//! continuation after the run's duration until the structure has settled, and the retirement
//! of blocks that fall out of the scene. Shared by both run loops (the full engine in
//! `analysis::run`, the reduced models in `analysis::reduced::record`); docs/run-end.md.
use crate::contact::Mobility;
use crate::motion::GroundMotion;
use crate::scene::{Excitation, Scene};
use crate::simulation::Simulation;
use serde::{Deserialize, Serialize};

/// Knobs of the end of a run. Each default says why.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RunEndParams {
    /// A free block is quiet when its kinetic energy relative to the ground is below this
    /// fraction of m·g·L (m its mass, g gravity, L half the diagonal of its bounding box).
    /// 1e-6: a rocking block with that energy at θ = 0 rises to θ ≈ 1e-6·L/(R sin α), a few
    /// µrad for any block of slenderness up to 1:10 (R: half diagonal, α: slenderness angle),
    /// and a sliding one moves on by 1e-6·L/μ — three orders below anything the outcome
    /// classification or a criterion can see (1 mm of slip, 30° of rotation); a column resting
    /// on the full engine's contact springs is below it (its runs end settled at their
    /// duration: docs/run-end.md).
    pub settle_energy_ratio: f64,
    /// s, how long every free block must stay quiet to count as settled. A rocking block's
    /// kinetic energy passes through zero at the top of each swing, for a moment: 0.1 s is
    /// longer than that moment for any swing larger than the bound above (the block falls
    /// back under gravity within milliseconds) and shorter than the shortest rocking period
    /// that matters.
    pub settle_window: f64,
    /// s, the longest continuation after the run's duration while the structure still moves.
    /// 10 s: a column rocking freely from just below its tipping angle loses 1 − e² of its
    /// energy at each impact (e = 0.85 for a 1:3 column) and comes to rest within seconds
    /// (reduced model, examples/column.json: at rest 3.1 s after the half-sine pulse ends;
    /// docs/run-end.md); 10 s leaves a wide margin for stockier or
    /// more slender blocks, and bounds the cost of a run that never settles (an undamped
    /// integrator) at 10 s of free vibration.
    pub max_extension: f64,
}

impl Default for RunEndParams {
    fn default() -> Self {
        Self {
            settle_energy_ratio: 1e-6,
            settle_window: 0.1,
            max_extension: 10.0,
        }
    }
}

/// Something that happened to a block during a run (`summary.json` `events`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct RunEvent {
    /// s.
    pub time: f64,
    /// The block's id.
    pub block: String,
    /// `"retired"`: the block's centroid fell more than the scene's height below its lowest
    /// fixed or driven block; it was frozen there (it left the structure).
    pub kind: String,
}

/// The scene's duration cut the record short (`diagnostics.record_truncated`).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct RecordTruncated {
    /// s, length of the ground-motion record.
    pub record_duration: f64,
    /// s, the run's duration (`control.duration`) that stops before the record ends.
    pub run_duration: f64,
}

/// The record is longer than the run's duration: report it.
pub fn truncation(duration: f64, motion: &GroundMotion) -> Option<RecordTruncated> {
    let record = motion.duration()?;
    (duration < record - 1e-9).then_some(RecordTruncated {
        record_duration: record,
        run_duration: duration,
    })
}

/// Latest simulated time of a run of `duration` (s): the continuation after `duration` runs
/// only when the ground is still by then (the record has ended, or there is no shaking). A
/// run whose duration cuts the record (reported as truncated) or that runs under an endless
/// signal stops at its duration: going on would go on shaking it past the window the user
/// chose.
pub fn cap(duration: f64, motion: &GroundMotion, params: &RunEndParams) -> f64 {
    let still = match motion.duration() {
        Some(record) => record <= duration + 1e-9,
        None => {
            matches!(motion.horizontal, crate::motion::Signal::Zero)
                && matches!(motion.vertical, crate::motion::Signal::Zero)
        }
    };
    if still {
        duration + params.max_extension
    } else {
        duration
    }
}

/// s, the latest time the next output frame may reach: the duration until the run has reached
/// it (frames land exactly on it), then the continuation's `cap`.
pub fn horizon(time: f64, duration: f64, cap: f64) -> f64 {
    if time < duration - 1e-9 {
        duration
    } else {
        cap
    }
}

/// s, the time from which the ground cannot load the structure any more: its acceleration is
/// zero for ever after it ([`GroundMotion::still_from`]). Under a driven block the ground may
/// go on moving at its last velocity (a record's integral need not end at rest), which moves
/// the driven block against any fixed one: `None` there unless the motion is scaled to zero.
pub fn still_from(scene: &Scene, motion: &GroundMotion) -> Option<f64> {
    match scene.excitation {
        Excitation::BaseAcceleration => motion.still_from(),
        Excitation::DrivenBlock(_) => (motion.scale == 0.0).then_some(0.0),
    }
}

/// A search's run may end here, before its duration (`RunOptions::end_when_still`): every free
/// block has been quiet for the whole settle `window` (s) under a ground that is still from
/// `still` (s) on, so nothing loads the structure any more: it is at rest in equilibrium and
/// stays so (the reasoning of the continuation's end after the record, [`may_end`], taken as
/// soon as it holds). `quiet_since` is [`SettleWatch::quiet_since`]; a structure quiet since
/// before `still` counts from `still`.
pub fn may_end_still(still: Option<f64>, quiet_since: Option<f64>, time: f64, window: f64) -> bool {
    match (still, quiet_since) {
        (Some(still), Some(since)) => time - since.max(still) >= window - 1e-12,
        _ => false,
    }
}

/// The run may end here: it has reached its duration and the structure has settled.
pub fn may_end(time: f64, duration: f64, settled: bool) -> bool {
    settled && time >= duration - 1e-9
}

/// The verdict of a run: [`super::run::failure_mode`], except that a structure still moving
/// at the end is "undecided" rather than "stable" (it might still fall).
pub fn verdict(mode: &'static str, settled: bool) -> &'static str {
    if !settled && mode == "stable" {
        "undecided"
    } else {
        mode
    }
}

/// Tracks whether the structure has settled: every free block quiet for the window.
#[derive(Debug, Clone, Default)]
pub struct SettleWatch {
    quiet_since: Option<f64>,
}

impl SettleWatch {
    /// Record the state at `time` (s); returns whether the structure has settled.
    pub fn update(&mut self, time: f64, quiet: bool, window: f64) -> bool {
        if !quiet {
            self.quiet_since = None;
            return false;
        }
        let t0 = *self.quiet_since.get_or_insert(time);
        time - t0 >= window - 1e-12
    }

    /// s, when the present quiet spell began (`None` while a block moves).
    pub fn quiet_since(&self) -> Option<f64> {
        self.quiet_since
    }
}

/// World y (m) below which a free block has left the scene: the scene's height below its
/// lowest fixed or driven block (at the start). `None` when nothing is fixed or driven.
pub fn retirement_floor(scene: &Scene) -> Option<f64> {
    let ys = || {
        scene
            .blocks
            .iter()
            .flat_map(|b| b.vertices.iter().map(|p| p.y))
    };
    let top = ys().fold(f64::NEG_INFINITY, f64::max);
    let bottom = ys().fold(f64::INFINITY, f64::min);
    let driven = match scene.excitation {
        Excitation::DrivenBlock(d) => Some(d),
        Excitation::BaseAcceleration => None,
    };
    let lowest_support = scene
        .blocks
        .iter()
        .enumerate()
        .filter(|(i, b)| matches!(b.kind, crate::scene::BlockKind::Fixed) || Some(*i) == driven)
        .flat_map(|(_, b)| b.vertices.iter().map(|p| p.y))
        .fold(f64::INFINITY, f64::min);
    lowest_support
        .is_finite()
        .then_some(lowest_support - (top - bottom))
}

/// Full engine: retire the free blocks whose centroid is below `floor`; returns the events.
pub fn retire_fallen(sim: &mut Simulation, floor: Option<f64>) -> Vec<RunEvent> {
    let Some(floor) = floor else {
        return Vec::new();
    };
    let mut events = Vec::new();
    for b in 0..sim.geoms().len() {
        if sim.mobility()[b] != Mobility::Free || sim.retired()[b] {
            continue;
        }
        if sim.geoms()[b].centroid.y < floor {
            sim.retire(b);
            events.push(RunEvent {
                time: sim.time(),
                block: sim.scene().blocks[b].id.clone(),
                kind: "retired".into(),
            });
        }
    }
    events
}

/// Full engine: kinetic energy (J per m of thickness) of free block `b`'s rigid motion
/// relative to the ground (the ground moves only under a driven block; base-acceleration
/// scenes are solved relative to it already).
pub fn kinetic_energy(sim: &Simulation, b: usize) -> f64 {
    let Some(f) = sim.dofs().free_index[b] else {
        return 0.0;
    };
    let g = &sim.geoms()[b];
    let rho = sim.scene().materials[sim.scene().blocks[b].material].density;
    let mut v = sim.states()[f].vel;
    if let Excitation::DrivenBlock(_) = sim.scene().excitation {
        let gv = sim.motion().state(sim.time())[1];
        v[0] -= gv[0];
        v[1] -= gv[1];
    }
    for k in 3..6 {
        v[k] = 0.0;
    }
    0.5 * (v.transpose() * g.mass_matrix(rho) * v)[(0, 0)]
}

/// Full engine: is every free block that is still in the scene quiet (kinetic energy below
/// `settle_energy_ratio`·m·g·L)?
pub fn all_quiet(sim: &Simulation, params: &RunEndParams) -> bool {
    (0..sim.geoms().len())
        .filter(|&b| sim.mobility()[b] == Mobility::Free && !sim.retired()[b])
        .all(|b| {
            let g = &sim.geoms()[b];
            let rho = sim.scene().materials[sim.scene().blocks[b].material].density;
            let m = rho * g.moments.area;
            let bound = params.settle_energy_ratio * m * sim.scene().gravity.abs() * g.half_size;
            kinetic_energy(sim, b) <= bound
        })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn settle_watch_needs_the_whole_window() {
        let mut w = SettleWatch::default();
        assert!(!w.update(0.0, true, 0.1));
        assert!(!w.update(0.05, true, 0.1));
        assert!(!w.update(0.08, false, 0.1), "motion restarts the window");
        assert!(!w.update(0.1, true, 0.1));
        assert!(w.update(0.2, true, 0.1));
    }

    #[test]
    fn the_ground_is_still_after_the_last_non_zero_sample() {
        use crate::motion::{Sampled, Signal};
        let rec = GroundMotion::horizontal(Signal::Sampled(Sampled::new(
            0.01,
            vec![0.0, 1.0, -2.0, 0.0, 0.0, 0.0],
        )));
        // Linear between samples: a(t) ≠ 0 on (0, 0.03), zero from sample 3 (0.03 s) on.
        assert!((rec.still_from().expect("a record ends") - 0.03).abs() < 1e-12);
        assert_eq!(rec.scaled(0.0).still_from(), Some(0.0));
        let sine = GroundMotion::horizontal(Signal::Sine {
            amplitude: 1.0,
            frequency: 2.0,
        });
        assert_eq!(sine.still_from(), None);
        assert_eq!(sine.scaled(0.0).still_from(), Some(0.0));
        assert_eq!(GroundMotion::none().still_from(), Some(0.0));
        // The rule needs the whole settle window (0.1 s) quiet under the still ground (from
        // 1 s), whenever the quiet spell began.
        assert!(!may_end_still(Some(1.0), Some(0.5), 1.05, 0.1));
        assert!(may_end_still(Some(1.0), Some(0.5), 1.1, 0.1));
        assert!(!may_end_still(Some(1.0), Some(1.2), 1.25, 0.1));
        assert!(may_end_still(Some(1.0), Some(1.2), 1.3, 0.1));
        assert!(!may_end_still(Some(1.0), None, 5.0, 0.1));
        assert!(!may_end_still(None, Some(0.0), 5.0, 0.1));
    }

    #[test]
    fn undecided_replaces_stable_only() {
        assert_eq!(verdict("stable", false), "undecided");
        assert_eq!(verdict("stable", true), "stable");
        assert_eq!(verdict("toppling", false), "toppling");
    }
}
