//! Exact area, centroid and second moments of a simple polygon (Green's theorem).
use nalgebra::Vector2;

/// Area (m²), centroid (m) and second moments about the centroid (m⁴):
/// `sxx = ∫(x−xc)² dA`, `syy = ∫(y−yc)² dA`, `sxy = ∫(x−xc)(y−yc) dA`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Moments {
    pub area: f64,
    pub centroid: Vector2<f64>,
    pub sxx: f64,
    pub syy: f64,
    pub sxy: f64,
}

/// Moments of a counter-clockwise polygon. Integrals are taken about the first vertex to keep
/// round-off small for polygons far from the origin.
pub fn polygon_moments(v: &[Vector2<f64>]) -> Moments {
    let o = v[0];
    let n = v.len();
    let (mut a, mut cx, mut cy, mut ixx, mut iyy, mut ixy) = (0.0, 0.0, 0.0, 0.0, 0.0, 0.0);
    for i in 0..n {
        let p = v[i] - o;
        let q = v[(i + 1) % n] - o;
        let cr = p.x * q.y - q.x * p.y;
        a += cr;
        cx += (p.x + q.x) * cr;
        cy += (p.y + q.y) * cr;
        ixx += (p.x * p.x + p.x * q.x + q.x * q.x) * cr;
        iyy += (p.y * p.y + p.y * q.y + q.y * q.y) * cr;
        ixy += (p.x * q.y + 2.0 * p.x * p.y + 2.0 * q.x * q.y + q.x * p.y) * cr;
    }
    let area = 0.5 * a;
    let cxl = cx / (6.0 * area);
    let cyl = cy / (6.0 * area);
    // ∫x² dA, ∫y² dA, ∫xy dA about the first vertex, then shifted to the centroid.
    let sxx = ixx / 12.0 - area * cxl * cxl;
    let syy = iyy / 12.0 - area * cyl * cyl;
    let sxy = ixy / 24.0 - area * cxl * cyl;
    Moments {
        area,
        centroid: Vector2::new(cxl + o.x, cyl + o.y),
        sxx,
        syy,
        sxy,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rectangle_moments_match_closed_form() {
        // b×h rectangle: A = bh, Sxx = b³h/12, Syy = bh³/12, Sxy = 0 (exact to round-off).
        let (b, h) = (0.4, 1.2);
        let v = vec![
            Vector2::new(10.0, 5.0),
            Vector2::new(10.0 + b, 5.0),
            Vector2::new(10.0 + b, 5.0 + h),
            Vector2::new(10.0, 5.0 + h),
        ];
        let m = polygon_moments(&v);
        assert!((m.area - b * h).abs() < 1e-14);
        assert!((m.centroid - Vector2::new(10.2, 5.6)).norm() < 1e-12);
        assert!((m.sxx - b.powi(3) * h / 12.0).abs() < 1e-12);
        assert!((m.syy - b * h.powi(3) / 12.0).abs() < 1e-12);
        assert!(m.sxy.abs() < 1e-12);
    }

    #[test]
    fn right_triangle_product_moment() {
        // Right triangle legs a (x), b (y): Sxy about centroid = −a²b²/72.
        let (a, b) = (3.0, 2.0);
        let m = polygon_moments(&[
            Vector2::new(0.0, 0.0),
            Vector2::new(a, 0.0),
            Vector2::new(0.0, b),
        ]);
        assert!((m.sxy + a * a * b * b / 72.0).abs() < 1e-12);
        assert!((m.sxx - a.powi(3) * b / 36.0).abs() < 1e-12);
    }
}
