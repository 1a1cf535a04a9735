//! Simulation › state: what the engine knows about the scene at time t (block geometry, block
//! states, contacts and their joint laws, retired blocks), built from the scene with the
//! unknowns numbered by `assembly::Dofs::number`. The stepper (`stepper.rs`) advances it.
use crate::assembly::contact_springs::{JointLaw, Prescribed};
use crate::assembly::{elasticity, BlockState, Dofs};
use crate::contact::{ContactSet, Mobility};
use crate::geometry::{BlockGeometry, Vec6};
use crate::motion::GroundMotion;
use crate::scene::{BlockKind, Scene};
use nalgebra::{Matrix3, Vector3};

/// 4·area / perimeter of a polygon, m: the side of a square, twice the thickness of a long slab
/// or needle, whatever its orientation.
fn thickness(v: &[nalgebra::Vector2<f64>]) -> f64 {
    let n = v.len();
    let (mut area2, mut perimeter) = (0.0, 0.0);
    for k in 0..n {
        let (a, b) = (v[k], v[(k + 1) % n]);
        area2 += a.perp(&b);
        perimeter += (b - a).norm();
    }
    2.0 * area2.abs() / perimeter
}
/// The engine state of one scene under one ground motion at the simulated time.
pub(super) struct SimState {
    pub(super) scene: Scene,
    pub(super) motion: GroundMotion,
    pub(super) geoms: Vec<BlockGeometry>,
    pub(super) mobility: Vec<Mobility>,
    pub(super) dofs: Dofs,
    /// Per free block.
    pub(super) states: Vec<BlockState>,
    /// Per free block, kg/m³.
    pub(super) densities: Vec<f64>,
    /// Per free block: the plane elasticity matrix, Pa.
    pub(super) elastic: Vec<Matrix3<f64>>,
    pub(super) contacts: ContactSet,
    /// Per contact, in `contacts` order.
    pub(super) laws: Vec<JointLaw>,
    /// Per block: the driven block's displacement over the step, m.
    pub(super) prescribed: Vec<Prescribed>,
    /// The block states at the step start (restored on a time-step cut).
    pub(super) start_states: Vec<BlockState>,
    /// Simulated time, s.
    pub(super) time: f64,
    /// Half the diagonal of the whole model's bounding box at the start, m.
    pub(super) model_half_size: f64,
    /// Per block: 4·area / perimeter at the start (the side of a square, twice the thickness
    /// of a slab), m; the length penetrations are measured against.
    pub(super) thickness: Vec<f64>,
    /// Per block: retired (left the scene, frozen where it was; see [`SimState::retire`]).
    pub(super) retired: Vec<bool>,
}

impl SimState {
    /// Move free block `f` by the rigid increment `d` (u0 m, v0 m, r0 rad) between detection
    /// and the solve (`ImpactParams::hand_over_weight`): its geometry, and the step-start gaps
    /// and shear displacements of its contacts to first order in `d` (|d| ≈ 5e-8 m, r0 ≈ 4e-7 rad:
    /// the neglected terms are ≈ 1e-13 m).
    pub(super) fn move_rigidly(&mut self, f: usize, d: Vector3<f64>) {
        let b = self.dofs.block_of[f];
        let d6 = Vec6::new(d[0], d[1], d[2], 0.0, 0.0, 0.0);
        crate::integrate::move_block(&mut self.geoms[b], &d6);
        for c in &mut self.contacts.contacts {
            if let Some(rows) = c.rows_on(b) {
                c.g0 += rows.normal.dot(&d6);
                c.s0 += rows.shear.dot(&d6);
            }
        }
    }

