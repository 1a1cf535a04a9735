//! Shi's open–close iteration: assume contact states, solve, check the states against the
//! solution, repeat until no contact changes state. Called once per step attempt after
//! `BlockSystem::assemble_blocks`; on non-convergence the caller cuts the time step.
use super::anderson::FrictionAnderson;
use super::{LinearSolver, SolveError};
use crate::assembly::contact_springs::{
    add_contact_loads, add_contacts, constants, shear_limit, spring_key, JointLaw, Prescribed,
    SpringParams,
};
use crate::assembly::{BlockSystem, Dofs};
use crate::contact::{Contact, ContactState};
use crate::geometry::{Mat6, Vec6};

/// Tuning of the open–close loop.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct OpenCloseParams {
    /// Iterations before giving up on the step (the caller then cuts Δt). Shi uses 6; 8 lets
    /// friction transitions settle without needless cuts.
    pub max_iterations: usize,
    /// Relative change of a sliding contact's normal force below which its friction counts as
    /// converged: friction uses the normal force of the previous iteration, so the loop also
    /// iterates that fixed point (1e-4 keeps the friction error far below the 1 % benchmarks).
    pub friction_tolerance: f64,
    /// Relative hysteresis of the stick–slip transitions: a locked contact slips when its shear
    /// force exceeds the Coulomb limit by this fraction, a sliding one re-sticks when its slip
    /// reverses by this fraction of the elastic shear displacement at the limit. Without it a
    /// contact exactly at the limit flips on round-off and the loop never settles (see
    /// tests/regression/regression_contact_chatter.rs). 1e-6 is far below any physical resolution.
    pub hysteresis: f64,
    /// Iterations of plain friction fixed-point updates before relaxing them (3: enough for
    /// the common, contracting case to converge unrelaxed).
    pub relax_after: usize,
    /// State changes of one contact within a step after which a stick ⇄ slip cycle is
    /// resolved as sliding at the limit (4: two full cycles, so genuine transitions pass).
    pub max_flips: u32,
    /// Change of a releasing contact's kept fraction (`Contact::release_factor`) below which
    /// it counts as converged: 1e-3 of the released spring energy, far below the 1 % energy
    /// benchmarks.
    pub release_tolerance: f64,
    /// Force below which a sliding contact's friction update (its friction normal force moved,
    /// state and slip direction unchanged, the contact lightly loaded: `light_load`) does not
    /// ask for another solve, as a fraction of the largest contact normal force on the less
    /// loaded of its stones at the step start: the update is still taken, into the next
    /// iteration if there is one, else into the next step. Opening, closing, the onset of slip,
    /// re-sticking and slip reversal always iterate. 0 = every change iterates. Default 1e-3:
    /// far below the 1 % tolerances of the engine benchmarks, which all pass with it, and it cuts
    /// the solves of a shaken 410-stone wall from 6.7 to 1.8 a step (docs/contact-solve.md).
    pub force_tolerance: f64,
    /// Normal force, as a fraction of the same force scale, below which a contact counts as
    /// lightly loaded, the only kind whose friction updates `force_tolerance` may leave to the
    /// next iteration or step. 0.1: the shaken wall's head joints carry 0.1–100 N against
    /// 2–44 kN on the bed joints of their stones (below 0.05), a block's own base contacts
    /// carry its weight (order 1).
    pub light_load: f64,
    /// Update a sliding contact's friction normal force by a secant step on its own fixed-point
    /// map (from the last two updates) instead of plain or half-relaxed substitution; falls back
    /// to the relaxed update when the secant slope is not in (−10, 0.9). Off: on the shaken
    /// wall under the record it did not cut the iterations (4.98 solves a step against 4.58,
    /// docs/contact-solve.md), since the contacts still iterating there are coupled through
    /// their neighbours' stick–slip changes, which a per-contact secant does not see.
    pub secant_friction: bool,
    /// Differences of past iterates mixed by the Anderson acceleration of the sliding contacts'
    /// friction fixed point while no contact changes state (`solve::anderson`); 0 = off (plain
    /// substitution, relaxed after `relax_after`). Default 5: measured in docs/contact-solve.md
    /// §6 on the shaken wall under the record.
    pub anderson_depth: usize,
    /// Keep Anderson's history when contacts change state (the map changes a little; contacts
    /// that leave the sliding set are dropped from it, those that join enter with zero
    /// differences) instead of restarting it. Measured in docs/contact-solve.md §6.
    pub anderson_keep: bool,
    /// Force bound of the settle rule, as a fraction of the force scale of `force_tolerance`
    /// (the largest contact normal force on the contact's less loaded stone at the step start):
    /// from iteration `settle_after` on, a change of any kind (opening, closing, stick ⇄ slip,
    /// a friction update) whose misjudged force — k·|g| for an opening or closing, the excess
    /// over the Coulomb limit for the onset of slip, twice the limit for re-sticking or a slip
    /// reversal, μ·|ΔN| for a friction update — is at most this bound no longer asks for another
    /// solve. The change is still taken into the contact's state for the next step. Rocking
    /// corners of a shaken wall cycle between states whose forces differ by this little, which
    /// otherwise ends the step at `max_iterations` and cuts Δt (docs/contact-solve.md §8).
    /// 0 = off: every change iterates. Default 0 (off): with 0.1 at the iteration limit it takes
    /// the shaken 410-stone wall's cycling steps (7 cuts → 1), but two engine benchmarks then
    /// leave their tolerance (docs/contact-solve.md §8), so it is opt-in. 0.1 is the value to
    /// opt in with: the changes left at the iteration limit of that wall misjudge up to 1 kN
    /// against 2–44 kN a vertex on its stones (1e-2 takes almost none of those steps).
    pub settle_tolerance: f64,
    /// First iteration at which `settle_tolerance` applies (1-based). Before it every change
    /// iterates, so a step that converges within it is exactly the loop without the rule.
    /// Default 20 = `max_iterations`: the rule then only takes steps that would otherwise be cut
    /// (applied from iteration 2 it halves the solves of the shaken wall but fails four engine
    /// benchmarks, as the "every change" force tolerance did: docs/contact-solve.md §8).
    pub settle_after: usize,
    /// Let a *state* change of a lightly loaded contact (opening, closing, the onset of slip,
    /// re-sticking, a slip reversal) skip the solve as `force_tolerance` lets a friction update
    /// do: when the contact's normal force before and after is at most `light_load` × its force
    /// scale, the force the change misjudges (as `settle_tolerance` measures it) is at most
    /// `force_tolerance` × that scale, the contact is a head joint (`light_state_tilt`) and its
    /// whole interface is lightly loaded (`light_state_interface`). The change is still taken
    /// into the contact's state, for the next iteration if one follows, else for the next step.
    /// A contact that carries its stone (a block's base, a rocking pivot, a landing corner) or
    /// whose partner corner does (a rocking drum's bed joint, an arch's hinge) never qualifies,
    /// so the decisions of few-block structures and rocking stacks always iterate. Default on:
    /// it cuts the solves of the shaken 410-stone wall under the 1 m/s² 1 Hz sine from 1.78 to
    /// 1.49 a step (docs/contact-solve.md §11–§12) and every engine benchmark passes with it. The
    /// rule as first written (the contact's own load only, any orientation) made the bundled
    /// Doric colonnade collapse under Friuli at 0.3 g; with the interface check it stands with
    /// its peak within 0.6 % of the run without the rule (tests/engine/light_state_rocking.rs).
    pub light_state_changes: bool,
    /// Largest angle between a contact's normal and the horizontal, rad, at which
    /// `light_state_changes` may let its state change through. Default π/4: head (vertical)
    /// joints only, the same split as [`ChangeCounts`] and the rule's whole gain on shaken walls
    /// (π/2, any orientation, takes exactly the same changes there). Alone it is not a safe
    /// guard: an arch's joints near the crown are "head" joints by orientation, and without the
    /// interface check the bundled arch's peak under Friuli 0.3 g moved +11 %
    /// (docs/contact-solve.md §12); with it, π/4 and π/2 gave identical runs on every scene
    /// measured, so it is a margin.
    pub light_state_tilt: f64,
    /// Let `light_state_changes` through only when the contact's whole interface is lightly
    /// loaded: every contact between the same two blocks carries at most `light_load` × the
    /// force scale at the step start, in the solve and after it. A corner of a joint whose other
    /// corner carries the stone (a rocking drum's bed joint, an arch's hinging joint) then never
    /// qualifies, however little the corner itself carries (docs/contact-solve.md §12). Default
    /// on: without it the bundled colonnade collapses under Friuli 0.3 g; with it the rule
    /// takes the same changes on the shaken walls (head joints carry nothing at either corner).
    pub light_state_interface: bool,
    /// Block Gauss–Seidel sweeps of a local round (0 = off): after a global solve whose
    /// contact update asks for another one, the contact states are first re-decided locally,
    /// without a global solve. Each round re-assembles the system with the new states, relaxes
    /// the solution by this many sweeps of block Gauss–Seidel (each block's own equations with
    /// its neighbours frozen, the contact-level nonlinear Gauss–Seidel of LMGC90 on the penalty
    /// system) and updates the states and friction normal forces against it; rounds stop when no
    /// state changes or after `local_rounds`. The global solve that follows starts from those
    /// states, and the loop's convergence test is unchanged (a global solve whose states hold),
    /// so the answer is the same kind of fixed point. Default 0 (off): on the shaken 410-stone
    /// wall it cuts the solves under the record's strong part (5.43 → 4.22 a step at 30 sweeps)
    /// but not the Δt cuts, makes the sine worse (1.66 → 2.0) and costs more time than it saves
    /// as written (docs/contact-solve.md §13).
    pub local_sweeps: usize,
    /// Local rounds (see `local_sweeps`) between two global solves, at most. 4: a bound on
    /// their cost, not tuned (docs/contact-solve.md §13).
    pub local_rounds: usize,
    /// First global iteration after whose solve the local rounds run (1 = from the first, the
    /// variant measured in docs/contact-solve.md §13; 3 was worse on the sine, 2.48 solves a step).
    pub local_after: usize,
    /// Damp the open–close iteration as a semismooth Newton method with an exact line search:
    /// from the second solve on, the states are decided at the point of the segment from the
    /// last iterate to the new solution that minimises the step's incremental potential with
    /// the unilateral normal springs (shear springs and friction loads held as assembled), not
    /// at the new solution itself. Open ⇄ close cycles of coupled contacts are Newton overshoots
    /// on a convex piecewise-quadratic potential, which the line search removes. The loop's
    /// convergence test is unchanged (a global solve whose states hold, taken undamped).
    /// Default off: it damps rarely (mean step 0.97), saves 7 % of the solves over the whole
    /// record (2 cuts instead of 3) but costs as much time as it saves, and adds solves on the
    /// record's strong part (5.43 → 5.70 a step; docs/contact-solve.md §13).
    pub line_search: bool,
    /// Measure the force a re-sticking misjudges as the jump from the friction force the solve
    /// used (−dir·limit) to the force the locked spring carries at the same solution (−k_s·s),
    /// instead of bounding it by twice the Coulomb limit. A sliding contact's shear reference
    /// trails it by the elastic displacement at the limit, so a head joint whose slip just
    /// reverses re-sticks with a jump of k_s × the reversal, far below 2·limit; the light rule
    /// (`light_state_changes`) then compares that jump with its floor. Default off: a small gain
    /// (sine 1.66 → 1.62 solves a step, whole record 2.84 → 2.81), no change on the record's
    /// strong part, and the engine suites were not run with it (docs/contact-solve.md §13).
    pub restick_jump: bool,
    /// Force bound of the settle rule for loaded friction updates, as a fraction of the force
    /// scale of `force_tolerance`: from iteration `stone_settle_after` on, a friction update
    /// (state and slip direction unchanged, its friction normal force moved) whose misjudged
    /// force μ·|ΔN| is at most this bound no longer asks for another solve when both of the
    /// contact's stones are held by many contacts (`stone_settle_interfaces`); the update is
    /// still taken, for the next iteration or step. Unlike `force_tolerance` it also takes
    /// loaded contacts (the bed joints of a wall), which carry the stone, but only on a stone
    /// whose balance several loaded interfaces share, so that a misjudged friction of one of them
    /// is a small part of it. 0 = off. Default 1e-3 (the fraction of `force_tolerance`), from
    /// the first iteration, with `stone_settle_neighbours` and `stone_settle_supports`: on the
    /// shaken 410-stone wall it cuts the solves a step (sine 1.66 → 1.25, the record's strong
    /// part 5.43 → 4.36, the whole 20 s record 2.82 → 1.71 and −32 % user CPU) within the tight
    /// reference's bounds (sine 9.4e-12 m, record 2.73e-8 m = 1.6 %), and every engine suite,
    /// the regressions and the golden digests pass with it; the bundled colonnade's peak moves
    /// 2.1 % (its check allows 10 %) and the arch's not at all (docs/contact-solve.md §17). It
    /// does not remove the cuts (whole record 3 → 5, all at Δt ≥ 3e-4 s): those follow the
    /// head joints' state changes.
    pub stone_settle_friction: f64,
    /// Force bound, as the same fraction, of a *state* change (opening, closing, stick ⇄ slip,
    /// a slip reversal) of a lightly loaded head joint (the `light_state_changes` load and
    /// orientation tests, without its interface test) between two stones held by many contacts,
    /// taken without another solve from iteration `stone_settle_after` on. The light rule takes
    /// such changes below `force_tolerance`; the cut steps of §13 keep a few at 1–10× that.
    /// 0 = off. Default 0 (off): 1e-2 from the first iteration, with the friction rule and
    /// `stone_settle_neighbours`, takes the shaken 410-stone wall's strong part from 5.43 to 3.84
    /// solves a step (7 → 4 cuts), the sine from 1.66 to 1.15 and the whole record to 0 cuts,
    /// but moves the wall 3.8× further from the tight reference (7.0 % against 1.8 %,
    /// docs/contact-solve.md §17): undecided head joints at 1e-2 of the scale change the answer.
    pub stone_settle_state: f64,
    /// First iteration (1-based) of `stone_settle_friction` and `stone_settle_state`. Default 1:
    /// from the first iteration the rule acts as
    /// `force_tolerance` does on light contacts and pays in solves; at the iteration limit (20)
    /// it only takes steps that would otherwise be cut, and measured there it takes 551 updates
    /// on the strong part yet leaves all 7 cuts and raises the solves (5.43 → 5.63,
    /// docs/contact-solve.md §17).
    pub stone_settle_after: usize,
    /// Loaded interfaces a free stone needs for `stone_settle_friction` (and `_state`) to apply
    /// to its contacts: distinct neighbouring blocks whose interface carried, at the step start,
    /// a normal force of at least `light_load` × the stone's largest contact force. 3: a stone
    /// of a wall in running bond sits on two stones and carries one or two (3–4), a stone on
    /// the foundation sits on it and carries two (3), while a single block on its base (1), a
    /// drum of a column, a voussoir of an arch, a frame's column or beam (2 each) never qualify:
    /// there the one interface's friction is the block's shear balance (docs/contact-solve.md §8;
    /// the top course of a wall has 2 too: `stone_settle_neighbours`).
    pub stone_settle_interfaces: usize,
    /// Let a stone with fewer than `stone_settle_interfaces` loaded interfaces qualify too when
    /// one of its loaded interfaces is with a free stone that has them: the top course of a wall
    /// (sitting on two stones, carrying none) is part of the wall's web of contacts, while in a
    /// frame, a stack of drums or an arch no block has three loaded interfaces, so none
    /// qualifies either way. Default on: the sine's gain is the top course (1.66 solves a step
    /// without it, 1.25 with it; docs/contact-solve.md §17).
    pub stone_settle_neighbours: bool,
    /// Loaded supports a stone must rest on (bed joints below it, whose normal from the
    /// support into the stone is more than `light_state_tilt` above horizontal; a fixed block
    /// counts as all of them) for `stone_settle_interfaces` to let it qualify. 2: a stone of a
    /// running-bond wall rests on two stones or on the foundation, while the capital of a
    /// column carrying two architraves rests on one drum, so it is kept out although it has
    /// three loaded interfaces (it moved the bundled colonnade's peak by 28 %,
    /// docs/contact-solve.md §17), and with it the architraves loaded against it.
    pub stone_settle_supports: usize,
    /// When a stone carried no contact force at the step start (the first step of a scene
    /// dropped onto its springs), use its weight (mass × gravity, N) as its force scale instead
    /// of 0, against which no change is small. Default off: on the shaken 410-stone wall's
    /// first step it changes nothing (44 solves, 2 cuts either way), since the changes left at
    /// the iteration limit there misjudge mostly 2e-3–0.2 of a stone's weight
    /// (docs/contact-solve.md §17); and it would move the first step of every scene that starts
    /// without contact forces.
    pub weight_scale: bool,
    /// State changes of one contact within a step (`Contact::flips`) after which, when it
    /// closes from open, it closes *sliding* at the Coulomb limit (slip along its shear
    /// displacement) instead of locked; from iteration `cycle_after` on. A lightly loaded head
    /// joint of a shaken wall cycles open → locked → sliding → open: the locked shear spring it
    /// closes with pushes its stones apart again, while sliding at μ·N with N ≈ 0 does not.
    /// With `max_flips` keeping a cycling contact sliding, this is `max_flips`' answer ("both
    /// states are inconsistent; the consistent one is sliding at the limit with vanishing
    /// slip") extended to the closing. The loop's convergence test is unchanged (a solve whose
    /// states hold). 0 = off. Default 4 (two full cycles, as `max_flips`), from the first
    /// iteration (`cycle_after` 1), kept out of loaded interfaces (`cycle_light_interface`) and
    /// bed joints (`cycle_tilt`): on the settled 410-stone wall under the record it removes the
    /// Δt cuts (strong part 1 → 0, the whole 20 s record 5 → 0) within the tight reference's
    /// bound (0.47 %, as without it) for +0.9 % instructions (docs/contact-solve.md §25, §27),
    /// it takes nothing at rest or under the sine (bit-identical there), and every rule of the
    /// loop alone and all of them keep the rocking colonnade's verdict and peak within 10 % of
    /// the run without any (§27). Without the interface check it moved the incline benchmark
    /// and the colonnade (§25); on the unsettled wall at 1 ms it was 10 % from the reference
    /// (§18).
    pub cycle_flips: u32,
    /// First iteration (1-based) at which `cycle_flips` applies. `max_iterations` + 1 with
    /// `cycle_extra` > 0: the first `max_iterations` iterations are the loop without the rule,
    /// and a step that would be cut gets `cycle_extra` more iterations with it instead
    /// (docs/contact-solve.md §18). Default 1: the same answer on the settled wall as at the
    /// limit (0.47 % of the tight reference, §22, §25) at fewer solves.
    pub cycle_after: usize,
    /// Iterations allowed beyond `max_iterations` while `cycle_flips` is on: with `cycle_after`
    /// ≤ `max_iterations`, only in a step in which the rule closed a contact sliding (a step it
    /// took nothing in ends at `max_iterations`: docs/contact-solve.md §25); if the loop has still not converged after them the step is
    /// refused (Δt cut) as before. 10: a bound on the cost of a finished step, about half a cut
    /// step's 20 solves (docs/contact-solve.md §18).
    pub cycle_extra: usize,
    /// Let `cycle_flips` close a contact sliding only when its whole interface is lightly
    /// loaded: every contact between the same two blocks has carried at most `light_load` × the
    /// weight of the lighter free stone of the pair, at the step start and in every solve of the
    /// step so far (the interface check of `light_state_interface`, against the weight: the
    /// step-start force scale is 0 on a dropped scene's first step). A wall's head joint (both
    /// corners carry 0.1–100 N against kN) qualifies; a block's base on an incline, a rocking
    /// drum's bed joint (its pivot corner carries the column above) or an architrave landing on
    /// its capital never does: there the closing decides the stone's own balance, and a corner
    /// closed at the Coulomb limit instead of on its shear spring moves the answer (without this
    /// check the bundled colonnade under Friuli 0.3 g slid 8.48 cm against 5.49 cm and the
    /// incline benchmark left its regression bound, docs/contact-solve.md §25). Default on.
    pub cycle_light_interface: bool,
    /// Largest angle between a contact's normal and the horizontal, rad, at which `cycle_flips`
    /// may close it sliding; a cycling contact of a steeper joint closes locked as without the
    /// rule (counted in `ChangeCounts::cycle_kept_locked`). Default π/4: head (vertical) joints
    /// only, the light rule's split (`light_state_tilt`). The interface check alone does not
    /// keep the rule off a rocking stack's bed joints: in the bundled colonnade under Friuli
    /// 0.3 g, 70–90 % of its closings were bed joints of drums, capitals and abaci whose whole
    /// interface carried under 0.1 of the lighter stone's weight for a step (a stack above
    /// bouncing on its landing), and with the light rule off that moved the peak +32 %; head
    /// joints only, the shaken walls' closings are all taken as before (docs/contact-solve.md
    /// §27). π/2: any orientation (session 37's rule).
    pub cycle_tilt: f64,
    /// Predict a sliding contact's friction normal force at the step start from the last two
    /// steps' converged normal forces, N₁ (the last step's) and N₀ (the one before):
    /// N = max(0, N₁ + g·(N₁ − N₀)) with g this gain (1 = linear extrapolation, 0 = the last
    /// solve's normal force), instead of the friction normal force the last step ended with.
    /// Only the loop's starting guess moves: its convergence test and every tolerance are
    /// unchanged, so a converged step is the same kind of fixed point. A contact not closed at
    /// both step starts keeps today's start. The gain assumes equal steps (Δt is not read).
    /// Applied only to contacts whose stones the stone settle rule takes
    /// (`stone_settle_interfaces`, `stone_settle_supports`, `stone_settle_neighbours`: the
    /// stones of a wall; never a single block's base, a column's drums or an arch), so it acts
    /// only with that rule on. Applied to every sliding contact it moved the sliding-stack
    /// benchmark beyond its regression bound and the rocking colonnade's chaotic run
    /// (docs/contact-solve.md §30). `None` = off. Default `Some(1.0)` (session 40): on the
    /// shaken 410-stone wall g = 1 cuts the solves a step of the record's strong part from
    /// 2.77 to 2.35 and of the whole 20 s record from 1.72 to 1.60 (0 cuts, 0.48 % of the tight
    /// reference's displacement against 0.47 %; the bound is §25's 3 %), and every engine
    /// benchmark keeps its tolerance with it. Before the energy-safe impact law
    /// (`ImpactParams::cluster`) was the default, the colonnade run with the stone and cycle
    /// rules without the light rule left its 10 % bound with it (+13 %, §30); with the cluster it
    /// passes. g = 1 rather than the scan's best 1.2 (2.23 solves): linear extrapolation has a
    /// reason, 1.2 would be fitted to one scene.
    pub friction_predict: Option<f64>,
    /// Predict a sliding contact's re-sticking at the step start: its slip over this step is
    /// extrapolated from the last two steps' converged slips σ₁ (the last step's) and σ₀ (the
    /// one before), σ = σ₁ + g·(σ₁ − σ₀) with g this gain (1 = linear extrapolation), and when
    /// σ reverses against the slip direction by more than the loop's own re-sticking threshold
    /// (hysteresis × limit / k_s + the length tolerance: the test `update_state` applies to a
    /// solve's slip) the loop starts the contact locked instead of sliding. Only the loop's
    /// starting guess moves, as for `friction_predict`: the convergence test and every tolerance
    /// are unchanged, so a converged step is the same kind of fixed point (a wrong guess costs
    /// the onset of slip the loop then finds, as a wrong "sliding" costs the re-sticking today).
    /// Applied where `friction_predict` is (the stones the stone settle rule takes), on the
    /// loop's first attempt of a step (a retry after a cut starts where the refused attempt
    /// ended). The gain assumes equal steps (Δt is not read). `None` = off. Default `Some(1.0)`
    /// (session 41, with `slip_predict`): on the shaken 410-stone wall the two take the record's
    /// strong part from 2.35 to 1.96 solves a step (re-sticking alone 2.05; the head joints'
    /// re-stickings after the first solve 920 → 365), the whole 20 s record from 1.60 to 1.53,
    /// the 1 Hz sine from 1.22 to 1.14, 0 cuts, within §25's bound of the tight reference, and
    /// every engine benchmark keeps its tolerance (docs/contact-solve.md §32). g = 1 for the
    /// reason of `friction_predict` (linear extrapolation); 0.5 and 2 were measured worse.
    pub stick_predict: Option<f64>,
    /// The same extrapolated slip for a locked contact: when the shear spring would carry more
    /// than the loop's slip threshold at the end of the step (|k_s·(s₀ + σ)| > limit·(1 + h) +
    /// k_s·tolerance, the test `update_state` applies), the loop starts it sliding in the
    /// direction of s₀ + σ, its friction normal force predicted as a sliding contact's
    /// (`friction_predict`) or else the last step's. Same restrictions as `stick_predict`, and
    /// bed joints only (normal more than `light_state_tilt` above horizontal): on every joint
    /// it took the strong part from 2.05 to 2.34 solves a step (head joints started sliding
    /// re-stick and slip again later). `None` = off. Default `Some(1.0)` (session 41, with
    /// `stick_predict`: 2.05 → 1.96 on the strong part, 1.56 → 1.53 over the whole record,
    /// docs/contact-solve.md §32).
    pub slip_predict: Option<f64>,
    /// Predict a head joint's opening or closing at the step start: its gap change over this
    /// step is extrapolated from the last two steps' converged gap changes Δ₁ (the last
    /// step's) and Δ₀ (the one before), Δ = Δ₁ + g·(Δ₁ − Δ₀) with g this gain (0 = the gap
    /// itself extrapolated linearly from the last two step ends, 1 = its change extrapolated
    /// linearly, as `stick_predict` does the slip), and the loop's own test is applied to the
    /// predicted gap g₀ + Δ (m): a closed joint whose predicted gap exceeds the opening
    /// threshold (tensile allowance + length tolerance) starts the loop open, an open one
    /// whose predicted gap is below −length tolerance starts it closed (locked). Only the
    /// loop's starting guess moves, the convergence test and every tolerance are unchanged.
    /// Same restrictions as `stick_predict` (the stones the stone settle rule takes, the
    /// step's first attempt), and head joints only (normal within `light_state_tilt` of
    /// horizontal): the head joints' openings and closings are what the first solve still
    /// finds on the shaken wall (docs/contact-solve.md §32, §33). The gain assumes equal
    /// steps. `None` = off. Default `Some(0.0)` (session 41, §33): on the shaken 410-stone
    /// wall g = 0 takes the whole 20 s record from 1.53 to 1.41 solves a step (#21's ≤ 1.5) and
    /// the 1620-stone wall's strong part from 3.68 to 3.63, where g = 1 made the latter 3.93
    /// with one more cut; 0 is the gap extrapolated linearly from the last two step ends,
    /// which needs no assumption on how its change varies.
    pub gap_predict: Option<f64>,
    /// Predict a locked **head** joint's onset of slip at the step start (`slip_predict` does
    /// bed joints): the slip over the step is extrapolated as `slip_predict` does it,
    /// σ = σ₁ + g·(σ₁ − σ₀) with g this gain, and the joint starts the loop sliding in the
    /// direction of s₀ + σ when its gap is predicted to stay closed (the `gap_predict`
    /// extrapolation, its gain or 0 when that rule is off) and the spring would carry more than
    /// the loop's slip threshold against the Coulomb limit of the predicted normal force
    /// (−k_n × the predicted gap). Same restrictions as `slip_predict` (the stones the stone
    /// settle rule takes, the step's first attempt, only the starting guess moves).
    /// `None` = off. Default off (session 42, docs/contact-solve.md §34): g = 1 takes the
    /// shaken 410-stone wall's record strong part from 1.92 to 1.85 solves a step, the whole
    /// 20 s record from 1.41 to 1.39 and the 1 Hz sine from 1.12 to 1.10, but the 3 m/s² 2 Hz
    /// sine from 3.00 to 3.42 and the 1620-stone wall from 3.63 (0 cuts) to 3.89 (2 cuts): a
    /// joint started sliding holds at the first solve and sheds its shear onto its neighbours,
    /// which then slip or re-stick. The limit of the *last* normal force (§32's test on every
    /// joint) was worse (strong part 2.29): it starts sliding twice as many joints that stay
    /// locked.
    pub head_slip_predict: Option<f64>,
    /// Factor on the Coulomb limit in `head_slip_predict`'s test: a locked head joint is
    /// started sliding only when |k_s·(s₀ + σ)| > margin·limit·(1 + h) + k_s·tolerance.
    /// 1 = the loop's own onset test. Only read with `head_slip_predict` on. Default 1 (§34's
    /// rule). Measured (docs/contact-solve.md §36, 410-stone wall, g = 1): 1.1 keeps the
    /// 3 m/s² sine at 3.00 solves a step (3.42 at 1) and takes the whole 20 s record to 1.38
    /// (1.41 with the rule off), but the 1620-stone wall keeps 2 cuts (3.72 solves a step
    /// against 3.63 and 0 cuts off), so the rule stays off.
    pub head_slip_margin: f64,
    /// Keep `head_slip_predict` off a joint whose last two slips (σ₁, σ₀) have opposite signs:
    /// its shear reverses (the stones rock), which a linear extrapolation cannot see coming.
    /// Default off: with it the 3 m/s² sine stays at 3.42 solves a step and the 1620-stone wall
    /// keeps its 2 cuts (§36): under that sine 336 of the 341 onsets the rule would predict
    /// have no reversal.
    pub head_slip_steady: bool,
    /// Keep `head_slip_predict` off a joint whose shear displacement changed sign over the last
    /// step (s₀ and s₀ − σ₁ of opposite signs). Default off: the 3 m/s² sine stays at 3.42
    /// solves a step, the 1620-stone wall keeps its 2 cuts (§36).
    pub head_slip_shear_sign: bool,
    /// Keep `head_slip_predict` off a joint one of whose stones' rotation rate changed sign
    /// between the last two step ends (the stone rocks; `Simulation` keeps the rates). Default
    /// off: the record's strong part 1.85 → 1.82 solves a step, but the 3 m/s² sine stays at
    /// 3.42 (§36).
    pub head_slip_spin: bool,
    /// Keep `head_slip_predict` off a joint whose state changed within the last step's loop
    /// (`Contact::flips` > 0 at the step start: it slipped and re-stuck, or closed): a joint
    /// that cycled, or that the rule started sliding and the loop re-locked, is left to the
    /// loop. Default off: the 3 m/s² sine 3.42 → 3.44 solves a step (§36).
    pub head_slip_calm: bool,
}

