//! Parametric historical structures (docs/templates.md): named templates that build an `ashlar.scene/1`
//! [`SceneSpec`] from a few parameters in metres, which then goes through the same validation
//! as a user's file. Sits before `scene::validate` in the flow (template → spec → scene); the CLI
//! (`ashlar scene`) and the service (`/v1/templates`) only call [`list`] and [`build`].
//!
//! Conventions of every template: SI units (lengths m, angles degrees, densities kg/m³); y up,
//! the ground at y = 0 carried by a fixed block named `foundation` below it; every stone a rigid
//! free block (`"block_model": "rigid"`: stone is stiff, its strain is not what the question is
//! about); materials and joints named in the scene (`limestone` or `marble`, joint `dry`, no
//! cohesion or tension).
mod arch;
mod buttressed_wall;
mod column;
pub(crate) mod common;
mod obelisk;
mod pyramid;
mod wall;

use super::spec::SceneSpec;
use super::{validate, Scene, SceneError};
use serde::Serialize;
use serde_json::Value;
use std::collections::BTreeMap;

/// What a parameter accepts.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Kind {
    /// A real number in `[min, max]`, in `units`.
    Number { default: f64, min: f64, max: f64 },
    /// A whole number in `[min, max]`.
    Integer { default: u32, min: u32, max: u32 },
    /// One of the listed words.
    Choice {
        default: &'static str,
        choices: &'static [&'static str],
    },
    /// `true` or `false`.
    Flag { default: bool },
}

/// One parameter of a template.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Param {
    pub name: &'static str,
    /// `m`, `deg`, `kg/m3`, `1` (a ratio), `count`, or `""` (a word or a flag).
    pub units: &'static str,
    pub description: &'static str,
    pub kind: Kind,
}

impl Serialize for Param {
    /// `{name, units, description, default, min, max}` (+ `choices` for a word); min and max are
    /// null for words and flags.
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        let (default, min, max, choices) = match self.kind {
            Kind::Number { default, min, max } => (
                Value::from(default),
                Value::from(min),
                Value::from(max),
                None,
            ),
            Kind::Integer { default, min, max } => (
                Value::from(default),
                Value::from(min),
                Value::from(max),
                None,
            ),
            Kind::Choice { default, choices } => (
                Value::from(default),
                Value::Null,
                Value::Null,
                Some(choices),
            ),
            Kind::Flag { default } => (Value::from(default), Value::Null, Value::Null, None),
        };
        let mut v = serde_json::json!({
            "name": self.name, "units": self.units, "description": self.description,
            "default": default, "min": min, "max": max,
        });
        if let Some(c) = choices {
            v["choices"] = Value::from(c.to_vec());
        }
        v.serialize(s)
    }
}

/// A template: its name, what it builds, its parameters, and the builder.
#[derive(Debug, Clone, Serialize)]
pub struct Template {
    pub name: &'static str,
    pub description: &'static str,
    pub parameters: Vec<Param>,
    #[serde(skip)]
    build: fn(&Values) -> Result<SceneSpec, TemplateError>,
}

/// Why a template could not be built.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum TemplateError {
    #[error("no template named {name:?}; the templates are: {known}")]
    UnknownTemplate { name: String, known: String },
    #[error("template {template:?} has no parameter {name:?}; its parameters are: {known}")]
    UnknownParameter {
        template: String,
        name: String,
        known: String,
    },
    #[error("parameter {name}: {message}")]
    BadValue { name: String, message: String },
    /// A combination of parameters that cannot be built (e.g. an opening wider than the wall).
    #[error("parameter {name}: {message}")]
    Geometry { name: String, message: String },
    /// The built scene failed validation: a defect of the template, reported rather than hidden.
    #[error("template {template:?} built an invalid scene ({source}); please report this")]
    Invalid {
        template: String,
        source: SceneError,
    },
}

impl TemplateError {
    /// The parameter the error is about, when there is one (the service's `pointer`).
    pub fn parameter(&self) -> Option<&str> {
        match self {
            TemplateError::UnknownParameter { name, .. }
            | TemplateError::BadValue { name, .. }
            | TemplateError::Geometry { name, .. } => Some(name),
            _ => None,
        }
    }

    pub(crate) fn geometry(name: &str, message: impl Into<String>) -> Self {
        TemplateError::Geometry {
            name: name.into(),
            message: message.into(),
        }
    }
}

/// Resolved parameter values (defaults filled in), read by the builders.
#[derive(Debug, Clone, PartialEq)]
pub struct Values {
    map: BTreeMap<&'static str, Resolved>,
}

