//! The impulse solve's polish ([`ImpactParams::polish`]): finishes a projected Gauss–Seidel
//! that did not converge with a direct solve, so that an impact joined to a large component
//! (a stack, a pile) ends at the impact law's solution, not wherever 200 sweeps left it.
//!
//! The law is the sweeps' own (`sweeps`): per row, pₙ ≥ 0, ġ⁺ ≥ target, pₙ(ġ⁺ − target)
//! = 0, and pₜ = clamp(pₜ − ṡ⁺/wₜ, ±μpₙ) (stick within the cone, slide against the slip at its
//! bound), with v⁺ = v⁻ + M⁻¹Hᵀp on the joined blocks' rigid-body unknowns. Method: the
//! augmented Lagrangian of that law in the velocities (Alart–Curnier's form), warm-started
//! from the sweeps' impulses λ:
//!
//! - inner equations, λ fixed: F(v) = M(v − v⁻) − Hᵀp(v) = 0 with pₙ = max(0, zₙ),
//!   zₙ = λₙ + ρₙ(target − ġₙ(v)), and pₜ = clamp(zₜ, ±μpₙ), zₜ = λₜ − ρₜṡ(v); F is piecewise
//!   linear in v, solved by semismooth Newton (Jacobian M + Σ_active ρₙhₙhₙᵀ + Σ_stick
//!   ρₜhₜhₜᵀ + Σ_slide σμρₙhₜhₙᵀ, a sparse LU (faer) a step; nonsingular whatever the redundancy of the
//!   contacts: four corners meeting at a node of an aligned stack make the Delassus matrix
//!   H M⁻¹ Hᵀ singular, M + ρHᵀH never is), Armijo backtracking on θ = ½FᵀM⁻¹F;
//! - outer: λ ← p(v) (the proximal point iteration on the impulses), then v = v⁻ + M⁻¹Hᵀλ
//!   exactly (momentum balanced to round-off by construction), until the law's residual is
//!   within tolerance.
//!
//! Why not an active-set Cholesky of the Delassus matrix: the aligned stacks' and the pile's
//! vertex–vertex contacts make it singular (dependent rows), which the primal form avoids.
//! The friction bound moves with pₙ(v) inside the Newton step: lagged at μλₙ (a symmetric
//! Jacobian), a sliding contact's bound drifted by μ·Δλₙ an outer iteration and the polish
//! stalled at 5e-4 m/s on the 4 × 4 stack (measured).
use super::residual;
use crate::assembly::restitution::{ImpactParams, ImpulseRow};
use faer::linalg::solvers::SolveCore;
use faer::sparse::{SparseColMat, Triplet};
use faer::{Conj, MatMut};
use nalgebra::{Matrix3, Vector3};
use rustc_hash::FxHashMap;

/// Sufficient decrease of the merit θ along a Newton step (Armijo's constant).
const ARMIJO: f64 = 1e-4;
/// Smallest step fraction of the backtracking: below it the step is taken anyway (round-off).
const MIN_STEP: f64 = 1e-10;

/// The polish's buffers, kept across impacts.
#[derive(Debug, Default, Clone)]
pub(super) struct PolishScratch {
    /// Per free block: rigid-body velocity before the impulses.
    start: Vec<Vector3<f64>>,
    /// Per free block: its index among the blocks taking impulses (`usize::MAX`: none).
    local: Vec<usize>,
    /// Per local block: its free block index and rigid-body mass matrix.
    blocks: Vec<usize>,
    mass: Vec<Matrix3<f64>>,
    inv_mass: Vec<Matrix3<f64>>,
    /// Per row: the multipliers (λₙ, λₜ), N·s.
    lambda: Vec<(f64, f64)>,
    /// Per row: active normal (bit 0) and sticking friction (bit 1) at the last Newton point.
    pattern: Vec<u8>,
    /// The sweeps' impulses and velocities, kept in case the polish does no better.
    sweeps_impulses: Vec<(f64, f64)>,
    sweeps_v: Vec<Vector3<f64>>,
    /// Newton's gradient and step, 3 per local block; a trial point of the line search.
    gradient: Vec<f64>,
    step: Vec<f64>,
    trial: Vec<Vector3<f64>>,
    /// The Newton matrix by blocks: diagonal per local block, off-diagonal per ordered pair
    /// (rows of a, columns of b), and its triplets.
    diag: Vec<Matrix3<f64>>,
    off: FxHashMap<(usize, usize), Matrix3<f64>>,
    triplets: Vec<Triplet<usize, usize, f64>>,
}

