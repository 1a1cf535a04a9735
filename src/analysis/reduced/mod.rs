//! Reduced models: scenes that are exactly one classic problem — one rigid block on a fixed or
//! driven base — run as an ODE instead of the full DDA engine (docs/format.md §1 `control.model`).
//! Sits beside `analysis::run`, which chooses between them; shares its outputs (summary,
//! histories, trajectory) so callers (CLI, service, PGA search) cannot tell the difference
//! except by `model` and the cost.
//!
//! The block is in one of four states: at rest, rocking on a corner (Housner's equation with an
//! impact law), sliding (rigid-plastic Newmark), or fallen on its side. From rest the combined
//! first-motion check decides which motion starts: rocking when the load's moment about a
//! corner tips the block, sliding when the tangential load exceeds friction; both at once, slip
//! of the pivot while rocking, a sliding block whose leading corner lifts, or loss of contact
//! are the coupled cases the reduced models do not represent (a *violation*: `auto` then runs
//! the full engine; in a PGA search from the model's state at the last record sample before
//! the violation, [`HandOver`], `analysis::run_fallback`).
//!
//! Length (over 600 lines): the four-state machine (`Reduced`: the step, the transitions
//! between the states, event location, impacts) is one piece whose transitions are read
//! together; each model's own equations are already `rocking.rs` and `sliding.rs`, the
//! qualification `qualify.rs`, the integrator `ode.rs`, the outputs `record.rs`.
pub mod ode;
pub mod qualify;
pub mod record;
pub mod rocking;
pub mod sliding;

pub use qualify::{qualify, NotReducible, SingleBlock};
pub use rocking::Restitution;

use crate::motion::GroundMotion;
use crate::scene::Scene;
use nalgebra::Vector2;
use ode::{State, Tolerance};

/// Knobs of the reduced models. Each default says why.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ReducedParams {
    /// Impact law of the rocking model: Housner's angular-momentum law by default, the law his
    /// equation was published with (and the reference of Yagoda-Biran & Hatzor's rocking benchmark).
    pub restitution: Restitution,
    /// ODE tolerance: 1e-10 relative keeps the integration error four orders below the 1 %
    /// accuracy target at a cost of microseconds per simulated second.
    pub tolerance: Tolerance,
    /// Largest ODE step, s: 2 ms bounds how far an impact or a lift-off can hide inside one
    /// step (events are detected at step ends). Steps also end at every kink of the ground
    /// motion (each sample of a record: the acceleration is linear between samples, so each
    /// step integrates a smooth load and the error estimate holds) and at every output frame.
    pub max_step: f64,
    /// Scan step of the at-rest state under curved motions (pulses, sines), s: onset
    /// conditions are checked this often and then located by bisection (0.5 ms resolves any
    /// pulse a record can carry). Under records the scan goes sample by sample instead, which
    /// is exact: between samples the load is linear, the rocking and lift-off conditions are
    /// linear in it and the sliding condition convex, so none can hold inside a sample interval
    /// without holding at one of its ends.
    pub rest_scan: f64,
    /// Angular speed (rad/s) below which a rocking block that lands is at rest: it would lift
    /// again by less than ω²/(2θ̈) ~ 1e-10 rad.
    pub rest_angular_speed: f64,
    /// Contact detection tolerance for qualification, as a fraction of the block size: 1e-6
    /// accepts scenes written with rounded coordinates and rejects visible gaps.
    pub contact_tolerance: f64,
    /// A deformable block is treated as rigid when its self-weight strain ρgH/E is below this:
    /// 1e-4 changes the geometry by 0.01 %, two orders below the 1 % accuracy target.
    pub rigid_strain: f64,
}

impl Default for ReducedParams {
    fn default() -> Self {
        Self {
            restitution: Restitution::Housner,
            tolerance: Tolerance {
                rtol: 1e-10,
                atol: 1e-12,
            },
            max_step: 2e-3,
            rest_scan: 5e-4,
            rest_angular_speed: 1e-5,
            contact_tolerance: 1e-6,
            rigid_strain: 1e-4,
        }
    }
}

