//! Reduced models, qualification: does the scene reduce to one free block resting flat on one
//! base? If so, the block in the contact's local frame; if not, the reason why not.
use super::ReducedParams;
use crate::geometry::polygon_moments;
use crate::scene::{BlockKind, BlockModel, Excitation, Scene};
use nalgebra::Vector2;

/// A single rigid block resting along one of its edges on one base edge, described in the local
/// frame of the contact: `t` runs along the block's bottom edge (its counter-clockwise
/// direction), `n` = t rotated +90° points into the block. Local coordinates are (along t,
/// along n) in m from the block's first contact corner.
#[derive(Debug, Clone)]
pub struct SingleBlock {
    /// Scene indices of the free block and of its base.
    pub free: usize,
    pub base: usize,
    /// The base is the driven block (results are absolute) rather than fixed.
    pub driven: bool,
    /// World position of the local origin (the first contact corner), m.
    pub origin: Vector2<f64>,
    /// Unit vectors of the local frame in world coordinates.
    pub t: Vector2<f64>,
    pub n: Vector2<f64>,
    /// Local t of the two contact corners (pivots): 0 and the contact length, m.
    pub pivots: [f64; 2],
    /// Local centroid, m.
    pub centroid: Vector2<f64>,
    /// Block vertices in local coordinates, m (counter-clockwise).
    pub vertices: Vec<Vector2<f64>>,
    /// kg per m of thickness.
    pub mass: f64,
    /// Polar moment of inertia about the centroid, kg·m² per m of thickness.
    pub inertia: f64,
    /// Coulomb friction coefficient tan φ of the joint.
    pub mu: f64,
    /// m/s², along world −y.
    pub gravity: f64,
    /// Initial sliding velocity along t, m/s.
    pub initial_slip_rate: f64,
    /// Slope of the contact: angle of t from the world +x axis, rad.
    pub slope: f64,
}

impl SingleBlock {
    /// Local vector from pivot `k` to the centroid at zero rotation, m.
    pub fn arm(&self, k: usize) -> Vector2<f64> {
        self.centroid - Vector2::new(self.pivots[k], 0.0)
    }

    /// Local vector → world vector.
    pub fn to_world(&self, v: Vector2<f64>) -> Vector2<f64> {
        self.t * v.x + self.n * v.y
    }

    /// World vector → local vector.
    pub fn to_local(&self, v: Vector2<f64>) -> Vector2<f64> {
        Vector2::new(v.dot(&self.t), v.dot(&self.n))
    }

    /// Angle between the line from pivot `k` to the centroid and the contact normal, rad
    /// (Housner's α for a rectangle on its corner).
    pub fn slenderness(&self, k: usize) -> f64 {
        let r = self.arm(k);
        r.x.abs().atan2(r.y)
    }
}

/// Why no reduced model represents a scene: its geometry ([`qualify`]) or a control they do
/// not represent ([`super::represented`]). Its text is shown to the user in `model_reason` and
/// in [`crate::analysis::run::RunError::ModelNotApplicable`].
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum NotReducible {
    #[error("the scene has {0} free blocks; a reduced model needs exactly one")]
    FreeBlocks(usize),
    #[error(
        "the scene has {0} blocks; a reduced model needs exactly two (one free block on one base)"
    )]
    Blocks(usize),
    #[error("block {0:?} must be the fixed base (base_acceleration) or the driven block")]
    Base(String),
    #[error("joint {0:?} has cohesion or tensile strength; the reduced models take a cohesionless Coulomb joint")]
    Cohesive(String),
    #[error("block {block:?} is not convex (vertex {vertex}); the reduced models pivot on the corners of a convex block")]
    NotConvex { block: String, vertex: usize },
    #[error("block {block:?} overhangs the edge of base {base:?}; the reduced models need its whole bottom edge on the base")]
    Overhangs { block: String, base: String },
    #[error("block {block:?} does not rest along one of its edges on an edge of {base:?} (flat contact within {tolerance:.1e} m)")]
    NoFlatContact {
        block: String,
        base: String,
        /// m.
        tolerance: f64,
    },
    #[error("block {block:?} is deformable and soft (self-weight strain ρ g H / E above {limit:.0e}); rigid behaviour is not adequate")]
    Soft { block: String, limit: f64 },
    #[error("block {0:?} starts with an angular or normal velocity; the reduced models start at rest or sliding")]
    Moving(String),
    /// Controls the reduced models do not represent, each a sentence ([`super::represented`]).
    #[error("{}", .0.join("; "))]
    Controls(Vec<String>),
}

fn cross(a: Vector2<f64>, b: Vector2<f64>) -> f64 {
    a.x * b.y - a.y * b.x
}

