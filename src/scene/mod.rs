//! Scene: parse and validate `ashlar.scene/1` (docs/format.md §1). First stage of the flow;
//! everything downstream receives a [`Scene`] that is known to be well formed.
//!
//! Conventions fixed here for the whole engine: SI units, y up, gravity along −y,
//! polygons stored counter-clockwise, rotations counter-clockwise positive (radians).
pub mod block_model;
pub mod generate;
pub mod import;
pub mod spec;
pub mod templates;
mod validate;

pub use spec::*;
pub use validate::validate;

use nalgebra::Vector2;

/// A validation or parse failure: `path` names the field (`blocks[2].vertices`), `message` says
/// what is wrong with it.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("scene: {path}: {message}")]
pub struct SceneError {
    pub path: String,
    pub message: String,
}

impl SceneError {
    pub fn new(path: impl Into<String>, message: impl Into<String>) -> Self {
        Self {
            path: path.into(),
            message: message.into(),
        }
    }
}

/// Parse and validate scene JSON text.
pub fn parse_scene(text: &str) -> Result<Scene, SceneError> {
    let de = &mut serde_json::Deserializer::from_str(text);
    let spec: SceneSpec = serde_path_to_error::deserialize(de).map_err(|e| {
        let path = e.path().to_string();
        let inner = e.into_inner();
        let path = if path == "." {
            "(document)".to_string()
        } else {
            path
        };
        SceneError::new(path, inner.to_string())
    })?;
    validate(&spec)
}

/// Parse and validate a scene from a JSON value (the service receives it embedded in a job).
pub fn scene_from_value(value: &serde_json::Value) -> Result<Scene, SceneError> {
    let spec: SceneSpec = serde_path_to_error::deserialize(value).map_err(|e| {
        let path = e.path().to_string();
        SceneError::new(path, e.into_inner().to_string())
    })?;
    validate(&spec)
}

/// Material constants, SI.
#[derive(Debug, Clone, PartialEq)]
pub struct Material {
    pub name: String,
    /// kg/m³.
    pub density: f64,
    /// Pa.
    pub young_modulus: f64,
    pub poisson_ratio: f64,
    pub plane: PlaneKind,
}

/// Mohr–Coulomb joint.
#[derive(Debug, Clone, PartialEq)]
pub struct Joint {
    pub name: String,
    /// radians.
    pub friction_angle: f64,
    /// Pa.
    pub cohesion: f64,
    /// Pa.
    pub tensile_strength: f64,
}

/// How a block moves.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum BlockKind {
    /// Never moves, no unknowns.
    Fixed,
    /// Follows the ground displacement exactly, no unknowns.
    Driven,
    /// Free, with unknowns according to its model.
    Free(BlockModel),
}

#[derive(Debug, Clone, PartialEq)]
pub struct Block {
    pub id: String,
    pub material: usize,
    pub kind: BlockKind,
    /// Counter-clockwise, m.
    pub vertices: Vec<Vector2<f64>>,
}

/// Penalty stiffness choice, N/m.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Penalty {
    Auto,
    Value(f64),
}

/// Resolved numerical controls (defaults applied). Each default is justified at
/// [`Control::default`].
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct Control {
    /// s; `None` means "the record's length plus 2 s".
    pub duration: Option<f64>,
    /// s; the maximum step when adaptive.
    pub time_step: f64,
    pub adaptive_time_step: bool,
    /// Shi's g2, fraction of the model's half size.
    pub max_displacement_ratio: f64,
    #[serde(serialize_with = "ser_penalty")]
    pub penalty_stiffness: Penalty,
    pub dynamic_factor: f64,
    /// 1/s.
    pub kinetic_damping_rate: f64,
    pub integrator: Integrator,
    pub contact_solver: ContactSolver,
    /// The model of free blocks that do not name their own (`"auto"`: chosen per block).
    pub block_model: BlockModelChoice,
    pub model: ModelChoice,
    /// s.
    pub output_interval: f64,
    pub max_steps: u64,
    /// The dual solver's stopping tolerance, as a fraction of the smallest free block's half
    /// size. `None`: the engine's default (`DualParams::tolerance`, 1e-9). Omitted from the
    /// reported controls when unset, so recorded outputs of scenes without it are unchanged.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub dual_tolerance: Option<f64>,
    /// Multiple of the dual tolerance up to which a stalled dual solve is accepted (≥ 1).
    /// `None`: the engine's default (`DualParams::stall_acceptance`, 1: none accepted).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub dual_stall_acceptance: Option<f64>,
    /// The floor of the cuts of a step whose contact loop does not converge, as a fraction of
    /// `time_step` (0: none). `None`: the engine's default (`SimParams::unconverged_floor_ratio`).
    /// Omitted from the reported controls when unset, so recorded outputs of scenes without it
    /// are unchanged.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub unconverged_floor: Option<f64>,
    /// Restitution of impacts (docs/format.md § controls). Reported always: it is a physical
    /// choice, not a solver knob.
    #[serde(serialize_with = "ser_restitution")]
    pub restitution: Restitution,
}

