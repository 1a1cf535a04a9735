//! DXF drawings → [`SceneSpec`] (docs/import.md), read with the `dxf` crate. Each closed
//! LWPOLYLINE or POLYLINE in model space is one block; its layer names the material, and the layer
//! `fixed` (any case) marks fixed blocks. Coordinates are converted to metres from the drawing's
//! `$INSUNITS`. The spec then goes through `scene::validate` like a user's file, and a refusal of a
//! block is reported with the entity handle and layer it came from.
//!
//! Nothing is approximated: arcs, bulged segments, circles, ellipses and splines are refused, not
//! cut into chords, because the choice of chords would change the contacts the engine sees.
//!
//! Length (over 600 lines): one importer read top to bottom (options and units, the error type
//! whose messages name the entity's handle and layer, reading, outlines, the spec), then its
//! tests; the drawings' validation is `scene::validate`, shared with every scene.
use crate::scene::spec::*;
use crate::scene::templates::common::{LIMESTONE, MAX_BLOCKS};
use crate::scene::{validate, Scene, SceneError};
use ::dxf::entities::EntityType;
use ::dxf::enums::Units;
use ::dxf::{Drawing, DxfError};
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;

/// The most vertices one block may have: the validation's self-intersection check is quadratic in
/// them, and 1000 straight segments already outline any dressed stone finely.
pub const MAX_VERTICES: usize = 1000;

/// The largest coordinate magnitude, m: the service's limit on a scene's vertex coordinates
/// (docs/format.md, "Physical ranges"), applied here so that the entity is named.
pub const MAX_COORDINATE: f64 = 1.0e6;

/// The joint every imported scene has (one joint between all blocks).
pub const JOINT_NAME: &str = "dry";

/// The material of blocks on the layer `fixed`.
pub const FIXED_MATERIAL: &str = "fixed";

/// The options file (`--options FILE`, or `"options"` in `POST /v1/scenes/import`). Every member
/// is optional; unknown members are refused.
#[derive(Debug, Clone, Default, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct ImportOptions {
    /// The scene's name (default: "imported drawing").
    #[serde(default)]
    pub name: Option<String>,
    /// The drawing's unit when its `$INSUNITS` is unset or unitless (default: metres, with a
    /// note). A drawing that states its unit keeps it; a different unit here is an error.
    #[serde(default)]
    pub units: Option<LengthUnit>,
    /// Material properties by name (= layer name; `fixed` for the fixed layer). A layer without
    /// an entry gets the default stone ([`default_material`]).
    #[serde(default)]
    pub materials: BTreeMap<String, MaterialSpec>,
    /// The joint between all blocks (default: [`default_joint`]).
    #[serde(default)]
    pub joint: Option<JointSpec>,
    /// The free blocks' model (default: rigid, as the templates).
    #[serde(default)]
    pub block_model: Option<BlockModel>,
    /// Layers whose entities are skipped (any case), e.g. dimensions or a survey grid.
    #[serde(default)]
    pub ignore_layers: Vec<String>,
}

/// A length unit of the options' `units`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize, Serialize)]
pub enum LengthUnit {
    #[serde(rename = "mm")]
    Millimetre,
    #[serde(rename = "cm")]
    Centimetre,
    #[serde(rename = "dm")]
    Decimetre,
    #[serde(rename = "m")]
    Metre,
    #[serde(rename = "km")]
    Kilometre,
    #[serde(rename = "in")]
    Inch,
    #[serde(rename = "ft")]
    Foot,
    #[serde(rename = "yd")]
    Yard,
}

impl LengthUnit {
    fn scale(self) -> Scale {
        match self {
            LengthUnit::Millimetre => Scale::Div(1000.0, "mm"),
            LengthUnit::Centimetre => Scale::Div(100.0, "cm"),
            LengthUnit::Decimetre => Scale::Div(10.0, "dm"),
            LengthUnit::Metre => Scale::Mul(1.0, "m"),
            LengthUnit::Kilometre => Scale::Mul(1000.0, "km"),
            LengthUnit::Inch => Scale::Mul(0.0254, "in"),
            LengthUnit::Foot => Scale::Mul(0.3048, "ft"),
            LengthUnit::Yard => Scale::Mul(0.9144, "yd"),
        }
    }
}

