//! Paleo-PGA back-analysis: the amplitude threshold at which a damage criterion is met.
//! Provisional interface; the search itself lands with its issue.
use super::run::{RunError, RunOptions};
use crate::motion::GroundMotion;
use crate::scene::Scene;
use serde::{Deserialize, Serialize};

/// One observation: `toppled:BLOCK`, `displacement:BLOCK:METRES`, `rotation:BLOCK:DEGREES`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum Criterion {
    Toppled { block: String },
    Displacement { block: String, metres: f64 },
    Rotation { block: String, degrees: f64 },
}

impl Criterion {
    /// Parse the command-line / API form.
    pub fn parse(text: &str) -> Result<Self, String> {
        let parts: Vec<&str> = text.split(':').collect();
        let num = |s: &str, what: &str| -> Result<f64, String> {
            s.parse::<f64>()
                .ok()
                .filter(|v| v.is_finite() && *v > 0.0)
                .ok_or_else(|| format!("criterion {text:?}: {what} must be a positive number, got {s:?}"))
        };
        match parts.as_slice() {
            ["toppled", b] if !b.is_empty() => Ok(Criterion::Toppled { block: b.to_string() }),
            ["displacement", b, m] if !b.is_empty() => Ok(Criterion::Displacement { block: b.to_string(), metres: num(m, "METRES")? }),
            ["rotation", b, d] if !b.is_empty() => Ok(Criterion::Rotation { block: b.to_string(), degrees: num(d, "DEGREES")? }),
            _ => Err(format!("criterion {text:?}: expected toppled:BLOCK, displacement:BLOCK:METRES or rotation:BLOCK:DEGREES")),
        }
    }
}

/// A PGA search request (amplitudes in m/s²).
#[derive(Debug, Clone, PartialEq)]
pub struct PgaRequest {
    pub criteria: Vec<Criterion>,
    pub min: f64,
    pub max: f64,
    pub tolerance: f64,
    /// Coarse scan points before bisection.
    pub scan_points: usize,
}

#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct PgaRun {
    pub pga: f64,
    pub failed: bool,
}

/// `result.json` of FORMAT.md §3.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct PgaResult {
    pub criterion: String,
    pub safe_pga: Option<f64>,
    pub failing_pga: Option<f64>,
    pub units: String,
    pub monotonic: bool,
    pub runs: Vec<PgaRun>,
}

/// Search for the threshold amplitude. Provisional until the search lands.
pub fn search(scene: &Scene, motion: &GroundMotion, req: &PgaRequest, opts: &RunOptions) -> Result<PgaResult, RunError> {
    let _ = (scene, motion, req, opts);
    Err(RunError::Simulation("the PGA search is not wired yet".into()))
}
