//! Sparse Cholesky (faer) of the block system; the symbolic factorization (ordering and
//! elimination tree) is reused while the block pattern of contacts is unchanged, and the last
//! numeric factor preconditions a conjugate-gradient solve of the next system (the matrix
//! changes little from one step or open–close iteration to the next), so most solves cost a
//! few triangular solves instead of a factorization. A solve that does not converge in
//! [`SparseParams::max_reuse_iterations`] falls back to a fresh factorization.
use super::SolveError;
use crate::assembly::{BlockSystem, Dofs};
use faer::dyn_stack::{MemBuffer, MemStack};
use faer::linalg::cholesky::llt::factor::LltRegularization;
use faer::sparse::linalg::cholesky::{
    factorize_symbolic_cholesky, CholeskySymbolicParams, LltRef, SymbolicCholesky,
    SymmetricOrdering,
};
use faer::sparse::linalg::SupernodalThreshold;
use faer::sparse::{SparseColMatRef, SymbolicSparseColMatRef};
use faer::{Par, Side};

/// Relative change of an off-diagonal block that counts as a changed spring in
/// [`SparseCholesky::major_changes`]: a spring opening or closing changes its coupling block by
/// 1/m of its size when m springs join the two blocks (m ≤ 4 between two polygons' sides);
/// geometry drift changes it by the blocks' relative motion within one step, usually far less
/// (a misjudged count only costs time: the iteration still checks its own convergence).
const MAJOR_CHANGE: f64 = 0.2;

#[derive(Default)]
pub struct SparseCholesky {
    pattern: Vec<(usize, usize)>,
    n: usize,
    col_ptr: Vec<usize>,
    row_idx: Vec<usize>,
    values: Vec<f64>,
    /// Per column block: sorted row blocks (≤ column) with the off-diagonal slot (None = diag).
    col_blocks: Vec<Vec<(usize, Option<usize>)>>,
    symbolic: Option<SymbolicCholesky<usize>>,
    l_values: Vec<f64>,
    /// `l_values` holds a factor of a matrix with the current pattern (usable as preconditioner).
    factored: bool,
    /// The matrix values `l_values` factors (to count how much the matrix changed since).
    factored_values: Vec<f64>,
    /// Scratch of [`SparseCholesky::major_changes`]: per off-diagonal slot, the largest
    /// change of an entry and the largest entry.
    change: Vec<[f64; 2]>,
    mem: Option<MemBuffer>,
    /// Conjugate-gradient scratch: right-hand side, residual, preconditioned residual,
    /// search direction and its image.
    b: Vec<f64>,
    r: Vec<f64>,
    z: Vec<f64>,
    p: Vec<f64>,
    ap: Vec<f64>,
    pub symbolic_count: u64,
    pub numeric_count: u64,
    pub reuse_iterations: u64,
    /// With [`SparseParams::check_reuse`]: the largest difference between a reused-factor
    /// solution and the refactored solution of the same system, relative to the largest
    /// unknown of the latter.
    pub reuse_max_error: f64,
}

/// Tuning of the sparse path.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SparseParams {
    /// Force faer's supernodal factorization. Block systems of 2D masonry have dense 3×3 or
    /// 6×6 blocks and nested-dissection fill, where supernodes (dense kernels) beat faer's
    /// automatic choice here, the simplicial (scalar) one, by 1.6× at 400 blocks (callgrind,
    /// `examples/engine_scaling.rs` wall); on whole shaken steps simplicial costs 12–31 % more
    /// at 410 blocks and 76–182 % more at 1620 (docs/contact-solve.md §16). `false` leaves the
    /// choice to faer, which picks simplicial at 410 blocks but supernodal at 1620.
    pub supernodal: bool,
    /// Conjugate-gradient iterations preconditioned by the previous factor before refactoring;
    /// 0 always refactors. A step that changes no contact state converges in 1–2, one that
    /// opens or closes k springs in about k + 1; 8 covers the common case and caps the cost of
    /// a failed attempt below one factorization. A change of the matrix whose rank is
    /// already this large (estimated by `major_changes`) refactors without trying.
    pub max_reuse_iterations: usize,
    /// Convergence: the preconditioned residual (≈ the remaining error of the solution, since
    /// the preconditioner is nearly the matrix) below this fraction of the largest unknown.
    /// 1e-12 leaves the solution as accurate as the direct solve's round-off at the condition
    /// numbers of penalty systems (≈ 1e4 relative to eps).
    pub reuse_tolerance: f64,
    /// Check every reused-factor solve against a fresh factorization of the same system and
    /// keep the largest relative difference (`SparseCounts::reuse_max_error`). Off: it costs a
    /// factorization a solve, the work the reuse saves; for tests of the shortcut only (the
    /// reused factor itself is kept, so the run takes the same path as without the check).
    pub check_reuse: bool,
}

