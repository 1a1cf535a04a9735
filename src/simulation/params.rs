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
    /// Floor of the cuts for a step whose open–close loop does not converge, as a fraction of
    /// `control.time_step`; `None` (the default): no floor, the loop's refusal cuts like any
    /// other down to `min_dt`. With a floor, such a step is cut no shorter than the floor, and
    /// at the floor it is taken with the loop's last iterate (if the displacement and
    /// penetration checks accept it), counted in `Stats::unconverged_taken`. Why: in a wall
    /// shaken to collapse (docs/contact-solve.md §24) the loop keeps failing at any Δt (the
    /// contacts of rocking panels open and close at once), so the cuts ratchet Δt down to
    /// 1e-8…1e-5 s, 100–1000× below the contact springs' period, where nothing is gained.
    /// 0.1 (measured in §24) is the tight reference's 0.1 ms at the default 1 ms.
    pub unconverged_floor_ratio: Option<f64>,
    /// Relative tolerance of "this step is at the floor" (Δt ≤ floor · (1 + tol)): a step cut
    /// to the floor is compared with the floor it was set to, or the product of cuts clamped
    /// to it, so only round-off separates them; 1e-9 is far above round-off (~1e-16) and far
    /// below any step a cut makes (a factor `cut_factor`).
    pub unconverged_floor_tolerance: f64,
    /// With `unconverged_floor_ratio`: the step after one taken unconverged at the floor starts
    /// at the floor (it grows back from there only once a step converges; also after a step
    /// the impact law's event location ended before the floor) instead of at the floor grown
    /// by `growth`, which fails again and is cut back to the floor (two loops run to their
    /// limit for one step). `false`: as after any step.
    pub unconverged_floor_hold: bool,
    /// With `unconverged_floor_ratio`: the bound on what an unconverged iterate taken at (or
    /// below) the floor may leave in any closed contact. Its depth may not exceed the deepest
    /// penetration a converged step of the run has left so far, nor the deepest contact closed
    /// at the step's start, nor this many elastic ranges δ = W/k_n of the contact (W the
    /// weight of the lighter free stone of the pair, N; k_n the normal spring, N/m; δ in m),
    /// whichever is deepest. Beyond it the iterate is refused and the step is cut below the
    /// floor (by `cut_factor`, as a non-converging step without a floor), where an iterate is
    /// again taken only within the bound. Why: the step checks bound a penetration's growth
    /// within a step (`penetration_ratio`), not its depth, so a run of taken iterates sank the
    /// colonnade's falling capital into a drum step by step to the contact search distance
    /// (docs/contact-solve.md §28), where converged steps' springs hold it. With the bound,
    /// taken iterates never leave a contact deeper than converged steps have. 2: the δ term
    /// only matters before any contact has carried load (a stone on one corner sinks by δ);
    /// infinite turns the bound off (session 38's floor).
    pub unconverged_floor_penetration: f64,
    /// With `unconverged_floor_ratio`: the open–close loop's iteration limit for a step at the
    /// floor (`None`: `OpenCloseParams::max_iterations`, as above the floor). A step at the
    /// floor that does not converge within it is taken there anyway (within the checks and the
    /// penetration bound above), so the iterations beyond it buy nothing when the loop does not
    /// converge at any Δt (docs/contact-solve.md §24, §26: ~20–30 solves a step at the floor).
    /// Below the floor, after the penetration bound refused an iterate, the loop runs to its
    /// full limit as without a floor.
    pub unconverged_floor_iterations: Option<usize>,
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
    /// edge) degrades; the deliberately soft single-contact tests of Li et al. 2018 (docs/verification.md) peak at ~2.5 %.
    pub max_penetration_ratio: f64,
    /// Impact location (adaptive runs only; off by default): the longest approach of a vertex onto an edge in
    /// the step where their contact closes, as a fraction of the smallest free block's half
    /// size; a longer one cuts the step (to this approach, at most by `cut_factor`). `None`:
    /// no impact location. See [`IMPACT_APPROACH_RATIO`].
    pub impact_approach_ratio: Option<f64>,
    /// Largest rotation increment of a free block in one step, rad (adaptive runs only): the
    /// step is shortened to it at the block's angular velocity. `None`: no bound.
    pub max_rotation_step: Option<f64>,
    /// Local error control (adaptive runs only): the Newmark step's local displacement error,
    /// estimated as |β − 1/6|·Δt²·|a₁ − a₀| at the vertices (Zienkiewicz & Xie 1991), is kept
    /// within this fraction of the smallest free block's half size; a step beyond twice the
    /// bound is redone shorter, and the next step is sized from the estimate. `None`: off.
    pub local_error_ratio: Option<f64>,
    /// The shortest step the local error control may ask for, as a fraction of
    /// `control.time_step` (it bounds the control's cost; impact location and the validity
    /// cuts may go shorter).
    pub min_error_step_ratio: f64,
    /// Rocking step control (adaptive runs only): while a free block rocks (it turned about one
    /// point, one closed contact, and its recent peak angular speed Ω is above
    /// `rocking_speed_floor`), Δt ≤ c·Ω/θ̈_g, θ̈_g gravity's angular acceleration about the
    /// pivot: gravity changes the block's angular velocity by at most this fraction of Ω in a
    /// step (never below `min_error_step_ratio` × `control.time_step`). Why: the DDA
    /// integrator's velocity update (γ = 1) errs by ½Δt·(θ̈(t) − θ̈(t₀)) since the last impact,
    /// so a half-cycle of length T ≈ Ω/θ̈ gains a rotation error ∝ Δt/T; the bound gives every
    /// half-cycle about 1/c steps (docs/accuracy-vs-speed.md, "Where the 1 ms error comes
    /// from"). `None`: off.
    pub rocking_velocity_change: Option<f64>,
    /// Angular speed, rad/s, below which the rocking step control leaves a block alone: 1e-3
    /// (a 1 m block's corner at 1 mm/s) is far above a resting block's spring vibration and
    /// below any rocking a user would observe.
    pub rocking_speed_floor: f64,
    /// Memory of the peak angular speed Ω of the rocking control, s: Ω decays as e^(−t/τ)
    /// unless the block turns faster. 0.25 s outlasts the short half-cycles (0.05–0.2 s) the
    /// control is for, so Ω at a half-cycle's peak (θ̇ = 0) is its start's speed.
    pub rocking_speed_memory: f64,
    /// DDA's rule (γ = 1, β = ½) takes the step's inertial ground load −m·ü_g at the step's
    /// end: v₁ = v₀ + Δt·a(t₁) is ahead of ∫a by ½Δt·ü̇_g, a first-order error that a record's
    /// rough acceleration makes the largest one. `true`: the load is ü_g's average over the
    /// step (the change of the ground's velocity / Δt), which makes the velocity update exact
    /// for the load and the step second order in it. The trapezoidal rule (γ = ½) averages
    /// itself and is left alone.
    pub average_ground_load: bool,
    /// With the trapezoidal rule and an impact law: the step right after an impact takes
    /// DDA's rule (β = ½, γ = 1), which does not read the stored acceleration a₀ that the
    /// impulse made stale. `false`: the trapezoidal rule averages the pre-impact a₀ into the
    /// step after the impact.
    pub restart_after_impact: bool,
    /// Newmark constants in place of the scene's integrator's (for studies of the integrator,
    /// examples/records_history `nm:γ`). `None`: the scene's `control.integrator`.
    pub newmark: Option<crate::assembly::Newmark>,
    /// The closing-contact limit on the next Δt (adaptive runs only; off by default).
    pub closing: ClosingParams,
}

