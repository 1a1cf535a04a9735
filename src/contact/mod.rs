//! Contact: which vertices touch which edges, and in what state. Third stage of the flow:
//! reads the current [`BlockGeometry`] of every block, produces [`Contact`]s that `assembly`
//! turns into springs and that `solve::open_close` updates.
//!
//! Call order each step: [`ContactSet::detect`] (broad + narrow phase, carrying states over
//! from the previous step), then [`ContactSet::linearize`] (per-step contact geometry).
//!
//! Conventions: a contact joins vertex `P` of the *vertex block* `i` to edge `AB` of the
//! *edge block* `j`. `n` is the edge's outward unit normal (pointing out of block `j`), `t` the
//! unit edge direction A→B (counter-clockwise). The gap `g = n·(P − A)` is positive when open,
//! negative when penetrating (penetration depth −g). Normal force `N` is compressive-positive.
mod broad_phase;
mod vertex_edge;

pub use broad_phase::BroadPhase;
pub use vertex_edge::{candidate, Candidate};

use crate::geometry::{displacement_matrix, BlockGeometry, Vec6};
use nalgebra::{Vector2, Vector3};
use rustc_hash::FxHashMap;

/// State of a contact spring pair.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum ContactState {
    /// No springs.
    Open,
    /// Normal and shear springs (stick).
    Locked,
    /// Normal spring plus Coulomb friction. `dir` = ±1 is the sign of the vertex's slip relative
    /// to the edge along `t`; friction on the vertex block acts along −dir·t.
    Sliding { dir: f64 },
}

impl ContactState {
    pub fn is_closed(self) -> bool {
        !matches!(self, ContactState::Open)
    }
}

/// Whether a block carries unknowns, follows the ground, or never moves.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Mobility {
    Fixed,
    Driven,
    Free,
}

/// Tuning knobs of contact detection.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ContactParams {
    /// Search distance as a multiple of the largest displacement allowed in one step: Shi's 2.5
    /// keeps every contact that can close within the step in the candidate list.
    pub search_factor: f64,
    /// Angle tolerance (rad) of the entrance criterion: edges within this of parallel still
    /// count as "not entering" so flat-on-flat contacts are found despite round-off.
    pub angle_tolerance: f64,
    /// Detection is skipped (the contact list kept, only re-linearized) while no vertex has
    /// moved more than this fraction of min(search distance, angle_tolerance × shortest edge)
    /// since the last full detection. Skipping is then the same as a detection whose distance
    /// thresholds moved by at most 0.2 % of the search distance and whose entrance tolerance
    /// moved by 0.2 % of itself: far below what either heuristic means physically, while a
    /// structure at rest (or creeping) pays for detection once instead of every step.
    /// 0 detects every step.
    pub reuse_ratio: f64,
}

impl Default for ContactParams {
    fn default() -> Self {
        Self {
            search_factor: 2.5,
            angle_tolerance: 1.0e-3,
            reuse_ratio: 1.0e-3,
        }
    }
}

