//! The compatibility iteration (Zheng et al. 2016, §6, Appendix B): He's projection–contraction method
//! for the variational inequality `find p ∈ X(p): (q − p)ᵀ G(p) ≥ 0 ∀ q ∈ X(p)`, with the set
//! `X(p)` frozen at the current approximation in each projection.
//!
//! The iteration runs in the metric of the diagonal of W (each contact's own flexibility), so
//! every component is scaled to unit stiffness: a contact between light blocks and one under a
//! heavy pile converge alike. One iteration:
//!   p̃ = Π(p − β D⁻¹G(p); p)                          (prediction, β adapted so that
//!   ‖βD^{-1/2}(G(p) − G(p̃))‖ ≤ ν ‖D^{1/2}(p − p̃)‖)
//!   d = (p − p̃) − β D⁻¹(G(p) − G(p̃)),  α = ⟨p − p̃, d⟩_D / ‖d‖²_D
//!   p ← p − γ α d                                     (contraction)
//! Stopping: the natural residual `D·(p − Π(p − D⁻¹G(p); p))`, a length in m (the gap or slide
//! still violating the contact conditions), is below the tolerance for every contact.
use super::flexibility::BlockFlex;
use super::gap::{GapFunction, Pair};
use super::projection::project;
use super::DualParams;
use crate::geometry::Vec6;

/// Work vectors reused from step to step.
#[derive(Debug, Default)]
pub struct Scratch {
    pub g: Vec<Pair>,
    g_trial: Vec<Pair>,
    p_trial: Vec<Pair>,
    dir: Vec<Pair>,
    pub d: Vec<Vec6>,
}

/// How an iteration ended.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct IterReport {
    pub iterations: usize,
    pub converged: bool,
    /// Largest natural residual, m.
    pub residual: f64,
    /// Contact with the largest residual.
    pub worst: Option<usize>,
}

/// Solve the QVI for `p` (warm-started by the caller). On return `s.d` and `s.g` hold the
/// block increments and gap function of the returned `p`, which lies in `X(p)`.
pub fn compatibility(
    gf: &GapFunction,
    flex: &[BlockFlex],
    p: &mut [Pair],
    params: &DualParams,
    tolerance: f64,
    s: &mut Scratch,
) -> IterReport {
    let n = p.len();
    // Each contact's own flexibility, the iteration's metric (read in place, not copied).
    let w = |k: usize| gf.terms[k].diag;
    // Contacts between blocks without unknowns carry no force.
    for k in 0..n {
        if w(k)[0] <= 0.0 {
            p[k] = [0.0; 2];
        }
    }
    let inv = |x: f64| if x > 0.0 { 1.0 / x } else { 0.0 };
    s.p_trial.resize(n, [0.0; 2]);
    s.dir.resize(n, [0.0; 2]);
    gf.displacements(flex, p, &mut s.d);
    gf.eval(&s.d, &mut s.g);
    let mut beta = params.initial_beta;
    let mut report = IterReport {
        iterations: 0,
        converged: false,
        residual: f64::INFINITY,
        worst: None,
    };
    for it in 0..=params.max_iterations {
        let (res, worst) = natural_residual(gf, p, &s.g);
        report.residual = res;
        report.worst = worst;
        report.iterations = it;
        if res <= tolerance {
            report.converged = true;
            break;
        }
        if it == params.max_iterations || !res.is_finite() {
            break;
        }
        // Prediction with an admissible β.
        let mut ratio;
        loop {
            for k in 0..n {
                let t = &gf.terms[k];
                let q = [
                    p[k][0] - beta * s.g[k][0] * inv(w(k)[0]),
                    p[k][1] - beta * s.g[k][1] * inv(w(k)[1]),
                ];
                s.p_trial[k] = if w(k)[0] > 0.0 {
                    project(t, q, p[k][0])
                } else {
                    [0.0; 2]
                };
            }
            gf.displacements(flex, &s.p_trial, &mut s.d);
            gf.eval(&s.d, &mut s.g_trial);
            let (mut num, mut den) = (0.0, 0.0);
            for k in 0..n {
                for c in 0..2 {
                    let dp = p[k][c] - s.p_trial[k][c];
                    let dg = s.g[k][c] - s.g_trial[k][c];
                    den += w(k)[c] * dp * dp;
                    num += beta * beta * dg * dg * inv(w(k)[c]);
                }
            }
            if den == 0.0 {
                // p̃ = p: p is a fixed point of the projection, i.e. a solution.
                ratio = 0.0;
                break;
            }
            ratio = (num / den).sqrt();
            if ratio <= params.nu {
                break;
            }
            beta *= params.beta_shrink * (1.0 / ratio).min(1.0);
        }
        if ratio == 0.0 {
            continue;
        }
        // Contraction along d in the D-metric.
        let (mut num, mut den) = (0.0, 0.0);
        for k in 0..n {
            for c in 0..2 {
                let dp = p[k][c] - s.p_trial[k][c];
                let dd = dp - beta * (s.g[k][c] - s.g_trial[k][c]) * inv(w(k)[c]);
                s.dir[k][c] = dd;
                num += w(k)[c] * dp * dd;
                den += w(k)[c] * dd * dd;
            }
        }
        let alpha = if den > 0.0 { num / den } else { 0.0 };
        for k in 0..n {
            for c in 0..2 {
                p[k][c] -= params.gamma * alpha * s.dir[k][c];
            }
        }
        gf.displacements(flex, p, &mut s.d);
        gf.eval(&s.d, &mut s.g);
        if ratio <= params.beta_grow_below {
            beta *= params.beta_grow;
        }
    }
    // Return the feasible projected point and the state consistent with it.
    for k in 0..n {
        let t = &gf.terms[k];
        let q = [
            p[k][0] - s.g[k][0] * inv(w(k)[0]),
            p[k][1] - s.g[k][1] * inv(w(k)[1]),
        ];
        p[k] = if w(k)[0] > 0.0 {
            project(t, q, p[k][0])
        } else {
            [0.0; 2]
        };
    }
    gf.displacements(flex, p, &mut s.d);
    gf.eval(&s.d, &mut s.g);
    // The stopping test ran on the last iterate; the point returned is its projection, whose
    // own violation can be a little larger. Report the larger, so that the violation reported
    // bounds the gaps returned (a stalled solve is accepted or refused on it).
    let (res, worst) = natural_residual(gf, p, &s.g);
    if res > report.residual || res.is_nan() {
        report.residual = res;
        report.worst = worst;
    }
    report
}

/// Largest `|D·(p − Π(p − D⁻¹G; p))|` over all components (m), and where it occurs
/// (D = diag W, from the terms).
pub(super) fn natural_residual(gf: &GapFunction, p: &[Pair], g: &[Pair]) -> (f64, Option<usize>) {
    let mut worst = (0.0, None);
    for (k, t) in gf.terms.iter().enumerate() {
        let w = t.diag;
        if w[0] <= 0.0 {
            continue;
        }
        let inv_t = if w[1] > 0.0 { 1.0 / w[1] } else { 0.0 };
        let q = [p[k][0] - g[k][0] / w[0], p[k][1] - g[k][1] * inv_t];
        let proj = project(t, q, p[k][0]);
        for c in 0..2 {
            let r = (w[c] * (p[k][c] - proj[c])).abs();
            if r > worst.0 || r.is_nan() {
                worst = (r, Some(k));
            }
        }
    }
    worst
}
