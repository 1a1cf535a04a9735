//! Engine tuning knobs and the automatic penalty stiffness.
use crate::assembly::restitution::ImpactParams;
use crate::contact::ContactParams;
use crate::scene::{Penalty, Scene};
use crate::solve::dual::DualParams;
use crate::solve::open_close::OpenCloseParams;
use crate::solve::SolverParams;

/// Knobs of the time-step loop. Each default says why.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SimParams {
    pub contact: ContactParams,
    pub open_close: OpenCloseParams,
    pub solver: SolverParams,
    /// The dual (penalty-free) contact solver, used when `control.contact_solver = "dual"`.
    pub dual: DualParams,
    /// Newton's impact law, used when `control.restitution` is a number.
    pub impact: ImpactParams,
    /// Shear spring stiffness as a fraction of the normal one: Shi's code uses 1/2.5.
    pub shear_ratio: f64,
    /// Cuts of one step before giving up: 0.3¹² ≈ 5e-7, so a 1 ms step can shrink to ~0.5 ns.
    pub max_cuts: u32,
    /// Factor applied to Δt on a cut (Shi's 0.3: large enough a cut to change the outcome).
    pub cut_factor: f64,
    /// Growth of Δt per accepted step back towards `control.time_step`: +10 % a step recovers
    /// a 0.3 cut in 13 steps without provoking an immediate new cut.
    pub growth: f64,
    /// Largest growth of a penetration within one step, as a fraction of the largest step
    /// displacement (Shi's g2 · half size): 0.3 keeps blocks from passing vertices through edges.
    pub penetration_ratio: f64,
    /// Smallest Δt (s) a cut may reach: below it the step fails with a typed diagnostic (a
    /// run crawling at nanosecond steps is a hang, not an answer).
    pub min_dt: f64,
    /// Length tolerance of the open–close tests (gap hysteresis, slip onset) as a fraction of
    /// the smallest free block's half size: 1e-10 is far above round-off in coordinates
    /// (~1e-16 of the model size) and far below any gap or slip a user could observe.
    pub gap_tolerance_ratio: f64,
    /// Deepest penetration a converged step may leave, as a fraction of the thinner block's
    /// 4·area/perimeter; beyond it the run stops with `SimError::PenaltyTooSoft`. At 5 % the
    /// overlap is visible in any drawing and the vertex–edge linearisation (vertex near its
    /// edge) degrades; the seeds' deliberately soft single-contact tests peak at ~2.5 %.
    pub max_penetration_ratio: f64,
}

impl Default for SimParams {
    fn default() -> Self {
        Self {
            contact: ContactParams::default(),
            open_close: OpenCloseParams::default(),
            solver: SolverParams::default(),
            dual: DualParams::default(),
            impact: ImpactParams::default(),
            shear_ratio: 0.4,
            max_cuts: 12,
            cut_factor: 0.3,
            growth: 1.1,
            penetration_ratio: 0.3,
            min_dt: 1e-9,
            gap_tolerance_ratio: 1e-10,
            max_penetration_ratio: 0.05,
        }
    }
}

/// The penalty stiffness to use, N/m: the scene's value, or for `"auto"` ten times the largest
/// Young's modulus (× 1 m of thickness), the upper end of Shi's recommended 1–10 E range:
/// stiff enough that penetration under self-weight is far below the displacements of interest.
pub fn resolve_penalty(scene: &Scene) -> f64 {
    match scene.control.penalty_stiffness {
        Penalty::Value(v) => v,
        Penalty::Auto => {
            let e = scene
                .materials
                .iter()
                .map(|m| m.young_modulus)
                .fold(0.0, f64::max);
            10.0 * e
        }
    }
}
