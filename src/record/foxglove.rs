//! Foxglove's well-known message types used by the trajectory recording (`foxglove.SceneUpdate`,
//! `foxglove.FrameTransforms`): the JSON messages and their JSON Schemas. Sits in `record`,
//! under the MCAP recorder.
//!
//! The schemas reproduce the published `foxglove.*` JSON Schemas field for field (names, types,
//! enums, nesting and `required` lists; the descriptions are ours and shorter). The optional
//! `message_id` / `lineage` fields that recent schema releases append are left out: nothing
//! here fills them and older viewers do not know them. Every array field is present in every
//! message, even empty, because the published schemas list them as required.
//!
//! Length (over 600 lines, about 40 of them tests): the schemas are long JSON literals, one per
//! message type, kept beside the message structs they describe so that a field is changed in
//! both at once.
use serde::Serialize;
use serde_json::{json, Value};

/// `time`: seconds and nanoseconds since the start of the run (simulation time).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
pub struct Time {
    pub sec: u64,
    pub nsec: u32,
}

impl Time {
    pub fn from_nanos(ns: u64) -> Self {
        Time {
            sec: ns / 1_000_000_000,
            nsec: (ns % 1_000_000_000) as u32,
        }
    }
}

/// `duration`; zero lifetime means "until replaced".
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Default)]
pub struct Duration {
    pub sec: i64,
    pub nsec: u32,
}

#[derive(Debug, Clone, Copy, PartialEq, Serialize, Default)]
pub struct Vector3 {
    pub x: f64,
    pub y: f64,
    pub z: f64,
}

#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Quaternion {
    pub x: f64,
    pub y: f64,
    pub z: f64,
    pub w: f64,
}

impl Quaternion {
    pub const IDENTITY: Quaternion = Quaternion {
        x: 0.0,
        y: 0.0,
        z: 0.0,
        w: 1.0,
    };
}

#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Pose {
    pub position: Vector3,
    pub orientation: Quaternion,
}

impl Pose {
    pub const IDENTITY: Pose = Pose {
        position: Vector3 {
            x: 0.0,
            y: 0.0,
            z: 0.0,
        },
        orientation: Quaternion::IDENTITY,
    };
}

/// A point in the viewer's 3D space, m; the 2D scene lies in z = 0.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Point3 {
    pub x: f64,
    pub y: f64,
    pub z: f64,
}

/// RGBA, each in [0, 1].
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Color {
    pub r: f64,
    pub g: f64,
    pub b: f64,
    pub a: f64,
}

#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct KeyValuePair {
    pub key: String,
    pub value: String,
}

/// `foxglove.LineType`.
pub const LINE_STRIP: u8 = 0;
pub const LINE_LOOP: u8 = 1;

#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct LinePrimitive {
    #[serde(rename = "type")]
    pub line_type: u8,
    pub pose: Pose,
    pub thickness: f64,
    pub scale_invariant: bool,
    pub points: Vec<Point3>,
    pub color: Color,
    pub colors: Vec<Color>,
    pub indices: Vec<u32>,
}

#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct TriangleListPrimitive {
    pub pose: Pose,
    pub points: Vec<Point3>,
    pub color: Color,
    pub colors: Vec<Color>,
    pub indices: Vec<u32>,
}

/// An always-empty array (primitive kinds the recording never uses).
pub type Unused = [(); 0];

#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct SceneEntity {
    pub timestamp: Time,
    pub frame_id: String,
    pub id: String,
    pub lifetime: Duration,
    pub frame_locked: bool,
    pub metadata: Vec<KeyValuePair>,
    pub arrows: Unused,
    pub cubes: Unused,
    pub spheres: Unused,
    pub cylinders: Unused,
    pub lines: Vec<LinePrimitive>,
    pub triangles: Vec<TriangleListPrimitive>,
    pub texts: Unused,
    pub models: Unused,
}

#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct SceneUpdate {
    pub deletions: Unused,
    pub entities: Vec<SceneEntity>,
}

#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct FrameTransform {
    pub timestamp: Time,
    pub parent_frame_id: String,
    pub child_frame_id: String,
    pub translation: Vector3,
    pub rotation: Quaternion,
}