/// Does the reduced model honour every control of `scene` that changes the physics? The
/// controls (`scene::Control`) divide into
/// - physics: `kinetic_damping_rate` (velocities decay at that rate: viscous damping) and
///   `dynamic_factor` < 1 (velocities cut at every step: damping that depends on the step).
///   Neither is in the reduced models, so a scene setting them runs the full engine
///   (`auto`) or is refused (`rocking`, `sliding`); `Err` says which and why.
/// - run length and budget: `duration`, `output_interval`, `max_steps`: honoured by both.
/// - the full engine's numerical controls (`time_step`, `adaptive_time_step`,
///   `max_displacement_ratio`, `penalty_stiffness`, `integrator`, `contact_solver`,
///   `dual_tolerance`, `dual_stall_acceptance`): how the engine approximates the rigid-block
///   equations the reduced models solve to their own tolerance ([`ReducedParams::tolerance`]);
///   they do not apply, and `model_reason` says so when the scene sets them
///   ([`engine_controls_note`]).
/// - `block_model`: a deformable block stands for a rigid one only when stiff enough
///   ([`ReducedParams::rigid_strain`], checked by [`qualify`]).
/// - `restitution`: `"housner"` and 0 are the rocking model's Housner law; a coefficient
///   above 0 makes a landing corner bounce, which the reduced models do not represent.
pub fn represented(scene: &Scene) -> Result<(), NotReducible> {
    use crate::scene::Restitution;
    let c = &scene.control;
    let mut why = Vec::new();
    if c.kinetic_damping_rate != 0.0 {
        why.push(format!(
            "control.kinetic_damping_rate = {} 1/s damps every velocity, which the reduced models do not",
            c.kinetic_damping_rate
        ));
    }
    if c.dynamic_factor != 1.0 {
        why.push(format!(
            "control.dynamic_factor = {} carries only part of the velocity from step to step (a damping that depends on the step), which the reduced models do not",
            c.dynamic_factor
        ));
    }
    if c.restitution == Restitution::Contact {
        why.push(
            "control.restitution = \"contact\" leaves impacts to the full engine's contact springs (a rebound that depends on Δt), which the reduced models do not represent".to_string(),
        );
    }
    if let Restitution::Coefficient(e) = c.restitution {
        // e = 0 is Housner's law (an impact without bounce or slip, angular momentum about the
        // landing corner conserved), which the rocking model uses; with e > 0 the landing corner
        // bounces and the block leaves pure rocking (tests/engine/restitution.rs).
        if e > 0.0 {
            why.push(format!(
                "control.restitution = {e} makes a landing corner bounce off the base (Newton's law at the contact; for a rectangle ω⁺/ω⁻ = 1 − 1.5 (1 + e) sin²α, then free flight), which the reduced rocking model (pure rocking with Housner's impact, e = 0) does not represent"
            ));
        }
    }
    if why.is_empty() {
        Ok(())
    } else {
        Err(NotReducible::Controls(why))
    }
}

/// The full engine's numerical controls the scene sets, which a reduced run does not use: a
/// note for `model_reason` (empty when the scene sets none).
pub fn engine_controls_note(scene: &Scene) -> String {
    let c = &scene.spec.control;
    let set: Vec<&str> = [
        ("time_step", c.time_step.is_some()),
        ("adaptive_time_step", c.adaptive_time_step.is_some()),
        ("max_displacement_ratio", c.max_displacement_ratio.is_some()),
        ("penalty_stiffness", c.penalty_stiffness.is_some()),
        ("integrator", c.integrator.is_some()),
        ("contact_solver", c.contact_solver.is_some()),
        ("dual_tolerance", c.dual_tolerance.is_some()),
        ("dual_stall_acceptance", c.dual_stall_acceptance.is_some()),
        ("unconverged_floor", c.unconverged_floor.is_some()),
    ]
    .into_iter()
    .filter_map(|(name, given)| given.then_some(name))
    .collect();
    if set.is_empty() {
        String::new()
    } else {
        format!(
            "; the full engine's numerical controls the scene sets ({}) do not apply: the reduced model solves the same rigid-block equations to its own tolerance",
            set.join(", ")
        )
    }
}

/// Which motions the run may use.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Modes {
    /// Both, with the coupled cases reported as violations that stop the run (`auto`).
    Auto,
    /// Rocking only (`"model": "rocking"`): friction never lets the block slide.
    Rocking,
    /// Sliding only (`"model": "sliding"`): the block never rotates.
    Sliding,
}

