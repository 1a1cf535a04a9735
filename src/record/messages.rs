//! The JSON messages of the trajectory recording, built from plain [`Frame`]s: ashlar's own
//! `ashlar.BlockStates` and `ashlar.GroundMotion` (docs/format.md §5) with their JSON Schemas, and the
//! `foxglove.SceneUpdate` that draws every block. Sits in `record`, under the MCAP recorder.
use super::foxglove::{
    Color, Duration, FrameTransform, FrameTransforms, KeyValuePair, LinePrimitive, Point3, Pose,
    Quaternion, SceneEntity, SceneUpdate, Time, TriangleListPrimitive, Vector3, LINE_LOOP,
};
use super::triangulate::triangulate;
use super::{BlockMotionState, Frame, FrameBlockKind, RecordHeader};
use serde::Serialize;
use serde_json::{json, Value};

/// The frame every entity is drawn in (the scene's own x right, y up; z = 0).
pub const WORLD_FRAME: &str = "world";

/// One block in `ashlar.BlockStates`.
#[derive(Debug, Clone, Serialize)]
pub struct BlockState<'a> {
    pub id: &'a str,
    pub x: f64,
    pub y: f64,
    pub rotation: f64,
    pub vx: f64,
    pub vy: f64,
    pub angular_velocity: f64,
    pub kind: FrameBlockKind,
    pub state: BlockMotionState,
}

/// `ashlar.BlockStates`: every block of the scene at one recorded frame, in scene order.
#[derive(Debug, Clone, Serialize)]
pub struct BlockStates<'a> {
    pub time: f64,
    pub blocks: Vec<BlockState<'a>>,
}

/// `ashlar.GroundMotion`: the ground at one recorded frame; horizontal components under the
/// docs/format.md names, vertical ones beside them (zero when the run has no vertical record).
#[derive(Debug, Clone, Serialize)]
pub struct GroundMotion {
    pub time: f64,
    pub acceleration: f64,
    pub velocity: f64,
    pub displacement: f64,
    pub vertical_acceleration: f64,
    pub vertical_velocity: f64,
    pub vertical_displacement: f64,
}

pub fn block_states<'a>(header: &'a RecordHeader, frame: &Frame) -> BlockStates<'a> {
    let blocks = frame
        .blocks
        .iter()
        .zip(header.block_ids.iter().zip(&header.block_kinds))
        .map(|(b, (id, kind))| BlockState {
            id,
            x: b.x,
            y: b.y,
            rotation: b.rotation,
            vx: b.vx,
            vy: b.vy,
            angular_velocity: b.angular_velocity,
            kind: *kind,
            state: b.state,
        })
        .collect();
    BlockStates {
        time: frame.time,
        blocks,
    }
}

pub fn ground_motion(frame: &Frame) -> GroundMotion {
    let g = &frame.ground;
    GroundMotion {
        time: frame.time,
        acceleration: g.acceleration[0],
        velocity: g.velocity[0],
        displacement: g.displacement[0],
        vertical_acceleration: g.acceleration[1],
        vertical_velocity: g.velocity[1],
        vertical_displacement: g.displacement[1],
    }
}

/// Fill colours. Free blocks are coloured by how they move (Okabe–Ito colours, told apart with
/// the common colour-vision deficiencies); fixed and driven blocks are neutral greys.
pub fn fill_color(kind: FrameBlockKind, state: BlockMotionState) -> Color {
    let (r, g, b) = match (kind, state) {
        (FrameBlockKind::Fixed, _) => (0.60, 0.60, 0.60),
        (FrameBlockKind::Driven, _) => (0.40, 0.40, 0.40),
        (FrameBlockKind::Free, BlockMotionState::AtRest) => (0.000, 0.447, 0.698), // blue
        (FrameBlockKind::Free, BlockMotionState::Sliding) => (0.902, 0.624, 0.000), // orange
        (FrameBlockKind::Free, BlockMotionState::Rocking) => (0.800, 0.475, 0.655), // purple
        (FrameBlockKind::Free, BlockMotionState::Toppled) => (0.835, 0.369, 0.000), // vermillion
    };
    // Slightly transparent so overlapping (penetrating) blocks stay visible.
    Color { r, g, b, a: 0.85 }
}

/// Outline colour: near-black, opaque, so joints between blocks read clearly.
pub const OUTLINE_COLOR: Color = Color {
    r: 0.1,
    g: 0.1,
    b: 0.1,
    a: 1.0,
};

/// How outlines are drawn.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SceneStyle {
    /// Outline width in screen pixels (scale-invariant, so it reads at any zoom).
    pub outline_px: f64,
}

