//! Contact springs of Shi's penalty method: a normal spring for every closed contact, a shear
//! spring for locked ones, and Coulomb friction (with cohesion while bonded) as point loads on
//! sliding ones. Driven blocks' prescribed displacements enter the gap constants.
use super::{BlockSystem, CouplingSlot, Dofs};
use crate::contact::{Contact, ContactState};
use crate::geometry::{Mat6, Vec6};

/// Spring constants and friction of the contacts, per contact.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SpringParams {
    /// Normal penalty stiffness, N/m.
    pub normal: f64,
    /// Shear penalty stiffness, N/m.
    pub shear: f64,
    /// Gap hysteresis, m: a closed contact opens only beyond +tol, an open one closes only
    /// below −tol, so joints at a round-off gap (blocks side by side) do not flip each
    /// iteration.
    pub gap_tolerance: f64,
    /// Weight of the step-start forces against the step-end ones in the integrator's averages,
    /// (1 − γ)/γ: 1 for the trapezoidal rule, 0 for Shi's DDA integrator (γ = 1), whose steps
    /// do not remember the start forces. Used by [`release_load`].
    pub release_weight: f64,
}

/// Friction data of a contact's joint.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct JointLaw {
    /// tan φ.
    pub tan_phi: f64,
    /// Pa.
    pub cohesion: f64,
    /// Pa.
    pub tensile_strength: f64,
}

/// Prescribed displacement increment of a block over the step (driven blocks), m; zero for
/// blocks with unknowns or fixed blocks.
pub type Prescribed = [f64; 2];

/// Gap and shear constants including prescribed motion of driven blocks.
#[inline]
pub fn constants(c: &Contact, prescribed: &[Prescribed]) -> (f64, f64) {
    let ui = prescribed[c.vertex_block];
    let uj = prescribed[c.edge_block];
    let du = [ui[0] - uj[0], ui[1] - uj[1]];
    let g = c.g0 + c.n.x * du[0] + c.n.y * du[1];
    let s = c.s0 + c.t.x * du[0] + c.t.y * du[1];
    (g, s)
}

/// Extra normal load (N, along the gap gradient, positive pushes apart) on a contact that was
/// compressed at the step start and opens during the step. The trapezoidal rule averages the
/// start force N₀ (inside a₀) with the end force 0, returning k|g₀|/2 · Δg of work while the
/// spring held only k g₀²/2: a spurious energy gain at every release. The discrete gradient of
/// the penalty energy keeps only the fraction λ = |g₀|/(|g₀| + g₁) of N₀ (the spring acts
/// until the gap closes at zero); this load, weighted like a₀, removes the rest.
#[inline]
pub fn release_load(c: &Contact, springs: &SpringParams) -> f64 {
    if springs.release_weight > 0.0 && c.start_normal_force > 0.0 && c.release_factor < 1.0 {
        springs.release_weight * (c.release_factor - 1.0) * c.start_normal_force
    } else {
        0.0
    }
}

/// Coulomb limit of the shear force of a contact, N (≥ 0).
#[inline]
pub fn shear_limit(c: &Contact, law: &JointLaw, normal_force: f64) -> f64 {
    let coh = if c.bonded {
        law.cohesion * c.length
    } else {
        0.0
    };
    (normal_force.max(0.0) * law.tan_phi + coh).max(0.0)
}

/// Add the springs and friction loads of every closed contact to the system.
pub fn add_contacts(
    sys: &mut BlockSystem,
    dofs: &Dofs,
    contacts: &[Contact],
    laws: &[JointLaw],
    springs: &SpringParams,
    prescribed: &[Prescribed],
) {
    assemble::<true>(sys, dofs, contacts, laws, springs, prescribed);
}

/// The right-hand side part of [`add_contacts`] alone (spring gap constants, friction and
/// release loads), for a matrix that already holds the springs of the same contact states: the
/// same operations on `rhs` in the same order as [`add_contacts`], so the right-hand side is
/// the same to the bit. The open–close loop uses it when no spring was added or removed since
/// its last assembly (docs/contact-solve.md §19).
pub fn add_contact_loads(
    sys: &mut BlockSystem,
    dofs: &Dofs,
    contacts: &[Contact],
    laws: &[JointLaw],
    springs: &SpringParams,
    prescribed: &[Prescribed],
) {
    assemble::<false>(sys, dofs, contacts, laws, springs, prescribed);
}

/// Which springs a contact's state puts into the matrix (normal: closed; shear: locked):
/// two states with the same key assemble the same matrix entries.
#[inline]
pub fn spring_key(state: ContactState) -> u8 {
    match state {
        ContactState::Open => 0,
        ContactState::Sliding { .. } => 1,
        ContactState::Locked => 2,
    }
}

