//! Simulation › diagnostics: what the steps report (the run summary's counters [`Stats`], the
//! stage timings [`StepProfile`]) and the typed errors that explain a refused step (which
//! blocks, why, what to change): a step refused at the last cut, a penalty too soft, a solve
//! failure's block, a non-finite state.
use super::control::Refusal;
use super::{SimError, Simulation};
use crate::contact::Contact;
use crate::scene::ContactSolver;
use crate::solve::SolveError;
use std::time::Duration;

/// Wall time spent in each stage (accumulated over steps).
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct StepProfile {
    pub detect: Duration,
    /// Newton's impact law at the step start, its impulse solve included.
    pub impacts: Duration,
    /// The impulse solve alone (`solve::impulse`: the sweeps and the polish).
    pub impulse_solve: Duration,
    pub assemble: Duration,
    pub solve: Duration,
    pub integrate: Duration,
}

/// Counters reported in the run summary.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct Stats {
    pub steps: u64,
    pub time_step_cuts: u64,
    pub open_close_iterations: u64,
    /// Projection–contraction iterations of the dual solver (all steps).
    pub dual_iterations: u64,
    /// Products with W of the dual solver's MPRGP minimisation (all steps).
    pub dual_cg_products: u64,
    /// Vertex–vertex contact pairs switched by the dual solver.
    pub dual_switches: u64,
    /// Steps whose dual solve stalled and was accepted within
    /// `DualParams::stall_acceptance` × its tolerance (0 with the default of 1).
    pub dual_loose_solves: u64,
    /// Largest remaining violation of those steps' solves, m (0 if none).
    pub dual_loose_residual: f64,
    /// Deepest penetration after a converged step, m.
    pub max_penetration: f64,
    pub min_dt: f64,
    pub max_dt: f64,
    /// Contacts that closed under Newton's impact law (`control.restitution` a number).
    pub impacts: u64,
    /// Accepted steps after which the closing-contact limit (`SimParams::closing`) shortened
    /// the next step.
    pub closing_limited_steps: u64,
    /// Steps taken at `SimParams::unconverged_floor_ratio` with the open–close loop's last
    /// iterate, unconverged.
    pub unconverged_taken: u64,
    /// Unconverged iterates at or below the floor that the step checks accepted but the
    /// floor's penetration bound (`SimParams::unconverged_floor_penetration`) refused; each
    /// cut the step below the floor.
    pub unconverged_floor_refused: u64,
    /// Steps the impact law's event location ended early (before a predicted impact).
    pub located_steps: u64,
    /// Impulse solves (steps with an impact) the projected Gauss–Seidel left above
    /// `ImpactParams::residual_tolerance` and the polish finished (`ImpactParams::polish`).
    pub impact_polished: u64,
    /// Impulse solves that ended above `ImpactParams::residual_tolerance` (after the polish
    /// if on): the velocities after such an impact are not the impact law's.
    pub impact_unconverged: u64,
    /// Largest end residual of an impulse solve relative to its speed scale
    /// (`solve::impulse::ImpulseReport`), 0 if none.
    pub impact_residual_ratio: f64,
}

impl Simulation {
    /// The typed error of a failed linear solve (open–close or the dual solver's
    /// flexibilities), naming the block of the degree of freedom it failed at.
    pub(super) fn solve_failed(&self, error: SolveError) -> SimError {
        let dof = match error {
            SolveError::NotPositiveDefinite { dof } | SolveError::NonFinite { dof } => dof,
            SolveError::Backend(_) | SolveError::NoSymbolic => 0,
        };
        SimError::Solve {
            time: self.state.time,
            error,
            block: self.block_of_dof(dof),
        }
    }

    pub(super) fn block_of_dof(&self, dof: usize) -> String {
        for f in 0..self.state.dofs.block_of.len() {
            if dof >= self.state.dofs.offset[f]
                && dof < self.state.dofs.offset[f] + self.state.dofs.ndof[f]
            {
                return self.state.scene.blocks[self.state.dofs.block_of[f]]
                    .id
                    .clone();
            }
        }
        "?".into()
    }

