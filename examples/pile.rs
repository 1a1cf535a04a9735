//! The dual form's speed case (after Zheng et al. 2016, §7, Figs. 11–12: a projectile penetrating a pile
//! of 1689 blocks with up to 11,000 contacts, mostly vertex–vertex, frictionless, 280
//! adaptive steps): times the same 280 steps with the penalty solver and the dual solver in
//! one run and prints both.
//!
//! The pile: `COLUMNS × ROWS` rectangular blocks (0.4 m × 0.2 m) stacked in aligned columns
//! (so four corners meet at every grid node: vertex–vertex contacts everywhere) in a fixed
//! U-shaped container, plus a pointed projectile (a pentagon 0.4 m wide, 1 m tall, twice as
//! dense) just above the pile moving down at `SPEED`. Stone: 2500 kg/m³, E = 10 GPa,
//! ν = 0.2; all joints frictionless and cohesionless (as Zheng et al.'s); g = 9.81 m/s²; adaptive
//! Δt ≤ 1 ms with Zheng et al.'s displacement ratio 0.003.
//!
//! Run: `cargo run --release --example pile` (`-- --help` lists the options; add `-- --write pile.json` to save the scene,
//! `-- --steps N` to change the step count, `-- --ordering block-amd|dissection|coordinates` and `-- --relax none|wide` for the sparse factorization's ordering and supernode amalgamation, `-- --only dual|penalty` to time one solver, `-- --trace` to print per-step work counts (with reused-factor attempts and low-rank solves), `-- --low-rank R` for the low-rank correction of the factor, `-- --cg-budget N` to
//! give the dual solver's MPRGP minimisation N products with W, 0 for the projection–contraction
//! iteration alone), `-- --dual-tolerance X` to stop its iterations at X × the smallest
//! block's half size instead of the default 1e-9, `-- --proportioning G` for MPRGP's
//! proportioning constant Γ instead of 1, `-- --block-model rigid` for 3 unknowns a block
//! instead of Zheng et al.'s 6, `-- --stall-acceptance A` to accept a stalled dual solve whose
//! violation is within A × its tolerance instead of cutting the step). The scene written by
//! `--write` carries the last two as `control.dual_tolerance` and
//! `control.dual_stall_acceptance`, so `ashlar run pile.json` runs the dual solver as this does.
use ashlar::motion::GroundMotion;
use ashlar::scene::{parse_scene, Scene};
use ashlar::simulation::{SimParams, Simulation};
use ashlar::solve::{SparseOrdering, SupernodeRelax};
use clap::Parser;
use serde_json::{json, Value};
use std::time::Instant;

const COLUMNS: usize = 41;
const ROWS: usize = 41;
const W: f64 = 0.4;
const H: f64 = 0.2;
/// Projectile speed, m/s.
const SPEED: f64 = 20.0;

fn rect(x0: f64, y0: f64, x1: f64, y1: f64) -> Value {
    json!([[x0, y0], [x1, y0], [x1, y1], [x0, y1]])
}