impl Default for OpenCloseParams {
    fn default() -> Self {
        Self {
            max_iterations: 20,
            friction_tolerance: 1e-4,
            hysteresis: 1e-6,
            relax_after: 3,
            max_flips: 4,
            release_tolerance: 1e-3,
            force_tolerance: 1e-3,
            light_load: 0.1,
            secant_friction: false,
            anderson_depth: 5,
            anderson_keep: true,
            settle_tolerance: 0.0,
            settle_after: 20,
            light_state_changes: true,
            light_state_tilt: std::f64::consts::FRAC_PI_4,
            light_state_interface: true,
            local_sweeps: 0,
            local_rounds: 4,
            local_after: 1,
            line_search: false,
            restick_jump: false,
            stone_settle_friction: 1e-3,
            stone_settle_state: 0.0,
            stone_settle_after: 1,
            stone_settle_interfaces: 3,
            stone_settle_neighbours: true,
            stone_settle_supports: 2,
            weight_scale: false,
            cycle_flips: 4,
            cycle_after: 1,
            cycle_extra: 10,
            cycle_light_interface: true,
            cycle_tilt: std::f64::consts::FRAC_PI_4,
            friction_predict: Some(1.0),
            stick_predict: Some(1.0),
            slip_predict: Some(1.0),
            gap_predict: Some(0.0),
            head_slip_predict: None,
            head_slip_margin: 1.0,
            head_slip_steady: false,
            head_slip_shear_sign: false,
            head_slip_spin: false,
            head_slip_calm: false,
        }
    }
}