pub fn scene_update(
    header: &RecordHeader,
    frame: &Frame,
    ns: u64,
    style: SceneStyle,
) -> SceneUpdate {
    let timestamp = Time::from_nanos(ns);
    let entities = frame
        .blocks
        .iter()
        .zip(header.block_ids.iter().zip(&header.block_kinds))
        .map(|(b, (id, kind))| {
            let points: Vec<Point3> = b
                .outline
                .iter()
                .map(|p| Point3 {
                    x: p[0],
                    y: p[1],
                    z: 0.0,
                })
                .collect();
            SceneEntity {
                timestamp,
                frame_id: WORLD_FRAME.to_string(),
                id: id.clone(),
                lifetime: Duration::default(),
                frame_locked: false,
                metadata: vec![
                    KeyValuePair {
                        key: "kind".into(),
                        value: snake(kind),
                    },
                    KeyValuePair {
                        key: "state".into(),
                        value: snake(&b.state),
                    },
                ],
                arrows: [],
                cubes: [],
                spheres: [],
                cylinders: [],
                lines: vec![LinePrimitive {
                    line_type: LINE_LOOP,
                    pose: Pose::IDENTITY,
                    thickness: style.outline_px,
                    scale_invariant: true,
                    points: points.clone(),
                    color: OUTLINE_COLOR,
                    colors: Vec::new(),
                    indices: Vec::new(),
                }],
                triangles: vec![TriangleListPrimitive {
                    pose: Pose::IDENTITY,
                    indices: triangulate(&b.outline),
                    points,
                    color: fill_color(*kind, b.state),
                    colors: Vec::new(),
                }],
                texts: [],
                models: [],
            }
        })
        .collect();
    SceneUpdate {
        deletions: [],
        entities,
    }
}

/// The static transform that declares the `world` frame (root of the tree, identity to its one
/// child `scene`), so viewers offer `world` as display frame.
pub fn static_transforms() -> FrameTransforms {
    FrameTransforms {
        transforms: vec![FrameTransform {
            timestamp: Time::from_nanos(0),
            parent_frame_id: WORLD_FRAME.to_string(),
            child_frame_id: "scene".to_string(),
            translation: Vector3::default(),
            rotation: Quaternion::IDENTITY,
        }],
    }
}

/// The serde name of a unit enum variant (`at_rest`, `free`, ...).
fn snake<T: Serialize>(v: &T) -> String {
    match serde_json::to_value(v) {
        Ok(Value::String(s)) => s,
        _ => String::new(),
    }
}

fn number(description: &str) -> Value {
    json!({ "type": "number", "description": description })
}

/// JSON Schema of `ashlar.BlockStates`.
pub fn block_states_schema() -> Value {
    json!({
        "title": "ashlar.BlockStates",
        "description": "Every block of the scene at one recorded frame, in scene order",
        "type": "object",
        "properties": {
            "time": number("Simulation time, s"),
            "blocks": {
                "type": "array",
                "items": {
                    "title": "ashlar.BlockState",
                    "type": "object",
                    "properties": {
                        "id": { "type": "string", "description": "Block id (scene file)" },
                        "x": number("Centroid displacement from the initial position, x (right), m"),
                        "y": number("Centroid displacement from the initial position, y (up), m"),
                        "rotation": number("Rotation since the start, rad, counter-clockwise positive"),
                        "vx": number("Centroid velocity, x, m/s"),
                        "vy": number("Centroid velocity, y, m/s"),
                        "angular_velocity": number("rad/s, counter-clockwise positive"),
                        "kind": { "type": "string", "enum": ["fixed", "driven", "free"] },
                        "state": {
                            "type": "string",
                            "enum": ["at_rest", "sliding", "rocking", "toppled"]
                        }
                    },
                    "required": ["id", "x", "y", "rotation", "vx", "vy", "angular_velocity",
                                 "kind", "state"]
                },
                "description": "One entry a block"
            }
        },
        "required": ["time", "blocks"]
    })
}

/// JSON Schema of `ashlar.GroundMotion`.
pub fn ground_motion_schema() -> Value {
    json!({
        "title": "ashlar.GroundMotion",
        "description": "Ground motion at one recorded frame (as applied, after scaling)",
        "type": "object",
        "properties": {
            "time": number("Simulation time, s"),
            "acceleration": number("Horizontal ground acceleration, m/s², +x"),
            "velocity": number("Horizontal ground velocity, m/s, +x"),
            "displacement": number("Horizontal ground displacement, m, +x"),
            "vertical_acceleration": number("Vertical ground acceleration, m/s², +y; 0 without a vertical record"),
            "vertical_velocity": number("Vertical ground velocity, m/s, +y"),
            "vertical_displacement": number("Vertical ground displacement, m, +y")
        },
        "required": ["time", "acceleration", "velocity", "displacement",
                     "vertical_acceleration", "vertical_velocity", "vertical_displacement"]
    })
}
