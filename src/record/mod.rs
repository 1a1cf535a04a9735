//! Recording: histories (CSV) and trajectories (MCAP) of a run. Sits after `simulation` in the
//! flow; consumes plain [`Frame`]s that `analysis` builds from the simulation state, so the
//! writers know nothing about the solver.

/// How a block is moving in a frame (colours the scene in viewers).
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum BlockMotionState {
    AtRest,
    Sliding,
    Rocking,
    Toppled,
}

/// What kind of block a frame entry is.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum FrameBlockKind {
    Fixed,
    Driven,
    Free,
}

/// One block in one frame.
#[derive(Debug, Clone, PartialEq)]
pub struct BlockFrame {
    /// Centroid displacement from the initial position, m (as in `histories.csv`).
    pub x: f64,
    pub y: f64,
    /// Rotation since the start, rad, counter-clockwise positive.
    pub rotation: f64,
    /// Centroid velocity, m/s.
    pub vx: f64,
    pub vy: f64,
    /// rad/s, counter-clockwise positive.
    pub angular_velocity: f64,
    pub state: BlockMotionState,
    /// Current outline in the world frame, m, counter-clockwise.
    pub outline: Vec<[f64; 2]>,
}

/// Ground motion at a frame time (horizontal x, vertical y), SI.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct GroundFrame {
    pub acceleration: [f64; 2],
    pub velocity: [f64; 2],
    pub displacement: [f64; 2],
}

/// A recorded instant: every block of the scene, in scene order.
#[derive(Debug, Clone, PartialEq)]
pub struct Frame {
    /// Simulation time, s.
    pub time: f64,
    pub blocks: Vec<BlockFrame>,
    pub ground: GroundFrame,
}

/// What the writers need to know about the run before the first frame.
#[derive(Debug, Clone)]
pub struct RecordHeader {
    /// Block ids in scene order.
    pub block_ids: Vec<String>,
    pub block_kinds: Vec<FrameBlockKind>,
    /// Indices (into `block_ids`) of the blocks whose histories are written.
    pub history_blocks: Vec<usize>,
    /// `ashlar.run` metadata: scene JSON, motion provenance and scale, solver settings, version.
    pub metadata: std::collections::BTreeMap<String, String>,
}

pub mod error;
pub mod foxglove;
pub mod histories;
pub mod mcap;
pub mod messages;
pub mod synthetic;
pub mod triangulate;

pub use error::RecordError;
pub use histories::HistoryWriter;
pub use mcap::{McapParams, McapRecorder, McapStats};
