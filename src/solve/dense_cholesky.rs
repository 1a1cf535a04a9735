//! Dense Cholesky factorization and solve for small systems, in reused buffers.
use super::SolveError;
use crate::assembly::{BlockSystem, Dofs};

#[derive(Debug, Default)]
pub struct DenseCholesky {
    /// Row-major n×n, lower triangle holds L after factorization.
    a: Vec<f64>,
}

impl DenseCholesky {
    pub fn factor_solve(
        &mut self,
        sys: &BlockSystem,
        dofs: &Dofs,
        x: &mut [f64],
    ) -> Result<(), SolveError> {
        let n = dofs.n;
        self.a.clear();
        self.a.resize(n * n, 0.0);
        let a = &mut self.a;
        for (f, d) in sys.diag.iter().enumerate() {
            let (o, m) = (dofs.offset[f], dofs.ndof[f]);
            for r in 0..m {
                for c in 0..m {
                    a[(o + r) * n + o + c] = d[(r, c)];
                }
            }
        }
        for (k, &(p, q)) in sys.pairs.iter().enumerate() {
            let blk = &sys.off[k];
            let (op, mp, oq, mq) = (dofs.offset[p], dofs.ndof[p], dofs.offset[q], dofs.ndof[q]);
            for r in 0..mp {
                for c in 0..mq {
                    a[(op + r) * n + oq + c] = blk[(r, c)];
                    a[(oq + c) * n + op + r] = blk[(r, c)];
                }
            }
        }
        for j in 0..n {
            let mut d = a[j * n + j];
            for k in 0..j {
                d -= a[j * n + k] * a[j * n + k];
            }
            if !d.is_finite() {
                return Err(SolveError::NonFinite { dof: j });
            }
            if d <= 0.0 {
                return Err(SolveError::NotPositiveDefinite { dof: j });
            }
            let d = d.sqrt();
            a[j * n + j] = d;
            for i in (j + 1)..n {
                let mut s = a[i * n + j];
                for k in 0..j {
                    s -= a[i * n + k] * a[j * n + k];
                }
                a[i * n + j] = s / d;
            }
        }
        for i in 0..n {
            let mut s = x[i];
            for k in 0..i {
                s -= a[i * n + k] * x[k];
            }
            x[i] = s / a[i * n + i];
        }
        for i in (0..n).rev() {
            let mut s = x[i];
            for k in (i + 1)..n {
                s -= a[k * n + i] * x[k];
            }
            x[i] = s / a[i * n + i];
        }
        Ok(())
    }
}
