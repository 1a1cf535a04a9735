//! Conjugate gradients with proportioning and gradient projection (Dostál's MPRGP, "Optimal
//! Quadratic Programming Algorithms", 2009, §5.8) for the dual form's contact problem: the
//! compatibility iteration done as a bound-constrained minimisation. Runs before the
//! projection–contraction iteration ([`super::iterate`]) on the same warm-started forces and
//! ends on the same exact test (the natural residual, m), so a solve that ends here is exactly
//! as accurate as one that ends there; if it has not converged within
//! `DualParams::max_cg_iterations`, the caller hands its forces on.
//!
//! Why: `G(p) = c + W p` is the gradient of `½pᵀWp + cᵀp`, and with the shear bounds frozen
//! the contact conditions are that function's minimum over the box `−T ≤ p_n`,
//! `|p_t| ≤ τ(p_n)`. The projection–contraction and Gauss–Seidel iterations need of order
//! κ(W) iterations, where a pile of n layers has κ ~ n²; conjugate gradients on the free
//! forces need of order √κ. The box depends on the solution (the "quasi" of the QVI):
//! friction is handled by freezing `τ(p_n)`, minimising, and refreezing, until the exact QVI
//! residual passes (frictionless joints, `τ ≡ 0`, need one round).
//!
//! Preconditioned by D = diag W (each contact's own flexibility), so the variables are
//! `√D p` and a heavy and a light contact converge alike.
//!
//! Call order: `GapFunction::build` first; on return `s.d` and `s.g` hold the block increments
//! and gap function of `p`, which lies in `X(p)`.
use super::flexibility::BlockFlex;
use super::gap::{GapFunction, Pair};
use super::iterate::{natural_residual, IterReport, Scratch};
use super::projection::shear_strength;
use super::DualParams;
use crate::geometry::Vec6;

/// Work vectors of the minimisation, reused from step to step.
#[derive(Debug, Default)]
pub struct CgScratch {
    lower: Vec<Pair>,
    upper: Vec<Pair>,
    dir: Vec<Pair>,
    w_dir: Vec<Pair>,
    grad: Vec<Pair>,
    tmp: Vec<Pair>,
    d_tmp: Vec<Vec6>,
}

/// Where a force component stands against its bounds.
#[derive(Clone, Copy, PartialEq)]
enum Face {
    /// No unknown (no flexibility, or a zero-width interval).
    Fixed,
    Free,
    Lower,
    Upper,
}

fn face(x: f64, lo: f64, hi: f64, w: f64) -> Face {
    if w <= 0.0 || lo >= hi {
        Face::Fixed
    } else if x <= lo {
        Face::Lower
    } else if x >= hi {
        Face::Upper
    } else {
        Face::Free
    }
}

/// Solve for `p` (warm-started by the caller) within `params.max_cg_iterations` products
/// with W. Returns the report of the last exact residual check.
pub fn minimise(
    gf: &GapFunction,
    flex: &[BlockFlex],
    p: &mut [Pair],
    params: &DualParams,
    tolerance: f64,
    s: &mut Scratch,
    c: &mut CgScratch,
) -> IterReport {
    let n = p.len();
    for v in [
        &mut c.lower,
        &mut c.upper,
        &mut c.dir,
        &mut c.w_dir,
        &mut c.grad,
        &mut c.tmp,
    ] {
        v.clear();
        v.resize(n, [0.0; 2]);
    }
    let mut products = 0;
    let alpha_bar = expansion_step(gf, flex, params, c, &mut products);
    let mut report = exact(gf, flex, p, tolerance, s, 0);
    while !report.converged && products < params.max_cg_iterations && report.residual.is_finite() {
        freeze_box(gf, p, c);
        let inner = bounded_cg(gf, flex, p, tolerance, alpha_bar, params, c, &mut products);
        report = exact(gf, flex, p, tolerance, s, products);
        if !inner {
            break;
        }
    }
    report
}

/// The exact natural residual of `p` (all of `s.d`, `s.g` recomputed from the forces).
fn exact(
    gf: &GapFunction,
    flex: &[BlockFlex],
    p: &[Pair],
    tolerance: f64,
    s: &mut Scratch,
    products: usize,
) -> IterReport {
    gf.displacements(flex, p, &mut s.d);
    gf.eval(&s.d, &mut s.g);
    let (residual, worst) = natural_residual(gf, p, &s.g);
    IterReport {
        iterations: products,
        converged: residual <= tolerance,
        residual,
        worst,
    }
}

