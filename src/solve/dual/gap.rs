//! Gap function of the dual form (Zheng et al. 2016, Eqs. 18–31): for contact forces `p`, the normal
//! gap and tangential slide of every contact at the end of the step, `G(p) = c + W p`,
//! evaluated block by block (`d_i = f_i + K_i⁻¹ C_i p_i`) without forming W.
//!
//! Conventions (as in `contact`): contact k joins vertex P of the vertex block i to edge AB of
//! the edge block j; `n` is the edge's outward normal, `t` the edge direction A→B. The contact
//! force on the vertex block is `p_n·n + p_t·t` (N per metre of thickness; p_n > 0 pushes the
//! blocks apart), the edge block receives the opposite. The gap `g = n·(P − Q)` (m, > 0 open)
//! and the slide `s = t·(ΔP − ΔQ)` (m, the vertex's motion along the edge relative to its
//! projection Q during the step).
use super::flexibility::BlockFlex;
use crate::assembly::contact_springs::{constants, JointLaw, Prescribed};
use crate::assembly::Dofs;
use crate::contact::{edge_points, Contact};
use crate::geometry::{displacement_matrix, BlockGeometry, Vec6};
use rayon::prelude::*;

/// A pair of contact quantities: [normal, tangential].
pub type Pair = [f64; 2];

/// Per-step terms of one contact.
#[derive(Debug, Clone, Copy)]
pub struct PairTerms {
    pub fi: Option<usize>,
    pub fj: Option<usize>,
    /// Generalized force directions (= gap gradients): `T_i(P)ᵀn`, `T_i(P)ᵀt`, `T_j(Q)ᵀn`,
    /// `T_j(Q)ᵀt`.
    pub wn_i: Vec6,
    pub wt_i: Vec6,
    pub wn_j: Vec6,
    pub wt_j: Vec6,
    /// The same directions premultiplied by the block flexibility K⁻¹ (Zheng et al.'s n_ki, τ_ki).
    pub kn_i: Vec6,
    pub kt_i: Vec6,
    pub kn_j: Vec6,
    pub kt_j: Vec6,
    /// Gap and slide constants (step-start gap, driven blocks' prescribed motion), m.
    pub constant: Pair,
    /// Diagonal of W: the contact's own flexibility in n and t, m/N.
    pub diag: Pair,
    /// Coulomb friction tan φ.
    pub tan_phi: f64,
    /// Cohesion (N) and tensile strength (N) of an intact bond; zero once broken.
    pub cohesion: f64,
    pub tension: f64,
}

/// One contact seen from one of its blocks: `K⁻¹w` with the side's sign folded in (+ for the
/// vertex block, − for the edge block, which receives the opposite force).
#[derive(Debug, Clone, Copy)]
struct GatherRow {
    contact: u32,
    kn: Vec6,
    kt: Vec6,
}

/// One contact's gap gradients, the edge side's negated; `NONE` marks a side without unknowns.
#[derive(Debug, Clone, Copy)]
struct ScatterRow {
    fi: u32,
    fj: u32,
    constant: Pair,
    wn_i: Vec6,
    wt_i: Vec6,
    wn_j: Vec6,
    wt_j: Vec6,
}

const NONE: u32 = u32::MAX;

/// The contact terms of a step plus the block incidence used to gather forces per block.
#[derive(Debug, Default)]
pub struct GapFunction {
    pub terms: Vec<PairTerms>,
    /// Per free block, its contacts' entries in `gather_rows[start[f]..start[f+1]]`.
    start: Vec<usize>,
    /// The product with W reads packed copies of the fields it needs, in the order its loops
    /// run, instead of striding through ~470-byte `PairTerms`: 16 % off the pile's dual run
    /// (docs/dual.md, "The product with W").
    gather_rows: Vec<GatherRow>,
    scatter_rows: Vec<ScatterRow>,
    /// `terms[k].diag` packed, for the minimisation's per-component loops.
    diag: Vec<Pair>,
    /// Item count from which loops run on rayon.
    pub parallel_from: usize,
}