/// The stick–slip prediction at a step start (`OpenCloseParams::stick_predict`,
/// `slip_predict`): call once per step, before its first open–close loop, after the contacts
/// are linearized (a locked contact's test reads its step-start shear displacement `s0`).
/// Sets `Contact::predicted_state` of a sliding contact predicted to re-stick (`Locked`) or a
/// locked one predicted to slip (`Sliding`), from the slips of the last two accepted steps;
/// clears it everywhere else. `iterate` starts from it where the rule applies.
/// `spin_reversed` (per block, may be empty) tells whether a block's rotation rate changed sign
/// between the last two step ends (`OpenCloseParams::head_slip_spin`).
pub fn predict_stick_slip(
    contacts: &mut [Contact],
    laws: &[JointLaw],
    springs: &SpringParams,
    params: &OpenCloseParams,
    spin_reversed: &[bool],
) {
    let h = params.hysteresis;
    for (c, law) in contacts.iter_mut().zip(laws) {
        c.predicted_state = None;
        let (Some(s1), Some(s0)) = (c.last_slip, c.prior_slip) else {
            continue;
        };
        let limit = shear_limit(c, law, c.normal_force);
        match (c.state, params.stick_predict, params.slip_predict) {
            (ContactState::Sliding { dir }, Some(g), _) => {
                let slip = s1 + g * (s1 - s0);
                // `update_state`'s re-sticking test, on the predicted slip.
                if limit > 0.0 && resticks(slip, dir, limit, h, springs) {
                    c.predicted_state = Some(ContactState::Locked);
                }
            }
            // Bed joints only (normal more than `light_state_tilt` above horizontal): on the
            // head joints too it added more re-stickings and later onsets than it removed.
            (ContactState::Locked, _, Some(g)) if !params.head_by_tilt(&c.n) => {
                let s = c.s0 + s1 + g * (s1 - s0);
                // `update_state`'s onset-of-slip test, on the predicted shear displacement.
                if slips(springs.shear * s, limit, h, springs) {
                    c.predicted_state = Some(ContactState::Sliding { dir: s.signum() });
                }
            }
            // Head joints (`head_slip_predict`): against the limit of the predicted normal
            // force, when the gap is predicted to stay closed.
            (ContactState::Locked, _, _) if params.head_by_tilt(&c.n) => {
                let Some(g) = params.head_slip_predict else {
                    continue;
                };
                if head_slip_guarded(c, s1, s0, params, spin_reversed) {
                    continue;
                }
                let Some(limit) = head_onset_limit(c, law, springs, params) else {
                    continue;
                };
                let s = c.s0 + s1 + g * (s1 - s0);
                if slips(
                    springs.shear * s,
                    params.head_slip_margin * limit,
                    h,
                    springs,
                ) {
                    c.predicted_state = Some(ContactState::Sliding { dir: s.signum() });
                }
            }
            _ => {}
        }
    }
}