/// Bounds of the box with the shear strength frozen at the current normal forces; `p` is
/// moved into it.
fn freeze_box(gf: &GapFunction, p: &mut [Pair], c: &mut CgScratch) {
    for (k, t) in gf.terms.iter().enumerate() {
        if t.diag[0] <= 0.0 {
            p[k] = [0.0; 2];
            c.lower[k] = [0.0; 2];
            c.upper[k] = [0.0; 2];
            continue;
        }
        let tau = shear_strength(t, p[k][0]);
        c.lower[k] = [-t.tension, -tau];
        c.upper[k] = [f64::INFINITY, tau];
        p[k][0] = p[k][0].max(-t.tension);
        p[k][1] = p[k][1].clamp(-tau, tau);
    }
}

/// Step length ᾱ of the expansion (projected-gradient) steps in the D metric: 1/λ with λ a
/// power-iteration estimate of the largest eigenvalue of D⁻¹W (ᾱ must not exceed 2/λ_max;
/// 12 iterations from a smooth start reach λ_max within a factor 2 on any pile, and the
/// estimate is from below, so 1/λ is inside the bound with margin).
fn expansion_step(
    gf: &GapFunction,
    flex: &[BlockFlex],
    params: &DualParams,
    c: &mut CgScratch,
    products: &mut usize,
) -> f64 {
    let mut lambda: f64 = 1.0;
    for (k, t) in gf.terms.iter().enumerate() {
        c.dir[k] = [
            if t.diag[0] > 0.0 { 1.0 } else { 0.0 },
            if t.diag[1] > 0.0 { 1.0 } else { 0.0 },
        ];
    }
    for _ in 0..params.power_iterations {
        gf.apply_w(flex, &c.dir, &mut c.d_tmp, &mut c.w_dir);
        *products += 1;
        let mut norm: f64 = 0.0;
        for (k, t) in gf.terms.iter().enumerate() {
            for j in 0..2 {
                let v = if t.diag[j] > 0.0 {
                    c.w_dir[k][j] / t.diag[j]
                } else {
                    0.0
                };
                c.dir[k][j] = v;
                norm = norm.max(v.abs());
            }
        }
        if norm == 0.0 || !norm.is_finite() {
            return 1.0;
        }
        lambda = norm;
        for v in c.dir.iter_mut() {
            v[0] /= norm;
            v[1] /= norm;
        }
    }
    1.0 / lambda
}

