//! Simulation › stages: the stages `Simulation::step` calls in the order of the algorithm:
//! detect contacts (contact), Newton's impact law at the step start (its impulse problem from
//! assembly::restitution, solved by solve::impulse, the velocities back), assemble
//! (assembly), solve by open–close or the dual solver (solve), integrate and the step's
//! bookkeeping (integrate). Whether a solved step is accepted is `control.rs`.
use super::{SimError, Simulation, Stats};
use crate::assembly::contact_springs::JointLaw;
use crate::assembly::restitution::{
    apply_impulses, assemble_impacts, hand_over_weight, located_step, ImpactInput,
};
use crate::assembly::BodyLoads;
use crate::contact::{ContactState, Mobility};
use crate::integrate;
use crate::scene::Excitation;
use crate::solve::dual::{DualInput, DualOutcome};
use crate::solve::impulse::ImpulseReport;
use crate::solve::open_close::{self, OpenClose, OpenCloseParams};
use std::time::Instant;

impl Simulation {
    /// Broad and narrow phase, then the per-step contact linearization and joint laws.
    pub(super) fn detect_contacts(&mut self) {
        let search = self.search_distance();
        let scene = &self.state.scene;
        let first = self.stepper.stats.steps == 0;
        // A retired block touches nothing: it is hidden from the broad phase as an immobile
        // block among immobile ones, and the only free blocks it could meet have left too.
        let hidden;
        let mobility = if self.state.retired.iter().any(|&r| r) {
            hidden = self
                .mobility()
                .iter()
                .zip(&self.state.retired)
                .map(|(&m, &r)| if r { Mobility::Fixed } else { m })
                .collect::<Vec<_>>();
            &hidden
        } else {
            &self.state.mobility
        };
        let rebuilt = self.state.contacts.detect(
            &self.state.geoms,
            mobility,
            search,
            &self.params.contact,
            first,
            |a, b| {
                let j = scene.joint_between(a, b);
                j.cohesion > 0.0 || j.tensile_strength > 0.0
            },
        );
        self.state.contacts.linearize(&self.state.geoms);
        if !rebuilt {
            // Same contacts as the last step: joint laws and the block pattern still hold.
            return;
        }
        self.state.laws.clear();
        for c in &self.state.contacts.contacts {
            let j = scene.joint_between(c.vertex_block, c.edge_block);
            self.state.laws.push(JointLaw {
                tan_phi: j.friction_angle.tan(),
                cohesion: j.cohesion,
                tensile_strength: j.tensile_strength,
            });
        }
        let mut pairs = Vec::new();
        for c in &self.state.contacts.contacts {
            if let (Some(a), Some(b)) = (
                self.state.dofs.free_index[c.vertex_block],
                self.state.dofs.free_index[c.edge_block],
            ) {
                pairs.push((a.min(b), a.max(b)));
            }
        }
        self.stepper.system.set_pattern(pairs);
        self.stepper
            .system
            .bind_contacts(&self.state.dofs, &self.state.contacts.contacts);
    }

