//! Simulation › stepper: what advances the state by one step (the equilibrium system, the
//! linear and dual solvers with their scratch, the spring parameters, the integrator's
//! constants, the adaptive time step) and what the steps have counted so far (statistics,
//! stage timings, refusals). The state it advances is `state.rs`.
use super::diagnostics::{Stats, StepProfile};
use super::params::{resolve_penalty, SimParams};
use super::state::SimState;
use crate::assembly::contact_springs::SpringParams;
use crate::assembly::restitution::ImpactScratch;
use crate::assembly::{BlockSystem, Newmark};
use crate::solve::dual::{DualOutcome, DualSolver};
use crate::solve::impulse::{ImpulseReport, ImpulseSolver};
use crate::solve::open_close;
use crate::solve::LinearSolver;

pub(super) struct Stepper {
    pub(super) springs: SpringParams,
    pub(super) system: BlockSystem,
    pub(super) solver: LinearSolver,
    pub(super) dual: DualSolver,
    /// Last dual solve (for diagnostics on failure).
    pub(super) last_dual: Option<DualOutcome>,
    /// Smallest free block's half size, m (length scale of tolerances).
    pub(super) smallest_free_block: f64,
    /// The increments of the step's last solve (scratch of the solvers).
    pub(super) x: Vec<f64>,
    pub(super) newmark: Newmark,
    /// Current (adaptive) time step, s.
    pub(super) dt: f64,
    pub(super) stats: Stats,
    pub(super) profile: StepProfile,
    /// Why the open–close loop iterated (diagnostics).
    pub(super) changes: open_close::ChangeCounts,
    /// Buffers of the open–close loop kept across steps.
    pub(super) open_close_scratch: open_close::OpenCloseScratch,
    /// Step attempts refused, by reason: [contact solve not converged, a block moved beyond
    /// the step limit, a contact overshot, a step-control bound (impact location or local
    /// error)]; each led to a time-step cut or the run's end.
    pub(super) refusals: [u64; 4],
    /// Per free block (in `dofs` order): recent peak angular speed Ω, rad/s, of the rocking
    /// step control (`SimParams::rocking_velocity_change`).
    pub(super) omega_scale: Vec<f64>,
    /// Per free block: gravity's angular acceleration about its last pivot, rad/s², while it
    /// rocks (0: not rocking; see `Simulation::update_rocking`).
    pub(super) rocking_accel: Vec<f64>,
    /// The impact law's per-contact results (impact times, landings), kept across steps.
    pub(super) impact_scratch: ImpactScratch,
    /// The impact law's impulse solve and its buffers.
    pub(super) impulse: ImpulseSolver,
    /// How the last step's impulse solve went (zero if the step had no impact).
    pub(super) impulse_report: ImpulseReport,
    /// Per block: velocity (vx, vy, ω; m/s, rad/s) of blocks without unknowns, the impact
    /// law's input, refilled each step.
    pub(super) impact_immobile: Vec<[f64; 3]>,
    /// Per contact: tan φ of its joint, the impact law's input, refilled each step.
    pub(super) impact_friction: Vec<f64>,
    /// The last accepted step's closing contacts as the closing limit saw them
    /// (`SimParams::closing`, on only): how many closed within the step, and the largest
    /// approach among them as a multiple of its elastic range W/k_n.
    pub(super) last_closing: (usize, f64),
    /// The step being taken was taken with the open–close loop unconverged at the floor
    /// (`SimParams::unconverged_floor_ratio`); read by `unconverged_floor_hold`.
    pub(super) taken_unconverged: bool,
    /// The deepest penetration of a closed contact that a converged step has left so far, m:
    /// the floor's penetration bound (`SimParams::unconverged_floor_penetration`).
    pub(super) converged_penetration: f64,
    /// Per block: its rotation rate at the last step's start, rad/s, and whether the rate
    /// changed sign between the last two step ends (`OpenCloseParams::head_slip_spin`; filled
    /// only with that rule on).
    pub(super) spin_prior: Vec<f64>,
    pub(super) spin_reversed: Vec<bool>,
}

impl Stepper {
    /// The stepper for `state`'s scene: springs from the resolved penalty, the scene's
    /// integrator and time step.
    pub(super) fn new(state: &SimState, params: &SimParams) -> Self {
        let scene = &state.scene;
        let smallest_free_block = state.smallest_free_block();
        let penalty = resolve_penalty(scene);
        let newmark = params
            .newmark
            .unwrap_or_else(|| Newmark::of(scene.control.integrator));
        let springs = SpringParams {
            normal: penalty,
            shear: penalty * params.shear_ratio,
            gap_tolerance: params.gap_tolerance_ratio * smallest_free_block,
            release_weight: (1.0 - newmark.gamma) / newmark.gamma,
        };
        Self {
            springs,
            system: BlockSystem::default(),
            solver: LinearSolver::new(params.solver),
            dual: DualSolver::new(params.dual),
            last_dual: None,
            smallest_free_block,
            x: Vec::new(),
            newmark,
            dt: scene.control.time_step,
            stats: Stats {
                min_dt: f64::INFINITY,
                ..Default::default()
            },
            profile: StepProfile::default(),
            changes: Default::default(),
            open_close_scratch: Default::default(),
            refusals: [0; 4],
            omega_scale: vec![0.0; state.dofs.block_of.len()],
            rocking_accel: vec![0.0; state.dofs.block_of.len()],
            impact_scratch: ImpactScratch::default(),
            impulse: ImpulseSolver::default(),
            impulse_report: ImpulseReport::default(),
            impact_immobile: Vec::new(),
            impact_friction: Vec::new(),
            last_closing: (0, 0.0),
            taken_unconverged: false,
            converged_penetration: 0.0,
            spin_prior: Vec::new(),
            spin_reversed: Vec::new(),
        }
    }
}
