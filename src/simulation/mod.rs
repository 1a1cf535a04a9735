//! Simulation: the DDA time step, assembled from the stages of the flow. `step` reads like
//! the algorithm: detect contacts, then (with time-step cuts on failure) assemble, run the
//! open–close loop and check the step, then integrate, then check that the state is finite.
//! Each stage is timed into [`StepProfile`]. The engine is two parts: the state it advances
//! (`state.rs`: geometry, block states, contacts) and the stepper that advances it
//! (`stepper.rs`: system, solvers and their scratch, the adaptive step, counters); the stages
//! are `stages.rs`, the acceptance of a step `control.rs`, what a failed step reports
//! `diagnostics.rs`, its errors `error.rs`.
mod control;
mod diagnostics;
mod energy;
mod error;
mod params;
mod stages;
mod state;
mod stepper;

pub use diagnostics::{Stats, StepProfile};
pub use energy::Energy;
pub use error::SimError;
pub use params::{resolve_penalty, ClosingParams, SimParams, IMPACT_APPROACH_RATIO};

use crate::assembly::contact_springs::SpringParams;
use crate::assembly::{BlockState, BlockSystem, Dofs};
use crate::contact::{ContactSet, Mobility};
use crate::geometry::BlockGeometry;
use crate::motion::GroundMotion;
use crate::scene::{ContactSolver, Control, Restitution, Scene};
use crate::solve::dual::DualOutcome;
use crate::solve::open_close::{self, OpenClose};
use control::Refusal;
use state::SimState;
use std::time::Instant;
use stepper::Stepper;

/// The engine of one scene under one ground motion: its state and the stepper that advances
/// it. Read through the accessors below; only [`Simulation::step`] and [`Simulation::retire`]
/// change it (and the `set_…`/`…_mut` accessors, for tests and restarted runs).
pub struct Simulation {
    params: SimParams,
    state: SimState,
    stepper: Stepper,
}

impl std::fmt::Debug for Simulation {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Simulation")
            .field("time", &self.state.time)
            .field("dt", &self.stepper.dt)
            .field("blocks", &self.state.geoms.len())
            .finish()
    }
}

/// The engine knobs a scene may set (`control.dual_tolerance`, `control.dual_stall_acceptance`,
/// `control.unconverged_floor`) override the caller's; unset ones keep them. A scene's own dual
/// tolerance is taken as given, without the small-Δt cap (`DualParams::settling_fraction`): it
/// is the user's trade of accuracy for speed (the pile's 1e-4, docs/dual.md). Under the dual
/// contact solver the impact law runs without the hand-over, which is the penalty pivot's
/// (`ImpactParams::without_hand_over`).
fn with_scene_knobs(mut params: SimParams, control: &Control) -> SimParams {
    if control.contact_solver == ContactSolver::Dual {
        params.impact = params.impact.without_hand_over();
    }
    if let Some(t) = control.dual_tolerance {
        params.dual.tolerance = t;
        params.dual.settling_fraction = 0.0;
    }
    if let Some(a) = control.dual_stall_acceptance {
        params.dual.stall_acceptance = a;
    }
    if let Some(r) = control.unconverged_floor {
        // 0 is "no floor", as `None` in the engine's knob.
        params.unconverged_floor_ratio = (r > 0.0).then_some(r);
    }
    params
}

impl Simulation {
    pub fn new(scene: &Scene, motion: &GroundMotion, params: SimParams) -> Self {
        let params = with_scene_knobs(params, &scene.control);
        let state = SimState::new(scene, motion);
        let stepper = Stepper::new(&state, &params);
        Self {
            params,
            state,
            stepper,
        }
    }

    /// Advance one step of at most `max_dt` (and at most the current adaptive step).
    /// Returns the step length taken. A step that leaves a non-finite state fails with
    /// [`SimError::NonFinite`] naming the block.
    pub fn step(&mut self, max_dt: f64) -> Result<f64, SimError> {
        let t0 = Instant::now();
        self.detect_contacts();
        self.stepper.profile.detect += t0.elapsed();
        let dt = self
            .stepper
            .dt
            .min(max_dt)
            .min(self.rotation_bound())
            .min(self.rocking_bound());
        let impacts_before = self.stepper.stats.impacts;
        let full = dt;
        let dt = self.restitution(dt);
        if dt < full {
            self.stepper.stats.located_steps += 1;
        }
        // The trapezoidal rule averages a₀, the acceleration stored at the last step's end,
        // which an impact just made stale (it is the motion before the impulse: a rocking
        // column's θ̈ about the pivot it left); the step after an impact then takes DDA's rule,
        // which does not read a₀ (`SimParams::restart_after_impact`).
        let restart = self.params.restart_after_impact
            && self.stepper.stats.impacts > impacts_before
            && self.stepper.newmark.gamma != 1.0;
        let saved = (self.stepper.newmark, self.stepper.springs.release_weight);
        if restart {
            self.stepper.newmark = crate::assembly::Newmark::of(crate::scene::Integrator::Dda);
            self.stepper.springs.release_weight = 0.0;
        }
        // Before the friction normal's prediction, which predicts a contact predicted to
        // slip as a sliding one.
        let oc = &self.params.open_close;
        if self.state.scene.control.contact_solver == ContactSolver::Penalty
            && (oc.stick_predict.is_some()
                || oc.slip_predict.is_some()
                || oc.gap_predict.is_some()
                || oc.head_slip_predict.is_some())
        {
            if oc.head_slip_spin {
                self.note_spin_reversals();
            }
            let oc = &self.params.open_close;
            open_close::predict_stick_slip(
                &mut self.state.contacts.contacts,
                &self.state.laws,
                &self.stepper.springs,
                oc,
                &self.stepper.spin_reversed,
            );
            // After the stick–slip prediction: a head joint predicted to open or close starts
            // in that state whatever its slip predicted.
            open_close::predict_gaps(
                &mut self.state.contacts.contacts,
                &self.state.laws,
                &self.stepper.springs,
                oc,
            );
        }
        if let (ContactSolver::Penalty, Some(gain)) = (
            self.state.scene.control.contact_solver,
            self.params.open_close.friction_predict,
        ) {
            open_close::predict_friction_normals(&mut self.state.contacts.contacts, gain);
        }
        let taken = self.solve_and_integrate(dt);
        self.stepper.newmark = saved.0;
        self.stepper.springs.release_weight = saved.1;
        taken
    }

