//! Shaken masonry benchmark and contact-solve diagnostics (docs/contact-solve.md): running-bond
//! walls of 0.6 × 0.3 m rigid stones (`scene::generate::running_bond_wall`, 35° dry joints) on a
//! fixed foundation, at rest, under a base sine of 1 m/s² at 1 Hz, and under the Northridge
//! (Mulholland 009) record of `data/ground-motions/` scaled to a PGA of 0.3 g and started 0.2 s
//! before its peak (so a short run sees the strong motion); `sine3` is a base sine of 3 m/s² at
//! 2 Hz. Δt = 1 ms with the default (adaptive) time-step control. A wall is first settled
//! under gravity alone, as a user's wall is built at rest, and the record is tapered in over
//! `--lead-in` s (0.1) before its start (`settle`, `tapered_in`; `--no-settle` drops the wall
//! onto its springs from zero contact forces as the record starts mid-way with a step of its
//! acceleration, as before session 35); the row counts only the steps from the start on
//! (docs/contact-solve.md §21). Prints one Markdown row per wall and motion: s/step, linear
//! solves a step, Δt cuts, the deepest penetration; `--diag` adds why the open–close loop
//! iterated (`ChangeCounts`), why steps were refused and the time per stage.
//!
//! `cargo run --release --example shaken_walls -- [--sizes 100,400,1600] [--steps 300]
//!  [--motions rest,sine,record] [--diag] [--tight] [--block-model rigid|deformable] [--poisson V]
//!  [--anderson DEPTH] [--anderson-restart] [--legacy] [--reference] [--record-start T]
//!  [--seconds S] [--settle TOL] [--settle-after K] [--light-states on|off] [--light-tilt DEG]
//!  [--stone-settle TOL] [--stone-settle-state TOL] [--stone-settle-after K]
//!  [--stone-settle-interfaces N] [--stone-settle-neighbours] [--weight-scale on|off]
//!  [--cycle-flips N] [--cycle-after K] [--cycle-extra E] [--cycle-interface on|off]
//!  [--cycle-tilt DEG]
//!  [--time-step DT] [--closing F]
//!  [--closing-floor R]
//!  [--light-interface on|off] [--simplicial] [--triangular faer|repacked] [--ordering scalar|block-amd|dissection|coordinates]
//!  [--relax faer|none|wide] [--dissection-leaf N] [--start-check K] [--start-check-audit]
//!  [--digest] [--no-settle] [--settle-max S] [--lead-in S] [--motions …,sine3]
//!  [--wall-set length=12,height=6,openings=0] [--record FILE] [--pga G] [--window S]
//!  [--unconverged-floor R] [--floor-hold on|off] [--floor-penetration F]
//!  [--floor-iterations N] [--min-located R] [--growth G] [--impact-cluster on|off]
//!  [--friction-predict GAIN|off] [--stick-predict GAIN|off] [--slip-predict GAIN|off]
//!  [--gap-predict GAIN|off] [--head-slip-predict GAIN|off] [--head-slip-margin M]
//!  [--head-slip-guard steady,shear,spin,calm] [--first-kinds]`
//!
//! `--wall-set`, `--record`/`--pga`, `--window S` (a line of counters every S simulated
//! seconds) and the knobs `--unconverged-floor`, `--min-located`, `--growth` are the wall shaken
//! to collapse of docs/contact-solve.md §24.
//!
//! `--start-check K` sets `SparseParams::start_check_samples` (cheaper start of a
//! reused-factor solve, default 2; 0 = the exact test at every start), `--start-check-audit`
//! counts the accepted starts the exact test rejects (`SparseParams::start_check_audit`);
//! `--simplicial` turns off faer's supernodal factorization (`SparseParams::supernodal`);
//! `--triangular` chooses the triangular solves (`SparseParams::triangular`: faer's, or the
//! repacked copy of its factor, docs/contact-solve.md §35);
//! `--ordering`, `--relax` and `--dissection-leaf` choose its ordering and supernode
//! amalgamation (`SparseParams::ordering`, `relax`, `dissection_leaf`);
//! `--digest` prints a hash of every vertex and velocity at the end (bit-identity checks).
//!
//! `--stick-predict` and `--slip-predict` set the stick–slip prediction's gains
//! (`OpenCloseParams::stick_predict`, `slip_predict`, docs/contact-solve.md §32; `off` turns it
//! off); `--gap-predict GAIN|off` the head joints' gap prediction (`OpenCloseParams::gap_predict`,
//! §33); `--head-slip-predict GAIN|off` the head joints' onset of slip
//! (`OpenCloseParams::head_slip_predict`, §34; off by default), `--head-slip-margin M` its
//! threshold's factor and `--head-slip-guard` its rocking guards (§36); `--first-kinds` prints, for the measured steps, the sets of change kinds the first
//! solve of a step found and the steps and solves each set cost.
//!
//! `--anderson 0` turns off the Anderson acceleration of the friction fixed point (the plain
//! fixed-point loop); `--anderson-restart` restarts its history whenever a contact changes state.
//!
//! `--tight`: the reference configuration of docs/contact-solve.md (Δt = 1e-4 s, the open–close
//! loop run to convergence with the previous defaults of `OpenCloseParams::legacy`).
use ashlar::analysis::run_end::{self, RunEndParams};
use ashlar::motion::{self, GroundMotion, Sampled, Signal};
use ashlar::presets;
use ashlar::scene::generate::WallParams;
use ashlar::scene::{validate, BlockModel};
use ashlar::simulation::{SimParams, Simulation};
use ashlar::solve::open_close::CHANGE_KINDS;
use ashlar::solve::{SparseOrdering, SupernodeRelax, TriangularSolve};
use std::time::Instant;

#[path = "support/args.rs"]
mod args;
use args::arg;

/// Courses and whole blocks a course of a wall of about `n` stones: √n × √n, as
/// `examples/engine_scaling.rs` (100 → 105 stones, 400 → 410, 1600 → 1620, 6400 → 6440).
fn layout(n: usize) -> (usize, usize) {
    let side = ((n as f64).sqrt().round() as usize).max(2);
    (side, side)
}