/// One vertex–edge contact with everything needed to linearize it in the current step.
#[derive(Debug, Clone)]
pub struct Contact {
    pub vertex_block: usize,
    pub vertex: usize,
    pub edge_block: usize,
    /// Edge k runs from vertex k to vertex k+1 of the edge block.
    pub edge: usize,
    pub state: ContactState,
    /// Shear-spring reference point on the edge, as a fraction of its length from A.
    pub ref_xi: f64,
    /// Joint bond intact (cohesion and tensile strength act until it breaks).
    pub bonded: bool,
    /// Tributary contact length, m (for cohesion and tensile strength per unit thickness).
    pub length: f64,
    // Per-step linearization (m, dimensionless):
    pub n: Vector2<f64>,
    pub t: Vector2<f64>,
    /// Gap at the step start, m.
    pub g0: f64,
    /// Shear displacement of the vertex from the reference point at the step start, m.
    pub s0: f64,
    /// Position of the vertex's projection on the edge at the step start (fraction).
    pub xi: f64,
    /// Normal gap gradients: g = g0 + e_i·D_i − e_j·D_j.
    pub e_i: Vec6,
    pub e_j: Vec6,
    /// Shear gradients: s = s0 + f_i·D_i − f_j·D_j.
    pub f_i: Vec6,
    pub f_j: Vec6,
    /// Normal force from the last solve, N (compression positive).
    pub normal_force: f64,
    /// Normal force used for the Coulomb friction of a sliding contact in the current solve, N.
    pub friction_normal: f64,
    /// Shear force on the vertex block along t, N.
    pub shear_force: f64,
    /// Gap after the last solve, m.
    pub gap: f64,
    /// Slip along t during the last solve, m.
    pub slip: f64,
    /// For sliding contacts: elastic shear displacement kept in the shear spring (m), so that
    /// re-sticking starts from the Coulomb force rather than from zero.
    pub slide_offset: f64,
    /// Open at the start of the last accepted step and closed at its end, or found already
    /// penetrating by a detection after the first step: the impact law
    /// (`assembly::restitution`) still treats it as at its impact while it approaches; a
    /// contact closed for longer (a block settling on its springs) is the contact's own.
    pub closed_within_last_step: bool,
    /// The last friction fixed-point update within the current open–close loop: the normal
    /// force the friction used, and the one the solve then gave (N); for the secant step
    /// (`OpenCloseParams::secant_friction`).
    pub friction_secant: Option<(f64, f64)>,
    /// State changes within the current open–close loop (cycle detection).
    pub flips: u32,
    /// Normal force at the start of the last step (the converged force of the step before),
    /// N, if the contact was closed then; read and set once a step by the friction normal's
    /// prediction (`OpenCloseParams::friction_predict`), `None` while it is off.
    pub prior_normal_force: Option<f64>,
    /// The friction normal force predicted for this step from `prior_normal_force` and the
    /// last step's (N), if the contact is sliding and was closed at both step starts; the loop
    /// starts from it where `OpenCloseParams::friction_predict` applies.
    pub predicted_friction_normal: Option<f64>,
    /// Slip along t of the last accepted step (the converged `slip`, m, vertex relative to the
    /// edge), if the contact was closed at its end; and the same of the step before. Set once
    /// a step by `finish_step`, read by the stick–slip prediction
    /// (`OpenCloseParams::stick_predict`, `slip_predict`).
    pub last_slip: Option<f64>,
    pub prior_slip: Option<f64>,
    /// Change of the normal gap over the last accepted step (the converged `gap` − `g0`, m,
    /// positive opening), and the same of the step before. Set once a step by `finish_step`,
    /// read by the gap prediction (`OpenCloseParams::gap_predict`).
    pub last_gap_change: Option<f64>,
    pub prior_gap_change: Option<f64>,
    /// The state the stick–slip prediction starts this step's loop from (`Locked` for a
    /// sliding contact predicted to re-stick, `Sliding` for a locked one predicted to slip),
    /// set at the step start and taken by the loop's first attempt.
    pub predicted_state: Option<ContactState>,
    /// Normal force carried into the step, N: its share of the stored acceleration a₀ that the
    /// trapezoidal rule averages with the step-end forces.
    pub start_normal_force: f64,
    /// For a contact that opens during the step: the fraction of `start_normal_force` that the
    /// step's force average keeps (1 = all; see `contact_springs::release_load`).
    pub release_factor: f64,
}

/// A contact's rows on one of its blocks: the derivatives of its normal gap g and of its shear
/// displacement s with respect to that block's unknowns D = (u0 m, v0 m, r0 rad, εx, εy, γxy),
/// signed so that g = g0 + Σ normal·D and s = s0 + Σ shear·D over the contact's two blocks (m
/// per m for u0 and v0, m per rad for r0, m for the strains).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BlockRows {
    pub normal: Vec6,
    pub shear: Vec6,
}

impl BlockRows {
    /// The normal and shear rows on the block's rigid-body unknowns (u0, v0, r0): what an
    /// impulse or a rigid move of the block acts on.
    pub fn rigid(&self) -> (Vector3<f64>, Vector3<f64>) {
        let three = |v: &Vec6| Vector3::new(v[0], v[1], v[2]);
        (three(&self.normal), three(&self.shear))
    }
}

impl Contact {
    /// The rows on the vertex block (`e_i`, `f_i`) and on the edge block (−`e_j`, −`f_j`), in
    /// that order. Why one place: the sign of the edge block's side is easy to get wrong, and
    /// the impact law, its weight hand-over and the rigid move of a block all need it.
    pub fn rows(&self) -> [BlockRows; 2] {
        [self.vertex_rows(), self.edge_rows()]
    }

    /// The rows on block `b`: the vertex block's or the edge block's (a contact joins two
    /// different blocks); `None` when `b` is neither.
    pub fn rows_on(&self, b: usize) -> Option<BlockRows> {
        if self.vertex_block == b {
            Some(self.vertex_rows())
        } else if self.edge_block == b {
            Some(self.edge_rows())
        } else {
            None
        }
    }

