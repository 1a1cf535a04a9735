//! Ear-clipping triangulation of a block outline, so viewers can fill the (possibly
//! non-convex) polygon. Sits in `record`; used by the scene messages of the MCAP recorder.

/// Triangles covering the simple polygon `points` (either orientation), as indices into
/// `points`, three a triangle, each triangle counter-clockwise in the plane when the polygon is
/// counter-clockwise. Vertices where the outline does not turn (collinear, repeated) are cut
/// off without a triangle, so a polygon with such vertices gives fewer than `n − 2` triangles.
/// Never panics: a self-intersecting outline (which a valid scene never produces) ends with a
/// fan over what is left, drawn wrongly but visibly.
pub fn triangulate(points: &[[f64; 2]]) -> Vec<u32> {
    let n = points.len();
    if n < 3 {
        return Vec::new();
    }
    // Work on a CCW order of indices.
    let mut ring: Vec<usize> = (0..n).collect();
    if signed_area(points) < 0.0 {
        ring.reverse();
    }
    let eps = area_tolerance(points);
    let mut out = Vec::with_capacity(3 * (n - 2));
    let mut i = 0;
    let mut since_last_cut = 0;
    while ring.len() > 3 {
        let m = ring.len();
        let (a, b, c) = (ring[(i + m - 1) % m], ring[i % m], ring[(i + 1) % m]);
        let turn = cross(points[a], points[b], points[c]);
        if turn.abs() <= eps {
            // No turn at b: dropping it loses no area.
            ring.remove(i % m);
            since_last_cut = 0;
            continue;
        }
        if turn > 0.0 && !any_inside(points, &ring, a, b, c, eps) {
            out.extend([a as u32, b as u32, c as u32]);
            ring.remove(i % m);
            since_last_cut = 0;
            continue;
        }
        i = (i + 1) % m;
        since_last_cut += 1;
        if since_last_cut > m {
            // No ear in a full turn: not a simple polygon. Fan what is left.
            for k in 1..ring.len() - 1 {
                out.extend([ring[0] as u32, ring[k] as u32, ring[k + 1] as u32]);
            }
            return out;
        }
    }
    if cross(points[ring[0]], points[ring[1]], points[ring[2]]).abs() > eps {
        out.extend([ring[0] as u32, ring[1] as u32, ring[2] as u32]);
    }
    out
}

/// Shoelace area, positive for a counter-clockwise polygon.
pub fn signed_area(points: &[[f64; 2]]) -> f64 {
    let n = points.len();
    (0..n)
        .map(|i| {
            let (p, q) = (points[i], points[(i + 1) % n]);
            p[0] * q[1] - q[0] * p[1]
        })
        .sum::<f64>()
        / 2.0
}

/// Twice the signed area of triangle (a, b, c); positive when it turns left at b.
fn cross(a: [f64; 2], b: [f64; 2], c: [f64; 2]) -> f64 {
    (b[0] - a[0]) * (c[1] - b[1]) - (b[1] - a[1]) * (c[0] - b[0])
}

/// What counts as "no turn": 1e-12 of the squared bounding-box size, far below any real corner
/// of a block yet above the rounding of a cross product of coordinates of that size.
fn area_tolerance(points: &[[f64; 2]]) -> f64 {
    let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
    for p in points {
        for k in 0..2 {
            lo[k] = lo[k].min(p[k]);
            hi[k] = hi[k].max(p[k]);
        }
    }
    let size = (hi[0] - lo[0]).max(hi[1] - lo[1]);
    1e-12 * size * size
}