fn record() -> GroundMotion {
    presets::shaken_wall_record().expect("the repository's Northridge record")
}

/// The settling phase before the motion (docs/contact-solve.md §21).
struct Settled {
    steps: u64,
    solves: u64,
    cuts: u64,
    /// Simulated time it took, s.
    time: f64,
    /// Every stone quiet for `RunEndParams::settle_window` (else stopped at the cap).
    quiet: bool,
}

/// `gm` at rest until `start − lead`, tapered in over `lead` s (a(t)·(1 − cos(π τ/lead))/2,
/// τ the time since `start − lead`), the record's own from `start` on. Starting a record
/// mid-way is a step of the ground's acceleration (−0.96 m/s² at the Northridge row's start),
/// a load no user's run sees: `ashlar run` starts a record at its t = 0, where it grows from
/// the noise. Returns the motion and the end of its quiet part (one sample before the taper,
/// so that the interpolation between the last zero and the first tapered sample is not inside
/// settling). Analytic signals (the sines, zero before t = 0) are left as they are.
fn tapered_in(gm: &GroundMotion, start: f64, lead: f64) -> (GroundMotion, f64) {
    let mut gm = gm.clone();
    let mut quiet_end = start;
    for sig in [&mut gm.horizontal, &mut gm.vertical] {
        if let Signal::Sampled(s) = sig {
            let mut a = s.accel.clone();
            for (i, x) in a.iter_mut().enumerate() {
                let tau = i as f64 * s.dt - (start - lead);
                if tau < 0.0 {
                    *x = 0.0;
                } else if tau < lead {
                    *x *= 0.5 * (1.0 - (std::f64::consts::PI * tau / lead).cos());
                }
            }
            quiet_end = quiet_end.min(start - lead - s.dt);
            *s = Sampled::new(s.dt, a);
        }
    }
    (gm, quiet_end)
}

/// Settles the freshly built wall under gravity alone (the ground is still: `tapered_in`):
/// steps from `quiet_end − max_time` until every stone is quiet (kinetic energy below
/// `RunEndParams::settle_energy_ratio` · m g L, the run-end rule of `ashlar run`) for
/// `settle_window`, or `quiet_end` is reached; then sets the clock to `start`, where the motion
/// begins. Why settle rather than preload the springs with static forces: the settled state is
/// the engine's own equilibrium (no second method to keep consistent), and its cost is outside
/// the measured row.
fn settle(sim: &mut Simulation, quiet_end: f64, start: f64, max_time: f64) -> Settled {
    let s0 = sim.stats();
    let t0 = quiet_end - max_time;
    sim.set_time(t0);
    let end_params = RunEndParams::default();
    let mut quiet_since: Option<f64> = None;
    let mut quiet = false;
    while sim.time() < quiet_end - 1e-12 {
        if let Err(e) = sim.step(quiet_end - sim.time()) {
            eprintln!("  settling stopped at t = {:.4} s: {e}", sim.time());
            break;
        }
        if run_end::all_quiet(sim, &end_params) {
            let since = *quiet_since.get_or_insert(sim.time());
            if sim.time() - since >= end_params.settle_window {
                quiet = true;
                break;
            }
        } else {
            quiet_since = None;
        }
    }
    let s = sim.stats();
    let settled = Settled {
        steps: s.steps - s0.steps,
        solves: s.open_close_iterations - s0.open_close_iterations,
        cuts: s.time_step_cuts - s0.time_step_cuts,
        time: sim.time() - t0,
        quiet,
    };
    sim.set_time(start);
    settled
}

/// The deepest penetration of a closed contact after the last step, m (what
/// `Stats::max_penetration` takes the maximum of, read here so the row excludes settling).
fn penetration(sim: &Simulation) -> f64 {
    sim.contacts()
        .contacts
        .iter()
        .filter(|c| c.state.is_closed())
        .fold(0.0, |p, c| p.max(-c.gap))
}

/// One window's counters (`--window S`, docs/contact-solve.md §24): the totals at its start.
struct WindowStart {
    time: f64,
    stats: ashlar::simulation::Stats,
    refusals: [u64; 4],
    factorizations: u64,
    profile: ashlar::simulation::StepProfile,
    changes: [[u64; 2]; 7],
    min_dt: f64,
    wall: Instant,
}

impl WindowStart {
    fn at(sim: &Simulation) -> Self {
        Self {
            time: sim.time(),
            stats: sim.stats(),
            refusals: sim.refusals(),
            factorizations: sim.solver_counts().numeric,
            profile: sim.profile(),
            changes: sim.changes().by_kind,
            min_dt: f64::INFINITY,
            wall: Instant::now(),
        }
    }
}