/// Whether one of the rocking guards of `head_slip_predict` keeps the rule off a head joint
/// with last slips `s1`, `s0` (m): its slip reversed (`head_slip_steady`), its shear
/// displacement changed sign (`head_slip_shear_sign`), a stone's rotation rate did
/// (`head_slip_spin`), or its state changed in the last step's loop (`head_slip_calm`).
fn head_slip_guarded(
    c: &Contact,
    s1: f64,
    s0: f64,
    params: &OpenCloseParams,
    spin_reversed: &[bool],
) -> bool {
    let spun = |b: usize| spin_reversed.get(b).copied().unwrap_or(false);
    (params.head_slip_calm && c.flips > 0)
        || (params.head_slip_steady && s1 * s0 < 0.0)
        || (params.head_slip_shear_sign && c.s0 * (c.s0 - s1) < 0.0)
        || (params.head_slip_spin && (spun(c.vertex_block) || spun(c.edge_block)))
}

/// The gap a contact is predicted to end this step with (`gap_predict`'s extrapolation at
/// gain `gain`), m, if it has the history of the last two steps.
fn predicted_gap(c: &Contact, gain: f64) -> Option<f64> {
    let (Some(d1), Some(d0)) = (c.last_gap_change, c.prior_gap_change) else {
        return None;
    };
    Some(c.g0 + d1 + gain * (d1 - d0))
}

/// A closed contact's opening threshold (`update_state`'s): the bond's tensile allowance (a
/// bonded joint holds tension up to its tensile strength) plus the length tolerance, m.
fn opening_gap(c: &Contact, law: &JointLaw, springs: &SpringParams) -> f64 {
    let allowance = if c.bonded {
        law.tensile_strength * c.length / springs.normal
    } else {
        0.0
    };
    allowance + springs.gap_tolerance
}

/// `update_state`'s onset-of-slip test: a locked spring carrying the shear force `shear` (N,
/// either sign) slips when it exceeds the Coulomb `limit` by the hysteresis `h` and by the
/// length tolerance's force too (joints with no normal load, limit ≈ 0, would otherwise slip
/// on round-off shear).
fn slips(shear: f64, limit: f64, h: f64, springs: &SpringParams) -> bool {
    shear.abs() > limit * (1.0 + h) + springs.shear * springs.gap_tolerance
}

/// `update_state`'s re-sticking test: a contact sliding in direction `dir` (±1) re-sticks
/// when its slip `slip` (m) runs back against `dir` by more than the hysteresis' elastic
/// slip and the length tolerance.
fn resticks(slip: f64, dir: f64, limit: f64, h: f64, springs: &SpringParams) -> bool {
    slip * dir < -(h * limit / springs.shear + springs.gap_tolerance)
}

/// The Coulomb limit against which `head_slip_predict` tests a locked head joint, N: that of
/// the normal force its predicted gap gives (−k_n × gap, 0 when not compressed), `None` when
/// the gap is predicted to open (the gap prediction decides that joint) or has no history.
fn head_onset_limit(
    c: &Contact,
    law: &JointLaw,
    springs: &SpringParams,
    params: &OpenCloseParams,
) -> Option<f64> {
    let gap = predicted_gap(c, params.gap_predict.unwrap_or(0.0))?;
    if gap > opening_gap(c, law, springs) {
        return None;
    }
    Some(shear_limit(c, law, -springs.normal * gap))
}

/// The gap prediction at a step start (`OpenCloseParams::gap_predict`): call once per step,
/// after `predict_stick_slip` (which clears the marks) and after the contacts are linearized
/// (it reads the step-start gap `g0`). Sets `Contact::predicted_state` of a closed head joint
/// predicted to open (`Open`) or an open one predicted to close (`Locked`), from the gap
/// changes of the last two accepted steps; leaves every other mark as it is.
pub fn predict_gaps(
    contacts: &mut [Contact],
    laws: &[JointLaw],
    springs: &SpringParams,
    params: &OpenCloseParams,
) {
    let Some(gain) = params.gap_predict else {
        return;
    };
    for (c, law) in contacts.iter_mut().zip(laws) {
        // Head joints only (normal within `light_state_tilt` of horizontal).
        if !params.head_by_tilt(&c.n) {
            continue;
        }
        let Some(gap) = predicted_gap(c, gain) else {
            continue;
        };
        // `update_state`'s opening and closing tests, on the predicted gap.
        if c.state.is_closed() {
            if gap > opening_gap(c, law, springs) {
                c.predicted_state = Some(ContactState::Open);
            }
        } else if gap <= -springs.gap_tolerance {
            c.predicted_state = Some(ContactState::Locked);
        }
    }
}

/// The friction normal's prediction at a step start (`OpenCloseParams::friction_predict`):
/// call once per step, before its first open–close loop (a refused attempt's retry must not
/// extrapolate again). Each contact's converged normal force is remembered for the next step;
/// a sliding contact (or one `predict_stick_slip` starts sliding) closed at both step starts
/// gets the extrapolated force, N, as
/// `Contact::predicted_friction_normal`, which `iterate` starts from where the rule applies.
pub fn predict_friction_normals(contacts: &mut [Contact], gain: f64) {
    for c in contacts {
        let n1 = c.state.is_closed().then(|| c.normal_force.max(0.0));
        // A contact the stick–slip prediction starts in another state (`predict_stick_slip`,
        // called before) is predicted in that state.
        let state = c.predicted_state.unwrap_or(c.state);
        c.predicted_friction_normal = match (state, n1, c.prior_normal_force) {
            (ContactState::Sliding { .. }, Some(n1), Some(n0)) => {
                Some((n1 + gain * (n1 - n0)).max(0.0))
            }
            _ => None,
        };
        c.prior_normal_force = n1;
    }
}

/// Why open–close iterations were needed (diagnostics, docs/contact-solve.md): every change that
/// asked for another solve, by kind and by joint orientation, and how many changes each
/// iteration number saw. Counting costs a few integer increments a contact and iteration.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct ChangeCounts {
    /// `[kind][orientation]`: kind indexes [`CHANGE_KINDS`]; orientation 0 = a bed joint
    /// (edge normal within 45° of vertical), 1 = a head (vertical) joint.
    pub by_kind: [[u64; 2]; 7],
    /// Changes seen after the solve of iteration k + 1 (the last bin counts all later ones).
    pub by_iteration: [u64; 12],
    /// Changes by the force they misjudged, in decades: bin d counts 10^(d−3) ≤ F < 10^(d−2) N
    /// (bin 0 everything below 1e-2 N, the last everything above 1e6 N). For an opened or
    /// closed contact F = k·|g|, for a stick–slip change the Coulomb limit, for a friction
    /// update μ·|ΔN|.
    pub by_force: [u64; 9],
    /// The changes seen after the iteration at which a step's loop stopped unconverged (its
    /// last: `max_iterations`, the floor's cap, or `iteration_limit` when the cycle rule gave
    /// the step its extra iterations), whose step is then refused or, at the floor, taken:
    /// `[kind][orientation]` as `by_kind`, and by force decade as `by_force`.
    pub last_kind: [[u64; 2]; 7],
    pub last_force: [u64; 9],
    /// Changes let through by the settle rule (`OpenCloseParams::settle_tolerance`).
    pub settled: u64,
    /// Friction updates and head-joint state changes let through by the stone settle rule
    /// (`OpenCloseParams::stone_settle_friction`, `stone_settle_state`).
    pub stone_settled_friction: u64,
    pub stone_settled_state: u64,
    /// State changes of lightly loaded contacts let through (`OpenCloseParams::light_state_changes`).
    pub light: u64,
    /// `[kind][orientation][iteration]`: `by_kind` split by iteration as `by_iteration`.
    pub by_kind_iteration: [[[u64; 12]; 2]; 7],
    /// Local rounds run (`OpenCloseParams::local_sweeps`) and the state changes they made.
    pub local_rounds: u64,
    pub local_changes: u64,
    /// Line searches run (`OpenCloseParams::line_search`), those that damped the step (t < 1),
    /// and the sum of their step lengths t.
    pub searches: u64,
    pub damped: u64,
    pub damped_t_sum: f64,
    /// Closings the cycle rule (`OpenCloseParams::cycle_flips`) made sliding, by whether the
    /// contact's interface was lightly loaded (0) or loaded (1) (`cycle_light_interface`), and
    /// the closings it left locked because of that check or of `cycle_tilt` (bed joints).
    pub cycle_closed: [u64; 2],
    pub cycle_kept_locked: u64,
    /// Steps that converged only in the iterations `cycle_extra` adds beyond `max_iterations`.
    pub cycle_extra_steps: u64,
    /// Contacts the stick–slip prediction (`OpenCloseParams::stick_predict`, `slip_predict`)
    /// started in another state: `[0]` started locked (predicted re-sticking), `[1]` started
    /// sliding (predicted onset of slip); and the gap prediction (`gap_predict`): `[2]`
    /// started open (predicted opening), `[3]` started closed (predicted closing); each
    /// `[held, changed]` after the first solve; `[4]` the head joints started sliding
    /// (`head_slip_predict`; `[1]` counts the bed joints).
    pub predicted: [[u64; 2]; 5],
}

/// Names of the kinds of [`ChangeCounts::by_kind`].
pub const CHANGE_KINDS: [&str; 7] = [
    "closed→open",
    "open→closed",
    "locked→sliding",
    "sliding→locked",
    "slip reversed",
    "friction normal moved",
    "release factor moved",
];

impl ChangeCounts {
    fn record(&mut self, kind: usize, head: bool, iteration: usize, force: f64) {
        self.by_kind[kind][head as usize] += 1;
        self.by_iteration[(iteration - 1).min(11)] += 1;
        self.by_kind_iteration[kind][head as usize][(iteration - 1).min(11)] += 1;
        let d = if force > 0.0 {
            (force.log10() + 3.0).floor().clamp(0.0, 8.0) as usize
        } else {
            0
        };
        self.by_force[d] += 1;
    }