/// The pile scene as JSON (`ashlar.scene/1`) for the given contact solver and block model
/// (`"deformable"`, 6 unknowns a block as in Zheng et al.'s DDA, or `"rigid"`, 3).
pub fn pile_scene(solver: &str, block_model: &str) -> Value {
    let width = COLUMNS as f64 * W;
    let height = ROWS as f64 * H;
    let mut blocks = vec![
        json!({ "id": "floor", "material": "stone", "fixed": true,
                "vertices": rect(-1.0, -1.0, width + 1.0, 0.0) }),
        json!({ "id": "wall_left", "material": "stone", "fixed": true,
                "vertices": rect(-1.0, 0.0, 0.0, height + 2.0) }),
        json!({ "id": "wall_right", "material": "stone", "fixed": true,
                "vertices": rect(width, 0.0, width + 1.0, height + 2.0) }),
    ];
    for r in 0..ROWS {
        for c in 0..COLUMNS {
            let (x0, y0) = (c as f64 * W, r as f64 * H);
            blocks.push(json!({ "id": format!("b{r}_{c}"), "material": "stone",
                                "vertices": rect(x0, y0, x0 + W, y0 + H) }));
        }
    }
    // Pointed projectile above the middle column, its tip 5 cm above the pile.
    let xm = (COLUMNS / 2) as f64 * W + 0.5 * W;
    let tip = height + 0.05;
    blocks.push(
        json!({ "id": "projectile", "material": "heavy", "vertices": [
        [xm, tip], [xm + 0.5 * W, tip + 0.3], [xm + 0.5 * W, tip + 1.0],
        [xm - 0.5 * W, tip + 1.0], [xm - 0.5 * W, tip + 0.3]] }),
    );
    json!({
        "format": "ashlar.scene/1",
        "name": "pile",
        "gravity": 9.81,
        "materials": {
            "stone": { "density": 2500.0, "young_modulus": 1.0e10, "poisson_ratio": 0.2 },
            "heavy": { "density": 5000.0, "young_modulus": 1.0e10, "poisson_ratio": 0.2 }
        },
        "joints": { "dry": { "friction_angle": 0.0 } },
        "blocks": blocks,
        "initial": [{ "block": "projectile", "velocity": [0.0, -SPEED] }],
        "control": { "time_step": 1.0e-3, "max_displacement_ratio": 0.003,
                     "contact_solver": solver, "block_model": block_model, "duration": 10.0 }
    })
}

/// The pile for `solver` with the command line's block model; with the dual solver, its
/// `--dual-tolerance` and `--stall-acceptance` become the scene's `control.dual_tolerance` and
/// `control.dual_stall_acceptance` (so the scene written by `--write` runs as this does).
fn scene_json(solver: &str, cli: &Cli) -> Value {
    let mut v = pile_scene(solver, &cli.block_model);
    if let Some(r) = &cli.restitution {
        v["control"]["restitution"] = r.as_str().into();
    }
    if solver == "dual" {
        if let Some(t) = cli.dual_tolerance {
            v["control"]["dual_tolerance"] = t.into();
        }
        if let Some(a) = cli.stall_acceptance {
            v["control"]["dual_stall_acceptance"] = a.into();
        }
    }
    v
}

fn scene(solver: &str, cli: &Cli) -> Scene {
    match parse_scene(&scene_json(solver, cli).to_string()) {
        Ok(s) => s,
        Err(e) => panic!("pile scene invalid: {e}"),
    }
}