    fn vertex_rows(&self) -> BlockRows {
        BlockRows {
            normal: self.e_i,
            shear: self.f_i,
        }
    }

    fn edge_rows(&self) -> BlockRows {
        BlockRows {
            normal: -self.e_j,
            shear: -self.f_j,
        }
    }
}

/// All contacts of the scene, carried from step to step.
#[derive(Debug, Default)]
pub struct ContactSet {
    pub contacts: Vec<Contact>,
    broad: BroadPhase,
    /// Scratch: previous contacts by key, reused each step.
    /// Fx hashing: the keys are small integers from our own detection, not adversarial input.
    previous: FxHashMap<(u32, u32, u32, u32), usize>,
    scratch: Vec<Contact>,
    candidates: Vec<Candidate>,
    /// Every block's vertices at the last full detection, flattened, and how far they may move
    /// before the next one is due (see [`ContactParams::reuse_ratio`]).
    snapshot: Vec<Vector2<f64>>,
    snapshot_search: f64,
    reuse_limit: f64,
    /// Full detections done (diagnostic).
    pub detections: u64,
}

impl ContactSet {
    /// Find contacts for the current geometry. `search` is the search distance (m); contacts
    /// found again keep their state, reference point and bond. Returns false when the list was
    /// kept because nothing moved enough to change it (see [`ContactParams::reuse_ratio`]).
    pub fn detect(
        &mut self,
        geoms: &[BlockGeometry],
        mobility: &[Mobility],
        search: f64,
        params: &ContactParams,
        first_step: bool,
        bond: impl Fn(usize, usize) -> bool,
    ) -> bool {
        if !first_step && self.unchanged_since_snapshot(geoms, search) {
            return false;
        }
        self.take_snapshot(geoms, search, params);
        self.detections += 1;
        self.previous.clear();
        for (k, c) in self.contacts.iter().enumerate() {
            self.previous
                .insert(key(c.vertex_block, c.vertex, c.edge_block, c.edge), k);
        }
        self.broad.update(geoms, mobility, search);
        self.scratch.clear();
        for &(a, b) in self.broad.pairs() {
            self.candidates.clear();
            vertex_edge::pair_candidates(geoms, a, b, search, params, &mut self.candidates);
            vertex_edge::pair_candidates(geoms, b, a, search, params, &mut self.candidates);
            vertex_edge::drop_mirrored_vertex_pairs(geoms, &mut self.candidates, search);
            for cand in &self.candidates {
                let k = key(cand.vertex_block, cand.vertex, cand.edge_block, cand.edge);
                let c = match self.previous.get(&k) {
                    Some(&p) => {
                        let old = &self.contacts[p];
                        Contact {
                            ref_xi: old.ref_xi,
                            state: old.state,
                            bonded: old.bonded,
                            normal_force: old.normal_force,
                            friction_normal: old.friction_normal,
                            prior_normal_force: old.prior_normal_force,
                            predicted_friction_normal: old.predicted_friction_normal,
                            last_slip: old.last_slip,
                            prior_slip: old.prior_slip,
                            last_gap_change: old.last_gap_change,
                            prior_gap_change: old.prior_gap_change,
                            predicted_state: old.predicted_state,
                            slide_offset: old.slide_offset,
                            closed_within_last_step: old.closed_within_last_step,
                            ..new_contact(cand)
                        }
                    }
                    None => {
                        let mut c = new_contact(cand);
                        // A contact touching at the start is closed from the outset so the
                        // scene starts in equilibrium rather than falling into its springs.
                        if cand.gap <= 0.0 {
                            c.state = ContactState::Locked;
                            c.closed_within_last_step = !first_step;
                        }
                        c.bonded = first_step
                            && cand.gap <= search * 1e-3
                            && bond(cand.vertex_block, cand.edge_block);
                        c
                    }
                };
                self.scratch.push(c);
            }
        }
        std::mem::swap(&mut self.contacts, &mut self.scratch);
        true
    }

    /// Make the next [`ContactSet::detect`] a full detection (the set of blocks that may touch
    /// changed: a block was retired).
    pub fn force_detection(&mut self) {
        self.snapshot.clear();
    }