/// Drawing units → metres. Decimal fractions of the metre divide (x / 1000 is the correctly
/// rounded value of x mm in metres; x · 0.001 rounds twice), the rest multiply by the exact
/// definition of the unit.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Scale {
    Mul(f64, &'static str),
    Div(f64, &'static str),
}

impl Scale {
    fn apply(self, x: f64) -> f64 {
        match self {
            Scale::Mul(f, _) => x * f,
            Scale::Div(d, _) => x / d,
        }
    }
    fn name(self) -> &'static str {
        match self {
            Scale::Mul(_, n) | Scale::Div(_, n) => n,
        }
    }
}

/// `$INSUNITS` → metres; `None` for unitless.
fn drawing_scale(u: Units) -> Option<Scale> {
    use Scale::{Div, Mul};
    Some(match u {
        Units::Unitless => return None,
        Units::Inches => Mul(0.0254, "in"),
        Units::Feet => Mul(0.3048, "ft"),
        Units::Miles => Mul(1609.344, "mi"),
        Units::Millimeters => Div(1000.0, "mm"),
        Units::Centimeters => Div(100.0, "cm"),
        Units::Meters => Mul(1.0, "m"),
        Units::Kilometers => Mul(1000.0, "km"),
        Units::Microinches => Mul(2.54e-8, "µin"),
        Units::Mils => Mul(2.54e-5, "mil"),
        Units::Yards => Mul(0.9144, "yd"),
        Units::Angstroms => Div(1e10, "Å"),
        Units::Nanometers => Div(1e9, "nm"),
        Units::Microns => Div(1e6, "µm"),
        Units::Decimeters => Div(10.0, "dm"),
        Units::Decameters => Mul(10.0, "dam"),
        Units::Hectometers => Mul(100.0, "hm"),
        Units::Gigameters => Mul(1e9, "Gm"),
        Units::AstronomicalUnits => Mul(1.495_978_707e11, "au"),
        Units::LightYears => Mul(9.460_730_472_580_8e15, "ly"),
        Units::Parsecs => Mul(3.085_677_581_491_367e16, "pc"),
        // US survey units: 1 ft = 1200/3937 m exactly.
        Units::USSurveyFeet => Mul(1200.0 / 3937.0, "US survey ft"),
        Units::USSurveyInch => Mul(100.0 / 3937.0, "US survey in"),
        Units::USSurveyYard => Mul(3600.0 / 3937.0, "US survey yd"),
        Units::USSurveyMile => Mul(6_336_000.0 / 3937.0, "US survey mi"),
    })
}

/// The material of a layer without an entry in the options: the templates' limestone
/// (2500 kg/m³, E = 20 GPa, ν = 0.2; `scene::templates`), plane stress.
pub fn default_material() -> MaterialSpec {
    MaterialSpec {
        density: LIMESTONE.density,
        young_modulus: LIMESTONE.young_modulus,
        poisson_ratio: LIMESTONE.poisson_ratio,
        plane: PlaneKind::Stress,
    }
}

/// The joint without options: the templates' dry joint, friction 37° (tan φ ≈ 0.75, the middle of
/// the 30–45° measured on dressed limestone and marble joints), no cohesion or tension.
pub fn default_joint() -> JointSpec {
    JointSpec {
        friction_angle: 37.0,
        cohesion: 0.0,
        tensile_strength: 0.0,
    }
}

/// Where a block came from in the drawing.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Source {
    /// The entity's handle as DXF writes it (hexadecimal, e.g. `2F`); `#N` for the N-th entity
    /// (from 1) of a drawing without handles.
    pub handle: String,
    pub layer: String,
}

