//! Reduced models, rocking: Housner's equation of a rigid block pivoting on one corner of its
//! contact edge, in the contact's local frame (so an inclined base needs no special case), with
//! an impact law at each change of pivot.
//!
//! Sign conventions: θ counter-clockwise positive (rad). Pivot 0 is the contact corner at
//! local t = 0: the block rocks on it with θ ≥ 0; pivot 1 (t = contact length) with θ ≤ 0.
//! `a` is the effective load per unit mass in local coordinates: gravity minus the ground
//! acceleration (m/s²).
use super::qualify::SingleBlock;
use nalgebra::Vector2;

/// Which impact law to apply when the block lands on its other corner.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Restitution {
    /// Conservation of angular momentum about the new pivot (Housner 1963): for a block of any
    /// convex shape e = (I_c + m r₀·r₁)/(I_c + m|r₁|²), which for a rectangle is
    /// 1 − 1.5 sin²α (α: the slenderness angle). For a squat block (a rectangle with
    /// α > 54.7°) the formula is negative: the momentum about the landing corner would turn
    /// the block back into the base, i.e. it does not rock onto that corner at all, and the
    /// impact ends the rocking (e = 0, see [`housner_ratio`]).
    Housner,
    /// A given ratio of angular velocities after/before impact.
    Coefficient(f64),
}

/// Sign of θ on pivot `k`: +1 on pivot 0, −1 on pivot 1.
pub fn side(k: usize) -> f64 {
    if k == 0 {
        1.0
    } else {
        -1.0
    }
}

fn rotate(v: Vector2<f64>, th: f64) -> Vector2<f64> {
    let (s, c) = th.sin_cos();
    Vector2::new(c * v.x - s * v.y, s * v.x + c * v.y)
}

fn cross(a: Vector2<f64>, b: Vector2<f64>) -> f64 {
    a.x * b.y - a.y * b.x
}

/// Moment of inertia about pivot `k`, kg·m².
pub fn pivot_inertia(b: &SingleBlock, k: usize) -> f64 {
    b.inertia + b.mass * b.arm(k).norm_squared()
}

/// θ̈ (rad/s²) on pivot `k` at rotation θ under the load `a` (m/s² per unit mass, local).
pub fn angular_acceleration(b: &SingleBlock, k: usize, th: f64, a: Vector2<f64>) -> f64 {
    let r = rotate(b.arm(k), th);
    b.mass * cross(r, a) / pivot_inertia(b, k)
}

/// Would the block start rocking on pivot `k` from rest under `a`? (The moment of the load
/// about the corner turns the block away from the base.)
pub fn tips(b: &SingleBlock, k: usize, a: Vector2<f64>) -> bool {
    side(k) * cross(b.arm(k), a) > 0.0
}

/// Contact reaction per unit mass at the pivot (local: tangential, normal), m/s².
pub fn reaction(b: &SingleBlock, k: usize, th: f64, w: f64, a: Vector2<f64>) -> Vector2<f64> {
    let r = rotate(b.arm(k), th);
    let acc = angular_acceleration(b, k, th, a);
    let centroid_acc = Vector2::new(-r.y, r.x) * acc - r * (w * w);
    centroid_acc - a
}

/// Angular velocity ratio at an impact that moves the pivot from `k` to the other corner.
pub fn restitution(b: &SingleBlock, k: usize, law: Restitution) -> f64 {
    match law {
        Restitution::Coefficient(e) => e,
        Restitution::Housner => housner_ratio(b, k).max(0.0),
    }
}

/// The ratio of Housner's angular-momentum law before the physical limit:
/// (I_c + m r₀·r₁)/(I_c + m|r₁|²), negative for squat blocks (the law does not apply to them:
/// the impact ends the rocking).
pub fn housner_ratio(b: &SingleBlock, k: usize) -> f64 {
    let (r0, r1) = (b.arm(k), b.arm(1 - k));
    (b.inertia + b.mass * r0.dot(&r1)) / (b.inertia + b.mass * r1.norm_squared())
}

