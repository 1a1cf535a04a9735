//! Simulation › step control: whether a solved step is accepted (displacement limit, overshot
//! contacts, the adaptive step's accuracy bounds: impact location, local error, rotation per
//! step) and, if not, why ([`Refusal`]) and by how much to cut.
use super::Simulation;
use crate::contact::Contact;
use crate::geometry::{displacement_matrix, Vec6};

/// Why one attempt at a step is refused (the step is then cut, or the run stops).
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) enum Refusal {
    /// The contact solver did not converge; the contact it changed last or left worst.
    Unconverged(Option<usize>),
    /// A vertex of this block (scene index) would move this far (m), beyond the step limit.
    Moved { block: usize, by: f64 },
    /// This contact deepened beyond what the time step resolves.
    Overshot(usize),
    /// This contact closed within the step after a longer approach than
    /// `SimParams::impact_approach_ratio` allows: the step is cut by `factor` to locate the
    /// impact.
    Impact { contact: usize, factor: f64 },
    /// The step's estimated local error exceeds the bound of `SimParams::local_error_ratio`.
    LocalError { factor: f64 },
}

impl Refusal {
    /// Factor applied to Δt for the next attempt: the step-control refusals aim at their bound
    /// (with a 10 % margin), never cutting deeper than `cut`; the others cut by `cut`.
    pub(super) fn factor(self, cut: f64) -> f64 {
        match self {
            Refusal::Impact { factor, .. } | Refusal::LocalError { factor, .. } => {
                (0.9 * factor).clamp(cut, 0.9)
            }
            _ => cut,
        }
    }

    /// A bound of the step's accuracy, not of its validity.
    pub(super) fn is_accuracy(self) -> bool {
        matches!(self, Refusal::Impact { .. } | Refusal::LocalError { .. })
    }
}

impl Simulation {
    /// After convergence: is the step within the displacement limit and the penetration
    /// tolerance? Returns why not, if not.
    pub(super) fn check_step(&self, dt: f64) -> Option<Refusal> {
        if self.state.scene.control.adaptive_time_step {
            let limit = self.max_step_displacement();
            for f in 0..self.state.dofs.block_of.len() {
                let d = self.block_increment(f);
                let b = self.state.dofs.block_of[f];
                let g = &self.state.geoms[b];
                let by = g
                    .vertices
                    .iter()
                    .map(|p| (displacement_matrix(*p, g.centroid) * d).norm())
                    .fold(0.0, f64::max);
                if by > limit {
                    return Some(Refusal::Moved { block: b, by });
                }
            }
        }
        for (k, c) in self.state.contacts.contacts.iter().enumerate() {
            if self.overshot(c) && self.stepper.dt * self.params.cut_factor > self.params.min_dt {
                return Some(Refusal::Overshot(k));
            }
        }
        if self.state.scene.control.adaptive_time_step {
            return self.step_control(dt);
        }
        None
    }

    /// The longest step that turns no free block by more than `SimParams::max_rotation_step`
    /// at its current angular velocity (adaptive runs only; infinite without the bound).
    pub(super) fn rotation_bound(&self) -> f64 {
        let Some(limit) = self.params.max_rotation_step else {
            return f64::INFINITY;
        };
        if !self.state.scene.control.adaptive_time_step {
            return f64::INFINITY;
        }
        let w = self
            .states()
            .iter()
            .map(|s| s.vel[2].abs())
            .fold(0.0, f64::max);
        (limit / w).max(10.0 * self.params.min_dt)
    }

    /// The first closed contact an unconverged iterate leaves deeper than the floor's bound
    /// (`SimParams::unconverged_floor_penetration`): the deepest penetration a converged step
    /// has left so far, `start` (the deepest contact closed at this step's start, m), or
    /// `unconverged_floor_penetration` × the contact's elastic range W/k_n (m; W the lighter
    /// free stone's weight), whichever is deepest. `None`: within the bound.
    pub(super) fn floor_penetration_exceeded(&self, start: f64) -> Option<usize> {
        let contacts = &self.state.contacts.contacts;
        let deepest = start.max(self.stepper.converged_penetration);
        let k = self.stepper.springs.normal;
        let weight = &self.stepper.system.weight;
        let free = &self.state.dofs.free_index;
        let factor = self.params.unconverged_floor_penetration;
        contacts.iter().position(|c| {
            if !c.state.is_closed() || -c.gap <= deepest {
                return false;
            }
            // The lighter free stone's weight (a fixed or driven block has none of its own).
            let w = [c.vertex_block, c.edge_block]
                .iter()
                .filter_map(|&b| free[b].and_then(|f| weight.get(f).copied()))
                .fold(f64::INFINITY, f64::min);
            w.is_finite() && k > 0.0 && -c.gap > factor * w / k
        })
    }