/// A DXF import refused; every error about an entity names its handle and layer.
#[derive(Debug, thiserror::Error)]
pub enum DxfImportError {
    #[error("the file cannot be read as DXF: {0}")]
    Unreadable(#[source] DxfError),
    #[error("the file cannot be read as DXF: the DXF reader failed on it ({message})")]
    ReaderFailed { message: String },
    #[error(
        "the file does not end with the DXF end marker `0 EOF`: it is truncated or not a DXF file"
    )]
    Truncated,
    #[error("the options{}: {message}", member(path))]
    Options { path: String, message: String },
    #[error(
        "the options' units {given:?} contradict the drawing's $INSUNITS ({drawing}); remove \
         `units` from the options (it applies only to unitless drawings) or fix the drawing"
    )]
    UnitsConflict { given: String, drawing: String },
    #[error(
        "the drawing has no closed polyline in model space: nothing to import (each block is a \
         closed LWPOLYLINE or POLYLINE)"
    )]
    Empty,
    #[error(
        "entity {handle} on layer {layer:?}: an open {entity}; each block must be a closed \
         polyline (close it in the CAD program)"
    )]
    Open {
        handle: String,
        layer: String,
        entity: &'static str,
    },
    #[error(
        "entity {handle} on layer {layer:?}: segment {segment} of the {entity} is an arc (bulge \
         {bulge}); curved segments are refused, not approximated: draw straight segments"
    )]
    Bulge {
        handle: String,
        layer: String,
        entity: &'static str,
        segment: usize,
        bulge: f64,
    },
    #[error(
        "entity {handle} on layer {layer:?}: a {entity}; curves are refused, not approximated: \
         draw the block as a closed polyline of straight segments"
    )]
    Curve {
        handle: String,
        layer: String,
        entity: &'static str,
    },
    #[error(
        "entity {handle} on layer {layer:?}: a {entity} is not a block outline; draw blocks as \
         closed polylines, or skip the layer with the options' `ignore_layers`"
    )]
    Unsupported {
        handle: String,
        layer: String,
        entity: &'static str,
    },
    #[error(
        "entity {handle} on layer {layer:?}: not drawn in the XY plane (extrusion direction \
         {direction:?}); ashlar's scenes are 2D in x (horizontal) and y (up)"
    )]
    NotPlanar {
        handle: String,
        layer: String,
        direction: [f64; 3],
    },
    #[error(
        "entity {handle} on layer {layer:?}: a closed {entity} with {count} distinct vertices; a \
         block needs at least 3"
    )]
    TooFewVertices {
        handle: String,
        layer: String,
        entity: &'static str,
        count: usize,
    },
    #[error(
        "entity {handle} on layer {layer:?}: {count} vertices; at most {MAX_VERTICES} per block"
    )]
    TooManyVertices {
        handle: String,
        layer: String,
        count: usize,
    },
    #[error("the drawing has more than {MAX_BLOCKS} block outlines; at most {MAX_BLOCKS}")]
    TooManyBlocks,
    #[error(
        "entity {handle} on layer {layer:?}: vertex {vertex} is at {value} m, beyond ±{MAX_COORDINATE} m \
         (check the drawing's units)"
    )]
    Coordinate {
        handle: String,
        layer: String,
        vertex: usize,
        value: f64,
    },
    #[error("entity {handle} on layer {layer:?}: {}", source.message)]
    Block {
        handle: String,
        layer: String,
        source: Box<SceneError>,
    },
    #[error(
        "entity {handle} on layer {layer:?} overlaps entity {other_handle} on layer \
         {other_layer:?}: {}", source.message
    )]
    Overlap {
        handle: String,
        layer: String,
        other_handle: String,
        other_layer: String,
        source: Box<SceneError>,
    },
    #[error("the imported scene is refused: {0}")]
    Scene(SceneError),
}

/// ` at MEMBER` for an error about one member of the options, nothing for the whole.
fn member(path: &str) -> String {
    if path.is_empty() {
        String::new()
    } else {
        format!(" at {path}")
    }
}