/// MPRGP in the frozen box from `p`. Returns true when the projected gradient is below the
/// tolerance (a length) in every component, false when the budget ran out or the state went
/// non-finite.
#[allow(clippy::too_many_arguments)]
fn bounded_cg(
    gf: &GapFunction,
    flex: &[BlockFlex],
    p: &mut [Pair],
    tolerance: f64,
    alpha_bar: f64,
    params: &DualParams,
    c: &mut CgScratch,
    products: &mut usize,
) -> bool {
    let n = p.len();
    let diag = gf.diag();
    let w = |k: usize, j: usize| diag[k][j];
    let gradient = |p: &[Pair], c: &mut CgScratch, products: &mut usize| {
        gf.displacements(flex, p, &mut c.d_tmp);
        gf.eval(&c.d_tmp, &mut c.grad);
        *products += 1;
    };
    gradient(p, c, products);
    // Free gradient preconditioned (D⁻¹φ) into `dir`: the first search direction.
    let precond_free = |p: &[Pair], c: &mut CgScratch, out_is_tmp: bool| {
        for k in 0..n {
            for j in 0..2 {
                let f = face(p[k][j], c.lower[k][j], c.upper[k][j], w(k, j));
                let v = if f == Face::Free {
                    c.grad[k][j] / w(k, j)
                } else {
                    0.0
                };
                if out_is_tmp {
                    c.tmp[k][j] = v;
                } else {
                    c.dir[k][j] = v;
                }
            }
        }
    };
    precond_free(p, c, false);
    let mut since_exact = 0;
    loop {
        // Proportionality: ‖β‖ and ‖φ‖ in the D⁻¹ metric, and the largest projected gradient.
        let (mut beta2, mut phi2, mut largest) = (0.0, 0.0, 0.0_f64);
        for k in 0..n {
            for j in 0..2 {
                let g = c.grad[k][j];
                let b = match face(p[k][j], c.lower[k][j], c.upper[k][j], w(k, j)) {
                    Face::Fixed => continue,
                    Face::Free => {
                        phi2 += g * g / w(k, j);
                        largest = largest.max(g.abs());
                        continue;
                    }
                    Face::Lower => g.min(0.0),
                    Face::Upper => g.max(0.0),
                };
                beta2 += b * b / w(k, j);
                largest = largest.max(b.abs());
            }
        }
        if !largest.is_finite() {
            return false;
        }
        if largest <= tolerance {
            return true;
        }
        if *products >= params.max_cg_iterations {
            return false;
        }
        if beta2 <= params.proportioning * params.proportioning * phi2 {
            // Conjugate gradient step along `dir`, cut at the box (then an expansion step).
            gf.apply_w(flex, &c.dir, &mut c.d_tmp, &mut c.w_dir);
            *products += 1;
            let (mut gp, mut pap) = (0.0, 0.0);
            let mut feasible = f64::INFINITY;
            for k in 0..n {
                for j in 0..2 {
                    let d = c.dir[k][j];
                    if d == 0.0 {
                        continue;
                    }
                    gp += c.grad[k][j] * d;
                    pap += d * c.w_dir[k][j];
                    let room = if d > 0.0 {
                        (p[k][j] - c.lower[k][j]) / d
                    } else {
                        (p[k][j] - c.upper[k][j]) / d
                    };
                    feasible = feasible.min(room);
                }
            }
            if pap <= 0.0 {
                return false;
            }
            let a_cg = gp / pap;
            if a_cg <= feasible {
                step(p, &c.dir, a_cg, &mut c.grad, &c.w_dir);
                precond_free(p, c, true);
                let mut zap = 0.0;
                for k in 0..n {
                    for j in 0..2 {
                        zap += c.tmp[k][j] * c.w_dir[k][j];
                    }
                }
                let gamma = zap / pap;
                for k in 0..n {
                    for j in 0..2 {
                        c.dir[k][j] = c.tmp[k][j] - gamma * c.dir[k][j];
                    }
                }
            } else {
                // Expansion: to the box along `dir`, then a projected preconditioned
                // gradient step of ᾱ on the free components; restart the directions.
                step(p, &c.dir, feasible, &mut c.grad, &c.w_dir);
                for k in 0..n {
                    for j in 0..2 {
                        let (lo, hi) = (c.lower[k][j], c.upper[k][j]);
                        if face(p[k][j], lo, hi, w(k, j)) == Face::Free {
                            p[k][j] = (p[k][j] - alpha_bar * c.grad[k][j] / w(k, j)).clamp(lo, hi);
                        } else if w(k, j) > 0.0 {
                            p[k][j] = p[k][j].clamp(lo, hi);
                        }
                    }
                }
                gradient(p, c, products);
                since_exact = 0;
                precond_free(p, c, false);
            }
        } else {
            // Proportioning: release the bound components whose gradient points inside.
            for k in 0..n {
                for j in 0..2 {
                    c.tmp[k][j] = match face(p[k][j], c.lower[k][j], c.upper[k][j], w(k, j)) {
                        Face::Lower => c.grad[k][j].min(0.0) / w(k, j),
                        Face::Upper => c.grad[k][j].max(0.0) / w(k, j),
                        _ => 0.0,
                    };
                }
            }
            gf.apply_w(flex, &c.tmp, &mut c.d_tmp, &mut c.w_dir);
            *products += 1;
            let (mut gd, mut dad) = (0.0, 0.0);
            for k in 0..n {
                for j in 0..2 {
                    gd += c.grad[k][j] * c.tmp[k][j];
                    dad += c.tmp[k][j] * c.w_dir[k][j];
                }
            }
            if dad <= 0.0 {
                return false;
            }
            let a = gd / dad;
            let tmp = std::mem::take(&mut c.tmp);
            step(p, &tmp, a, &mut c.grad, &c.w_dir);
            c.tmp = tmp;
            // Leaving a bound may overshoot the opposite one (shear box): stay inside.
            for k in 0..n {
                for j in 0..2 {
                    if w(k, j) > 0.0 {
                        p[k][j] = p[k][j].clamp(c.lower[k][j], c.upper[k][j]);
                    }
                }
            }
            gradient(p, c, products);
            since_exact = 0;
            precond_free(p, c, false);
        }
        since_exact += 1;
        if since_exact >= params.gradient_refresh {
            // The recurrence g ← g − αWd drifts by round-off; recompute it from the forces.
            gradient(p, c, products);
            since_exact = 0;
        }
    }
}

/// `p ← p − a·dir`, `g ← g − a·W dir`.
fn step(p: &mut [Pair], dir: &[Pair], a: f64, g: &mut [Pair], w_dir: &[Pair]) {
    for k in 0..p.len() {
        for j in 0..2 {
            p[k][j] -= a * dir[k][j];
            g[k][j] -= a * w_dir[k][j];
        }
    }
}
