//! Impacts with a user-given coefficient of restitution (`control.restitution`, docs/restitution.md).
//! Sits between `contact` and the step's assembly: after contact detection and linearization,
//! before the step is assembled, it changes the free blocks' velocities at the step start by
//! the impulses of the contacts that close within the step (Newton's law), so the step begins
//! after the impact, whatever the time step or the contact solver.
//!
//! Why a velocity-level law: the penalty springs (10 E) and the dual solver's rigid contact both
//! resolve an impact within one step or less at the default Δt, so the rebound they give is the
//! integrator's (measured 0.88 at 1 ms and 1.0 at 50 ms for two equal blocks, docs/restitution.md) and a
//! viscous dashpot sized from e (Li et al. 2018, Eq. for ζ(e)) would act only where the contact
//! period is resolved, ≥ 10 steps a contact. Moreau's impact law on velocities is exact for
//! rigid bodies at any Δt:
//!
//! - an *impacting* contact approaches (gap rate ġ < −`v_min`) and is at its impact: closed
//!   within the last step (`Contact::closed_within_last_step`; a contact closed for longer, a
//!   block settling on its springs, is the contact's own), or open and closing within
//!   the first `window` × Δt of the step (g0 + ġ·t + ½·g̈·t² = 0, g̈ from the blocks'
//!   accelerations at the step start);
//! - an impact later in the step ends the step at its instant, one within the next step
//!   splits the time to it into two equal steps ([`located_step`], the step is shortened,
//!   never refused): the impulse then acts at the configuration of the impact, not
//!   at the step start. Applied at the step start, a rocking column's impulse was taken a
//!   fraction of a step early, before the fall to the impact, and the height still to fall
//!   was lost in a second, slow landing: five impacts at Δt = 1 ms were 7.6–9.4 % of the
//!   peak off Housner's history (docs/restitution.md);
//! - contacts that land later within the step of an impact join it (one impulse set; each
//!   lands at the step's end, `ImpactParams::group_landings`): a rocking frame's two columns
//!   land a fraction of a step apart, and stopped one at a time they parted;
//! - the contacts involved are the impacting ones and every closed contact of the blocks they
//!   touch (e.g. the pivot a rocking column leaves), and of the free blocks joined to those by
//!   closed contacts (`ImpactParams::cluster`);
//! - normal impulses pₙ ≥ 0 and friction impulses |pₜ| ≤ tanφ·pₙ on the blocks' rigid-body
//!   unknowns (u0, v0, r0: the impact law is a rigid-body law; strain rates are kept) make
//!   ġ⁺ = −e·ġ⁻ at impacting contacts (ġ⁺ ≥ −e·ġ⁻ where pₙ = 0) and ġ⁺ ≥ min(ġ⁻, 0) at the
//!   closed ones, and stop slip (ṡ⁺ = 0) within the friction cone; projected Gauss–Seidel on
//!   this small set, then optionally a direct polish ([`ImpactParams::polish`]).
//!
//! The law is three calls, which `Simulation::impacts` makes in order: [`assemble_impacts`]
//! finds the impacts and writes their rows on the joined blocks' rigid-body velocities
//! ([`ImpulseProblem`]), `solve::impulse` solves them (the sweeps and the polish), and
//! [`apply_impulses`] writes the velocities after the impulses back. Why split: the impulse
//! solve is a solve, and its polish's sparse LU is faer's, which lives behind `solve`;
//! `assembly` sits before `solve` in the flow and cannot call it (docs/architecture.md).
//!
//! Momentum is conserved (the impulses act equal and opposite on the two blocks; fixed blocks
//! take the rest). Free blocks joined to the impact's blocks by closed contacts, transitively,
//! take impulses with their own mass (`ImpactParams::cluster`, default since session 40);
//! without it they took the rest without moving, which added energy
//! (docs/energy-after-record.md). A column landing on its other corner with e = 0 and no slip
//! keeps its angular momentum about that corner: Housner's r = 1 − 3/2 sin²α; with e > 0 the
//! corner bounces, r = 1 − 3/2 (1 + e) sin²α (tests/engine/restitution.rs derives both).
//! Units: velocities m/s and rad/s, impulses N·s (per metre of thickness).
use crate::assembly::{BlockState, Dofs};
use crate::contact::Contact;
use crate::geometry::{BlockGeometry, Vec6};
use nalgebra::{Matrix3, Vector3};

