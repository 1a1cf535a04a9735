//! Dual form of DDA (Zheng et al. 2016, "DDA-d"): the contact forces are the unknowns, no penalty
//! springs. The solve-stage alternative to `open_close`, chosen by
//! `control.contact_solver = "dual"`; called once per step attempt after
//! `BlockSystem::assemble_blocks` + `reset_to_blocks` (which give each block's Newmark matrix
//! and load) and before `integrate` (which consumes the increments written to `x`).
//!
//! Per step: (1) invert each block's matrix ([`flexibility`]); (2) per-contact gap and slide
//! terms ([`gap`]); (3) solve the quasi-variational inequality for the contact forces: first
//! as a bound-constrained minimisation by conjugate gradients ([`mprgp`]), and where that has
//! not converged within its budget by Zheng et al.'s projection–contraction "compatibility
//! iteration" ([`iterate`], projections in [`projection`]), both to the same stopping test;
//! (4) re-choose the pair of each compressed vertex–vertex contact (the separating line with
//! the largest step-end gap) and re-solve ([`switch`]); (5) block increments
//! `d_i = f_i + K_i⁻¹ C_i p_i` into `x`.
//! The non-penetration condition holds to the stated tolerance (a length), with no stiffness
//! parameter anywhere.
//!
//! Units: forces N per metre of thickness (normal compression positive; shear along the edge
//! direction `t`, acting on the vertex block), lengths m.
mod flexibility;
mod gap;
mod iterate;
mod mprgp;
mod projection;
mod switch;

pub use flexibility::{invert, BlockFlex};
pub use gap::{GapFunction, Pair, PairTerms};
pub use iterate::IterReport;

use super::SolveError;
use crate::assembly::contact_springs::{JointLaw, Prescribed};
use crate::assembly::{BlockSystem, Dofs};
use crate::contact::{Contact, ContactParams, ContactState};
use crate::geometry::BlockGeometry;
use std::collections::HashMap;

/// Tuning of the dual solver. Each default says why.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DualParams {
    /// Stopping tolerance of the compatibility iteration, as a fraction of the smallest free
    /// block's half size: the largest remaining violation of a contact condition (penetration,
    /// gap under a compressive force, slip of a sticking contact) must be below it. 1e-9
    /// (a nanometre on a metre block) is invisible in any result and still far above round-off
    /// (1e-16 of the model size), so the iteration can always reach it.
    pub tolerance: f64,
    /// Iterations of one solve before the caller cuts the time step (which stiffens the
    /// inertia and improves the conditioning). Warm-started steps need tens; 20 000 bounds a
    /// hopeless step to well under a second for thousands of contacts.
    pub max_iterations: usize,
    /// First step size β of the projection (in the unit-diagonal metric, 1 is the natural
    /// scale; it adapts from there).
    pub initial_beta: f64,
    /// He's admissibility bound ν < 1 on ‖β ΔG‖ / ‖Δp‖: 0.9 is the customary value (larger
    /// steps, still contracting).
    pub nu: f64,
    /// Factor on β when the bound fails (×min(1, 1/ratio) too): 0.7 as in He's method.
    pub beta_shrink: f64,
    /// β grows by `beta_grow` after an iteration whose ratio was below `beta_grow_below`
    /// (1.5 and 0.4: He's values, so β does not stay needlessly small).
    pub beta_grow: f64,
    pub beta_grow_below: f64,
    /// Relaxation γ ∈ (0, 2) of the contraction step: 1.8 converges fastest in He's tests.
    pub gamma: f64,
    /// Products with W allowed to the MPRGP minimisation ([`mprgp`]) before the
    /// projection–contraction iteration takes over from its forces (0: the
    /// projection–contraction iteration alone, as in Zheng, Zhang & Du 2016, docs/dual.md). 5000: the warm-started solves
    /// that converge take hundreds (small stacks and walls, `tests/engine/dual_mprgp.rs`) to ~8000
    /// (the 1700-block pile); on the pile a budget of 20 000 ran its first 5 steps slower
    /// than 5000 (more time spent on solves that end in a time-step cut anyway).
    pub max_cg_iterations: usize,
    /// Power iterations estimating the largest eigenvalue of D⁻¹W (the expansion step): 12
    /// reach it within a factor 2 from a smooth start, which is all the step bound needs.
    pub power_iterations: usize,
    /// MPRGP's proportioning constant Γ: a conjugate-gradient step is taken while the
    /// gradient of the bound forces is at most Γ times that of the free ones. 1 is Dostál's
    /// recommended value (his convergence bound is best near it).
    pub proportioning: f64,
    /// Conjugate-gradient steps after which the gradient is recomputed from the forces (the
    /// recurrence drifts by round-off): 50 costs 2 % more products and keeps the drift far
    /// below the tolerance.
    pub gradient_refresh: usize,
    /// Rounds of vertex–vertex switching per step (each re-solves warm-started): 4 allows a
    /// vertex to settle at a corner without letting it flip back and forth.
    pub max_switch_rounds: usize,
    /// Items (blocks, contacts) from which per-block and per-contact loops run on rayon: below
    /// ~2000 the thread hand-off costs more than the work.
    pub parallel_from: usize,
    /// A stalled solve (MPRGP's budget and then `max_iterations` spent, the violation still
    /// above the tolerance) is accepted when its remaining violation is at most this multiple
    /// of the tolerance, and counted ([`DualOutcome::loose`], the run's
    /// `Stats::dual_loose_solves` and the largest such violation); beyond it the caller cuts
    /// the time step. 1 accepts none, so every step meets the tolerance: what the benchmarks
    /// are checked with. Larger values are for large degenerate scenes, where a stall at
    /// contacts with zero force and zero gap is not cured by a shorter step (the pile of
    /// `examples/pile.rs`, `--stall-acceptance`; docs/dual.md).
    pub stall_acceptance: f64,
    /// Cap on the stopping tolerance (a length) at the scene's time scale: at most this
    /// fraction × g × Δt², m, with Δt the scene's nominal step. The tolerance above is
    /// absolute, and a displacement error ε of a step is a velocity error 2ε/Δt (DDA's
    /// v₁ = 2d/Δt − v₀), which at a small Δt grows past the impact law's settling speed 2gΔt
    /// (`ImpactParams::slow_factor`): resting corners then read as impacts and the block lifts
    /// (the slender column at Δt = 3e-6 s,
    /// `tests/regression/regression_dual_tolerance_small_dt.rs`). With the cap the velocity
    /// error of a full step is at most this fraction of 2gΔt. 0.01: the tolerance that stopped
    /// the early lift at 3e-6 s (1e-11 of the half size, 1.2e-12 m) is 0.014 gΔt²; at the
    /// default Δt = 1 ms the cap is 9.8e-8 m, above 1e-9 of any half size below 98 m, so the
    /// default runs are unchanged. The nominal Δt, not the cut one: a cap that shrinks with
    /// each cut made a stalled solve unreachable (the rocking column's overturning bisection
    /// under the dual solver, cut to 3e-9 s, tolerance 3e-13 m). No cap without gravity (no
    /// settling speed to protect) or at 0, which a scene's own `control.dual_tolerance` sets
    /// (`Simulation::new`: an explicit tolerance is taken as given).
    pub settling_fraction: f64,
}

