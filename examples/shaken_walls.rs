//! Shaken masonry benchmark and contact-solve diagnostics (docs/contact-solve.md): running-bond
//! walls of 0.6 × 0.3 m rigid stones (`scene::generate::running_bond_wall`, 35° dry joints) on a
//! fixed foundation, at rest, under a base sine of 1 m/s² at 1 Hz, and under the Northridge
//! (Mulholland 009) record of `data/ground-motions/` scaled to a PGA of 0.3 g and started 0.2 s
//! before its peak (so a short run sees the strong motion). Δt = 1 ms with the default
//! (adaptive) time-step control. Prints one Markdown row per wall and motion: s/step, linear
//! solves a step, Δt cuts, the deepest penetration; `--diag` adds why the open–close loop
//! iterated (`ChangeCounts`), why steps were refused and the time per stage.
//!
//! `cargo run --release --example shaken_walls -- [--sizes 100,400,1600] [--steps 300]
//!  [--motions rest,sine,record] [--diag] [--tight] [--block-model rigid|deformable] [--poisson V]
//!  [--anderson DEPTH] [--anderson-restart] [--legacy] [--reference] [--record-start T]
//!  [--seconds S] [--settle TOL] [--settle-after K] [--light-states on|off] [--light-tilt DEG]
//!  [--stone-settle TOL] [--stone-settle-state TOL] [--stone-settle-after K]
//!  [--stone-settle-interfaces N] [--stone-settle-neighbours] [--weight-scale on|off]
//!  [--light-interface on|off] [--simplicial] [--start-check K] [--digest]`
//!
//! `--start-check K` sets `SparseParams::start_check_samples` (opt-in cheaper start of a
//! reused-factor solve); `--simplicial` turns off faer's supernodal factorization (`SparseParams::supernodal`);
//! `--digest` prints a hash of every vertex and velocity at the end (bit-identity checks).
//!
//! `--anderson 0` turns off the Anderson acceleration of the friction fixed point (the plain
//! fixed-point loop); `--anderson-restart` restarts its history whenever a contact changes state.
//!
//! `--tight`: the reference configuration of docs/contact-solve.md (Δt = 1e-4 s, the open–close
//! loop run to convergence with the previous defaults of `OpenCloseParams::legacy`).
use ashlar::motion::{self, GroundMotion, Signal};
use ashlar::presets;
use ashlar::scene::generate::WallParams;
use ashlar::scene::{validate, BlockModel};
use ashlar::simulation::{SimParams, Simulation};
use ashlar::solve::open_close::CHANGE_KINDS;
use std::time::Instant;

fn arg(name: &str) -> Option<String> {
    let args: Vec<String> = std::env::args().collect();
    args.iter()
        .position(|a| a == name)
        .and_then(|i| args.get(i + 1).cloned())
}

/// Courses and whole blocks a course of a wall of about `n` stones: √n × √n, as
/// `examples/engine_scaling.rs` (100 → 105 stones, 400 → 410, 1600 → 1620, 6400 → 6440).
fn layout(n: usize) -> (usize, usize) {
    let side = ((n as f64).sqrt().round() as usize).max(2);
    (side, side)
}

fn record() -> GroundMotion {
    presets::shaken_wall_record().expect("the repository's Northridge record")
}

/// Runs the tight reference (Δt = 1e-4 s fixed, the previous open–close loop run to
/// convergence) over the same simulated time as `sim` and prints the largest difference of a
/// stone's position (any vertex, m) and the deepest penetration of both.
fn compare_with_reference(
    sim: &Simulation,
    scene: &ashlar::scene::Scene,
    gm: &GroundMotion,
    start: f64,
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
    let rec = record();
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
            let scene = validate(&spec).expect("wall");
            let (gm, start) = match m {
                "rest" => (GroundMotion::none(), 0.0),
                "sine" => (
                    GroundMotion::horizontal(Signal::Sine {
                        amplitude: 1.0,
                        frequency: 1.0,
                    }),
                    0.0,
                ),
                "record" => (rec.clone(), rec_start),
                other => panic!("--motions: unknown {other:?} (rest, sine, record)"),
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
            if std::env::args().any(|a| a == "--simplicial") {
                params.solver.sparse.supernodal = false;
            }
            let mut sim = Simulation::new(&scene, &gm, params);
            sim.set_time(start);
            let t = Instant::now();
            let mut done = 0;
            let end = seconds.map(|s| start + s);
            loop {
                match end {
                    Some(end) if sim.time() >= end - 1e-12 => break,
                    None if done >= steps => break,
                    _ => {}
                }
                let max_dt = end.map_or(f64::INFINITY, |end| end - sim.time());
                if let Err(e) = sim.step(max_dt) {
                    eprintln!("  {n} {m}: stopped after {done} steps: {e}");
                    break;
                }
                done += 1;
            }
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
                compare_with_reference(&sim, &scene, &gm, start);
            }
            let c = sim.solver_counts();
            let solves = sim.stats().open_close_iterations as f64;
            println!(
                "| {} | {} | {} | {:.3e} | {:.2} | {:.2} | {} | {:.1e} | {:.2e} |",
                scene.blocks.len() - 1,
                m,
                done,
                wall / done.max(1) as f64,
                solves / done.max(1) as f64,
                sim.stats().open_close_iterations as f64 / done.max(1) as f64,
                sim.stats().time_step_cuts,
                sim.stats().min_dt,
                sim.stats().max_penetration
            );
            if diag {
                eprintln!(
                    "  {} stones, {m}: contacts {}, factorizations {}, reuse CG iterations {}, detections {}",
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
                }
                let fc = c.factor_cost;
                eprintln!(
                    "  factor cost (solve multiply-adds): factorization {:.3e}, pair {:.3e}, matvec {:.3e}, n {}, break-even {:.2} iterations",
                    fc.factor,
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
            }
        }
    }
}