impl Default for SparseParams {
    fn default() -> Self {
        Self {
            supernodal: true,
            max_reuse_iterations: 8,
            reuse_tolerance: 1e-12,
            check_reuse: false,
        }
    }
}

impl std::fmt::Debug for SparseCholesky {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("SparseCholesky")
            .field("n", &self.n)
            .field("symbolic_count", &self.symbolic_count)
            .finish()
    }
}

impl SparseCholesky {
    fn rebuild_pattern(
        &mut self,
        sys: &BlockSystem,
        dofs: &Dofs,
        supernodal: bool,
    ) -> Result<(), SolveError> {
        let nf = dofs.ndof.len();
        self.col_blocks = vec![Vec::new(); nf];
        for b in 0..nf {
            self.col_blocks[b].push((b, None));
        }
        for (k, &(a, b)) in sys.pairs.iter().enumerate() {
            self.col_blocks[b].push((a, Some(k)));
        }
        for cb in &mut self.col_blocks {
            cb.sort_unstable_by_key(|e| e.0);
        }
        self.col_ptr.clear();
        self.row_idx.clear();
        self.col_ptr.push(0);
        for b in 0..nf {
            for c in 0..dofs.ndof[b] {
                for &(a, _) in &self.col_blocks[b] {
                    let rows = if a == b { c + 1 } else { dofs.ndof[a] };
                    for r in 0..rows {
                        self.row_idx.push(dofs.offset[a] + r);
                    }
                }
                self.col_ptr.push(self.row_idx.len());
            }
        }
        let n = dofs.n;
        let symb = SymbolicSparseColMatRef::new_checked(n, n, &self.col_ptr, None, &self.row_idx);
        let symbolic = factorize_symbolic_cholesky(
            symb,
            Side::Upper,
            SymmetricOrdering::Amd,
            CholeskySymbolicParams {
                supernodal_flop_ratio_threshold: if supernodal {
                    SupernodalThreshold::FORCE_SUPERNODAL
                } else {
                    SupernodalThreshold::AUTO
                },
                ..Default::default()
            },
        )
        .map_err(|e| SolveError::Backend(format!("{e:?}")))?;
        self.l_values = vec![0.0; symbolic.len_val()];
        self.factored = false;
        let req = symbolic
            .factorize_numeric_llt_scratch::<f64>(Par::Seq, Default::default())
            .or(symbolic.solve_in_place_scratch::<f64>(1, Par::Seq));
        self.mem = Some(MemBuffer::new(req));
        self.symbolic = Some(symbolic);
        self.pattern.clone_from(&sys.pairs);
        self.n = n;
        self.symbolic_count += 1;
        Ok(())
    }

