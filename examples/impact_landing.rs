//! An e = 0 landing on a stack, as tests/regression/regression_impact_cluster_size.rs runs it:
//! how the impulse solve went (sweeps, residuals, the polish) and what the landing left.
//!
//! Scene: `presets::stack_with_lander(columns, rows, bond, 0.05)`: `presets::aligned_stack`
//! (0.4 × 0.2 m blocks in a fixed U) with rigid blocks, φ = 30°, the penalty solver, Δt = 1 ms, and a 0.4 × 0.2 m lander 5 cm above the top
//! middle block thrown down at 1 m/s (it lands at ≈ 1.41 m/s, ≈ 198 J/m); `--bond` takes
//! `presets::running_bond_stack` (every other course offset by half a block, half blocks at
//! its ends). The regression test puts its lander before the stack's blocks, this example
//! after them: the same scene with its contacts in another order, which the sweeps visit in
//! that order, so the joined bond landings' figures differ (8 × 4 bond joined: sweeps
//! residual 3.50e-5 and polish 21/3989 here, 4.30e-5 and 35/685 there).
//! Reference: an e = 0 landing on a stack resting on a rigid floor leaves everything at rest.
//!
//! Run: `cargo run --release --example impact_landing -- --stacks 4x4,8x4,8x8,7x9,5x13`
//! (`--cap N` for `ImpactParams::cluster_max_blocks`, `--no-polish` for the sweeps alone (the
//! engine's default; the example turns `ImpactParams::polish` on otherwise),
//! `--pair` for `cluster: false`, `--sweeps N` for `max_sweeps`, `--penalty`, `--outer`,
//! `--newton`, `--tolerance` for the polish's knobs, `--after S` for the seconds
//! watched after the landing, `--bond` for the running bond). Per stack it prints the
//! landing step's impulse solve (contacts, blocks, sweeps and whether they stopped on their
//! own criterion, the residual after them and at the end relative to the speed scale, the
//! polish's outer iterations and Newton steps), the kinetic energy before and after the
//! landing's step, Δt cuts and steps in the `--after` seconds, and the polish/unconverged
//! counters over the run.
use ashlar::motion::GroundMotion;
use ashlar::presets::stack_with_lander;
use ashlar::scene::parse_scene;
use ashlar::simulation::{SimParams, Simulation};
use clap::Parser;
use std::time::Instant;

/// Height of the lander's bottom above the stack's top at the start, m.
const DROP: f64 = 0.05;

#[derive(Parser)]
struct Args {
    /// Stacks as COLUMNSxROWS, comma-separated.
    #[arg(long, default_value = "4x4,8x4,8x8,7x9,5x13")]
    stacks: String,
    /// `ImpactParams::cluster_max_blocks` (default: the engine's).
    #[arg(long)]
    cap: Option<usize>,
    /// The sweeps alone (`ImpactParams::polish` false, the default; without this flag the
    /// example turns the polish on).
    #[arg(long)]
    no_polish: bool,
    /// `ImpactParams::cluster` false (the pair law).
    #[arg(long)]
    pair: bool,
    /// `ImpactParams::max_sweeps`.
    #[arg(long)]
    sweeps: Option<usize>,
    /// `ImpactParams::polish_penalty`.
    #[arg(long)]
    penalty: Option<f64>,
    /// `ImpactParams::polish_iterations`.
    #[arg(long)]
    outer: Option<usize>,
    /// `ImpactParams::polish_newton_steps`.
    #[arg(long)]
    newton: Option<usize>,
    /// `ImpactParams::residual_tolerance`.
    #[arg(long)]
    tolerance: Option<f64>,
    /// Seconds watched after the landing's step.
    #[arg(long, default_value_t = 0.01)]
    after: f64,
    /// Every other course offset by half a block.
    #[arg(long)]
    bond: bool,
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args = Args::parse();
    println!("stack | free blocks | contacts in solve | blocks in solve | sweeps (stopped) | sweeps residual/scale | polish outer/Newton | end residual/scale | KE before -> after (J/m) | cuts | steps after | polished/unconverged solves | CPU s");
    for spec in args.stacks.split(',') {
        let (c, r) = spec
            .split_once('x')
            .ok_or_else(|| format!("stack {spec:?} is not COLUMNSxROWS"))?;
        let (columns, rows): (usize, usize) = (c.trim().parse()?, r.trim().parse()?);
        let scene = parse_scene(&stack_with_lander(columns, rows, args.bond, DROP).to_string())?;
        let free = scene
            .blocks
            .iter()
            .filter(|b| matches!(b.kind, ashlar::scene::BlockKind::Free(_)))
            .count()
            - 1;
        let mut params = SimParams::default();
        if let Some(cap) = args.cap {
            params.impact.cluster_max_blocks = cap;
        }
        if let Some(n) = args.sweeps {
            params.impact.max_sweeps = n;
        }
        params.impact.polish = !args.no_polish;
        if let Some(p) = args.penalty {
            params.impact.polish_penalty = p;
        }
        if let Some(n) = args.newton {
            params.impact.polish_newton_steps = n;
        }
        if let Some(t) = args.tolerance {
            params.impact.residual_tolerance = t;
        }
        if let Some(n) = args.outer {
            params.impact.polish_iterations = n;
        }
        params.impact.cluster = !args.pair;
        let clock = Instant::now();
        let mut s = Simulation::new(&scene, &GroundMotion::none(), params);
        let (mut before, mut cuts_before) = (0.0, 0);
        while s.stats().impacts == 0 {
            if s.time() > 0.1 {
                return Err("no landing by 0.1 s".into());
            }
            before = s.energy().kinetic;
            cuts_before = s.stats().time_step_cuts;
            s.step(1.0)?;
        }
        let report = s.impact_report();
        let after = s.energy().kinetic;
        let (t, steps) = (s.time(), s.stats().steps);
        while s.time() < t + args.after - 1e-12 {
            s.step(t + args.after - s.time())?;
        }
        let st = s.stats();
        let ratio = |x: f64| x / report.scale.max(f64::MIN_POSITIVE);
        println!(
            "{columns}x{rows}{} | {free} | {} | {} | {} ({}) | {:.2e} | {}/{} | {:.2e} | {:.1} -> {:.3e} | {} | {} | {}/{} | {:.2}",
            if args.bond { " bond" } else { "" },
            report.contacts,
            report.blocks,
            report.sweeps,
            if report.sweeps_stopped { "stopped" } else { "cap" },
            ratio(report.sweeps_residual),
            report.polish_iterations,
            report.newton_steps,
            ratio(report.residual),
            before,
            after,
            st.time_step_cuts - cuts_before,
            st.steps - steps,
            st.impact_polished,
            st.impact_unconverged,
            clock.elapsed().as_secs_f64(),
        );
    }
    Ok(())
}
