//! Solve › impulse: the impact law's impulse solve. `assembly::restitution::assemble_impacts`
//! writes an impact's rows on the joined blocks' rigid-body velocities ([`ImpulseProblem`]);
//! [`ImpulseSolver::solve`] finds their impulses (projected Gauss–Seidel, then with
//! [`ImpactParams::polish`] a semismooth Newton, `impulse/polish.rs`) and leaves the velocities
//! after them in the problem; `assembly::restitution::apply_impulses` writes those back.
//! Why here and not in `assembly`: it is a solve, the polish's sparse LU is faer's, and faer
//! lives behind `solve` (docs/architecture.md); `assembly` sits before `solve` and cannot call
//! it, so `Simulation::impacts` calls the three in order (moved from
//! `assembly::restitution` in session 43, bit-identical).
//!
//! Units: velocities m/s and rad/s, impulses N·s (per metre of thickness).
use crate::assembly::restitution::{ImpactParams, ImpulseProblem, ImpulseRow};
use nalgebra::{Matrix3, Vector3};

mod polish;

/// How one impulse solve went: what the diagnostics count (`Stats::impact_unconverged`,
/// `Stats::impact_polished`) and the measurements read (`Simulation::impact_report`).
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct ImpulseReport {
    /// Contacts in the solve (impacting and closed ones of the joined blocks).
    pub contacts: usize,
    /// Free blocks taking impulses.
    pub blocks: usize,
    /// Projected Gauss–Seidel sweeps done, and whether they stopped on their own criterion
    /// ([`ImpactParams::tolerance`]) before [`ImpactParams::max_sweeps`].
    pub sweeps: usize,
    pub sweeps_stopped: bool,
    /// The speed scale of the solve (largest |ġ| before the impulses or |target| over its
    /// rows), m/s.
    pub scale: f64,
    /// Complementarity residual after the sweeps and at the end, m/s (the natural map,
    /// [`ImpactParams::residual_tolerance`]).
    pub sweeps_residual: f64,
    pub residual: f64,
    /// Outer iterations and Newton steps (sparse LU factorizations) of the polish; 0 when
    /// it did not run.
    pub polish_iterations: usize,
    pub newton_steps: usize,
    /// The end residual is within `residual_tolerance` × `scale`.
    pub converged: bool,
}

/// The impulse solve's buffers, kept across impacts.
#[derive(Debug, Default, Clone)]
pub struct ImpulseSolver {
    /// The polish's buffers ([`ImpactParams::polish`]).
    polish: polish::PolishScratch,
}

impl ImpulseSolver {
    /// Solve `problem`'s rows for their impulses (left in the rows) and the velocities after
    /// them (left in `problem.v`): the sweeps from zero impulses, then the polish if it is on
    /// and the sweeps end above [`ImpactParams::residual_tolerance`].
    pub fn solve(&mut self, problem: &mut ImpulseProblem, params: &ImpactParams) -> ImpulseReport {
        let ImpulseProblem {
            rows,
            inv_mass,
            involved,
            v,
        } = problem;
        let scale = rows
            .iter()
            .map(|r| r.rate(v, true).abs().max(r.target.abs()))
            .fold(0.0, f64::max);
        let mut report = ImpulseReport {
            contacts: rows.len(),
            blocks: involved.iter().filter(|&&i| i).count(),
            scale,
            ..Default::default()
        };
        if params.polish {
            self.polish.keep_start(v);
        }
        (report.sweeps, report.sweeps_stopped) = sweeps(rows, inv_mass, v, params);
        report.sweeps_residual = residual(rows, v);
        report.residual = report.sweeps_residual;
        let tolerance = params.residual_tolerance * scale;
        if params.polish && report.residual > tolerance {
            let outcome = self
                .polish
                .run(rows, inv_mass, involved, v, params, tolerance);
            report.polish_iterations = outcome.iterations;
            report.newton_steps = outcome.newton_steps;
            report.residual = residual(rows, v);
        }
        report.converged = report.residual <= tolerance;
        report
    }
}

/// The row's complementarity residual at `v` with its impulses, m/s: the natural map of the
/// normal condition, |min(pₙ·wₙ, ġ⁺ − target)|, and of the friction law the sweeps solve,
/// |pₜ − clamp(pₜ − ṡ⁺/wₜ, ±μpₙ)|·wₜ; the larger.
fn row_residual(r: &ImpulseRow, v: &[Vector3<f64>]) -> f64 {
    let mut res: f64 = 0.0;
    if r.wn > 0.0 {
        res = (r.pn * r.wn).min(r.rate(v, true) - r.target).abs();
    }
    if r.wt > 0.0 {
        let limit = r.mu * r.pn.max(0.0);
        let free = r.pt - r.rate(v, false) / r.wt;
        res = res.max((r.pt - free.clamp(-limit, limit)).abs() * r.wt);
    }
    res
}

/// The largest residual of `rows` at `v` ([`row_residual`]), m/s.
fn residual(rows: &[ImpulseRow], v: &[Vector3<f64>]) -> f64 {
    rows.iter().map(|r| row_residual(r, v)).fold(0.0, f64::max)
}
/// Projected Gauss–Seidel on `rows` from their impulses, changing `v` (rigid-body velocities
/// per free block): at most `max_sweeps` sweeps, stopping when no impulse changes by more than
/// `tolerance` × the largest. Returns the sweeps done and whether that criterion stopped them.
fn sweeps(
    rows: &mut [ImpulseRow],
    inv_mass: &[Matrix3<f64>],
    v: &mut [Vector3<f64>],
    params: &ImpactParams,
) -> (usize, bool) {
    for sweep in 0..params.max_sweeps {
        let mut change: f64 = 0.0;
        let mut largest: f64 = 0.0;
        for r in rows.iter_mut() {
            if r.wn > 0.0 {
                let pn = (r.pn + (r.target - r.rate(v, true)) / r.wn).max(0.0);
                let dp = pn - r.pn;
                r.push(inv_mass, v, dp, true);
                change = change.max(dp.abs());
                r.pn = pn;
            }
            if r.wt > 0.0 {
                let limit = r.mu * r.pn;
                let pt = (r.pt - r.rate(v, false) / r.wt).clamp(-limit, limit);
                let dp = pt - r.pt;
                r.push(inv_mass, v, dp, false);
                change = change.max(dp.abs());
                r.pt = pt;
            }
            largest = largest.max(r.pn.abs()).max(r.pt.abs());
        }
        if change <= params.tolerance * largest {
            return (sweep + 1, true);
        }
    }
    (params.max_sweeps, false)
}