impl Default for DualParams {
    fn default() -> Self {
        Self {
            tolerance: 1e-9,
            max_iterations: 20_000,
            initial_beta: 1.0,
            nu: 0.9,
            beta_shrink: 0.7,
            beta_grow: 1.5,
            beta_grow_below: 0.4,
            gamma: 1.8,
            max_cg_iterations: 5_000,
            power_iterations: 12,
            proportioning: 1.0,
            gradient_refresh: 50,
            max_switch_rounds: 4,
            parallel_from: 2000,
            stall_acceptance: 1.0,
            settling_fraction: 0.01,
        }
    }
}

/// Result of one dual solve.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DualOutcome {
    pub converged: bool,
    /// Projection–contraction iterations over all switching rounds.
    pub iterations: usize,
    /// Products with W of the MPRGP minimisation over all switching rounds.
    pub cg_products: usize,
    /// Largest remaining contact-condition violation over the step's switching rounds, m.
    pub residual: f64,
    /// Contact with the largest residual.
    pub worst: Option<usize>,
    /// Vertex–vertex pairs switched.
    pub switches: usize,
    /// Converged only within `DualParams::stall_acceptance` × the tolerance (a stalled solve
    /// taken as it was; `residual` says how far from the tolerance).
    pub loose: bool,
}

/// Everything the dual solve reads besides the block system.
#[derive(Debug, Clone, Copy)]
pub struct DualInput<'a> {
    pub dofs: &'a Dofs,
    pub geoms: &'a [BlockGeometry],
    pub laws: &'a [JointLaw],
    pub prescribed: &'a [Prescribed],
    /// Length scale of the tolerances (smallest free block's half size), m.
    pub length_scale: f64,
    /// Search distance and contact parameters (for finding the alternative vertex–vertex pair).
    pub search: f64,
    pub contact: &'a ContactParams,
    /// The scene's nominal Δt, s, and |g|, m/s²: the scale of the tolerance's cap
    /// (`DualParams::settling_fraction`).
    pub nominal_dt: f64,
    pub gravity: f64,
}

/// The solve's stopping tolerance, m: `DualParams::tolerance` × the length scale, capped at
/// `settling_fraction` × g × Δt² (nominal Δt) where gravity acts.
fn stopping_tolerance(prm: &DualParams, input: &DualInput) -> f64 {
    let tol = prm.tolerance * input.length_scale;
    let cap = prm.settling_fraction * input.gravity.abs() * input.nominal_dt.powi(2);
    if cap > 0.0 {
        tol.min(cap)
    } else {
        tol
    }
}

type Key = (u32, u32, u32, u32);

fn key(c: &Contact) -> Key {
    (
        c.vertex_block as u32,
        c.vertex as u32,
        c.edge_block as u32,
        c.edge as u32,
    )
}