impl DxfImportError {
    /// The entity the error is about, if any: (handle, layer).
    pub fn entity(&self) -> Option<(&str, &str)> {
        use DxfImportError::*;
        match self {
            Open { handle, layer, .. }
            | Bulge { handle, layer, .. }
            | Curve { handle, layer, .. }
            | Unsupported { handle, layer, .. }
            | NotPlanar { handle, layer, .. }
            | TooFewVertices { handle, layer, .. }
            | TooManyVertices { handle, layer, .. }
            | Coordinate { handle, layer, .. }
            | Block { handle, layer, .. }
            | Overlap { handle, layer, .. } => Some((handle, layer)),
            _ => None,
        }
    }

    /// The options' member the error is about (a dotted path, `materials.stone.density`), when
    /// the options and not the drawing are at fault.
    pub fn options_path(&self) -> Option<&str> {
        match self {
            DxfImportError::Options { path, .. } => Some(path),
            DxfImportError::UnitsConflict { .. } => Some("units"),
            _ => None,
        }
    }
}

impl ImportOptions {
    /// Parse the options from JSON text; an error names the member.
    pub fn from_json(text: &str) -> Result<Self, DxfImportError> {
        let value: serde_json::Value =
            serde_json::from_str(text).map_err(|e| DxfImportError::Options {
                path: String::new(),
                message: format!("not JSON: {e}"),
            })?;
        Self::from_value(&value)
    }

    /// The options from a JSON value (`null` is every default).
    pub fn from_value(value: &serde_json::Value) -> Result<Self, DxfImportError> {
        match value {
            serde_json::Value::Null => Ok(Self::default()),
            // serde would also take a struct from an array of its fields in order.
            serde_json::Value::Object(_) => {
                serde_path_to_error::deserialize(value).map_err(options_error)
            }
            other => Err(DxfImportError::Options {
                path: String::new(),
                message: format!("expected an object of options or null, got {other}"),
            }),
        }
    }
}

fn options_error<E: std::fmt::Display>(e: serde_path_to_error::Error<E>) -> DxfImportError {
    let path = e.path().to_string();
    DxfImportError::Options {
        path: if path == "." { String::new() } else { path },
        message: e.into_inner().to_string(),
    }
}

/// A drawing imported: the spec (to write out), the validated scene, the unit the drawing's
/// coordinates were read in, where each block came from, and notes on choices made (defaulted
/// units and materials, entities skipped).
#[derive(Debug)]
pub struct Imported {
    pub spec: SceneSpec,
    pub scene: Scene,
    pub units: &'static str,
    /// Per block of `spec.blocks`, in order.
    pub sources: Vec<Source>,
    pub notes: Vec<String>,
}

/// One closed outline read from the drawing, in metres, in the drawing's vertex order.
struct Outline {
    source: Source,
    fixed: bool,
    vertices: Vec<[f64; 2]>,
}

/// A vertex as drawn: position in drawing units and the bulge of the segment that starts at it.
type Raw = ([f64; 2], f64);