    /// The step from its solve on (see [`Simulation::step`]).
    fn solve_and_integrate(&mut self, dt: f64) -> Result<f64, SimError> {
        let (dt, cuts) = self.solve_with_cuts(dt)?;
        if let Some(e) = self.too_soft(dt) {
            return Err(e);
        }
        let error = if self.state.scene.control.adaptive_time_step {
            self.local_error(dt).map(|(_, e)| e)
        } else {
            None
        };
        let t3 = Instant::now();
        self.integrate(dt);
        self.stepper.profile.integrate += t3.elapsed();
        self.finish_step(dt, cuts, error);
        self.check_finite()?;
        Ok(dt)
    }

    /// Newton's impact law at the step start, if the scene asks for it; returns the step to
    /// take (see `impacts`).
    fn restitution(&mut self, dt: f64) -> f64 {
        // "housner" is Newton's law with e = 0 (an impact without bounce); "contact" leaves the
        // impact to the contact springs / dual solver.
        match self.state.scene.control.restitution {
            Restitution::Housner => self.impacts(0.0, dt),
            Restitution::Coefficient(e) => self.impacts(e, dt),
            Restitution::Contact => dt,
        }
    }

    /// Assemble, solve and check the step, cutting Δt while it is refused. Returns the step
    /// length accepted and the number of cuts, or the typed error of a step refused at the
    /// last cut allowed.
    fn solve_with_cuts(&mut self, mut dt: f64) -> Result<(f64, u32), SimError> {
        self.state.start_states.clone_from(&self.state.states);
        self.stepper.taken_unconverged = false;
        let mut cuts = 0u32;
        let floor = self.unconverged_floor();
        // Once the floor's penetration bound refused an iterate, this step is cut below the
        // floor like any non-converging step (no clamp to the floor).
        let mut below_floor = false;
        // The deepest contact closed at the step's start (m), read by the floor's bound: a
        // candidate contact that is not closed may have a negative gap without touching (its
        // vertex behind the edge's line, beyond the edge), so open ones are left out.
        let start_depth = if floor > 0.0 {
            self.state
                .contacts
                .contacts
                .iter()
                .filter(|c| c.state.is_closed())
                .map(|c| -c.g0)
                .fold(0.0, f64::max)
        } else {
            0.0
        };
        loop {
            self.assemble(dt);
            let t2 = Instant::now();
            let at_floor = dt <= floor * (1.0 + self.params.unconverged_floor_tolerance);
            let refusal = match self.state.scene.control.contact_solver {
                // The iteration cap is the floor's; below it (after the bound refused an
                // iterate) the loop runs as without the floor.
                ContactSolver::Penalty => match self.open_close(at_floor && !below_floor)? {
                    OpenClose::Converged { .. } => self.check_step(dt),
                    OpenClose::NotConverged { contact, .. } => Some(Refusal::Unconverged(contact)),
                },
                ContactSolver::Dual => match self.dual_solve()? {
                    DualOutcome {
                        converged: true, ..
                    } => self.check_step(dt),
                    DualOutcome { worst, .. } => Some(Refusal::Unconverged(worst)),
                },
            };
            self.stepper.profile.solve += t2.elapsed();
            // At the floor of `unconverged_floor_ratio`, an unconverged loop's last iterate is
            // taken if the step's other checks accept it and it leaves no contact deeper than
            // the floor's penetration bound.
            let refusal = match refusal {
                Some(Refusal::Unconverged(_)) if at_floor => match self.check_step(dt) {
                    None => match self.floor_penetration_exceeded(start_depth) {
                        None => {
                            self.stepper.stats.unconverged_taken += 1;
                            self.stepper.taken_unconverged = true;
                            None
                        }
                        Some(k) => {
                            self.stepper.stats.unconverged_floor_refused += 1;
                            below_floor = true;
                            Some(Refusal::Unconverged(Some(k)))
                        }
                    },
                    r => r,
                },
                r => r,
            };
            let Some(refusal) = refusal else { break };
            self.stepper.refusals[match refusal {
                Refusal::Unconverged(_) => 0,
                Refusal::Moved { .. } => 1,
                Refusal::Overshot(_) => 2,
                Refusal::Impact { .. } | Refusal::LocalError { .. } => 3,
            }] += 1;
            // An accuracy bound never fails a run: out of cuts, the step is taken as it is.
            if refusal.is_accuracy() && cuts >= self.params.max_cuts {
                break;
            }
            cuts += 1;
            self.stepper.stats.time_step_cuts += 1;
            // Cutting below min_dt means the step cannot be resolved: fail with a diagnostic
            // instead of creeping forward at a vanishing step.
            if cuts > self.params.max_cuts || dt * self.params.cut_factor < self.params.min_dt {
                return Err(self.refused(cuts, dt, refusal));
            }
            dt *= refusal.factor(self.params.cut_factor);
            if matches!(refusal, Refusal::Unconverged(_)) && !below_floor {
                dt = dt.max(floor);
            }
            self.state.states.clone_from(&self.state.start_states);
        }
        Ok((dt, cuts))
    }

    /// The shortest Δt a non-converging loop is cut to (`SimParams::unconverged_floor_ratio`),
    /// s; 0 without the floor.
    /// Penalty solver only: an unconverged dual solve leaves no iterate to take (its
    /// increments are not written), so under the dual solver the floor is 0 and a
    /// non-converging step is cut as without it (scene validation refuses the combination).
    pub(super) fn unconverged_floor(&self) -> f64 {
        if self.state.scene.control.contact_solver == ContactSolver::Dual {
            return 0.0;
        }
        self.params
            .unconverged_floor_ratio
            .map_or(0.0, |r| r * self.state.scene.control.time_step)
    }

    /// Work counters of the sparse linear solver (factorizations, reused-factor iterations).
    pub fn solver_counts(&self) -> crate::solve::SparseCounts {
        self.stepper.solver.sparse_counts()
    }

    /// The linear system the last linear solve of [`Simulation::step`] solved, read-only, for
    /// verification (tests/engine/invariants.rs checks its symmetry and that the step's increments
    /// solve it). With the penalty contact solver: block terms + the contact springs of the
    /// converged open–close iteration (the step's last solve; integration does not touch it).
    /// With the dual solver: the block terms its flexibilities come from (no springs).
    /// Off-diagonal blocks are stored once per coupled pair: `off[p]` is K_ab for
    /// `pairs[p] = (a, b)`, a < b, and the solvers read K_ba as K_abᵀ.
    pub fn solved_system(&self) -> &BlockSystem {
        &self.stepper.system
    }