/// Prints one window's line (`--window S`): steps, mean and smallest Δt, cuts by the reason of
/// the refused attempt, open–close iterations and factorizations a step, the contacts at its
/// end (closed = locked + sliding, and those whose vertex is within 1 % of an edge end: the
/// vertex–vertex corners), stones moving faster than 1 cm/s, the time per stage and the state
/// changes by kind.
fn window_line(sim: &Simulation, w: &WindowStart) {
    let s = sim.stats();
    let steps = (s.steps - w.stats.steps).max(1) as f64;
    let r = sim.refusals();
    let p = sim.profile();
    let (mut locked, mut sliding, mut open, mut corner) = (0, 0, 0, 0);
    for c in &sim.contacts().contacts {
        match c.state {
            ashlar::contact::ContactState::Open => open += 1,
            ashlar::contact::ContactState::Locked => locked += 1,
            ashlar::contact::ContactState::Sliding { .. } => sliding += 1,
        }
        if c.state.is_closed() && (c.xi < 0.01 || c.xi > 0.99) {
            corner += 1;
        }
    }
    // Relative to the foundation (block 0, driven with the ground): speed and displacement.
    let v0 = sim.block_velocity(0);
    let moving = (1..sim.geoms().len())
        .filter(|&b| {
            let v = sim.block_velocity(b);
            (v[0] - v0[0]).hypot(v[1] - v0[1]) > 0.01
        })
        .count();
    let shift = |b: usize| sim.geoms()[b].vertices[0] - sim.scene().blocks[b].vertices[0];
    let (mut displaced, mut drop, mut rise) = (0, 0.0f64, 0.0f64);
    for b in 1..sim.geoms().len() {
        let d = shift(b) - shift(0);
        if d.norm() > 0.01 {
            displaced += 1;
        }
        drop = drop.max(-d.y);
        rise = rise.max(d.y);
    }
    let e = sim.energy();
    let ch = sim.changes().by_kind;
    let kinds: Vec<u64> = (0..7)
        .map(|k| ch[k][0] + ch[k][1] - w.changes[k][0] - w.changes[k][1])
        .collect();
    let secs = |a: std::time::Duration, b: std::time::Duration| (a - b).as_secs_f64();
    eprintln!(
        "  window {:.2}–{:.2} s: steps {}, Δt mean {:.2e} min {:.2e}, cuts {} (unconverged {}, moved {}, overshot {}, bound {}), taken unconverged {} (refused by the penetration bound {}), located steps {}, impacts {}, solves/step {:.2}, factorizations/step {:.2}, closing-limited {}, contacts locked {} sliding {} open {} corner {}, moving {} (>1 cm/s), displaced {} (>1 cm), largest drop {:.3} m rise {:.2e} m, gravity energy {:.6e} J, springs {:.3e} J, max penetration {:.2e} m, wall {:.1} s (detect {:.1}, assemble {:.1}, solve {:.1}, integrate {:.1}), changes by kind {:?}",
        w.time,
        sim.time(),
        s.steps - w.stats.steps,
        (sim.time() - w.time) / steps,
        w.min_dt,
        s.time_step_cuts - w.stats.time_step_cuts,
        r[0] - w.refusals[0],
        r[1] - w.refusals[1],
        r[2] - w.refusals[2],
        r[3] - w.refusals[3],
        s.unconverged_taken - w.stats.unconverged_taken,
        s.unconverged_floor_refused - w.stats.unconverged_floor_refused,
        s.located_steps - w.stats.located_steps,
        s.impacts - w.stats.impacts,
        (s.open_close_iterations - w.stats.open_close_iterations) as f64 / steps,
        (sim.solver_counts().numeric - w.factorizations) as f64 / steps,
        s.closing_limited_steps - w.stats.closing_limited_steps,
        locked,
        sliding,
        open,
        corner,
        moving,
        displaced,
        drop,
        rise,
        e.gravity,
        e.springs,
        s.max_penetration,
        w.wall.elapsed().as_secs_f64(),
        secs(p.detect, w.profile.detect),
        secs(p.assemble, w.profile.assemble),
        secs(p.solve, w.profile.solve),
        secs(p.integrate, w.profile.integrate),
        kinds
    );
}

/// The measured steps (kept out of line: `valgrind --tool=callgrind --collect-atstart=no
/// --toggle-collect='*measured_steps*'` counts them alone, without building or settling).
/// Returns (steps, smallest step, deepest penetration).
#[inline(never)]
fn measured_steps(
    sim: &mut Simulation,
    steps: usize,
    end: Option<f64>,
    label: &str,
) -> (usize, f64, f64) {
    let mut done = 0;
    let mut min_dt = f64::INFINITY;
    let mut deepest: f64 = 0.0;
    let window: Option<f64> = arg("--window").map(|v| v.parse().expect("--window"));
    let mut w = WindowStart::at(sim);
    // `--first-kinds` (§32): per set of change kinds the first solve of a step found, the
    // steps and their solves.
    let first_kinds = std::env::args().any(|a| a == "--first-kinds");
    let mut masks: std::collections::BTreeMap<u16, (u64, u64)> = Default::default();
    loop {
        if let Some(len) = window {
            if sim.time() >= w.time + len - 1e-12 {
                window_line(sim, &w);
                w = WindowStart::at(sim);
            }
        }
        match end {
            Some(end) if sim.time() >= end - 1e-12 => break,
            None if done >= steps => break,
            _ => {}
        }
        let max_dt = end.map_or(f64::INFINITY, |end| end - sim.time());
        let before = (
            sim.stats().open_close_iterations,
            sim.stats().time_step_cuts,
        );
        let first_before = sim.changes().by_kind_iteration;
        match sim.step(max_dt) {
            Ok(dt) => {
                min_dt = min_dt.min(dt);
                w.min_dt = w.min_dt.min(dt);
                if first_kinds {
                    // The kinds (× bed/head) the step's first solve found changing.
                    let now = &sim.changes().by_kind_iteration;
                    let mut mask = 0u16;
                    for k in 0..CHANGE_KINDS.len() {
                        for o in 0..2 {
                            if now[k][o][0] > first_before[k][o][0] {
                                mask |= 1 << (2 * k + o);
                            }
                        }
                    }
                    let e = masks.entry(mask).or_insert((0u64, 0u64));
                    e.0 += 1;
                    e.1 += sim.stats().open_close_iterations - before.0;
                }
                // `--step-log`: one line a step (time, Δt, solves, cuts, the closing
                // contacts and their largest approach / elastic range, with `--closing`).
                if std::env::args().any(|a| a == "--step-log") {
                    let (n, ratio) = sim.last_closing();
                    eprintln!(
                        "  step {done}: t {:.5} s, dt {dt:.2e} s, solves {}, cuts {}, closing {n}, approach/range {ratio:.3e}",
                        sim.time(),
                        sim.stats().open_close_iterations - before.0,
                        sim.stats().time_step_cuts - before.1
                    );
                }
            }
            Err(e) => {
                eprintln!("  {label}: stopped after {done} steps: {e}");
                break;
            }
        }
        deepest = deepest.max(penetration(sim));
        done += 1;
    }
    if window.is_some() && sim.stats().steps > w.stats.steps {
        window_line(sim, &w);
    }
    if first_kinds {
        print_first_kinds(&masks);
    }
    (done, min_dt, deepest)
}