    /// The scene at rest at t = 0 (free blocks at their initial velocity).
    pub(super) fn new(scene: &Scene, motion: &GroundMotion) -> Self {
        let geoms: Vec<BlockGeometry> = scene
            .blocks
            .iter()
            .map(|b| BlockGeometry::new(b.vertices.clone()))
            .collect();
        let mobility: Vec<Mobility> = scene
            .blocks
            .iter()
            .map(|b| match b.kind {
                BlockKind::Fixed => Mobility::Fixed,
                BlockKind::Driven => Mobility::Driven,
                BlockKind::Free(_) => Mobility::Free,
            })
            .collect();
        let dofs = Dofs::number(scene);
        let (mut densities, mut elastic, mut states) = (Vec::new(), Vec::new(), Vec::new());
        for &b in &dofs.block_of {
            let blk = &scene.blocks[b];
            let mat = &scene.materials[blk.material];
            densities.push(mat.density);
            elastic.push(elasticity(mat));
            let v = scene.initial_velocity[b];
            let mut st = BlockState::default();
            st.vel[0] = v[0];
            st.vel[1] = v[1];
            st.vel[2] = v[2];
            states.push(st);
        }
        let mut lo = geoms[0].vertices[0];
        let mut hi = lo;
        for g in &geoms {
            let (a, b) = g.bounds();
            lo = lo.inf(&a);
            hi = hi.sup(&b);
        }
        let model_half_size = 0.5 * (hi - lo).norm();
        let thickness = geoms.iter().map(|g| thickness(&g.vertices)).collect();
        Self {
            scene: scene.clone(),
            motion: motion.clone(),
            geoms,
            mobility,
            dofs,
            states,
            densities,
            elastic,
            contacts: ContactSet::default(),
            laws: Vec::new(),
            prescribed: vec![[0.0; 2]; scene.blocks.len()],
            start_states: Vec::new(),
            time: 0.0,
            model_half_size,
            thickness,
            retired: vec![false; scene.blocks.len()],
        }
    }

    /// Smallest free block's half size, m (the length scale of the solvers' tolerances).
    pub(super) fn smallest_free_block(&self) -> f64 {
        self.dofs
            .block_of
            .iter()
            .map(|&b| self.geoms[b].half_size)
            .fold(f64::INFINITY, f64::min)
    }

    pub(super) fn elastic_inverse(&self, f: usize) -> Option<Matrix3<f64>> {
        self.elastic[f].try_inverse()
    }
    /// Velocity of a block's centroid and its angular velocity (m/s, rad/s); driven blocks move
    /// with the ground, fixed blocks are still.
    pub fn block_velocity(&self, b: usize) -> [f64; 3] {
        match self.dofs.free_index[b] {
            Some(f) => [
                self.states[f].vel[0],
                self.states[f].vel[1],
                self.states[f].vel[2],
            ],
            None if self.mobility[b] == Mobility::Driven => {
                let v = self.motion.state(self.time)[1];
                [v[0], v[1], 0.0]
            }
            None => [0.0; 3],
        }
    }

    /// Retire free block `b`: it left the scene (fell far below it), so it is frozen where it
    /// is — no velocity, no load, no contacts — and costs the step control nothing from now
    /// on. Its unknowns stay in the system (solved to zero) so the numbering does not change.
    pub fn retire(&mut self, b: usize) {
        let Some(f) = self.dofs.free_index[b] else {
            return;
        };
        self.retired[b] = true;
        let st = &mut self.states[f];
        st.vel = Vec6::zeros();
        st.acc = Vec6::zeros();
        st.stress = Vector3::zeros();
        // Its contacts are dropped by the next detection, which must not be skipped.
        self.contacts.force_detection();
    }

    /// The first block whose position, rotation or velocity is not finite (`step` fails with
    /// [`super::SimError::NonFinite`] naming it).
    pub fn first_non_finite_block(&self) -> Option<usize> {
        for (b, g) in self.geoms.iter().enumerate() {
            if !g.centroid.x.is_finite() || !g.centroid.y.is_finite() || !g.rotation.is_finite() {
                return Some(b);
            }
        }
        for (f, st) in self.states.iter().enumerate() {
            if st.vel.iter().any(|v| !v.is_finite()) {
                return Some(self.dofs.block_of[f]);
            }
        }
        None
    }
}