#[derive(Debug, Clone, PartialEq)]
enum Resolved {
    Number(f64),
    Text(&'static str),
    Flag(bool),
}

impl Values {
    /// A number or an integer parameter. A name the template does not declare reads 0 (a
    /// builder bug caught by the templates' unit tests, which build every template).
    pub fn num(&self, name: &str) -> f64 {
        match self.map.get(name) {
            Some(Resolved::Number(x)) => *x,
            _ => 0.0,
        }
    }
    /// An integer parameter (validated whole and within its range).
    pub fn count(&self, name: &str) -> usize {
        self.num(name) as usize
    }
    pub fn word(&self, name: &str) -> &'static str {
        match self.map.get(name) {
            Some(Resolved::Text(t)) => t,
            _ => "",
        }
    }
    pub fn flag(&self, name: &str) -> bool {
        matches!(self.map.get(name), Some(Resolved::Flag(true)))
    }
}

/// Every template, in a stable order.
pub fn list() -> Vec<Template> {
    vec![
        Template {
            name: "drum-column",
            description: "A free-standing column of drums with capital (echinus) and abacus, \
                          optionally on a base, standing on a fixed stylobate",
            parameters: column::column_params(),
            build: column::drum_column,
        },
        Template {
            name: "colonnade",
            description: "A row of drum columns carrying architrave blocks jointed over the \
                          column axes",
            parameters: column::colonnade_params(),
            build: column::colonnade,
        },
        Template {
            name: "arch",
            description: "A semicircular or pointed (equilateral) arch of voussoirs with radial \
                          joints, on two piers or springing from the fixed foundation",
            parameters: arch::params(),
            build: arch::arch,
        },
        Template {
            name: "wall",
            description: "A running-bond wall in elevation, with openings under lintels",
            parameters: wall::params(),
            build: wall::wall,
        },
        Template {
            name: "buttressed-wall",
            description: "The cross-section of a wall with a stepped buttress bonded to one \
                          face (out-of-plane shaking acts across the section)",
            parameters: buttressed_wall::params(),
            build: buttressed_wall::buttressed_wall,
        },
        Template {
            name: "obelisk",
            description: "A monolithic obelisk with its pyramidion, on a pedestal on steps",
            parameters: obelisk::params(),
            build: obelisk::obelisk,
        },
        Template {
            name: "pyramid",
            description: "The section of a stepped pyramid: tiers of running-bond courses, each \
                          set back from the one below",
            parameters: pyramid::params(),
            build: pyramid::pyramid,
        },
    ]
}

/// The template named `name`.
pub fn find(name: &str) -> Result<Template, TemplateError> {
    let all = list();
    let known = all.iter().map(|t| t.name).collect::<Vec<_>>().join(", ");
    all.into_iter()
        .find(|t| t.name == name)
        .ok_or(TemplateError::UnknownTemplate {
            name: name.into(),
            known,
        })
}

impl Template {
    /// Check the given values against the declared parameters and fill in the defaults. A value
    /// may be a JSON number/boolean/string or a string to parse (`--set drums=7` on the CLI).
    pub fn resolve(&self, given: &BTreeMap<String, Value>) -> Result<Values, TemplateError> {
        for name in given.keys() {
            if !self.parameters.iter().any(|p| p.name == name) {
                return Err(TemplateError::UnknownParameter {
                    template: self.name.into(),
                    name: name.clone(),
                    known: self
                        .parameters
                        .iter()
                        .map(|p| p.name)
                        .collect::<Vec<_>>()
                        .join(", "),
                });
            }
        }
        let mut map = BTreeMap::new();
        for p in &self.parameters {
            let value = match given.get(p.name) {
                None => default_of(p),
                Some(v) => resolve_one(p, v)?,
            };
            map.insert(p.name, value);
        }
        Ok(Values { map })
    }

    /// Build the scene file (not yet validated).
    pub fn spec(&self, given: &BTreeMap<String, Value>) -> Result<SceneSpec, TemplateError> {
        let values = self.resolve(given)?;
        (self.build)(&values)
    }

    /// Build and validate, exactly as a user's file is validated.
    pub fn build(
        &self,
        given: &BTreeMap<String, Value>,
    ) -> Result<(SceneSpec, Scene), TemplateError> {
        let spec = self.spec(given)?;
        let scene = validate(&spec).map_err(|source| TemplateError::Invalid {
            template: self.name.into(),
            source,
        })?;
        Ok((spec, scene))
    }
}

/// Build template `name` with `given` values and validate it.
pub fn build(
    name: &str,
    given: &BTreeMap<String, Value>,
) -> Result<(SceneSpec, Scene), TemplateError> {
    find(name)?.build(given)
}

fn default_of(p: &Param) -> Resolved {
    match p.kind {
        Kind::Number { default, .. } => Resolved::Number(default),
        Kind::Integer { default, .. } => Resolved::Number(default as f64),
        Kind::Choice { default, .. } => Resolved::Text(default),
        Kind::Flag { default } => Resolved::Flag(default),
    }
}

fn bad(p: &Param, message: String) -> TemplateError {
    TemplateError::BadValue {
        name: p.name.into(),
        message,
    }
}