/// `--first-kinds`: the steps by the set of change kinds their first solve found (the
/// extra solves a prediction of those kinds could save), most solves first; then, per kind,
/// the steps whose first solve found only that kind, and the steps without any change.
fn print_first_kinds(masks: &std::collections::BTreeMap<u16, (u64, u64)>) {
    let name = |bit: usize| {
        format!(
            "{} {}",
            CHANGE_KINDS[bit / 2],
            if bit % 2 == 0 { "bed" } else { "head" }
        )
    };
    let mut rows: Vec<_> = masks.iter().collect();
    rows.sort_by_key(|(_, &(_, solves))| std::cmp::Reverse(solves));
    eprintln!("  first solve's change kinds (steps, solves):");
    for (mask, (steps, solves)) in rows.iter().take(15) {
        let kinds: Vec<String> = (0..16)
            .filter(|b| *mask & (1 << b) != 0)
            .map(name)
            .collect();
        eprintln!(
            "    {steps:>6} steps, {solves:>7} solves: [{}]",
            kinds.join(", ")
        );
    }
    for bit in 0..2 * CHANGE_KINDS.len() {
        let (steps, solves) = masks
            .iter()
            .filter(|(m, _)| **m == 1 << bit)
            .fold((0, 0), |a, (_, v)| (a.0 + v.0, a.1 + v.1));
        let any = masks
            .iter()
            .filter(|(m, _)| **m & (1 << bit) != 0)
            .fold(0, |a, (_, v)| a + v.0);
        if any > 0 {
            eprintln!(
                "    {:>32}: in {any} steps, the only kind in {steps} ({solves} solves)",
                name(bit)
            );
        }
    }
}

/// Runs the tight reference (Δt = 1e-4 s fixed, the previous open–close loop run to
/// convergence) over the same simulated time as `sim` and prints the largest difference of a
/// stone's position (any vertex, m) and the deepest penetration of both.
fn compare_with_reference(
    sim: &Simulation,
    scene: &ashlar::scene::Scene,
    gm: &GroundMotion,
    start: f64,
    settling: Option<(f64, f64)>,
) {
    let mut params = SimParams {
        open_close: ashlar::solve::open_close::OpenCloseParams::legacy(),
        ..Default::default()
    };
    params.open_close.max_iterations = 200;
    let mut scene = scene.clone();
    scene.control.time_step = 1e-4;
    scene.control.adaptive_time_step = false;
    let mut reference = Simulation::new(&scene, gm, params);
    reference.set_time(start);
    // Settled the same way as the run (`settling`: quiet end and cap, s).
    if let Some((quiet_end, max_time)) = settling {
        settle(&mut reference, quiet_end, start, max_time);
    }
    while reference.time() < sim.time() - 1e-12 {
        let left = sim.time() - reference.time();
        if let Err(e) = reference.step(left) {
            eprintln!("  reference stopped at t = {:.4} s: {e}", reference.time());
            return;
        }
    }
    let mut worst: f64 = 0.0;
    let mut moved: f64 = 0.0;
    for (b, (g, r)) in sim.geoms().iter().zip(reference.geoms()).enumerate() {
        let s0 = &scene.blocks[b].vertices;
        for ((v, w), v0) in g.vertices.iter().zip(&r.vertices).zip(s0) {
            worst = worst.max((v - w).norm());
            moved = moved.max((w - v0).norm());
        }
    }
    println!(
        "  reference (Δt 1e-4 s, {} steps, {:.2} iterations/step): largest vertex difference {:.3e} m; largest vertex displacement in the reference {:.3e} m; max penetration {:.2e} m (reference) vs {:.2e} m",
        reference.stats().steps,
        reference.stats().open_close_iterations as f64 / reference.stats().steps as f64,
        worst,
        moved,
        reference.stats().max_penetration,
        sim.stats().max_penetration
    );
}

/// FNV-1a of the bits of every vertex and velocity (`--digest`): equal digests mean a change
/// left the run bit-identical.
fn state_digest(sim: &Simulation) -> u64 {
    let mut h: u64 = 0xcbf2_9ce4_8422_2325;
    let mut eat = |x: f64| {
        for byte in x.to_bits().to_le_bytes() {
            h = (h ^ u64::from(byte)).wrapping_mul(0x0000_0100_0000_01b3);
        }
    };
    for g in sim.geoms() {
        for v in &g.vertices {
            eat(v.x);
            eat(v.y);
        }
    }
    for st in sim.states() {
        st.vel.iter().chain(st.acc.iter()).for_each(|&x| eat(x));
    }
    eat(sim.time());
    h
}