/// Knobs of the impact solve. Each default says why.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ImpactParams {
    /// Projected Gauss–Seidel sweeps at most: 200 bounds the cost of one impact. The sweeps
    /// seldom stop on [`tolerance`](Self::tolerance): session 42 found every solve of the
    /// pair law on 4-block impacts running all 200 (ending at 0.5–3e-7 of the landing speed on
    /// the stacks measured, far below what the step after them resolves), and
    /// joined stacks of 16 blocks or more stopping well above it; each solve's residual is
    /// reported (`solve::impulse::ImpulseReport`, `Stats::impact_unconverged`), and
    /// [`polish`](Self::polish) finishes the ones left above
    /// [`residual_tolerance`](Self::residual_tolerance).
    pub max_sweeps: usize,
    /// Stop when no impulse changes by more than this fraction of the largest impulse: 1e-12 is
    /// round-off for the velocities that follow.
    pub tolerance: f64,
    /// An approach slower than `slow_factor` × g × Δt is settling, not an impact (gravity gives
    /// g·Δt within one step to a contact that closes under load); 2 keeps resting contacts out.
    pub slow_factor: f64,
    /// Event location: an impact within the first `window` × Δt of the step is applied at the
    /// step start; a later one ends the step `margin` × Δt before its predicted instant, so
    /// that the next step finds it open and within its window. 0.01: the impulse then acts
    /// within 1 % of a step of the impact (the height a rocking column still has to fall, lost
    /// otherwise, is 1 % of a step's), at the cost of one short step an impact.
    pub window: f64,
    /// See `window`. 1e-4: the corner is left ≈ 1e-4·Δt·ġ above its edge (40 nm for a column
    /// landing at 0.4 m/s at 1 ms), a hover too short to matter (it falls in 0.1 ms), while the
    /// prediction (quadratic in t from the step-start acceleration) is good to ≈ 1e-8 m there.
    /// Ending the step at the predicted instant itself lets the contact close within it about
    /// half the time, and the contact then takes part of the impact (five-impact history
    /// 3.7–4.2 % of peak instead of 2.2–2.6 % with ½·`window`, docs/restitution.md).
    pub margin: f64,
    /// Contacts that land later within the step of an impact (open, approaching faster than
    /// the settling threshold, predicted to close within Δt) join that impact: one impulse set
    /// for all, each later contact given ġ⁺ = −2 g0/Δt so that it lands at the step's end, and
    /// no located step for them afterwards. Why: the two columns of a rocking frame land a
    /// fraction of a step apart (0.1–0.3 Δt under Loma Prieta 0.6 g); taken one at a time,
    /// each landing stopped one column while the cap and the other column flew on, every such
    /// impact left the columns' rotations further apart (1e-4 rad by 4.9 s), and the frame's
    /// one degree of freedom split: the columns parted by 0.11 rad and the peak was −28.6 %
    /// off Makris–Vassiliou's (docs/impacts-and-multiblock.md). `false` restores the old law
    /// (for diagnosis).
    pub group_landings: bool,
    /// An impact predicted within the next step splits the time to it into two equal steps
    /// ([`located_step`]); `false` runs the step whole and locates the impact from within its
    /// own step only (the law before the split, for diagnosis).
    pub split_before: bool,
    /// An impacting contact still open by g0 that does not bounce clear of it leaves at
    /// −2 g0/Δt and lands at the step's end (the hover closed, see `assemble_impacts`); `false`
    /// gives it −e ġ⁻ (for diagnosis).
    pub close_hover: bool,
    /// Location (the split step, the closed hover, grouped landings) only for impacts
    /// approaching faster than this × the settling threshold (`slow_factor` g Δt); slower ones
    /// take the impulse at the step start unlocated. 1: every impact is located. Not raised
    /// although 1.5 or 2 cuts the pile's open–close iterations by 13.5 % (its 24 landings at
    /// 1.0–1.2× the threshold): at 2 the rocking frame under Loma Prieta 0.6 g (dual) splits
    /// again (+48 % peak), at 1.5 the rocking colonnade's light-state test fails (peaks with and
    /// without the rule 14 % apart, bound 10 %) and the column example's golden digest moves
    /// (docs/pile.md, sessions 33–34). For diagnosis.
    pub locate_speed_ratio: f64,
    /// At an impact on a free block whose contacts are all with fixed or driven blocks (a
    /// column landing on its base), the block's pose is moved by a rigid displacement of order
    /// (its weight)/k, 5e-8 m for a slender column, so that the landing contacts start the step
    /// at the penetration the released ones had (the old pivot's spring force handed to the
    /// new corner) and the released ones at zero gap ([`hand_over_weight`]). Why: the penalty
    /// pivot stores (mg)²/2k; left to the springs, that energy moves from one corner to the
    /// other through a ringing of period 2π/√(2k/m), three steps of 1e-4 s, that the step
    /// damps: slow landings of micro-rocking lost 1.6 % more of θ̇ than Housner's law. The
    /// move swaps the stored energy between the springs (equal penetrations) and changes
    /// gravity's to second order in the rotation (≈ 4e-7 rad). It acts at impacts only: for
    /// landings slower than the settling threshold set `slow_factor` to 0 as well (then the
    /// slow landings' r is Housner's within 0.2 % at 1e-4 s), or give it its own threshold
    /// ([`hand_over_below`](Self::hand_over_below)). `true` (default) with `hand_over_below`
    /// `Some(2.0)`: the pair meets 86 of the records study's 90 targets and 88 of 88 robust
    /// verdicts (85 and 87 without it); alone, with `slow_factor` 0, it lost nine points
    /// (docs/accuracy-vs-speed.md, "Micro-rocking: the landing corner takes the weight
    /// (session 35)" and "The hand-over's threshold as the default (session 38)"). Penalty
    /// contact solver only ([`ImpactParams::without_hand_over`]).
    pub hand_over_weight: bool,
    /// Shortest located step, as a fraction of `control.time_step`: an impact predicted
    /// sooner than this (beyond the `window`) is not located; the step runs whole and the
    /// contact closes within it on its springs. 0 (default): every impact is located. Why a
    /// floor: location is global, so in a wall shaken to collapse, with hundreds of stones
    /// landing, the next impact somewhere is always near and every step ends before it
    /// (docs/contact-solve.md §24). Off by default: the engine suites were not run with it on.
    pub min_located_ratio: f64,
    /// With [`hand_over_weight`](Self::hand_over_weight): `Some(f)` gives the hand-over its
    /// own threshold. It then takes only *pivot landings* approaching slower than
    /// f × g × Δt (the nominal Δt when the step is cut): a contact with a fixed or driven
    /// block, on a free block whose contacts are all with fixed or driven blocks and one of
    /// which has been closed for more than a step and penetrates (a pivot carrying the
    /// weight). Those landings are impacts however slow (`slow_factor` 0 for them alone) and
    /// the block is moved; every other landing keeps `slow_factor` and no move. Why: with
    /// `slow_factor` 0 for every contact the records study lost nine points at Δt = 1 ms
    /// (session 35): every slow re-closing of a lone pivot's spring became an e = 0 impact,
    /// hundreds a run, draining large rocking; without it the slow landings of micro-rocking,
    /// which the hand-over is for, are not impacts. A corner re-closing with no other corner
    /// down is not a pivot landing. `None`: the session-35 law, the move at every impact of
    /// such a block, `slow_factor` for all. `Some(2.0)` (default): F = 2 is the settling
    /// threshold itself, so the hand-over takes exactly the pivot landings the springs would
    /// otherwise take; on the records study it meets 86 of 90 targets, every robust verdict
    /// (88 of 88) and 22 of 26 peaks, against 85, 87 and 21 with `None` (issue #20 §2's verdict
    /// target met). It loses one peak the old law met, column Friuli 0.5 g (+1.6 → −19.3 %), an
    /// ill-conditioned point: Housner's own peak moves +42.6 % / −28.6 % at 0.99 / 1.01 × the
    /// PGA, and the engine's is Housner's at +0.67 % PGA. F from 1 to 4 all lose it; 3 and 4
    /// flip verdicts, 1 keeps a +30 % miss. Measured in docs/accuracy-vs-speed.md, "The
    /// hand-over with its own threshold (session 37)" and "The hand-over's threshold as the
    /// default (session 38)".
    pub hand_over_below: Option<f64>,
    /// `true` (default since session 40): every free block joined to an impact's blocks
    /// through closed contacts (the whole stack a landing drum or architrave rests in,
    /// transitively; found by union–find, [`join_clusters`]) takes part in the impulse solve
    /// with its own mass. `false` (the law before session 40): only the blocks the impacting
    /// contacts touch take impulses; their closed contacts with other free blocks still act,
    /// but those blocks keep their velocities, i.e. they act as bodies of infinite mass
    /// moving at their velocity, and an e = 0 impact against one that moves towards the
    /// impacting block *adds* kinetic energy no other block pays for: +1 005 J in one step
    /// of the Doric colonnade after Northridge 0.4 g (architrave2 landing on c2_abacus while
    /// column c2 lifts it), impact steps adding 0.5–1.2 kJ each in 9 seconds of that record,
    /// and the colonnade toppled at 37 s with the ground still (docs/energy-after-record.md).
    /// With all connected blocks taking part and the fixed blocks at rest, the normal
    /// impulses are a projection onto a convex set that holds zero velocity (every target
    /// ≤ 0), and the kinetic energy cannot grow (friction's bounded impulses are outside this
    /// argument; measured: no impact step of the colonnade gained more than 91 J, the summed
    /// impact steps lost energy in every second of the record, and the colonnade stands).
    /// A single block has no free neighbour: its impacts are unchanged. Cost and suites:
    /// docs/energy-after-record.md, "The cluster as the default (session 40)".
    pub cluster: bool,
    /// With [`cluster`](Self::cluster): a component of blocks joined by closed contacts with
    /// more free blocks than this keeps the law before session 40 (only the blocks the
    /// impacting contacts touch take impulses). Why: the impulse solve is a projected
    /// Gauss–Seidel of at most [`max_sweeps`](Self::max_sweeps) sweeps, which converges over a
    /// stack of tens of blocks (the colonnade: 29) but not over a pile: with no cap, the
    /// 1685-block pile of `examples/pile.rs` joined the whole pile (~10,000 closed contacts) to
    /// each landing, the unconverged sweeps opened ~3,700 contacts in one step (9,865 → 6,156
    /// closed), and the run became a rain of located impacts: 280 steps simulated 0.0148 s
    /// instead of 0.2783 s, deepest penetration 3.1e-4 m instead of 8.0e-7 m, 37 s instead of
    /// 24 s (session 40, lead). 64: twice the largest stack the suites and bundled examples
    /// need (the colonnade, 29 free blocks). Above it the energy defect the cluster fixes is
    /// still possible (docs/energy-after-record.md). Not a size the sweeps are known to
    /// converge at: an aligned 8 × 8 stack (64, joined) takes 4 Δt cuts at a landing, 5 × 13
    /// (65, not joined) none, 30 with no cap (tests/regression/regression_impact_cluster_size.rs).
    /// With [`polish`](Self::polish) the joined solve converges on those stacks (no cut, the
    /// pair law's energy); the cap stays: the polish is opt-in and the pile was not measured
    /// with it in time (docs/energy-after-record.md, session 42).
    pub cluster_max_blocks: usize,
    /// When the projected Gauss–Seidel leaves a complementarity residual above
    /// [`residual_tolerance`](Self::residual_tolerance), finish the solve with a direct one
    /// (`polish`: an augmented-Lagrangian semismooth Newton on the joined blocks' rigid-body
    /// velocities, each Newton step a sparse LU of the 3n × 3n Jacobian), warm-started from the
    /// sweeps' impulses. Why: the sweeps carry an impulse one contact a sweep, and 200 sweeps
    /// left an 8 × 8 stack's e = 0 landing at 4.2e-3 J/m and 13 Δt cuts instead of at rest;
    /// polished, 4.1e-7 J/m and none, the pair law's level (docs/energy-after-record.md, "An
    /// impulse solve that converges (session 42)"). Only runs on a solve the sweeps leave above
    /// the tolerance. `false` (default): the engine suites were not run with it on; the
    /// counters (`Stats::impact_unconverged`) report the unconverged solves either way.
    pub polish: bool,
    /// Largest complementarity residual accepted as converged, as a fraction of the impact's
    /// speed scale (the largest |ġ| before the impulses or target among its rows): the natural
    /// map of each normal row, |min(pₙ·wₙ, ġ⁺ − target)|, and of each friction row,
    /// |pₜ − clamp(pₜ − ṡ⁺/wₜ, ±μpₙ)|·wₜ, both m/s. 1e-7: a landing at 1.4 m/s is stopped to
    /// 0.14 µm/s, a kinetic energy of 1e-10 J/m over 64 blocks of 200 kg/m, a thousandth of
    /// what the step after the impulses leaves anyway (1e-7–1e-6 J/m on the stacks,
    /// measured); the sweeps end the pair law's landings on those stacks at 0.5–3e-7 after
    /// their 200 sweeps (measured), so a tighter bound flags solves no one can tell apart.
    pub residual_tolerance: f64,
    /// The polish's penalty ρ on each row, as a multiple of that row's effective mass 1/w:
    /// the outer (multiplier) iterations contract as 1/(1 + ρ·λ) for the Delassus operator's
    /// smallest eigenvalue λ (relative to its diagonal), while the inner Newton's kinks sharpen
    /// with ρ. 1e4: at 1e6 and 1e8 the inner Newton did not end on any stack of 32 blocks or
    /// more; at 1e4 it ends on all (measured, docs/energy-after-record.md).
    pub polish_penalty: f64,
    /// Outer (multiplier) iterations of the polish at most; each runs up to
    /// `polish_newton_steps` Newton steps. Not converged after them: the solve is counted
    /// unconverged (`Stats::impact_unconverged`) and keeps whichever of the sweeps' and the
    /// polish's impulses has the smaller residual.
    pub polish_iterations: usize,
    /// Newton steps per outer iteration at most (each a sparse LU of the joined blocks' 3n
    /// unknowns); the piecewise-linear inner equations end when a full step keeps the active
    /// set or their velocity error is 1 % of the tolerance. 300: at 30 the 9- and 13-course
    /// stacks' first inner solve never ended and the polish gave up (measured).
    pub polish_newton_steps: usize,
}