/// The block's state.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Phase {
    Rest,
    /// On pivot 0 or 1: θ (rad) and ω (rad/s).
    Rocking {
        pivot: usize,
        theta: f64,
        omega: f64,
    },
    /// Slip rate (m/s) and direction (±1).
    Sliding {
        rate: f64,
        dir: f64,
    },
    /// Lying on another face after overturning about `pivot` at rotation `theta`.
    Fallen {
        pivot: usize,
        theta: f64,
    },
}

/// A case the reduced models do not represent, at time `time` (s).
#[derive(Debug, Clone, PartialEq)]
pub struct Violation {
    pub time: f64,
    pub what: String,
}

/// The model's state at the last record sample it passed within its assumptions (at rest,
/// rocking with the pivot's friction demand within μ, or sliding flat): a state the full engine
/// can start from (the block's pose and velocity, the record from `time` on), which
/// `analysis::run`'s fallback uses (`analysis::run_fallback`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct HandOver {
    /// s; a sample of the record (or 0).
    pub time: f64,
    pub phase: Phase,
    /// Accumulated slip along the local t axis, m.
    pub slip: f64,
    /// Total sliding distance so far, m.
    pub slid: f64,
}

/// Counters of a reduced run.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct ReducedStats {
    /// Accepted ODE steps plus at-rest scan steps.
    pub steps: u64,
    pub rejected_steps: u64,
    pub impacts: u64,
    /// Smallest and largest ODE step the error control chose, s (∞ and 0 while none was):
    /// steps cut short to end on a kink of the record, an output frame or a located event are
    /// not counted, since their length says nothing about the accuracy the control needed.
    pub min_dt: f64,
    pub max_dt: f64,
    /// Time of the first rocking and first sliding onset, s.
    pub first_rocking: Option<f64>,
    pub first_sliding: Option<f64>,
}

/// The running state of a reduced model. It borrows the motion: a search runs one model per
/// amplitude, and a copy of a record (its samples and their integrals) cost each run as much as
/// a few hundred of its steps.
#[derive(Debug, Clone)]
pub struct Reduced<'a> {
    pub block: SingleBlock,
    pub motion: &'a GroundMotion,
    pub params: ReducedParams,
    pub modes: Modes,
    pub time: f64,
    pub phase: Phase,
    /// Accumulated slip along t, m (shifts the block for rocking after sliding).
    pub slip: f64,
    /// Total sliding distance, m.
    pub slid: f64,
    h: f64,
    /// f at the end of the last ODE step, for the next one (FSAL).
    first_stage: Option<FirstStage>,
    /// s, the time at which the at-rest scan last found nothing starting (NaN: none yet): the
    /// next scan step starts there and need not check it again (the onset is a function of
    /// the time alone, so the check would give the same answer).
    quiet_at: f64,
    pub stats: ReducedStats,
    /// Violations met so far (only the first stops an `Auto` run; the forced models keep
    /// going and report them).
    pub violations: Vec<Violation>,
    /// The state at the last record sample (or t = 0) the model passed within its
    /// assumptions: kept only under piecewise-linear motions, whose samples the model's steps
    /// end on.
    pub hand_over: Option<HandOver>,
}

/// What would start at an instant: rocking on a pivot, sliding in a direction, loss of contact.
type Onset = (Option<usize>, Option<f64>, bool);

/// Which motion would start for a block at rest on its base under the load `a` (per unit mass,
/// local coordinates, m/s²): (rocking pivot, sliding direction, loss of contact), each only
/// for the motions `modes` admits.
fn onset_under(block: &SingleBlock, modes: Modes, a: Vector2<f64>) -> Onset {
    let lift = sliding::pressure(a) <= 0.0;
    let rock = if modes == Modes::Sliding {
        None
    } else {
        (0..2).find(|&k| rocking::tips(block, k, a))
    };
    let slide = if modes == Modes::Rocking {
        None
    } else {
        sliding::slips(block, a)
    };
    (rock, slide, lift)
}

/// Is nothing starting under the onset `o`? (Loss of contact only stops `Auto` runs; the
/// forced models keep the block on its base through it.)
fn quiet(modes: Modes, o: &Onset) -> bool {
    o.0.is_none() && o.1.is_none() && (!o.2 || modes != Modes::Auto)
}

