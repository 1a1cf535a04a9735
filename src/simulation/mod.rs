//! Simulation: the DDA time step, assembled from the stages of the flow. `step` reads like
//! the algorithm: detect contacts, then (with time-step cuts on failure) assemble, run the
//! open–close loop and check the step, then integrate. Each stage is timed into
//! [`StepProfile`].
mod energy;
mod params;

pub use energy::Energy;
pub use params::{resolve_penalty, SimParams, IMPACT_APPROACH_RATIO};

use crate::assembly::contact_springs::{JointLaw, Prescribed, SpringParams};
use crate::assembly::restitution::{apply_impacts, located_step, ImpactInput};
use crate::assembly::{elasticity, BlockState, BlockSystem, BodyLoads, Dofs, Newmark};
use crate::contact::{Contact, ContactSet, ContactState, Mobility};
use crate::geometry::{displacement_matrix, BlockGeometry, Vec6};
use crate::integrate;
use crate::motion::GroundMotion;
use crate::scene::{BlockKind, BlockModel, ContactSolver, Control, Excitation, Restitution, Scene};
use crate::solve::dual::{DualInput, DualOutcome, DualSolver};
use crate::solve::open_close::{self, OpenClose};
use crate::solve::{LinearSolver, SolveError};
use nalgebra::{Matrix3, Vector3};
use std::time::{Duration, Instant};

/// A typed failure of the engine, with where and what to change.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum SimError {
    #[error(
        "open–close did not converge at t = {time:.6} s after {cuts} time-step cuts (Δt = {dt:.3e} s); contact between blocks {block_a:?} and {block_b:?}; try a smaller penalty stiffness or time step"
    )]
    NotConverged {
        time: f64,
        cuts: u32,
        dt: f64,
        block_a: String,
        block_b: String,
    },
    #[error("linear solve failed at t = {time:.6} s: {error} (block {block:?}); check for unconstrained or degenerate blocks, or reduce the penalty stiffness")]
    Solve {
        time: f64,
        error: SolveError,
        block: String,
    },
    #[error(
        "dual contact solver did not converge at t = {time:.6} s after {cuts} time-step cuts (Δt = {dt:.3e} s, {iterations} iterations, remaining violation {residual:.3e} m) at the contact between blocks {block_a:?} and {block_b:?}; try a smaller control.time_step, a larger control.dual_tolerance (default 1e-9 of the smallest block's half size), or control.dual_stall_acceptance above 1 to accept stalled solves within that multiple of the tolerance"
    )]
    DualNotConverged {
        time: f64,
        cuts: u32,
        dt: f64,
        iterations: usize,
        residual: f64,
        block_a: String,
        block_b: String,
    },
    /// A step whose solution moves a block's vertex farther than the step's displacement limit
    /// (Shi's g2 × the model's half size), even at the shortest step the cuts allow.
    #[error(
        "block {block:?} would move {moved:.3e} m in one step at t = {time:.6} s, more than the step limit of {limit:.3e} m (control.max_displacement_ratio × the model's half size), still after {cuts} time-step cuts (Δt = {dt:.3e} s): check the block's support and initial velocity; with the dual solver, a stalled solve taken by control.dual_stall_acceptance can also leave forces this wrong"
    )]
    StepTooLarge {
        time: f64,
        cuts: u32,
        dt: f64,
        /// Largest vertex displacement of the block in the refused step, m.
        moved: f64,
        limit: f64,
        block: String,
    },
    /// A step left a block's position, rotation or velocity NaN or infinite (checked at the
    /// end of every `step`); `time` is the step's end, s.
    #[error("non-finite state at t = {time:.6} s in block {block:?}; reduce the time step or the penalty stiffness")]
    NonFinite { time: f64, block: String },
    #[error("penetration of {depth:.3e} m at t = {time:.6} s between blocks {block_a:?} and {block_b:?} could not be reduced by cutting the time step; raise the penalty stiffness")]
    Penetration {
        time: f64,
        depth: f64,
        block_a: String,
        block_b: String,
    },
    /// A converged step left a vertex deeper inside a block than the penetration limit: the
    /// smaller of `SimParams::max_penetration_ratio` × the thinner block and the contact search
    /// distance (deeper contacts are no longer detected and the blocks would pass through each
    /// other). `explanation` says why this limit, whether the penetration built up (springs too
    /// soft) or appeared within a step (step too long), and what to change.
    #[error("penetration of {depth:.3e} m at t = {time:.6} s between blocks {block_a:?} and {block_b:?} exceeds the limit of {limit:.3e} m ({explanation}")]
    PenaltyTooSoft {
        time: f64,
        depth: f64,
        limit: f64,
        /// "<why this limit>); <cause>; <what to change>" (one string keeps the error small).
        explanation: String,
        block_a: String,
        block_b: String,
    },
}

