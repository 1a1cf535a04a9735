//! Simulation › errors: the typed failures of `Simulation::step` (constructed by the step's
//! stages and by `diagnostics`), each saying when, where and what to change. Analysis wraps
//! them (`RunError::Simulation`, `#[from]`).
use crate::solve::SolveError;

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