/// Read a DXF file (ASCII or binary) and build the scene it draws.
pub fn import(bytes: &[u8], options: &ImportOptions) -> Result<Imported, DxfImportError> {
    let drawing = read(bytes)?;
    let mut notes = Vec::new();
    let scale = units(&drawing, options, &mut notes)?;
    let ignored_layer = |layer: &str| {
        options
            .ignore_layers
            .iter()
            .any(|l| l.eq_ignore_ascii_case(layer))
    };
    let mut outlines: Vec<Outline> = Vec::new();
    let (mut paper, mut skipped, mut annotations) = (0usize, 0usize, 0usize);
    for (n, e) in drawing.entities().enumerate() {
        if e.common.is_in_paper_space {
            paper += 1;
            continue;
        }
        let layer = e.common.layer.clone();
        if ignored_layer(&layer) {
            skipped += 1;
            continue;
        }
        let handle = if e.common.handle.is_empty() {
            format!("#{}", n + 1)
        } else {
            e.common.handle.as_string()
        };
        let at = Source { handle, layer };
        let outline = match &e.specific {
            EntityType::LwPolyline(p) => {
                let mirror = plane(&at, &p.extrusion_direction)?;
                let raw = p.vertices.iter().map(|v| ([v.x, v.y], v.bulge)).collect();
                Some((
                    closed_outline(&at, "LWPOLYLINE", p.is_closed(), raw)?,
                    mirror,
                ))
            }
            EntityType::Polyline(p) => {
                let unsupported = if p.is_3d_polyline() {
                    Some("3D POLYLINE")
                } else if p.is_3d_polygon_mesh() {
                    Some("POLYLINE polygon mesh")
                } else if p.is_polyface_mesh() {
                    Some("POLYLINE polyface mesh")
                } else {
                    None
                };
                if let Some(entity) = unsupported {
                    return Err(unsupported_at(&at, entity));
                }
                let fitted = if p.spline_fit_vertices_added() {
                    Some("spline-fitted POLYLINE")
                } else if p.curve_fit_vertices_added() {
                    Some("curve-fitted POLYLINE")
                } else {
                    None
                };
                if let Some(entity) = fitted {
                    return Err(DxfImportError::Curve {
                        handle: at.handle,
                        layer: at.layer,
                        entity,
                    });
                }
                let mirror = plane(&at, &p.normal)?;
                let raw = p
                    .vertices()
                    .map(|v| ([v.location.x, v.location.y], v.bulge))
                    .collect();
                Some((closed_outline(&at, "POLYLINE", p.is_closed(), raw)?, mirror))
            }
            other => {
                if let Some(entity) = curve_name(other) {
                    return Err(DxfImportError::Curve {
                        handle: at.handle,
                        layer: at.layer,
                        entity,
                    });
                }
                if let Some(entity) = geometry_name(other) {
                    return Err(unsupported_at(&at, entity));
                }
                annotations += 1;
                None
            }
        };
        let Some((raw, mirror)) = outline else {
            continue;
        };
        if raw.len() > MAX_VERTICES {
            return Err(DxfImportError::TooManyVertices {
                handle: at.handle,
                layer: at.layer,
                count: raw.len(),
            });
        }
        let mut vertices = Vec::with_capacity(raw.len());
        for (k, [x, y]) in raw.into_iter().enumerate() {
            let x = if mirror { -x } else { x };
            let p = [scale.apply(x), scale.apply(y)];
            for value in p {
                if !(value.is_finite() && value.abs() <= MAX_COORDINATE) {
                    return Err(DxfImportError::Coordinate {
                        handle: at.handle,
                        layer: at.layer,
                        vertex: k,
                        value,
                    });
                }
            }
            vertices.push(p);
        }
        if outlines.len() == MAX_BLOCKS {
            return Err(DxfImportError::TooManyBlocks);
        }
        outlines.push(Outline {
            fixed: at.layer.eq_ignore_ascii_case(FIXED_MATERIAL),
            source: at,
            vertices,
        });
    }
    if outlines.is_empty() {
        return Err(DxfImportError::Empty);
    }
    if paper > 0 {
        notes.push(format!(
            "{paper} paper-space entities skipped (layouts, not the model)"
        ));
    }
    if skipped > 0 {
        notes.push(format!(
            "{skipped} entities on the options' ignore_layers skipped"
        ));
    }
    if annotations > 0 {
        notes.push(format!(
            "{annotations} annotation entities (text, dimensions, points, …) skipped"
        ));
    }
    let spec = build_spec(&outlines, options, &mut notes);
    let sources: Vec<Source> = outlines.into_iter().map(|o| o.source).collect();
    let scene = validate(&spec).map_err(|e| locate(e, &spec, &sources, options))?;
    Ok(Imported {
        spec,
        scene,
        units: scale.name(),
        sources,
        notes,
    })
}