    /// The increments of the step's last solve (global unknowns in `dofs` order, 6 a block:
    /// u0, v0, r0, εx, εy, γxy): with the penalty solver, the solution of
    /// [`Simulation::solved_system`].
    pub fn solved_increments(&self) -> &[f64] {
        &self.stepper.x
    }

    /// Contact search distance, m: Shi's search factor × the largest step displacement. One
    /// definition for detection, the dual solver and the penetration check.
    pub fn search_distance(&self) -> f64 {
        self.params.contact.search_factor * self.max_step_displacement()
    }

    /// Largest displacement allowed in one step (Shi's g2 × model half size), m.
    pub fn max_step_displacement(&self) -> f64 {
        self.state.scene.control.max_displacement_ratio * self.state.model_half_size
    }

    /// Velocity of a block's centroid and its angular velocity (m/s, rad/s); driven blocks move
    /// with the ground, fixed blocks are still.
    pub fn block_velocity(&self, b: usize) -> [f64; 3] {
        self.state.block_velocity(b)
    }

    /// Retire free block `b` (see `SimState::retire`): it left the scene, so it is frozen
    /// where it is and costs the step control nothing from now on.
    pub fn retire(&mut self, b: usize) {
        self.state.retire(b)
    }

    /// The first block whose position, rotation or velocity is not finite (`step` fails with
    /// [`SimError::NonFinite`] naming it).
    pub fn first_non_finite_block(&self) -> Option<usize> {
        self.state.first_non_finite_block()
    }

    /// Restart the clock at `time`, s (a run continued from a saved state).
    pub fn set_time(&mut self, time: f64) {
        self.state.time = time;
    }

    /// Change `control.kinetic_damping_rate` between steps, 1/s (a test settles a block
    /// under damping, then releases it).
    pub fn set_kinetic_damping_rate(&mut self, rate: f64) {
        self.state.scene.control.kinetic_damping_rate = rate;
    }

    /// Per free block (in `dofs` order), to set: velocity, acceleration, stress (a test
    /// launches a block, or feeds a state the step must refuse).
    pub fn states_mut(&mut self) -> &mut [BlockState] {
        &mut self.state.states
    }

    /// Simulated time, s.
    pub fn time(&self) -> f64 {
        self.state.time
    }

    /// Current (adaptive) time step, s.
    pub fn dt(&self) -> f64 {
        self.stepper.dt
    }

    pub fn scene(&self) -> &Scene {
        &self.state.scene
    }

    pub fn motion(&self) -> &GroundMotion {
        &self.state.motion
    }

    /// The engine knobs in force (the caller's, with the scene's overrides).
    pub fn params(&self) -> &SimParams {
        &self.params
    }

    /// Per block: the current geometry.
    pub fn geoms(&self) -> &[BlockGeometry] {
        &self.state.geoms
    }

    /// Per block: fixed, driven or free.
    pub fn mobility(&self) -> &[Mobility] {
        &self.state.mobility
    }

    /// The numbering of the unknowns (free blocks).
    pub fn dofs(&self) -> &Dofs {
        &self.state.dofs
    }

    /// Per free block (in `dofs` order): velocity, acceleration, stress.
    pub fn states(&self) -> &[BlockState] {
        &self.state.states
    }

    pub fn contacts(&self) -> &ContactSet {
        &self.state.contacts
    }

    /// The contact springs' parameters (penalty, shear, gap tolerance).
    pub fn springs(&self) -> &SpringParams {
        &self.stepper.springs
    }

    /// Half the diagonal of the whole model's bounding box at the start, m.
    pub fn model_half_size(&self) -> f64 {
        self.state.model_half_size
    }

    /// Per block: 4·area / perimeter at the start, m (see `SimState::thickness`).
    pub fn thickness(&self) -> &[f64] {
        &self.state.thickness
    }

    /// Per block: retired (see [`Simulation::retire`]).
    pub fn retired(&self) -> &[bool] {
        &self.state.retired
    }

    /// The last accepted step's closing contacts as the closing limit saw them (with
    /// `SimParams::closing` on; (0, 0) otherwise): how many closed within the step, and the
    /// largest approach among them as a multiple of its elastic range W/k_n.
    pub fn last_closing(&self) -> (usize, f64) {
        self.stepper.last_closing
    }

    pub fn stats(&self) -> Stats {
        self.stepper.stats
    }

    /// How the last step's impulse solve went (all zero if the step had no impact).
    pub fn impact_report(&self) -> crate::solve::impulse::ImpulseReport {
        self.stepper.impulse_report
    }

    /// Wall time per stage, accumulated over the steps.
    pub fn profile(&self) -> StepProfile {
        self.stepper.profile
    }

    /// Why the open–close loop iterated.
    pub fn changes(&self) -> &open_close::ChangeCounts {
        &self.stepper.changes
    }