impl ImpactParams {
    /// These knobs without the hand-over ([`hand_over_weight`](Self::hand_over_weight) and
    /// [`hand_over_below`](Self::hand_over_below) off): what the impact law runs with under the
    /// dual contact solver. Why: the hand-over moves the penalty pivot's stored spring force to
    /// the landing corner, and the dual solver stores none; and its resting corners re-close
    /// at approach rates below its own tolerance (all below 0.01 g Δt), which the own
    /// threshold's "impacts however slow" took for pivot landings: 15 644 impacts in 0.1 s on
    /// the resting slender column at Δt = 3e-6 s (tests/regression/
    /// regression_dual_tolerance_small_dt.rs; none with the hand-over off) and 5 of the dual
    /// engine subset's 22 tests off their bounds (docs/accuracy-vs-speed.md, session 38).
    pub fn without_hand_over(self) -> Self {
        Self {
            hand_over_weight: false,
            hand_over_below: None,
            ..self
        }
    }

    /// The hand-over's own threshold f (in g × Δt) when the hand-over is on and has one
    /// ([`hand_over_weight`](Self::hand_over_weight) and
    /// [`hand_over_below`](Self::hand_over_below) `Some(f)`), else `None`. Why one method: the
    /// pivot-landing test, the pivoted-block scan, the impact solve and the move all ask this
    /// same question and must agree.
    pub fn hand_over_threshold(&self) -> Option<f64> {
        self.hand_over_below.filter(|_| self.hand_over_weight)
    }
}