fn main() {
    let sizes: Vec<usize> = arg("--sizes")
        .unwrap_or_else(|| "100,400,1600".into())
        .split(',')
        .map(|s| s.trim().parse().expect("--sizes: stone counts"))
        .collect();
    let steps: usize = arg("--steps")
        .map(|s| s.parse().expect("--steps"))
        .unwrap_or(300);
    let motions = arg("--motions").unwrap_or_else(|| "rest,sine,record".into());
    let diag = std::env::args().any(|a| a == "--diag");
    let tight = std::env::args().any(|a| a == "--tight");
    let model = match arg("--block-model").as_deref() {
        Some("deformable") => BlockModel::Deformable,
        _ => BlockModel::Rigid,
    };
    // `--record FILE [--pga G]`: a record of `data/ground-motions` scaled to a PGA of G g
    // (0.3 g, the shaken walls' record, unless given) instead of Northridge at 0.3 g.
    let rec = match arg("--record") {
        Some(f) => {
            let pga: f64 = arg("--pga").map_or(0.3, |v| v.parse().expect("--pga"));
            presets::record(&f)
                .expect("--record: a record of data/ground-motions")
                .scaled_to_pga(pga * motion::STANDARD_GRAVITY)
        }
        None => record(),
    };
    // `--record-start T`: start the record at T s (default 0.2 s before its peak); with
    // `--seconds S` the run covers S s of simulated time instead of `--steps` steps (the
    // whole-record run of docs/contact-solve.md §8: `--record-start 0 --seconds 20`).
    let rec_start = arg("--record-start")
        .map(|v| v.parse().expect("--record-start"))
        .unwrap_or_else(|| (motion::peak_time(&rec, 1e-3) - 0.2).max(0.0));
    let seconds: Option<f64> = arg("--seconds").map(|v| v.parse().expect("--seconds"));
    println!(
        "| stones | motion | steps | s/step | linear solves/step | open–close iterations/step | Δt cuts | min Δt (s) | max penetration (m) |"
    );
    println!("|---|---|---|---|---|---|---|---|---|");
    for &n in &sizes {
        let (courses, per) = layout(n);
        for m in motions.split(',') {
            let mut spec = presets::wall_of(&WallParams {
                courses,
                blocks_per_course: per,
                block_model: model,
                ..Default::default()
            });
            if tight {
                spec.control.time_step = Some(1e-4);
            }
            // `--poisson V`: the stones' Poisson ratio (deformable walls: docs/contact-solve.md §7).
            if let Some(v) = arg("--poisson") {
                for m in spec.materials.values_mut() {
                    m.poisson_ratio = v.parse().expect("--poisson");
                }
            }
            let mut scene = validate(&spec).expect("wall");
            // `--wall-set length=12,height=6,openings=0`: the `ashlar scene wall` template with
            // these values instead of the √n × √n wall (the walls a PGA search runs, §24).
            if let Some(v) = arg("--wall-set") {
                let given: std::collections::BTreeMap<String, serde_json::Value> = v
                    .split(',')
                    .map(|kv| {
                        let (k, x) = kv.split_once('=').expect("--wall-set KEY=VALUE,…");
                        (k.to_string(), serde_json::Value::String(x.to_string()))
                    })
                    .collect();
                scene = ashlar::scene::templates::build("wall", &given)
                    .expect("--wall-set: the wall template")
                    .1;
            }
            // `--time-step DT`: a fixed Δt, s, as the tight reference's (separates the Δt
            // error from a loop variant's, docs/contact-solve.md §18).
            if let Some(v) = arg("--time-step") {
                scene.control.time_step = v.parse().expect("--time-step");
                scene.control.adaptive_time_step = false;
            }
            let (gm, start) = match m {
                "rest" => (GroundMotion::none(), 0.0),
                "sine" => (
                    GroundMotion::horizontal(Signal::Sine {
                        amplitude: 1.0,
                        frequency: 1.0,
                    }),
                    0.0,
                ),
                "sine3" => (
                    GroundMotion::horizontal(Signal::Sine {
                        amplitude: 3.0,
                        frequency: 2.0,
                    }),
                    0.0,
                ),
                "record" => (rec.clone(), rec_start),
                other => panic!("--motions: unknown {other:?} (rest, sine, sine3, record)"),
            };
            let mut params = SimParams::default();
            if let Some(v) = arg("--reuse-rule") {
                // "off": the fixed cap alone decides (the rule before session 34).
                if v == "off" {
                    params.solver.sparse.cost_rule_min_work = f64::INFINITY;
                }
            }
            if let Some(v) = arg("--factor-weight") {
                params.solver.sparse.factor_work_weight = v.parse().expect("--factor-weight");
            }
            if std::env::args().any(|a| a == "--legacy") {
                params.open_close = ashlar::solve::open_close::OpenCloseParams::legacy();
            }
            if std::env::args().any(|a| a == "--no-secant") {
                params.open_close.secant_friction = false;
            }
            if let Some(v) = arg("--force-tol") {
                params.open_close.force_tolerance = v.parse().expect("--force-tol");
            }
            if let Some(v) = arg("--hysteresis") {
                params.open_close.hysteresis = v.parse().expect("--hysteresis");
            }
            if let Some(v) = arg("--max-iterations") {
                params.open_close.max_iterations = v.parse().expect("--max-iterations");
            }
            if let Some(v) = arg("--max-flips") {
                params.open_close.max_flips = v.parse().expect("--max-flips");
            }
            if let Some(v) = arg("--relax-after") {
                params.open_close.relax_after = v.parse().expect("--relax-after");
            }
            if let Some(v) = arg("--anderson") {
                params.open_close.anderson_depth = v.parse().expect("--anderson");
            }
            if std::env::args().any(|a| a == "--anderson-restart") {
                params.open_close.anderson_keep = false;
            }
            if let Some(v) = arg("--settle") {
                params.open_close.settle_tolerance = v.parse().expect("--settle");
            }
            if let Some(v) = arg("--settle-after") {
                params.open_close.settle_after = v.parse().expect("--settle-after");
            }
            // `--light-states on|off`: state changes of lightly loaded contacts skip the solve
            // below the force tolerance (`OpenCloseParams::light_state_changes`, §11; on by
            // default since §12).
            if let Some(v) = arg("--light-states") {
                params.open_close.light_state_changes = v == "on";
            }
            // `--light-tilt DEG`: largest angle of a contact normal from the horizontal at which
            // the light rule applies (45: head joints only; 90: any orientation, session 31).
            if let Some(v) = arg("--light-tilt") {
                let deg: f64 = v.parse().expect("--light-tilt");
                params.open_close.light_state_tilt = deg.to_radians();
            }
            // `--light-interface on|off`: the rule only where the contact's whole interface is
            // lightly loaded (on, the default since §12; off: the contact's own load, §11).
            if let Some(v) = arg("--light-interface") {
                params.open_close.light_state_interface = v == "on";
            }
            // `--local-sweeps S [--local-rounds R]`: local rounds of block Gauss–Seidel between
            // global solves (`OpenCloseParams::local_sweeps`, docs/contact-solve.md §13).
            if let Some(v) = arg("--local-sweeps") {
                params.open_close.local_sweeps = v.parse().expect("--local-sweeps");
            }
            // `--line-search`: the damped (semismooth Newton) open–close loop (§13).
            if std::env::args().any(|a| a == "--line-search") {
                params.open_close.line_search = true;
            }
            // `--restick-jump`: a re-sticking misjudges the jump to the locked force (§13).
            if std::env::args().any(|a| a == "--restick-jump") {
                params.open_close.restick_jump = true;
            }
            if let Some(v) = arg("--local-after") {
                params.open_close.local_after = v.parse().expect("--local-after");
            }
            if let Some(v) = arg("--local-rounds") {
                params.open_close.local_rounds = v.parse().expect("--local-rounds");
            }
            // `--stone-settle TOL [--stone-settle-state TOL] [--stone-settle-after K]
            // [--stone-settle-interfaces N]`: the settle rule for loaded friction updates (and
            // light head-joint state changes) between stones held by many contacts
            // (`OpenCloseParams::stone_settle_friction`, docs/contact-solve.md §17).
            if let Some(v) = arg("--stone-settle") {
                params.open_close.stone_settle_friction = v.parse().expect("--stone-settle");
            }
            if let Some(v) = arg("--stone-settle-state") {
                params.open_close.stone_settle_state = v.parse().expect("--stone-settle-state");
            }
            if let Some(v) = arg("--stone-settle-after") {
                params.open_close.stone_settle_after = v.parse().expect("--stone-settle-after");
            }
            if let Some(v) = arg("--stone-settle-interfaces") {
                params.open_close.stone_settle_interfaces =
                    v.parse().expect("--stone-settle-interfaces");
            }
            // `--stone-settle-neighbours`: a stone loaded against one with enough interfaces
            // qualifies too (`OpenCloseParams::stone_settle_neighbours`, §17).
            if std::env::args().any(|a| a == "--stone-settle-neighbours") {
                params.open_close.stone_settle_neighbours = true;
            }
            // `--weight-scale on|off`: a stone with no contact force uses its weight as force
            // scale (`OpenCloseParams::weight_scale`, §17).
            if let Some(v) = arg("--weight-scale") {
                params.open_close.weight_scale = v == "on";
            }
            // `--cycle-flips N [--cycle-after K] [--cycle-extra E]`: a contact that has
            // flipped N times in the step closes sliding, from iteration K on, with E
            // iterations beyond the limit (`OpenCloseParams::cycle_flips`, §18).
            if let Some(v) = arg("--cycle-flips") {
                params.open_close.cycle_flips = v.parse().expect("--cycle-flips");
            }
            if let Some(v) = arg("--cycle-after") {
                params.open_close.cycle_after = v.parse().expect("--cycle-after");
            }
            if let Some(v) = arg("--cycle-extra") {
                params.open_close.cycle_extra = v.parse().expect("--cycle-extra");
            }
            // `--cycle-interface on|off`: the rule only on lightly loaded interfaces
            // (`OpenCloseParams::cycle_light_interface`, §25).
            if let Some(v) = arg("--cycle-interface") {
                params.open_close.cycle_light_interface = v == "on";
            }
            // `--cycle-tilt DEG`: the steepest joint the rule may close sliding
            // (`OpenCloseParams::cycle_tilt`, §27; 90 = any orientation).
            if let Some(v) = arg("--cycle-tilt") {
                let deg: f64 = v.parse().expect("--cycle-tilt");
                params.open_close.cycle_tilt = deg.to_radians();
            }
            // The predictions at a step start, each an extrapolation gain (1 = linear) or `off`:
            // the friction normal's (`OpenCloseParams::friction_predict`, §30), the stick–slip
            // (`stick_predict`, `slip_predict`, §32), the head joints' gaps (`gap_predict`, §33).
            let oc = &mut params.open_close;
            for (name, knob) in [
                ("--friction-predict", &mut oc.friction_predict),
                ("--stick-predict", &mut oc.stick_predict),
                ("--slip-predict", &mut oc.slip_predict),
                ("--gap-predict", &mut oc.gap_predict),
                ("--head-slip-predict", &mut oc.head_slip_predict),
            ] {
                if let Some(v) = arg(name) {
                    *knob = (v != "off").then(|| {
                        v.parse()
                            .unwrap_or_else(|_| panic!("{name}: a gain or off"))
                    });
                }
            }
            // `--head-slip-margin M`, `--head-slip-guard steady,shear,spin`: the head onset
            // prediction's margin and rocking guards (`OpenCloseParams::head_slip_margin`,
            // `head_slip_steady`, `head_slip_shear_sign`, `head_slip_spin`, `head_slip_calm`, §36).
            if let Some(v) = arg("--head-slip-margin") {
                oc.head_slip_margin = v.parse().expect("--head-slip-margin");
            }
            if let Some(v) = arg("--head-slip-guard") {
                for g in v.split(',') {
                    match g {
                        "steady" => oc.head_slip_steady = true,
                        "shear" => oc.head_slip_shear_sign = true,
                        "spin" => oc.head_slip_spin = true,
                        "calm" => oc.head_slip_calm = true,
                        "none" => {}
                        _ => panic!("--head-slip-guard: steady, shear, spin, calm or none"),
                    }
                }
            }
            // `--closing F [--closing-floor R]`: the next Δt is limited so that a contact
            // closing within a step approaches by at most F of its elastic range W/k_n,
            // never below R × Δt (`SimParams::closing`, §22).
            if let Some(v) = arg("--closing") {
                params.closing.elastic_fraction = Some(v.parse().expect("--closing"));
            }
            if let Some(v) = arg("--closing-floor") {
                params.closing.min_step_ratio = v.parse().expect("--closing-floor");
            }
            // `--unconverged-floor R`: a non-converging loop's step is cut no shorter than
            // R × Δt and taken there (`SimParams::unconverged_floor_ratio`, §24).
            if let Some(v) = arg("--unconverged-floor") {
                params.unconverged_floor_ratio = Some(v.parse().expect("--unconverged-floor"));
            }
            // `--floor-hold on|off`: the step after one taken at the floor starts at the floor
            // (`SimParams::unconverged_floor_hold`, §26).
            if let Some(v) = arg("--floor-hold") {
                params.unconverged_floor_hold = v == "on";
            }
            // `--floor-penetration F`: the floor's penetration bound in elastic ranges
            // (`SimParams::unconverged_floor_penetration`, §28; infinite: no bound).
            if let Some(v) = arg("--floor-penetration") {
                params.unconverged_floor_penetration = v.parse().expect("--floor-penetration");
            }
            // `--floor-iterations N`: the loop's iteration limit at the floor
            // (`SimParams::unconverged_floor_iterations`, §28; 0: none, the loop's own).
            if let Some(v) = arg("--floor-iterations") {
                let n: usize = v.parse().expect("--floor-iterations");
                params.unconverged_floor_iterations = (n > 0).then_some(n);
            }
            // `--min-located R`: no impact located sooner than R × Δt
            // (`ImpactParams::min_located_ratio`, §24).
            if let Some(v) = arg("--min-located") {
                params.impact.min_located_ratio = v.parse().expect("--min-located");
            }
            // `--impact-cluster on|off`: the impact law's cluster (`ImpactParams::cluster`, on
            // by default since session 40). Session 40's `fixed-point` value (session 39's
            // search for the joined blocks) was removed in session 41: it ignored
            // `cluster_max_blocks` (docs/energy-after-record.md).
            match arg("--impact-cluster").as_deref() {
                Some("on") => params.impact.cluster = true,
                Some("off") => params.impact.cluster = false,
                None => {}
                Some(o) => panic!("--impact-cluster {o}: on or off"),
            }
            // `--growth G`: Δt's growth a step after a cut (`SimParams::growth`, §24).
            if let Some(v) = arg("--growth") {
                params.growth = v.parse().expect("--growth");
            }
            if let Some(v) = arg("--friction-tol") {
                params.open_close.friction_tolerance = v.parse().expect("--friction-tol");
            }
            if tight {
                params.open_close = ashlar::solve::open_close::OpenCloseParams::legacy();
                params.open_close.max_iterations = 200;
            }
            if let Some(v) = arg("--start-check") {
                // `SparseParams::start_check_samples` (docs/contact-solve.md §19).
                params.solver.sparse.start_check_samples = v.parse().expect("--start-check");
            }
            if std::env::args().any(|a| a == "--start-check-audit") {
                // `SparseParams::start_check_audit`: count accepted starts the exact test rejects.
                params.solver.sparse.start_check_audit = true;
            }
            if std::env::args().any(|a| a == "--simplicial") {
                params.solver.sparse.supernodal = false;
            }
            // `--triangular faer|repacked` (`SparseParams::triangular`, §35).
            match arg("--triangular").as_deref() {
                Some("repacked") => params.solver.sparse.triangular = TriangularSolve::Repacked,
                Some("faer") => params.solver.sparse.triangular = TriangularSolve::Faer,
                None => {}
                Some(t) => panic!("--triangular {t}: faer or repacked"),
            }
            // `--ordering block-amd|dissection`, `--relax none|wide`, `--dissection-leaf N`
            // (`SparseParams`, docs/contact-solve.md §20).
            match arg("--ordering").as_deref() {
                Some("block-amd") => params.solver.sparse.ordering = SparseOrdering::BlockAmd,
                Some("dissection") => {
                    params.solver.sparse.ordering = SparseOrdering::BlockDissection
                }
                Some("coordinates") => {
                    params.solver.sparse.ordering = SparseOrdering::BlockCoordinates
                }
                Some("scalar") | None => {}
                Some(o) => panic!("--ordering {o}: scalar, block-amd, dissection or coordinates"),
            }
            match arg("--relax").as_deref() {
                Some("none") => params.solver.sparse.relax = SupernodeRelax::None,
                Some("wide") => params.solver.sparse.relax = SupernodeRelax::Wide,
                Some("faer") | None => {}
                Some(r) => panic!("--relax {r}: faer, none or wide"),
            }
            if let Some(l) = arg("--dissection-leaf") {
                params.solver.sparse.dissection_leaf = l.parse().expect("--dissection-leaf");
            }
            // `--no-settle`: drop the wall onto its springs as the motion starts (before
            // session 35); `--settle-max S`: the longest settling, s (0.5 s: walls of 105 to
            // 1620 stones are quiet from their second step, §21). `--lead-in S`: a record is
            // tapered in over S s before `start`, unmeasured (0.1 s: no cut in it and none in
            // the first steps at 105–1620 stones; 0.05 s leaves the same, §21).
            let lead_in: f64 = arg("--lead-in")
                .map(|v| v.parse().expect("--lead-in"))
                .unwrap_or(0.1);
            let settling = (!std::env::args().any(|a| a == "--no-settle")).then(|| {
                let max_time: f64 = arg("--settle-max")
                    .map(|v| v.parse().expect("--settle-max"))
                    .unwrap_or(0.5);
                let (quiet, quiet_end) = tapered_in(&gm, start, lead_in);
                (quiet, quiet_end, max_time)
            });
            let gm = settling.as_ref().map_or(gm.clone(), |s| s.0.clone());
            let mut sim = Simulation::new(&scene, &gm, params);
            sim.set_time(start);
            if let Some((_, quiet_end, max_time)) = settling {
                let lead_start = quiet_end.max(start - lead_in);
                let st = settle(&mut sim, quiet_end, lead_start, max_time);
                if sim.time() < start {
                    let l0 = sim.stats();
                    measured_steps(&mut sim, 0, Some(start), "lead-in");
                    let l1 = sim.stats();
                    eprintln!(
                        "  lead-in {lead_in} s (tapered): {} steps, {} solves, {} cuts",
                        l1.steps - l0.steps,
                        l1.open_close_iterations - l0.open_close_iterations,
                        l1.time_step_cuts - l0.time_step_cuts
                    );
                }
                eprintln!(
                    "  ground acceleration at the start ({start:.3} s): {:.3} m/s²",
                    gm.acceleration(start)[0]
                );
                eprintln!(
                    "  {} stones, {m}: settled in {} steps ({:.3} s simulated, quiet {}), {} solves, {} cuts",
                    scene.blocks.len() - 1,
                    st.steps,
                    st.time,
                    st.quiet,
                    st.solves,
                    st.cuts
                );
            }
            let s0 = sim.stats();
            let t = Instant::now();
            let end = seconds.map(|s| start + s);
            let label = format!("{n} {m}");
            let (done, min_dt, deepest) = measured_steps(&mut sim, steps, end, &label);
            let wall = t.elapsed().as_secs_f64();
            if std::env::args().any(|a| a == "--digest") {
                eprintln!(
                    "  {} stones, {m}: state digest {:016x}, impacts {}",
                    scene.blocks.len() - 1,
                    state_digest(&sim),
                    sim.stats().impacts
                );
            }
            if std::env::args().any(|a| a == "--reference") {
                compare_with_reference(
                    &sim,
                    &scene,
                    &gm,
                    start,
                    settling.map(|(_, quiet_end, max_time)| (quiet_end, max_time)),
                );
            }
            let c = sim.solver_counts();
            let s1 = sim.stats();
            let solves = (s1.open_close_iterations - s0.open_close_iterations) as f64;
            println!(
                "| {} | {} | {} | {:.3e} | {:.2} | {:.2} | {} | {:.1e} | {:.2e} |",
                scene.blocks.len() - 1,
                m,
                done,
                wall / done.max(1) as f64,
                solves / done.max(1) as f64,
                solves / done.max(1) as f64,
                s1.time_step_cuts - s0.time_step_cuts,
                min_dt,
                deepest
            );
            if diag {
                eprintln!(
                    "  {} stones, {m}: {} measured steps shortened the next by the closing limit",
                    scene.blocks.len() - 1,
                    s1.closing_limited_steps - s0.closing_limited_steps
                );
                eprintln!(
                    "  {} stones, {m} (settling included): contacts {}, factorizations {}, reuse CG iterations {}, detections {}",
                    scene.blocks.len() - 1,
                    sim.contacts().contacts.len(),
                    c.numeric,
                    c.reuse_iterations,
                    sim.contacts().detections
                );
                if c.start_skips > 0 {
                    eprintln!(
                        "  reused-factor starts accepted by the estimate: {}",
                        c.start_skips
                    );
                    if sim.params().solver.sparse.start_check_audit {
                        eprintln!(
                            "  of which rejected by the exact test (audited): {}",
                            c.start_check_misses
                        );
                    }
                }
                let fc = c.factor_cost;
                eprintln!(
                    "  factor cost (solve multiply-adds): factorization {:.3e} (unweighted {:.4e}), pair {:.3e}, matvec {:.3e}, n {}, break-even {:.2} iterations",
                    fc.factor,
                    fc.factor / SimParams::default().solver.sparse.factor_work_weight,
                    fc.pair,
                    fc.matvec,
                    fc.n,
                    fc.break_even()
                );
                for (p, [tries, its, failed, skipped]) in c.reuse_table.iter().enumerate() {
                    if tries + skipped > 0 {
                        eprintln!(
                            "  predicted {p:>2}: attempts {tries}, CG iterations {its}, failed {failed}, refactored by the cost rule {skipped}"
                        );
                    }
                }
                let p = sim.profile();
                eprintln!(
                    "  time: detect {:.3} s, assemble {:.3} s, solve {:.3} s, integrate {:.3} s",
                    p.detect.as_secs_f64(),
                    p.assemble.as_secs_f64(),
                    p.solve.as_secs_f64(),
                    p.integrate.as_secs_f64()
                );
                eprintln!(
                    "  refusals: unconverged {}, moved too far {}, overshot {}",
                    sim.refusals()[0],
                    sim.refusals()[1],
                    sim.refusals()[2]
                );
                let ch = sim.changes();
                for (k, name) in CHANGE_KINDS.iter().enumerate() {
                    eprintln!(
                        "  {name:>22}: bed {:>7} head {:>7}",
                        ch.by_kind[k][0], ch.by_kind[k][1]
                    );
                }
                eprintln!("  changes by iteration: {:?}", ch.by_iteration);
                for (k, name) in CHANGE_KINDS.iter().enumerate() {
                    for (o, side) in ["bed", "head"].iter().enumerate() {
                        if ch.by_kind[k][o] > 0 {
                            eprintln!(
                                "  by iteration {name:>22} {side:>4}: {:?}",
                                ch.by_kind_iteration[k][o]
                            );
                        }
                    }
                }
                eprintln!(
                    "  local rounds {}, state changes in them {}",
                    ch.local_rounds, ch.local_changes
                );
                eprintln!(
                    "  line searches {}, damped {} (mean t {:.3})",
                    ch.searches,
                    ch.damped,
                    ch.damped_t_sum / ch.damped.max(1) as f64
                );
                for (k, name) in CHANGE_KINDS.iter().enumerate() {
                    eprintln!(
                        "  last iteration {name:>22}: bed {:>7} head {:>7}",
                        ch.last_kind[k][0], ch.last_kind[k][1]
                    );
                }
                eprintln!(
                    "  last iteration by force decade (1e-3.. N): {:?}; settled {}; light state changes taken {}",
                    ch.last_force, ch.settled, ch.light
                );
                eprintln!("  changes by force decade (1e-3.. N): {:?}", ch.by_force);
                eprintln!(
                    "  stone settle rule: friction updates taken {}, state changes taken {}",
                    ch.stone_settled_friction, ch.stone_settled_state
                );
                eprintln!(
                    "  cycle rule: closed sliding light {} loaded {}, kept locked {}, steps finished in the extra iterations {}",
                    ch.cycle_closed[0], ch.cycle_closed[1], ch.cycle_kept_locked, ch.cycle_extra_steps
                );
                eprintln!(
                    "  stick–slip prediction: started locked {} (held after the first solve {}), started sliding {} (held {})",
                    ch.predicted[0][0] + ch.predicted[0][1],
                    ch.predicted[0][0],
                    ch.predicted[1][0] + ch.predicted[1][1],
                    ch.predicted[1][0]
                );
                eprintln!(
                    "  gap prediction: started open {} (held after the first solve {}), started closed {} (held {})",
                    ch.predicted[2][0] + ch.predicted[2][1],
                    ch.predicted[2][0],
                    ch.predicted[3][0] + ch.predicted[3][1],
                    ch.predicted[3][0]
                );
                eprintln!(
                    "  head onset prediction: started sliding {} (held {})",
                    ch.predicted[4][0] + ch.predicted[4][1],
                    ch.predicted[4][0]
                );
            }
        }
    }
}