/// Does a block at rest on its base stay at rest at `t` under `motion` (the `Auto` model: no
/// rocking, no sliding, no loss of contact starts)? The rule the reduced model applies at
/// rest, for a caller that wants to start it there (the hand-back).
pub(crate) fn stays_at_rest(block: &SingleBlock, motion: &GroundMotion, t: f64) -> bool {
    quiet(
        Modes::Auto,
        &onset_under(block, Modes::Auto, load_at(block, motion, t)),
    )
}

/// Bisection depth of event location: 2⁻⁶⁰ of a step is below round-off of the time.
const BISECTIONS: usize = 60;

/// Precision of a located event's time, s: 1e-13 s moves a state by ω·1e-13, below the ODE's
/// absolute tolerance for any angular or slip rate under 10 per second.
const EVENT_TIME: f64 = 1e-13;

/// Effective load per unit mass on `block` at t in its local coordinates (m/s²): gravity and
/// the inertial load −a_g of the moving base.
fn load_at(block: &SingleBlock, motion: &GroundMotion, t: f64) -> Vector2<f64> {
    let ag = motion.acceleration(t);
    block.to_local(Vector2::new(-ag[0], -block.gravity - ag[1]))
}

/// The load over one ODE step [t0, end] that ends at or before the motion's next kink
/// (`GroundMotion::next_kink`), per unit mass in local coordinates (m/s²). Under a record
/// (piecewise linear) it is linear in t there, so it is the line through its values at the
/// step's midpoint and end: two evaluations of the record a step instead of one per stage
/// (seven), exact up to round-off. The midpoint and not t0: at the record's end the
/// acceleration drops to zero right after t0, and the line must be that of the open interval.
/// Curved motions (pulses, sines) are evaluated at each stage.
enum StepLoad<'a> {
    Linear {
        end: f64,
        at_end: Vector2<f64>,
        slope: Vector2<f64>,
    },
    Exact {
        block: &'a SingleBlock,
        motion: &'a GroundMotion,
    },
}

impl<'a> StepLoad<'a> {
    fn new(block: &'a SingleBlock, motion: &'a GroundMotion, t0: f64, end: f64) -> Self {
        if motion.piecewise_linear() && end.is_finite() && end > t0 {
            let mid = 0.5 * (t0 + end);
            let at_end = load_at(block, motion, end);
            let slope = (at_end - load_at(block, motion, mid)) / (end - mid);
            StepLoad::Linear { end, at_end, slope }
        } else {
            StepLoad::Exact { block, motion }
        }
    }

    /// The load at `t` when `t` is the step's end and the load there is already known (under
    /// a record: the value [`StepLoad::new`] evaluated there, bit for bit what [`load_at`]
    /// gives), so the checks at the end of a step cut short by a sample need not evaluate the
    /// record again.
    fn at_end(&self, t: f64) -> Option<Vector2<f64>> {
        match self {
            StepLoad::Linear { end, at_end, .. } if t == *end => Some(*at_end),
            _ => None,
        }
    }

    #[inline]
    fn at(&self, t: f64) -> Vector2<f64> {
        match self {
            StepLoad::Linear { end, at_end, slope } => at_end + slope * (t - end),
            StepLoad::Exact { block, motion } => load_at(block, motion, t),
        }
    }
}

/// The first stage of the next ODE step, f(t, y) of the motion `tag` (pivot 0/1 for rocking,
/// 2/3 for sliding −/+), as the last stage of the step that ended at (t, y) left it
/// ([`ode::step_from`]). Used only where (t, y, tag) match bit for bit.
#[derive(Debug, Clone, Copy, PartialEq)]
struct FirstStage {
    t: f64,
    y: State,
    tag: u8,
    k: State,
}