impl Default for ImpactParams {
    fn default() -> Self {
        Self {
            max_sweeps: 200,
            tolerance: 1e-12,
            slow_factor: 2.0,
            window: 0.01,
            margin: 1e-4,
            group_landings: true,
            split_before: true,
            close_hover: true,
            locate_speed_ratio: 1.0,
            hand_over_weight: true,
            min_located_ratio: 0.0,
            hand_over_below: Some(2.0),
            cluster: true,
            cluster_max_blocks: 64,
            polish: false,
            residual_tolerance: 1e-7,
            polish_penalty: 1e4,
            polish_iterations: 50,
            polish_newton_steps: 300,
        }
    }
}

/// What one block contributes to the impact solve.
pub struct ImpactInput<'a> {
    pub dofs: &'a Dofs,
    pub geoms: &'a [BlockGeometry],
    /// Per free block, kg/m³.
    pub densities: &'a [f64],
    /// Per block: velocity (vx, vy, ω) of blocks without unknowns (fixed: 0; driven: the
    /// ground's), m/s and rad/s.
    pub immobile_velocity: &'a [[f64; 3]],
    /// Per contact: tan φ of its joint.
    pub friction: &'a [f64],
    /// Per block: retired (takes no part in impacts).
    pub retired: &'a [bool],
    /// Coefficient of normal restitution, [0, 1].
    pub restitution: f64,
    /// The step about to be taken, s.
    pub dt: f64,
    /// The scene's time step (`control.time_step`), s: sets the settling threshold, so that a
    /// short step (an output instant, a located impact) does not turn settling into impacts.
    pub nominal_dt: f64,
    /// m/s², for the settling threshold.
    pub gravity: f64,
}

/// The impact law's per-contact results of one step, kept across steps so that its vectors
/// are reused. Filled by [`assemble_impacts`] and [`apply_impulses`], read by
/// [`located_step`].
#[derive(Debug, Default, Clone)]
pub struct ImpactScratch {
    /// Per contact: its impact time ([`impact_time`]) at the velocities after this step's
    /// impulses, s from the step start. Why kept: [`located_step`] needs every contact's impact
    /// time at those velocities, and the impulses change only the involved blocks'
    /// velocities, so only their contacts are evaluated again (the second pass over every
    /// contact was 5 % of a shaken step and 10 % of one at rest, docs/contact-solve.md §16).
    times: Vec<Option<f64>>,
    /// Per contact: whether it joined the impact from later in the step
    /// ([`ImpactParams::group_landings`]).
    landing: Vec<bool>,
    /// Per contact: whether it takes part in the impulse set.
    impacting: Vec<bool>,
    /// The impulse problem [`assemble_impacts`] writes for `solve::impulse`.
    problem: ImpulseProblem,
    /// [`hand_over_weight`]'s buffers and its moves.
    hand_over: HandOver,
    /// Per free block: it rests on a pivot carrying its weight, every contact with a fixed or
    /// driven block ([`ImpactParams::hand_over_below`]; empty when that is `None`).
    pivoted: Vec<bool>,
    /// Whether `pivoted` holds this step's flags ([`Pivoted`]).
    pivoted_ready: bool,
    /// Per contact: a pivot landing the hand-over takes ([`ImpactParams::hand_over_below`]).
    taken: Vec<bool>,
    /// [`join_clusters`]'s union–find: per free block, its parent (a root is its own).
    parent: Vec<usize>,
    /// [`join_clusters`]: per free block, whether it is the root of a component holding an
    /// impact's block.
    hit: Vec<bool>,
    /// [`join_clusters`]: per free block, the number of free blocks of its component if it is
    /// a root.
    size: Vec<usize>,
}

impl ImpactScratch {
    /// The rigid moves (free block index, (u0 m, v0 m, r0 rad)) the last [`hand_over_weight`]
    /// found.
    pub fn moves(&self) -> &[(usize, Vector3<f64>)] {
        &self.hand_over.moves
    }

    /// The impulse problem of the last [`assemble_impacts`], for `solve::impulse`, which
    /// leaves the impulses in its rows and the velocities after them in its `v`.
    pub fn problem_mut(&mut self) -> &mut ImpulseProblem {
        &mut self.problem
    }
}

/// Buffers of [`hand_over_weight`], kept across impacts.
#[derive(Debug, Default, Clone)]
struct HandOver {
    /// One block's gap and shear rows on its rigid-body unknowns, each with its Δg (m).
    rows: Vec<(Vector3<f64>, f64)>,
    /// Which of `rows` are the landing contacts' normal rows.
    landing: Vec<usize>,
    /// The Gram matrix of `rows` (column-major) and the solve's right-hand side.
    gram: Vec<f64>,
    dg: Vec<f64>,
    /// Per block moved: (free block index, (u0 m, v0 m, r0 rad)).
    moves: Vec<(usize, Vector3<f64>)>,
}

/// An impact's impulse problem, written by [`assemble_impacts`], solved by `solve::impulse`
/// (impulses into `rows`, velocities into `v`), read back by [`apply_impulses`]. Kept in
/// [`ImpactScratch`] so that its vectors are reused.
#[derive(Debug, Default, Clone)]
pub struct ImpulseProblem {
    /// The contacts in the solve: the impacting ones and the closed ones of the joined blocks.
    pub rows: Vec<ImpulseRow>,
    /// Per free block: inverse rigid-body mass about the centroid (zero if not involved).
    pub inv_mass: Vec<Matrix3<f64>>,
    /// Per free block: whether it takes impulses (an impacting contact touches it, or with
    /// [`ImpactParams::cluster`] it is joined to one that does).
    pub involved: Vec<bool>,
    /// Per free block: rigid-body velocity (u0, v0, r0; m/s, rad/s), before the impulses as
    /// written, after them once solved.
    pub v: Vec<Vector3<f64>>,
}

/// One contact in the impact solve: its rows on the two blocks' rigid-body unknowns.
#[derive(Debug, Clone)]
pub struct ImpulseRow {
    /// Free-block indices (None: fixed or driven).
    pub fi: Option<usize>,
    pub fj: Option<usize>,
    /// Normal and tangential rows on block i (vertex) and j (edge), rigid-body part
    /// ([`Contact::rows`], signed: ġ = n_fixed + ni·vᵢ + nj·vⱼ).
    pub ni: Vector3<f64>,
    pub nj: Vector3<f64>,
    pub ti: Vector3<f64>,
    pub tj: Vector3<f64>,
    /// Constant part of the rates from immobile blocks, m/s.
    pub n_fixed: f64,
    pub t_fixed: f64,
    /// Lowest allowed normal gap rate after the impact, m/s.
    pub target: f64,
    /// tan φ of the contact's joint.
    pub mu: f64,
    /// Inverse effective masses of the normal and tangential rows.
    pub wn: f64,
    pub wt: f64,
    /// Normal and tangential impulses, N·s.
    pub pn: f64,
    pub pt: f64,
}

