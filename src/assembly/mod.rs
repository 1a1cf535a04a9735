//! Assembly: the DDA equilibrium system for one time step. Fourth stage of the flow: takes the
//! geometry, block states, loads (gravity, ground motion) and contact springs and builds the
//! block-sparse symmetric system `K̂ D = F` solved by `solve`.
//!
//! Call order: [`BlockSystem::assemble_blocks`] once per step attempt (inertia, elastic,
//! loads), then per open–close iteration [`BlockSystem::reset_to_blocks`] and
//! [`contact_springs::add_contacts`].
//!
//! Units: D in m and rad (strains dimensionless), forces in N (per metre of thickness), moments
//! in N·m. Newmark: `D = Δ·v0 + Δ²[(½−β)·a0 + β·a1]`, `v1 = v0 + Δ[(1−γ)·a0 + γ·a1]`.
pub mod contact_springs;
pub mod restitution;

use crate::geometry::{BlockGeometry, Mat6, Vec6};
use crate::scene::{BlockKind, BlockModel, Integrator, Material, PlaneKind, Scene};
use nalgebra::{Matrix3, Vector3};

/// Newmark constants of an integrator.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Newmark {
    pub beta: f64,
    pub gamma: f64,
}

impl Newmark {
    pub fn of(integrator: Integrator) -> Self {
        match integrator {
            Integrator::Dda => Newmark {
                beta: 0.5,
                gamma: 1.0,
            },
            Integrator::Trapezoidal => Newmark {
                beta: 0.25,
                gamma: 0.5,
            },
        }
    }
}

/// Where each block's unknowns sit in the global vector.
#[derive(Debug, Clone, Default)]
pub struct Dofs {
    /// Per block: index among free blocks, if free.
    pub free_index: Vec<Option<usize>>,
    /// Per free block: scene block index.
    pub block_of: Vec<usize>,
    /// Per free block: 3 (rigid) or 6 (deformable).
    pub ndof: Vec<usize>,
    /// Per free block: first global dof.
    pub offset: Vec<usize>,
    /// Total unknowns.
    pub n: usize,
    /// Per free block: the mean of its initial vertices (x, y), m. Only for the sparse
    /// factorization's coordinate ordering (`SparseOrdering::BlockCoordinates`), which needs
    /// where blocks are roughly, not where they are now; empty when not numbered from a scene.
    pub position: Vec<[f64; 2]>,
}

impl Dofs {
    /// Number the unknowns of `scene`: its free blocks in scene order, 3 for a rigid block
    /// (u0, v0, r0), 6 for a deformable one (+ εx, εy, γxy), consecutive.
    pub fn number(scene: &Scene) -> Self {
        let mut dofs = Dofs {
            free_index: vec![None; scene.blocks.len()],
            ..Default::default()
        };
        for (b, blk) in scene.blocks.iter().enumerate() {
            if let BlockKind::Free(model) = blk.kind {
                let nd = if model == BlockModel::Rigid { 3 } else { 6 };
                dofs.free_index[b] = Some(dofs.block_of.len());
                dofs.block_of.push(b);
                dofs.ndof.push(nd);
                dofs.offset.push(dofs.n);
                dofs.n += nd;
                let k = blk.vertices.len().max(1) as f64;
                let (x, y) = blk
                    .vertices
                    .iter()
                    .fold((0.0, 0.0), |(x, y), v| (x + v.x, y + v.y));
                dofs.position.push([x / k, y / k]);
            }
        }
        dofs
    }
}

/// Dynamic state of a free block.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BlockState {
    /// Velocity of the six unknowns (m/s, rad/s, 1/s).
    pub vel: Vec6,
    /// Acceleration of the six unknowns (needed by the trapezoidal rule).
    pub acc: Vec6,
    /// Constant stress in the block, Pa: [σx, σy, τxy], tension positive.
    pub stress: Vector3<f64>,
}

impl Default for BlockState {
    fn default() -> Self {
        Self {
            vel: Vec6::zeros(),
            acc: Vec6::zeros(),
            stress: Vector3::zeros(),
        }
    }
}

/// Elasticity matrix (Pa) relating [εx, εy, γxy] to [σx, σy, τxy].
pub fn elasticity(m: &Material) -> Matrix3<f64> {
    let (e, nu) = (m.young_modulus, m.poisson_ratio);
    match m.plane {
        PlaneKind::Stress => {
            let k = e / (1.0 - nu * nu);
            Matrix3::new(
                k,
                k * nu,
                0.0,
                k * nu,
                k,
                0.0,
                0.0,
                0.0,
                k * (1.0 - nu) / 2.0,
            )
        }
        PlaneKind::Strain => {
            let k = e / ((1.0 + nu) * (1.0 - 2.0 * nu));
            Matrix3::new(
                k * (1.0 - nu),
                k * nu,
                0.0,
                k * nu,
                k * (1.0 - nu),
                0.0,
                0.0,
                0.0,
                k * (1.0 - 2.0 * nu) / 2.0,
            )
        }
    }
}

/// Loads that act on every free block in this step (evaluated at the step end).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BodyLoads {
    /// m/s², along −y.
    pub gravity: f64,
    /// Ground acceleration for the inertial load −m·a_g (zero for driven-block excitation), m/s².
    pub ground_acceleration: [f64; 2],
}