/// A physical limit on the next step's length from the contacts that closed within the last
/// one (adaptive runs only): a vertex that approached its edge by `a` within a step of length
/// Δt closes at v = a/Δt; the next step is shortened to `elastic_fraction` · δ / v, with
/// δ = W/k_n the elastic range of the contact (the penetration of the normal spring under the
/// weight W of the lighter free stone of the pair; N, N/m → m). So no step lets a contact
/// close by more than that fraction of what its spring resolves: the small impacts between
/// stones (head joints closing and opening within a step, docs/contact-solve.md §13, §18, §22)
/// are taken in several steps instead of being undecided within one. The step is accepted as
/// it is (this is not a cut); the next ones grow back at `SimParams::growth`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ClosingParams {
    /// Largest approach of a closing contact within one step, as a fraction of its elastic
    /// range W/k_n. `None`: off (the default: opt-in until measured on every suite, §22).
    pub elastic_fraction: Option<f64>,
    /// The shortest step the limit may ask for, as a fraction of `control.time_step`: 0.1
    /// (0.1 ms at the default 1 ms) is the tight reference's Δt, at which the cycle rule's
    /// answer is within 1 % of it (§18); shorter steps would cost without a measured gain.
    pub min_step_ratio: f64,
}

impl Default for ClosingParams {
    fn default() -> Self {
        Self {
            elastic_fraction: None,
            min_step_ratio: 0.1,
        }
    }
}