impl ImpulseRow {
    /// The normal (`normal`) or tangential gap rate at the rigid-body velocities `v`, m/s.
    pub fn rate(&self, v: &[Vector3<f64>], normal: bool) -> f64 {
        let (gi, gj, c) = if normal {
            (&self.ni, &self.nj, self.n_fixed)
        } else {
            (&self.ti, &self.tj, self.t_fixed)
        };
        let mut rate = c;
        if let Some(f) = self.fi {
            rate += gi.dot(&v[f]);
        }
        if let Some(f) = self.fj {
            rate += gj.dot(&v[f]);
        }
        rate
    }

    /// Apply the impulse increment `dp` (N·s) of the normal or tangential row to `v`.
    pub fn push(&self, inv_mass: &[Matrix3<f64>], v: &mut [Vector3<f64>], dp: f64, normal: bool) {
        let (gi, gj) = if normal {
            (&self.ni, &self.nj)
        } else {
            (&self.ti, &self.tj)
        };
        if let Some(f) = self.fi {
            v[f] += inv_mass[f] * gi * dp;
        }
        if let Some(f) = self.fj {
            v[f] += inv_mass[f] * gj * dp;
        }
    }
}

fn rigid(v: &Vec6) -> Vector3<f64> {
    Vector3::new(v[0], v[1], v[2])
}

/// Whether contact `c` can take part in an impact: neither block retired, one of them free.
fn takes_part(input: &ImpactInput, c: &Contact) -> bool {
    let dofs = input.dofs;
    !input.retired[c.vertex_block]
        && !input.retired[c.edge_block]
        && (dofs.free_index[c.vertex_block].is_some() || dofs.free_index[c.edge_block].is_some())
}

/// Velocity (first three: rigid-body) and acceleration of block `b`, SI.
fn motion_of(input: &ImpactInput, b: usize, states: &[BlockState]) -> (Vec6, Vec6) {
    match input.dofs.free_index[b] {
        Some(f) => (states[f].vel, states[f].acc),
        None => {
            let v = input.immobile_velocity[b];
            (Vec6::new(v[0], v[1], v[2], 0.0, 0.0, 0.0), Vec6::zeros())
        }
    }
}

/// The approach speed (m/s) below which a contact is settling, not impacting:
/// `slow_factor` × g × Δt (the nominal Δt when the step is cut).
fn settling_speed(input: &ImpactInput, params: &ImpactParams) -> f64 {
    params.slow_factor * input.gravity.abs() * input.dt.max(input.nominal_dt)
}

/// Whether contact `c`, approaching at the normal gap rate `rate` (m/s), is a pivot landing the
/// hand-over takes ([`ImpactParams::hand_over_below`]): slower than its threshold, between a
/// fixed or driven block and a free one that rests on a weight-carrying pivot (`pivoted`).
/// The rate is tested before the block's flag, so that [`Pivoted`] scans the contacts only when
/// some contact approaches within the threshold.
fn pivot_landing(
    input: &ImpactInput,
    contacts: &[Contact],
    c: &Contact,
    rate: f64,
    params: &ImpactParams,
    pivoted: &mut Pivoted,
) -> bool {
    let Some(f) = params.hand_over_threshold() else {
        return false;
    };
    let Some(block) = lone_free_block(input, c) else {
        return false;
    };
    rate < 0.0
        && -rate < f * input.gravity.abs() * input.dt.max(input.nominal_dt)
        && pivoted.get(block, input, contacts, params)
}

/// [`find_pivoted`]'s flags, computed at their first use in a step's [`assemble_impacts`] or
/// [`apply_impulses`] (`ready` is kept in [`ImpactScratch`] between the two): only
/// [`pivot_landing`] reads them, for a contact approaching slower than the hand-over's
/// threshold, and on most steps none does (the two scans over every contact were +0.86 % of
/// the shaken 410-stone wall's instructions, where the hand-over never acts:
/// docs/contact-solve.md §29). The flags depend on the contacts' states and gaps, not on the
/// velocities the impulses change, so computing them later gives the same flags.
struct Pivoted<'v> {
    flags: &'v mut Vec<bool>,
    ready: &'v mut bool,
}

impl Pivoted<'_> {
    fn get(
        &mut self,
        block: usize,
        input: &ImpactInput,
        contacts: &[Contact],
        params: &ImpactParams,
    ) -> bool {
        if !*self.ready {
            find_pivoted(input, contacts, params, self.flags);
            *self.ready = true;
        }
        self.flags.get(block).copied().unwrap_or(false)
    }
}

/// Per free block, whether it rests on a pivot carrying its weight with every contact on a fixed
/// or driven block (a closed contact, closed for more than a step and penetrating): the blocks
/// whose landings [`ImpactParams::hand_over_below`] gives the hand-over. Left empty when that
/// knob is off.
fn find_pivoted(
    input: &ImpactInput,
    contacts: &[Contact],
    params: &ImpactParams,
    out: &mut Vec<bool>,
) {
    out.clear();
    if params.hand_over_threshold().is_none() {
        return;
    }
    out.resize(input.dofs.block_of.len(), false);
    // Two passes with no buffer: weight-carrying pivots first, then blocks touching another
    // free block are struck off.
    for c in contacts.iter().filter(|c| takes_part(input, c)) {
        if let Some(f) = lone_free_block(input, c) {
            if c.state.is_closed() && !c.closed_within_last_step && c.g0 < 0.0 {
                out[f] = true;
            }
        }
    }
    let free = &input.dofs.free_index;
    for c in contacts.iter().filter(|c| takes_part(input, c)) {
        if let (Some(a), Some(b)) = (free[c.vertex_block], free[c.edge_block]) {
            out[a] = false;
            out[b] = false;
        }
    }
}

/// The free block of a contact with a fixed or driven block (its free index), `None` when
/// both sides are free or neither is.
fn lone_free_block(input: &ImpactInput, c: &Contact) -> Option<usize> {
    let free = &input.dofs.free_index;
    match (free[c.vertex_block], free[c.edge_block]) {
        (Some(b), None) | (None, Some(b)) => Some(b),
        _ => None,
    }
}