/// The block-sparse symmetric system `K̂ D = F`.
#[derive(Debug, Default)]
pub struct BlockSystem {
    /// Diagonal 6×6 block per free block (only the leading ndof×ndof part is used).
    pub diag: Vec<Mat6>,
    pub rhs: Vec<Vec6>,
    /// Off-diagonal blocks K_ab for free-block pairs a < b (row block a, column block b).
    pub pairs: Vec<(usize, usize)>,
    pub off: Vec<Mat6>,
    /// Inertia + elastic + loads, before contacts.
    base_diag: Vec<Mat6>,
    base_rhs: Vec<Vec6>,
    /// Mass matrices of this step (for energy and velocity updates).
    pub mass: Vec<Mat6>,
    /// Per free block, its weight m·g, N (≥ 0; the open–close loop's force scale of a stone
    /// with no contact force yet, `OpenCloseParams::weight_scale`).
    pub weight: Vec<f64>,
    /// Per contact (in `ContactSet` order): where its coupling block goes, found once per step
    /// by [`BlockSystem::bind_contacts`] rather than once per spring and iteration.
    /// `None` for a contact with a fixed or driven block (no coupling block).
    pub contact_slots: Vec<Option<CouplingSlot>>,
}

/// Where the coupling block of a contact between free blocks i (vertex) and j (edge) is
/// stored: `off[slot]` holds K_ij when `vertex_is_row` (i < j), else its transpose K_ji.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct CouplingSlot {
    pub slot: usize,
    pub vertex_is_row: bool,
}

impl BlockSystem {
    /// Inertia, elastic stiffness and body loads of every free block for step length `dt`.
    pub fn assemble_blocks(
        &mut self,
        dofs: &Dofs,
        geoms: &[BlockGeometry],
        densities: &[f64],
        elastic: &[Matrix3<f64>],
        states: &[BlockState],
        loads: &BodyLoads,
        newmark: Newmark,
        dt: f64,
    ) {
        let nf = dofs.block_of.len();
        self.base_diag.resize(nf, Mat6::zeros());
        self.base_rhs.resize(nf, Vec6::zeros());
        self.mass.resize(nf, Mat6::zeros());
        self.weight.resize(nf, 0.0);
        let a_coef = 1.0 / (newmark.beta * dt * dt);
        for f in 0..nf {
            let b = dofs.block_of[f];
            let g = &geoms[b];
            let mass = g.mass_matrix(densities[f]);
            let st = &states[f];
            let mut k = mass * a_coef;
            let history = st.vel * dt + st.acc * (dt * dt * (0.5 - newmark.beta));
            let mut rhs = mass * (history * a_coef);
            let m = densities[f] * g.moments.area;
            rhs[0] += -m * loads.ground_acceleration[0];
            rhs[1] += -m * (loads.gravity + loads.ground_acceleration[1]);
            if dofs.ndof[f] == 6 {
                let area = g.moments.area;
                let e = elastic[f] * area;
                for r in 0..3 {
                    for c in 0..3 {
                        k[(3 + r, 3 + c)] += e[(r, c)];
                    }
                    // Initial stress does work −A·σ·ε on the strain unknowns.
                    rhs[3 + r] -= area * st.stress[r];
                }
            }
            self.mass[f] = mass;
            self.weight[f] = (m * loads.gravity).abs();
            self.base_diag[f] = k;
            self.base_rhs[f] = rhs;
        }
    }

    /// Remove the loads of free block `f` (a retired block: with no velocity it then stays put).
    pub fn clear_block_load(&mut self, f: usize) {
        self.base_rhs[f] = Vec6::zeros();
    }

    /// Start an open–close iteration from the block terms, with an empty off-diagonal part.
    pub fn reset_to_blocks(&mut self) {
        self.diag.clone_from(&self.base_diag);
        self.rhs.clone_from(&self.base_rhs);
        // One fill of the whole slice (the same zeros): a loop over the blocks compiled to
        // one memset call per 6×6 block in some builds (docs/contact-solve.md §15).
        self.off.fill(Mat6::zeros());
    }

    /// Reset the right-hand side only to the block terms, keeping the matrix (for
    /// [`contact_springs::add_contact_loads`], when the contacts' springs did not change).
    pub fn reset_rhs_to_blocks(&mut self) {
        self.rhs.clone_from(&self.base_rhs);
    }

    /// Declare the off-diagonal pattern (free-block pairs a < b) for this step.
    pub fn set_pattern(&mut self, mut pairs: Vec<(usize, usize)>) {
        pairs.sort_unstable();
        pairs.dedup();
        if pairs != self.pairs {
            self.off = vec![Mat6::zeros(); pairs.len()];
            self.pairs = pairs;
        }
    }

    /// Find the coupling slot of every contact between two distinct free blocks (call after
    /// [`BlockSystem::set_pattern`], whose pattern must contain every such pair).
    pub fn bind_contacts(&mut self, dofs: &Dofs, contacts: &[crate::contact::Contact]) {
        let mut slots = std::mem::take(&mut self.contact_slots);
        slots.clear();
        for c in contacts {
            let s = match (
                dofs.free_index[c.vertex_block],
                dofs.free_index[c.edge_block],
            ) {
                (Some(i), Some(j)) if i != j => Some(CouplingSlot {
                    slot: self.slot(i.min(j), i.max(j)),
                    vertex_is_row: i < j,
                }),
                _ => None,
            };
            slots.push(s);
        }
        self.contact_slots = slots;
    }

    /// Slot of the off-diagonal block of free blocks (a, b), a < b, in `pairs`/`off`.
    /// `pairs` is sorted, so a binary search finds it (cheaper than hashing at these sizes).
    ///
    /// # Panics
    /// If the pair was not declared by [`BlockSystem::set_pattern`]: a bug, not bad input.
    #[inline]
    fn slot(&self, a: usize, b: usize) -> usize {
        match self.pairs.binary_search(&(a, b)) {
            Ok(k) => k,
            Err(_) => panic!("block pair ({a}, {b}) missing from the declared pattern"),
        }
    }
}