    /// Newton's impact law (`control.restitution`) at the contacts at their impact at the step
    /// start: the step then starts from the velocities after the impact. Returns the step to
    /// take: `dt`, or shorter so that it ends just before the next impact (event location,
    /// `ImpactParams::window`; not a cut: the next step is `dt` again). In order: the impacts'
    /// impulse problem (`assemble_impacts`), its solve (`solve::impulse`, timed apart into
    /// `StepProfile::impulse_solve`), the velocities after it (`apply_impulses`), the
    /// hand-over's moves and the located step; the whole into `StepProfile::impacts`.
    pub(super) fn impacts(&mut self, e: f64, dt: f64) -> f64 {
        let t = Instant::now();
        // The per-block and per-contact inputs are refilled in the stepper's vectors (kept
        // across steps, no allocation a step).
        let state = &self.state;
        let immobile = &mut self.stepper.impact_immobile;
        immobile.clear();
        immobile.extend(
            (0..state.scene.blocks.len()).map(|b| match state.dofs.free_index[b] {
                Some(_) => [0.0; 3],
                None => state.block_velocity(b),
            }),
        );
        let friction = &mut self.stepper.impact_friction;
        friction.clear();
        friction.extend(state.laws.iter().map(|l| l.tan_phi));
        let input = ImpactInput {
            dofs: &self.state.dofs,
            geoms: &self.state.geoms,
            densities: &self.state.densities,
            immobile_velocity: &self.stepper.impact_immobile,
            friction: &self.stepper.impact_friction,
            retired: &self.state.retired,
            restitution: e,
            dt,
            nominal_dt: self.state.scene.control.time_step,
            gravity: self.state.scene.gravity,
        };
        let n = assemble_impacts(
            &input,
            &self.state.contacts.contacts,
            &self.state.states,
            &self.params.impact,
            &mut self.stepper.impact_scratch,
        );
        self.stepper.stats.impacts += n as u64;
        self.stepper.impulse_report = ImpulseReport::default();
        if n > 0 {
            let ts = Instant::now();
            let report = self.stepper.impulse.solve(
                self.stepper.impact_scratch.problem_mut(),
                &self.params.impact,
            );
            self.stepper.profile.impulse_solve += ts.elapsed();
            apply_impulses(
                &input,
                &self.state.contacts.contacts,
                &mut self.state.states,
                &self.params.impact,
                &mut self.stepper.impact_scratch,
            );
            count_impulse_solve(&mut self.stepper.stats, report);
            self.stepper.impulse_report = report;
        }
        let hand_over = n > 0 && self.params.impact.hand_over_weight;
        if hand_over {
            hand_over_weight(
                &input,
                &self.state.contacts.contacts,
                &self.state.states,
                &self.params.impact,
                &mut self.stepper.impact_scratch,
            );
        }
        let step = located_step(
            &input,
            &self.state.contacts.contacts,
            &self.state.states,
            &self.params.impact,
            &self.stepper.impact_scratch,
        );
        if hand_over {
            for &(f, d) in self.stepper.impact_scratch.moves() {
                self.state.move_rigidly(f, d);
            }
        }
        self.stepper.profile.impacts += t.elapsed();
        step
    }

    /// Kinetic damping, loads at the step end, prescribed motion, block terms.
    pub(super) fn assemble(&mut self, dt: f64) {
        let t = Instant::now();
        let c = &self.state.scene.control;
        let keep = c.dynamic_factor * (-c.kinetic_damping_rate * dt).exp();
        for st in &mut self.state.states {
            st.vel *= keep;
            st.acc *= keep;
        }
        let t_end = self.state.time + dt;
        let ground = match self.state.scene.excitation {
            Excitation::BaseAcceleration => self.ground_load(t_end, dt),
            Excitation::DrivenBlock(b) => {
                let d0 = self.state.motion.state(self.state.time)[2];
                let d1 = self.state.motion.state(t_end)[2];
                self.state.prescribed[b] = [d1[0] - d0[0], d1[1] - d0[1]];
                [0.0, 0.0]
            }
        };
        let loads = BodyLoads {
            gravity: self.state.scene.gravity,
            ground_acceleration: ground,
        };
        self.stepper.system.assemble_blocks(
            &self.state.dofs,
            &self.state.geoms,
            &self.state.densities,
            &self.state.elastic,
            &self.state.states,
            &loads,
            self.stepper.newmark,
            dt,
        );
        for (f, &b) in self.state.dofs.block_of.iter().enumerate() {
            if self.state.retired[b] {
                self.stepper.system.clear_block_load(f);
            }
        }
        self.stepper.profile.assemble += t.elapsed();
    }

    /// The ground acceleration the step's inertial load uses, m/s² ([x, y]): with DDA's rule
    /// (γ = 1, `SimParams::average_ground_load`) its average over the step, else its value at
    /// the step's end.
    fn ground_load(&self, t_end: f64, dt: f64) -> [f64; 2] {
        let motion = &self.state.motion;
        if !(self.params.average_ground_load && self.stepper.newmark.gamma == 1.0 && dt > 0.0) {
            return motion.acceleration(t_end);
        }
        let v0 = motion.state(self.state.time)[1];
        let v1 = motion.state(t_end)[1];
        [(v1[0] - v0[0]) / dt, (v1[1] - v0[1]) / dt]
    }