/// Marks in `involved` (per free block) every free block joined to one already marked through
/// closed contacts between two free blocks that take part ([`ImpactParams::cluster`]),
/// transitively. Union–find with path halving over one pass of the contacts, then one pass over
/// the blocks: O(contacts + blocks) whatever the stack's depth. A component of more than
/// `max_blocks` free blocks is not joined ([`ImpactParams::cluster_max_blocks`]). `parent`,
/// `hit` and `size` are kept buffers (no allocation once grown).
fn join_clusters(
    input: &ImpactInput,
    contacts: &[Contact],
    involved: &mut [bool],
    (parent, hit, size): (&mut Vec<usize>, &mut Vec<bool>, &mut Vec<usize>),
    max_blocks: usize,
) {
    let n = involved.len();
    parent.clear();
    parent.extend(0..n);
    fn root(parent: &mut [usize], mut a: usize) -> usize {
        while parent[a] != a {
            parent[a] = parent[parent[a]];
            a = parent[a];
        }
        a
    }
    let free = &input.dofs.free_index;
    for c in contacts {
        if !c.state.is_closed() || !takes_part(input, c) {
            continue;
        }
        let (Some(fi), Some(fj)) = (free[c.vertex_block], free[c.edge_block]) else {
            continue;
        };
        let (ri, rj) = (root(parent, fi), root(parent, fj));
        if ri != rj {
            parent[ri] = rj;
        }
    }
    size.clear();
    size.resize(n, 0);
    for f in 0..n {
        let r = root(parent, f);
        size[r] += 1;
    }
    hit.clear();
    hit.resize(n, false);
    for f in 0..n {
        if involved[f] {
            let r = root(parent, f);
            // A component too large for the impulse solve keeps the pair law.
            hit[r] = size[r] <= max_blocks;
        }
    }
    for f in 0..n {
        if !involved[f] {
            let r = root(parent, f);
            involved[f] = hit[r];
        }
    }
}

/// Whether an impact approaching at the normal gap rate `rate` (m/s, negative closing) is
/// located (`ImpactParams::locate_speed_ratio`; at 1 or less every impact is).
fn fast_enough(rate: f64, input: &ImpactInput, params: &ImpactParams) -> bool {
    params.locate_speed_ratio <= 1.0
        || -rate > params.locate_speed_ratio * settling_speed(input, params)
}

/// Whether contact `c` approaches fast enough to be located (`ImpactParams::locate_speed_ratio`).
fn locatable(
    input: &ImpactInput,
    c: &Contact,
    states: &[BlockState],
    params: &ImpactParams,
) -> bool {
    if params.locate_speed_ratio <= 1.0 {
        return true;
    }
    let (vi, _) = motion_of(input, c.vertex_block, states);
    let (vj, _) = motion_of(input, c.edge_block, states);
    fast_enough(c.e_i.dot(&vi) - c.e_j.dot(&vj), input, params)
}

/// When contact `c` impacts, s from the step start: 0 for a contact closed within the last step
/// still approaching faster than `v_min`, the first root within two steps of g0 + ġ·t + ½·g̈·t² for an open one
/// approaching that fast, `None` otherwise (not approaching, settling, or not closing within
/// the step: an approach decelerating before contact has no root).
fn impact_time(
    input: &ImpactInput,
    contacts: &[Contact],
    c: &Contact,
    states: &[BlockState],
    params: &ImpactParams,
    pivoted: &mut Pivoted,
) -> Option<f64> {
    // Closed for longer than the last step: the contact's own (a block on its springs), never
    // an impact whatever its rate (tested first: most contacts of a wall are such).
    if c.state.is_closed() && !c.closed_within_last_step {
        return None;
    }
    if !takes_part(input, c) {
        return None;
    }
    let (vi, ai) = motion_of(input, c.vertex_block, states);
    let (vj, aj) = motion_of(input, c.edge_block, states);
    let rate = c.e_i.dot(&vi) - c.e_j.dot(&vj);
    // Not approaching faster than the settling speed: no impact, unless a pivot landing the
    // hand-over takes (an impact however slow; it needs `rate` < 0, and is tested only here, so
    // that most contacts never reach it).
    if rate >= -settling_speed(input, params)
        && (rate >= 0.0 || !pivot_landing(input, contacts, c, rate, params, pivoted))
    {
        return None;
    }
    if c.state.is_closed() {
        // Closed within the last step (the others returned above).
        return Some(0.0);
    }
    if c.g0 <= 0.0 {
        return Some(0.0);
    }
    let accel = c.e_i.dot(&ai) - c.e_j.dot(&aj);
    // ½·g̈·t² + ġ·t + g0 = 0, smaller positive root in the form stable for g̈ → 0.
    let disc = rate * rate - 2.0 * accel * c.g0;
    if disc < 0.0 {
        return None;
    }
    let t = 2.0 * c.g0 / (-rate + disc.sqrt());
    // Two steps ahead: see [`located_step`].
    (t <= 2.0 * input.dt).then_some(t)
}

/// The first impact after the window at the step start ([`ImpactParams::window`]), s from the
/// step start, if one falls within the next two steps, from the impact times `scratch` holds
/// (filled by [`assemble_impacts`] and [`apply_impulses`] for these contacts and states). Contacts flagged landing (they
/// joined this step's impact) are skipped: they land at the step's end.
fn next_impact(
    input: &ImpactInput,
    contacts: &[Contact],
    states: &[BlockState],
    params: &ImpactParams,
    scratch: &ImpactScratch,
) -> Option<f64> {
    let window = params.window * input.dt;
    contacts
        .iter()
        .zip(&scratch.times)
        .zip(&scratch.landing)
        .filter(|(_, &landing)| !landing)
        .filter(|((c, _), _)| locatable(input, c, states, params))
        .filter_map(|((_, &t), _)| t)
        .filter(|&t| t > window)
        .min_by(f64::total_cmp)
}

/// The step to take (s, at most `input.dt`) so that a step ends `margin` × Δt before the next
/// impact: an impact within this step ends it there; one within the next step splits the time
/// to it into two equal steps.
///
/// Why two equal steps: a step much shorter than the one before turns the closing of a closed
/// contact's gap (a rocking column's pivot lifts ½ r² h a step, r the rotation increment, from
/// the exact rotation against the linear contact condition) into a velocity 2 g0/t (the Newmark
/// rules give v⁺ = 2 d/t − v⁻): a step of 0.43 Δt before a landing at h/b = 3 left the pivot
/// approaching at 1e-3 m/s, which the impulse about the landing corner carried into ω⁺ (−0.08 to
/// −0.12 % of the ratio), and the dual solver's own step then reached the landing contact and
/// took part of the impact (−0.125 %). Split, the step before the impact is ≥ ½ Δt and as long
/// as the one before it.
///
/// `scratch` is the one [`assemble_impacts`] and [`apply_impulses`] filled for the same input,
/// contacts and (updated)
/// states.
pub fn located_step(
    input: &ImpactInput,
    contacts: &[Contact],
    states: &[BlockState],
    params: &ImpactParams,
    scratch: &ImpactScratch,
) -> f64 {
    debug_assert_eq!(scratch.times.len(), contacts.len());
    let dt = input.dt;
    let located = match next_impact(input, contacts, states, params, scratch) {
        Some(t) if t <= dt => t - params.margin * dt,
        Some(t) if t <= 2.0 * dt && params.split_before => 0.5 * (t - params.margin * dt),
        _ => dt,
    };
    if params.min_located_ratio > 0.0 && located < params.min_located_ratio * input.nominal_dt {
        dt
    } else {
        located
    }
}