/// Whether another remaining vertex lies inside or on triangle (a, b, c) (then cutting the ear
/// would overlap the rest of the polygon). Vertices at the same place as a corner are ignored.
fn any_inside(points: &[[f64; 2]], ring: &[usize], a: usize, b: usize, c: usize, eps: f64) -> bool {
    let (pa, pb, pc) = (points[a], points[b], points[c]);
    ring.iter().any(|&k| {
        if k == a || k == b || k == c {
            return false;
        }
        let p = points[k];
        if p == pa || p == pb || p == pc {
            return false;
        }
        cross(pa, pb, p) >= -eps && cross(pb, pc, p) >= -eps && cross(pc, pa, p) >= -eps
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    fn triangle_areas(points: &[[f64; 2]], idx: &[u32]) -> Vec<f64> {
        idx.chunks(3)
            .map(|t| {
                cross(
                    points[t[0] as usize],
                    points[t[1] as usize],
                    points[t[2] as usize],
                ) / 2.0
            })
            .collect()
    }

    /// Independent reference: the shoelace area. The triangles must tile the polygon, so their
    /// areas (all positive) add up to it; 1e-11 relative covers the rounding of up to 40
    /// products of coordinates a few times the polygon's size.
    fn assert_tiles(points: &[[f64; 2]]) -> Vec<u32> {
        let idx = triangulate(points);
        let areas = triangle_areas(points, &idx);
        let a = signed_area(points).abs();
        // Orientation: triangles come out CCW whatever the input's orientation.
        assert!(areas.iter().all(|&t| t > 0.0), "{areas:?}");
        let sum: f64 = areas.iter().sum();
        assert!((sum - a).abs() <= 1e-11 * a, "sum {sum} vs area {a}");
        idx
    }

    #[test]
    fn square_either_orientation_gives_two_triangles() {
        let ccw = [[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]];
        assert_eq!(assert_tiles(&ccw).len(), 6);
        let mut cw = ccw;
        cw.reverse();
        assert_eq!(assert_tiles(&cw).len(), 6);
    }

    #[test]
    fn non_convex_l_shape_and_u_shape() {
        let l = [
            [0.0, 0.0],
            [2.0, 0.0],
            [2.0, 1.0],
            [1.0, 1.0],
            [1.0, 3.0],
            [0.0, 3.0],
        ];
        assert_eq!(assert_tiles(&l).len(), 3 * 4);
        let u = [
            [0.0, 0.0],
            [3.0, 0.0],
            [3.0, 2.0],
            [2.0, 2.0],
            [2.0, 1.0],
            [1.0, 1.0],
            [1.0, 2.0],
            [0.0, 2.0],
        ];
        assert_eq!(assert_tiles(&u).len(), 3 * 6);
    }

    #[test]
    fn collinear_and_repeated_vertices_are_dropped_without_slivers() {
        // assert_tiles rejects zero-area triangles; at most n − 2 = 4 triangles, fewer when the
        // repeated vertex is cut off on its own.
        let p = [
            [0.0, 0.0],
            [1.0, 0.0],
            [2.0, 0.0],
            [2.0, 1.0],
            [2.0, 1.0],
            [0.0, 1.0],
        ];
        assert!(assert_tiles(&p).len() <= 3 * 4);
    }

    #[test]
    fn degenerate_inputs_do_not_panic() {
        assert!(triangulate(&[[0.0, 0.0], [1.0, 0.0]]).is_empty());
        assert!(triangulate(&[[0.0, 0.0], [1.0, 0.0], [2.0, 0.0]]).is_empty());
        // A bow tie is not simple: some triangles come out, nothing panics or loops.
        let bow = [[0.0, 0.0], [1.0, 1.0], [1.0, 0.0], [0.0, 1.0]];
        let idx = triangulate(&bow);
        assert!(idx.len() % 3 == 0 && idx.iter().all(|&i| i < 4));
    }

    proptest! {
        /// Star-shaped polygons (radii at sorted angles) are simple and often very non-convex.
        #[test]
        fn star_polygons_are_tiled(radii in prop::collection::vec(0.2f64..2.0, 3..40),
                                   jitter in prop::collection::vec(0.0f64..0.9, 40),
                                   scale in 1e-3f64..1e3, offset in -2.0f64..2.0) {
            let n = radii.len();
            let pts: Vec<[f64; 2]> = (0..n).map(|i| {
                let ang = (i as f64 + jitter[i]) / n as f64 * std::f64::consts::TAU;
                [scale * (offset + radii[i] * ang.cos()), scale * radii[i] * ang.sin()]
            }).collect();
            assert_tiles(&pts);
        }
    }
}
