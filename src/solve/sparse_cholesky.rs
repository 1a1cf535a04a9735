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
    SymbolicCholeskyRaw, SymmetricOrdering,
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
    /// The supernodal factor's layout for [`FactorLayout::solve`] (empty: simplicial, solved
    /// by faer).
    layout: FactorLayout,
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
    /// `examples/engine_scaling.rs` wall).
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
        self.layout = FactorLayout::of(&symbolic);
        self.symbolic = Some(symbolic);
        self.pattern.clone_from(&sys.pairs);
        self.n = n;
        self.symbolic_count += 1;
        Ok(())
    }

    fn fill_values(&mut self, sys: &BlockSystem, dofs: &Dofs) {
        self.values.clear();
        for b in 0..dofs.ndof.len() {
            for c in 0..dofs.ndof[b] {
                for &(a, slot) in &self.col_blocks[b] {
                    match slot {
                        None => {
                            for r in 0..=c {
                                self.values.push(sys.diag[b][(r, c)]);
                            }
                        }
                        Some(k) => {
                            for r in 0..dofs.ndof[a] {
                                self.values.push(sys.off[k][(r, c)]);
                            }
                        }
                    }
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
        self.fill_values(sys, dofs);
        if self.factored
            && params.max_reuse_iterations > 0
            && self.major_changes(sys, dofs) < params.max_reuse_iterations
        {
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

    /// `x ← (L Lᵀ)⁻¹ x` with the current factor: [`FactorLayout::solve`] for a supernodal
    /// factor, faer's own solve for a simplicial one.
    fn factor_solve_in_place(&mut self, x: &mut [f64]) -> Result<(), SolveError> {
        let (Some(symbolic), Some(mem)) = (self.symbolic.as_ref(), self.mem.as_mut()) else {
            return Err(SolveError::NoSymbolic);
        };
        if !self.layout.solve(&self.l_values, x) {
            let llt = LltRef::new(symbolic, &self.l_values);
            let rhs = faer::MatMut::from_column_major_slice_mut(x, self.n, 1);
            llt.solve_in_place_with_conj(faer::Conj::No, rhs, Par::Seq, MemStack::new(mem));
        }
        Ok(())
    }

    /// About the rank of the change of the matrix since its last factorization, which is
    /// about the number of conjugate-gradient iterations the reused factor needs: the number
    /// of off-diagonal blocks that changed by more than [`MAJOR_CHANGE`] of their size (each is
    /// at least one spring opened, closed or switched between stick and slip). Small changes
    /// of every block (the geometry and Δt drifting from step to step) are not counted: they
    /// keep the factor a good preconditioner. When the count reaches
    /// [`SparseParams::max_reuse_iterations`] the iteration cannot converge in time, and
    /// trying costs more than a factorization (the pile of examples/pile.rs spent 55 % of its
    /// solve time in such failed attempts: docs/pile.md).
    fn major_changes(&mut self, sys: &BlockSystem, dofs: &Dofs) -> usize {
        self.change.clear();
        self.change.resize(sys.pairs.len(), [0.0; 2]);
        let mut at = 0;
        for b in 0..dofs.ndof.len() {
            for c in 0..dofs.ndof[b] {
                for &(a, slot) in &self.col_blocks[b] {
                    let rows = if slot.is_none() { c + 1 } else { dofs.ndof[a] };
                    if let Some(k) = slot {
                        let [delta, size] = &mut self.change[k];
                        for (new, old) in self.values[at..at + rows]
                            .iter()
                            .zip(&self.factored_values[at..at + rows])
                        {
                            *delta = delta.max((new - old).abs());
                            *size = size.max(new.abs()).max(old.abs());
                        }
                    }
                    at += rows;
                }
            }
        }
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
        let (layout, l_values) = (&mut self.layout, &self.l_values);
        let mut precondition = |v: &mut [f64]| {
            if !layout.solve(l_values, v) {
                let m = faer::MatMut::from_column_major_slice_mut(v, n, 1);
                llt.solve_in_place_with_conj(faer::Conj::No, m, Par::Seq, MemStack::new(mem));
            }
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

/// The supernodal factor L of faer (`SymbolicSupernodalCholesky`) as plain index arrays, and
/// its triangular solves as plain loops. faer's own `solve_in_place_with_conj` dispatches a
/// dense triangular solve and a matrix product per supernode, which at the 3–30-column
/// supernodes of a masonry wall costs ~10× the arithmetic (callgrind, 410 stones: 783 k
/// instructions a solve for ~60 k multiply-adds, 34 % of a shaken step; docs/contact-solve.md
/// §14). Same factor, same permutation; the sums are taken in another order, so the result
/// differs from faer's by round-off only.
#[derive(Debug, Default)]
struct FactorLayout {
    /// `w[i] = x[perm_fwd[i]]` (the fill-reducing ordering), and back `x[i] = w[perm_inv[i]]`.
    perm_fwd: Vec<usize>,
    perm_inv: Vec<usize>,
    /// Per supernode s: its first column `begin[s]` (and `begin[s + 1]` its end), the range
    /// `row_ptr[s]..row_ptr[s + 1]` of `rows` holding the row indices below its diagonal block,
    /// and the offset `val_ptr[s]` of its column-major values (diagonal block on top).
    begin: Vec<usize>,
    row_ptr: Vec<usize>,
    rows: Vec<usize>,
    val_ptr: Vec<usize>,
    /// The permuted right-hand side.
    work: Vec<f64>,
}

impl FactorLayout {
    /// The layout of `symbolic` if it is supernodal, else an empty layout (faer then solves).
    fn of(symbolic: &SymbolicCholesky<usize>) -> Self {
        let SymbolicCholeskyRaw::Supernodal(sn) = symbolic.raw() else {
            return Self::default();
        };
        let n = sn.nrows();
        let (perm_fwd, perm_inv) = match symbolic.perm() {
            Some(p) => (p.arrays().0.to_vec(), p.arrays().1.to_vec()),
            None => ((0..n).collect(), (0..n).collect()),
        };
        let ns = sn.n_supernodes();
        let mut layout = Self {
            perm_fwd,
            perm_inv,
            begin: Vec::with_capacity(ns + 1),
            row_ptr: Vec::with_capacity(ns + 1),
            rows: Vec::new(),
            val_ptr: sn.col_ptr_for_val().to_vec(),
            work: vec![0.0; n],
        };
        layout.row_ptr.push(0);
        for s in 0..ns {
            let node = sn.supernode(s);
            layout.begin.push(node.start());
            layout.rows.extend_from_slice(node.pattern());
            layout.row_ptr.push(layout.rows.len());
        }
        layout.begin.push(n);
        layout
    }

    /// `x ← (L Lᵀ)⁻¹ x` with the factor values `l` (faer's supernodal layout). Returns false,
    /// leaving `x` untouched, when there is no supernodal layout.
    fn solve(&mut self, l: &[f64], x: &mut [f64]) -> bool {
        let n = x.len();
        if self.perm_fwd.len() != n || self.begin.is_empty() {
            return false;
        }
        let w = &mut self.work;
        for (wi, &p) in w.iter_mut().zip(&self.perm_fwd) {
            *wi = x[p];
        }
        let ns = self.begin.len() - 1;
        // L y = b, column by column.
        for s in 0..ns {
            let (b, e) = (self.begin[s], self.begin[s + 1]);
            let size = e - b;
            let rows = &self.rows[self.row_ptr[s]..self.row_ptr[s + 1]];
            let nr = size + rows.len();
            let ls = &l[self.val_ptr[s]..self.val_ptr[s + 1]];
            for j in 0..size {
                let col = &ls[j * nr..(j + 1) * nr];
                let xj = w[b + j] / col[j];
                w[b + j] = xj;
                for (wi, &v) in w[b + j + 1..e].iter_mut().zip(&col[j + 1..size]) {
                    *wi -= v * xj;
                }
                for (&r, &v) in rows.iter().zip(&col[size..]) {
                    w[r] -= v * xj;
                }
            }
        }
        // Lᵀ z = y, backwards.
        for s in (0..ns).rev() {
            let (b, e) = (self.begin[s], self.begin[s + 1]);
            let size = e - b;
            let rows = &self.rows[self.row_ptr[s]..self.row_ptr[s + 1]];
            let nr = size + rows.len();
            let ls = &l[self.val_ptr[s]..self.val_ptr[s + 1]];
            for j in (0..size).rev() {
                let col = &ls[j * nr..(j + 1) * nr];
                let mut acc = w[b + j];
                for (wi, &v) in w[b + j + 1..e].iter().zip(&col[j + 1..size]) {
                    acc -= v * wi;
                }
                for (&r, &v) in rows.iter().zip(&col[size..]) {
                    acc -= v * w[r];
                }
                w[b + j] = acc / col[j];
            }
        }
        for (xi, &p) in x.iter_mut().zip(&self.perm_inv) {
            *xi = w[p];
        }
        true
    }
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

    /// The plain-loop triangular solves on faer's supernodal factor give faer's own solve within
    /// round-off (1e-13 of the solution: both are backward stable on a matrix of condition ~2),
    /// and the solution satisfies the system (residual 1e-12 of the right-hand side).
    #[test]
    fn supernodal_layout_solve_matches_faer() {
        let (sys, dofs) = grid_system(150, 10);
        let mut chol = SparseCholesky::default();
        let params = SparseParams::default();
        let b = rhs_of(&sys, &dofs);
        let mut x = b.clone();
        chol.factor_solve(&sys, &dofs, &mut x, &params)
            .expect("positive definite");
        assert!(!chol.layout.begin.is_empty(), "the factor is supernodal");
        let mut faer_x = b.clone();
        let symbolic = chol.symbolic.as_ref().expect("symbolic");
        let llt = LltRef::new(symbolic, &chol.l_values);
        let mem = chol.mem.as_mut().expect("scratch");
        llt.solve_in_place_with_conj(
            faer::Conj::No,
            faer::MatMut::from_column_major_slice_mut(&mut faer_x, dofs.n, 1),
            Par::Seq,
            MemStack::new(mem),
        );
        let scale = max_abs(&faer_x);
        let diff = x
            .iter()
            .zip(&faer_x)
            .fold(0.0_f64, |m, (a, b)| m.max((a - b).abs()));
        assert!(diff <= 1e-13 * scale, "differs by {diff:e} of {scale:e}");
        let mut ax = Vec::new();
        symmetric_upper_matvec(&chol.col_ptr, &chol.row_idx, &chol.values, &x, &mut ax);
        let res = ax
            .iter()
            .zip(&b)
            .fold(0.0_f64, |m, (a, b)| m.max((a - b).abs()));
        assert!(res <= 1e-12 * max_abs(&b), "residual {res:e}");
    }

    /// The simplicial path (no supernodal layout) still solves, through faer.
    #[test]
    fn simplicial_factor_falls_back_to_faer() {
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
        let simplicial = matches!(
            chol.symbolic.as_ref().map(|s| s.raw()),
            Some(SymbolicCholeskyRaw::Simplicial(_))
        );
        assert!(simplicial, "faer's automatic choice is simplicial here");
        assert!(chol.layout.begin.is_empty(), "no supernodal layout");
        let mut ax = Vec::new();
        symmetric_upper_matvec(&chol.col_ptr, &chol.row_idx, &chol.values, &x, &mut ax);
        let res = ax
            .iter()
            .zip(&b)
            .fold(0.0_f64, |m, (a, b)| m.max((a - b).abs()));
        assert!(res <= 1e-12 * max_abs(&b), "residual {res:e}");
    }
}
