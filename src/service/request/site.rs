//! Request bodies: `POST /v1/site-analyses`, observations (each a criterion) × records.
use super::pga::{
    check_records_work, parse_records, search_range, summary_with_records, RangeSpec,
};
use super::RequestError;
use super::{parse_criteria, typed, JobInput, Limits, Parsed};
use crate::motion::Amplitude;
use serde::Deserialize;
use serde_json::Value;

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct SiteBody {
    scene: Value,
    /// The records (each a ground motion, optionally named), as a multi-record search's.
    motions: Vec<Value>,
    observations: Value,
    range: RangeSpec,
    #[serde(default)]
    tolerance: Option<Amplitude>,
    #[serde(default)]
    scan_points: Option<usize>,
    /// The scan resolution asked for, as a search's.
    #[serde(default)]
    resolution: Option<Amplitude>,
}

/// One observation of a site analysis: a criterion and whether its damage was seen.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct ObservationSpec {
    criterion: Value,
    /// `true`: the damage is there (a lower bound on the PGA); `false`: it is not (an upper one).
    observed: bool,
}

/// Observations of one site analysis: a site's field observations number a handful (docs/
/// observations.md), and each one is a search per record, so 50 bounds one job to 50 × 100
/// searches while the work budget bounds their runs.
pub const MAX_OBSERVATIONS: usize = 50;

/// `POST /v1/site-analyses` body → site analysis input (amplitudes converted to m/s²).
pub fn parse_site(body: &Value, limits: &Limits) -> Result<Parsed, RequestError> {
    if !body.is_object() {
        return Err(RequestError::NotAnObject {
            members: "{\"scene\", \"motions\", \"observations\", \"range\"}",
        });
    }
    let b: SiteBody = typed("", body)?;
    let (scene, records) = parse_records(&b.scene, &b.motions, limits)?;
    let items = match &b.observations {
        Value::Array(v) if !v.is_empty() => v,
        _ => return Err(RequestError::NoObservations),
    };
    if items.len() > MAX_OBSERVATIONS {
        return Err(RequestError::TooManyObservations { count: items.len() });
    }
    let mut observations = Vec::new();
    for (i, item) in items.iter().enumerate() {
        let p = format!("/observations/{i}");
        let spec: ObservationSpec = typed(&p, item)?;
        let cp = format!("{p}/criterion");
        if spec.criterion.is_array() {
            return Err(RequestError::ObservationArray { index: i });
        }
        let mut parsed = parse_criteria(&spec.criterion, &cp, &scene)?;
        let (_, criterion) = parsed.remove(0);
        observations.push(crate::analysis::observations::Observation {
            criterion,
            observed: spec.observed,
        });
    }
    let request = search_range(
        &b.range,
        b.tolerance.as_ref(),
        b.scan_points,
        b.resolution.as_ref(),
        limits,
    )?;
    // Each observation is one search per record.
    let runs = observations.len() as f64
        * crate::service::request::budget::search_runs(records.len(), &request);
    check_records_work(&scene, records.iter().map(|(_, m)| m), runs, limits)?;
    let motion = records[0].1.clone();
    let motion_summary = summary_with_records(&motion, &records);
    Ok(Parsed {
        input: JobInput::SiteAnalysis {
            scene,
            motion,
            records,
            observations,
            request,
        },
        motion_summary,
    })
}