/// Find the impacts of the step about to be taken at `states` (velocities at the step start)
/// and write their impulse problem into `scratch` ([`ImpactScratch::problem_mut`]). Returns the
/// number of impacting contacts; 0: there is nothing to solve, no velocity changes, and
/// `scratch` already holds what [`located_step`] needs. Otherwise solve the problem
/// (`solve::impulse`) and call [`apply_impulses`]. `scratch` is filled with, per contact,
/// whether it joined the impact from later in the step ([`ImpactParams::group_landings`]) and
/// its impact time at `states`.
pub fn assemble_impacts(
    input: &ImpactInput,
    contacts: &[Contact],
    states: &[BlockState],
    params: &ImpactParams,
    scratch: &mut ImpactScratch,
) -> usize {
    let dofs = input.dofs;
    let ImpactScratch {
        times,
        landing,
        impacting,
        problem:
            ImpulseProblem {
                rows,
                inv_mass,
                involved,
                v,
            },
        pivoted,
        pivoted_ready,
        taken,
        parent,
        hit,
        size,
        ..
    } = scratch;
    *pivoted_ready = false;
    let mut pivoted = Pivoted {
        flags: pivoted,
        ready: pivoted_ready,
    };
    landing.clear();
    landing.resize(contacts.len(), false);
    let velocity = |b: usize, states: &[BlockState]| -> Vec6 {
        match dofs.free_index[b] {
            Some(f) => states[f].vel,
            None => {
                let v = input.immobile_velocity[b];
                Vec6::new(v[0], v[1], v[2], 0.0, 0.0, 0.0)
            }
        }
    };
    let gap_rate = |c: &Contact, states: &[BlockState]| {
        c.e_i.dot(&velocity(c.vertex_block, states)) - c.e_j.dot(&velocity(c.edge_block, states))
    };
    let takes_part = |c: &Contact| takes_part(input, c);
    let window = params.window * input.dt;
    // Impacting contacts and the free blocks they touch.
    impacting.clear();
    impacting.resize(contacts.len(), false);
    involved.clear();
    involved.resize(dofs.block_of.len(), false);
    times.clear();
    times.extend(
        contacts
            .iter()
            .map(|c| impact_time(input, contacts, c, states, params, &mut pivoted)),
    );
    let any_now = times.iter().any(|t| t.is_some_and(|t| t <= window));
    for (k, c) in contacts.iter().enumerate() {
        let now = times[k].is_some_and(|t| t <= window);
        // A later landing within this step joins the impact (`ImpactParams::group_landings`).
        let later = any_now
            && params.group_landings
            && times[k].is_some_and(|t| t > window && t <= input.dt)
            && locatable(input, c, states, params);
        if now || later {
            impacting[k] = true;
            landing[k] = later;
            for b in [c.vertex_block, c.edge_block] {
                if let Some(f) = dofs.free_index[b] {
                    involved[f] = true;
                }
            }
        }
    }
    // With `ImpactParams::cluster`, the free blocks joined to them through closed contacts,
    // transitively: the connected components (over closed contacts between two free blocks)
    // that hold an involved block and have at most `cluster_max_blocks` free blocks, by
    // union–find in one pass over the contacts. Within the cap, the same set as session 39's
    // fixed point it replaced (rescan every contact until nothing grows: one pass per block of
    // depth, a wall's whole height for a landing in it); that copy was removed in session 41.
    let count = impacting.iter().filter(|&&i| i).count();
    if params.cluster && count > 0 {
        join_clusters(
            input,
            contacts,
            involved,
            (parent, hit, size),
            params.cluster_max_blocks,
        );
    }
    // The pivot landings among them, at their approach rates before the impulses: marked in
    // the row loop below, which computes those rates anyway.
    taken.clear();
    // As `find_pivoted` leaves its flags: empty when the knob is off or there is no block.
    let hand_over_on = params.hand_over_threshold().is_some() && !dofs.block_of.is_empty();
    if hand_over_on {
        taken.resize(contacts.len(), false);
    }
    if count == 0 {
        // No velocity changed: `times` already holds the impact times `located_step` needs.
        return 0;
    }
    let involved: &[bool] = involved;
    // Inverse rigid-body mass per involved free block (diagonal about the centroid).
    inv_mass.clear();
    inv_mass.extend((0..dofs.block_of.len()).map(|f| {
        if !involved[f] {
            return Matrix3::zeros();
        }
        let m = input.geoms[dofs.block_of[f]].mass_matrix(input.densities[f]);
        let rigid = m.fixed_view::<3, 3>(0, 0).clone_owned();
        rigid.try_inverse().unwrap_or_else(Matrix3::zeros)
    }));
    rows.clear();
    for (k, c) in contacts.iter().enumerate() {
        let free = |b: usize| dofs.free_index[b].filter(|&f| involved[f]);
        let (fi, fj) = (free(c.vertex_block), free(c.edge_block));
        let closed_here = c.state.is_closed() && takes_part(c) && (fi.is_some() || fj.is_some());
        if !impacting[k] && !closed_here {
            continue;
        }
        let rate = gap_rate(c, states);
        if impacting[k] && hand_over_on {
            taken[k] = pivot_landing(input, contacts, c, rate, params, &mut pivoted);
        }
        let target = if impacting[k] {
            // A contact still open by g0 (the step before ended `margin` × Δt ahead of the
            // impact) that does not bounce clear of it within the step lands at the step's
            // end with no normal velocity: d = −g0 = ġ⁺ Δt + ½ a Δt² and ġ_end = 2 d/Δt − ġ⁺
            // = 0 give ġ⁺ = −2 g0/Δt. Left at ġ⁺ = 0 (e = 0), the column hovered: it fell the
            // gap without the ground's torque and closed it at 2 g0/Δt (ratio +0.14 % at h/b
            // = 2, 1 ms; +0.6 % with a 2e-3 Δt margin).
            let bounce = -input.restitution * rate;
            let g0 = c.g0.max(0.0);
            let hover = params.close_hover && fast_enough(rate, input, params);
            if bounce * input.dt > g0 || !hover {
                bounce
            } else {
                -2.0 * g0 / input.dt
            }
        } else {
            rate.min(0.0)
        };
        // Rates of blocks not taking impulses (immobile, or free but not involved) are constant.
        let fixed_part = |grad_i: &Vec6, grad_j: &Vec6| {
            let mut r = 0.0;
            if fi.is_none() {
                r += grad_i.dot(&velocity(c.vertex_block, states));
            } else {
                // Strain rates are not changed by the impulses.
                r += grad_i
                    .rows(3, 3)
                    .dot(&velocity(c.vertex_block, states).rows(3, 3));
            }
            if fj.is_none() {
                r += grad_j.dot(&velocity(c.edge_block, states));
            } else {
                r += grad_j
                    .rows(3, 3)
                    .dot(&velocity(c.edge_block, states).rows(3, 3));
            }
            r
        };
        let [on_i, on_j] = c.rows();
        let ((ni, ti), (nj, tj)) = (on_i.rigid(), on_j.rigid());
        let w = |gi: &Vector3<f64>, gj: &Vector3<f64>| {
            let mut w = 0.0;
            if let Some(f) = fi {
                w += gi.dot(&(inv_mass[f] * gi));
            }
            if let Some(f) = fj {
                w += gj.dot(&(inv_mass[f] * gj));
            }
            w
        };
        rows.push(ImpulseRow {
            fi,
            fj,
            n_fixed: fixed_part(&on_i.normal, &on_j.normal),
            t_fixed: fixed_part(&on_i.shear, &on_j.shear),
            wn: w(&ni, &nj),
            wt: w(&ti, &tj),
            ni,
            nj,
            ti,
            tj,
            target,
            mu: input.friction[k],
            pn: 0.0,
            pt: 0.0,
        });
    }
    // Rigid-body velocities the impulses change, per free block.
    v.clear();
    v.extend(states.iter().map(|s| rigid(&s.vel)));
    count
}