    /// The open–close loop on the assembled step (`at_floor`: the step is at the unconverged
    /// floor, where `SimParams::unconverged_floor_iterations` may cap it).
    pub(super) fn open_close(&mut self, at_floor: bool) -> Result<OpenClose, SimError> {
        // At the floor the loop may stop earlier (`SimParams::unconverged_floor_iterations`).
        let capped;
        let params = match self
            .params
            .unconverged_floor_iterations
            .filter(|_| at_floor)
        {
            Some(n) => {
                capped = OpenCloseParams {
                    max_iterations: n,
                    ..self.params.open_close
                };
                &capped
            }
            None => &self.params.open_close,
        };
        let r = open_close::iterate(
            &mut self.stepper.system,
            &self.state.dofs,
            &mut self.state.contacts.contacts,
            &self.state.laws,
            &self.stepper.springs,
            &self.state.prescribed,
            &mut self.stepper.solver,
            &mut self.stepper.x,
            params,
            &mut self.stepper.changes,
            &mut self.stepper.open_close_scratch,
        );
        match r {
            Ok(o) => {
                let (OpenClose::Converged { iterations }
                | OpenClose::NotConverged { iterations, .. }) = o;
                self.stepper.stats.open_close_iterations += iterations as u64;
                Ok(o)
            }
            Err(error) => Err(self.solve_failed(error)),
        }
    }

    /// The dual form's solve stage: contact forces as unknowns (no springs), per-block
    /// flexibilities, the compatibility iteration; writes the increments into `x`.
    pub(super) fn dual_solve(&mut self) -> Result<DualOutcome, SimError> {
        self.stepper.system.reset_to_blocks();
        let input = DualInput {
            dofs: &self.state.dofs,
            geoms: &self.state.geoms,
            laws: &self.state.laws,
            prescribed: &self.state.prescribed,
            length_scale: self.stepper.smallest_free_block,
            search: self.search_distance(),
            contact: &self.params.contact,
            nominal_dt: self.state.scene.control.time_step,
            gravity: self.state.scene.gravity,
        };
        let r = self.stepper.dual.solve(
            &self.stepper.system,
            &input,
            &mut self.state.contacts.contacts,
            &mut self.stepper.x,
        );
        match r {
            Ok(o) => {
                self.stepper.stats.dual_iterations += o.iterations as u64;
                self.stepper.stats.dual_cg_products += o.cg_products as u64;
                self.stepper.stats.dual_switches += o.switches as u64;
                self.stepper.last_dual = Some(o);
                Ok(o)
            }
            Err(error) => Err(self.solve_failed(error)),
        }
    }

    pub(super) fn integrate(&mut self, dt: f64) {
        for f in 0..self.state.dofs.block_of.len() {
            let d = self.block_increment(f);
            let b = self.state.dofs.block_of[f];
            integrate::move_block(&mut self.state.geoms[b], &d);
            integrate::update_motion(&mut self.state.states[f], &d, self.stepper.newmark, dt);
            if self.state.dofs.ndof[f] == 6 {
                integrate::update_stress(&mut self.state.states[f], &d, &self.state.elastic[f]);
            }
        }
        if let Excitation::DrivenBlock(b) = self.state.scene.excitation {
            integrate::translate_block(&mut self.state.geoms[b], self.state.prescribed[b]);
        }
        self.remove_release_loads();
    }

    /// The release loads of contacts that opened in this step (see
    /// `contact_springs::release_load`) correct the step's force average, not the forces at
    /// its end: take them out of the stored acceleration a₁, which the next step averages as
    /// its a₀.
    pub(super) fn remove_release_loads(&mut self) {
        for c in &self.state.contacts.contacts {
            let l = crate::assembly::contact_springs::release_load(c, &self.stepper.springs);
            if l == 0.0 {
                continue;
            }
            for (block, load) in [(c.vertex_block, c.e_i * l), (c.edge_block, c.e_j * -l)] {
                let Some(f) = self.state.dofs.free_index[block] else {
                    continue;
                };
                let n = self.state.dofs.ndof[f];
                let m = self.stepper.system.mass[f]
                    .view((0, 0), (n, n))
                    .clone_owned();
                let rhs = load.rows(0, n).clone_owned();
                if let Some(da) = m.cholesky().map(|ch| ch.solve(&rhs)) {
                    for k in 0..n {
                        self.state.states[f].acc[k] -= da[k];
                    }
                }
            }
        }
    }