    /// The longest step the rocking control allows (`SimParams::rocking_velocity_change`, adaptive
    /// runs only; infinite without it): for each free block in a rocking episode (recent peak
    /// angular speed Ω above `rocking_speed_floor`, and a pivot seen: see
    /// `Simulation::update_rocking`), c·Ω/θ̈_g with θ̈_g gravity's angular acceleration about
    /// its last pivot, never below `min_error_step_ratio` × `control.time_step`. Both Ω (a
    /// decaying maximum) and θ̈_g (geometry) vary slowly, so the steps do too: a step much
    /// shorter than the one before turns the pivot's per-step lift (exact rotation against the
    /// linear contact condition) into a spurious velocity (assembly::restitution::located_step),
    /// which is why the instantaneous θ̈ is not used.
    pub(super) fn rocking_bound(&self) -> f64 {
        let Some(c) = self.params.rocking_velocity_change else {
            return f64::INFINITY;
        };
        if !self.state.scene.control.adaptive_time_step {
            return f64::INFINITY;
        }
        let floor = self.params.min_error_step_ratio * self.state.scene.control.time_step;
        let mut bound = f64::INFINITY;
        for (f, &b) in self.state.dofs.block_of.iter().enumerate() {
            let a = self.stepper.rocking_accel[f];
            if self.state.retired[b] || a <= 0.0 {
                continue;
            }
            bound = bound.min((c * self.stepper.omega_scale[f] / a).max(floor));
        }
        bound
    }

    /// Marks the blocks whose rotation rate changed sign between the last two step ends
    /// (`Stepper::spin_reversed`, read by `OpenCloseParams::head_slip_spin`); call once a step,
    /// at its start. A block with no unknowns never turns.
    pub(super) fn note_spin_reversals(&mut self) {
        let n = self.state.geoms.len();
        let st = &mut self.stepper;
        st.spin_prior.resize(n, 0.0);
        st.spin_reversed.clear();
        st.spin_reversed.resize(n, false);
        for (f, &b) in self.state.dofs.block_of.iter().enumerate() {
            let w = self.state.states[f].vel[2];
            st.spin_reversed[b] = w * st.spin_prior[b] < 0.0;
            st.spin_prior[b] = w;
        }
    }

    /// After an accepted step: each free block's recent peak angular speed Ω (decaying over
    /// `rocking_speed_memory`) and, while Ω is above `rocking_speed_floor`, gravity's angular
    /// acceleration about its pivot when it turns on one closed contact, m·g·|x_c − x_p| / I_p
    /// (rad/s²; I_p the moment of inertia about the pivot p). Below the floor the block is no
    /// longer rocking and the rocking control forgets it.
    pub(super) fn update_rocking(&mut self, dt: f64) {
        if self.params.rocking_velocity_change.is_none() {
            return;
        }
        let memory = (-dt / self.params.rocking_speed_memory).exp();
        let mut closed = vec![(0u32, 0usize); self.state.geoms.len()];
        for (k, c) in self.state.contacts.contacts.iter().enumerate() {
            if c.state.is_closed() {
                for b in [c.vertex_block, c.edge_block] {
                    closed[b].0 += 1;
                    closed[b].1 = k;
                }
            }
        }
        let g = self.state.scene.gravity.abs();
        for (f, &b) in self.state.dofs.block_of.iter().enumerate() {
            let w = &mut self.stepper.omega_scale[f];
            *w = self.state.states[f].vel[2].abs().max(*w * memory);
            if *w < self.params.rocking_speed_floor {
                self.stepper.rocking_accel[f] = 0.0;
                continue;
            }
            if closed[b].0 != 1 {
                continue;
            }
            let c = &self.state.contacts.contacts[closed[b].1];
            let pivot = self.state.geoms[c.vertex_block].vertices[c.vertex];
            let m = &self.state.geoms[b].moments;
            let r = pivot - m.centroid;
            let inertia = m.sxx + m.syy + m.area * r.norm_squared();
            if inertia > 0.0 {
                self.stepper.rocking_accel[f] = m.area * g * r.x.abs() / inertia;
            }
        }
    }

    /// The longest next step the closing-contact limit allows (`SimParams::closing`; adaptive
    /// runs only, infinite when off or when nothing closed): for each contact open at the step
    /// start and closed at its end, with approach a = g0 − gap (m) within the step just taken
    /// (`dt`, s), Δt ≤ f · δ · dt / a, δ = W/k_n the elastic range of its lighter free stone
    /// (m); never below `min_step_ratio` × `control.time_step`.
    pub(super) fn closing_bound(&mut self, dt: f64) -> f64 {
        let Some(fraction) = self.params.closing.elastic_fraction else {
            return f64::INFINITY;
        };
        if !self.state.scene.control.adaptive_time_step {
            return f64::INFINITY;
        }
        let k = self.stepper.springs.normal;
        let mut bound = f64::INFINITY;
        self.stepper.last_closing = (0, 0.0);
        let weight = &self.stepper.system.weight;
        let free = &self.state.dofs.free_index;
        for c in &self.state.contacts.contacts {
            let approach = c.g0 - c.gap;
            if !(c.g0 > 0.0 && c.state.is_closed() && approach > 0.0) {
                continue;
            }
            // The lighter free stone's weight (a fixed or driven block has none of its own).
            let w = [c.vertex_block, c.edge_block]
                .iter()
                .filter_map(|&b| free[b].and_then(|f| weight.get(f).copied()))
                .fold(f64::INFINITY, f64::min);
            if !w.is_finite() || w <= 0.0 || k <= 0.0 {
                continue;
            }
            bound = bound.min(fraction * (w / k) * dt / approach);
            let last = &mut self.stepper.last_closing;
            *last = (last.0 + 1, last.1.max(approach * k / w));
        }
        let floor = self.params.closing.min_step_ratio * self.state.scene.control.time_step;
        bound.max(floor)
    }