/// Parse the bytes with the `dxf` crate. Its parser is third-party code run on untrusted input
/// (the service's request bodies): a panic inside it becomes a refusal of the file, not a crash of
/// the request's task.
fn read(bytes: &[u8]) -> Result<Drawing, DxfImportError> {
    // The crate takes an ASCII file that ends without its `0 EOF` as complete: a truncated
    // upload would lose its last blocks silently. Binary DXF (its own sentinel) is left to it.
    if !bytes.starts_with(b"AutoCAD Binary DXF") {
        let last = bytes
            .split(|&b| b == b'\n')
            .map(|l| l.trim_ascii())
            .rfind(|l| !l.is_empty());
        if last != Some(b"EOF".as_slice()) {
            return Err(DxfImportError::Truncated);
        }
    }
    let mut reader = bytes;
    match std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| Drawing::load(&mut reader))) {
        Ok(Ok(d)) => Ok(d),
        Ok(Err(e)) => Err(DxfImportError::Unreadable(e)),
        Err(panic) => {
            let message = panic
                .downcast_ref::<&str>()
                .map(|s| s.to_string())
                .or_else(|| panic.downcast_ref::<String>().cloned())
                .unwrap_or_else(|| "a panic".to_string());
            Err(DxfImportError::ReaderFailed { message })
        }
    }
}

/// The scale to metres: the drawing's `$INSUNITS`, else the options' `units`, else metres.
fn units(
    drawing: &Drawing,
    options: &ImportOptions,
    notes: &mut Vec<String>,
) -> Result<Scale, DxfImportError> {
    match (
        drawing_scale(drawing.header.default_drawing_units),
        options.units,
    ) {
        (Some(d), Some(given)) if given.scale() != d => Err(DxfImportError::UnitsConflict {
            given: given.scale().name().to_string(),
            drawing: d.name().to_string(),
        }),
        (Some(d), _) => Ok(d),
        (None, Some(given)) => Ok(given.scale()),
        (None, None) => {
            notes.push(
                "the drawing does not state its units ($INSUNITS unset or unitless): read as \
                 metres; set \"units\" in the options if it is drawn in another unit"
                    .to_string(),
            );
            Ok(Scale::Mul(1.0, "m"))
        }
    }
}

/// The extrusion direction of a 2D entity: +z draws in the XY plane as is; −z (a mirrored
/// entity, e.g. after AutoCAD's MIRROR) has its object x axis along −x (the DXF arbitrary-axis
/// rule), so x is negated. Anything else is not in the plane.
fn plane(at: &Source, n: &::dxf::Vector) -> Result<bool, DxfImportError> {
    let tol = 1e-12;
    if n.x.abs() <= tol && n.y.abs() <= tol && n.z > 0.0 {
        Ok(false)
    } else if n.x.abs() <= tol && n.y.abs() <= tol && n.z < 0.0 {
        Ok(true)
    } else {
        Err(DxfImportError::NotPlanar {
            handle: at.handle.clone(),
            layer: at.layer.clone(),
            direction: [n.x, n.y, n.z],
        })
    }
}

/// The vertices of a closed polyline (drawing units, drawing order), or the reason it is not a
/// block. Exactly repeated consecutive vertices are dropped (a zero-length segment draws
/// nothing), and so is a last vertex equal to the first: an open polyline whose ends coincide is
/// closed as drawn. A segment's bulge is that of the vertex it starts at.
fn closed_outline(
    at: &Source,
    entity: &'static str,
    closed_flag: bool,
    raw: Vec<Raw>,
) -> Result<Vec<[f64; 2]>, DxfImportError> {
    let mut pts: Vec<Raw> = Vec::with_capacity(raw.len());
    for (p, bulge) in raw {
        match pts.last_mut() {
            // The zero-length segment from the repeated vertex goes; the next one starts here.
            Some(last) if last.0 == p => last.1 = bulge,
            _ => pts.push((p, bulge)),
        }
    }
    let ends_meet = pts.len() > 1 && pts.first().map(|f| f.0) == pts.last().map(|l| l.0);
    if ends_meet {
        pts.pop();
    }
    if !closed_flag && !ends_meet {
        return Err(DxfImportError::Open {
            handle: at.handle.clone(),
            layer: at.layer.clone(),
            entity,
        });
    }
    if pts.len() < 3 {
        return Err(DxfImportError::TooFewVertices {
            handle: at.handle.clone(),
            layer: at.layer.clone(),
            entity,
            count: pts.len(),
        });
    }
    if let Some((segment, &(_, bulge))) = pts.iter().enumerate().find(|(_, p)| p.1 != 0.0) {
        return Err(DxfImportError::Bulge {
            handle: at.handle.clone(),
            layer: at.layer.clone(),
            entity,
            segment,
            bulge,
        });
    }
    Ok(pts.into_iter().map(|(p, _)| p).collect())
}

