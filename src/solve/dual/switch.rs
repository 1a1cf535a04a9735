//! Switching of vertex–vertex contact pairs (Zheng et al. 2016, §6, Appendix C). When vertex V of block
//! i meets corner E of block j, several contact pairs are possible: V against either edge of
//! j that ends at E, or E against either edge of i that ends at V. Each is one separating line;
//! the true condition is that *some* line separates the corners. Detection picks one pair from
//! the step-start geometry; after a solve, the pair is re-chosen as the admissible line that
//! the corners' relative motion (without this contact's own force) leaves the largest gap —
//! the line needing the smallest correction, which is Bao and Zhao's argument for their
//! four-block example — and the step is re-solved.
use super::gap::{GapFunction, Pair};
use super::DualInput;
use crate::contact::{edge_points, linearize_contact, Contact, ContactState, ShearReference};
use crate::geometry::{displacement_matrix, inside_depth, BlockGeometry, Vec6};
use nalgebra::Vector2;

/// A possible pair: vertex (block, index) against edge (block, index).
type PairKey = (usize, usize, usize, usize);

/// Re-choose the pair of every compressed vertex–vertex contact: the admissible line with the
/// largest step-end gap (step-start distance plus the corners' relative motion). If that line
/// is already another contact, this one is made inert for the step. Returns how many changed.
/// `p`, `d`: the solved forces and block increments. Each corner switches at most once per
/// step (`switched` remembers them), so a step cannot cycle; a switch needs a gap gain above
/// `gain` (m), so round-off ties in aligned stacks keep the detected pair.
pub fn vertex_vertex(
    contacts: &mut [Contact],
    inert: &mut [bool],
    gf: &GapFunction,
    p: &[Pair],
    d: &[Vec6],
    input: &DualInput,
    gain: f64,
    switched: &mut Vec<(usize, usize)>,
) -> usize {
    let geoms = input.geoms;
    let sin_tol = input.contact.angle_tolerance.sin();
    let mut count = 0;
    for k in 0..contacts.len() {
        if inert[k] || p[k][0] <= 0.0 {
            continue;
        }
        let c = &contacts[k];
        let gj = &geoms[c.edge_block];
        let nj = gj.vertices.len();
        let vi = geoms[c.vertex_block].vertices[c.vertex];
        // Singular: the vertex is within the search distance of the nearer end E of its edge.
        let corner = if c.xi < 0.5 {
            c.edge
        } else {
            (c.edge + 1) % nj
        };
        let ej = gj.vertices[corner];
        if (vi - ej).norm() > input.search {
            continue;
        }
        if switched.contains(&(c.vertex_block, c.vertex))
            || switched.contains(&(c.edge_block, corner))
        {
            continue;
        }
        // Relative motion of V with respect to E over the step, without this contact's force.
        let t = &gf.terms[k];
        let [pn, pt] = p[k];
        let mut delta = Vector2::zeros();
        if let Some(f) = t.fi {
            let di = d[f] - (t.kn_i * pn + t.kt_i * pt);
            delta += displacement_matrix(vi, geoms[c.vertex_block].centroid) * di;
        }
        if let Some(f) = t.fj {
            let dj = d[f] + (t.kn_j * pn + t.kt_j * pt);
            delta -= displacement_matrix(ej, gj.centroid) * dj;
        }
        let options = lines(
            (c.vertex_block, &geoms[c.vertex_block], c.vertex),
            (c.edge_block, gj, corner),
            &delta,
            sin_tol,
        );
        let current = (c.vertex_block, c.vertex, c.edge_block, c.edge);
        let Some(&(best, best_gap)) = options.iter().max_by(|x, y| x.1.total_cmp(&y.1)) else {
            continue;
        };
        let current_gap = options
            .iter()
            .find(|o| o.0 == current)
            .map_or(f64::NEG_INFINITY, |o| o.1);
        // Switch only for a clear gain (a tie keeps the detected pair).
        if best == current || best_gap <= current_gap + gain {
            continue;
        }
        switched.push((c.vertex_block, c.vertex));
        switched.push((c.edge_block, corner));
        count += 1;
        let exists = contacts
            .iter()
            .any(|o| (o.vertex_block, o.vertex, o.edge_block, o.edge) == best);
        if exists {
            // The better line is already a contact: this one is the wrong line of the same
            // corner pair and carries no force this step.
            inert[k] = true;
            continue;
        }
        let mut new = contacts[k].clone();
        (new.vertex_block, new.vertex, new.edge_block, new.edge) = best;
        new.state = ContactState::Locked;
        // The step-start frame, with the shear reference at the vertex's projection.
        linearize_contact(&mut new, geoms, ShearReference::AtVertex);
        contacts[k] = new;
    }
    count
}