/// 4·area / perimeter of a polygon, m: the side of a square, twice the thickness of a long slab
/// or needle, whatever its orientation.
fn thickness(v: &[nalgebra::Vector2<f64>]) -> f64 {
    let n = v.len();
    let (mut area2, mut perimeter) = (0.0, 0.0);
    for k in 0..n {
        let (a, b) = (v[k], v[(k + 1) % n]);
        area2 += a.perp(&b);
        perimeter += (b - a).norm();
    }
    2.0 * area2.abs() / perimeter
}

/// Why one attempt at a step is refused (the step is then cut, or the run stops).
#[derive(Debug, Clone, Copy, PartialEq)]
enum Refusal {
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
    fn factor(self, cut: f64) -> f64 {
        match self {
            Refusal::Impact { factor, .. } | Refusal::LocalError { factor, .. } => {
                (0.9 * factor).clamp(cut, 0.9)
            }
            _ => cut,
        }
    }

    /// A bound of the step's accuracy, not of its validity.
    fn is_accuracy(self) -> bool {
        matches!(self, Refusal::Impact { .. } | Refusal::LocalError { .. })
    }
}

/// Wall time spent in each stage (accumulated over steps).
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct StepProfile {
    pub detect: Duration,
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
}

/// The engine state of one scene under one ground motion.
pub struct Simulation {
    pub scene: Scene,
    pub motion: GroundMotion,
    pub params: SimParams,
    pub geoms: Vec<BlockGeometry>,
    pub mobility: Vec<Mobility>,
    pub dofs: Dofs,
    /// Per free block.
    pub states: Vec<BlockState>,
    densities: Vec<f64>,
    elastic: Vec<Matrix3<f64>>,
    pub contacts: ContactSet,
    laws: Vec<JointLaw>,
    pub springs: SpringParams,
    system: BlockSystem,
    solver: LinearSolver,
    dual: DualSolver,
    /// Last dual solve (for diagnostics on failure).
    last_dual: Option<DualOutcome>,
    /// Smallest free block's half size, m (length scale of tolerances).
    smallest_free_block: f64,
    x: Vec<f64>,
    prescribed: Vec<Prescribed>,
    start_states: Vec<BlockState>,
    newmark: Newmark,
    /// Simulated time, s.
    pub time: f64,
    /// Current (adaptive) time step, s.
    pub dt: f64,
    /// Half the diagonal of the whole model's bounding box at the start, m.
    pub model_half_size: f64,
    /// Per block: 4·area / perimeter at the start (the side of a square, twice the thickness
    /// of a slab), m; the length penetrations are measured against.
    pub thickness: Vec<f64>,
    pub stats: Stats,
    pub profile: StepProfile,
    /// Why the open–close loop iterated (diagnostics).
    pub changes: open_close::ChangeCounts,
    /// Buffers of the open–close loop kept across steps.
    open_close_scratch: open_close::OpenCloseScratch,
    /// Step attempts refused, by reason: [contact solve not converged, a block moved beyond
    /// the step limit, a contact overshot, a step-control bound (impact location or local
    /// error)]; each led to a time-step cut or the run's end.
    pub refusals: [u64; 4],
    /// Per block: retired (left the scene, frozen where it was; see [`Simulation::retire`]).
    pub retired: Vec<bool>,
}

impl std::fmt::Debug for Simulation {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Simulation")
            .field("time", &self.time)
            .field("dt", &self.dt)
            .field("blocks", &self.geoms.len())
            .finish()
    }
}

/// The engine knobs a scene may set (`control.dual_tolerance`, `control.dual_stall_acceptance`)
/// override the caller's; unset ones keep them.
fn with_scene_knobs(mut params: SimParams, control: &Control) -> SimParams {
    if let Some(t) = control.dual_tolerance {
        params.dual.tolerance = t;
    }
    if let Some(a) = control.dual_stall_acceptance {
        params.dual.stall_acceptance = a;
    }
    params
}