impl GapFunction {
    /// Build the terms of every contact from the step-start geometry and the flexibilities.
    /// `phantom` (m): a corner beside an edge's end and outside its block that lies deeper
    /// than this below the edge's line is given g0 = 0 (see `terms_of`).
    #[allow(clippy::too_many_arguments)]
    pub fn build(
        &mut self,
        contacts: &[Contact],
        geoms: &[BlockGeometry],
        laws: &[JointLaw],
        dofs: &Dofs,
        flex: &[BlockFlex],
        prescribed: &[Prescribed],
        inert: &[bool],
        phantom: f64,
    ) {
        let make = |((c, law), &off): ((&Contact, &JointLaw), &bool)| {
            let mut t = terms_of(c, law, geoms, dofs, flex, prescribed, phantom);
            if off {
                // No force and no incidence: the solver leaves it at zero.
                (t.fi, t.fj, t.diag) = (None, None, [0.0; 2]);
            }
            t
        };
        self.terms.clear();
        if contacts.len() >= self.parallel_from {
            contacts
                .par_iter()
                .zip(laws)
                .zip(inert)
                .map(make)
                .collect_into_vec(&mut self.terms);
        } else {
            self.terms
                .extend(contacts.iter().zip(laws).zip(inert).map(make));
        }
        self.pack(dofs.block_of.len());
    }

    /// Lay out the product's packed rows from `terms` for `nf` free blocks.
    fn pack(&mut self, nf: usize) {
        self.start.clear();
        self.start.resize(nf + 1, 0);
        for t in &self.terms {
            for f in [t.fi, t.fj].into_iter().flatten() {
                self.start[f + 1] += 1;
            }
        }
        for f in 0..nf {
            self.start[f + 1] += self.start[f];
        }
        self.gather_rows.clear();
        let empty = GatherRow {
            contact: 0,
            kn: Vec6::zeros(),
            kt: Vec6::zeros(),
        };
        self.gather_rows.resize(self.start[nf], empty);
        let mut fill = self.start.clone();
        for (k, t) in self.terms.iter().enumerate() {
            let contact = k as u32;
            if let Some(f) = t.fi {
                self.gather_rows[fill[f]] = GatherRow {
                    contact,
                    kn: t.kn_i,
                    kt: t.kt_i,
                };
                fill[f] += 1;
            }
            if let Some(f) = t.fj {
                self.gather_rows[fill[f]] = GatherRow {
                    contact,
                    kn: -t.kn_j,
                    kt: -t.kt_j,
                };
                fill[f] += 1;
            }
        }
        self.diag.clear();
        self.diag.extend(self.terms.iter().map(|t| t.diag));
        let index = |f: Option<usize>| f.map_or(NONE, |f| f as u32);
        self.scatter_rows.clear();
        self.scatter_rows
            .extend(self.terms.iter().map(|t| ScatterRow {
                fi: index(t.fi),
                fj: index(t.fj),
                constant: t.constant,
                wn_i: t.wn_i,
                wt_i: t.wt_i,
                wn_j: -t.wn_j,
                wt_j: -t.wt_j,
            }));
    }

    /// The diagonal of W per contact (m/N), packed: `terms[k].diag`.
    pub fn diag(&self) -> &[Pair] {
        &self.diag
    }

    /// Block increments `d_f = f_f + Σ K⁻¹ w p` for contact forces `p`.
    pub fn displacements(&self, flex: &[BlockFlex], p: &[Pair], d: &mut Vec<Vec6>) {
        self.gather(flex, p, true, d);
    }

    /// `G(p)`: gap and slide of every contact for the block increments `d`
    /// (from [`GapFunction::displacements`]).
    pub fn eval(&self, d: &[Vec6], out: &mut Vec<Pair>) {
        self.scatter(d, true, out);
    }

    /// `W v` (m): the change of the gap function for a change `v` of the contact forces, with
    /// `d` as scratch (the block increments of `v` alone).
    pub fn apply_w(&self, flex: &[BlockFlex], v: &[Pair], d: &mut Vec<Vec6>, out: &mut Vec<Pair>) {
        self.gather(flex, v, false, d);
        self.scatter(d, false, out);
    }

    fn gather(&self, flex: &[BlockFlex], p: &[Pair], with_free: bool, d: &mut Vec<Vec6>) {
        d.resize(flex.len(), Vec6::zeros());
        let one = |(f, out): (usize, &mut Vec6)| {
            let mut v = if with_free {
                flex[f].free
            } else {
                Vec6::zeros()
            };
            for row in &self.gather_rows[self.start[f]..self.start[f + 1]] {
                let [pn, pt] = p[row.contact as usize];
                v += row.kn * pn + row.kt * pt;
            }
            *out = v;
        };
        if flex.len() >= self.parallel_from {
            d.par_iter_mut().enumerate().for_each(one);
        } else {
            d.iter_mut().enumerate().for_each(one);
        }
    }

