//! The scene file as written by users (`ashlar.scene/1`, docs/format.md §1): plain serde types.
//!
//! Every struct rejects unknown fields so a typo is an error, not a silently ignored setting.
//! Validation into the engine's model happens in [`super::validate`].
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;

#[derive(Debug, Clone, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct SceneSpec {
    pub format: String,
    #[serde(default)]
    pub name: Option<String>,
    /// m/s², acting in −y.
    #[serde(default)]
    pub gravity: Option<f64>,
    pub materials: BTreeMap<String, MaterialSpec>,
    pub joints: BTreeMap<String, JointSpec>,
    pub blocks: Vec<BlockSpec>,
    #[serde(default)]
    pub interfaces: Option<InterfacesSpec>,
    #[serde(default)]
    pub excitation: Option<ExcitationSpec>,
    #[serde(default)]
    pub initial: Vec<InitialSpec>,
    #[serde(default)]
    pub control: ControlSpec,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize, Serialize, Default)]
#[serde(rename_all = "lowercase")]
pub enum PlaneKind {
    #[default]
    Stress,
    Strain,
}

#[derive(Debug, Clone, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct MaterialSpec {
    /// kg/m³ (per unit thickness: 2D blocks are slices 1 m thick).
    pub density: f64,
    /// Pa.
    pub young_modulus: f64,
    pub poisson_ratio: f64,
    #[serde(default)]
    pub plane: PlaneKind,
}

#[derive(Debug, Clone, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct JointSpec {
    /// degrees.
    pub friction_angle: f64,
    /// Pa.
    #[serde(default)]
    pub cohesion: f64,
    /// Pa.
    #[serde(default)]
    pub tensile_strength: f64,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum BlockModel {
    /// 6 unknowns: u0, v0, r0, εx, εy, γxy.
    Deformable,
    /// 3 unknowns: u0, v0, r0.
    Rigid,
}

/// `control.block_model`: a model for every free block that does not name its own, or
/// `"auto"`: chosen per block from the scene (`scene::block_model`, docs/format.md).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum BlockModelChoice {
    /// Rigid where strain cannot change the answer by more than the stated bound, else
    /// deformable ([`crate::scene::block_model::AutoBlockModelParams`]).
    Auto,
    Deformable,
    Rigid,
}

#[derive(Debug, Clone, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct BlockSpec {
    pub id: String,
    pub material: String,
    #[serde(default)]
    pub fixed: bool,
    pub vertices: Vec<[f64; 2]>,
    #[serde(default)]
    pub block_model: Option<BlockModel>,
}

#[derive(Debug, Clone, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct InterfacesSpec {
    #[serde(default)]
    pub default: Option<String>,
    #[serde(default)]
    pub pairs: Vec<InterfacePairSpec>,
}

#[derive(Debug, Clone, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct InterfacePairSpec {
    pub blocks: [String; 2],
    pub joint: String,
}

#[derive(Debug, Clone, Deserialize, Serialize, PartialEq)]
#[serde(tag = "type", rename_all = "snake_case", deny_unknown_fields)]
pub enum ExcitationSpec {
    BaseAcceleration,
    DrivenBlock { block: String },
}

#[derive(Debug, Clone, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct InitialSpec {
    pub block: String,
    /// m/s.
    #[serde(default)]
    pub velocity: [f64; 2],
    /// rad/s, counter-clockwise positive.
    #[serde(default)]
    pub angular_velocity: f64,
}

/// `penalty_stiffness`: a number (N/m) or `"auto"`.
#[derive(Debug, Clone, Copy, PartialEq, Deserialize, Serialize)]
#[serde(untagged)]
pub enum PenaltySpec {
    Value(f64),
    Keyword(PenaltyKeyword),
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum PenaltyKeyword {
    Auto,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Integrator {
    /// Newmark β = 1/2, γ = 1 (Shi's original; dissipative).
    Dda,
    /// Newmark β = 1/4, γ = 1/2 (energy conserving).
    Trapezoidal,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum ContactSolver {
    Penalty,
    Dual,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum ModelChoice {
    Dda,
    Auto,
    Rocking,
    Sliding,
}

#[derive(Debug, Clone, Default, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct ControlSpec {
    pub duration: Option<f64>,
    pub time_step: Option<f64>,
    pub adaptive_time_step: Option<bool>,
    pub max_displacement_ratio: Option<f64>,
    pub penalty_stiffness: Option<PenaltySpec>,
    pub dynamic_factor: Option<f64>,
    pub kinetic_damping_rate: Option<f64>,
    pub integrator: Option<Integrator>,
    pub contact_solver: Option<ContactSolver>,
    pub block_model: Option<BlockModelChoice>,
    pub model: Option<ModelChoice>,
    pub output_interval: Option<f64>,
    /// Extension: hard cap on the number of steps (protects against runaway runs).
    pub max_steps: Option<u64>,
    /// Extension: the dual solver's stopping tolerance, a fraction of the smallest free
    /// block's half size. Skipped when unset, like the next one: the spec is written into
    /// every recording's metadata, whose bytes must not change for scenes without them
    /// (tests/record/record_golden_run.rs).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub dual_tolerance: Option<f64>,
    /// Extension: the multiple of `dual_tolerance` up to which a stalled dual solve is taken.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub dual_stall_acceptance: Option<f64>,
    /// Extension: the shortest step a non-converging contact loop is cut to, a fraction of
    /// `time_step` (0: no floor). Skipped when unset, like the two above.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub unconverged_floor: Option<f64>,
    /// Restitution of impacts: `"housner"` or a coefficient in [0, 1] (docs/format.md §
    /// controls). Skipped when unset, like the three above.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub restitution: Option<RestitutionSpec>,
}

/// `control.restitution` as written: a number (validated into [0, 1] by `validate`) or the
/// keyword `"housner"`. Deserialized by hand so that a wrong string or type says what is
/// expected instead of serde's "did not match any variant".
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum RestitutionSpec {
    Housner,
    Contact,
    Coefficient(f64),
}

impl Serialize for RestitutionSpec {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        match self {
            RestitutionSpec::Housner => s.serialize_str("housner"),
            RestitutionSpec::Contact => s.serialize_str("contact"),
            RestitutionSpec::Coefficient(e) => s.serialize_f64(*e),
        }
    }
}

impl<'de> Deserialize<'de> for RestitutionSpec {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct Visitor;
        impl serde::de::Visitor<'_> for Visitor {
            type Value = RestitutionSpec;
            fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
                f.write_str("a coefficient of restitution in [0, 1], \"housner\" or \"contact\"")
            }
            fn visit_f64<E: serde::de::Error>(self, v: f64) -> Result<Self::Value, E> {
                Ok(RestitutionSpec::Coefficient(v))
            }
            fn visit_u64<E: serde::de::Error>(self, v: u64) -> Result<Self::Value, E> {
                Ok(RestitutionSpec::Coefficient(v as f64))
            }
            fn visit_i64<E: serde::de::Error>(self, v: i64) -> Result<Self::Value, E> {
                Ok(RestitutionSpec::Coefficient(v as f64))
            }
            fn visit_str<E: serde::de::Error>(self, v: &str) -> Result<Self::Value, E> {
                match v {
                    "housner" => Ok(RestitutionSpec::Housner),
                    "contact" => Ok(RestitutionSpec::Contact),
                    _ => Err(E::invalid_value(serde::de::Unexpected::Str(v), &self)),
                }
            }
        }
        d.deserialize_any(Visitor)
    }
}