impl Simulation {
    pub fn new(scene: &Scene, motion: &GroundMotion, params: SimParams) -> Self {
        let params = with_scene_knobs(params, &scene.control);
        let geoms: Vec<BlockGeometry> = scene
            .blocks
            .iter()
            .map(|b| BlockGeometry::new(b.vertices.clone()))
            .collect();
        let mobility: Vec<Mobility> = scene
            .blocks
            .iter()
            .map(|b| match b.kind {
                BlockKind::Fixed => Mobility::Fixed,
                BlockKind::Driven => Mobility::Driven,
                BlockKind::Free(_) => Mobility::Free,
            })
            .collect();
        let mut dofs = Dofs {
            free_index: vec![None; geoms.len()],
            ..Default::default()
        };
        let (mut densities, mut elastic, mut states) = (Vec::new(), Vec::new(), Vec::new());
        for (b, blk) in scene.blocks.iter().enumerate() {
            if let BlockKind::Free(model) = blk.kind {
                let nd = if model == BlockModel::Rigid { 3 } else { 6 };
                dofs.free_index[b] = Some(dofs.block_of.len());
                dofs.block_of.push(b);
                dofs.ndof.push(nd);
                dofs.offset.push(dofs.n);
                dofs.n += nd;
                let mat = &scene.materials[blk.material];
                densities.push(mat.density);
                elastic.push(elasticity(mat));
                let v = scene.initial_velocity[b];
                let mut st = BlockState::default();
                st.vel[0] = v[0];
                st.vel[1] = v[1];
                st.vel[2] = v[2];
                states.push(st);
            }
        }
        let mut lo = geoms[0].vertices[0];
        let mut hi = lo;
        for g in &geoms {
            let (a, b) = g.bounds();
            lo = lo.inf(&a);
            hi = hi.sup(&b);
        }
        let model_half_size = 0.5 * (hi - lo).norm();
        let smallest_free_block = dofs
            .block_of
            .iter()
            .map(|&b| geoms[b].half_size)
            .fold(f64::INFINITY, f64::min);
        let penalty = resolve_penalty(scene);
        let newmark = Newmark::of(scene.control.integrator);
        let springs = SpringParams {
            normal: penalty,
            shear: penalty * params.shear_ratio,
            gap_tolerance: params.gap_tolerance_ratio * smallest_free_block,
            release_weight: (1.0 - newmark.gamma) / newmark.gamma,
        };
        let dt = scene.control.time_step;
        let thickness = geoms.iter().map(|g| thickness(&g.vertices)).collect();
        Self {
            scene: scene.clone(),
            motion: motion.clone(),
            geoms,
            mobility,
            dofs,
            states,
            densities,
            elastic,
            contacts: ContactSet::default(),
            laws: Vec::new(),
            springs,
            system: BlockSystem::default(),
            solver: LinearSolver::new(params.solver),
            dual: DualSolver::new(params.dual),
            last_dual: None,
            smallest_free_block,
            x: Vec::new(),
            prescribed: vec![[0.0; 2]; scene.blocks.len()],
            start_states: Vec::new(),
            newmark,
            time: 0.0,
            dt,
            model_half_size,
            thickness,
            stats: Stats {
                min_dt: f64::INFINITY,
                ..Default::default()
            },
            profile: StepProfile::default(),
            changes: Default::default(),
            open_close_scratch: Default::default(),
            refusals: [0; 4],
            retired: vec![false; scene.blocks.len()],
            params,
        }
    }

    /// Work counters of the sparse linear solver (factorizations, reused-factor iterations).
    pub fn solver_counts(&self) -> crate::solve::SparseCounts {
        self.solver.sparse_counts()
    }

    /// The linear system the last linear solve of [`Simulation::step`] solved, read-only, for
    /// verification (tests/engine/invariants.rs checks its symmetry and that the step's increments
    /// solve it). With the penalty contact solver: block terms + the contact springs of the
    /// converged open–close iteration (the step's last solve; integration does not touch it).
    /// With the dual solver: the block terms its flexibilities come from (no springs).
    /// Off-diagonal blocks are stored once per coupled pair: `off[p]` is K_ab for
    /// `pairs[p] = (a, b)`, a < b, and the solvers read K_ba as K_abᵀ.
    pub fn solved_system(&self) -> &BlockSystem {
        &self.system
    }

    /// The increments of the step's last solve (global unknowns in `dofs` order, 6 a block:
    /// u0, v0, r0, εx, εy, γxy): with the penalty solver, the solution of
    /// [`Simulation::solved_system`].
    pub fn solved_increments(&self) -> &[f64] {
        &self.x
    }