/// One adaptive step of `f` from (t, y), ending at `end` at the latest. f(t, y) is taken from
/// `first` when the last step (of the same phase `tag`) ended exactly at (t, y), and `first`
/// is set to this step's end ([`ode::step_from`] returns f there). `h` is the step-size
/// proposal, updated for the next step. Returns the step taken, the new state, whether the
/// step was cut short to end exactly on `end` (the caller then sets its time to `end`), and
/// f(t, y) (for locating an event within the step).
#[allow(clippy::too_many_arguments)]
fn ode_step(
    h: &mut f64,
    stats: &mut ReducedStats,
    first: &mut Option<FirstStage>,
    tag: u8,
    params: &ReducedParams,
    f: &impl Fn(f64, State) -> State,
    t: f64,
    y: State,
    end: f64,
) -> (f64, State, bool, State) {
    let k1 = match *first {
        Some(fs) if fs.t == t && fs.y == y && fs.tag == tag => fs.k,
        _ => f(t, y),
    };
    loop {
        let proposal = h.min(params.max_step);
        let clipped = proposal >= end - t;
        let step = if clipped { end - t } else { proposal };
        let (y1, err, k7) = ode::step_from(f, t, y, k1, step, params.tolerance);
        if err <= 1.0 || step < 1e-12 {
            let next = ode::next_h(step, err).max(1e-12);
            // A step cut short by `end` must not shrink the next proposal.
            *h = if clipped { next.max(proposal) } else { next };
            stats.steps += 1;
            if !clipped {
                stats.min_dt = stats.min_dt.min(step);
                stats.max_dt = stats.max_dt.max(step);
            }
            *first = Some(FirstStage {
                t: t + step,
                y: y1,
                tag,
                k: k7,
            });
            return (step, y1, clipped, k1);
        }
        stats.rejected_steps += 1;
        *h = ode::next_h(step, err);
    }
}

/// Smallest step in (0, h] from (t, y) after which `crossed(state)` holds (it does not at the
/// start, it does after h), to [`EVENT_TIME`]. Each trial re-takes one step from the start, so
/// the state returned is a full fifth-order step. The trial steps come from the Illinois
/// variant of regula falsi on the event function `g` (positive before the event, ≤ 0 after:
/// a handful of trials instead of bisection's 60), with a bisection whenever it stalls.
#[allow(clippy::too_many_arguments)]
fn locate(
    f: &impl Fn(f64, State) -> State,
    tol: Tolerance,
    t: f64,
    y: State,
    k1: State,
    h: f64,
    g: impl Fn(&State) -> f64,
    crossed: impl Fn(&State) -> bool,
) -> (f64, State) {
    let (mut lo, mut glo) = (0.0, g(&y));
    let mut yh = ode::step_from(f, t, y, k1, h, tol).0;
    let (mut hi, mut ghi) = (h, g(&yh));
    // Which end the last trial replaced (Illinois halves the weight of an end kept twice).
    let mut last = 0i8;
    let mut stalls = 0;
    for _ in 0..BISECTIONS {
        let width = hi - lo;
        if width <= EVENT_TIME {
            break;
        }
        let secant = lo + width * glo / (glo - ghi);
        let mid = if stalls < 2 && glo > 0.0 && ghi <= 0.0 && secant > lo && secant < hi {
            secant
        } else {
            stalls = 0;
            0.5 * (lo + hi)
        };
        if mid <= lo || mid >= hi {
            break;
        }
        let ym = ode::step_from(f, t, y, k1, mid, tol).0;
        let gm = g(&ym);
        if crossed(&ym) {
            hi = mid;
            ghi = gm.min(0.0);
            yh = ym;
            if last == -1 {
                glo *= 0.5;
            }
            last = -1;
        } else {
            lo = mid;
            glo = gm.max(f64::MIN_POSITIVE);
            if last == 1 {
                ghi *= 0.5;
            }
            last = 1;
        }
        stalls = if hi - lo > 0.5 * width { stalls + 1 } else { 0 };
    }
    (hi, yh)
}

impl<'a> Reduced<'a> {
    pub fn new(
        block: SingleBlock,
        motion: &'a GroundMotion,
        params: ReducedParams,
        modes: Modes,
    ) -> Self {
        let v0 = block.initial_slip_rate;
        let phase = if v0 != 0.0 && modes != Modes::Rocking {
            Phase::Sliding {
                rate: v0,
                dir: v0.signum(),
            }
        } else {
            Phase::Rest
        };
        Self {
            h: params.max_step.min(1e-4),
            first_stage: None,
            quiet_at: f64::NAN,
            block,
            motion,
            params,
            modes,
            time: 0.0,
            phase,
            slip: 0.0,
            slid: 0.0,
            stats: ReducedStats {
                min_dt: f64::INFINITY,
                ..Default::default()
            },
            violations: Vec::new(),
            hand_over: (phase == Phase::Rest).then_some(HandOver {
                time: 0.0,
                phase,
                slip: 0.0,
                slid: 0.0,
            }),
        }
    }

