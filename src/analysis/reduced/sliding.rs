//! Reduced models, sliding: the rigid-plastic (Newmark 1965) block on a Coulomb joint, in the
//! contact's local frame so an inclined base needs no special case.
//!
//! s is the slip along t (m), v = ṡ (m/s); `a` the effective load per unit mass in local
//! coordinates (m/s²): its normal component presses the block on the base when negative.
use super::qualify::SingleBlock;
use nalgebra::Vector2;

/// Normal pressure per unit mass, m/s² (positive while the block is pressed on its base).
pub fn pressure(a: Vector2<f64>) -> f64 {
    -a.y
}

/// Slip acceleration (m/s²) while sliding in the direction `dir` (±1).
pub fn acceleration(b: &SingleBlock, dir: f64, a: Vector2<f64>) -> f64 {
    a.x - dir * b.mu * pressure(a)
}

/// Would a block at rest start to slide under `a`? Returns the direction (±1) if so.
pub fn slips(b: &SingleBlock, a: Vector2<f64>) -> Option<f64> {
    (a.x.abs() > b.mu * pressure(a)).then_some(a.x.signum())
}

/// Does a block sliding in `dir` stay flat? In the frame sliding with it the load is tilted by
/// exactly φ towards the motion, so the leading corner tips iff φ exceeds that corner's
/// slenderness angle (independent of the record: a property of the scene).
pub fn stays_flat(b: &SingleBlock, dir: f64) -> bool {
    let lead = if dir > 0.0 { 1 } else { 0 };
    let load = Vector2::new(dir * b.mu, -1.0);
    !super::rocking::tips(b, lead, load)
}