    /// Contact search distance, m: Shi's search factor × the largest step displacement. One
    /// definition for detection, the dual solver and the penetration check.
    pub fn search_distance(&self) -> f64 {
        self.params.contact.search_factor * self.max_step_displacement()
    }

    /// Largest displacement allowed in one step (Shi's g2 × model half size), m.
    pub fn max_step_displacement(&self) -> f64 {
        self.scene.control.max_displacement_ratio * self.model_half_size
    }

    /// Advance one step of at most `max_dt` (and at most the current adaptive step).
    /// Returns the step length taken.
    pub fn step(&mut self, max_dt: f64) -> Result<f64, SimError> {
        let t0 = Instant::now();
        self.detect_contacts();
        let t1 = Instant::now();
        self.profile.detect += t1 - t0;
        let mut dt = self.dt.min(max_dt).min(self.rotation_bound());
        // "housner" is Newton's law with e = 0 (an impact without bounce); "contact" leaves the
        // impact to the contact springs / dual solver.
        match self.scene.control.restitution {
            Restitution::Housner => dt = self.impacts(0.0, dt),
            Restitution::Coefficient(e) => dt = self.impacts(e, dt),
            Restitution::Contact => {}
        }
        self.start_states.clone_from(&self.states);
        let mut cuts = 0u32;
        loop {
            self.assemble(dt);
            let t2 = Instant::now();
            let refusal = match self.scene.control.contact_solver {
                ContactSolver::Penalty => match self.open_close()? {
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
            self.profile.solve += t2.elapsed();
            let Some(refusal) = refusal else { break };
            self.refusals[match refusal {
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
            self.stats.time_step_cuts += 1;
            // Cutting below min_dt means the step cannot be resolved: fail with a diagnostic
            // instead of creeping forward at a vanishing step.
            if cuts > self.params.max_cuts || dt * self.params.cut_factor < self.params.min_dt {
                return Err(self.refused(cuts, dt, refusal));
            }
            dt *= refusal.factor(self.params.cut_factor);
            self.states.clone_from(&self.start_states);
        }
        if let Some(e) = self.too_soft(dt) {
            return Err(e);
        }
        let error = if self.scene.control.adaptive_time_step {
            self.local_error(dt).map(|(_, e)| e)
        } else {
            None
        };
        let t3 = Instant::now();
        self.integrate(dt);
        self.profile.integrate += t3.elapsed();
        self.finish_step(dt, cuts, error);
        // A NaN or infinity never leaves an accepted step: it would poison every later step
        // and every recorded frame.
        if let Some(b) = self.first_non_finite_block() {
            return Err(SimError::NonFinite {
                time: self.time,
                block: self.scene.blocks[b].id.clone(),
            });
        }
        Ok(dt)
    }

    /// Broad and narrow phase, then the per-step contact linearization and joint laws.
    fn detect_contacts(&mut self) {
        let search = self.search_distance();
        let scene = &self.scene;
        let first = self.stats.steps == 0;
        // A retired block touches nothing: it is hidden from the broad phase as an immobile
        // block among immobile ones, and the only free blocks it could meet have left too.
        let hidden;
        let mobility = if self.retired.iter().any(|&r| r) {
            hidden = self
                .mobility
                .iter()
                .zip(&self.retired)
                .map(|(&m, &r)| if r { Mobility::Fixed } else { m })
                .collect::<Vec<_>>();
            &hidden
        } else {
            &self.mobility
        };
        let rebuilt = self.contacts.detect(
            &self.geoms,
            mobility,
            search,
            &self.params.contact,
            first,
            |a, b| {
                let j = scene.joint_between(a, b);
                j.cohesion > 0.0 || j.tensile_strength > 0.0
            },
        );
        self.contacts.linearize(&self.geoms);
        if !rebuilt {
            // Same contacts as the last step: joint laws and the block pattern still hold.
            return;
        }
        self.laws.clear();
        for c in &self.contacts.contacts {
            let j = scene.joint_between(c.vertex_block, c.edge_block);
            self.laws.push(JointLaw {
                tan_phi: j.friction_angle.tan(),
                cohesion: j.cohesion,
                tensile_strength: j.tensile_strength,
            });
        }
        let mut pairs = Vec::new();
        for c in &self.contacts.contacts {
            if let (Some(a), Some(b)) = (
                self.dofs.free_index[c.vertex_block],
                self.dofs.free_index[c.edge_block],
            ) {
                pairs.push((a.min(b), a.max(b)));
            }
        }
        self.system.set_pattern(pairs);
        self.system
            .bind_contacts(&self.dofs, &self.contacts.contacts);
    }

    /// Newton's impact law (`control.restitution`) at the contacts at their impact at the step
    /// start: the step then starts from the velocities after the impact. Returns the step to
    /// take: `dt`, or shorter so that it ends just before the next impact (event location,
    /// `ImpactParams::window`; not a cut: the next step is `dt` again).
    fn impacts(&mut self, e: f64, dt: f64) -> f64 {
        let immobile: Vec<[f64; 3]> = (0..self.scene.blocks.len())
            .map(|b| match self.dofs.free_index[b] {
                Some(_) => [0.0; 3],
                None => self.block_velocity(b),
            })
            .collect();
        let friction: Vec<f64> = self.laws.iter().map(|l| l.tan_phi).collect();
        let input = ImpactInput {
            dofs: &self.dofs,
            geoms: &self.geoms,
            densities: &self.densities,
            immobile_velocity: &immobile,
            friction: &friction,
            retired: &self.retired,
            restitution: e,
            dt,
            nominal_dt: self.scene.control.time_step,
            gravity: self.scene.gravity,
        };
        let n = apply_impacts(
            &input,
            &self.contacts.contacts,
            &mut self.states,
            &self.params.impact,
        );
        self.stats.impacts += n as u64;
        located_step(
            &input,
            &self.contacts.contacts,
            &self.states,
            &self.params.impact,
        )
    }

    /// Kinetic damping, loads at the step end, prescribed motion, block terms.
    fn assemble(&mut self, dt: f64) {
        let t = Instant::now();
        let c = &self.scene.control;
        let keep = c.dynamic_factor * (-c.kinetic_damping_rate * dt).exp();
        for st in &mut self.states {
            st.vel *= keep;
            st.acc *= keep;
        }
        let t_end = self.time + dt;
        let ground = match self.scene.excitation {
            Excitation::BaseAcceleration => self.motion.acceleration(t_end),
            Excitation::DrivenBlock(b) => {
                let d0 = self.motion.state(self.time)[2];
                let d1 = self.motion.state(t_end)[2];
                self.prescribed[b] = [d1[0] - d0[0], d1[1] - d0[1]];
                [0.0, 0.0]
            }
        };
        let loads = BodyLoads {
            gravity: self.scene.gravity,
            ground_acceleration: ground,
        };
        self.system.assemble_blocks(
            &self.dofs,
            &self.geoms,
            &self.densities,
            &self.elastic,
            &self.states,
            &loads,
            self.newmark,
            dt,
        );
        for (f, &b) in self.dofs.block_of.iter().enumerate() {
            if self.retired[b] {
                self.system.clear_block_load(f);
            }
        }
        self.profile.assemble += t.elapsed();
    }

    fn open_close(&mut self) -> Result<OpenClose, SimError> {
        let r = open_close::iterate(
            &mut self.system,
            &self.dofs,
            &mut self.contacts.contacts,
            &self.laws,
            &self.springs,
            &self.prescribed,
            &mut self.solver,
            &mut self.x,
            &self.params.open_close,
            &mut self.changes,
            &mut self.open_close_scratch,
        );
        match r {
            Ok(o) => {
                let (OpenClose::Converged { iterations }
                | OpenClose::NotConverged { iterations, .. }) = o;
                self.stats.open_close_iterations += iterations as u64;
                Ok(o)
            }
            Err(error) => {
                let dof = match error {
                    SolveError::NotPositiveDefinite { dof } | SolveError::NonFinite { dof } => dof,
                    SolveError::Backend(_) => 0,
                };
                Err(SimError::Solve {
                    time: self.time,
                    error,
                    block: self.block_of_dof(dof),
                })
            }
        }
    }

    /// The dual form's solve stage: contact forces as unknowns (no springs), per-block
    /// flexibilities, the compatibility iteration; writes the increments into `x`.
    fn dual_solve(&mut self) -> Result<DualOutcome, SimError> {
        self.system.reset_to_blocks();
        let input = DualInput {
            dofs: &self.dofs,
            geoms: &self.geoms,
            laws: &self.laws,
            prescribed: &self.prescribed,
            length_scale: self.smallest_free_block,
            search: self.search_distance(),
            contact: &self.params.contact,
        };
        let r = self.dual.solve(
            &self.system,
            &input,
            &mut self.contacts.contacts,
            &mut self.x,
        );
        match r {
            Ok(o) => {
                self.stats.dual_iterations += o.iterations as u64;
                self.stats.dual_cg_products += o.cg_products as u64;
                self.stats.dual_switches += o.switches as u64;
                self.last_dual = Some(o);
                Ok(o)
            }
            Err(error) => {
                let dof = match error {
                    SolveError::NotPositiveDefinite { dof } | SolveError::NonFinite { dof } => dof,
                    SolveError::Backend(_) => 0,
                };
                Err(SimError::Solve {
                    time: self.time,
                    error,
                    block: self.block_of_dof(dof),
                })
            }
        }
    }

    /// After convergence: is the step within the displacement limit and the penetration
    /// tolerance? Returns why not, if not.
    fn check_step(&self, dt: f64) -> Option<Refusal> {
        if self.scene.control.adaptive_time_step {
            let limit = self.max_step_displacement();
            for f in 0..self.dofs.block_of.len() {
                let d = self.block_increment(f);
                let b = self.dofs.block_of[f];
                let g = &self.geoms[b];
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
        for (k, c) in self.contacts.contacts.iter().enumerate() {
            if self.overshot(c) && self.dt * self.params.cut_factor > self.params.min_dt {
                return Some(Refusal::Overshot(k));
            }
        }
        if self.scene.control.adaptive_time_step {
            return self.step_control(dt);
        }
        None
    }

    /// The longest step that turns no free block by more than `SimParams::max_rotation_step`
    /// at its current angular velocity (adaptive runs only; infinite without the bound).
    fn rotation_bound(&self) -> f64 {
        let Some(limit) = self.params.max_rotation_step else {
            return f64::INFINITY;
        };
        if !self.scene.control.adaptive_time_step {
            return f64::INFINITY;
        }
        let w = self
            .states
            .iter()
            .map(|s| s.vel[2].abs())
            .fold(0.0, f64::max);
        (limit / w).max(10.0 * self.params.min_dt)
    }

    /// The accuracy bounds of the adaptive step (impact location, rotation per step): the
    /// worst violation, if any, as a refusal with the factor that meets its bound. Never
    /// below `min_dt` × 10 (a step this short is no longer an accuracy question).
    fn step_control(&self, dt: f64) -> Option<Refusal> {
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
            let limit = ratio * self.smallest_free_block;
            for (k, c) in self.contacts.contacts.iter().enumerate() {
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
            let floor = self.params.min_error_step_ratio * self.scene.control.time_step;
            if e > 2.0 * tol && dt > floor {
                let factor = (tol / e).sqrt().max(floor / dt);
                keep(Refusal::LocalError { factor }, factor);
            }
        }
        worst
    }

    /// The local error bound, m (infinite when the control is off).
    fn local_error_tolerance(&self) -> f64 {
        self.params
            .local_error_ratio
            .map_or(f64::INFINITY, |r| r * self.smallest_free_block)
    }

    /// The step's estimated local displacement error, m, and the block where it is largest:
    /// |β − 1/6|·Δt²·|a₁ − a₀| at the worst vertex, a₁ from the solved increments (the same
    /// Newmark rule as `integrate::update_motion`), a₀ the step-start acceleration. `None`
    /// when the control is off.
    fn local_error(&self, dt: f64) -> Option<(usize, f64)> {
        self.params.local_error_ratio?;
        let nm = self.newmark;
        let c = (nm.beta - 1.0 / 6.0).abs() * dt * dt;
        let mut worst = (0, 0.0f64);
        for f in 0..self.dofs.block_of.len() {
            let b = self.dofs.block_of[f];
            if self.retired[b] {
                continue;
            }
            let d = self.block_increment(f);
            let st = &self.states[f];
            let a1 = (d - st.vel * dt - st.acc * (dt * dt * (0.5 - nm.beta))) / (nm.beta * dt * dt);
            let da = a1 - st.acc;
            let g = &self.geoms[b];
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

    fn block_increment(&self, f: usize) -> Vec6 {
        let mut d = Vec6::zeros();
        let o = self.dofs.offset[f];
        for k in 0..self.dofs.ndof[f] {
            d[k] = self.x[o + k];
        }
        d
    }

    fn integrate(&mut self, dt: f64) {
        for f in 0..self.dofs.block_of.len() {
            let d = self.block_increment(f);
            let b = self.dofs.block_of[f];
            integrate::move_block(&mut self.geoms[b], &d);
            integrate::update_motion(&mut self.states[f], &d, self.newmark, dt);
            if self.dofs.ndof[f] == 6 {
                integrate::update_stress(&mut self.states[f], &d, &self.elastic[f]);
            }
        }
        if let Excitation::DrivenBlock(b) = self.scene.excitation {
            integrate::translate_block(&mut self.geoms[b], self.prescribed[b]);
        }
        self.remove_release_loads();
    }

    /// The release loads of contacts that opened in this step (see
    /// `contact_springs::release_load`) correct the step's force average, not the forces at
    /// its end: take them out of the stored acceleration a₁, which the next step averages as
    /// its a₀.
    fn remove_release_loads(&mut self) {
        for c in &self.contacts.contacts {
            let l = crate::assembly::contact_springs::release_load(c, &self.springs);
            if l == 0.0 {
                continue;
            }
            for (block, load) in [(c.vertex_block, c.e_i * l), (c.edge_block, c.e_j * -l)] {
                let Some(f) = self.dofs.free_index[block] else {
                    continue;
                };
                let n = self.dofs.ndof[f];
                let m = self.system.mass[f].view((0, 0), (n, n)).clone_owned();
                let rhs = load.rows(0, n).clone_owned();
                if let Some(da) = m.cholesky().map(|ch| ch.solve(&rhs)) {
                    for k in 0..n {
                        self.states[f].acc[k] -= da[k];
                    }
                }
            }
        }
    }

    /// Contact bookkeeping and time-step control after an accepted step.
    fn finish_step(&mut self, dt: f64, cuts: u32, error: Option<f64>) {
        let shear = self.springs.shear;
        for (c, law) in self.contacts.contacts.iter_mut().zip(&self.laws) {
            c.closed_within_last_step = c.g0 > 0.0 && c.state.is_closed();
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
                self.stats.max_penetration = self.stats.max_penetration.max(-c.gap);
            }
        }
        if let Some(o) = self.last_dual.filter(|o| o.loose) {
            self.stats.dual_loose_solves += 1;
            self.stats.dual_loose_residual = self.stats.dual_loose_residual.max(o.residual);
        }
        self.time += dt;
        self.stats.steps += 1;
        self.stats.min_dt = self.stats.min_dt.min(dt);
        self.stats.max_dt = self.stats.max_dt.max(dt);
        if cuts > 0 {
            self.dt = dt;
        } else if self.scene.control.adaptive_time_step || self.dt < self.scene.control.time_step {
            self.dt = (self.dt * self.params.growth).min(self.scene.control.time_step);
        }
        if let Some(e) = error {
            // The next step from the estimate (local error ∝ Δt²), never below the floor.
            let tol = self.local_error_tolerance();
            let floor = self.params.min_error_step_ratio * self.scene.control.time_step;
            if e > 0.0 {
                let sized = (0.9 * dt * (tol / e).sqrt()).max(floor);
                self.dt = self.dt.min(sized);
            }
        }
    }

    fn elastic_inverse(&self, f: usize) -> Option<Matrix3<f64>> {
        self.elastic[f].try_inverse()
    }

    fn block_of_dof(&self, dof: usize) -> String {
        for f in 0..self.dofs.block_of.len() {
            if dof >= self.dofs.offset[f] && dof < self.dofs.offset[f] + self.dofs.ndof[f] {
                return self.scene.blocks[self.dofs.block_of[f]].id.clone();
            }
        }
        "?".into()
    }

    /// A closed contact whose penetration deepened within the step by more than the tolerance:
    /// a vertex overshot its edge (a time-step problem). A deep but steady penetration is the
    /// spring's compliance (a penalty problem) and is reported, not cut.
    fn overshot(&self, c: &Contact) -> bool {
        let deepened = -c.gap - (-c.g0).max(0.0);
        c.state.is_closed()
            && deepened > self.params.penetration_ratio * self.max_step_displacement()
    }

    /// A closed contact deeper than `max_penetration_ratio` of the thinner block after a
    /// converged step (docs/stability.md: a soft penalty used to complete silently with blocks sunk
    /// into each other, see tests/regression/regression_soft_penalty.rs).
    fn too_soft(&self, dt: f64) -> Option<SimError> {
        let ratio = self.params.max_penetration_ratio;
        let search = self.search_distance();
        let limit_of = |c: &Contact| {
            let thin = self.thickness[c.vertex_block].min(self.thickness[c.edge_block]);
            (ratio * thin).min(search)
        };
        let c = self
            .contacts
            .contacts
            .iter()
            .find(|c| c.state.is_closed() && -c.gap > limit_of(c))?;
        let thin = self.thickness[c.vertex_block].min(self.thickness[c.edge_block]);
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
        let penalty = self.springs.normal;
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
            let stiffest = self.scene.materials.iter().map(|m| m.young_modulus);
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
            time: self.time + dt,
            depth,
            limit,
            explanation: format!("{limit_reason}); {cause}; {advice}"),
            block_a: self.scene.blocks[c.vertex_block].id.clone(),
            block_b: self.scene.blocks[c.edge_block].id.clone(),
        })
    }

    /// The typed error for a step refused at the last cut allowed.
    fn refused(&self, cuts: u32, dt: f64, refusal: Refusal) -> SimError {
        let contact = match refusal {
            Refusal::Moved { block, by } => {
                return SimError::StepTooLarge {
                    time: self.time,
                    cuts,
                    dt,
                    moved: by,
                    limit: self.max_step_displacement(),
                    block: self.scene.blocks[block].id.clone(),
                }
            }
            Refusal::Unconverged(k) => k,
            Refusal::Overshot(k) | Refusal::Impact { contact: k, .. } => Some(k),
            Refusal::LocalError { .. } => None,
        };
        let (a, b) = match contact.and_then(|k| self.contacts.contacts.get(k)) {
            Some(c) => (
                self.scene.blocks[c.vertex_block].id.clone(),
                self.scene.blocks[c.edge_block].id.clone(),
            ),
            None => ("?".into(), "?".into()),
        };
        if let (ContactSolver::Dual, Some(o)) = (self.scene.control.contact_solver, self.last_dual)
        {
            if !o.converged {
                return SimError::DualNotConverged {
                    time: self.time,
                    cuts,
                    dt,
                    iterations: o.iterations,
                    residual: o.residual,
                    block_a: a,
                    block_b: b,
                };
            }
        }
        if let Some(c) = contact.and_then(|k| self.contacts.contacts.get(k)) {
            if self.overshot(c) {
                return SimError::Penetration {
                    time: self.time,
                    depth: -c.gap,
                    block_a: a,
                    block_b: b,
                };
            }
        }
        SimError::NotConverged {
            time: self.time,
            cuts,
            dt,
            block_a: a,
            block_b: b,
        }
    }

    /// Velocity of a block's centroid and its angular velocity (m/s, rad/s); driven blocks move
    /// with the ground, fixed blocks are still.
    pub fn block_velocity(&self, b: usize) -> [f64; 3] {
        match self.dofs.free_index[b] {
            Some(f) => [
                self.states[f].vel[0],
                self.states[f].vel[1],
                self.states[f].vel[2],
            ],
            None if self.mobility[b] == Mobility::Driven => {
                let v = self.motion.state(self.time)[1];
                [v[0], v[1], 0.0]
            }
            None => [0.0; 3],
        }
    }

    /// Retire free block `b`: it left the scene (fell far below it), so it is frozen where it
    /// is — no velocity, no load, no contacts — and costs the step control nothing from now
    /// on. Its unknowns stay in the system (solved to zero) so the numbering does not change.
    pub fn retire(&mut self, b: usize) {
        let Some(f) = self.dofs.free_index[b] else {
            return;
        };
        self.retired[b] = true;
        let st = &mut self.states[f];
        st.vel = Vec6::zeros();
        st.acc = Vec6::zeros();
        st.stress = Vector3::zeros();
        // Its contacts are dropped by the next detection, which must not be skipped.
        self.contacts.force_detection();
    }

    /// The first block whose position, rotation or velocity is not finite (`step` fails with
    /// [`SimError::NonFinite`] naming it).
    pub fn first_non_finite_block(&self) -> Option<usize> {
        for (b, g) in self.geoms.iter().enumerate() {
            if !g.centroid.x.is_finite() || !g.centroid.y.is_finite() || !g.rotation.is_finite() {
                return Some(b);
            }
        }
        for (f, st) in self.states.iter().enumerate() {
            if st.vel.iter().any(|v| !v.is_finite()) {
                return Some(self.dofs.block_of[f]);
            }
        }
        None
    }
}