/// [`add_contacts`], with the matrix part (`MATRIX`) or without.
#[inline(always)]
fn assemble<const MATRIX: bool>(
    sys: &mut BlockSystem,
    dofs: &Dofs,
    contacts: &[Contact],
    laws: &[JointLaw],
    springs: &SpringParams,
    prescribed: &[Prescribed],
) {
    for (k, (c, law)) in contacts.iter().zip(laws).enumerate() {
        if !c.state.is_closed() {
            let l = release_load(c, springs);
            if l != 0.0 {
                if let Some(i) = dofs.free_index[c.vertex_block] {
                    sys.rhs[i] += c.e_i * l;
                }
                if let Some(j) = dofs.free_index[c.edge_block] {
                    sys.rhs[j] -= c.e_j * l;
                }
            }
            continue;
        }
        let fi = dofs.free_index[c.vertex_block];
        let fj = dofs.free_index[c.edge_block];
        let slot = sys.contact_slots[k];
        let (g0, s0) = constants(c, prescribed);
        if c.state == ContactState::Locked && (fi.is_none() || fi != fj) {
            // Both springs in one pass over the contact's blocks (docs/contact-solve.md §37).
            add_locked::<MATRIX>(sys, dofs, (fi, fj, slot), c, springs, (g0, s0));
            continue;
        }
        add_spring::<MATRIX>(
            sys,
            dofs,
            (fi, fj, slot),
            &c.e_i,
            &c.e_j,
            springs.normal,
            g0,
        );
        match c.state {
            ContactState::Locked => {
                add_spring::<MATRIX>(sys, dofs, (fi, fj, slot), &c.f_i, &c.f_j, springs.shear, s0)
            }
            ContactState::Sliding { dir } => {
                let f = dir * shear_limit(c, law, c.friction_normal);
                if let Some(a) = fi {
                    sys.rhs[a] -= c.f_i * f;
                }
                if let Some(b) = fj {
                    sys.rhs[b] += c.f_j * f;
                }
            }
            ContactState::Open => {}
        }
    }
}

/// Spring of stiffness `k` on the measure `m = m0 + a·D_i − b·D_j`: energy k/2·m². The
/// matrix part only with `MATRIX` (the right-hand side always).
#[inline]
fn add_spring<const MATRIX: bool>(
    sys: &mut BlockSystem,
    dofs: &Dofs,
    (fi, fj, slot): (Option<usize>, Option<usize>, Option<CouplingSlot>),
    a: &Vec6,
    b: &Vec6,
    k: f64,
    m0: f64,
) {
    let rigid = |f: usize| dofs.ndof[f] == 3;
    if let Some(i) = fi {
        if MATRIX {
            rank_one(&mut sys.diag[i], k, a, a, rigid(i));
        }
        sys.rhs[i] -= a * (k * m0);
    }
    if let Some(j) = fj {
        if MATRIX {
            rank_one(&mut sys.diag[j], k, b, b, rigid(j));
        }
        sys.rhs[j] += b * (k * m0);
    }
    if !MATRIX {
        return;
    }
    if let (Some(i), Some(j), Some(slot)) = (fi, fj, slot) {
        let both_rigid = rigid(i) && rigid(j);
        let off = &mut sys.off[slot.slot];
        if slot.vertex_is_row {
            rank_one(off, -k, a, b, both_rigid);
        } else {
            rank_one(off, -k, b, a, both_rigid);
        }
    }
}

/// A locked contact's normal spring (gradients `e`, stiffness `springs.normal`, measure
/// constant g0) and shear spring (`f`, `springs.shear`, s0), as [`add_spring`] twice (normal,
/// then shear) but in one pass: each entry of a block and of the right-hand side takes the
/// normal spring's term, then the shear spring's, the same operations in the same order, so
/// the system is the same to the bit. Only for a contact whose two blocks are distinct (`fi !=
/// fj`), so that no entry is touched by both blocks' terms in between.
#[inline]
fn add_locked<const MATRIX: bool>(
    sys: &mut BlockSystem,
    dofs: &Dofs,
    (fi, fj, slot): (Option<usize>, Option<usize>, Option<CouplingSlot>),
    c: &Contact,
    springs: &SpringParams,
    (g0, s0): (f64, f64),
) {
    let (kn, ks) = (springs.normal, springs.shear);
    let rigid = |f: usize| dofs.ndof[f] == 3;
    if let Some(i) = fi {
        if MATRIX {
            rank_two(
                &mut sys.diag[i],
                [kn, ks],
                [&c.e_i, &c.f_i],
                [&c.e_i, &c.f_i],
                rigid(i),
            );
        }
        let r = &mut sys.rhs[i];
        *r -= c.e_i * (kn * g0);
        *r -= c.f_i * (ks * s0);
    }
    if let Some(j) = fj {
        if MATRIX {
            rank_two(
                &mut sys.diag[j],
                [kn, ks],
                [&c.e_j, &c.f_j],
                [&c.e_j, &c.f_j],
                rigid(j),
            );
        }
        let r = &mut sys.rhs[j];
        *r += c.e_j * (kn * g0);
        *r += c.f_j * (ks * s0);
    }
    if !MATRIX {
        return;
    }
    if let (Some(i), Some(j), Some(slot)) = (fi, fj, slot) {
        let both_rigid = rigid(i) && rigid(j);
        let off = &mut sys.off[slot.slot];
        let (row, col) = if slot.vertex_is_row {
            ([&c.e_i, &c.f_i], [&c.e_j, &c.f_j])
        } else {
            ([&c.e_j, &c.f_j], [&c.e_i, &c.f_i])
        };
        rank_two(off, [-kn, -ks], row, col, both_rigid);
    }
}