/// Run `cli.steps` steps with `solver` and the command line's block model and dual-solver
/// overrides; returns (seconds, simulation). With `--trace`, print one line per step:
/// Δt, cuts, open–close iterations, numeric and symbolic factorizations, preconditioned CG
/// iterations, MPRGP products, projection–contraction iterations, loosely accepted dual solves,
/// contact detections, contacts, closed contacts.
fn time_run(solver: &str, cli: &Cli) -> Result<(f64, Simulation), String> {
    let (steps, trace) = (cli.steps, cli.trace);
    let scene = scene(solver, cli);
    // The knobs a scene cannot set; the tolerance and stall acceptance are in `scene`.
    let mut params = SimParams::default();
    if let Some(n) = cli.cg_budget {
        params.dual.max_cg_iterations = n;
    }
    if let Some(g) = cli.proportioning {
        params.dual.proportioning = g;
    }
    params.impact.group_landings &= !cli.no_group_landings;
    params.impact.split_before &= !cli.no_split;
    params.impact.close_hover &= !cli.no_hover_landing;
    if let Some(r) = cli.locate_speed_ratio {
        params.impact.locate_speed_ratio = r;
    }
    if let Some(cap) = cli.cluster_cap {
        params.impact.cluster_max_blocks = cap;
    }
    params.impact.polish |= cli.polish;
    params.solver.sparse.ordering = match cli.ordering.as_str() {
        "block-amd" => SparseOrdering::BlockAmd,
        "dissection" => SparseOrdering::BlockDissection,
        "coordinates" => SparseOrdering::BlockCoordinates,
        _ => SparseOrdering::ScalarAmd,
    };
    params.solver.sparse.relax = match cli.relax.as_str() {
        "none" => SupernodeRelax::None,
        "wide" => SupernodeRelax::Wide,
        _ => SupernodeRelax::Faer,
    };
    if let Some(l) = cli.dissection_leaf {
        params.solver.sparse.dissection_leaf = l;
    }
    if let Some(r) = cli.low_rank {
        params.solver.sparse.low_rank_max_rank = r;
    }
    let mut sim = Simulation::new(&scene, &GroundMotion::none(), params);
    let t = Instant::now();
    if trace {
        println!("step  dt(s)      cuts  oc  numeric  symbolic  cg  mprgp  pc  loose  detect  contacts  closed  ms  attempts  failed  lowrank  rank  declined");
    }
    for k in 0..steps {
        let (stats, counts, detections) =
            (sim.stats(), sim.solver_counts(), sim.contacts().detections);
        let ts = Instant::now();
        let dt = match sim.step(1.0) {
            Ok(dt) => dt,
            Err(e) => {
                return Err(format!(
                    "step {k} failed after {:.2} s: {e}",
                    t.elapsed().as_secs_f64()
                ))
            }
        };
        if trace {
            let c = sim.solver_counts();
            let closed = sim
                .contacts()
                .contacts
                .iter()
                .filter(|c| c.state.is_closed())
                .count();
            let table =
                |t: &ashlar::solve::ReuseTable, i: usize| t.iter().map(|r| r[i]).sum::<u64>();
            println!(
                "{k:4}  {dt:.3e}  {:4}  {:2}  {:7}  {:8}  {:2}  {:6}  {:5}  {:5}  {:6}  {:8}  {:6}  {:.0}  {:8}  {:6}  {:7}  {:4}  {:8}",
                sim.stats().time_step_cuts - stats.time_step_cuts,
                sim.stats().open_close_iterations - stats.open_close_iterations,
                c.numeric - counts.numeric,
                c.symbolic - counts.symbolic,
                c.reuse_iterations - counts.reuse_iterations,
                sim.stats().dual_cg_products - stats.dual_cg_products,
                sim.stats().dual_iterations - stats.dual_iterations,
                sim.stats().dual_loose_solves - stats.dual_loose_solves,
                sim.contacts().detections - detections,
                sim.contacts().contacts.len(),
                closed,
                ts.elapsed().as_secs_f64() * 1e3,
                table(&c.reuse_table, 0) - table(&counts.reuse_table, 0),
                table(&c.reuse_table, 2) - table(&counts.reuse_table, 2),
                c.low_rank_solves - counts.low_rank_solves,
                c.low_rank_rank - counts.low_rank_rank,
                c.low_rank_declined - counts.low_rank_declined,
            );
        }
    }
    Ok((t.elapsed().as_secs_f64(), sim))
}