    /// Step attempts refused, by reason: [contact solve not converged, a block moved beyond
    /// the step limit, a contact overshot, a step-control bound].
    pub fn refusals(&self) -> [u64; 4] {
        self.stepper.refusals
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::presets::Column;
    use serde_json::json;

    /// A non-finite state never leaves `step`: the check inside it (after integration) fails
    /// with the typed `SimError::NonFinite` naming the block, so the run loop in
    /// `analysis::run` checks nothing itself. The seed column's rotation angle is fed a NaN
    /// (the solvers never read it, so only the step's own check can see it).
    #[test]
    fn a_non_finite_state_is_refused_naming_the_block() {
        let scene = Column::SEED
            .scene(json!({ "time_step": 1e-3, "duration": 0.01 }))
            .expect("the seed column parses");
        let mut sim = Simulation::new(&scene, &GroundMotion::none(), SimParams::default());
        sim.step(1.0).expect("a step at rest");
        let column = 1;
        assert_eq!(sim.scene().blocks[column].id, "column");
        sim.state.geoms[column].rotation = f64::NAN;
        match sim.step(1.0) {
            Err(SimError::NonFinite { time, block }) => {
                assert_eq!(block, "column");
                assert!((time - 2e-3).abs() < 1e-12, "time {time}");
            }
            other => panic!("expected NonFinite naming the column, got {other:?}"),
        }
    }

    /// A 4 × 5 wall of the presets after one step at rest: contacts detected, linearized and
    /// converged, the fixture of the unit tests below that set states and histories by hand.
    fn wall_after_a_step_at_rest() -> Simulation {
        let scene = crate::scene::validate(&crate::presets::wall(4, 5)).expect("wall scene");
        let mut sim = Simulation::new(&scene, &GroundMotion::none(), SimParams::default());
        sim.step(1.0).expect("a step at rest");
        sim
    }

    /// `ChangeCounts::last_kind` counts the changes left after the last iteration of every
    /// loop that stopped unconverged: each such loop ends with at least one change asking for
    /// a solve, so their sum is at least the loops refused as unconverged (`refusals()[0]`, a
    /// counter of its own). A 4 × 5 wall shaken at 1 g with the loop held to 2 iterations,
    /// 50 steps (or to a step that fails after its cuts), the cycle rule on as
    /// by default, so the loop's last iteration (2) is not `iteration_limit` (12): before the
    /// count was taken at the loop's end it was 0 here.
    #[test]
    fn a_failing_loop_leaves_its_last_changes_counted() {
        let scene = crate::scene::validate(&crate::presets::wall(4, 5)).expect("wall scene");
        let mut params = SimParams::default();
        params.open_close.max_iterations = 2;
        assert!(params.open_close.iteration_limit() > 2, "the cycle rule on");
        // Shaken hard (1 g at 5 Hz), so its contacts keep changing state.
        let shake = GroundMotion::horizontal(crate::motion::Signal::Sine {
            amplitude: 9.81,
            frequency: 5.0,
        });
        let mut sim = Simulation::new(&scene, &shake, params);
        // Cut or not down to its limit, a step's loops are counted as they end.
        for _ in 0..50 {
            if sim.step(1.0).is_err() {
                break;
            }
        }
        let refused = sim.refusals()[0];
        let ch = sim.changes();
        let last: u64 = ch.last_kind.iter().flatten().sum();
        assert!(refused > 0, "the loop must fail at 2 iterations");
        assert!(
            last >= refused,
            "{last} changes left for {refused} failing loops"
        );
        assert_eq!(ch.last_force.iter().sum::<u64>(), last);
        for (k, (l, all)) in ch.last_kind.iter().zip(&ch.by_kind).enumerate() {
            assert!(
                l[0] <= all[0] && l[1] <= all[1],
                "kind {k}: {l:?} of {all:?}"
            );
        }
    }

    /// The friction normal's prediction (`OpenCloseParams::friction_predict`) against its
    /// closed form: a sliding contact closed at both step starts is predicted
    /// max(0, N₁ + g·(N₁ − N₀)); without a remembered force, or not sliding, nothing; an open
    /// contact forgets its force. Contacts of a 4 × 5 wall after one step at rest, with their
    /// states and forces set by hand (exact arithmetic on integers, so the comparison is exact).
    #[test]
    fn the_friction_normal_prediction_extrapolates_the_last_two_steps() {
        use crate::contact::ContactState;
        use crate::solve::open_close::predict_friction_normals;
        let sim = wall_after_a_step_at_rest();
        let mut cs: Vec<_> = sim.state.contacts.contacts[..4].to_vec();
        let sliding = ContactState::Sliding { dir: 1.0 };
        let states = [sliding, sliding, ContactState::Open, ContactState::Locked];
        for (c, s) in cs.iter_mut().zip(states) {
            c.state = s;
            c.normal_force = 100.0;
            c.prior_normal_force = None;
        }
        let predicted = |cs: &[crate::contact::Contact]| -> Vec<Option<f64>> {
            cs.iter().map(|c| c.predicted_friction_normal).collect()
        };
        // First step start: nothing remembered, nothing predicted.
        predict_friction_normals(&mut cs, 1.0);
        assert_eq!(predicted(&cs), [None, None, None, None]);
        let prior: Vec<_> = cs.iter().map(|c| c.prior_normal_force).collect();
        assert_eq!(prior, [Some(100.0), Some(100.0), None, Some(100.0)]);
        // Second step start: the last step ended at 130, 20 (sliding), open, 40 (locked).
        cs[0].normal_force = 130.0;
        cs[1].normal_force = 20.0;
        cs[3].normal_force = 40.0;
        cs[2].state = sliding;
        predict_friction_normals(&mut cs, 1.0);
        // 130 + (130 − 100); 20 − 80 clamped to 0; no remembered force; locked: none.
        assert_eq!(predicted(&cs), [Some(160.0), Some(0.0), None, None]);
        // Gain 0.5 from (130 remembered, 160 now).
        cs[0].normal_force = 160.0;
        predict_friction_normals(&mut cs, 0.5);
        assert_eq!(cs[0].predicted_friction_normal, Some(175.0));
    }

    /// The stick–slip prediction (`OpenCloseParams::stick_predict`, `slip_predict`) against its
    /// closed form: the slip over the step is extrapolated, σ = σ₁ + g·(σ₁ − σ₀), and the loop's
    /// own tests decide on it: a sliding contact (direction d) starts locked when σ·d <
    /// −(h·limit/k_s + tol); a locked one starts sliding, in the direction of s₀ + σ, when
    /// |k_s·(s₀ + σ)| > limit·(1 + h) + k_s·tol. Contacts of a 4 × 5 wall after one step at rest,
    /// states and slips set by hand, thresholds from the wall's own springs and joint law; each
    /// case sits at least a factor 2 inside or outside its threshold (a test of the decision,
    /// not of the rounding at the boundary).
    #[test]
    fn the_stick_slip_prediction_extrapolates_the_last_two_slips() {
        use crate::assembly::contact_springs::shear_limit;
        use crate::contact::ContactState::{Locked, Open, Sliding};
        use crate::solve::open_close::{predict_stick_slip, OpenCloseParams};
        let sim = wall_after_a_step_at_rest();
        let springs = sim.stepper.springs;
        let laws = &sim.state.laws[..8];
        let mut cs: Vec<_> = sim.state.contacts.contacts[..8].to_vec();
        for c in &mut cs {
            c.normal_force = 1000.0;
            c.s0 = 0.0;
            c.bonded = false;
        }
        let params = OpenCloseParams {
            stick_predict: Some(1.0),
            slip_predict: Some(1.0),
            ..OpenCloseParams::default()
        };
        let h = params.hysteresis;
        let limit = shear_limit(&cs[0], &laws[0], 1000.0);
        assert!(laws.iter().all(|l| *l == laws[0]) && limit > 0.0);
        // Re-sticking threshold on the slip (m) and onset threshold on the displacement (m).
        let stick = h * limit / springs.shear + springs.gap_tolerance;
        let onset = (limit * (1.0 + h) + springs.shear * springs.gap_tolerance) / springs.shear;
        // (state, σ₁, σ₀): the expected start.
        let cases = [
            // Slowing from 4·stick to stick: σ = −2·stick, reversal → locked.
            (
                Sliding { dir: 1.0 },
                Some(stick),
                Some(4.0 * stick),
                Some(Locked),
            ),
            // Slowing from 4 to 3: σ = 2·stick, still forward → as it is.
            (
                Sliding { dir: 1.0 },
                Some(3.0 * stick),
                Some(4.0 * stick),
                None,
            ),
            // The mirror of the first, sliding the other way.
            (
                Sliding { dir: -1.0 },
                Some(-stick),
                Some(-4.0 * stick),
                Some(Locked),
            ),
            // No history of the step before: nothing predicted.
            (Sliding { dir: 1.0 }, Some(stick), None, None),
            // Locked, loading at 0.6·onset a step: s₀ + σ = 1.2·onset → slides forward.
            (
                Locked,
                Some(0.6 * onset),
                Some(0.0),
                Some(Sliding { dir: 1.0 }),
            ),
            // Locked, loading at 0.4·onset: 0.8·onset → stays locked.
            (Locked, Some(0.4 * onset), Some(0.0), None),
            // Loading the other way, steady at −1.2·onset a step → slides backward.
            (
                Locked,
                Some(-1.2 * onset),
                Some(-1.2 * onset),
                Some(Sliding { dir: -1.0 }),
            ),
            // Open: never.
            (Open, Some(stick), Some(4.0 * stick), None),
        ];
        for (c, &(state, s1, s0, _)) in cs.iter_mut().zip(&cases) {
            // A bed joint (the onset of slip is predicted on bed joints only).
            c.n = nalgebra::Vector2::new(0.0, 1.0);
            c.state = state;
            c.last_slip = s1;
            c.prior_slip = s0;
            c.predicted_state = Some(Open);
        }
        predict_stick_slip(&mut cs, laws, &springs, &params, &[]);
        for (k, (c, case)) in cs.iter().zip(&cases).enumerate() {
            assert_eq!(c.predicted_state, case.3, "case {k}");
        }
        // A head joint (normal horizontal) loading as case 4: not predicted to slip.
        cs[4].n = nalgebra::Vector2::new(1.0, 0.0);
        predict_stick_slip(&mut cs, laws, &springs, &params, &[]);
        assert_eq!(cs[4].predicted_state, None);
        // Off: nothing predicted (and the stale mark cleared).
        let off = OpenCloseParams {
            stick_predict: None,
            slip_predict: None,
            ..params
        };
        predict_stick_slip(&mut cs, laws, &springs, &off, &[]);
        assert!(cs.iter().all(|c| c.predicted_state.is_none()));
    }

    /// The head joints' onset prediction (`OpenCloseParams::head_slip_predict`) against its
    /// closed form: a locked head joint whose gap is predicted to stay closed (g₀ + Δ₁ at the
    /// gap rule's gain 0, not above the length tolerance) starts sliding, in the direction of
    /// s₀ + σ with σ = σ₁ + g·(σ₁ − σ₀), when |s₀ + σ| exceeds the onset threshold
    /// (limit·(1 + h) + k_s·tol)/k_s of the Coulomb limit of the *predicted* normal force
    /// −k_n·(g₀ + Δ₁), not of the last one. Contacts of a 4 × 5 wall after one step at rest,
    /// every length in units of the wall's own tolerance; each decision at least a factor 2
    /// from its threshold (a test of the decision, not of the rounding at the boundary).
    #[test]
    fn the_head_onset_prediction_uses_the_predicted_normal_force() {
        use crate::assembly::contact_springs::shear_limit;
        use crate::contact::ContactState::{Locked, Sliding};
        use crate::solve::open_close::{predict_stick_slip, OpenCloseParams};
        let sim = wall_after_a_step_at_rest();
        let springs = sim.stepper.springs;
        let laws = &sim.state.laws[..8];
        let mut cs: Vec<_> = sim.state.contacts.contacts[..8].to_vec();
        let tol = springs.gap_tolerance;
        let params = OpenCloseParams {
            stick_predict: None,
            slip_predict: None,
            head_slip_predict: Some(1.0),
            gap_predict: Some(0.0),
            ..OpenCloseParams::default()
        };
        let h = params.hysteresis;
        assert!(laws.iter().all(|l| *l == laws[0]));
        // The onset threshold on the shear displacement (m) at a normal force N.
        let onset = |n: f64| {
            (shear_limit(&cs[0], &laws[0], n) * (1.0 + h) + springs.shear * tol) / springs.shear
        };
        // A compressed head joint: predicted gap −10 tol, so N = 10·k_n·tol; its threshold must
        // be well above the unloaded one for the cases below to tell the two forces apart.
        let loaded = 10.0 * springs.normal * tol;
        let (hi, lo) = (onset(loaded), onset(0.0));
        assert!(hi > 5.0 * lo, "thresholds {hi:e} {lo:e}");
        // (last normal force N, g₀, Δ₁, Δ₀, σ₁, σ₀): the expected start. s₀ = 0.
        let cases = [
            // Predicted N = loaded, loading at 0.6·hi a step from rest: s = 1.2·hi → slides.
            (
                loaded,
                -9.0,
                Some(-1.0),
                Some(0.0),
                0.6 * hi,
                0.0,
                Some(Sliding { dir: 1.0 }),
            ),
            // The same at 0.4·hi: s = 0.8·hi → stays as it is.
            (loaded, -9.0, Some(-1.0), Some(0.0), 0.4 * hi, 0.0, None),
            // Last N = 0 (its threshold lo) but predicted N = loaded: s = 0.5·hi ≫ lo → as it
            // is (the last force's limit would make it slide).
            (0.0, -9.0, Some(-1.0), Some(5.0), 0.25 * hi, 0.0, None),
            // Last N = loaded but predicted unloaded (gap 0): s = −2·lo, below −lo → slides
            // backward (the last force's limit, hi > 5·lo, would keep it).
            (
                loaded,
                -1.0,
                Some(1.0),
                Some(-3.0),
                -lo,
                0.0,
                Some(Sliding { dir: -1.0 }),
            ),
            // Predicted to open (gap 2 tol > tol): the gap rule's, not this one's.
            (0.0, 1.0, Some(1.0), Some(1.0), 10.0 * hi, 0.0, None),
            // No gap history: nothing.
            (loaded, -9.0, Some(-1.0), None, 10.0 * hi, 0.0, None),
            // Steady loading at 1.2·hi a step (σ₀ = σ₁): s = 1.2·hi → slides.
            (
                loaded,
                -9.0,
                Some(-1.0),
                Some(-1.0),
                1.2 * hi,
                1.2 * hi,
                Some(Sliding { dir: 1.0 }),
            ),
            // Slowing from 2·hi to 1.2·hi a step: s = 0.4·hi → as it is.
            (
                loaded,
                -9.0,
                Some(-1.0),
                Some(-1.0),
                1.2 * hi,
                2.0 * hi,
                None,
            ),
        ];
        let set = |cs: &mut [crate::contact::Contact]| {
            for (c, &(n, g0, d1, d0, s1, s0, _)) in cs.iter_mut().zip(&cases) {
                c.n = nalgebra::Vector2::new(1.0, 0.0);
                c.bonded = false;
                c.state = Locked;
                c.normal_force = n;
                c.s0 = 0.0;
                c.g0 = g0 * tol;
                c.last_gap_change = d1.map(|d| d * tol);
                c.prior_gap_change = d0.map(|d| d * tol);
                c.last_slip = Some(s1);
                c.prior_slip = Some(s0);
            }
        };
        set(&mut cs);
        predict_stick_slip(&mut cs, laws, &springs, &params, &[]);
        for (k, (c, case)) in cs.iter().zip(&cases).enumerate() {
            assert_eq!(c.predicted_state, case.6, "case {k}");
        }
        // A bed joint (normal vertical) as case 0: not this rule's (`slip_predict` is off).
        set(&mut cs);
        cs[0].n = nalgebra::Vector2::new(0.0, 1.0);
        predict_stick_slip(&mut cs, laws, &springs, &params, &[]);
        assert_eq!(cs[0].predicted_state, None);
        // Off: nothing predicted.
        set(&mut cs);
        let off = OpenCloseParams {
            head_slip_predict: None,
            ..params
        };
        predict_stick_slip(&mut cs, laws, &springs, &off, &[]);
        assert!(cs.iter().all(|c| c.predicted_state.is_none()));
    }

    /// The head onset prediction's margin and rocking guards (`OpenCloseParams::
    /// head_slip_margin`, `head_slip_steady`, `head_slip_shear_sign`, `head_slip_spin`,
    /// `head_slip_calm`)
    /// against their closed forms. Every case is a locked head joint predicted closed at the
    /// same compressed gap (so one Coulomb limit L, onset threshold on the shear displacement
    /// θ(m) = (m·L·(1 + h) + k_s·tol)/k_s at margin m), s = s₀ + σ₁ + (σ₁ − σ₀) at gain 1; each
    /// decision at least a factor 1.25 from its threshold. Without a guard every case but the
    /// margin's "stays" slides (the guards, not the threshold, decide).
    #[test]
    fn the_head_onset_guards_keep_rocking_joints_out() {
        use crate::assembly::contact_springs::shear_limit;
        use crate::contact::ContactState::{Locked, Sliding};
        use crate::solve::open_close::{predict_stick_slip, OpenCloseParams};
        let mut sim = wall_after_a_step_at_rest();
        let springs = sim.stepper.springs;
        let laws = &sim.state.laws[..8].to_vec();
        let mut cs: Vec<_> = sim.state.contacts.contacts[..8].to_vec();
        let tol = springs.gap_tolerance;
        let base = OpenCloseParams {
            stick_predict: None,
            slip_predict: None,
            head_slip_predict: Some(1.0),
            gap_predict: Some(0.0),
            ..OpenCloseParams::default()
        };
        let h = base.hysteresis;
        assert!(laws.iter().all(|l| *l == laws[0]));
        // Predicted gap −10 tol (g₀ = −9 tol, Δ₁ = −tol): N = 10·k_n·tol.
        let limit = shear_limit(&cs[0], &laws[0], 10.0 * springs.normal * tol);
        let onset = |m: f64| (m * limit * (1.0 + h) + springs.shear * tol) / springs.shear;
        let hi = onset(1.0);
        assert!(
            onset(2.0) > 1.9 * hi,
            "the margin must dominate the tolerance"
        );
        // (s₀, σ₁, σ₀), in units of hi.
        let set = |cs: &mut [crate::contact::Contact], s: (f64, f64, f64)| {
            for c in cs.iter_mut() {
                c.n = nalgebra::Vector2::new(1.0, 0.0);
                c.bonded = false;
                c.state = Locked;
                c.normal_force = 0.0;
                c.g0 = -9.0 * tol;
                c.last_gap_change = Some(-tol);
                c.prior_gap_change = Some(0.0);
                c.s0 = s.0 * hi;
                c.last_slip = Some(s.1 * hi);
                c.prior_slip = Some(s.2 * hi);
                c.flips = 0;
            }
        };
        let slide = Some(Sliding { dir: 1.0 });
        // (s₀, σ₁, σ₀), the rule's parameters, the expected start.
        let steady = OpenCloseParams {
            head_slip_steady: true,
            ..base
        };
        let shear_sign = OpenCloseParams {
            head_slip_shear_sign: true,
            ..base
        };
        let margin = OpenCloseParams {
            head_slip_margin: 2.0,
            ..base
        };
        let cases = [
            // Margin 2: s = 1.5·hi slides at margin 1, stays below θ(2) ≈ 2·hi; s = 3·hi slides.
            ((0.0, 0.75, 0.0), base, slide),
            ((0.0, 0.75, 0.0), margin, None),
            ((0.0, 1.5, 0.0), margin, slide),
            // The last two slips of opposite signs: s = 2.6·hi, guarded; same signs: 2.2·hi.
            ((0.0, 1.2, -0.2), base, slide),
            ((0.0, 1.2, -0.2), steady, None),
            ((0.0, 1.2, 0.2), steady, slide),
            // The shear displacement changed sign over the last step (s₀ − σ₁ = −0.5·hi
            // against s₀ = 0.1·hi): s = 1.3·hi, guarded; it kept its sign (0.1·hi): 1.9·hi.
            ((0.1, 0.6, 0.0), base, slide),
            ((0.1, 0.6, 0.0), shear_sign, None),
            ((0.7, 0.6, 0.0), shear_sign, slide),
        ];
        for (k, (s, params, expected)) in cases.iter().enumerate() {
            set(&mut cs, *s);
            predict_stick_slip(&mut cs[..1], laws, &springs, params, &[]);
            assert_eq!(cs[0].predicted_state, *expected, "case {k}");
        }
        // A joint whose state changed in the last step's loop (it slipped and re-stuck:
        // 2 flips) is left to the loop; one that did not change slides.
        let calm = OpenCloseParams {
            head_slip_calm: true,
            ..base
        };
        for (flips, expected) in [(2, None), (0, slide)] {
            set(&mut cs, (0.0, 1.2, 0.2));
            cs[0].flips = flips;
            predict_stick_slip(&mut cs[..1], laws, &springs, &calm, &[]);
            assert_eq!(cs[0].predicted_state, expected, "{flips} flips");
        }
        // A stone whose rotation rate changed sign: the joints it takes part in are guarded,
        // a joint between two other stones is not. The flags come from the simulation's own
        // bookkeeping: ω = +1 then −1 rad/s at two step starts.
        let (b, f) = [cs[0].vertex_block, cs[0].edge_block]
            .into_iter()
            .find_map(|b| sim.state.dofs.free_index[b].map(|f| (b, f)))
            .expect("a free stone");
        for w in [1.0, -1.0] {
            sim.state.states[f].vel[2] = w;
            sim.note_spin_reversals();
        }
        let reversed = &sim.stepper.spin_reversed;
        assert!(reversed[b] && reversed.iter().filter(|&&r| r).count() == 1);
        let other = cs
            .iter()
            .position(|c| c.vertex_block != b && c.edge_block != b)
            .expect("a joint between two other stones");
        let spin = OpenCloseParams {
            head_slip_spin: true,
            ..base
        };
        set(&mut cs, (0.0, 1.2, 0.2));
        predict_stick_slip(&mut cs, laws, &springs, &spin, reversed);
        assert_eq!(cs[0].predicted_state, None, "a rocking stone's joint");
        assert_eq!(cs[other].predicted_state, slide, "another joint");
        set(&mut cs, (0.0, 1.2, 0.2));
        predict_stick_slip(&mut cs, laws, &springs, &base, reversed);
        assert_eq!(cs[0].predicted_state, slide, "the guard off");
    }

    /// The gap prediction (`OpenCloseParams::gap_predict`) against its closed form: the gap
    /// change over the step is extrapolated, Δ = Δ₁ + g·(Δ₁ − Δ₀), and the loop's own tests
    /// decide on the predicted gap g₀ + Δ: a closed head joint starts open when it exceeds the
    /// length tolerance (no bond), an open one starts locked when it is below −tolerance.
    /// Contacts of a 4 × 5 wall after one step at rest, gaps and histories set by hand in
    /// units of the wall's own tolerance; each case at least a factor 2 from its threshold
    /// (a test of the decision, not of the rounding at the boundary).
    #[test]
    fn the_gap_prediction_extrapolates_the_last_two_gap_changes() {
        use crate::contact::ContactState::{Locked, Open, Sliding};
        use crate::solve::open_close::{predict_gaps, OpenCloseParams};
        let sim = wall_after_a_step_at_rest();
        let springs = sim.stepper.springs;
        let laws = &sim.state.laws[..8];
        let mut cs: Vec<_> = sim.state.contacts.contacts[..8].to_vec();
        let tol = springs.gap_tolerance;
        assert!(tol > 0.0);
        let params = OpenCloseParams {
            gap_predict: Some(1.0),
            ..OpenCloseParams::default()
        };
        // (state, g₀, Δ₁, Δ₀, the mark before, the expected mark), lengths in tolerances.
        let cases = [
            // Closed, opening faster: Δ = 1 + (1 + 2) = 4, gap 3 > 1 → open.
            (Locked, -1.0, Some(1.0), Some(-2.0), None, Some(Open)),
            // Closed, opening steadily from deep: Δ = 2, gap −2 → as it is.
            (Locked, -4.0, Some(1.0), Some(0.0), None, None),
            // Sliding, opening at 2 a step from 0: gap 2 → open, over the stick–slip mark.
            (
                Sliding { dir: 1.0 },
                0.0,
                Some(2.0),
                Some(2.0),
                Some(Locked),
                Some(Open),
            ),
            // Open, closing faster: Δ = −2 + (−2 + 1) = −3, gap −2 < −1 → closed, locked.
            (Open, 1.0, Some(-2.0), Some(-1.0), None, Some(Locked)),
            // Open, closing steadily from afar: Δ = −2, gap 2 → as it is.
            (Open, 4.0, Some(-1.0), Some(0.0), None, None),
            // Open, no history of the step before: nothing predicted.
            (Open, 1.0, Some(-2.0), None, None, None),
            // Closed and staying so: the stick–slip mark is kept.
            (
                Locked,
                -4.0,
                Some(0.0),
                Some(0.0),
                Some(Sliding { dir: 1.0 }),
                Some(Sliding { dir: 1.0 }),
            ),
            // Closed, opening slowly: Δ = 1, gap −1 → as it is.
            (Locked, -2.0, Some(1.0), Some(1.0), None, None),
        ];
        let set = |cs: &mut [crate::contact::Contact]| {
            for (c, &(state, g0, d1, d0, mark, _)) in cs.iter_mut().zip(&cases) {
                // A head joint (the rule acts on head joints only).
                c.n = nalgebra::Vector2::new(1.0, 0.0);
                c.bonded = false;
                c.state = state;
                c.g0 = g0 * tol;
                c.last_gap_change = d1.map(|d| d * tol);
                c.prior_gap_change = d0.map(|d| d * tol);
                c.predicted_state = mark;
            }
        };
        set(&mut cs);
        predict_gaps(&mut cs, laws, &springs, &params);
        for (k, (c, case)) in cs.iter().zip(&cases).enumerate() {
            assert_eq!(c.predicted_state, case.5, "case {k}");
        }
        // Gain 0 (the gap extrapolated from the last two step ends): case 0's Δ = 1, gap 0 →
        // as it is; case 2's Δ = 2, gap 2 → open.
        set(&mut cs);
        let g0 = OpenCloseParams {
            gap_predict: Some(0.0),
            ..params
        };
        predict_gaps(&mut cs, laws, &springs, &g0);
        assert_eq!(cs[0].predicted_state, None);
        assert_eq!(cs[2].predicted_state, Some(Open));
        // A bed joint (normal vertical) as case 0: not predicted.
        set(&mut cs);
        cs[0].n = nalgebra::Vector2::new(0.0, 1.0);
        predict_gaps(&mut cs, laws, &springs, &params);
        assert_eq!(cs[0].predicted_state, None);
        // Off: every mark as it was.
        set(&mut cs);
        let off = OpenCloseParams {
            gap_predict: None,
            ..params
        };
        predict_gaps(&mut cs, laws, &springs, &off);
        for (c, case) in cs.iter().zip(&cases) {
            assert_eq!(c.predicted_state, case.4);
        }
    }

    /// The open–close loop's kept-matrix rule (docs/contact-solve.md §19): when no contact's
    /// spring key changed since the last full assembly, `reset_rhs_to_blocks` +
    /// `add_contact_loads` must give the matrix and right-hand side of a full re-assembly to
    /// the bit (tolerance 0: the rule is only sound if it is bit-identical). On a 4 × 5 wall
    /// after one step at rest, the contacts' loads are then changed without changing a key
    /// (sliding directions flipped, friction normals, gap constants and release factors
    /// moved); a fifth of the contacts are made sliding and a fifth open, so all three states occur.
    #[test]
    fn the_rhs_only_reassembly_gives_the_full_assemblys_system_to_the_bit() {
        use crate::assembly::contact_springs::{add_contact_loads, add_contacts, spring_key};
        use crate::contact::ContactState;
        let mut sim = wall_after_a_step_at_rest();
        let mut held = sim.state.contacts.contacts.clone();
        for (k, c) in held.iter_mut().enumerate() {
            match k % 5 {
                0 => c.state = ContactState::Sliding { dir: 1.0 },
                1 => c.state = ContactState::Open,
                _ => {}
            }
        }
        let mut moved = held.clone();
        for c in &mut moved {
            if let ContactState::Sliding { dir } = c.state {
                c.state = ContactState::Sliding { dir: -dir };
            }
            c.friction_normal = 1.5 * c.friction_normal + 10.0;
            c.g0 += 1e-6;
            c.s0 -= 2e-6;
            c.start_normal_force = 100.0;
            c.release_factor = 0.25;
        }
        // Contacts per spring key (open, sliding, locked).
        let states = |cs: &[crate::contact::Contact]| {
            let mut n = [0usize; 3];
            for c in cs {
                n[usize::from(spring_key(c.state))] += 1;
            }
            n
        };
        let n = states(&held);
        assert!(n.iter().all(|&k| k > 0), "every state occurs: {n:?}");
        let st = &sim.state;
        let sys = &mut sim.stepper.system;
        let springs = sim.stepper.springs;
        // A full assembly (`MATRIX`) or the loads only, of `cs`, from the block terms.
        let assemble = |sys: &mut BlockSystem, cs: &[crate::contact::Contact], matrix: bool| {
            let add = if matrix {
                sys.reset_to_blocks();
                add_contacts
            } else {
                sys.reset_rhs_to_blocks();
                add_contact_loads
            };
            add(sys, &st.dofs, cs, &st.laws, &springs, &st.prescribed);
            let mut b = Vec::new();
            for m in sys.diag.iter().chain(&sys.off) {
                b.extend(m.iter().map(|v| v.to_bits()));
            }
            b.extend(sys.rhs.iter().flat_map(|r| r.iter().map(|v| v.to_bits())));
            b
        };
        // Reference: a full assembly of the moved contacts.
        let full = assemble(sys, &moved, true);
        // The rule: the held contacts' full assembly, then the moved contacts' loads only.
        let before = assemble(sys, &held, true);
        assert_ne!(before, full, "the loads moved, so the systems must differ");
        let kept = assemble(sys, &moved, false);
        assert!(
            kept == full,
            "rhs-only re-assembly differs from the full one"
        );
    }

    /// The locked contacts' fused spring assembly (`add_contacts`, docs/contact-solve.md §37)
    /// gives the system of the unfused one (a normal then a shear `add_spring` a contact, the
    /// assembly before session 43) to the bit: tolerance 0, since the fusion only keeps each
    /// entry's two terms together and claims the same operations in the same order. On 4 × 5
    /// walls after one step at rest, rigid and with every other block deformable (3 × 3, 6 × 6
    /// and mixed blocks), a fifth of the contacts made sliding and a fifth open, so every
    /// state occurs and most contacts are locked.
    #[test]
    fn the_fused_locked_springs_give_the_unfused_system_to_the_bit() {
        use crate::assembly::contact_springs::{add_contacts, add_contacts_unfused};
        use crate::contact::ContactState;
        for mixed in [false, true] {
            let mut spec = crate::presets::wall(4, 5);
            if mixed {
                for (k, b) in spec.blocks.iter_mut().enumerate() {
                    if k % 2 == 1 {
                        b.block_model = Some(crate::scene::BlockModel::Deformable);
                    }
                }
            }
            let scene = crate::scene::validate(&spec).expect("wall scene");
            let mut sim = Simulation::new(&scene, &GroundMotion::none(), SimParams::default());
            sim.step(1.0).expect("a step at rest");
            let mut cs = sim.state.contacts.contacts.clone();
            for (k, c) in cs.iter_mut().enumerate() {
                match k % 5 {
                    0 => c.state = ContactState::Sliding { dir: 1.0 },
                    1 => c.state = ContactState::Open,
                    _ => c.state = ContactState::Locked,
                }
                // Shear constants of both signs, away from the converged ones.
                c.s0 += 1e-6 * (k % 3) as f64 - 1e-6;
            }
            let st = &sim.state;
            let sys = &mut sim.stepper.system;
            let springs = sim.stepper.springs;
            let deformable = st.dofs.ndof.iter().filter(|&&n| n == 6).count();
            assert_eq!(deformable > 0, mixed, "block models as asked");
            let mut assemble = |fused: bool| {
                sys.reset_to_blocks();
                let add = if fused {
                    add_contacts
                } else {
                    add_contacts_unfused
                };
                add(sys, &st.dofs, &cs, &st.laws, &springs, &st.prescribed);
                let mut b = Vec::new();
                for m in sys.diag.iter().chain(&sys.off) {
                    b.extend(m.iter().map(|v| v.to_bits()));
                }
                b.extend(sys.rhs.iter().flat_map(|r| r.iter().map(|v| v.to_bits())));
                b
            };
            let (unfused, fused) = (assemble(false), assemble(true));
            assert!(fused == unfused, "fused assembly differs (mixed {mixed})");
        }
    }
}