fn unsupported_at(at: &Source, entity: &'static str) -> DxfImportError {
    DxfImportError::Unsupported {
        handle: at.handle.clone(),
        layer: at.layer.clone(),
        entity,
    }
}

/// Curved entities: refused.
fn curve_name(e: &EntityType) -> Option<&'static str> {
    Some(match e {
        EntityType::Arc(_) => "ARC",
        EntityType::Circle(_) => "CIRCLE",
        EntityType::Ellipse(_) => "ELLIPSE",
        EntityType::Spline(_) => "SPLINE",
        EntityType::Helix(_) => "HELIX",
        _ => return None,
    })
}

/// Other geometry that could be meant as part of the structure but is not a closed outline:
/// refused so that nothing drawn is silently dropped (a block reference's contents, lines that
/// might have been meant as a polygon).
fn geometry_name(e: &EntityType) -> Option<&'static str> {
    Some(match e {
        EntityType::Line(_) => "LINE",
        EntityType::Ray(_) => "RAY",
        EntityType::XLine(_) => "XLINE",
        EntityType::MLine(_) => "MLINE",
        EntityType::Solid(_) => "SOLID",
        EntityType::Trace(_) => "TRACE",
        EntityType::Face3D(_) => "3DFACE",
        EntityType::Insert(_) => "INSERT (block reference; explode it)",
        EntityType::Region(_) => "REGION",
        EntityType::Body(_) => "BODY",
        EntityType::Solid3D(_) => "3DSOLID",
        EntityType::Wipeout(_) => "WIPEOUT",
        _ => return None,
    })
}

/// The spec: one material per layer (the options' properties or the default stone), the joint
/// `dry` between all blocks, block ids `<layer>-<handle>`.
fn build_spec(outlines: &[Outline], options: &ImportOptions, notes: &mut Vec<String>) -> SceneSpec {
    let mut materials = options.materials.clone();
    let mut defaulted = Vec::new();
    let blocks = outlines
        .iter()
        .map(|o| {
            let material = if o.fixed {
                FIXED_MATERIAL.to_string()
            } else {
                o.source.layer.clone()
            };
            if !materials.contains_key(&material) {
                materials.insert(material.clone(), default_material());
                defaulted.push(material.clone());
            }
            BlockSpec {
                id: format!("{}-{}", o.source.layer, o.source.handle),
                material,
                fixed: o.fixed,
                vertices: o.vertices.clone(),
                block_model: if o.fixed {
                    None
                } else {
                    Some(options.block_model.unwrap_or(BlockModel::Rigid))
                },
            }
        })
        .collect();
    if !defaulted.is_empty() {
        notes.push(format!(
            "materials {defaulted:?} not in the options: the default stone (limestone, 2500 kg/m³, \
             E = 20 GPa, ν = 0.2)"
        ));
    }
    let mut joints = BTreeMap::new();
    joints.insert(
        JOINT_NAME.to_string(),
        options.joint.clone().unwrap_or_else(default_joint),
    );
    SceneSpec {
        format: "ashlar.scene/1".into(),
        name: Some(
            options
                .name
                .clone()
                .unwrap_or_else(|| "imported drawing".into()),
        ),
        gravity: Some(9.81),
        materials,
        joints,
        blocks,
        interfaces: None,
        excitation: None,
        initial: Vec::new(),
        control: ControlSpec::default(),
    }
}

