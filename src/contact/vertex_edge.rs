//! Narrow phase for one block pair: vertex–edge candidates with Shi's entrance (angle)
//! criterion; vertex–vertex situations are resolved to the edge the vertex can enter.
use super::ContactParams;
use crate::geometry::{inside_depth, BlockGeometry};

/// A vertex of `vertex_block` near edge `edge` of `edge_block`.
#[derive(Debug, Clone, Copy)]
pub struct Candidate {
    pub vertex_block: usize,
    pub vertex: usize,
    pub edge_block: usize,
    pub edge: usize,
    /// Signed gap, m (negative = penetration).
    pub gap: f64,
    /// Projection of the vertex on the edge, fraction of its length.
    pub xi: f64,
    /// Tributary length, m.
    pub length: f64,
}

/// Best candidate edge of block `j` for vertex `k` of block `i`, if any. `sin_tol` is the sine
/// of [`ContactParams::angle_tolerance`] (computed once per pair by the caller).
pub fn candidate(
    geoms: &[BlockGeometry],
    i: usize,
    k: usize,
    j: usize,
    search: f64,
    sin_tol: f64,
) -> Option<Candidate> {
    let gi = &geoms[i];
    let gj = &geoms[j];
    let nv = gi.vertices.len();
    let p = gi.vertices[k];
    let prev = gi.vertices[(k + nv - 1) % nv];
    let next = gi.vertices[(k + 1) % nv];
    let (e1, e2) = (prev - p, next - p);
    let (l1, l2) = (e1.norm(), e2.norm());
    let ne = gj.vertices.len();
    let mut best: Option<Candidate> = None;
    for m in 0..ne {
        let a = gj.vertices[m];
        let b = gj.vertices[(m + 1) % ne];
        let ab = b - a;
        let len = ab.norm();
        let t = ab / len;
        let n = nalgebra::Vector2::new(t.y, -t.x);
        let gap = n.dot(&(p - a));
        if gap > search || gap < -search {
            continue;
        }
        let xi = t.dot(&(p - a)) / len;
        let margin = search / len;
        if xi < -margin || xi > 1.0 + margin {
            continue;
        }
        // Entrance criterion: the vertex's wedge must lie on the outer side of the edge, i.e.
        // both adjacent edges of the vertex point away from (or along) the edge block. A vertex
        // still above the edge's line (gap > 0) is admitted while its neighbours are not below
        // that line: it cannot be crossing, and a corner landing on a nearly parallel edge (a
        // rocking column's other corner) is then found before it lands. With the angle alone
        // it was found only within 1 mrad of flat, after it had crossed when the block turns
        // faster than that in a step (h/b = 2 column at Δt = 1 ms: 85 µm deep when found).
        let lift = gap.max(0.0);
        if e1.dot(&n) + lift < -sin_tol * l1 || e2.dot(&n) + lift < -sin_tol * l2 {
            continue;
        }
        // Outside the edge's span the vertex must still be within the search distance of the
        // nearest endpoint (a real vertex–vertex approach, not a far-away extension of the line).
        if !(0.0..=1.0).contains(&xi) {
            let end = if xi < 0.0 { a } else { b };
            if (p - end).norm() > search {
                continue;
            }
        }
        let length = 0.5 * (e1.dot(&t).abs() + e2.dot(&t).abs());
        let c = Candidate {
            vertex_block: i,
            vertex: k,
            edge_block: j,
            edge: m,
            gap,
            xi,
            length,
        };
        // Several admissible edges (near a corner): the shallowest penetration is the edge the
        // vertex actually crossed.
        if best.is_none_or(|bc| gap > bc.gap) {
            best = Some(c);
        }
    }
    // A vertex outside the edge block penetrates nothing. A deep negative gap can still come
    // from an edge whose line the vertex is beyond while it sits outside by another edge (that
    // edge rejected by the entrance criterion at a small relative rotation, e.g. a vertex at
    // the end of a slightly tilted face-to-face contact): such a phantom penetration pushed
    // the vertex 8 cm "out" of a block it was not in (tests: `phantom_penetration_…`). Gaps
    // within the entrance criterion's round-off scale (angle tolerance × edge length) are kept,
    // so touching corners are not affected by which side round-off puts them.
    if let Some(bc) = best {
        let (a, b) = (gj.vertices[bc.edge], gj.vertices[(bc.edge + 1) % ne]);
        let floor = sin_tol * (b - a).norm();
        if bc.gap < -floor && inside_depth(p, &gj.vertices) <= 0.0 {
            return None;
        }
    }
    best
}

/// Candidates of every vertex of block `i` against the edges of block `j`.
pub fn pair_candidates(
    geoms: &[BlockGeometry],
    i: usize,
    j: usize,
    search: f64,
    params: &ContactParams,
    out: &mut Vec<Candidate>,
) {
    let sin_tol = params.angle_tolerance.sin();
    // A vertex outside block j's box inflated by the search distance cannot be near its edges.
    let (lo, hi) = geoms[j].bounds();
    for (k, p) in geoms[i].vertices.iter().enumerate() {
        if p.x < lo.x - search || p.x > hi.x + search || p.y < lo.y - search || p.y > hi.y + search
        {
            continue;
        }
        if let Some(c) = candidate(geoms, i, k, j, search, sin_tol) {
            out.push(c);
        }
    }
}

