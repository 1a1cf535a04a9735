//! Switching of vertex–vertex contact pairs (seed 003 §6, Appendix C). When vertex V of block
//! i meets corner E of block j, several contact pairs are possible: V against either edge of
//! j that ends at E, or E against either edge of i that ends at V. Each is one separating line;
//! the true condition is that *some* line separates the corners. Detection picks one pair from
//! the step-start geometry; after a solve, the pair is re-chosen as the admissible line that
//! the corners' relative motion (without this contact's own force) leaves the largest gap —
//! the line needing the smallest correction, which is Bao and Zhao's argument for their
//! four-block example — and the step is re-solved.
use super::gap::{GapFunction, Pair};
use super::DualInput;
use crate::contact::{edge_points, Contact, ContactState};
use crate::geometry::{displacement_matrix, BlockGeometry, Vec6};
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
        let gi = &geoms[c.vertex_block];
        let ni = gi.vertices.len();
        // Step-end gap of each admissible separating line through the two corners.
        let mut options: Vec<(PairKey, f64)> = Vec::with_capacity(4);
        for e in [corner, (corner + nj - 1) % nj] {
            let n = outward_normal(gj, e);
            if admissible(gi, c.vertex, &n, sin_tol) {
                let g0 = n.dot(&(vi - gj.vertices[e]));
                options.push((
                    (c.vertex_block, c.vertex, c.edge_block, e),
                    g0 + n.dot(&delta),
                ));
            }
        }
        for e in [c.vertex, (c.vertex + ni - 1) % ni] {
            let n = outward_normal(gi, e);
            if admissible(gj, corner, &n, sin_tol) {
                let g0 = n.dot(&(ej - gi.vertices[e]));
                options.push((
                    (c.edge_block, corner, c.vertex_block, e),
                    g0 - n.dot(&delta),
                ));
            }
        }
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
        linearize(&mut new, geoms);
        contacts[k] = new;
    }
    count
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

/// The step-start contact frame of a switched pair (as `contact::ContactSet::linearize` does
/// for detected ones), with the shear reference at the vertex's projection.
fn linearize(c: &mut Contact, geoms: &[BlockGeometry]) {
    let gi = &geoms[c.vertex_block];
    let gj = &geoms[c.edge_block];
    let p = gi.vertices[c.vertex];
    let (a, b) = edge_points(gj, c.edge);
    let ab = b - a;
    let len = ab.norm();
    let t = ab / len;
    let n = Vector2::new(t.y, -t.x);
    c.t = t;
    c.n = n;
    c.g0 = n.dot(&(p - a));
    c.xi = t.dot(&(p - a)) / len;
    c.ref_xi = c.xi;
    c.s0 = 0.0;
    let q = a + ab * c.xi;
    let ti = displacement_matrix(p, gi.centroid);
    let tq = displacement_matrix(q, gj.centroid);
    c.e_i = ti.transpose() * n;
    c.e_j = tq.transpose() * n;
    c.f_i = ti.transpose() * t;
    c.f_j = tq.transpose() * t;
}