/// A validation error of the built spec, traced back to the drawing (the entity of
/// `blocks[i]`) or to the options (`materials.X`, the joint).
fn locate(
    e: SceneError,
    spec: &SceneSpec,
    sources: &[Source],
    options: &ImportOptions,
) -> DxfImportError {
    if let Some(i) = e
        .path
        .strip_prefix("blocks[")
        .and_then(|r| r.split(']').next())
        .and_then(|n| n.parse::<usize>().ok())
        .filter(|&i| i < sources.len())
    {
        let at = sources[i].clone();
        if e.message.contains(" overlaps block ") {
            let other = spec.blocks.iter().zip(sources).find(|(b, _)| {
                b.id != spec.blocks[i].id && e.message.contains(&format!("{:?}", b.id))
            });
            if let Some((_, o)) = other {
                return DxfImportError::Overlap {
                    handle: at.handle,
                    layer: at.layer,
                    other_handle: o.handle.clone(),
                    other_layer: o.layer.clone(),
                    source: Box::new(e),
                };
            }
        }
        return DxfImportError::Block {
            handle: at.handle,
            layer: at.layer,
            source: Box::new(e),
        };
    }
    if let Some(rest) = e.path.strip_prefix("materials.") {
        let name = rest.split('.').next().unwrap_or_default();
        if options.materials.contains_key(name) {
            return DxfImportError::Options {
                path: e.path.clone(),
                message: e.message,
            };
        }
    }
    if let Some(rest) = e.path.strip_prefix(&format!("joints.{JOINT_NAME}")) {
        if options.joint.is_some() {
            return DxfImportError::Options {
                path: format!("joint{rest}"),
                message: e.message,
            };
        }
    }
    DxfImportError::Scene(e)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn at() -> Source {
        Source {
            handle: "2F".into(),
            layer: "stone".into(),
        }
    }

    #[test]
    fn outlines_drop_repeats_and_close_coincident_ends() {
        let sq = |b: f64| {
            vec![
                ([0.0, 0.0], 0.0),
                ([1.0, 0.0], 0.0),
                ([1.0, 0.0], b),
                ([1.0, 1.0], 0.0),
                ([0.0, 1.0], 0.0),
                ([0.0, 0.0], 0.0),
            ]
        };
        let v =
            closed_outline(&at(), "LWPOLYLINE", false, sq(0.0)).expect("closed by coincident ends");
        assert_eq!(v, vec![[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]]);
        // The repeated vertex's bulge belongs to the segment that follows it (segment 1).
        match closed_outline(&at(), "LWPOLYLINE", true, sq(0.5)) {
            Err(DxfImportError::Bulge { segment, .. }) => assert_eq!(segment, 1),
            other => panic!("{other:?}"),
        }
        let open = vec![([0.0, 0.0], 0.0), ([1.0, 0.0], 0.0), ([1.0, 1.0], 0.0)];
        assert!(matches!(
            closed_outline(&at(), "POLYLINE", false, open),
            Err(DxfImportError::Open { .. })
        ));
    }

    #[test]
    fn units_divide_decimal_fractions_exactly() {
        assert_eq!(
            drawing_scale(Units::Millimeters).map(|s| s.apply(1234.5)),
            Some(1.2345)
        );
        assert_eq!(drawing_scale(Units::Unitless), None);
        let ft = drawing_scale(Units::Feet).map_or(0.0, |s| s.apply(10.0));
        assert!((ft - 3.048).abs() < 1e-15, "{ft}");
    }

    #[test]
    fn options_name_the_member() {
        let e = ImportOptions::from_json(r#"{"materials": {"stone": {"density": "x"}}}"#)
            .expect_err("bad density");
        assert_eq!(e.options_path(), Some("materials.stone.density"), "{e}");
        let e = ImportOptions::from_json(r#"{"unit": "mm"}"#).expect_err("unknown member");
        assert!(e.to_string().contains("unit"), "{e}");
    }
}