    /// Contact bookkeeping and time-step control after an accepted step.
    pub(super) fn finish_step(&mut self, dt: f64, cuts: u32, error: Option<f64>) {
        let shear = self.stepper.springs.shear;
        let mut deepest = 0.0f64;
        for (c, law) in self
            .state
            .contacts
            .contacts
            .iter_mut()
            .zip(&self.state.laws)
        {
            c.closed_within_last_step = c.g0 > 0.0 && c.state.is_closed();
            // The step's converged slip, for the stick–slip prediction of the next steps.
            c.prior_slip = c.last_slip;
            c.last_slip = c.state.is_closed().then_some(c.slip);
            // And its converged gap change, for the gap prediction (`gap_predict`).
            c.prior_gap_change = c.last_gap_change;
            c.last_gap_change = Some(c.gap - c.g0);
            match c.state {
                ContactState::Open => c.bonded = false,
                ContactState::Sliding { dir } => {
                    c.bonded = false;
                    let limit =
                        crate::assembly::contact_springs::shear_limit(c, law, c.normal_force);
                    c.slide_offset = dir * limit / shear;
                }
                ContactState::Locked => {}
            }
            if c.state.is_closed() {
                deepest = deepest.max(-c.gap);
            }
        }
        self.stepper.stats.max_penetration = self.stepper.stats.max_penetration.max(deepest);
        if !self.stepper.taken_unconverged {
            self.stepper.converged_penetration = self.stepper.converged_penetration.max(deepest);
        }
        if let Some(o) = self.stepper.last_dual.filter(|o| o.loose) {
            self.stepper.stats.dual_loose_solves += 1;
            self.stepper.stats.dual_loose_residual =
                self.stepper.stats.dual_loose_residual.max(o.residual);
        }
        self.update_rocking(dt);
        self.state.time += dt;
        self.stepper.stats.steps += 1;
        self.stepper.stats.min_dt = self.stepper.stats.min_dt.min(dt);
        self.stepper.stats.max_dt = self.stepper.stats.max_dt.max(dt);
        if self.stepper.taken_unconverged && self.params.unconverged_floor_hold {
            // At the floor, also after a step the impact law's event location shortened.
            self.stepper.dt = self.unconverged_floor();
        } else if cuts > 0 {
            self.stepper.dt = dt;
        } else if self.state.scene.control.adaptive_time_step
            || self.stepper.dt < self.state.scene.control.time_step
        {
            self.stepper.dt =
                (self.stepper.dt * self.params.growth).min(self.state.scene.control.time_step);
        }
        let closing = self.closing_bound(dt);
        if closing < self.stepper.dt {
            // Accept this step, shorten the next (a limit, not a cut: nothing is redone).
            self.stepper.dt = closing;
            self.stepper.stats.closing_limited_steps += 1;
        }
        if let Some(e) = error {
            // The next step from the estimate (local error ∝ Δt²), never below the floor.
            let tol = self.local_error_tolerance();
            let floor = self.params.min_error_step_ratio * self.state.scene.control.time_step;
            if e > 0.0 {
                let sized = (0.9 * dt * (tol / e).sqrt()).max(floor);
                self.stepper.dt = self.stepper.dt.min(sized);
            }
        }
    }
}

/// An impulse solve's counters (`Stats::impact_polished`, `impact_unconverged`,
/// `impact_residual_ratio`).
fn count_impulse_solve(stats: &mut Stats, report: ImpulseReport) {
    stats.impact_polished += u64::from(report.polish_iterations > 0);
    stats.impact_unconverged += u64::from(!report.converged);
    if report.scale > 0.0 {
        stats.impact_residual_ratio = stats
            .impact_residual_ratio
            .max(report.residual / report.scale);
    }
}