/// The restitution law of impacts (`control.restitution`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Restitution {
    /// Housner's law: an impact without bounce (Newton's law with e = 0 at every contact that
    /// closes, `assembly::restitution`); for a rocking rectangle without slip it is
    /// r = 1 − 3/2 sin²α (angular momentum about the new pivot conserved), the reduced rocking
    /// model's law.
    Housner,
    /// The contacts' own response (penalty springs or the dual solver's rigid contact), no
    /// impact law: the rebound then depends on Δt (docs/restitution.md). Kept for tests and studies of
    /// the contact model itself; the reduced models do not represent it.
    Contact,
    /// Newton's coefficient of normal restitution e ∈ [0, 1] at every contact that closes:
    /// the normal relative velocity after the impact is −e × before, momentum conserved
    /// (`assembly::restitution`), whatever Δt and contact solver.
    Coefficient(f64),
}

fn ser_restitution<S: serde::Serializer>(r: &Restitution, s: S) -> Result<S::Ok, S::Error> {
    match r {
        Restitution::Housner => s.serialize_str("housner"),
        Restitution::Contact => s.serialize_str("contact"),
        Restitution::Coefficient(e) => s.serialize_f64(*e),
    }
}

fn ser_penalty<S: serde::Serializer>(p: &Penalty, s: S) -> Result<S::Ok, S::Error> {
    match p {
        Penalty::Auto => s.serialize_str("auto"),
        Penalty::Value(v) => s.serialize_f64(*v),
    }
}

impl Default for Control {
    fn default() -> Self {
        Self {
            duration: None,
            // 1 ms resolves the 1–20 Hz content of earthquake records with ≥ 50 steps a cycle;
            // the adaptive control shortens it where contacts need more.
            time_step: 1.0e-3,
            adaptive_time_step: true,
            // Shi's recommended range is 1e-3…1e-2; 1e-3 keeps the per-step contact
            // linearisation accurate for rocking (see docs/accuracy-vs-speed.md).
            max_displacement_ratio: 1.0e-3,
            penalty_stiffness: Penalty::Auto,
            // Fully dynamic: earthquake response must not be damped artificially.
            dynamic_factor: 1.0,
            kinetic_damping_rate: 0.0,
            integrator: Integrator::Dda,
            contact_solver: ContactSolver::Penalty,
            // Chosen from the scene: rigid where strain cannot change the answer by more than
            // the rule's bound (1e-4 of the lever arms that decide toppling), deformable
            // elsewhere. The study (docs/accuracy-vs-speed.md) finds deformable stone within
            // 0.006 % of rigid at 17–23 % more time on its benchmarks and 23–31× per step on a
            // 410-stone wall (docs/contact-solve.md), so stone gains nothing from deformable blocks.
            block_model: BlockModelChoice::Auto,
            // The lightest model that represents the scene: the speed/accuracy study
            // (docs/accuracy-vs-speed.md) finds the reduced rocking/sliding models within
            // 0.063 % of the independent references on every single-block benchmark, never less
            // accurate than the full engine, at 6–100× less time; every other scene runs the
            // full engine as before. `"model": "dda"` forces the engine.
            model: ModelChoice::Auto,
            output_interval: 0.01,
            // 50 million steps is hours of CPU: far beyond any sensible run, well short of a hang.
            max_steps: 50_000_000,
            // The engine's own defaults (the scene layer sits above the solver and does not
            // repeat them).
            dual_tolerance: None,
            dual_stall_acceptance: None,
            unconverged_floor: None,
            // Housner's law (e = 0 in the full engine): the reduced rocking model's law, and in
            // the engine it makes impacts independent of Δt; measured against the contacts' own
            // response in docs/restitution.md ("The default").
            restitution: Restitution::Housner,
        }
    }
}

/// Excitation resolved to block indices.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Excitation {
    /// Inertial load −m·a_g on every free block; results relative to the ground.
    BaseAcceleration,
    /// Block index that follows the ground displacement.
    DrivenBlock(usize),
}

/// A validated scene: the engine's input.
#[derive(Debug, Clone)]
pub struct Scene {
    pub name: String,
    /// m/s², acts along −y.
    pub gravity: f64,
    pub materials: Vec<Material>,
    pub joints: Vec<Joint>,
    pub blocks: Vec<Block>,
    /// Joint index for a pair of block indices (symmetric); see [`Scene::joint_between`].
    pub default_joint: usize,
    pub pair_joints: std::collections::HashMap<(usize, usize), usize>,
    pub excitation: Excitation,
    /// Per block: (vx, vy, ω) initial velocity.
    pub initial_velocity: Vec<[f64; 3]>,
    pub control: Control,
    /// Per block: why its block model was chosen (`summary.json`'s `block_model_reason`);
    /// empty for fixed and driven blocks.
    pub block_model_reasons: Vec<String>,
    /// The spec as given (kept for provenance in recordings and job records).
    pub spec: SceneSpec,
}

impl Scene {
    /// Joint acting between blocks `a` and `b`.
    pub fn joint_between(&self, a: usize, b: usize) -> &Joint {
        let key = if a < b { (a, b) } else { (b, a) };
        let j = self
            .pair_joints
            .get(&key)
            .copied()
            .unwrap_or(self.default_joint);
        &self.joints[j]
    }

    pub fn block_index(&self, id: &str) -> Option<usize> {
        self.blocks.iter().position(|b| b.id == id)
    }

    /// Indices of blocks that carry unknowns.
    pub fn free_blocks(&self) -> impl Iterator<Item = usize> + '_ {
        self.blocks
            .iter()
            .enumerate()
            .filter(|(_, b)| matches!(b.kind, BlockKind::Free(_)))
            .map(|(i, _)| i)
    }
}
