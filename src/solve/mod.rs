//! Solve: the linear solver for the assembled block system, Shi's open–close iteration, the
//! dual contact solver and the impact law's impulse solve ([`impulse`]). Fifth stage of the
//! flow (after `assembly`, before `integrate`). Every use of faer is in this module: the
//! step's factorizations behind [`LinearSolver`] (a dense Cholesky for small systems, faer's
//! sparse Cholesky with a reused symbolic factorization for large ones), and the impulse
//! polish's sparse LU (`impulse/polish.rs`).
mod anderson;
mod dense_cholesky;
mod dissection;
pub mod dual;
pub mod impulse;
pub mod open_close;
mod repacked;
mod sparse_cholesky;

pub use sparse_cholesky::{
    FactorCost, ReuseTable, SparseOrdering, SparseParams, SupernodeRelax, TriangularSolve,
    REUSE_TABLE_LEN,
};

use crate::assembly::{BlockSystem, Dofs};

/// Why a linear solve failed; `dof` is the global unknown where it was detected.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum SolveError {
    #[error("system matrix not positive definite at unknown {dof}")]
    NotPositiveDefinite { dof: usize },
    #[error("non-finite value in the system at unknown {dof}")]
    NonFinite { dof: usize },
    /// faer's own error (its error types print only with `Debug`).
    #[error("sparse factorization failed: {0}")]
    Backend(String),
    /// A numeric factorization or solve was asked for before the symbolic one (a defect of
    /// the call order: `factorize` makes it).
    #[error("sparse factorization failed: symbolic factorization missing")]
    NoSymbolic,
}

/// Tuning of the linear solver.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SolverParams {
    /// Systems with at most this many unknowns use the dense factorization: below ~100 the
    /// dense kernel beats sparse bookkeeping (measured in benches/engine.rs).
    pub dense_limit: usize,
    /// The sparse path: supernodal factorization and reuse of the last factor as a
    /// preconditioner (see [`SparseParams`]).
    pub sparse: SparseParams,
}

impl Default for SolverParams {
    fn default() -> Self {
        Self {
            dense_limit: 96,
            sparse: SparseParams::default(),
        }
    }
}

/// Reusable linear solver (scratch buffers persist across steps).
#[derive(Debug, Default)]
pub struct LinearSolver {
    pub params: SolverParams,
    dense: dense_cholesky::DenseCholesky,
    sparse: sparse_cholesky::SparseCholesky,
    /// Number of symbolic factorizations done (diagnostic).
    pub symbolic_count: u64,
}

/// Work counters of the sparse path (diagnostics for benchmarks).
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct SparseCounts {
    pub symbolic: u64,
    pub numeric: u64,
    /// Conjugate-gradient iterations preconditioned by a reused factor.
    pub reuse_iterations: u64,
    /// See [`SparseParams::check_reuse`]; 0 when unchecked.
    pub reuse_max_error: f64,
    /// Reused-factor attempts per predicted iteration count (see [`ReuseTable`]).
    pub reuse_table: ReuseTable,
    /// Cost model of the current factor (zero before the first sparse solve).
    pub factor_cost: FactorCost,
    /// Reused-factor solves accepted at the start (`SparseParams::start_check_samples`).
    pub start_skips: u64,
    /// See [`SparseParams::start_check_audit`]; 0 when unaudited.
    pub start_check_misses: u64,
    /// Solves by the low-rank correction of the last factor
    /// ([`SparseParams::low_rank_max_rank`]), the sum of their ranks, the corrections
    /// declined (change too large) and failed (refinement short of the tolerance).
    pub low_rank_solves: u64,
    pub low_rank_rank: u64,
    pub low_rank_declined: u64,
    pub low_rank_failed: u64,
    /// Declined after the eigen-decomposition (rank above the bound), and Σ support³.
    pub low_rank_declined_rank: u64,
    pub low_rank_declined_cube: f64,
    /// Copies of the factor made for [`TriangularSolve::Repacked`] (one per factor solved).
    pub repacks: u64,
}

impl LinearSolver {
    pub fn new(params: SolverParams) -> Self {
        Self {
            params,
            ..Default::default()
        }
    }

    pub fn sparse_counts(&self) -> SparseCounts {
        SparseCounts {
            symbolic: self.sparse.symbolic_count,
            numeric: self.sparse.numeric_count,
            reuse_iterations: self.sparse.reuse_iterations,
            reuse_max_error: self.sparse.reuse_max_error,
            reuse_table: self.sparse.reuse_table,
            factor_cost: self.sparse.cost(),
            start_skips: self.sparse.start_skips,
            start_check_misses: self.sparse.start_check_misses,
            low_rank_solves: self.sparse.low_rank_solves,
            low_rank_rank: self.sparse.low_rank_rank,
            low_rank_declined: self.sparse.low_rank_declined,
            low_rank_failed: self.sparse.low_rank_failed,
            low_rank_declined_rank: self.sparse.low_rank_declined_rank,
            low_rank_declined_cube: self.sparse.low_rank_declined_cube,
            repacks: self.sparse.repack_count,
        }
    }

    /// Solve `sys` into `x` (length `dofs.n`).
    pub fn solve(
        &mut self,
        sys: &BlockSystem,
        dofs: &Dofs,
        x: &mut Vec<f64>,
    ) -> Result<(), SolveError> {
        x.clear();
        x.resize(dofs.n, 0.0);
        for (f, r) in sys.rhs.iter().enumerate() {
            for k in 0..dofs.ndof[f] {
                if !r[k].is_finite() {
                    return Err(SolveError::NonFinite {
                        dof: dofs.offset[f] + k,
                    });
                }
                x[dofs.offset[f] + k] = r[k];
            }
        }
        if dofs.n <= self.params.dense_limit {
            self.dense.factor_solve(sys, dofs, x)?;
        } else {
            let before = self.sparse.symbolic_count;
            self.sparse
                .factor_solve(sys, dofs, x, &self.params.sparse)?;
            self.symbolic_count += self.sparse.symbolic_count - before;
        }
        if let Some(dof) = x.iter().position(|v| !v.is_finite()) {
            return Err(SolveError::NonFinite { dof });
        }
        Ok(())
    }
}
