//! Projection onto the contact-force set of the quasi-variational inequality (Zheng et al.
//! 2016, Eqs. 36–39, Appendix A): per contact, the normal force onto `[−T, ∞)` (T the tensile
//! strength of an intact bond, else 0) and the tangential force onto `[−τ, τ]` with the
//! shear strength `τ = c + μ·max(0, p_n)` taken from the *current* approximation `p`, so the
//! set depends on the solution (the "quasi" of QVI).
use super::gap::{Pair, PairTerms};

/// Shear strength τ(p_n) of a contact, N (≥ 0).
#[inline]
pub fn shear_strength(t: &PairTerms, normal: f64) -> f64 {
    t.cohesion + t.tan_phi * normal.max(0.0)
}

/// `Π(q; p)` for one contact: `q` projected onto the set `X(p)` fixed by the normal force of
/// the approximation `p_n`.
#[inline]
pub fn project(t: &PairTerms, q: Pair, p_normal: f64) -> Pair {
    let n = q[0].max(-t.tension);
    let tau = shear_strength(t, p_normal);
    [n, q[1].clamp(-tau, tau)]
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::Vec6;

    fn terms(tan_phi: f64, cohesion: f64, tension: f64) -> PairTerms {
        let z = Vec6::zeros();
        PairTerms {
            fi: None,
            fj: None,
            wn_i: z,
            wt_i: z,
            wn_j: z,
            wt_j: z,
            kn_i: z,
            kt_i: z,
            kn_j: z,
            kt_j: z,
            constant: [0.0; 2],
            diag: [1.0; 2],
            tan_phi,
            cohesion,
            tension,
        }
    }

    #[test]
    fn projection_onto_the_coulomb_box_of_the_approximation() {
        let t = terms(0.5, 0.0, 0.0);
        // Tension is cut to zero, shear to μ·p_n of the approximation (not of q).
        assert_eq!(project(&t, [-3.0, 7.0], 10.0), [0.0, 5.0]);
        assert_eq!(project(&t, [4.0, -7.0], 10.0), [4.0, -5.0]);
        assert_eq!(project(&t, [4.0, 1.0], 10.0), [4.0, 1.0]);
        // A negative approximation normal gives no friction.
        assert_eq!(project(&t, [4.0, 1.0], -2.0), [4.0, 0.0]);
        // Bonded joint: tension down to −T, shear up to c + μ p_n.
        let b = terms(0.5, 2.0, 3.0);
        assert_eq!(project(&b, [-5.0, 9.0], 4.0), [-3.0, 4.0]);
    }
}