    /// The accuracy bounds of the adaptive step (impact location, rotation per step): the
    /// worst violation, if any, as a refusal with the factor that meets its bound. Never
    /// below `min_dt` × 10 (a step this short is no longer an accuracy question).
    pub(super) fn step_control(&self, dt: f64) -> Option<Refusal> {
        let floor = 10.0 * self.params.min_dt;
        let mut worst: Option<Refusal> = None;
        let mut keep = |r: Refusal, f: f64| {
            let better = match worst {
                Some(Refusal::Impact { factor, .. } | Refusal::LocalError { factor, .. }) => {
                    f < factor
                }
                _ => true,
            };
            if f < 1.0 && dt * f.max(self.params.cut_factor) > floor && better {
                worst = Some(r);
            }
        };
        if let Some(ratio) = self.params.impact_approach_ratio {
            let limit = ratio * self.stepper.smallest_free_block;
            for (k, c) in self.state.contacts.contacts.iter().enumerate() {
                // Open at the step start, closed at its end: the contact closed within the step.
                let approach = c.g0 - c.gap;
                if c.g0 > 0.0 && c.state.is_closed() && approach > limit {
                    let factor = limit / approach;
                    keep(Refusal::Impact { contact: k, factor }, factor);
                }
            }
        }
        if let Some((_, e)) = self.local_error(dt) {
            let tol = self.local_error_tolerance();
            let floor = self.params.min_error_step_ratio * self.state.scene.control.time_step;
            if e > 2.0 * tol && dt > floor {
                let factor = (tol / e).sqrt().max(floor / dt);
                keep(Refusal::LocalError { factor }, factor);
            }
        }
        worst
    }

    /// The local error bound, m (infinite when the control is off).
    pub(super) fn local_error_tolerance(&self) -> f64 {
        self.params
            .local_error_ratio
            .map_or(f64::INFINITY, |r| r * self.stepper.smallest_free_block)
    }

    /// The step's estimated local displacement error, m, and the block where it is largest:
    /// |β − 1/6|·Δt²·|a₁ − a₀| at the worst vertex, a₁ from the solved increments (the same
    /// Newmark rule as `integrate::update_motion`), a₀ the step-start acceleration. `None`
    /// when the control is off.
    pub(super) fn local_error(&self, dt: f64) -> Option<(usize, f64)> {
        self.params.local_error_ratio?;
        let nm = self.stepper.newmark;
        let c = (nm.beta - 1.0 / 6.0).abs() * dt * dt;
        let mut worst = (0, 0.0f64);
        for f in 0..self.state.dofs.block_of.len() {
            let b = self.state.dofs.block_of[f];
            if self.state.retired[b] {
                continue;
            }
            let d = self.block_increment(f);
            let st = &self.state.states[f];
            let a1 = (d - st.vel * dt - st.acc * (dt * dt * (0.5 - nm.beta))) / (nm.beta * dt * dt);
            let da = a1 - st.acc;
            let g = &self.state.geoms[b];
            let e = g
                .vertices
                .iter()
                .map(|p| (displacement_matrix(*p, g.centroid) * da).norm())
                .fold(0.0, f64::max)
                * c;
            if e > worst.1 {
                worst = (b, e);
            }
        }
        Some(worst)
    }

    pub(super) fn block_increment(&self, f: usize) -> Vec6 {
        let mut d = Vec6::zeros();
        let o = self.state.dofs.offset[f];
        for k in 0..self.state.dofs.ndof[f] {
            d[k] = self.stepper.x[o + k];
        }
        d
    }

    /// A closed contact whose penetration deepened within the step by more than the tolerance:
    /// a vertex overshot its edge (a time-step problem). A deep but steady penetration is the
    /// spring's compliance (a penalty problem) and is reported, not cut.
    pub(super) fn overshot(&self, c: &Contact) -> bool {
        let deepened = -c.gap - (-c.g0).max(0.0);
        c.state.is_closed()
            && deepened > self.params.penetration_ratio * self.max_step_displacement()
    }
}