/// Command line (`cargo run --release --example pile -- --help`).
#[derive(Parser)]
#[command(
    about = "Times Zheng et al.'s 1700-block pile with the penalty and the dual contact solver in one run"
)]
struct Cli {
    /// Steps to run with each solver.
    #[arg(long, default_value_t = 280)]
    steps: usize,
    /// Time one solver only.
    #[arg(long, value_parser = ["penalty", "dual"])]
    only: Option<String>,
    /// Print one line of work counters per step.
    #[arg(long)]
    trace: bool,
    /// `deformable` (6 unknowns a block, as Zheng et al.'s DDA) or `rigid` (3).
    #[arg(long, default_value = "deformable", value_parser = ["deformable", "rigid"])]
    block_model: String,
    /// Also write the scene (`ashlar.scene/1`, dual solver, with the dual options given) to this file.
    #[arg(long, value_name = "PATH")]
    write: Option<std::path::PathBuf>,
    /// Products with W for the dual solver's MPRGP minimisation (0: projection–contraction alone).
    #[arg(long, value_name = "N")]
    cg_budget: Option<usize>,
    /// The dual solver's stopping tolerance, × the smallest block's half size (default 1e-9).
    #[arg(long, value_name = "X", value_parser = positive)]
    dual_tolerance: Option<f64>,
    /// MPRGP's proportioning constant Γ (default 1).
    #[arg(long, value_name = "G", value_parser = positive)]
    proportioning: Option<f64>,
    /// Accept a stalled dual solve whose violation is within A × its tolerance (default 1: none).
    #[arg(long, value_name = "A", value_parser = at_least_one)]
    stall_acceptance: Option<f64>,
    /// The scene's `control.restitution` instead of its default (`contact`: no impact law).
    #[arg(long, value_parser = ["housner", "contact"])]
    restitution: Option<String>,
    /// Diagnosis: landings later within an impact's step do not join it (`ImpactParams::group_landings`).
    #[arg(long)]
    no_group_landings: bool,
    /// Diagnosis: no split step before an impact in the next step (`ImpactParams::split_before`).
    #[arg(long)]
    no_split: bool,
    /// Diagnosis: an impacting contact's hover is not closed (`ImpactParams::close_hover`).
    #[arg(long)]
    no_hover_landing: bool,
    /// Diagnosis: locate only impacts faster than R × the settling threshold (`ImpactParams::locate_speed_ratio`).
    #[arg(long, value_name = "R", value_parser = positive)]
    locate_speed_ratio: Option<f64>,
    /// Largest component joined to an impact (`ImpactParams::cluster_max_blocks`; a huge
    /// number lifts the cap).
    #[arg(long, value_name = "N")]
    cluster_cap: Option<usize>,
    /// Finish unconverged impulse solves with the polish (`ImpactParams::polish`, off by default).
    #[arg(long)]
    polish: bool,
    /// The sparse factorization's ordering (`SparseParams::ordering`): faer's minimum degree
    /// on the unknowns (`scalar`, the default), on the blocks (`block-amd`), or nested
    /// dissection of the blocks by level sets (`dissection`) or straight cuts (`coordinates`).
    #[arg(long, default_value = "scalar", value_parser = ["scalar", "block-amd", "dissection", "coordinates"])]
    ordering: String,
    /// faer's supernode amalgamation (`SparseParams::relax`): `faer` (default), `none`, `wide`.
    #[arg(long, default_value = "faer", value_parser = ["faer", "none", "wide"])]
    relax: String,
    /// Blocks in a leaf of the nested dissection (`SparseParams::dissection_leaf`).
    #[arg(long, value_name = "N")]
    dissection_leaf: Option<usize>,
    /// Solve changes of the matrix up to this rank since the last factorization by a
    /// low-rank correction of the factor (`SparseParams::low_rank_max_rank`; default 0: off).
    #[arg(long, value_name = "R")]
    low_rank: Option<usize>,
    /// Write each block's final centroid (x, y, m) and rotation (rad), one line a block, to
    /// compare the final states of two runs (shortest round-trip digits: equal files mean
    /// equal bits).
    #[arg(long, value_name = "PATH")]
    write_state: Option<std::path::PathBuf>,
}

fn positive(s: &str) -> Result<f64, String> {
    match s.parse::<f64>() {
        Ok(x) if x.is_finite() && x > 0.0 => Ok(x),
        _ => Err(format!("{s:?} is not a finite number > 0")),
    }
}

fn at_least_one(s: &str) -> Result<f64, String> {
    match s.parse::<f64>() {
        Ok(x) if x.is_finite() && x >= 1.0 => Ok(x),
        _ => Err(format!(
            "{s:?} is not a finite number ≥ 1 (1 accepts no stalled solve)"
        )),
    }
}