    /// No vertex moved more than the reuse limit since the last full detection at this search
    /// distance.
    fn unchanged_since_snapshot(&self, geoms: &[BlockGeometry], search: f64) -> bool {
        if self.reuse_limit <= 0.0 || search != self.snapshot_search {
            return false;
        }
        let limit2 = self.reuse_limit * self.reuse_limit;
        let mut old = self.snapshot.iter();
        for g in geoms {
            for v in &g.vertices {
                match old.next() {
                    Some(o) if (v - o).norm_squared() <= limit2 => {}
                    _ => return false,
                }
            }
        }
        old.next().is_none()
    }

    fn take_snapshot(&mut self, geoms: &[BlockGeometry], search: f64, params: &ContactParams) {
        self.snapshot.clear();
        let mut shortest = f64::INFINITY;
        for g in geoms {
            self.snapshot.extend_from_slice(&g.vertices);
            for k in 0..g.vertices.len() {
                let (a, b) = edge_points(g, k);
                shortest = shortest.min((b - a).norm());
            }
        }
        self.snapshot_search = search;
        self.reuse_limit = params.reuse_ratio * search.min(params.angle_tolerance * shortest);
    }

    /// Compute the per-step linearization of every contact from the geometry at the step start.
    pub fn linearize(&mut self, geoms: &[BlockGeometry]) {
        for c in &mut self.contacts {
            linearize_contact(c, geoms, ShearReference::FromState);
        }
    }
}

fn key(a: usize, b: usize, c: usize, d: usize) -> (u32, u32, u32, u32) {
    (a as u32, b as u32, c as u32, d as u32)
}

fn new_contact(cand: &Candidate) -> Contact {
    Contact {
        vertex_block: cand.vertex_block,
        vertex: cand.vertex,
        edge_block: cand.edge_block,
        edge: cand.edge,
        state: ContactState::Open,
        ref_xi: cand.xi,
        bonded: false,
        length: cand.length,
        n: Vector2::zeros(),
        t: Vector2::zeros(),
        g0: cand.gap,
        s0: 0.0,
        xi: cand.xi,
        e_i: Vec6::zeros(),
        e_j: Vec6::zeros(),
        f_i: Vec6::zeros(),
        f_j: Vec6::zeros(),
        normal_force: 0.0,
        friction_normal: 0.0,
        shear_force: 0.0,
        gap: cand.gap,
        slip: 0.0,
        slide_offset: 0.0,
        closed_within_last_step: false,
        friction_secant: None,
        flips: 0,
        prior_normal_force: None,
        predicted_friction_normal: None,
        last_slip: None,
        prior_slip: None,
        last_gap_change: None,
        prior_gap_change: None,
        predicted_state: None,
        start_normal_force: 0.0,
        release_factor: 1.0,
    }
}

/// Edge endpoints (A, B) of edge `k` of a block.
#[inline]
pub fn edge_points(g: &BlockGeometry, k: usize) -> (Vector2<f64>, Vector2<f64>) {
    let n = g.vertices.len();
    (g.vertices[k], g.vertices[(k + 1) % n])
}

/// Where the shear spring of a contact being linearized is anchored.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ShearReference {
    /// By its state: a material point of the edge while locked; follows the vertex while open;
    /// trails it by the elastic shear displacement while sliding (a detected contact).
    FromState,
    /// At the vertex's projection, with no shear displacement (a pair the dual solver has just
    /// switched onto another edge).
    AtVertex,
}

/// The step-start frame of one contact from the geometry: unit tangent t (A → B) and normal n,
/// the gap g₀, the projection ξ, the shear reference and s₀, and the gap and shear gradients.
pub fn linearize_contact(c: &mut Contact, geoms: &[BlockGeometry], reference: ShearReference) {
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
    match (reference, c.state) {
        (ShearReference::AtVertex, _) | (_, ContactState::Open) => c.ref_xi = c.xi,
        (_, ContactState::Sliding { .. }) => c.ref_xi = c.xi - c.slide_offset / len,
        (_, ContactState::Locked) => {}
    }
    let q = a + ab * c.xi;
    let qr = a + ab * c.ref_xi;
    c.s0 = match reference {
        ShearReference::FromState => t.dot(&(p - qr)),
        ShearReference::AtVertex => 0.0,
    };
    let ti = displacement_matrix(p, gi.centroid);
    let tq = displacement_matrix(q, gj.centroid);
    let tqr = displacement_matrix(qr, gj.centroid);
    c.e_i = ti.transpose() * n;
    c.e_j = tq.transpose() * n;
    c.f_i = ti.transpose() * t;
    c.f_j = tqr.transpose() * t;
}