    /// Effective load per unit mass at t in local coordinates (m/s²): gravity and the inertial
    /// load −a_g of the moving base.
    pub fn load(&self, t: f64) -> Vector2<f64> {
        load_at(&self.block, self.motion, t)
    }

    /// Keep the state now as the hand-over point (called at record samples where the state is
    /// within the model's assumptions).
    fn keep_hand_over(&mut self) {
        if self.motion.piecewise_linear() {
            self.hand_over = Some(HandOver {
                time: self.time,
                phase: self.phase,
                slip: self.slip,
                slid: self.slid,
            });
        }
    }

    fn violate(&mut self, time: f64, what: String) -> bool {
        if self.violations.len() < 8 {
            self.violations.push(Violation { time, what });
        }
        self.modes == Modes::Auto
    }

    /// Advance to `target` (s). Returns the violation that stopped an `Auto` run.
    pub fn advance(&mut self, target: f64) -> Result<(), Violation> {
        while self.time < target - 1e-12 {
            let stop = match self.phase {
                Phase::Rest => self.rest(target),
                Phase::Rocking { .. } => self.rock(target),
                Phase::Sliding { .. } => self.slide(target),
                Phase::Fallen { .. } => {
                    self.time = target;
                    false
                }
            };
            if stop {
                return Err(self.violations.last().cloned().unwrap_or(Violation {
                    time: self.time,
                    what: "unknown".into(),
                }));
            }
        }
        Ok(())
    }

    /// Which motion would start at t: (rocking pivot, sliding direction), each if any.
    fn onset(&self, t: f64) -> Onset {
        onset_under(&self.block, self.modes, self.load(t))
    }

    /// Is nothing starting under the onset `o`?
    fn quiet(&self, o: &Onset) -> bool {
        quiet(self.modes, o)
    }

    /// At rest: scan for the first instant a motion starts, locate it by bisection.
    fn rest(&mut self, target: f64) -> bool {
        let t0 = self.time;
        if t0 != self.quiet_at {
            let first = self.onset(t0);
            if !self.quiet(&first) {
                return self.start(t0, first);
            }
        }
        // Records: to the next sample (exact, see `ReducedParams::rest_scan`); curved motions:
        // one scan step.
        let kink = self.motion.next_kink(t0);
        let t1 = if self.motion.piecewise_linear() {
            kink.min(target)
        } else {
            (t0 + self.params.rest_scan).min(target)
        };
        let end = self.onset(t1);
        self.stats.steps += 1;
        if self.quiet(&end) {
            self.time = t1;
            self.quiet_at = t1;
            if t1 == kink {
                self.keep_hand_over();
            }
            return false;
        }
        // Bisection for each condition separately, so "both at once" is decided at the
        // precision of the time, not of the scan.
        let locate = |pred: &dyn Fn(&Onset) -> bool| {
            let (mut lo, mut hi) = (t0, t1);
            if !pred(&self.onset(hi)) {
                return f64::INFINITY;
            }
            for _ in 0..BISECTIONS {
                let mid = 0.5 * (lo + hi);
                if mid <= lo || mid >= hi {
                    break;
                }
                if pred(&self.onset(mid)) {
                    hi = mid;
                } else {
                    lo = mid;
                }
            }
            hi
        };
        let auto = self.modes == Modes::Auto;
        let tr = locate(&|o| o.0.is_some());
        let ts = locate(&|o| o.1.is_some());
        let tl = locate(&|o| o.2 && auto);
        let t = tr.min(ts).min(tl);
        let mut o = self.onset(t);
        if tr.is_finite() && ts.is_finite() && (tr - ts).abs() > 1e-9 {
            // Only the first of the two starts.
            if tr < ts {
                o.1 = None;
            } else {
                o.0 = None;
            }
        }
        self.time = t;
        self.start(t, o)
    }