#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct FrameTransforms {
    pub transforms: Vec<FrameTransform>,
}

// ---- JSON Schemas -------------------------------------------------------------------------

/// An object schema whose every property is required (as in the published schemas).
fn object(title: &str, description: &str, props: Vec<(&str, Value)>) -> Value {
    let required: Vec<&str> = props.iter().map(|(k, _)| *k).collect();
    let properties: serde_json::Map<String, Value> =
        props.into_iter().map(|(k, v)| (k.to_string(), v)).collect();
    json!({
        "title": title,
        "description": description,
        "type": "object",
        "properties": properties,
        "required": required,
    })
}

fn typed(ty: &str, description: &str) -> Value {
    json!({ "type": ty, "description": description })
}

fn array(items: Value, description: &str) -> Value {
    json!({ "type": "array", "items": items, "description": description })
}

fn indices(description: &str) -> Value {
    array(json!({ "type": "integer", "minimum": 0 }), description)
}

/// `time` and `duration` carry no `required` list in the published schemas.
fn time(description: &str) -> Value {
    json!({
        "type": "object",
        "title": "time",
        "properties": {
            "sec": { "type": "integer", "minimum": 0 },
            "nsec": { "type": "integer", "minimum": 0, "maximum": 999_999_999 }
        },
        "description": description,
    })
}

fn duration(description: &str) -> Value {
    json!({
        "type": "object",
        "title": "duration",
        "properties": {
            "sec": { "type": "integer" },
            "nsec": { "type": "integer", "minimum": 0, "maximum": 999_999_999 }
        },
        "description": description,
    })
}

fn vector3(description: &str) -> Value {
    object(
        "foxglove.Vector3",
        description,
        vec![
            ("x", typed("number", "x component")),
            ("y", typed("number", "y component")),
            ("z", typed("number", "z component")),
        ],
    )
}

fn quaternion(description: &str) -> Value {
    object(
        "foxglove.Quaternion",
        description,
        vec![
            ("x", typed("number", "x value")),
            ("y", typed("number", "y value")),
            ("z", typed("number", "z value")),
            ("w", typed("number", "w value")),
        ],
    )
}

fn pose(description: &str) -> Value {
    object(
        "foxglove.Pose",
        description,
        vec![
            ("position", vector3("Position in 3D space")),
            ("orientation", quaternion("Orientation in 3D space")),
        ],
    )
}

fn point3(description: &str) -> Value {
    object(
        "foxglove.Point3",
        description,
        vec![
            ("x", typed("number", "x coordinate")),
            ("y", typed("number", "y coordinate")),
            ("z", typed("number", "z coordinate")),
        ],
    )
}

fn color(description: &str) -> Value {
    object(
        "foxglove.Color",
        description,
        vec![
            ("r", typed("number", "Red, 0 to 1")),
            ("g", typed("number", "Green, 0 to 1")),
            ("b", typed("number", "Blue, 0 to 1")),
            ("a", typed("number", "Alpha, 0 to 1")),
        ],
    )
}

fn enumeration(title: &str, description: &str, values: &[(&str, u8)]) -> Value {
    let one_of: Vec<Value> = values
        .iter()
        .map(|(name, v)| json!({ "title": name, "const": v }))
        .collect();
    json!({ "title": title, "description": description, "oneOf": one_of })
}

fn arrow_primitive() -> Value {
    object(
        "foxglove.ArrowPrimitive",
        "An arrow",
        vec![
            (
                "pose",
                pose("Tail position and orientation (identity points along +x)"),
            ),
            ("shaft_length", typed("number", "Shaft length")),
            ("shaft_diameter", typed("number", "Shaft diameter")),
            ("head_length", typed("number", "Head length")),
            ("head_diameter", typed("number", "Head diameter")),
            ("color", color("Arrow color")),
        ],
    )
}

fn sized_primitive(title: &str, description: &str, size: &str) -> Value {
    object(
        title,
        description,
        vec![
            ("pose", pose("Center position and orientation")),
            ("size", vector3(size)),
            ("color", color("Color")),
        ],
    )
}