/// Write the velocities after the impulses (`solve::impulse` left them in the problem of
/// [`assemble_impacts`]) into `states`, and evaluate again the impact times of the contacts
/// whose blocks took impulses; `scratch` is then ready for [`located_step`].
pub fn apply_impulses(
    input: &ImpactInput,
    contacts: &[Contact],
    states: &mut [BlockState],
    params: &ImpactParams,
    scratch: &mut ImpactScratch,
) {
    let dofs = input.dofs;
    let ImpactScratch {
        times,
        problem: ImpulseProblem { involved, v, .. },
        pivoted,
        pivoted_ready,
        ..
    } = scratch;
    // The flags of this step's `assemble_impacts`, if it computed them.
    let mut pivoted = Pivoted {
        flags: pivoted,
        ready: pivoted_ready,
    };
    for (f, st) in states.iter_mut().enumerate() {
        if involved[f] {
            st.vel[0] = v[f][0];
            st.vel[1] = v[f][1];
            st.vel[2] = v[f][2];
        }
    }
    // Only the involved blocks' velocities changed: the impact times of the contacts that touch
    // one are evaluated again, the others' are the same numbers.
    let touches_involved = |b: usize| dofs.free_index[b].is_some_and(|f| involved[f]);
    for (t, c) in times.iter_mut().zip(contacts) {
        if touches_involved(c.vertex_block) || touches_involved(c.edge_block) {
            *t = impact_time(input, contacts, c, states, params, &mut pivoted);
        }
    }
}

/// The rigid moves that hand the weight over at this step's impacts
/// ([`ImpactParams::hand_over_weight`]), from the `scratch` and velocities [`apply_impulses`]
/// left; read them with [`ImpactScratch::moves`]. Per involved free block whose contacts all
/// have a fixed or driven block on the other side: the *released* contacts (closed,
/// penetrating at the step start, not impacting, separating at the velocities after the
/// impulses) are brought to zero gap, the impacting ones take their summed penetration in
/// equal shares, every other closed or impacting contact of the block keeps its gap; the move
/// is the one of least kinetic metric (D = M⁻¹Gᵀ(GM⁻¹Gᵀ)⁻¹Δg on the rigid-body unknowns). A
/// block with no released contact, or whose gap rows are dependent (more than three
/// independent contacts), is left where it is. With [`ImpactParams::hand_over_below`] set, only
/// blocks with a pivot landing among their impacting contacts are moved.
pub fn hand_over_weight(
    input: &ImpactInput,
    contacts: &[Contact],
    states: &[BlockState],
    params: &ImpactParams,
    scratch: &mut ImpactScratch,
) {
    let dofs = input.dofs;
    let ImpactScratch {
        impacting,
        problem: ImpulseProblem { involved, .. },
        hand_over,
        taken,
        ..
    } = scratch;
    let own_threshold = params.hand_over_threshold().is_some();
    let HandOver {
        rows,
        landing,
        gram,
        dg,
        moves,
    } = hand_over;
    moves.clear();
    for (f, _) in involved.iter().enumerate().filter(|(_, &i)| i) {
        let b = dofs.block_of[f];
        // Per contact of the block: its row on the block's rigid unknowns, and Δg.
        rows.clear();
        landing.clear();
        let mut released = 0.0;
        let mut coupled = false;
        let mut takes = !own_threshold;
        for (k, c) in contacts.iter().enumerate() {
            let Some(on_b) = c.rows_on(b) else {
                continue;
            };
            let other = if c.vertex_block == b {
                c.edge_block
            } else {
                c.vertex_block
            };
            if !(c.state.is_closed() || impacting[k]) || !takes_part(input, c) {
                continue;
            }
            if dofs.free_index[other].is_some() {
                coupled = true;
                break;
            }
            let (normal, shear) = on_b.rigid();
            if impacting[k] {
                takes |= taken.get(k).copied().unwrap_or(false);
                landing.push(rows.len());
                rows.push((normal, 0.0));
                // The landing corner does not slide in the move: a shear increment of h·r0
                // (3e-7 m for the slender column) would load its shear spring with k·h·r0, six
                // times the block's weight.
                rows.push((shear, 0.0));
                continue;
            }
            let (vi, _) = motion_of(input, c.vertex_block, states);
            let (vj, _) = motion_of(input, c.edge_block, states);
            let rate = c.e_i.dot(&vi) - c.e_j.dot(&vj);
            if c.g0 < 0.0 && rate > 0.0 {
                released += -c.g0;
                rows.push((normal, -c.g0));
            } else {
                rows.push((normal, 0.0));
            }
        }
        if !takes || coupled || landing.is_empty() || released == 0.0 || rows.len() > 3 {
            continue;
        }
        let share = released / landing.len() as f64;
        for &r in landing.iter() {
            rows[r].1 = -share;
        }
        let m = input.geoms[b].mass_matrix(input.densities[f]);
        let Some(inv) = m.fixed_view::<3, 3>(0, 0).clone_owned().try_inverse() else {
            continue;
        };
        // G M⁻¹ Gᵀ column by column (nalgebra's order) in the kept buffer.
        let n = rows.len();
        gram.clear();
        gram.extend((0..n * n).map(|e| rows[e % n].0.dot(&(inv * rows[e / n].0))));
        let Some(ch) = nalgebra::DMatrix::from_vec(n, n, std::mem::take(gram)).cholesky() else {
            continue;
        };
        dg.clear();
        dg.extend(rows.iter().map(|r| r.1));
        ch.solve_mut(&mut nalgebra::DVectorViewMut::from_slice(dg, n));
        *gram = ch.unpack_dirty().data.into();
        let d = rows
            .iter()
            .zip(dg.iter())
            .fold(Vector3::zeros(), |acc, (r, &l)| acc + inv * r.0 * l);
        moves.push((f, d));
    }
}