/// Step-end gap of each admissible separating line through vertex `v` of block `i` and corner
/// `corner` of block `j` (each given as (index, geometry, vertex)), `delta` being the relative
/// motion of the vertex with respect to the corner over the step.
///
/// A line must separate the corners at the step start: one that the step-start geometry
/// already puts a corner deeper beyond than the corner is inside the other block (a corner
/// beside the other block's face, not at its corner) would assert a penetration of that depth,
/// and the solve would throw the block out by as much. In the 1700-block pile (step 192, rigid
/// blocks) a corner lying on its neighbour's face 7.7 cm below that block's top corner was
/// switched to the top edge's line, g₀ = −7.7 cm, and the solves moved the block 6 cm in one
/// step. Depths within the entrance criterion's round-off scale (angle tolerance × edge
/// length) are kept, as in detection (`contact::vertex_edge::candidate`).
fn lines(
    (ib, gi, v): (usize, &BlockGeometry, usize),
    (jb, gj, corner): (usize, &BlockGeometry, usize),
    delta: &Vector2<f64>,
    sin_tol: f64,
) -> Vec<(PairKey, f64)> {
    let (ni, nj) = (gi.vertices.len(), gj.vertices.len());
    let (vi, ej) = (gi.vertices[v], gj.vertices[corner]);
    // How deep each corner is inside the other block (0 outside), once for its two lines.
    let (vi_depth, ej_depth) = (
        inside_depth(vi, &gj.vertices).max(0.0),
        inside_depth(ej, &gi.vertices).max(0.0),
    );
    let separates = |g0: f64, depth: f64, other: &BlockGeometry, e: usize| {
        let (a, b) = edge_points(other, e);
        g0 >= -(depth + sin_tol * (b - a).norm())
    };
    let mut options: Vec<(PairKey, f64)> = Vec::with_capacity(4);
    for e in [corner, (corner + nj - 1) % nj] {
        let n = outward_normal(gj, e);
        let g0 = n.dot(&(vi - gj.vertices[e]));
        if admissible(gi, v, &n, sin_tol) && separates(g0, vi_depth, gj, e) {
            options.push(((ib, v, jb, e), g0 + n.dot(delta)));
        }
    }
    for e in [v, (v + ni - 1) % ni] {
        let n = outward_normal(gi, e);
        let g0 = n.dot(&(ej - gi.vertices[e]));
        if admissible(gj, corner, &n, sin_tol) && separates(g0, ej_depth, gi, e) {
            options.push(((jb, corner, ib, e), g0 - n.dot(delta)));
        }
    }
    options
}

/// Outward unit normal of edge `e` of a counter-clockwise polygon.
fn outward_normal(g: &BlockGeometry, e: usize) -> Vector2<f64> {
    let (a, b) = edge_points(g, e);
    let t = (b - a).normalize();
    Vector2::new(t.y, -t.x)
}

/// Shi's entrance criterion: both edges at vertex `v` of `g` point away from (or along) the
/// other block's edge with outward normal `n`.
fn admissible(g: &BlockGeometry, v: usize, n: &Vector2<f64>, sin_tol: f64) -> bool {
    let nv = g.vertices.len();
    let p = g.vertices[v];
    let e1 = g.vertices[(v + nv - 1) % nv] - p;
    let e2 = g.vertices[(v + 1) % nv] - p;
    e1.dot(n) >= -sin_tol * e1.norm() && e2.dot(n) >= -sin_tol * e2.norm()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn rect(x0: f64, y0: f64, x1: f64, y1: f64) -> BlockGeometry {
        let v = Vector2::new;
        BlockGeometry::new(vec![v(x0, y0), v(x1, y0), v(x1, y1), v(x0, y1)])
    }

    /// Regression (the 1700-block pile, rigid blocks, step 192): two neighbours of the top row,
    /// the right one 12.3 cm lower. The left block's bottom-right corner V lies on the right
    /// block's left face, 7.7 cm below that block's top-left corner E. With a relative motion
    /// that carries V into the face and upwards, the right block's top edge (V 7.7 cm below
    /// its line) and the left block's bottom edge (E 7.7 cm above its line) used to offer the
    /// largest step-end gaps, and V was switched onto the top edge with g₀ = −7.7 cm: the
    /// solves then moved the block 6 cm in one step and the run stopped.
    #[test]
    fn a_line_the_corner_is_already_deep_beyond_is_not_an_option() {
        let left = rect(0.4, 8.0, 0.8, 8.2);
        let right = rect(0.8, 7.877, 1.2, 8.077);
        let sin_tol = crate::contact::ContactParams::default()
            .angle_tolerance
            .sin();
        // V = vertex 1 of the left block (block 0), E = vertex 3 of the right block (block 1).
        let delta = Vector2::new(0.05, 0.1);
        let options = lines((0, &left, 1), (1, &right, 3), &delta, sin_tol);
        let keys: Vec<PairKey> = options.iter().map(|o| o.0).collect();
        // Kept: V on the right block's left face (edge 3) and E on the left block's right face
        // (edge 1), both touching at the step start.
        assert_eq!(keys, vec![(0, 1, 1, 3), (1, 3, 0, 1)], "{options:?}");
        for (_, gap) in &options {
            assert!((gap + 0.05).abs() < 1e-12, "{options:?}");
        }
        // A corner genuinely inside by 1 cm keeps the lines it is up to that deep beyond.
        let right_lower = rect(0.79, 7.877, 1.19, 8.077);
        let options = lines((0, &left, 1), (1, &right_lower, 3), &delta, sin_tol);
        assert!(
            options.iter().any(|o| o.0 == (0, 1, 1, 3)),
            "the 1 cm penetration through the left face is still an option: {options:?}"
        );
    }

    /// At a true vertex–vertex contact (corners coincide), every admissible line is an option.
    #[test]
    fn coincident_corners_keep_every_admissible_line() {
        let left = rect(0.0, 0.0, 0.4, 0.2);
        let right = rect(0.4, -0.2, 0.8, 0.0);
        let sin_tol = crate::contact::ContactParams::default()
            .angle_tolerance
            .sin();
        // V = left's bottom-right corner (vertex 1), E = right's top-left corner (vertex 3).
        let options = lines((0, &left, 1), (1, &right, 3), &Vector2::zeros(), sin_tol);
        assert_eq!(options.len(), 4, "{options:?}");
        assert!(options.iter().all(|o| o.1.abs() < 1e-12), "{options:?}");
    }
}
