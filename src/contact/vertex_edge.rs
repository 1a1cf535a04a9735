//! Narrow phase for one block pair: vertex–edge candidates with Shi's entrance (angle)
//! criterion; vertex–vertex situations are resolved to the edge the vertex can enter.
use super::ContactParams;
use crate::geometry::BlockGeometry;

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
        // both adjacent edges of the vertex point away from (or along) the edge block.
        if e1.dot(&n) < -sin_tol * l1 || e2.dot(&n) < -sin_tol * l2 {
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