    /// The iteration's changes (those recorded since `kinds`, `forces` were read at its
    /// start) as the changes of a loop's last, unconverged iteration. Counted at the loop's
    /// end because which iteration is the last is known only then (the cycle rule's
    /// closings in this very iteration may give the step its extra iterations).
    fn record_last(&mut self, kinds: &[[u64; 2]; 7], forces: &[u64; 9]) {
        for ((last, now), before) in self.last_kind.iter_mut().zip(&self.by_kind).zip(kinds) {
            for ((l, n), b) in last.iter_mut().zip(now).zip(before) {
                *l += n - b;
            }
        }
        for ((l, n), b) in self.last_force.iter_mut().zip(&self.by_force).zip(forces) {
            *l += n - b;
        }
    }
}

impl OpenCloseParams {
    /// Whether a contact of unit normal `n` is a head joint by the light rule's tilt: its
    /// normal within `light_state_tilt` of horizontal (the 1e-12 absorbs the rounding of a
    /// normal at exactly the tilt). The light rule, the stick–slip and gap predictions and the
    /// stone rule's state bound ask the same.
    pub fn head_by_tilt(&self, n: &nalgebra::Vector2<f64>) -> bool {
        n.y.abs() <= self.light_state_tilt.sin() + 1e-12
    }

    /// The loop as it was before docs/contact-solve.md (for the reference runs there).
    pub fn legacy() -> Self {
        Self {
            force_tolerance: 0.0,
            secant_friction: false,
            anderson_depth: 0,
            settle_tolerance: 0.0,
            light_state_changes: false,
            // The reference loop cuts Δt where it does not converge (§18, §25).
            cycle_flips: 0,
            friction_predict: None,
            stick_predict: None,
            slip_predict: None,
            gap_predict: None,
            head_slip_predict: None,
            ..Self::default()
        }
    }

    /// The settle rule (`settle_tolerance`, `settle_after`): at `iteration`, a change that
    /// misjudges `force` (N) against the force scale `scale` (N) is taken without another solve.
    fn settles(&self, iteration: usize, force: f64, scale: f64) -> bool {
        self.settle_tolerance > 0.0
            && iteration >= self.settle_after
            && force <= self.settle_tolerance * scale
    }

    /// The last iteration a step allows: `max_iterations`, plus `cycle_extra` when the cycle
    /// rule (`cycle_flips`) is on.
    pub fn iteration_limit(&self) -> usize {
        if self.cycle_flips > 0 {
            self.max_iterations + self.cycle_extra
        } else {
            self.max_iterations
        }
    }

    /// Whether a contact that has flipped `flips` times this step closes sliding at
    /// `iteration` (`cycle_flips`).
    fn closes_sliding(&self, flips: u32, iteration: usize) -> bool {
        self.cycle_flips > 0 && flips >= self.cycle_flips && iteration >= self.cycle_after
    }

    /// Whether the stone settle rule is on (`stone_settle_friction` or `stone_settle_state`).
    fn stone_settle(&self) -> bool {
        self.stone_settle_friction > 0.0 || self.stone_settle_state > 0.0
    }
}

/// Result of one open–close loop.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum OpenClose {
    Converged {
        iterations: usize,
    },
    /// `contact` is one that was still changing state.
    NotConverged {
        iterations: usize,
        contact: Option<usize>,
    },
}

/// A block's unknowns in `x` (`None` for a block without unknowns).
#[inline]
fn block_unknowns<'x>(x: &'x [f64], dofs: &Dofs, block: usize) -> Option<&'x [f64]> {
    dofs.free_index[block].map(|f| {
        let o = dofs.offset[f];
        &x[o..o + dofs.ndof[f]]
    })
}

/// Dot product of a contact gradient with a block's unknowns (rigid blocks use 3; 0 for a
/// block without unknowns).
#[inline]
fn dot(v: &Vec6, xb: Option<&[f64]>) -> f64 {
    match xb {
        // Rigid: the same sum unrolled (a float sum starts from −0.0, which adds nothing).
        Some(&[x0, x1, x2]) => v[0] * x0 + v[1] * x1 + v[2] * x2,
        Some(xb) => xb.iter().enumerate().map(|(k, &xk)| v[k] * xk).sum(),
        None => 0.0,
    }
}

/// Gap and shear measure of a contact for the solution `x` (m). Each block's unknowns are
/// looked up once for both measures (session 41; the same sums in the same order as four
/// look-ups, docs/contact-solve.md §31).
#[inline]
pub fn measures(c: &Contact, x: &[f64], dofs: &Dofs, prescribed: &[Prescribed]) -> (f64, f64) {
    let (g0, s0) = constants(c, prescribed);
    let xi = block_unknowns(x, dofs, c.vertex_block);
    let xj = block_unknowns(x, dofs, c.edge_block);
    let g = g0 + dot(&c.e_i, xi) - dot(&c.e_j, xj);
    let s = s0 + dot(&c.f_i, xi) - dot(&c.f_j, xj);
    (g, s)
}

/// Buffers of the loop kept across steps.
#[derive(Debug, Default, Clone)]
pub struct OpenCloseScratch {
    block_force: Vec<f64>,
    anderson: FrictionAnderson,
    /// Per contact its interface, per interface its running load and the cycle rule's limit.
    iface: InterfaceLoads,
    /// Contacts (with their change) that qualify for the light rule on their own, pending the
    /// check of their interface's load after the iteration's pass.
    light: Vec<(usize, LightChange)>,
    /// Scratch for grouping contacts by interface.
    pairs: Vec<(usize, usize, usize)>,
    /// Contacts the stick–slip prediction started in another state this loop, with that
    /// state (diagnostics: `ChangeCounts::predicted`).
    /// (contact, predicted state, slot of `ChangeCounts::predicted`).
    predicted: Vec<(usize, ContactState, usize)>,
    /// Per interface, in `interface` numbering: its blocks (lower index first) and its first
    /// contact. Built with `interface` once per step: the stone rule's passes over interfaces.
    interfaces: Vec<(usize, usize, usize)>,
    /// Per block, its interfaces loaded at the step start (`OpenCloseParams::
    /// stone_settle_interfaces`).
    loaded_interfaces: Vec<usize>,
    /// Per block, its loaded supports below at the step start (`OpenCloseParams::
    /// stone_settle_supports`).
    supports: Vec<usize>,
    /// Per block, whether the stone settle rule may apply to its contacts.
    many_stone: Vec<bool>,
    /// Per contact, whether both its stones (its free blocks) are `many_stone`: the stone
    /// settle rule's test, fixed for the step.
    many_stones: Vec<bool>,
    local: LocalScratch,
    /// The last iterate (`OpenCloseParams::line_search`), the undamped solution, and per free
    /// block the direction between them.
    x_old: Vec<f64>,
    x_new: Vec<f64>,
    dir: Vec<Vec6>,
    /// Per contact, the springs (`spring_key`) that the system's matrix holds: an iteration
    /// whose contacts hold the same springs keeps the matrix and re-adds only the loads.
    spring_keys: Vec<u8>,
}

/// The interfaces' loads, read by the light rule's and the cycle rule's interface checks.
#[derive(Debug, Default, Clone)]
struct InterfaceLoads {
    /// Per contact, the index of its interface (the unordered pair of its blocks).
    interface: Vec<usize>,
    /// Per interface, the largest normal force of its contacts at the step start, in the
    /// current solve and after it, N.
    load: Vec<f64>,
    /// Per interface, the load up to which the cycle rule counts it as light
    /// (`OpenCloseParams::cycle_light_interface`): `light_load` × the weight of the lighter
    /// free stone of its pair, N. Fixed for the step, built with `interface`.
    cycle_limit: Vec<f64>,
}

impl InterfaceLoads {
    /// The running load of contact `k`'s interface, N.
    fn load_of(&self, k: usize) -> f64 {
        self.load[self.interface[k]]
    }

    /// Raises each interface's running load to its contacts' `force`, N.
    fn note_loads(&mut self, contacts: &[Contact], force: impl Fn(&Contact) -> f64) {
        for (c, &i) in contacts.iter().zip(&self.interface) {
            let load = &mut self.load[i];
            *load = load.max(force(c));
        }
    }

    /// Contact `k`'s interface class for the cycle rule: its interface's running load (step
    /// start and the solves so far, when tracked) against the interface's `cycle_limit`
    /// (`light_load` × the weight of the lighter free stone of the pair, set once a step by
    /// `cycle_limits`). With the rule off every contact counts as light (the loads are
    /// tracked, and read, only with it on).
    fn cycle_class(&self, params: &OpenCloseParams, k: usize) -> CycleInterface {
        if params.cycle_flips == 0 {
            return CycleInterface::Light;
        }
        let i = self.interface[k];
        CycleInterface::from(self.load[i] <= self.cycle_limit[i])
    }
}

/// Buffers of the local rounds (`OpenCloseParams::local_sweeps`).
#[derive(Debug, Default, Clone)]
struct LocalScratch {
    /// Per free block, its coupled blocks: (block, slot in `BlockSystem::off`, whether the
    /// stored block is transposed for this row).
    nbr: Vec<Vec<(usize, usize, bool)>>,
    /// Per free block, the inverse of its diagonal block (leading ndof × ndof, zero-padded).
    inv: Vec<Mat6>,
}

/// A state change that `OpenCloseParams::light_state_changes` may let through, pending the
/// interface check: what `ChangeCounts::record` needs if it does not.
#[derive(Debug, Clone, Copy)]
struct LightChange {
    kind: usize,
    head: bool,
    force: f64,
}

/// What one contact's update asks of the loop.
#[derive(Debug, Clone, Copy)]
enum Update {
    /// Nothing changed, or only what needs no other solve.
    Quiet,
    /// A change that asks for another solve (counted).
    Changed,
    /// A light state change, not yet counted: let through if its interface is light.
    Light(LightChange),
}