fn as_number(p: &Param, v: &Value) -> Result<f64, TemplateError> {
    let x = match v {
        Value::Number(n) => n.as_f64(),
        Value::String(s) => s.trim().parse::<f64>().ok(),
        _ => None,
    };
    match x {
        Some(x) if x.is_finite() => Ok(x),
        _ => Err(bad(
            p,
            format!(
                "expected a number{}, got {v}",
                in_units(p).replace(' ', " in ")
            ),
        )),
    }
}

/// " m", " deg", …: the units as they follow a number in a message; nothing for a ratio (`1`)
/// or a count, whose units would read as a stray number ("[0.02, 0.5] 1").
fn in_units(p: &Param) -> String {
    match p.units {
        "" | "1" | "count" => String::new(),
        u => format!(" {u}"),
    }
}

fn resolve_one(p: &Param, v: &Value) -> Result<Resolved, TemplateError> {
    match p.kind {
        Kind::Number { min, max, .. } => {
            let x = as_number(p, v)?;
            if !(min..=max).contains(&x) {
                return Err(bad(
                    p,
                    format!("must be in [{min}, {max}]{}, got {x}", in_units(p)),
                ));
            }
            Ok(Resolved::Number(x))
        }
        Kind::Integer { min, max, .. } => {
            let x = as_number(p, v)?;
            if x.fract() != 0.0 {
                return Err(bad(p, format!("must be a whole number, got {x}")));
            }
            if !(min as f64..=max as f64).contains(&x) {
                return Err(bad(p, format!("must be in [{min}, {max}], got {x}")));
            }
            Ok(Resolved::Number(x))
        }
        Kind::Choice { choices, .. } => {
            let s = v.as_str().unwrap_or_default();
            choices
                .iter()
                .find(|c| **c == s)
                .map(|c| Resolved::Text(c))
                .ok_or_else(|| bad(p, format!("must be one of {}, got {v}", choices.join(", "))))
        }
        Kind::Flag { .. } => match v {
            Value::Bool(b) => Ok(Resolved::Flag(*b)),
            Value::String(s) if s == "true" || s == "false" => Ok(Resolved::Flag(s == "true")),
            _ => Err(bad(p, format!("must be true or false, got {v}"))),
        },
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn given(pairs: &[(&str, Value)]) -> BTreeMap<String, Value> {
        pairs
            .iter()
            .map(|(k, v)| (k.to_string(), v.clone()))
            .collect()
    }

    #[test]
    fn every_template_builds_a_valid_scene_at_its_defaults() {
        for t in list() {
            if let Err(e) = t.build(&BTreeMap::new()) {
                panic!("{}: {e}", t.name);
            }
        }
    }

    #[test]
    fn every_template_builds_at_its_parameters_extremes() {
        // Each parameter alone at its min and at its max, the others at their defaults: either
        // a valid scene or a Geometry error naming a parameter (never an invalid scene).
        for t in list() {
            for p in &t.parameters {
                let ends: Vec<Value> = match p.kind {
                    Kind::Number { min, max, .. } => vec![min.into(), max.into()],
                    Kind::Integer { min, max, .. } => vec![min.into(), max.into()],
                    Kind::Choice { choices, .. } => choices.iter().map(|c| (*c).into()).collect(),
                    Kind::Flag { .. } => vec![true.into(), false.into()],
                };
                for v in ends {
                    match t.build(&given(&[(p.name, v.clone())])) {
                        Ok(_) | Err(TemplateError::Geometry { .. }) => {}
                        Err(e) => panic!("{} {}={v}: {e}", t.name, p.name),
                    }
                }
            }
        }
    }

    #[test]
    fn out_of_range_and_unknown_values_name_the_parameter() {
        let e =
            build("arch", &given(&[("thickness_ratio", 0.9.into())])).expect_err("must be refused");
        assert_eq!(e.parameter(), Some("thickness_ratio"), "{e}");
        assert!(e.to_string().contains("must be in"), "{e}");
        let e =
            build("drum-column", &given(&[("drums", "7.5".into())])).expect_err("must be refused");
        assert_eq!(e.parameter(), Some("drums"), "{e}");
        let e = build("drum-column", &given(&[("drumz", 7.into())])).expect_err("must be refused");
        assert_eq!(e.parameter(), Some("drumz"), "{e}");
        let e = build("arch", &given(&[("shape", "gothic".into())])).expect_err("must be refused");
        assert!(e.to_string().contains("semicircular, pointed"), "{e}");
        let e = build("temple", &BTreeMap::new()).expect_err("must be refused");
        assert!(matches!(e, TemplateError::UnknownTemplate { .. }), "{e}");
    }

    #[test]
    fn list_serializes_name_units_default_min_max() {
        let v = serde_json::to_value(list()).unwrap_or_default();
        let p = &v[0]["parameters"][0];
        for key in ["name", "units", "default", "min", "max"] {
            assert!(p.get(key).is_some(), "{key} missing in {p}");
        }
    }
}