/// Two coincident vertices each produce a contact against the other's edge at the same point
/// (vertex–vertex): keep one, so the joint is not twice as stiff there. The one kept has the
/// lower vertex-block index, which makes the choice deterministic.
pub fn drop_mirrored_vertex_pairs(
    geoms: &[BlockGeometry],
    cands: &mut Vec<Candidate>,
    search: f64,
) {
    let tol = 1e-3 * search;
    let mut k = 0;
    while k < cands.len() {
        let c = cands[k];
        let p = geoms[c.vertex_block].vertices[c.vertex];
        let mirrored = cands.iter().any(|o| {
            o.vertex_block == c.edge_block
                && o.edge_block == c.vertex_block
                && c.vertex_block > o.vertex_block
                && {
                    let q = geoms[o.vertex_block].vertices[o.vertex];
                    (p - q).norm() <= tol
                }
        });
        if mirrored {
            cands.remove(k);
        } else {
            k += 1;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::Vector2;

    fn v(x: f64, y: f64) -> Vector2<f64> {
        Vector2::new(x, y)
    }

    /// Regression (the 1700-block pile, step 187, examples/pile.rs): two neighbouring blocks of
    /// the top row, face to face with a relative rotation of 2.7e-3 rad (above the 1e-3 rad
    /// angle tolerance), the right one 12 cm lower. Its top-left vertex is 0.08 mm outside the
    /// left block's right face; the entrance criterion rejects that face (the vertex's lower
    /// edge turns 2.7e-3 rad into it), and the left block's bottom edge was then taken with a
    /// gap of −7.8 cm: a phantom penetration that stopped the run with `PenaltyTooSoft`.
    /// Now the vertex is never paired with that bottom edge: the face contact is carried by the
    /// other block's corner (and, open, by this vertex on the face it is outside of).
    #[test]
    fn phantom_penetration_of_an_outside_vertex_is_not_a_contact() {
        let left = BlockGeometry::new(vec![
            v(8.000053556221753, 8.203145931882563),
            v(8.40004252152172, 8.20388651421613),
            v(8.399674955454675, 8.403885594805596),
            v(7.999685990154714, 8.403145012472004),
        ]);
        let right = BlockGeometry::new(vec![
            v(8.400142628141174, 8.081631594985907),
            v(8.800113730516161, 8.081974148666433),
            v(8.799948423706624, 8.281977137748559),
            v(8.39997732133163, 8.281634584068032),
        ]);
        let geoms = [right, left];
        let sin_tol = ContactParams::default().angle_tolerance.sin();
        // Search distance of the pile (2.5 × 0.003 × its half size ≈ 0.083 m): the bottom edge's
        // −7.8 cm is within it.
        let search = 0.083;
        assert!(inside_depth(geoms[0].vertices[3], &geoms[1].vertices) < 0.0);
        // What broke was the −7.8 cm gap on the bottom edge. Since a vertex still above an
        // edge's line is admitted while its neighbours are not below it (corners landing on a
        // nearly parallel edge), the vertex may now be paired with the face it is outside of,
        // at its true distance (0.078 mm, open), never with the bottom edge.
        let outside = candidate(&geoms, 0, 3, 1, search, sin_tol);
        if let Some(c) = outside {
            assert_eq!(c.edge, 1, "{c:?}");
            assert!(c.gap > 0.0 && c.gap < 1e-4, "{c:?}");
        }
        // The real contact of the two faces: the left block's bottom-right corner on the right
        // block's left face, a tiny penetration (≈ 0.2 mm), still found.
        let c = candidate(&geoms, 1, 1, 0, search, sin_tol).expect("corner on the face");
        assert_eq!(c.edge, 3);
        assert!(c.gap.abs() < 1e-3, "{c:?}");
    }

    /// A vertex genuinely inside keeps its (shallowest) penetration; a vertex touching a face
    /// (gap at round-off) keeps its contact whichever side round-off puts it.
    #[test]
    fn real_and_touching_contacts_are_kept() {
        let base = BlockGeometry::new(vec![v(0.0, 0.0), v(2.0, 0.0), v(2.0, 1.0), v(0.0, 1.0)]);
        let sin_tol = ContactParams::default().angle_tolerance.sin();
        for dy in [-0.01, 1e-17, -1e-17] {
            let top = BlockGeometry::new(vec![
                v(0.5, 1.0 + dy),
                v(1.5, 1.0 + dy),
                v(1.5, 2.0 + dy),
                v(0.5, 2.0 + dy),
            ]);
            let geoms = [top, base.clone()];
            let c = candidate(&geoms, 0, 0, 1, 0.05, sin_tol).expect("contact kept");
            assert_eq!(c.edge, 2, "top edge of the base");
            assert!((c.gap - dy).abs() < 1e-12);
        }
    }
}