/// Run the loop; `x` holds the converged solution on return.
pub fn iterate(
    sys: &mut BlockSystem,
    dofs: &Dofs,
    contacts: &mut [Contact],
    laws: &[JointLaw],
    springs: &SpringParams,
    prescribed: &[Prescribed],
    solver: &mut LinearSolver,
    x: &mut Vec<f64>,
    params: &OpenCloseParams,
    counts: &mut ChangeCounts,
    scratch: &mut OpenCloseScratch,
) -> Result<OpenClose, SolveError> {
    let mut last_changed = None;
    // Largest contact normal force on each block at the step start (the last step's converged
    // forces), N: the force scale of `OpenCloseParams::force_tolerance`. Not the trial forces
    // of this step's iterations: an iterate with a wrong contact state can carry forces 10⁴×
    // the stone's weight (measured on the incline at 1 m/s), which would let real friction
    // changes pass as small.
    let block_force = &mut scratch.block_force;
    block_force.clear();
    block_force.resize(dofs.free_index.len(), 0.0);
    let anderson = &mut scratch.anderson;
    anderson.clear();
    let interfaces = params.light_state_changes && params.light_state_interface;
    // The cycle rule's interface check needs the same running interface loads.
    // (tracked with the check off too, to count what it would keep out).
    let cycle_interfaces = params.cycle_flips > 0;
    let track = interfaces || cycle_interfaces;
    let stone_settle = params.stone_settle();
    if track || stone_settle {
        group_interfaces(
            contacts,
            &mut scratch.pairs,
            &mut scratch.iface.interface,
            &mut scratch.interfaces,
        );
        scratch.iface.load.clear();
        scratch.iface.load.resize(scratch.interfaces.len(), 0.0);
        if cycle_interfaces {
            cycle_limits(
                &scratch.interfaces,
                dofs,
                &sys.weight,
                params.light_load,
                &mut scratch.iface.cycle_limit,
            );
        }
    }
    for (c, law) in contacts.iter_mut().zip(laws) {
        c.flips = 0;
        c.friction_secant = None;
        // A frictionless contact carried in locked (found touching, or locked by a slip below
        // the length tolerance) holds a shear spring it cannot have: start it sliding.
        if c.state == ContactState::Locked && frictionless(c, law) {
            c.state = ContactState::Sliding { dir: 1.0 };
        }
        c.start_normal_force = if c.state.is_closed() {
            c.normal_force.max(0.0)
        } else {
            0.0
        };
        c.release_factor = 1.0;
        note_force(block_force, c, c.start_normal_force);
    }
    if params.weight_scale {
        // A stone with no contact force yet: its weight is the force its contacts will carry.
        for (f, &b) in dofs.block_of.iter().enumerate() {
            if block_force[b] == 0.0 {
                block_force[b] = sys.weight.get(f).copied().unwrap_or(0.0);
            }
        }
    }
    if track || stone_settle {
        scratch.iface.note_loads(contacts, |c| c.start_normal_force);
    }
    if stone_settle {
        // Count each block's interfaces that carried a comparable share of its load at the
        // step start.
        let counts = &mut scratch.loaded_interfaces;
        counts.clear();
        counts.resize(block_force.len(), 0);
        let supports = &mut scratch.supports;
        supports.clear();
        supports.resize(block_force.len(), 0);
        let free = |x: usize| dofs.free_index[x].is_some();
        for (&(a, b, k), &load) in scratch.interfaces.iter().zip(&scratch.iface.load) {
            let c = &contacts[k];
            for (blk, other) in [(a, b), (b, a)] {
                if load > 0.0 && load >= params.light_load * block_force[blk] {
                    counts[blk] += 1;
                    // `n` points out of the edge block into the vertex block: the normal
                    // from `other` into `blk`, upward for a bed joint that `blk` rests on.
                    let up = if blk == c.vertex_block { c.n.y } else { -c.n.y };
                    if up > params.light_state_tilt.sin() {
                        // A fixed support carries the stone alone.
                        supports[blk] += if free(other) {
                            1
                        } else {
                            params.stone_settle_supports
                        };
                    }
                }
            }
        }
        let core = |x: usize| {
            counts[x] >= params.stone_settle_interfaces
                && supports[x] >= params.stone_settle_supports
        };
        let many_stone = &mut scratch.many_stone;
        many_stone.clear();
        many_stone.extend((0..counts.len()).map(core));
        if params.stone_settle_neighbours {
            // A stone loaded against a stone of the web belongs to it.
            for (&(a, b, _), &load) in scratch.interfaces.iter().zip(&scratch.iface.load) {
                for (x, y) in [(a, b), (b, a)] {
                    if free(y)
                        && core(y)
                        && load > 0.0
                        && load >= params.light_load * block_force[x]
                    {
                        many_stone[x] = true;
                    }
                }
            }
        }
    }
    // Whether both of a contact's stones (its free blocks) are held by many loaded interfaces.
    let many_stone = &scratch.many_stone;
    scratch.many_stones.clear();
    scratch.many_stones.extend(contacts.iter().map(|c| {
        stone_settle
            && [c.vertex_block, c.edge_block]
                .into_iter()
                .filter(|&b| dofs.free_index[b].is_some())
                .all(|b| many_stone[b])
    }));
    if params.friction_predict.is_some() {
        // The friction normal's prediction, on the stones the stone settle rule takes.
        for (c, &many) in contacts.iter_mut().zip(&scratch.many_stones) {
            if let (true, Some(n)) = (many, c.predicted_friction_normal) {
                c.friction_normal = n;
            }
        }
    }
    scratch.predicted.clear();
    for (k, ((c, law), &many)) in contacts
        .iter_mut()
        .zip(laws)
        .zip(&scratch.many_stones)
        .enumerate()
    {
        // The stick–slip prediction, on the same stones, on the step's first attempt only
        // (`take`: a retry after a cut starts where the refused attempt ended).
        let Some(state) = c.predicted_state.take() else {
            continue;
        };
        // The stick–slip prediction marks closed contacts Locked or Sliding; the gap
        // prediction closed ones Open and open ones Locked.
        let slot = match (c.state, state) {
            (ContactState::Open, ContactState::Open) => continue,
            (_, ContactState::Open) => 2,
            (ContactState::Open, _) => 3,
            (_, ContactState::Sliding { .. }) if params.head_by_tilt(&c.n) => 4,
            (_, ContactState::Sliding { .. }) => 1,
            _ => 0,
        };
        if many && (slot == 2 || !frictionless(c, law)) {
            if let (ContactState::Locked, ContactState::Sliding { .. }) = (c.state, state) {
                // Its friction from the friction normal's prediction (applied above), else
                // from the last normal force, as the loop's own onset of slip.
                if params.friction_predict.is_none() || c.predicted_friction_normal.is_none() {
                    c.friction_normal = c.normal_force.max(0.0);
                }
            }
            c.state = state;
            scratch.predicted.push((k, state, slot));
        }
    }
    let block_force: &[f64] = block_force;
    // One contact's update at an iterate: the pass after the solve, the pass again at the
    // undamped solution, and the local rounds' passes.
    let rule = Rule {
        springs,
        dofs,
        prescribed,
        params,
        block_force,
    };
    let limit = params.iteration_limit();
    // The cycle rule's closings before this step: from the first iteration, `cycle_extra`
    // iterations are for a step in which the rule closed a contact sliding; a step it took
    // nothing in ends at `max_iterations`, as without the rule (so a scene the rule never acts
    // on runs bit for bit as with the rule off, its refused steps included).
    let cycle_before = counts.cycle_closed;
    // Whether `sys`'s matrix holds the block terms and the springs of `spring_keys` (set by
    // this call's assemblies only: the first iteration always assembles).
    let mut matrix_holds_keys = false;
    for it in 1..=limit {
        // The matrix depends on which springs the contacts hold, not on their loads (friction,
        // gap constants, release): when no spring was added or removed since the last
        // assembly, the same rank-one updates would rebuild the same matrix to the bit, so
        // only the right-hand side is rebuilt (the same operations on it, in the same order).
        let keys = &mut scratch.spring_keys;
        if matrix_holds_keys
            && keys.len() == contacts.len()
            && contacts
                .iter()
                .zip(keys.iter())
                .all(|(c, &k)| spring_key(c.state) == k)
        {
            sys.reset_rhs_to_blocks();
            add_contact_loads(sys, dofs, contacts, laws, springs, prescribed);
        } else {
            sys.reset_to_blocks();
            add_contacts(sys, dofs, contacts, laws, springs, prescribed);
            keys.clear();
            keys.extend(contacts.iter().map(|c| spring_key(c.state)));
            matrix_holds_keys = true;
        }
        if params.line_search {
            scratch.x_old.clone_from(x);
        }
        solver.solve(sys, dofs, x)?;
        // Damped: the states below are decided at x(t), t < 1, not at the solve's x.
        let mut damped = false;
        if params.line_search && it > 1 {
            let t = line_search_step(
                sys,
                dofs,
                contacts,
                springs,
                prescribed,
                &scratch.x_old,
                x,
                &mut scratch.dir,
            );
            counts.searches += 1;
            if t < 1.0 {
                counts.damped += 1;
                counts.damped_t_sum += t;
                damped = true;
                scratch.x_new.clone_from(x);
                for (xi, &xo) in x.iter_mut().zip(&scratch.x_old) {
                    *xi = xo + t * (*xi - xo);
                }
            }
        }
        let mut changed = 0;
        // This iteration's changes, counted as a failing loop's last if it is (`record_last`).
        let (kinds_before, forces_before) = (counts.by_kind, counts.by_force);
        // Whether a contact changed state or load (the friction map changed: Anderson's
        // history no longer applies).
        let mut structural = false;
        anderson.begin();
        scratch.light.clear();
        for (k, (c, law)) in contacts.iter_mut().zip(laws).enumerate() {
            let (old_state, n_in, old_release) = (c.state, c.friction_normal, c.release_factor);
            if track {
                // The load the solve used (a closed contact's force of the last iterate).
                let load = &mut scratch.iface.load[scratch.iface.interface[k]];
                if c.state.is_closed() {
                    *load = load.max(c.normal_force);
                }
            }
            let cycle = scratch.iface.cycle_class(params, k);
            match rule.update(c, law, x, it, scratch.many_stones[k], cycle, counts) {
                Update::Quiet => {}
                Update::Changed => {
                    changed += 1;
                    last_changed = Some(k);
                }
                Update::Light(change) if interfaces => scratch.light.push((k, change)),
                Update::Light(_) => counts.light += 1,
            }
            if c.state != old_state
                || (c.release_factor - old_release).abs() > params.release_tolerance
            {
                structural = true;
            } else if law.tan_phi != 0.0 && params.anderson_depth > 0 {
                anderson.note(k, c.state, n_in, c.normal_force.max(0.0));
            }
        }
        if track {
            // The loads the solve gave.
            scratch.iface.note_loads(contacts, |c| c.normal_force);
        }
        if interfaces {
            // The pending light changes against those loads: a light corner of a loaded
            // interface (a pivot's partner) asks for its solve after all.
            for &(k, change) in &scratch.light {
                let c = &contacts[k];
                let scale = force_scale(block_force, c, dofs);
                if scratch.iface.load_of(k) <= params.light_load * scale {
                    counts.light += 1;
                } else if params.settles(it, change.force, scale) {
                    // As in `update_state`: the settle rule still applies.
                    counts.settled += 1;
                } else {
                    counts.record(change.kind, change.head, it, change.force);
                    changed += 1;
                    last_changed = Some(k);
                }
            }
        }
        if it == 1 {
            for &(k, state, slot) in &scratch.predicted {
                let changed = state_changed(state, contacts[k].state) as usize;
                counts.predicted[slot][changed] += 1;
            }
        }
        if changed == 0 && damped {
            // No change at the damped point: decide at the solve's own solution instead,
            // so a converged step is always an undamped solve whose states hold.
            x.clone_from(&scratch.x_new);
            for (k, (c, law)) in contacts.iter_mut().zip(laws).enumerate() {
                let cycle = scratch.iface.cycle_class(params, k);
                match rule.update(c, law, x, it, scratch.many_stones[k], cycle, counts) {
                    Update::Quiet => {}
                    // The interface check is skipped here: such a change asks for a solve.
                    Update::Changed | Update::Light(_) => {
                        changed += 1;
                        last_changed = Some(k);
                    }
                }
            }
        }
        if changed == 0 {
            if it > params.max_iterations {
                counts.cycle_extra_steps += 1;
            }
            return Ok(OpenClose::Converged { iterations: it });
        }
        if params.anderson_depth > 0 {
            if structural && !params.anderson_keep {
                anderson.clear();
            } else if let Some(next) = anderson.step(
                params.anderson_depth,
                springs.normal * springs.gap_tolerance,
            ) {
                for &(k, n) in next {
                    contacts[k].friction_normal = n;
                }
            }
        }
        // This step's last iteration: `limit` once the rule has closed a contact sliding, or
        // always when the rule only starts after `max_iterations` ("at the limit", §18).
        let last =
            if counts.cycle_closed == cycle_before && params.cycle_after <= params.max_iterations {
                params.max_iterations
            } else {
                limit
            };
        if params.local_sweeps > 0 && it >= params.local_after && it < last {
            // The rounds assemble the system themselves.
            matrix_holds_keys = false;
            local_rounds(
                sys,
                &rule,
                contacts,
                laws,
                x,
                it,
                counts,
                &mut scratch.local,
            );
        }
        if it >= last {
            counts.record_last(&kinds_before, &forces_before);
            return Ok(OpenClose::NotConverged {
                iterations: it,
                contact: last_changed,
            });
        }
    }
    Ok(OpenClose::NotConverged {
        iterations: limit,
        contact: last_changed,
    })
}

