//! Plane geometry of polygons and segments (geometry, the ground floor of the flow): signed
//! area, segment crossings, the depth of a point inside a polygon. Used by `scene` to validate
//! polygons and by `contact` and `solve::dual` to tell a real penetration from a grazing one.
//! Units: m, m²; polygons counter-clockwise.
use nalgebra::Vector2;

/// Shoelace signed area, m²; positive for counter-clockwise.
pub fn polygon_signed_area(v: &[Vector2<f64>]) -> f64 {
    let n = v.len();
    let mut s = 0.0;
    for i in 0..n {
        let a = v[i];
        let b = v[(i + 1) % n];
        s += a.x * b.y - b.x * a.y;
    }
    0.5 * s
}

fn orient(a: Vector2<f64>, b: Vector2<f64>, c: Vector2<f64>) -> f64 {
    (b - a).perp(&(c - a))
}

/// True when segments `ab` and `cd` cross at a point interior to both (a proper crossing),
/// with `tol` the tolerance on the orientation tests (m²).
pub fn segments_cross(
    a: Vector2<f64>,
    b: Vector2<f64>,
    c: Vector2<f64>,
    d: Vector2<f64>,
    tol: f64,
) -> bool {
    let o = orientations(a, b, c, d);
    proper_cross(&o, tol)
}

/// Orientations of c and d against ab, then of a and b against cd.
fn orientations(a: Vector2<f64>, b: Vector2<f64>, c: Vector2<f64>, d: Vector2<f64>) -> [f64; 4] {
    [
        orient(a, b, c),
        orient(a, b, d),
        orient(c, d, a),
        orient(c, d, b),
    ]
}

/// Each segment's endpoints lie strictly on opposite sides of the other's line.
fn proper_cross(o: &[f64; 4], tol: f64) -> bool {
    let opposite = |p: f64, q: f64| (p > tol && q < -tol) || (p < -tol && q > tol);
    opposite(o[0], o[1]) && opposite(o[2], o[3])
}

/// True when segments touch or cross anywhere (used for self-intersection of non-adjacent edges).
pub fn segments_touch(
    a: Vector2<f64>,
    b: Vector2<f64>,
    c: Vector2<f64>,
    d: Vector2<f64>,
    tol: f64,
) -> bool {
    let o = orientations(a, b, c, d);
    if proper_cross(&o, tol) {
        return true;
    }
    let [o1, o2, o3, o4] = o;
    let on = |p: Vector2<f64>, q: Vector2<f64>, r: Vector2<f64>, o: f64| {
        o.abs() <= tol
            && r.x >= p.x.min(q.x) - tol.sqrt()
            && r.x <= p.x.max(q.x) + tol.sqrt()
            && r.y >= p.y.min(q.y) - tol.sqrt()
            && r.y <= p.y.max(q.y) + tol.sqrt()
    };
    on(a, b, c, o1) || on(a, b, d, o2) || on(c, d, a, o3) || on(c, d, b, o4)
}

/// Signed depth of `p` inside the counter-clockwise polygon `poly` (m): positive inside (the
/// distance to the nearest edge), negative or zero outside.
pub fn inside_depth(p: Vector2<f64>, poly: &[Vector2<f64>]) -> f64 {
    let n = poly.len();
    let mut inside = false;
    let mut dmin = f64::INFINITY;
    for i in 0..n {
        let a = poly[i];
        let b = poly[(i + 1) % n];
        if (a.y > p.y) != (b.y > p.y) {
            let x = a.x + (p.y - a.y) / (b.y - a.y) * (b.x - a.x);
            if p.x < x {
                inside = !inside;
            }
        }
        let ab = b - a;
        let t = ((p - a).dot(&ab) / ab.norm_squared()).clamp(0.0, 1.0);
        dmin = dmin.min((a + ab * t - p).norm());
    }
    if inside {
        dmin
    } else {
        -dmin
    }
}