/// The dual solver with its scratch and the forces of the last step (warm start).
#[derive(Debug, Default)]
pub struct DualSolver {
    pub params: DualParams,
    flex: Vec<BlockFlex>,
    gap: GapFunction,
    p: Vec<Pair>,
    scratch: iterate::Scratch,
    cg: mprgp::CgScratch,
    /// Per contact: made inert by vertex–vertex switching for this step.
    inert: Vec<bool>,
    warm: HashMap<Key, Pair>,
}

impl DualSolver {
    pub fn new(params: DualParams) -> Self {
        Self {
            params,
            ..Default::default()
        }
    }

    /// Solve one step: contact forces, contact states and the block increments `x` (global
    /// layout of `dofs`). `sys` holds the block terms only (after `reset_to_blocks`).
    pub fn solve(
        &mut self,
        sys: &BlockSystem,
        input: &DualInput,
        contacts: &mut [Contact],
        x: &mut Vec<f64>,
    ) -> Result<DualOutcome, SolveError> {
        let prm = self.params;
        let tol = stopping_tolerance(&prm, input);
        self.gap.parallel_from = prm.parallel_from;
        flexibility::flexibilities(sys, input.dofs, prm.parallel_from, &mut self.flex)?;
        let mut outcome = DualOutcome {
            converged: false,
            iterations: 0,
            cg_products: 0,
            residual: 0.0,
            worst: None,
            switches: 0,
            loose: false,
        };
        let mut switched_this_step = Vec::new();
        self.inert.clear();
        self.inert.resize(contacts.len(), false);
        for round in 0..=prm.max_switch_rounds {
            self.gap.build(
                contacts,
                input.geoms,
                input.laws,
                input.dofs,
                &self.flex,
                input.prescribed,
                &self.inert,
                // 10× the solve's tolerance: a phantom depth below it is within what the
                // solve accepts anyway, so the aligned walls' round-off is left as it was.
                10.0 * tol,
            );
            self.p.clear();
            self.p.extend(
                contacts
                    .iter()
                    .map(|c| self.warm.get(&key(c)).copied().unwrap_or([0.0; 2])),
            );
            let mut r = iterate::IterReport {
                iterations: 0,
                converged: false,
                residual: f64::INFINITY,
                worst: None,
            };
            if prm.max_cg_iterations > 0 {
                r = mprgp::minimise(
                    &self.gap,
                    &self.flex,
                    &mut self.p,
                    &prm,
                    tol,
                    &mut self.scratch,
                    &mut self.cg,
                );
                outcome.cg_products += r.iterations;
            }
            if !r.converged {
                r = iterate::compatibility(
                    &self.gap,
                    &self.flex,
                    &mut self.p,
                    &prm,
                    tol,
                    &mut self.scratch,
                );
                outcome.iterations += r.iterations;
            }
            // NaN is never accepted.
            let loose = !r.converged && r.residual <= prm.stall_acceptance * tol;
            outcome.converged = r.converged || loose;
            outcome.loose |= loose;
            // The largest over the rounds: a loosely accepted round stays on record even when a
            // later round (after switching) converges.
            if r.residual >= outcome.residual || r.residual.is_nan() {
                outcome.residual = r.residual;
                outcome.worst = r.worst;
            }
            if !outcome.converged {
                return Ok(outcome);
            }
            for (c, p) in contacts.iter().zip(&self.p) {
                self.warm.insert(key(c), *p);
            }
            if round == prm.max_switch_rounds {
                break;
            }
            let n = switch::vertex_vertex(
                contacts,
                &mut self.inert,
                &self.gap,
                &self.p,
                &self.scratch.d,
                input,
                tol,
                &mut switched_this_step,
            );
            if n == 0 {
                break;
            }
            outcome.switches += n;
        }
        self.finish(input, contacts, x, tol);
        Ok(outcome)
    }

    /// Write increments, forces and states; keep the forces for the next step's warm start.
    fn finish(&mut self, input: &DualInput, contacts: &mut [Contact], x: &mut Vec<f64>, tol: f64) {
        let dofs = input.dofs;
        x.clear();
        x.resize(dofs.n, 0.0);
        for (f, d) in self.scratch.d.iter().enumerate() {
            for k in 0..dofs.ndof[f] {
                x[dofs.offset[f] + k] = d[k];
            }
        }
        self.warm.clear();
        for (k, c) in contacts.iter_mut().enumerate() {
            let [pn, pt] = self.p[k];
            let [g, s] = self.scratch.g[k];
            let t = &self.gap.terms[k];
            c.normal_force = pn;
            c.friction_normal = pn;
            c.shear_force = pt;
            c.gap = g;
            c.slip = s;
            let strength = projection::shear_strength(t, pn);
            c.state = if self.inert[k] || (g > tol && pn <= 0.0) {
                ContactState::Open
            } else if s.abs() > tol && pt.abs() >= strength * (1.0 - 1e-9) {
                ContactState::Sliding { dir: s.signum() }
            } else {
                ContactState::Locked
            };
            self.warm.insert(key(c), [pn, pt]);
        }
    }
}