/// Exact line search of `OpenCloseParams::line_search` on the segment x(t) = x_old + t·(x −
/// x_old), t ∈ (0, 1]: the root of the derivative of the step's incremental potential with
/// the normal springs unilateral (energy k/2·min(0, g)² for an unbonded contact) and everything
/// else as assembled in `sys` (for which `x` is the exact minimiser). With A the assembled
/// matrix, φ'(t) = (t − 1)·dᵀAd + Σ k·g'·(min(0, g(t)) − [closed]·g(t)), convex in t, so φ' is
/// monotone and bisection finds its root. Returns 1 when the full step still descends.
#[allow(clippy::too_many_arguments)]
fn line_search_step(
    sys: &BlockSystem,
    dofs: &Dofs,
    contacts: &[Contact],
    springs: &SpringParams,
    prescribed: &[Prescribed],
    x_old: &[f64],
    x: &[f64],
    dir: &mut Vec<Vec6>,
) -> f64 {
    let nf = dofs.ndof.len();
    dir.clear();
    dir.extend((0..nf).map(|f| {
        let mut v = Vec6::zeros();
        let o = dofs.offset[f];
        for i in 0..dofs.ndof[f] {
            v[i] = x[o + i] - x_old[o + i];
        }
        v
    }));
    let mut dad: f64 = (0..nf).map(|f| dir[f].dot(&(sys.diag[f] * dir[f]))).sum();
    for (k, &(a, b)) in sys.pairs.iter().enumerate() {
        dad += 2.0 * dir[a].dot(&(sys.off[k] * dir[b]));
    }
    if dad.is_nan() || dad <= 0.0 {
        return 1.0;
    }
    let k = springs.normal;
    // (g at x_old, g' along the segment, closed as assembled) of every unbonded contact whose
    // spring is not what the assembly assumed somewhere on the segment.
    let terms: Vec<(f64, f64, bool)> = contacts
        .iter()
        .filter(|c| !c.bonded)
        .filter_map(|c| {
            let g0 = measures(c, x_old, dofs, prescribed).0;
            let g1 = measures(c, x, dofs, prescribed).0;
            let closed = c.state.is_closed();
            let differs = if closed {
                g0 > 0.0 || g1 > 0.0
            } else {
                g0 < 0.0 || g1 < 0.0
            };
            differs.then_some((g0, g1 - g0, closed))
        })
        .collect();
    let slope = |t: f64| {
        let mut s = (t - 1.0) * dad;
        for &(g0, gp, closed) in &terms {
            let g = g0 + t * gp;
            s += k * gp * if closed { -g.max(0.0) } else { g.min(0.0) };
        }
        s
    };
    if slope(1.0) <= 0.0 || slope(0.0) >= 0.0 {
        return 1.0;
    }
    let (mut lo, mut hi) = (0.0, 1.0);
    for _ in 0..30 {
        let mid = 0.5 * (lo + hi);
        if slope(mid) > 0.0 {
            hi = mid;
        } else {
            lo = mid;
        }
    }
    hi
}

/// Whether a contact's state changed in a way the loop iterates on (open ⇄ closed, stick ⇄
/// slip, a slip reversal).
fn state_changed(old: ContactState, new: ContactState) -> bool {
    match (old, new) {
        (ContactState::Sliding { dir: a }, ContactState::Sliding { dir: b }) => a != b,
        _ => std::mem::discriminant(&old) != std::mem::discriminant(&new),
    }
}

/// The local rounds of `OpenCloseParams::local_sweeps`: re-decide the contact states after a
/// global solve by block Gauss–Seidel sweeps on the re-assembled system, starting from the
/// solve's `x`, before the next global solve. `x` is overwritten by that solve; only the
/// contacts' states and friction normal forces carry over. A contact's flip count is left as
/// the global iterations set it, so `max_flips` still counts global decisions only.
#[allow(clippy::too_many_arguments)]
fn local_rounds(
    sys: &mut BlockSystem,
    rule: &Rule,
    contacts: &mut [Contact],
    laws: &[JointLaw],
    x: &mut [f64],
    iteration: usize,
    counts: &mut ChangeCounts,
    local: &mut LocalScratch,
) {
    let (dofs, springs, prescribed, params) =
        (rule.dofs, rule.springs, rule.prescribed, rule.params);
    let nf = dofs.ndof.len();
    local.nbr.iter_mut().for_each(Vec::clear);
    local.nbr.resize_with(nf, Vec::new);
    for (k, &(a, b)) in sys.pairs.iter().enumerate() {
        local.nbr[a].push((b, k, false));
        local.nbr[b].push((a, k, true));
    }
    let block_x = |x: &[f64], f: usize| {
        let mut v = Vec6::zeros();
        let o = dofs.offset[f];
        for i in 0..dofs.ndof[f] {
            v[i] = x[o + i];
        }
        v
    };
    // The changes of local rounds are predictions, not the loop's decisions: not counted.
    let mut ignored = ChangeCounts::default();
    for _ in 0..params.local_rounds {
        sys.reset_to_blocks();
        add_contacts(sys, dofs, contacts, laws, springs, prescribed);
        local.inv.clear();
        for f in 0..nf {
            let d = &sys.diag[f];
            let inv = if dofs.ndof[f] == 3 {
                let m = d.fixed_view::<3, 3>(0, 0).into_owned();
                let mut full = Mat6::zeros();
                if let Some(i) = m.try_inverse() {
                    full.fixed_view_mut::<3, 3>(0, 0).copy_from(&i);
                }
                full
            } else {
                d.try_inverse().unwrap_or_else(Mat6::zeros)
            };
            local.inv.push(inv);
        }
        for _ in 0..params.local_sweeps {
            for f in 0..nf {
                let mut r = sys.rhs[f];
                for &(b, k, t) in &local.nbr[f] {
                    let xb = block_x(x, b);
                    if t {
                        r -= sys.off[k].transpose() * xb;
                    } else {
                        r -= sys.off[k] * xb;
                    }
                }
                let xf = local.inv[f] * r;
                let o = dofs.offset[f];
                for i in 0..dofs.ndof[f] {
                    x[o + i] = xf[i];
                }
            }
        }
        let mut changed = 0;
        for (c, law) in contacts.iter_mut().zip(laws) {
            let (old, flips) = (c.state, c.flips);
            // The cycle rule's interface loads are the global loop's: with its check on, local
            // predictions close locked.
            let cycle = CycleInterface::from(!params.cycle_light_interface);
            rule.update(c, law, x, iteration, false, cycle, &mut ignored);
            c.flips = flips;
            changed += state_changed(old, c.state) as u64;
        }
        counts.local_rounds += 1;
        counts.local_changes += changed;
        if changed == 0 {
            break;
        }
    }
}

/// Number the interfaces (unordered block pairs) of `contacts`: `interface[k]` is contact k's,
/// `interfaces[i]` is interface i's blocks (lower first) and first contact.
fn group_interfaces(
    contacts: &[Contact],
    pairs: &mut Vec<(usize, usize, usize)>,
    interface: &mut Vec<usize>,
    interfaces: &mut Vec<(usize, usize, usize)>,
) {
    pairs.clear();
    pairs.extend(contacts.iter().enumerate().map(|(k, c)| {
        let (a, b) = (c.vertex_block, c.edge_block);
        (a.min(b), a.max(b), k)
    }));
    pairs.sort_unstable();
    interface.clear();
    interface.resize(contacts.len(), 0);
    interfaces.clear();
    for (n, &(a, b, k)) in pairs.iter().enumerate() {
        if n == 0 || (pairs[n - 1].0, pairs[n - 1].1) != (a, b) {
            interfaces.push((a, b, k));
        }
        interface[k] = interfaces.len() - 1;
    }
}

/// Record `force` (N) as acting on both blocks of `c`.
#[inline]
fn note_force(block_force: &mut [f64], c: &Contact, force: f64) {
    for b in [c.vertex_block, c.edge_block] {
        block_force[b] = block_force[b].max(force);
    }
}

/// Force scale of a contact, N: the largest contact force on the less loaded of its blocks
/// with unknowns (a fixed foundation's load says nothing about a stone's balance).
#[inline]
fn force_scale(block_force: &[f64], c: &Contact, dofs: &Dofs) -> f64 {
    [c.vertex_block, c.edge_block]
        .into_iter()
        .filter(|&b| dofs.free_index[b].is_some())
        .map(|b| block_force[b])
        .fold(f64::INFINITY, f64::min)
        .min(block_force[c.vertex_block].max(block_force[c.edge_block]))
}

/// What a contact's update reads besides the contact and the iterate: the step's constants.
struct Rule<'a> {
    springs: &'a SpringParams,
    dofs: &'a Dofs,
    prescribed: &'a [Prescribed],
    params: &'a OpenCloseParams,
    /// Per block, its largest contact force at the step start (`force_scale`), N.
    block_force: &'a [f64],
}

impl Rule<'_> {
    /// Contact `c`'s new state at the iterate `x`, at its force scale (`update_state`).
    fn update(
        &self,
        c: &mut Contact,
        law: &JointLaw,
        x: &[f64],
        iteration: usize,
        many_stones: bool,
        cycle: CycleInterface,
        counts: &mut ChangeCounts,
    ) -> Update {
        let scale = force_scale(self.block_force, c, self.dofs);
        update_state(
            c,
            law,
            self.springs,
            x,
            self.dofs,
            self.prescribed,
            self.params,
            iteration,
            scale,
            many_stones,
            cycle,
            counts,
        )
    }
}

/// Whether the cycle rule may close a contact sliding, by its interface's load
/// (`OpenCloseParams::cycle_light_interface`).
#[derive(Debug, Clone, Copy, PartialEq)]
enum CycleInterface {
    /// Lightly loaded interface, or the check off.
    Light,
    /// A loaded interface: the rule is kept out.
    Loaded,
}

impl From<bool> for CycleInterface {
    fn from(light: bool) -> Self {
        if light {
            Self::Light
        } else {
            Self::Loaded
        }
    }
}

