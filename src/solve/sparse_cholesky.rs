//! Sparse Cholesky (faer) of the block system; the symbolic factorization (ordering and
//! elimination tree) is reused while the block pattern of contacts is unchanged.
use super::SolveError;
use crate::assembly::{BlockSystem, Dofs};
use faer::dyn_stack::{MemBuffer, MemStack};
use faer::linalg::cholesky::llt::factor::LltRegularization;
use faer::sparse::linalg::cholesky::{
    factorize_symbolic_cholesky, CholeskySymbolicParams, SymbolicCholesky, SymmetricOrdering,
};
use faer::sparse::{SparseColMatRef, SymbolicSparseColMatRef};
use faer::{Par, Side};

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
    mem: Option<MemBuffer>,
    pub symbolic_count: u64,
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
    fn rebuild_pattern(&mut self, sys: &BlockSystem, dofs: &Dofs) -> Result<(), SolveError> {
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
            CholeskySymbolicParams::default(),
        )
        .map_err(|e| SolveError::Backend(format!("{e:?}")))?;
        self.l_values = vec![0.0; symbolic.len_val()];
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
    ) -> Result<(), SolveError> {
        if self.symbolic.is_none() || self.pattern != sys.pairs || self.n != dofs.n {
            self.rebuild_pattern(sys, dofs)?;
        }
        self.fill_values(sys, dofs);
        let (Some(symbolic), Some(mem)) = (self.symbolic.as_ref(), self.mem.as_mut()) else {
            return Err(SolveError::Backend("symbolic factorization missing".into()));
        };
        let n = dofs.n;
        let a = SparseColMatRef::new(
            SymbolicSparseColMatRef::new_checked(n, n, &self.col_ptr, None, &self.row_idx),
            &self.values,
        );
        let stack = MemStack::new(mem);
        let llt = symbolic
            .factorize_numeric_llt(
                &mut self.l_values,
                a,
                Side::Upper,
                LltRegularization::default(),
                Par::Seq,
                stack,
                Default::default(),
            )
            .map_err(|_| SolveError::NotPositiveDefinite {
                dof: first_bad_pivot(sys, dofs),
            })?;
        let rhs = faer::MatMut::from_column_major_slice_mut(x, n, 1);
        llt.solve_in_place_with_conj(faer::Conj::No, rhs, Par::Seq, MemStack::new(mem));
        Ok(())
    }
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