fn cylinder_primitive() -> Value {
    object(
        "foxglove.CylinderPrimitive",
        "A cylinder, elliptic cylinder or truncated cone",
        vec![
            (
                "pose",
                pose("Center position and orientation; flat faces normal to z"),
            ),
            ("size", vector3("Bounding box size")),
            (
                "bottom_scale",
                typed("number", "Bottom face diameter ratio, 0 to 1"),
            ),
            (
                "top_scale",
                typed("number", "Top face diameter ratio, 0 to 1"),
            ),
            ("color", color("Color")),
        ],
    )
}

fn line_primitive() -> Value {
    object(
        "foxglove.LinePrimitive",
        "Points connected by lines",
        vec![
            (
                "type",
                enumeration(
                    "foxglove.LineType",
                    "How the points are connected",
                    &[("LINE_STRIP", 0), ("LINE_LOOP", 1), ("LINE_LIST", 2)],
                ),
            ),
            ("pose", pose("Origin of the points")),
            ("thickness", typed("number", "Line thickness")),
            (
                "scale_invariant",
                typed(
                    "boolean",
                    "Thickness in screen pixels (true) or world units (false)",
                ),
            ),
            ("points", array(point3("A point"), "Points along the line")),
            (
                "color",
                color("Color of the whole line, unless `colors` is non-empty"),
            ),
            (
                "colors",
                array(color("A color"), "Per-point colors, or empty"),
            ),
            (
                "indices",
                indices("Indices into `points`; empty means 0..N-1"),
            ),
        ],
    )
}

fn triangle_list_primitive() -> Value {
    object(
        "foxglove.TriangleListPrimitive",
        "A set of triangles",
        vec![
            ("pose", pose("Origin of the triangles")),
            (
                "points",
                array(
                    point3("A point"),
                    "Vertices, three a triangle unless indexed",
                ),
            ),
            (
                "color",
                color("Color of the whole shape, unless `colors` is non-empty"),
            ),
            (
                "colors",
                array(color("A color"), "Per-vertex colors, or empty"),
            ),
            (
                "indices",
                indices("Indices into `points`, three a triangle; empty means 0..N-1"),
            ),
        ],
    )
}

fn text_primitive() -> Value {
    object(
        "foxglove.TextPrimitive",
        "A text label",
        vec![
            ("pose", pose("Center of the text box and orientation")),
            ("billboard", typed("boolean", "Always face the camera")),
            ("font_size", typed("number", "Font size")),
            (
                "scale_invariant",
                typed("boolean", "Font size in screen pixels"),
            ),
            ("color", color("Text color")),
            ("text", typed("string", "Text")),
        ],
    )
}

fn model_primitive() -> Value {
    let mut data = typed("string", "Embedded model, base64");
    data["contentEncoding"] = json!("base64");
    object(
        "foxglove.ModelPrimitive",
        "A 3D model from a URL or embedded data",
        vec![
            ("pose", pose("Origin of the model")),
            ("scale", vector3("Scale along each axis")),
            ("color", color("Color used when `override_color` is true")),
            (
                "override_color",
                typed("boolean", "Use `color` instead of the model's materials"),
            ),
            ("url", typed("string", "URL of the model file")),
            ("media_type", typed("string", "Media type of embedded data")),
            ("data", data),
        ],
    )
}

fn key_value_pair() -> Value {
    object(
        "foxglove.KeyValuePair",
        "A key and its value",
        vec![
            ("key", typed("string", "Key")),
            ("value", typed("string", "Value")),
        ],
    )
}

