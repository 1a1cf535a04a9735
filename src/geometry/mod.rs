//! Geometry: block polygons and their exact mass properties. Second stage of the flow (after
//! `scene`); `contact` and `assembly` read the current [`BlockGeometry`], `integrate` moves it.
//!
//! Units: m, m², m⁴. Polygons are counter-clockwise; second moments are about the centroid.
mod mass;
pub mod plane;

pub use mass::{polygon_moments, Moments};
use nalgebra::{Matrix2x6, SMatrix, Vector2};
pub use plane::{inside_depth, polygon_signed_area, segments_cross, segments_touch};

/// 6×6 block matrix (u0, v0, r0, εx, εy, γxy).
pub type Mat6 = SMatrix<f64, 6, 6>;
/// Block vector of the six unknowns.
pub type Vec6 = SMatrix<f64, 6, 1>;

/// Shi's first-order displacement function T(x, y) about the centroid `c`:
/// displacement of the material point `p` is `T · d` for block unknowns `d`.
#[inline]
pub fn displacement_matrix(p: Vector2<f64>, c: Vector2<f64>) -> Matrix2x6<f64> {
    let x = p.x - c.x;
    let y = p.y - c.y;
    Matrix2x6::new(1.0, 0.0, -y, x, 0.0, 0.5 * y, 0.0, 1.0, x, 0.0, y, 0.5 * x)
}

/// The moving shape of one block.
#[derive(Debug, Clone)]
pub struct BlockGeometry {
    /// Current vertices, m, counter-clockwise.
    pub vertices: Vec<Vector2<f64>>,
    /// Current centroid, m.
    pub centroid: Vector2<f64>,
    /// Centroid at the start, m (histories report displacement from here).
    pub initial_centroid: Vector2<f64>,
    /// Accumulated rigid rotation since the start, rad, counter-clockwise positive.
    pub rotation: f64,
    /// Current area and second moments about the centroid.
    pub moments: Moments,
    /// Half the diagonal of the bounding box, m (a size for tolerances).
    pub half_size: f64,
}

impl BlockGeometry {
    pub fn new(vertices: Vec<Vector2<f64>>) -> Self {
        let moments = polygon_moments(&vertices);
        let centroid = moments.centroid;
        let mut g = Self {
            vertices,
            centroid,
            initial_centroid: centroid,
            rotation: 0.0,
            moments,
            half_size: 0.0,
        };
        g.half_size = g.bounds_half_diagonal();
        g
    }

    /// Recompute centroid and moments after the vertices moved.
    pub fn refresh(&mut self) {
        self.moments = polygon_moments(&self.vertices);
        self.centroid = self.moments.centroid;
    }

    /// Axis-aligned bounding box (min, max), m.
    pub fn bounds(&self) -> (Vector2<f64>, Vector2<f64>) {
        let mut lo = self.vertices[0];
        let mut hi = self.vertices[0];
        for v in &self.vertices[1..] {
            lo = lo.inf(v);
            hi = hi.sup(v);
        }
        (lo, hi)
    }

    fn bounds_half_diagonal(&self) -> f64 {
        let (lo, hi) = self.bounds();
        0.5 * (hi - lo).norm()
    }

    /// Mass matrix ∫ρ TᵀT dA about the centroid (exact polygon integrals), kg·(m, m², …).
    pub fn mass_matrix(&self, density: f64) -> Mat6 {
        let m = &self.moments;
        let (a, sxx, syy, sxy) = (m.area, m.sxx, m.syy, m.sxy);
        let mut k = Mat6::zeros();
        k[(0, 0)] = a;
        k[(1, 1)] = a;
        k[(2, 2)] = sxx + syy;
        k[(2, 3)] = -sxy;
        k[(2, 4)] = sxy;
        k[(2, 5)] = 0.5 * (sxx - syy);
        k[(3, 3)] = sxx;
        k[(3, 5)] = 0.5 * sxy;
        k[(4, 4)] = syy;
        k[(4, 5)] = 0.5 * sxy;
        k[(5, 5)] = 0.25 * (sxx + syy);
        for i in 0..6 {
            for j in 0..i {
                k[(i, j)] = k[(j, i)];
            }
        }
        k * density
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn mass_matrix_equals_numeric_integral_of_t_transpose_t() {
        // Independent check: midpoint-rule integration of TᵀT over a fine grid of an L-shaped
        // polygon; 600×600 cells (aligned with the re-entrant corner) give ~1e-5 relative accuracy.
        let verts = vec![
            Vector2::new(0.0, 0.0),
            Vector2::new(2.0, 0.0),
            Vector2::new(2.0, 1.0),
            Vector2::new(1.0, 1.0),
            Vector2::new(1.0, 3.0),
            Vector2::new(0.0, 3.0),
        ];
        let g = BlockGeometry::new(verts);
        let exact = g.mass_matrix(1.0);
        let n = 600;
        let (hx, hy) = (2.0 / n as f64, 3.0 / n as f64);
        let mut num = Mat6::zeros();
        for i in 0..n {
            for j in 0..n {
                let p = Vector2::new((i as f64 + 0.5) * hx, (j as f64 + 0.5) * hy);
                if p.x > 1.0 && p.y > 1.0 {
                    continue;
                }
                let t = displacement_matrix(p, g.centroid);
                num += t.transpose() * t * hx * hy;
            }
        }
        let err = (exact - num).abs().max();

        assert!(err < 1e-4 * exact.abs().max(), "mass matrix error {err}");
    }
}