    /// A closed contact deeper than `max_penetration_ratio` of the thinner block after a
    /// converged step (docs/stability.md: a soft penalty used to complete silently with blocks sunk
    /// into each other, see tests/regression/regression_soft_penalty.rs).
    pub(super) fn too_soft(&self, dt: f64) -> Option<SimError> {
        let ratio = self.params.max_penetration_ratio;
        let search = self.search_distance();
        let limit_of = |c: &Contact| {
            let thin = self.state.thickness[c.vertex_block].min(self.state.thickness[c.edge_block]);
            (ratio * thin).min(search)
        };
        let c = self
            .contacts()
            .contacts
            .iter()
            .find(|c| c.state.is_closed() && -c.gap > limit_of(c))?;
        let thin = self.state.thickness[c.vertex_block].min(self.state.thickness[c.edge_block]);
        let limit = limit_of(c);
        let limit_reason = if ratio * thin <= search {
            format!(
                "{:.0}% of the thinner block, {thin:.3e} m thick",
                100.0 * ratio
            )
        } else {
            "the contact search distance: deeper vertices are no longer seen as contacts"
                .to_string()
        };
        let depth = -c.gap;
        let penalty = self.stepper.springs.normal;
        // Every accepted step leaves closed contacts within the limit, so a contact already
        // beyond it at the step start was open or unseen: the vertex entered between contact
        // detections (e.g. through a very thin block). Otherwise: most of the depth gained
        // within this step is an overshoot (time-step problem), else it built up under load
        // over steps (spring compliance).
        let entered_unseen = -c.g0 > limit;
        let overshoot = depth - (-c.g0).max(0.0) > 0.5 * depth;
        let (cause, advice) = if entered_unseen || overshoot {
            (
                if entered_unseen {
                    "the vertex was already this deep when its contact was found (it entered between contact detections)".to_string()
                } else {
                    format!("it appeared within one step of {dt:.3e} s")
                },
                "reduce control.max_displacement_ratio or control.time_step".to_string(),
            )
        } else {
            let stiffest = self.state.scene.materials.iter().map(|m| m.young_modulus);
            let auto = 10.0 * stiffest.fold(0.0, f64::max);
            (
                format!("the penalty stiffness {penalty:.3e} N/m is too soft for these loads"),
                // Penetration under a given load scales as 1/k; the depth may still be
                // growing, so this is a lower bound.
                format!(
                    "raise control.penalty_stiffness above {:.1e} N/m (\"auto\" gives {auto:.1e} N/m)",
                    penalty * depth / limit
                ),
            )
        };
        Some(SimError::PenaltyTooSoft {
            time: self.state.time + dt,
            depth,
            limit,
            explanation: format!("{limit_reason}); {cause}; {advice}"),
            block_a: self.state.scene.blocks[c.vertex_block].id.clone(),
            block_b: self.state.scene.blocks[c.edge_block].id.clone(),
        })
    }

    /// The typed error for a step refused at the last cut allowed.
    pub(super) fn refused(&self, cuts: u32, dt: f64, refusal: Refusal) -> SimError {
        let contact = match refusal {
            Refusal::Moved { block, by } => {
                return SimError::StepTooLarge {
                    time: self.state.time,
                    cuts,
                    dt,
                    moved: by,
                    limit: self.max_step_displacement(),
                    block: self.state.scene.blocks[block].id.clone(),
                }
            }
            Refusal::Unconverged(k) => k,
            Refusal::Overshot(k) | Refusal::Impact { contact: k, .. } => Some(k),
            Refusal::LocalError { .. } => None,
        };
        let (a, b) = match contact.and_then(|k| self.state.contacts.contacts.get(k)) {
            Some(c) => (
                self.state.scene.blocks[c.vertex_block].id.clone(),
                self.state.scene.blocks[c.edge_block].id.clone(),
            ),
            None => ("?".into(), "?".into()),
        };
        if let (ContactSolver::Dual, Some(o)) = (
            self.state.scene.control.contact_solver,
            self.stepper.last_dual,
        ) {
            if !o.converged {
                return SimError::DualNotConverged {
                    time: self.state.time,
                    cuts,
                    dt,
                    iterations: o.iterations,
                    residual: o.residual,
                    block_a: a,
                    block_b: b,
                };
            }
        }
        if let Some(c) = contact.and_then(|k| self.state.contacts.contacts.get(k)) {
            if self.overshot(c) {
                return SimError::Penetration {
                    time: self.state.time,
                    depth: -c.gap,
                    block_a: a,
                    block_b: b,
                };
            }
        }
        SimError::NotConverged {
            time: self.state.time,
            cuts,
            dt,
            block_a: a,
            block_b: b,
        }
    }

    /// A NaN or infinity never leaves an accepted step: it would poison every later step and
    /// every recorded frame. The typed error names the first such block.
    pub(super) fn check_finite(&self) -> Result<(), SimError> {
        match self.state.first_non_finite_block() {
            Some(b) => Err(SimError::NonFinite {
                time: self.state.time,
                block: self.state.scene.blocks[b].id.clone(),
            }),
            None => Ok(()),
        }
    }
}