fn main() -> std::process::ExitCode {
    let cli = Cli::parse();
    let block_model = cli.block_model.as_str();
    if let Some(path) = &cli.write {
        let text = serde_json::to_string_pretty(&scene_json("dual", &cli)).expect("json");
        if let Err(e) = std::fs::write(path, text) {
            eprintln!("pile: cannot write {}: {e}", path.display());
            return std::process::ExitCode::FAILURE;
        }
        eprintln!("wrote {}", path.display());
    }
    let steps = cli.steps;
    let blocks = scene("dual", &cli).blocks.len();
    println!(
        "pile: {blocks} {block_model} blocks, {steps} steps, {} rayon threads",
        rayon::current_num_threads()
    );
    let mut code = std::process::ExitCode::SUCCESS;
    for solver in ["penalty", "dual"] {
        if cli.only.as_deref().is_some_and(|o| o != solver) {
            continue;
        }
        let (secs, sim) = match time_run(solver, &cli) {
            Ok(r) => r,
            Err(e) => {
                println!("{solver:>7}: {e}");
                code = std::process::ExitCode::FAILURE;
                continue;
            }
        };
        let tip = sim.geoms()[blocks - 1].bounds().0.y;
        println!(
            "{solver:>7}: {secs:.2} s for {steps} steps (simulated {:.4} s), {} contacts at the end, \
             projectile tip at y = {tip:.3} m, max penetration {:.2e} m, cuts {}, \
             open–close iterations {}, MPRGP products with W {}, projection–contraction iterations {}, switches {}, \
             loosely accepted dual solves {} (largest violation {:.2e} m)",
            sim.time(),
            sim.contacts().contacts.len(),
            sim.stats().max_penetration,
            sim.stats().time_step_cuts,
            sim.stats().open_close_iterations,
            sim.stats().dual_cg_products,
            sim.stats().dual_iterations,
            sim.stats().dual_switches,
            sim.stats().dual_loose_solves,
            sim.stats().dual_loose_residual,
        );
        println!(
            "         profile: {:?}; impacting contacts {}; impulse solves polished {}, unconverged {} (largest residual/scale {:.2e})",
            sim.profile(),
            sim.stats().impacts,
            sim.stats().impact_polished,
            sim.stats().impact_unconverged,
            sim.stats().impact_residual_ratio,
        );
        let (c, w) = (sim.solver_counts(), SimParams::default().solver.sparse);
        println!(
            "         factor: nnz(L) {:.4e}, factorization multiply-adds {:.4e} (ordering {}, relax {}), \
             numeric factorizations {}, symbolic {}, reuse CG iterations {}, reuse attempts {} ({} failed), \
             low-rank solves {} (rank sum {}, declined {} of which {} after the eigen-decomposition, \
             Σ their support³ {:.3e}, failed {})",
            c.factor_cost.pair / 2.0,
            c.factor_cost.factor / w.factor_work_weight,
            cli.ordering,
            cli.relax,
            c.numeric,
            c.symbolic,
            c.reuse_iterations,
            c.reuse_table.iter().map(|r| r[0]).sum::<u64>(),
            c.reuse_table.iter().map(|r| r[2]).sum::<u64>(),
            c.low_rank_solves,
            c.low_rank_rank,
            c.low_rank_declined,
            c.low_rank_declined_rank,
            c.low_rank_declined_cube,
            c.low_rank_failed,
        );
        if let Some(path) = &cli.write_state {
            let text: String = scene(solver, &cli)
                .blocks
                .iter()
                .zip(sim.geoms())
                .map(|(b, g)| {
                    format!(
                        "{} {:e} {:e} {:e}\n",
                        b.id, g.centroid.x, g.centroid.y, g.rotation
                    )
                })
                .collect();
            if let Err(e) = std::fs::write(path, text) {
                eprintln!("pile: cannot write {}: {e}", path.display());
                code = std::process::ExitCode::FAILURE;
            }
        }
    }
    code
}