/// What the polish did.
#[derive(Debug, Default, Clone, Copy)]
pub(super) struct Outcome {
    /// Outer iterations and Newton steps done.
    pub iterations: usize,
    pub newton_steps: usize,
}

/// Active-set bits of a row: normal active, friction sticking, sliding at +μpₙ, at −μpₙ.
const ACTIVE: u8 = 1;
const STICK: u8 = 2;
const SLIP_UP: u8 = 4;
const SLIP_DOWN: u8 = 8;

/// One row's impulses at `v` for the multipliers `lambda`: (pₙ, pₜ) and its active-set bits.
/// The friction bound is μ·pₙ(v), not μ·λₙ (see the module's header).
fn impulses(
    r: &ImpulseRow,
    lambda: (f64, f64),
    v: &[Vector3<f64>],
    penalty: f64,
) -> (f64, f64, u8) {
    let (mut pn, mut pt, mut bits) = (0.0, 0.0, 0);
    if r.wn > 0.0 {
        let z = lambda.0 + penalty / r.wn * (r.target - r.rate(v, true));
        if z > 0.0 {
            pn = z;
            bits |= ACTIVE;
        }
    }
    if r.wt > 0.0 && pn > 0.0 {
        let bound = r.mu * pn;
        let z = lambda.1 - penalty / r.wt * r.rate(v, false);
        pt = z.clamp(-bound, bound);
        bits |= if z.abs() < bound {
            STICK
        } else if z > 0.0 {
            SLIP_UP
        } else {
            SLIP_DOWN
        };
    }
    (pn, pt, bits)
}

impl PolishScratch {
    /// Keep the velocities before the impulses (per free block).
    pub(super) fn keep_start(&mut self, v: &[Vector3<f64>]) {
        self.start.clear();
        self.start.extend_from_slice(v);
    }

    /// Polish the sweeps' impulses in `rows` and velocities `v` (per free block; `involved`
    /// marks those taking impulses) until the law's residual is within `tolerance` (m/s) or
    /// `params.polish_iterations` outer iterations. Leaves the sweeps' result if the polish's
    /// residual is not smaller.
    pub(super) fn run(
        &mut self,
        rows: &mut [ImpulseRow],
        inv_mass: &[Matrix3<f64>],
        involved: &[bool],
        v: &mut [Vector3<f64>],
        params: &ImpactParams,
        tolerance: f64,
    ) -> Outcome {
        let mut outcome = Outcome::default();
        if !self.number_blocks(inv_mass, involved) {
            return outcome;
        }
        let before = residual(rows, v);
        self.sweeps_impulses.clear();
        self.sweeps_impulses
            .extend(rows.iter().map(|r| (r.pn, r.pt)));
        self.sweeps_v.clear();
        self.sweeps_v.extend_from_slice(v);
        self.lambda.clone_from(&self.sweeps_impulses);
        for _ in 0..params.polish_iterations {
            outcome.iterations += 1;
            match self.minimise(rows, v, params, tolerance) {
                Some(steps) => outcome.newton_steps += steps,
                None => {
                    self.balance(rows, inv_mass, v);
                    break;
                }
            }
            for (r, l) in rows.iter_mut().zip(self.lambda.iter_mut()) {
                let (pn, pt, _) = impulses(r, *l, v, params.polish_penalty);
                *l = (pn, pt);
                (r.pn, r.pt) = (pn, pt);
            }
            self.balance(rows, inv_mass, v);
            if residual(rows, v) <= tolerance {
                break;
            }
        }
        // Not better (or not a number): the sweeps' result stands.
        let better = residual(rows, v) < before;
        if !better {
            for (r, &(pn, pt)) in rows.iter_mut().zip(&self.sweeps_impulses) {
                (r.pn, r.pt) = (pn, pt);
            }
            v.copy_from_slice(&self.sweeps_v);
        }
        outcome
    }