fn scene_entity() -> Value {
    object(
        "foxglove.SceneEntity",
        "A visual element of a 3D scene, made of primitives sharing one frame",
        vec![
            ("timestamp", time("Timestamp of the entity")),
            ("frame_id", typed("string", "Frame of reference")),
            (
                "id",
                typed(
                    "string",
                    "Identifier; replaces an earlier entity with the same id",
                ),
            ),
            (
                "lifetime",
                duration("Time until removal; zero keeps it until replaced"),
            ),
            (
                "frame_locked",
                typed("boolean", "Follow `frame_id` as it moves"),
            ),
            ("metadata", array(key_value_pair(), "User metadata")),
            ("arrows", array(arrow_primitive(), "Arrow primitives")),
            (
                "cubes",
                array(
                    sized_primitive(
                        "foxglove.CubePrimitive",
                        "A cube or box",
                        "Size along each axis",
                    ),
                    "Cube primitives",
                ),
            ),
            (
                "spheres",
                array(
                    sized_primitive(
                        "foxglove.SpherePrimitive",
                        "A sphere or ellipsoid",
                        "Diameter along each axis",
                    ),
                    "Sphere primitives",
                ),
            ),
            (
                "cylinders",
                array(cylinder_primitive(), "Cylinder primitives"),
            ),
            ("lines", array(line_primitive(), "Line primitives")),
            (
                "triangles",
                array(triangle_list_primitive(), "Triangle list primitives"),
            ),
            ("texts", array(text_primitive(), "Text primitives")),
            ("models", array(model_primitive(), "Model primitives")),
        ],
    )
}

fn scene_entity_deletion() -> Value {
    object(
        "foxglove.SceneEntityDeletion",
        "Removes previously published entities",
        vec![
            (
                "timestamp",
                time("Only matching entities older than this are removed"),
            ),
            (
                "type",
                enumeration(
                    "foxglove.SceneEntityDeletionType",
                    "What to remove",
                    &[("MATCHING_ID", 0), ("ALL", 1)],
                ),
            ),
            ("id", typed("string", "Entity id, for MATCHING_ID")),
        ],
    )
}

fn with_comment(mut schema: Value) -> Value {
    schema["$comment"] = json!("Foxglove well-known schema, reproduced by ashlar");
    schema
}

/// JSON Schema of `foxglove.SceneUpdate`.
pub fn scene_update_schema() -> Value {
    with_comment(object(
        "foxglove.SceneUpdate",
        "An update to the entities of a 3D scene",
        vec![
            (
                "deletions",
                array(scene_entity_deletion(), "Entities to delete"),
            ),
            (
                "entities",
                array(scene_entity(), "Entities to add or replace"),
            ),
        ],
    ))
}

/// JSON Schema of `foxglove.FrameTransforms`.
pub fn frame_transforms_schema() -> Value {
    let transform = object(
        "foxglove.FrameTransform",
        "Position and orientation of a child frame in its parent frame",
        vec![
            ("timestamp", time("Timestamp of the transform")),
            ("parent_frame_id", typed("string", "Parent frame")),
            ("child_frame_id", typed("string", "Child frame")),
            ("translation", vector3("Child origin in the parent frame")),
            (
                "rotation",
                quaternion("Child orientation in the parent frame"),
            ),
        ],
    );
    with_comment(object(
        "foxglove.FrameTransforms",
        "A list of frame transforms",
        vec![("transforms", array(transform, "Transforms"))],
    ))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_object_requires_exactly_its_properties() {
        // Walks the whole schema: the published schemas require every property of every
        // message type (time and duration excepted, which have no `required`).
        fn walk(v: &Value) {
            if let Some(props) = v.get("properties").and_then(Value::as_object) {
                let title = v.get("title").and_then(Value::as_str).unwrap_or("");
                if title != "time" && title != "duration" {
                    let req: Vec<&str> = v["required"]
                        .as_array()
                        .map(|a| a.iter().filter_map(Value::as_str).collect())
                        .unwrap_or_default();
                    let mut keys: Vec<&str> = props.keys().map(String::as_str).collect();
                    let mut sorted = req.clone();
                    sorted.sort();
                    keys.sort();
                    assert_eq!(sorted, keys, "{title}");
                }
                props.values().for_each(walk);
            }
            if let Some(items) = v.get("items") {
                walk(items);
            }
        }
        walk(&scene_update_schema());
        walk(&frame_transforms_schema());
    }

    #[test]
    fn time_splits_nanoseconds() {
        assert_eq!(Time::from_nanos(3_000_000_007), Time { sec: 3, nsec: 7 });
        assert_eq!(
            Time::from_nanos(999_999_999),
            Time {
                sec: 0,
                nsec: 999_999_999
            }
        );
    }
}