/// A starting value for [`SimParams::impact_approach_ratio`] (off by default, see
/// [`SimParams::default`]). DDA's step ends with v₁ = 2d/Δt − v₀, so the velocity a closing
/// contact leaves depends on where within the step it closed: a vertex approaching at v that
/// closes a fraction τ into the step leaves with a normal velocity (2τ − 1)·v. Bounding the
/// approach of the closing step bounds the impact's timing error to approach / v; 1e-4 of the
/// half size is 63 µm for a 0.4 × 1.2 m column (a 0.4 m/s corner then closes in 0.16 ms).
pub const IMPACT_APPROACH_RATIO: f64 = 1e-4;

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
            // Off: the engine suites and golden digests were not run with a floor on (§24).
            unconverged_floor_ratio: None,
            unconverged_floor_tolerance: 1e-9,
            // On (it acts only with a floor): measured on the 105-stone wall under Northridge
            // 1.0 g (docs/contact-solve.md §26), 24 % fewer solves over the collapse window and,
            // over the whole record, the same verdict with 2,552 cuts instead of 8,064.
            unconverged_floor_hold: true,
            // Acts only with a floor; measured in docs/contact-solve.md §28.
            unconverged_floor_penetration: 2.0,
            // 10 (acts only with a floor), measured in docs/contact-solve.md §28 on the 105-stone
            // wall under Northridge: −39 % solves over §24's window against the loop's full 20,
            // the same verdicts at 0.8 and 1.0 g with −16 % / −31 % CPU.
            unconverged_floor_iterations: Some(10),
            gap_tolerance_ratio: 1e-10,
            max_penetration_ratio: 0.05,
            // Off: measured on Friuli (docs/accuracy-vs-speed.md, "Records"), locating impacts to
            // approaches of 3e-6…3e-4 of the half size changed the squat column's peak by −12 …
            // +12 % without converging; the impact's outcome is set by the spring contact after
            // closure, not by where in the step it closed.
            impact_approach_ratio: None,
            // Off: free rocking between impacts is integrated to within 1 % at the default
            // 1 ms (rocking-history benchmark); on Friuli bounds of 1e-4 and 3e-5 rad a step
            // (+16–116 % steps) did not bring the answers closer to the converged run.
            max_rotation_step: None,
            // Off: measured on the impact histories (tests/engine/rocking_impacts.rs) at 1e-6 it
            // resolves the penalty contact's impact over several short steps, where the springs
            // give energy back: five-impact history 11.4 % → 20.1 % of peak, stocky restitution
            // −5.3 % → +2.7 %; on the records' well-conditioned points it moves the answer
            // towards the engine at Δt = 1e-4 s, which is itself 4–13 % off Housner there
            // (docs/accuracy-vs-speed.md, "Records"). Worth turning on once the impact law is
            // the user's restitution rather than the springs' (docs/restitution.md).
            local_error_ratio: None,
            min_error_step_ratio: 0.05,
            // Off: measured on the records (docs/accuracy-vs-speed.md, "Where the 1 ms error
            // comes from"): at 0.005 it did not bring the default closer to Housner at the
            // well-conditioned points (already within 0.5 %), moved the ill-conditioned ones
            // either way (Friuli 0.5 g +6.0 → −42 %, 1.0 g −1.3 → −6.0 %; at 0.6 g the peak
            // +5.1 / −8.8 % at half-cycle 9 for c = 0.005 / 0.002, not converging), and took
            // 2.1× the steps over the 96 points (up to 9.4× at one).
            rocking_velocity_change: None,
            rocking_speed_floor: 1e-3,
            rocking_speed_memory: 0.25,
            // Off: measured on Friuli 0.6 g and the slender column under Kobe 0.4 g
            // (examples/records_history `avg`), it shifts the whole history by ½Δt and changes
            // no peak (0.07144 rad both ways): the load's timing is not the 1 ms error.
            average_ground_load: false,
            // On: the trapezoidal rule's impacts (tests/regression/regression_trapezoidal_impact.rs;
            // on the records, docs/accuracy-vs-speed.md "Why the trapezoidal rule gave −91 %").
            restart_after_impact: true,
            newmark: None,
            closing: ClosingParams::default(),
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