    /// Number the involved free blocks and keep their masses; `false` if a mass matrix is
    /// singular (nothing to polish then).
    fn number_blocks(&mut self, inv_mass: &[Matrix3<f64>], involved: &[bool]) -> bool {
        self.local.clear();
        self.local.resize(involved.len(), usize::MAX);
        self.blocks.clear();
        self.mass.clear();
        self.inv_mass.clear();
        for (f, _) in involved.iter().enumerate().filter(|(_, &i)| i) {
            let Some(m) = inv_mass[f].try_inverse() else {
                return false;
            };
            self.local[f] = self.blocks.len();
            self.blocks.push(f);
            self.mass.push(m);
            self.inv_mass.push(inv_mass[f]);
        }
        true
    }

    /// v = v⁻ + M⁻¹Hᵀp for the rows' impulses: the momentum balance, exact by construction.
    fn balance(&self, rows: &[ImpulseRow], inv_mass: &[Matrix3<f64>], v: &mut [Vector3<f64>]) {
        for &f in &self.blocks {
            v[f] = self.start[f];
        }
        for r in rows {
            r.push(inv_mass, v, r.pn, true);
            r.push(inv_mass, v, r.pt, false);
        }
    }

    /// The merit θ(v) = ½ Σ Fᵀ M⁻¹ F of the inner equations F(v) = M(v − v⁻) − Hᵀp(v) (into
    /// `gradient` as a side effect), J/m.
    fn merit(&mut self, rows: &[ImpulseRow], v: &[Vector3<f64>], penalty: f64) -> f64 {
        self.force(rows, v, penalty, false);
        self.merit_of_gradient()
    }

    /// The inner equations at fixed λ by semismooth Newton from `v`, backtracking on the merit
    /// θ; the Newton steps taken, or `None` if a factorization failed (`v` is then the last
    /// iterate).
    fn minimise(
        &mut self,
        rows: &[ImpulseRow],
        v: &mut [Vector3<f64>],
        params: &ImpactParams,
        tolerance: f64,
    ) -> Option<usize> {
        let penalty = params.polish_penalty;
        // Done when F's velocity error (θ = ½ Σm δv²) is 1 % of the law's tolerance: rows at
        // the edge of the friction cone (pₙ ≈ 0) can flip their bits at round-off for ever.
        let mass: f64 = self.mass.iter().map(|m| m[(0, 0)]).sum();
        let small = 0.5 * mass * (1e-2 * tolerance).powi(2);
        for step in 1..=params.polish_newton_steps {
            self.force(rows, v, penalty, true);
            let theta = self.merit_of_gradient();
            if theta <= small {
                return Some(step - 1);
            }
            self.solve()?;
            let mut s = 1.0;
            self.trial.clear();
            self.trial.extend_from_slice(v);
            loop {
                for (l, &f) in self.blocks.iter().enumerate() {
                    let d = &self.step[3 * l..3 * l + 3];
                    self.trial[f] = v[f] + s * Vector3::new(d[0], d[1], d[2]);
                }
                let trial = std::mem::take(&mut self.trial);
                let trial_theta = self.merit(rows, &trial, penalty);
                self.trial = trial;
                // The Newton direction's slope of θ is −2θ.
                if trial_theta <= (1.0 - 2.0 * ARMIJO * s) * theta || s < MIN_STEP {
                    break;
                }
                s *= 0.5;
            }
            for &f in &self.blocks {
                v[f] = self.trial[f];
            }
            // F is piecewise linear in v: a full step that keeps the active set solved the
            // piece's linear equations, which are then F's.
            let same = rows
                .iter()
                .zip(&self.lambda)
                .zip(&self.pattern)
                .all(|((r, &l), &bits)| impulses(r, l, v, penalty).2 == bits);
            if s == 1.0 && same {
                return Some(step);
            }
        }
        Some(params.polish_newton_steps)
    }

    /// θ of the F in `gradient`.
    fn merit_of_gradient(&self) -> f64 {
        (0..self.blocks.len())
            .map(|l| {
                let f = Vector3::new(
                    self.gradient[3 * l],
                    self.gradient[3 * l + 1],
                    self.gradient[3 * l + 2],
                );
                0.5 * f.dot(&(self.inv_mass[l] * f))
            })
            .sum()
    }