/// `m += k₀·x₀·y₀ᵀ`, then `m += k₁·x₁·y₁ᵀ`, entry by entry ([`rank_one`] twice, fused).
#[inline]
fn rank_two(m: &mut Mat6, k: [f64; 2], x: [&Vec6; 2], y: [&Vec6; 2], rigid: bool) {
    if rigid {
        rank_two_n::<3>(m, k, x, y);
    } else {
        rank_two_n::<6>(m, k, x, y);
    }
}

#[inline(always)]
fn rank_two_n<const N: usize>(m: &mut Mat6, k: [f64; 2], x: [&Vec6; 2], y: [&Vec6; 2]) {
    let m = m.as_mut_slice();
    let (x0, y0, x1, y1) = (
        x[0].as_slice(),
        y[0].as_slice(),
        x[1].as_slice(),
        y[1].as_slice(),
    );
    for c in 0..N {
        for r in 0..N {
            let e = &mut m[6 * c + r];
            *e += (x0[r] * y0[c]) * k[0];
            *e += (x1[r] * y1[c]) * k[1];
        }
    }
}

/// `m += k·x·yᵀ`, on the leading 3×3 part only when both blocks are rigid (the solver reads
/// only the leading ndof × ndof part of each block, and the rigid case is 4× cheaper). Each
/// entry is rounded as (x_r·y_c)·k, as a full outer product scaled by k would be.
#[inline]
fn rank_one(m: &mut Mat6, k: f64, x: &Vec6, y: &Vec6, rigid: bool) {
    // A constant size lets the loops unroll without index checks (the assembly of a shaken
    // 410-stone wall's springs spent half its instructions on checked indexing with a runtime
    // size: docs/contact-solve.md §14); same operations in the same order.
    if rigid {
        rank_one_n::<3>(m, k, x, y);
    } else {
        rank_one_n::<6>(m, k, x, y);
    }
}

#[inline(always)]
fn rank_one_n<const N: usize>(m: &mut Mat6, k: f64, x: &Vec6, y: &Vec6) {
    let (m, x, y) = (m.as_mut_slice(), x.as_slice(), y.as_slice());
    for c in 0..N {
        for r in 0..N {
            // Column-major, as nalgebra stores a 6×6 matrix.
            m[6 * c + r] += (x[r] * y[c]) * k;
        }
    }
}

/// [`add_contacts`] as before session 43: a locked contact's normal spring, then its shear
/// spring, each by [`add_spring`] (the reference of the fused assembly's bit-identity test).
#[cfg(test)]
pub(crate) fn add_contacts_unfused(
    sys: &mut BlockSystem,
    dofs: &Dofs,
    contacts: &[Contact],
    laws: &[JointLaw],
    springs: &SpringParams,
    prescribed: &[Prescribed],
) {
    for (k, (c, law)) in contacts.iter().zip(laws).enumerate() {
        if !c.state.is_closed() {
            let l = release_load(c, springs);
            if l != 0.0 {
                if let Some(i) = dofs.free_index[c.vertex_block] {
                    sys.rhs[i] += c.e_i * l;
                }
                if let Some(j) = dofs.free_index[c.edge_block] {
                    sys.rhs[j] -= c.e_j * l;
                }
            }
            continue;
        }
        let blocks = (
            dofs.free_index[c.vertex_block],
            dofs.free_index[c.edge_block],
            sys.contact_slots[k],
        );
        let (g0, s0) = constants(c, prescribed);
        add_spring::<true>(sys, dofs, blocks, &c.e_i, &c.e_j, springs.normal, g0);
        match c.state {
            ContactState::Locked => {
                add_spring::<true>(sys, dofs, blocks, &c.f_i, &c.f_j, springs.shear, s0)
            }
            ContactState::Sliding { dir } => {
                let f = dir * shear_limit(c, law, c.friction_normal);
                if let Some(a) = blocks.0 {
                    sys.rhs[a] -= c.f_i * f;
                }
                if let Some(b) = blocks.1 {
                    sys.rhs[b] += c.f_j * f;
                }
            }
            ContactState::Open => {}
        }
    }
}