    /// Copy the system's blocks into the compressed upper triangle `values` (column by
    /// column, as `rebuild_pattern` laid it out). With `track_changes` (a factor of the same
    /// pattern exists) it also notes, per off-diagonal slot, the largest change of an entry
    /// since the factored values and the largest entry, for [`SparseCholesky::major_changes`]:
    /// one pass over the values instead of two.
    fn fill_values(&mut self, sys: &BlockSystem, dofs: &Dofs, track_changes: bool) {
        self.values.resize(self.row_idx.len(), 0.0);
        if track_changes {
            self.change.clear();
            self.change.resize(sys.pairs.len(), [0.0; 2]);
        }
        let mut at = 0;
        for b in 0..dofs.ndof.len() {
            for c in 0..dofs.ndof[b] {
                for &(a, slot) in &self.col_blocks[b] {
                    // Column c of a 6×6 block (nalgebra stores columns contiguously).
                    let (src, rows) = match slot {
                        None => (&sys.diag[b].as_slice()[6 * c..], c + 1),
                        Some(k) => (&sys.off[k].as_slice()[6 * c..], dofs.ndof[a]),
                    };
                    let new = &src[..rows];
                    self.values[at..at + rows].copy_from_slice(new);
                    if let (true, Some(k)) = (track_changes, slot) {
                        let [delta, size] = &mut self.change[k];
                        for (new, old) in new.iter().zip(&self.factored_values[at..at + rows]) {
                            *delta = delta.max((new - old).abs());
                            *size = size.max(new.abs()).max(old.abs());
                        }
                    }
                    at += rows;
                }
            }
        }
    }

    pub fn factor_solve(
        &mut self,
        sys: &BlockSystem,
        dofs: &Dofs,
        x: &mut [f64],
        params: &SparseParams,
    ) -> Result<(), SolveError> {
        if self.symbolic.is_none() || self.pattern != sys.pairs || self.n != dofs.n {
            self.rebuild_pattern(sys, dofs, params.supernodal)?;
        }
        let try_reuse = self.factored && params.max_reuse_iterations > 0;
        self.fill_values(sys, dofs, try_reuse);
        if try_reuse && self.major_changes() < params.max_reuse_iterations {
            let rhs = params.check_reuse.then(|| x.to_vec());
            if self.reuse_solve(x, params) {
                if let Some(mut fresh) = rhs {
                    self.check_against_fresh(sys, dofs, x, &mut fresh)?;
                }
                return Ok(());
            }
        }
        self.factorize(sys, dofs)?;
        self.factor_solve_in_place(x)
    }

    /// `x ← (L Lᵀ)⁻¹ x` with the current factor.
    fn factor_solve_in_place(&mut self, x: &mut [f64]) -> Result<(), SolveError> {
        let (Some(symbolic), Some(mem)) = (self.symbolic.as_ref(), self.mem.as_mut()) else {
            return Err(SolveError::NoSymbolic);
        };
        let llt = LltRef::new(symbolic, &self.l_values);
        let rhs = faer::MatMut::from_column_major_slice_mut(x, self.n, 1);
        llt.solve_in_place_with_conj(faer::Conj::No, rhs, Par::Seq, MemStack::new(mem));
        Ok(())
    }

    /// About the rank of the change of the matrix since its last factorization (from the
    /// changes `fill_values` noted), which is
    /// about the number of conjugate-gradient iterations the reused factor needs: the number
    /// of off-diagonal blocks that changed by more than [`MAJOR_CHANGE`] of their size (each is
    /// at least one spring opened, closed or switched between stick and slip). Small changes
    /// of every block (the geometry and Δt drifting from step to step) are not counted: they
    /// keep the factor a good preconditioner. When the count reaches
    /// [`SparseParams::max_reuse_iterations`] the iteration cannot converge in time, and
    /// trying costs more than a factorization (the pile of examples/pile.rs spent 55 % of its
    /// solve time in such failed attempts: docs/pile.md).
    fn major_changes(&self) -> usize {
        self.change
            .iter()
            .filter(|[delta, size]| *delta > MAJOR_CHANGE * size)
            .count()
    }