    /// Start the motion `o` found at `t`. Returns true when an `Auto` run must stop.
    fn start(&mut self, t: f64, o: Onset) -> bool {
        if o.2 && self.modes == Modes::Auto {
            return self.violate(
                t,
                format!("the block loses contact (vertical load exceeds gravity) at t = {t:.6} s"),
            );
        }
        let mut o = o;
        if let (Some(k), Some(dir)) = (o.0, o.1) {
            // Both conditions hold (Yeung's region): a block whose leading corner stays down
            // while sliding slides; one whose pivot sticks at the onset of rocking rocks;
            // otherwise it slides and rocks together.
            if sliding::stays_flat(&self.block, dir) {
                o.0 = None;
            } else {
                let r = rocking::reaction(&self.block, k, 0.0, 0.0, self.load(t));
                if r.y > 0.0 && r.x.abs() <= self.block.mu * r.y {
                    o.1 = None;
                } else if self.violate(
                    t,
                    format!(
                        "rocking and sliding start together at t = {t:.6} s (the pivot would slip)"
                    ),
                ) {
                    return true;
                } else {
                    o.1 = None;
                }
            }
        }
        if let Some(dir) = o.1 {
            self.stats.first_sliding.get_or_insert(t);
            if self.modes == Modes::Auto && !sliding::stays_flat(&self.block, dir) {
                return self.violate(t, format!("the block slides at t = {t:.6} s and its leading corner lifts (friction angle above its slenderness angle): sliding and rocking together"));
            }
            self.phase = Phase::Sliding { rate: 0.0, dir };
        } else if let Some(k) = o.0 {
            self.stats.first_rocking.get_or_insert(t);
            self.phase = Phase::Rocking {
                pivot: k,
                theta: 0.0,
                omega: 0.0,
            };
        }
        false
    }

    fn rock(&mut self, target: f64) -> bool {
        let Phase::Rocking {
            pivot: k,
            theta,
            omega,
        } = self.phase
        else {
            return false;
        };
        let (b, motion, params, t0) = (&self.block, self.motion, self.params, self.time);
        let motion_kink = motion.next_kink(t0);
        let end = target.min(motion_kink);
        let load = StepLoad::new(b, motion, t0, end);
        let f = |t: f64, y: State| [y[1], rocking::angular_acceleration(b, k, y[0], load.at(t))];
        let s = rocking::side(k);
        let lift = 1e-9 * b.pivots[1];
        let landing = |y: &State| s * y[0];
        let landed = |y: &State| landing(y) < 0.0;
        let clearance = |y: &State| rocking::side_clearance(b, k, y[0], lift);
        let on_side = |y: &State| clearance(y) < 0.0;
        let y0 = [theta, omega];
        let tag = k as u8;
        let (h, y1, clipped, k1) = ode_step(
            &mut self.h,
            &mut self.stats,
            &mut self.first_stage,
            tag,
            &params,
            &f,
            t0,
            y0,
            end,
        );
        if landed(&y1) {
            let (h, y) = locate(&f, params.tolerance, t0, y0, k1, h, landing, landed);
            self.time += h;
            let w = rocking::restitution(b, k, params.restitution) * y[1];
            self.stats.impacts += 1;
            self.phase = if w.abs() < self.params.rest_angular_speed {
                Phase::Rest
            } else {
                Phase::Rocking {
                    pivot: 1 - k,
                    theta: 0.0,
                    omega: w,
                }
            };
            // The step size carries over: the motion after the impact is as smooth as before.
            return false;
        }
        if on_side(&y1) {
            let (h, y) = locate(&f, params.tolerance, t0, y0, k1, h, clearance, on_side);
            let b = self.block.clone();
            self.time += h;
            if !rocking::beyond_tipping(&b, k, y[0]) {
                let t = self.time;
                if self.violate(
                    t,
                    format!(
                        "another face of the block reaches the base while rocking at t = {t:.6} s"
                    ),
                ) {
                    return true;
                }
            }
            self.phase = Phase::Fallen {
                pivot: k,
                theta: y[0],
            };
            return false;
        }
        self.time = if clipped { end } else { t0 + h };
        self.phase = Phase::Rocking {
            pivot: k,
            theta: y1[0],
            omega: y1[1],
        };
        let b = &self.block;
        if self.modes != Modes::Sliding {
            let a = load
                .at_end(self.time)
                .unwrap_or_else(|| self.load(self.time));
            let r = rocking::reaction(b, k, y1[0], y1[1], a);
            let t = self.time;
            if r.y < 0.0 {
                return self.violate(
                    t,
                    format!("the pivot loses contact (the block would jump) at t = {t:.6} s"),
                );
            }
            if self.modes == Modes::Auto
                && r.x.abs() > b.mu * r.y
                && !rocking::beyond_tipping(b, k, y1[0])
            {
                let what = format!("the pivot slips while rocking at t = {t:.6} s (friction demand {:.3} above μ = {:.3}): sliding and rocking together", r.x.abs() / r.y, b.mu);
                return self.violate(t, what);
            }
        }
        if clipped && end == motion_kink {
            self.keep_hand_over();
        }
        false
    }