/// Local position of the centroid on pivot `k` at θ, with the block slid by `slip` along t.
pub fn centroid(b: &SingleBlock, k: usize, th: f64, slip: f64) -> Vector2<f64> {
    Vector2::new(b.pivots[k] + slip, 0.0) + rotate(b.arm(k), th)
}

/// Local vertices on pivot `k` at θ, slid by `slip`.
pub fn vertices(b: &SingleBlock, k: usize, th: f64, slip: f64) -> Vec<Vector2<f64>> {
    let p = Vector2::new(b.pivots[k], 0.0);
    b.vertices
        .iter()
        .map(|v| p + Vector2::new(slip, 0.0) + rotate(v - p, th))
        .collect()
}

/// Lowest normal coordinate (m) of the vertices that start above the contact line, on pivot
/// `k` at θ: it reaches 0 when another face of the block lands on the base.
pub fn side_clearance(b: &SingleBlock, k: usize, th: f64, lift_tol: f64) -> f64 {
    let p = Vector2::new(b.pivots[k], 0.0);
    b.vertices
        .iter()
        .filter(|v| v.y > lift_tol)
        .map(|v| (p + rotate(v - p, th)).y)
        .fold(f64::INFINITY, f64::min)
}

/// Has the centroid passed over the pivot (the block is falling, not rocking back)?
pub fn beyond_tipping(b: &SingleBlock, k: usize, th: f64) -> bool {
    let r = rotate(b.arm(k), th);
    side(k) * r.x > 0.0
}

#[cfg(test)]
mod tests {
    use super::*;

    fn rectangle(bh: f64, hh: f64) -> SingleBlock {
        let v = vec![
            Vector2::new(0.0, 0.0),
            Vector2::new(2.0 * bh, 0.0),
            Vector2::new(2.0 * bh, 2.0 * hh),
            Vector2::new(0.0, 2.0 * hh),
        ];
        let m = 4.0 * bh * hh;
        SingleBlock {
            free: 1,
            base: 0,
            driven: false,
            origin: Vector2::zeros(),
            t: Vector2::new(1.0, 0.0),
            n: Vector2::new(0.0, 1.0),
            pivots: [0.0, 2.0 * bh],
            centroid: Vector2::new(bh, hh),
            vertices: v,
            mass: m,
            inertia: m * (4.0 * bh * bh + 4.0 * hh * hh) / 12.0,
            mu: 1.0,
            gravity: 9.81,
            initial_slip_rate: 0.0,
            slope: 0.0,
        }
    }

    #[test]
    fn housner_restitution_of_a_rectangle() {
        // Closed form 1 − 1.5 sin²α, α = atan(b/h); exact up to round-off (1e-12).
        let b = rectangle(0.2, 0.6);
        let alpha = (0.2f64 / 0.6).atan();
        let e = restitution(&b, 0, Restitution::Housner);
        assert!((e - (1.0 - 1.5 * alpha.sin().powi(2))).abs() < 1e-12, "{e}");
    }

    #[test]
    fn squat_blocks_stop_at_the_impact() {
        // 1 − 1.5 sin²α < 0 for α > 54.7° (here α = atan 2 = 63.4°): the impact is plastic.
        let b = rectangle(0.6, 0.3);
        let alpha = 2f64.atan();
        assert!((housner_ratio(&b, 0) - (1.0 - 1.5 * alpha.sin().powi(2))).abs() < 1e-12);
        assert!(housner_ratio(&b, 0) < 0.0);
        assert_eq!(restitution(&b, 0, Restitution::Housner), 0.0);
    }

    #[test]
    fn housner_equation_of_motion() {
        // θ̈ = −(3g/4R) sin(α − θ) on pivot 0 under gravity alone (Housner, p = √(3g/4R)).
        let b = rectangle(0.2, 0.6);
        let r = (0.2f64.powi(2) + 0.6f64.powi(2)).sqrt();
        let alpha = (0.2f64 / 0.6).atan();
        let th = 0.1;
        let acc = angular_acceleration(&b, 0, th, Vector2::new(0.0, -9.81));
        let exact = -3.0 * 9.81 / (4.0 * r) * (alpha - th).sin();
        assert!(
            (acc - exact).abs() < 1e-12 * exact.abs(),
            "{acc} vs {exact}"
        );
    }
}