    /// Solve the system with the right-hand side `fresh` by a fresh factorization, compare
    /// with the reused-factor solution `x`, and restore the reused factor (so a checked run
    /// takes the same path as an unchecked one).
    fn check_against_fresh(
        &mut self,
        sys: &BlockSystem,
        dofs: &Dofs,
        x: &[f64],
        fresh: &mut [f64],
    ) -> Result<(), SolveError> {
        let kept = (
            self.l_values.clone(),
            self.factored_values.clone(),
            self.numeric_count,
        );
        self.factorize(sys, dofs)?;
        self.factor_solve_in_place(fresh)?;
        let scale = max_abs(fresh);
        let diff = x
            .iter()
            .zip(fresh.iter())
            .fold(0.0_f64, |m, (a, b)| m.max((a - b).abs()));
        if scale > 0.0 {
            self.reuse_max_error = self.reuse_max_error.max(diff / scale);
        }
        (self.l_values, self.factored_values, self.numeric_count) = kept;
        Ok(())
    }

    /// Numeric factorization of the current values into `l_values`.
    fn factorize(&mut self, sys: &BlockSystem, dofs: &Dofs) -> Result<(), SolveError> {
        let (Some(symbolic), Some(mem)) = (self.symbolic.as_ref(), self.mem.as_mut()) else {
            return Err(SolveError::NoSymbolic);
        };
        let n = self.n;
        let a = SparseColMatRef::new(
            SymbolicSparseColMatRef::new_checked(n, n, &self.col_ptr, None, &self.row_idx),
            &self.values,
        );
        self.factored = false;
        symbolic
            .factorize_numeric_llt(
                &mut self.l_values,
                a,
                Side::Upper,
                LltRegularization::default(),
                Par::Seq,
                MemStack::new(mem),
                Default::default(),
            )
            .map_err(|_| SolveError::NotPositiveDefinite {
                dof: first_bad_pivot(sys, dofs),
            })?;
        self.factored = true;
        self.factored_values.clone_from(&self.values);
        self.numeric_count += 1;
        Ok(())
    }

    /// Conjugate gradients on the current values, preconditioned by the last factor. On
    /// success `x` (the right-hand side on entry) holds the solution; on failure (no
    /// convergence, or a breakdown that signals an indefinite matrix) `x` is restored and the
    /// caller refactors.
    fn reuse_solve(&mut self, x: &mut [f64], params: &SparseParams) -> bool {
        let n = self.n;
        let (Some(symbolic), Some(mem)) = (self.symbolic.as_ref(), self.mem.as_mut()) else {
            return false;
        };
        let llt = LltRef::new(symbolic, &self.l_values);
        let mut precondition = |v: &mut [f64]| {
            let m = faer::MatMut::from_column_major_slice_mut(v, n, 1);
            llt.solve_in_place_with_conj(faer::Conj::No, m, Par::Seq, MemStack::new(mem));
        };
        self.b.clear();
        self.b.extend_from_slice(x);
        precondition(x);
        symmetric_upper_matvec(&self.col_ptr, &self.row_idx, &self.values, x, &mut self.ap);
        self.r.clear();
        self.r
            .extend(self.b.iter().zip(&self.ap).map(|(b, ax)| b - ax));
        self.z.clone_from(&self.r);
        precondition(&mut self.z);
        self.p.clone_from(&self.z);
        let mut rz = dot(&self.r, &self.z);
        for _ in 0..params.max_reuse_iterations {
            let scale = max_abs(x);
            let err = max_abs(&self.z);
            if !(err.is_finite() && scale.is_finite()) {
                break;
            }
            if err <= params.reuse_tolerance * scale || err == 0.0 {
                return true;
            }
            self.reuse_iterations += 1;
            symmetric_upper_matvec(
                &self.col_ptr,
                &self.row_idx,
                &self.values,
                &self.p,
                &mut self.ap,
            );
            let pap = dot(&self.p, &self.ap);
            if !(pap > 0.0 && pap.is_finite()) {
                break;
            }
            let alpha = rz / pap;
            for i in 0..n {
                x[i] += alpha * self.p[i];
                self.r[i] -= alpha * self.ap[i];
            }
            self.z.clone_from(&self.r);
            precondition(&mut self.z);
            let rz_new = dot(&self.r, &self.z);
            let beta = rz_new / rz;
            rz = rz_new;
            for i in 0..n {
                self.p[i] = self.z[i] + beta * self.p[i];
            }
        }
        x.copy_from_slice(&self.b);
        false
    }
}

