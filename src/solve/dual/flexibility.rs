//! Flexibility of each block (Zheng et al. 2016, Eqs. 11–16): the block's Newmark equation
//! `K_i d_i = q_i + C_i p_i` inverted once per step, so that `d_i = f_i + K_i⁻¹ C_i p_i`.
//! No global matrix is assembled: every block is condensed on its own (3×3 rigid, 6×6
//! deformable), in parallel when there are many.
use crate::assembly::{BlockSystem, Dofs};
use crate::geometry::{Mat6, Vec6};
use crate::solve::SolveError;
use nalgebra::{Cholesky, Matrix3};
use rayon::prelude::*;

/// One block's flexibility: `d = free + kinv · r` for generalized contact force `r`.
#[derive(Debug, Clone, Copy)]
pub struct BlockFlex {
    /// K⁻¹ (m/N, rad/(N·m), …); zero beyond the block's unknowns.
    pub kinv: Mat6,
    /// Flexibility vector f = K⁻¹ q: the step's increment with no contact force.
    pub free: Vec6,
}

/// Invert every free block's effective matrix (`sys.diag`) and apply it to its load
/// (`sys.rhs`). `parallel_from`: block count from which the loop runs on rayon.
pub fn flexibilities(
    sys: &BlockSystem,
    dofs: &Dofs,
    parallel_from: usize,
    out: &mut Vec<BlockFlex>,
) -> Result<(), SolveError> {
    let nf = dofs.block_of.len();
    out.resize(
        nf,
        BlockFlex {
            kinv: Mat6::zeros(),
            free: Vec6::zeros(),
        },
    );
    let one = |f: usize, slot: &mut BlockFlex| -> Result<(), SolveError> {
        let kinv = invert(&sys.diag[f], dofs.ndof[f]).ok_or(SolveError::NotPositiveDefinite {
            dof: dofs.offset[f],
        })?;
        let free = kinv * sys.rhs[f];
        if free.iter().any(|v| !v.is_finite()) {
            return Err(SolveError::NonFinite {
                dof: dofs.offset[f],
            });
        }
        *slot = BlockFlex { kinv, free };
        Ok(())
    };
    if nf >= parallel_from {
        out.par_iter_mut()
            .enumerate()
            .try_for_each(|(f, slot)| one(f, slot))
    } else {
        out.iter_mut()
            .enumerate()
            .try_for_each(|(f, slot)| one(f, slot))
    }
}

/// Inverse of the leading `ndof`×`ndof` part of a symmetric positive definite block matrix,
/// padded with zeros; `None` if it is not positive definite.
pub fn invert(k: &Mat6, ndof: usize) -> Option<Mat6> {
    let mut out = Mat6::zeros();
    if ndof == 3 {
        let k3: Matrix3<f64> = k.fixed_view::<3, 3>(0, 0).into_owned();
        let inv = Cholesky::new(k3)?.inverse();
        out.fixed_view_mut::<3, 3>(0, 0).copy_from(&inv);
    } else {
        out = Cholesky::new(*k)?.inverse();
    }
    if out.iter().all(|v| v.is_finite()) {
        Some(out)
    } else {
        None
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn inverse_of_rigid_and_deformable_blocks() {
        // An SPD matrix built as AᵀA + I: K·K⁻¹ = I on the block's unknowns, zeros beyond.
        let a = Mat6::from_fn(|r, c| ((r * 7 + c * 3) % 5) as f64 - 2.0);
        let k = a.transpose() * a + Mat6::identity();
        let inv = invert(&k, 6).expect("spd");
        assert!((k * inv - Mat6::identity()).abs().max() < 1e-12);
        let inv3 = invert(&k, 3).expect("spd");
        let k3 = k.fixed_view::<3, 3>(0, 0).into_owned();
        let prod = k3 * inv3.fixed_view::<3, 3>(0, 0);
        assert!((prod - Matrix3::identity()).abs().max() < 1e-12);
        assert_eq!(inv3.fixed_view::<3, 3>(3, 3).abs().max(), 0.0);
        assert!(invert(&(-k), 6).is_none());
    }
}