    /// F(v) = M(v − v⁻) − Hᵀp(v) into `gradient`; with `jacobian`, also its Jacobian's blocks
    /// and the active pattern (into `pattern`): M + Σ_active ρₙhₙhₙᵀ + Σ_stick ρₜhₜhₜᵀ +
    /// Σ_slide σμρₙhₜhₙᵀ (the bound μpₙ(v) moves with the normal impulse; not symmetric).
    fn force(&mut self, rows: &[ImpulseRow], v: &[Vector3<f64>], penalty: f64, jacobian: bool) {
        let n = self.blocks.len();
        if jacobian {
            self.diag.clear();
            self.diag.extend_from_slice(&self.mass);
            self.off.clear();
            self.pattern.clear();
        }
        self.gradient.clear();
        self.gradient.resize(3 * n, 0.0);
        for (l, (&f, m)) in self.blocks.iter().zip(&self.mass).enumerate() {
            let g = m * (v[f] - self.start[f]);
            self.gradient[3 * l..3 * l + 3].copy_from_slice(g.as_slice());
        }
        for (k, r) in rows.iter().enumerate() {
            let (pn, pt, bits) = impulses(r, self.lambda[k], v, penalty);
            let a = r.fi.map(|f| self.local[f]);
            let b = r.fj.map(|f| self.local[f]);
            for (gi, gj, p) in [(&r.ni, &r.nj, pn), (&r.ti, &r.tj, pt)] {
                if let Some(a) = a {
                    for c in 0..3 {
                        self.gradient[3 * a + c] -= gi[c] * p;
                    }
                }
                if let Some(b) = b {
                    for c in 0..3 {
                        self.gradient[3 * b + c] -= gj[c] * p;
                    }
                }
            }
            if !jacobian {
                continue;
            }
            self.pattern.push(bits);
            let (normal, shear) = ((&r.ni, &r.nj), (&r.ti, &r.tj));
            if bits & ACTIVE != 0 {
                self.add(a, b, normal, normal, penalty / r.wn);
            }
            if bits & STICK != 0 {
                self.add(a, b, shear, shear, penalty / r.wt);
            }
            if bits & (SLIP_UP | SLIP_DOWN) != 0 {
                let sign = if bits & SLIP_UP != 0 { 1.0 } else { -1.0 };
                self.add(a, b, shear, normal, sign * r.mu * penalty / r.wn);
            }
        }
    }

    /// Add c·u wᵀ to the Jacobian, u = (u.0 on local block a, u.1 on b), w likewise.
    fn add(
        &mut self,
        a: Option<usize>,
        b: Option<usize>,
        u: (&Vector3<f64>, &Vector3<f64>),
        w: (&Vector3<f64>, &Vector3<f64>),
        c: f64,
    ) {
        if let Some(a) = a {
            self.diag[a] += c * u.0 * w.0.transpose();
        }
        if let Some(b) = b {
            self.diag[b] += c * u.1 * w.1.transpose();
        }
        if let (Some(a), Some(b)) = (a, b) {
            *self.off.entry((a, b)).or_insert_with(Matrix3::zeros) += c * u.0 * w.1.transpose();
            *self.off.entry((b, a)).or_insert_with(Matrix3::zeros) += c * u.1 * w.0.transpose();
        }
    }

    /// Solve the Newton system J·step = −F (F in `gradient`) by a sparse LU (faer); `None` if
    /// it failed.
    fn solve(&mut self) -> Option<()> {
        let n = 3 * self.blocks.len();
        self.triplets.clear();
        for (l, d) in self.diag.iter().enumerate() {
            for i in 0..3 {
                for j in 0..3 {
                    self.triplets
                        .push(Triplet::new(3 * l + i, 3 * l + j, d[(i, j)]));
                }
            }
        }
        for (&(a, b), m) in &self.off {
            for i in 0..3 {
                for j in 0..3 {
                    self.triplets
                        .push(Triplet::new(3 * a + i, 3 * b + j, m[(i, j)]));
                }
            }
        }
        let matrix =
            SparseColMat::<usize, f64>::try_new_from_triplets(n, n, &self.triplets).ok()?;
        let lu = matrix.as_ref().sp_lu().ok()?;
        self.step.clear();
        self.step.extend(self.gradient.iter().map(|g| -g));
        lu.solve_in_place_with_conj(
            Conj::No,
            MatMut::from_column_major_slice_mut(&mut self.step, n, 1),
        );
        self.step.iter().all(|x| x.is_finite()).then_some(())
    }
}