    fn scatter(&self, d: &[Vec6], with_constant: bool, out: &mut Vec<Pair>) {
        out.resize(self.terms.len(), [0.0; 2]);
        let one = |(r, g): (&ScatterRow, &mut Pair)| {
            let [mut gn, mut gt] = if with_constant { r.constant } else { [0.0; 2] };
            if r.fi != NONE {
                let di = &d[r.fi as usize];
                gn += r.wn_i.dot(di);
                gt += r.wt_i.dot(di);
            }
            if r.fj != NONE {
                let dj = &d[r.fj as usize];
                gn += r.wn_j.dot(dj);
                gt += r.wt_j.dot(dj);
            }
            *g = [gn, gt];
        };
        if self.terms.len() >= self.parallel_from {
            let rows = self.scatter_rows.par_iter();
            rows.zip(out.par_iter_mut()).for_each(one);
        } else {
            self.scatter_rows.iter().zip(out.iter_mut()).for_each(one);
        }
    }
}

fn terms_of(
    c: &Contact,
    law: &JointLaw,
    geoms: &[BlockGeometry],
    dofs: &Dofs,
    flex: &[BlockFlex],
    prescribed: &[Prescribed],
    phantom: f64,
) -> PairTerms {
    let gi = &geoms[c.vertex_block];
    let gj = &geoms[c.edge_block];
    let p = gi.vertices[c.vertex];
    let (a, b) = edge_points(gj, c.edge);
    let q = a + (b - a) * c.xi;
    let ti = displacement_matrix(p, gi.centroid).transpose();
    let tj = displacement_matrix(q, gj.centroid).transpose();
    let (wn_i, wt_i) = (ti * c.n, ti * c.t);
    let (wn_j, wt_j) = (tj * c.n, tj * c.t);
    let fi = dofs.free_index[c.vertex_block];
    let fj = dofs.free_index[c.edge_block];
    let (mut kn_i, mut kt_i, mut kn_j, mut kt_j) =
        (Vec6::zeros(), Vec6::zeros(), Vec6::zeros(), Vec6::zeros());
    let mut diag = [0.0; 2];
    if let Some(f) = fi {
        kn_i = flex[f].kinv * wn_i;
        kt_i = flex[f].kinv * wt_i;
        diag[0] += wn_i.dot(&kn_i);
        diag[1] += wt_i.dot(&kt_i);
    }
    if let Some(f) = fj {
        kn_j = flex[f].kinv * wn_j;
        kt_j = flex[f].kinv * wt_j;
        diag[0] += wn_j.dot(&kn_j);
        diag[1] += wt_j.dot(&kt_j);
    }
    // The step-start slide is zero by definition (Q is the vertex's projection); only driven
    // blocks' prescribed motion contributes to the slide constant.
    let (mut g0, s_with_ref) = constants(c, prescribed);
    // A corner beside the edge's end and outside the edge's block (a cap's corner pair with
    // a column's top corner, 87 µm apart) is not inside it, whatever its distance below the
    // edge's line: asserted, that phantom penetration (−3.6e-7 m on the rocking frame under
    // Loma Prieta 0.6 g) was never met, the solve stalled and the step was cut to 1.6e-9 s
    // (docs/dual.md, "The frame's cap–column corner pair"). Depths within `phantom` are left
    // as detected (the 4-corner nodes of aligned walls, ≤ 4e-10 m, at round-off).
    if g0 < -phantom
        && !(0.0..=1.0).contains(&c.xi)
        && crate::geometry::inside_depth(p, &gj.vertices) <= 0.0
    {
        g0 = 0.0;
    }
    let slide_prescribed = s_with_ref - c.s0;
    let (cohesion, tension) = if c.bonded {
        (law.cohesion * c.length, law.tensile_strength * c.length)
    } else {
        (0.0, 0.0)
    };
    PairTerms {
        fi,
        fj,
        wn_i,
        wt_i,
        wn_j,
        wt_j,
        kn_i,
        kt_i,
        kn_j,
        kt_j,
        constant: [g0, slide_prescribed],
        diag,
        tan_phi: law.tan_phi,
        cohesion,
        tension,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::Mat6;

    /// A small system: 3 free blocks, contacts between free blocks, against a fixed block
    /// (`None`), and one with no unknown at all; arbitrary gradients, SPD flexibilities.
    fn system() -> (GapFunction, Vec<BlockFlex>) {
        let wave = |seed: usize| Vec6::from_fn(|r, _| ((seed * 7 + r * 5) % 11) as f64 - 5.0);
        let flex: Vec<BlockFlex> = (0..3)
            .map(|f| {
                let a = Mat6::from_fn(|r, c| ((f * 3 + r * 7 + c * 2) % 9) as f64 - 4.0);
                BlockFlex {
                    kinv: a.transpose() * a + Mat6::identity(),
                    free: wave(f + 20),
                }
            })
            .collect();
        let sides = [
            (Some(0), Some(1)),
            (Some(1), Some(2)),
            (Some(2), None),
            (None, Some(0)),
        ];
        let mut gf = GapFunction::default();
        for (k, (fi, fj)) in sides.into_iter().chain([(None, None)]).enumerate() {
            let (wn_i, wt_i, wn_j, wt_j) = (
                wave(4 * k),
                wave(4 * k + 1),
                wave(4 * k + 2),
                wave(4 * k + 3),
            );
            let k_of = |f: Option<usize>, w: Vec6| f.map_or(Vec6::zeros(), |f| flex[f].kinv * w);
            gf.terms.push(PairTerms {
                fi,
                fj,
                wn_i,
                wt_i,
                wn_j,
                wt_j,
                kn_i: k_of(fi, wn_i),
                kt_i: k_of(fi, wt_i),
                kn_j: k_of(fj, wn_j),
                kt_j: k_of(fj, wt_j),
                constant: [0.5 * k as f64, -0.25 * k as f64],
                diag: [1.0; 2],
                tan_phi: 0.0,
                cohesion: 0.0,
                tension: 0.0,
            });
        }
        gf.parallel_from = usize::MAX;
        gf.pack(flex.len());
        (gf, flex)
    }

    /// The gradient of contact `k`'s component `j` on block `f`, signed by its side, or zero.
    fn grad(t: &PairTerms, j: usize, f: usize) -> Vec6 {
        let pick = |a: Vec6, b: Vec6| if j == 0 { a } else { b };
        let mut g = Vec6::zeros();
        if t.fi == Some(f) {
            g += pick(t.wn_i, t.wt_i);
        }
        if t.fj == Some(f) {
            g -= pick(t.wn_j, t.wt_j);
        }
        g
    }

    #[test]
    fn packed_product_is_the_dense_w_of_the_terms() {
        // Reference: W assembled densely from its definition, W[(k,j),(l,m)] =
        // Σ_f g_kj,f · K_f⁻¹ g_lm,f, with g the side-signed gap gradients (Zheng et al. 2016, Eqs. 21–30).
        // The packed rows fold the edge side's sign into stored copies; a wrong sign, index
        // or block in that packing changes entries by O(1). Tolerance 1e-12 relative: the
        // two evaluations only sum the same terms in a different order.
        let (gf, flex) = system();
        let n = gf.terms.len();
        let v: Vec<Pair> = (0..n)
            .map(|k| [1.0 + k as f64, 2.0 - 0.5 * k as f64])
            .collect();
        let (mut d, mut out) = (Vec::new(), Vec::new());
        gf.apply_w(&flex, &v, &mut d, &mut out);
        let mut scale: f64 = 0.0;
        for k in 0..n {
            for j in 0..2 {
                let mut want = 0.0;
                for (l, vl) in v.iter().enumerate() {
                    for m in 0..2 {
                        for (f, fl) in flex.iter().enumerate() {
                            let a = grad(&gf.terms[k], j, f);
                            want += a.dot(&(fl.kinv * grad(&gf.terms[l], m, f))) * vl[m];
                        }
                    }
                }
                scale = scale.max(want.abs());
                assert!(
                    (out[k][j] - want).abs() <= 1e-12 * scale.max(1.0),
                    "W v at contact {k}, component {j}: {} vs {want}",
                    out[k][j]
                );
            }
        }
        assert!(scale > 1.0, "the check saw a nonzero product");
        // The contact with no unknown sees nothing.
        assert_eq!(out[n - 1], [0.0; 2]);
        // G(p) adds the free increments and the constants: G(p) − G(0) = W p.
        let (mut g0, mut gp) = (Vec::new(), Vec::new());
        gf.displacements(&flex, &vec![[0.0; 2]; n], &mut d);
        gf.eval(&d, &mut g0);
        gf.displacements(&flex, &v, &mut d);
        gf.eval(&d, &mut gp);
        for k in 0..n {
            for j in 0..2 {
                let diff = gp[k][j] - g0[k][j];
                assert!(
                    (diff - out[k][j]).abs() <= 1e-12 * scale,
                    "G(p) − G(0) at {k}, {j}"
                );
            }
        }
        assert_eq!(g0[n - 1], gf.terms[n - 1].constant);
    }
}