/// Per interface (`interfaces`: its blocks, lower first), the load up to which the cycle rule
/// counts it as light: `light_load` × the weight of the lighter free stone of the pair (`weight`:
/// per free block, N). The weight, not the step-start force scale of `force_tolerance`: that
/// scale is 0 in the first step of a scene dropped onto its springs (every interface would count
/// as loaded) and 100× the weight right after an impact (a pivot would count as light,
/// docs/contact-solve.md §12); "carries a stone" is a load against its weight.
fn cycle_limits(
    interfaces: &[(usize, usize, usize)],
    dofs: &Dofs,
    weight: &[f64],
    light_load: f64,
    limit: &mut Vec<f64>,
) {
    limit.clear();
    limit.extend(interfaces.iter().map(|&(a, b, _)| {
        let lighter = [a, b]
            .into_iter()
            .filter_map(|x| dofs.free_index[x])
            .map(|f| weight.get(f).copied().unwrap_or(0.0))
            .fold(f64::INFINITY, f64::min);
        light_load * lighter
    }));
}

/// New state of one contact given the trial solution; returns whether it changed.
fn update_state(
    c: &mut Contact,
    law: &JointLaw,
    springs: &SpringParams,
    x: &[f64],
    dofs: &Dofs,
    prescribed: &[Prescribed],
    params: &OpenCloseParams,
    iteration: usize,
    floor_scale: f64,
    many_stones: bool,
    cycle: CycleInterface,
    counts: &mut ChangeCounts,
) -> Update {
    let floor = params.force_tolerance * floor_scale;
    let friction_tol = params.friction_tolerance;
    let h = params.hysteresis;
    let (g, s) = measures(c, x, dofs, prescribed);
    let old_friction_normal = c.friction_normal;
    // The shear force the solve applied (a sliding contact's friction; N, on the vertex block).
    let old_shear = if let ContactState::Sliding { dir } = c.state {
        -dir * shear_limit(c, law, c.friction_normal)
    } else {
        c.shear_force
    };
    // The normal force the solve just used (the previous iterate's, or the last step's).
    let old_normal = if c.state.is_closed() {
        c.normal_force.max(0.0)
    } else {
        0.0
    };
    c.gap = g;
    c.slip = s - c.s0;
    let old = c.state;
    let threshold = if old.is_closed() {
        opening_gap(c, law, springs)
    } else {
        -springs.gap_tolerance
    };
    let new = if g > threshold {
        c.normal_force = 0.0;
        c.shear_force = 0.0;
        ContactState::Open
    } else {
        let n = -springs.normal * g;
        c.normal_force = n;
        let limit = shear_limit(c, law, n);
        match old {
            ContactState::Open => {
                c.shear_force = 0.0;
                if frictionless(c, law) {
                    ContactState::Sliding {
                        dir: if s != 0.0 { s.signum() } else { 1.0 },
                    }
                } else if params.closes_sliding(c.flips, iteration)
                    && ((cycle == CycleInterface::Loaded && params.cycle_light_interface)
                        || c.n.y.abs() > params.cycle_tilt.sin() + 1e-12)
                {
                    // A cycling corner of a loaded interface (a block's base, a rocking pivot's
                    // joint) or of a bed joint (a stack landing on it): its closing decides the
                    // stone's balance, so it closes locked.
                    counts.cycle_kept_locked += 1;
                    ContactState::Locked
                } else if params.closes_sliding(c.flips, iteration) {
                    // A cycling contact: close at the limit, not on a shear spring.
                    counts.cycle_closed[(cycle == CycleInterface::Loaded) as usize] += 1;
                    let dir = if s != 0.0 { s.signum() } else { 1.0 };
                    c.shear_force = -dir * limit;
                    ContactState::Sliding { dir }
                } else {
                    ContactState::Locked
                }
            }
            ContactState::Locked => {
                let f = -springs.shear * s;
                c.shear_force = f;
                if slips(f, limit, h, springs) {
                    ContactState::Sliding { dir: s.signum() }
                } else {
                    ContactState::Locked
                }
            }
            ContactState::Sliding { dir } => {
                c.shear_force = -dir * limit;
                if c.flips >= params.max_flips {
                    // Stick ⇄ slip cycling within one step: both states are inconsistent, and
                    // the consistent answer is sliding at the Coulomb limit with vanishing slip.
                    ContactState::Sliding { dir }
                } else if limit <= 0.0 {
                    // No friction: the slip direction is irrelevant and must not count as a change.
                    ContactState::Sliding {
                        dir: if c.slip != 0.0 { c.slip.signum() } else { dir },
                    }
                } else if resticks(c.slip, dir, limit, h, springs) {
                    ContactState::Locked
                } else {
                    ContactState::Sliding { dir }
                }
            }
        }
    };
    c.state = new;
    if std::mem::discriminant(&old) != std::mem::discriminant(&new) {
        c.flips += 1;
    }
    let release_moved = update_release(c, springs, params);
    let frictionless = shear_limit(c, law, c.normal_force) <= 0.0;
    let changed = std::mem::discriminant(&old) != std::mem::discriminant(&new)
        || (!frictionless
            && matches!((old, new), (ContactState::Sliding { dir: a }, ContactState::Sliding { dir: b }) if a != b));
    let mut friction_moved = false;
    if let ContactState::Sliding { .. } = new {
        let n = c.normal_force.max(0.0);
        // Without a friction coefficient the friction force does not depend on the normal
        // force (it is zero, or the bond's cohesion): nothing to iterate.
        friction_moved = law.tan_phi != 0.0
            && matches!(old, ContactState::Sliding { .. })
            && (n - c.friction_normal).abs()
                > friction_tol
                    * (n.max(c.friction_normal) + springs.normal * springs.gap_tolerance);
        // The friction force depends on the normal force it helps to determine (a pivoting,
        // sliding corner): plain fixed-point iteration can oscillate, so after the first
        // iterations the update is relaxed by half, which converges for slopes in (−3, 1).
        let was_sliding = matches!(old, ContactState::Sliding { .. });
        let input = c.friction_normal;
        let relaxed = if was_sliding && iteration > params.relax_after {
            0.5 * (input + n)
        } else {
            n
        };
        c.friction_normal = match c.friction_secant {
            Some((in0, out0)) if params.secant_friction && was_sliding && input != in0 => {
                // The map N_in ↦ N_out is locally linear with slope s: its fixed point is
                // N_in + (N_out − N_in)/(1 − s).
                let slope = (n - out0) / (input - in0);
                if slope.is_finite() && slope > -10.0 && slope < 0.9 {
                    (input + (n - input) / (1.0 - slope)).max(0.0)
                } else {
                    relaxed
                }
            }
            _ => relaxed,
        };
        c.friction_secant = was_sliding.then_some((input, n));
    } else {
        c.friction_secant = None;
    }
    if !(changed || friction_moved || release_moved) {
        return Update::Quiet;
    }
    {
        let head = c.n.y.abs() < std::f64::consts::FRAC_1_SQRT_2;
        let (kind, force) = match (old, new) {
            (o, ContactState::Open) if o.is_closed() => (0, springs.normal * g.abs()),
            (ContactState::Open, _) => (1, springs.normal * g.abs()),
            // The locked spring carried more than the limit: by this much.
            (ContactState::Locked, ContactState::Sliding { .. }) => (
                2,
                (c.shear_force.abs() - shear_limit(c, law, c.normal_force)).max(0.0),
            ),
            // The friction force was the limit; the true one lies within ±limit.
            (ContactState::Sliding { .. }, ContactState::Locked) if params.restick_jump => {
                (3, (-springs.shear * s - old_shear).abs())
            }
            (ContactState::Sliding { .. }, ContactState::Locked) => {
                (3, 2.0 * shear_limit(c, law, c.normal_force))
            }
            _ if changed => (4, 2.0 * shear_limit(c, law, c.normal_force)),
            _ if friction_moved => (
                5,
                law.tan_phi * (c.normal_force.max(0.0) - old_friction_normal).abs(),
            ),
            _ => (6, c.start_normal_force),
        };
        // Only a friction value update of a contact that stays sliding the same way may skip
        // the solve: opening, closing, the onset of slip, re-sticking and a slip reversal
        // decide the physics (the failure-mode chart's incipient sliding starts below any
        // such tolerance), so they always iterate.
        // And only on a contact that does not carry its stone (a head joint next to bed
        // joints): a sliding block's own base friction is its balance, whose lag of one step
        // shows in the incline benchmarks.
        let light = c.normal_force.max(old_friction_normal) <= params.light_load * floor_scale;
        if params.force_tolerance > 0.0 && kind == 5 && light && force <= floor && !release_moved {
            // Taken, but too small to need another solve.
            return Update::Quiet;
        }
        // A state change of a contact that carries almost none of its stones' load, misjudging
        // a force below the same floor: the head joints of a shaken wall, which otherwise ask
        // for a solve every time they open, close or slip by a fraction of a newton.
        let light_before_after = old_normal
            .max(c.normal_force.max(0.0))
            .max(old_friction_normal)
            <= params.light_load * floor_scale;
        // A head joint by the light rule's tilt (`light_state_tilt`); the stone rule's state
        // bound below asks the same.
        let head_by_tilt = params.head_by_tilt(&c.n);
        if params.light_state_changes
            && head_by_tilt
            && params.force_tolerance > 0.0
            && kind <= 4
            && light_before_after
            && force <= floor
            && !release_moved
        {
            return Update::Light(LightChange { kind, head, force });
        }
        // The stone settle rule: late in the loop, a small change between stones that many
        // loaded interfaces hold (walls; never a single block's base or a column's joint).
        if many_stones && iteration >= params.stone_settle_after && !release_moved {
            if kind == 5
                && params.stone_settle_friction > 0.0
                && force <= params.stone_settle_friction * floor_scale
            {
                counts.stone_settled_friction += 1;
                return Update::Quiet;
            }
            if kind <= 4
                && params.stone_settle_state > 0.0
                && light_before_after
                && head_by_tilt
                && force <= params.stone_settle_state * floor_scale
            {
                counts.stone_settled_state += 1;
                return Update::Quiet;
            }
        }
        if params.settles(iteration, force, floor_scale) && !release_moved {
            // Settle rule: taken, and too small to hold the step back any longer.
            counts.settled += 1;
            return Update::Quiet;
        }
        counts.record(kind, head, iteration, force);
    }
    Update::Changed
}

/// A joint that can carry no shear force at any normal force (no friction, no intact
/// cohesion): it closes straight into sliding, since a locked state would only add a shear
/// spring for one iteration, perturbing every other contact, before slipping anyway.
fn frictionless(c: &Contact, law: &JointLaw) -> bool {
    law.tan_phi == 0.0 && !(c.bonded && law.cohesion > 0.0)
}

/// The kept fraction λ = |g₀|/(|g₀| + g₁) of a contact compressed at the step start that is
/// open at its end (see `contact_springs::release_load`); returns whether it moved enough to
/// need another solve.
fn update_release(c: &mut Contact, springs: &SpringParams, params: &OpenCloseParams) -> bool {
    let lambda = if springs.release_weight > 0.0
        && c.start_normal_force > 0.0
        && !c.state.is_closed()
        && c.g0 < 0.0
        && c.gap > 0.0
    {
        -c.g0 / (c.gap - c.g0)
    } else {
        1.0
    };
    let moved = (lambda - c.release_factor).abs() > params.release_tolerance;
    c.release_factor = lambda;
    moved
}