    fn slide(&mut self, target: f64) -> bool {
        let Phase::Sliding { rate, dir } = self.phase else {
            return false;
        };
        let (b, motion, params, t0) = (&self.block, self.motion, self.params, self.time);
        let motion_kink = motion.next_kink(t0);
        let end = target.min(motion_kink);
        let load = StepLoad::new(b, motion, t0, end);
        let f = |t: f64, y: State| [y[1], sliding::acceleration(b, dir, load.at(t))];
        let speed = |y: &State| dir * y[1];
        let stopped = |y: &State| speed(y) <= 0.0;
        let y0 = [self.slip, rate];
        let tag = if dir > 0.0 { 3 } else { 2 };
        let (h, y1, clipped, k1) = ode_step(
            &mut self.h,
            &mut self.stats,
            &mut self.first_stage,
            tag,
            &params,
            &f,
            t0,
            y0,
            end,
        );
        let (t1, y1) = if stopped(&y1) {
            let (h, y) = locate(&f, params.tolerance, t0, y0, k1, h, speed, stopped);
            (t0 + h, y)
        } else if clipped {
            (end, y1)
        } else {
            (t0 + h, y1)
        };
        let b = self.block.clone();
        self.time = t1;
        self.slid += (y1[0] - self.slip).abs();
        self.slip = y1[0];
        if stopped(&y1) {
            let a = self.load(self.time);
            self.phase = match sliding::slips(&b, a) {
                Some(d) if d != dir => Phase::Sliding { rate: 0.0, dir: d },
                _ => Phase::Rest,
            };
        } else {
            self.phase = Phase::Sliding { rate: y1[1], dir };
        }
        if sliding::pressure(self.load(self.time)) <= 0.0 {
            let t = self.time;
            return self.violate(
                t,
                format!("the block loses contact (vertical load exceeds gravity) at t = {t:.6} s"),
            );
        }
        if self.time == motion_kink {
            self.keep_hand_over();
        }
        false
    }

    /// Local centroid displacement (m), rotation (rad) and their rates (m/s, rad/s).
    pub fn kinematics(&self) -> (Vector2<f64>, f64, Vector2<f64>, f64) {
        let b = &self.block;
        let slip = Vector2::new(self.slip, 0.0);
        match self.phase {
            Phase::Rest => (slip, 0.0, Vector2::zeros(), 0.0),
            Phase::Sliding { rate, .. } => (slip, 0.0, Vector2::new(rate, 0.0), 0.0),
            Phase::Rocking {
                pivot,
                theta,
                omega,
            } => {
                let c = rocking::centroid(b, pivot, theta, self.slip);
                let r = c - Vector2::new(b.pivots[pivot] + self.slip, 0.0);
                (
                    c - b.centroid,
                    theta,
                    Vector2::new(-r.y, r.x) * omega,
                    omega,
                )
            }
            Phase::Fallen { pivot, theta } => {
                let c = rocking::centroid(b, pivot, theta, self.slip);
                (c - b.centroid, theta, Vector2::zeros(), 0.0)
            }
        }
    }

    /// Local outline of the block now.
    pub fn outline(&self) -> Vec<Vector2<f64>> {
        match self.phase {
            Phase::Rocking { pivot, theta, .. } | Phase::Fallen { pivot, theta } => {
                rocking::vertices(&self.block, pivot, theta, self.slip)
            }
            _ => self
                .block
                .vertices
                .iter()
                .map(|v| v + Vector2::new(self.slip, 0.0))
                .collect(),
        }
    }
}