/// y = A·x for a symmetric matrix stored as its upper triangle in compressed columns, each
/// column's diagonal entry last (as `rebuild_pattern` lays them out: row blocks in increasing
/// order, the diagonal block last with rows 0..=c). Same operations in the same order as a
/// loop that tests `i != j` on every entry, without the test.
fn symmetric_upper_matvec(
    col_ptr: &[usize],
    row_idx: &[usize],
    values: &[f64],
    x: &[f64],
    y: &mut Vec<f64>,
) {
    y.clear();
    y.resize(x.len(), 0.0);
    for (j, (&xj, ends)) in x.iter().zip(col_ptr.windows(2)).enumerate() {
        let (rows, vals) = (&row_idx[ends[0]..ends[1]], &values[ends[0]..ends[1]]);
        let Some((&diag, below)) = vals.split_last() else {
            continue;
        };
        let mut acc = 0.0;
        for (&i, &v) in rows.iter().zip(below) {
            y[i] += v * xj;
            acc += v * x[i];
        }
        y[j] += diag * xj;
        y[j] += acc;
    }
}

fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}

fn max_abs(a: &[f64]) -> f64 {
    a.iter().fold(0.0_f64, |m, v| m.max(v.abs()))
}

/// Best effort at naming the unknown behind a failed factorization: the first non-positive
/// diagonal entry, else 0.
fn first_bad_pivot(sys: &BlockSystem, dofs: &Dofs) -> usize {
    for (f, d) in sys.diag.iter().enumerate() {
        for k in 0..dofs.ndof[f] {
            if d[(k, k)].is_nan() || d[(k, k)] <= 0.0 {
                return dofs.offset[f] + k;
            }
        }
    }
    0
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::{Mat6, Vec6};

    /// A block system of `nb` rigid blocks on a grid `cols` wide, each coupled to its right and
    /// upper neighbours (the pattern of a wall): diagonally dominant, so positive definite.
    fn grid_system(nb: usize, cols: usize) -> (BlockSystem, Dofs) {
        let mut dofs = Dofs::default();
        for b in 0..nb {
            dofs.free_index.push(Some(b));
            dofs.block_of.push(b);
            dofs.ndof.push(3);
            dofs.offset.push(3 * b);
        }
        dofs.n = 3 * nb;
        // Deterministic pseudo-random entries in [-1, 1).
        let mut seed = 12345_u64;
        let mut next = || {
            seed = seed
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (seed >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0
        };
        let mut sys = BlockSystem::default();
        for b in 0..nb {
            for n in [b + 1, b + cols] {
                if n < nb && (n != b + 1 || n % cols != 0) {
                    sys.pairs.push((b, n));
                }
            }
        }
        sys.pairs.sort_unstable();
        for _ in &sys.pairs {
            let mut m = Mat6::zeros();
            for c in 0..3 {
                for r in 0..3 {
                    m[(r, c)] = next();
                }
            }
            sys.off.push(m);
        }
        for _ in 0..nb {
            let mut m = Mat6::zeros();
            for c in 0..3 {
                for r in 0..c {
                    let v = 0.5 * next();
                    m[(r, c)] = v;
                    m[(c, r)] = v;
                }
                m[(c, c)] = 20.0 + next();
            }
            sys.diag.push(m);
            let mut r = Vec6::zeros();
            for k in 0..3 {
                r[k] = next();
            }
            sys.rhs.push(r);
        }
        (sys, dofs)
    }

    fn rhs_of(sys: &BlockSystem, dofs: &Dofs) -> Vec<f64> {
        let mut b = vec![0.0; dofs.n];
        for (f, r) in sys.rhs.iter().enumerate() {
            for k in 0..3 {
                b[dofs.offset[f] + k] = r[k];
            }
        }
        b
    }

    fn max_diff(a: &[f64], b: &[f64]) -> f64 {
        a.iter()
            .zip(b)
            .fold(0.0_f64, |m, (x, y)| m.max((x - y).abs()))
    }

    /// The supernodal factorization solves the system (residual 1e-12 of the right-hand side,
    /// by the matrix-vector product of the conjugate gradients, whose operand layout this also
    /// checks); after a small change of every block (geometry drift: no major change) the next
    /// solve reuses the factor and gives the fresh factorization's answer within the reuse
    /// tolerance's order (1e-11 of the solution, as tests/engine/solver_reuse.rs).
    #[test]
    fn supernodal_solve_and_reuse_after_a_small_change() {
        let (mut sys, dofs) = grid_system(150, 10);
        let mut chol = SparseCholesky::default();
        let params = SparseParams::default();
        let b = rhs_of(&sys, &dofs);
        let mut x = b.clone();
        chol.factor_solve(&sys, &dofs, &mut x, &params)
            .expect("positive definite");
        let mut ax = Vec::new();
        symmetric_upper_matvec(&chol.col_ptr, &chol.row_idx, &chol.values, &x, &mut ax);
        assert!(max_diff(&ax, &b) <= 1e-12 * max_abs(&b), "residual");
        for m in sys.diag.iter_mut().chain(sys.off.iter_mut()) {
            *m *= 1.0 + 1e-4;
        }
        let mut reused = b.clone();
        chol.factor_solve(&sys, &dofs, &mut reused, &params)
            .expect("positive definite");
        assert_eq!(chol.numeric_count, 1, "the second solve reuses the factor");
        assert!(chol.reuse_iterations >= 1);
        let mut fresh_chol = SparseCholesky::default();
        let mut fresh = b.clone();
        fresh_chol
            .factor_solve(&sys, &dofs, &mut fresh, &params)
            .expect("positive definite");
        let d = max_diff(&reused, &fresh);
        assert!(d <= 1e-11 * max_abs(&fresh), "reuse differs by {d:e}");
    }

    /// A change of many coupling blocks by more than `MAJOR_CHANGE` (springs opening) is
    /// counted as such and refactors without trying the old factor.
    #[test]
    fn major_changes_refactor() {
        let (mut sys, dofs) = grid_system(150, 10);
        let mut chol = SparseCholesky::default();
        let params = SparseParams::default();
        let mut x = rhs_of(&sys, &dofs);
        chol.factor_solve(&sys, &dofs, &mut x, &params)
            .expect("positive definite");
        for m in sys.off.iter_mut().take(params.max_reuse_iterations) {
            *m *= 0.5;
        }
        let mut x = rhs_of(&sys, &dofs);
        chol.factor_solve(&sys, &dofs, &mut x, &params)
            .expect("positive definite");
        assert_eq!(chol.major_changes(), params.max_reuse_iterations);
        assert_eq!(chol.numeric_count, 2, "refactored");
        assert_eq!(chol.reuse_iterations, 0, "without trying the old factor");
    }

    /// The simplicial path (faer's automatic choice) solves the same way.
    #[test]
    fn simplicial_factor_solves() {
        let (sys, dofs) = grid_system(60, 6);
        let mut chol = SparseCholesky::default();
        let params = SparseParams {
            supernodal: false,
            ..Default::default()
        };
        let b = rhs_of(&sys, &dofs);
        let mut x = b.clone();
        chol.factor_solve(&sys, &dofs, &mut x, &params)
            .expect("positive definite");
        let mut ax = Vec::new();
        symmetric_upper_matvec(&chol.col_ptr, &chol.row_idx, &chol.values, &x, &mut ax);
        let res = ax
            .iter()
            .zip(&b)
            .fold(0.0_f64, |m, (a, b)| m.max((a - b).abs()));
        assert!(res <= 1e-12 * max_abs(&b), "residual {res:e}");
    }
}