/// The single-block description of `scene`, or why the scene is not one (its geometry, or a
/// control the reduced models do not represent: [`super::represented`]).
pub fn qualify(scene: &Scene, params: &ReducedParams) -> Result<SingleBlock, NotReducible> {
    let free: Vec<usize> = scene.free_blocks().collect();
    if free.len() != 1 {
        return Err(NotReducible::FreeBlocks(free.len()));
    }
    if scene.blocks.len() != 2 {
        return Err(NotReducible::Blocks(scene.blocks.len()));
    }
    let f = free[0];
    let b = 1 - f;
    let (fb, bb) = (&scene.blocks[f], &scene.blocks[b]);
    let driven = match (scene.excitation, bb.kind) {
        (Excitation::BaseAcceleration, BlockKind::Fixed) => false,
        (Excitation::DrivenBlock(d), BlockKind::Driven) if d == b => true,
        _ => return Err(NotReducible::Base(bb.id.clone())),
    };
    let joint = scene.joint_between(f, b);
    if joint.cohesion != 0.0 || joint.tensile_strength != 0.0 {
        return Err(NotReducible::Cohesive(joint.name.clone()));
    }
    let v = &fb.vertices;
    let nv = v.len();
    for i in 0..nv {
        let (a, p, c) = (v[(i + nv - 1) % nv], v[i], v[(i + 1) % nv]);
        if cross(p - a, c - p) < -1e-12 * (p - a).norm() * (c - p).norm() {
            return Err(NotReducible::NotConvex {
                block: fb.id.clone(),
                vertex: i,
            });
        }
    }
    let moments = polygon_moments(v);
    let size = v
        .iter()
        .map(|p| (p - moments.centroid).norm())
        .fold(0.0, f64::max);
    let tol = params.contact_tolerance * size;
    let base = &bb.vertices;
    let mut found = None;
    for i in 0..nv {
        let (p0, p1) = (v[i], v[(i + 1) % nv]);
        let len = (p1 - p0).norm();
        let t = (p1 - p0) / len;
        for j in 0..base.len() {
            let (q0, q1) = (base[j], base[(j + 1) % base.len()]);
            let lq = (q1 - q0).norm();
            let tq = (q1 - q0) / lq;
            // A block resting on the base edge runs against it (both polygons counter-clockwise).
            if t.dot(&tq) > -1.0 + 1e-9 {
                continue;
            }
            let off = |p: Vector2<f64>| cross(tq, p - q0);
            if off(p0).abs() > tol || off(p1).abs() > tol {
                continue;
            }
            let along = |p: Vector2<f64>| (p - q0).dot(&tq);
            let inside = |s: f64| (-tol..=lq + tol).contains(&s);
            if !inside(along(p0)) || !inside(along(p1)) {
                return Err(NotReducible::Overhangs {
                    block: fb.id.clone(),
                    base: bb.id.clone(),
                });
            }
            found = Some((p0, t, len));
        }
    }
    let Some((origin, t, len)) = found else {
        return Err(NotReducible::NoFlatContact {
            block: fb.id.clone(),
            base: bb.id.clone(),
            tolerance: tol,
        });
    };
    let n = Vector2::new(-t.y, t.x);
    let local = |p: Vector2<f64>| Vector2::new((p - origin).dot(&t), (p - origin).dot(&n));
    let rigid_ok = match fb.kind {
        BlockKind::Free(BlockModel::Rigid) => true,
        _ => {
            let mat = &scene.materials[fb.material];
            let height = v.iter().map(|p| local(*p).y).fold(0.0, f64::max);
            let strain = mat.density * scene.gravity * height / mat.young_modulus;
            strain <= params.rigid_strain
        }
    };
    if !rigid_ok {
        return Err(NotReducible::Soft {
            block: fb.id.clone(),
            limit: params.rigid_strain,
        });
    }
    let iv = scene.initial_velocity[f];
    let vt = iv[0] * t.x + iv[1] * t.y;
    let vn = iv[0] * n.x + iv[1] * n.y;
    if iv[2] != 0.0 || vn.abs() > 1e-12 {
        return Err(NotReducible::Moving(fb.id.clone()));
    }
    let density = scene.materials[fb.material].density;
    // The geometry qualifies; the controls must be ones the reduced models represent too.
    super::represented(scene)?;
    Ok(SingleBlock {
        free: f,
        base: b,
        driven,
        origin,
        t,
        n,
        pivots: [0.0, len],
        centroid: local(moments.centroid),
        vertices: v.iter().map(|p| local(*p)).collect(),
        mass: density * moments.area,
        inertia: density * (moments.sxx + moments.syy),
        mu: joint.friction_angle.tan(),
        gravity: scene.gravity,
        initial_slip_rate: vt,
        slope: t.y.atan2(t.x),
    })
}
