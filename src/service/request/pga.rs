//! Request bodies: `POST /v1/pga-searches`, a PGA search over one record or several (the
//! records and the search range are shared with site analyses).
use super::{motion_summary, parse_criteria, scene_and_motion, typed, JobInput, Limits, Parsed};
use crate::analysis::fragility::Method;
use crate::analysis::pga::Criterion;
use crate::analysis::pga::{Combine, PgaRequest};
use crate::motion::GroundMotion;
use crate::motion::{Amplitude, Units};
use crate::scene::Scene;
use crate::service::http::problem::ApiError;
use serde::Deserialize;
use serde_json::Value;

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct RangeSpec {
    /// A number in `units`, or a string with its own units ("0.05g").
    min: Amplitude,
    max: Amplitude,
    /// Units of numeric `min`, `max` and `tolerance` (m/s² by default).
    #[serde(default = "default_units")]
    units: Units,
}

fn default_units() -> Units {
    Units::MetresPerSecond2
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct PgaBody {
    scene: Value,
    #[serde(default)]
    motion: Value,
    /// Several records (a fragility study) instead of `motion`.
    #[serde(default)]
    motions: Option<Vec<Value>>,
    criterion: Value,
    #[serde(default)]
    combine: Option<String>,
    #[serde(default)]
    fit: Option<String>,
    range: RangeSpec,
    /// A number in `range.units`, or a string with its own units ("0.01g").
    #[serde(default)]
    tolerance: Option<Amplitude>,
    #[serde(default)]
    scan_points: Option<usize>,
}

/// Scan points of a PGA search when the request does not say (as `ashlar pga`): 40 puts
/// them 0.49 m/s² apart over 0.05–2 g, finer than the failing intervals of a rocking column
/// under the bundled records (docs/pga.md); the search reports this resolution.
pub const DEFAULT_SCAN_POINTS: usize = 40;

/// Records of one multi-record search: 100 is more than any fragility study uses (FEMA P695
/// has 44), and bounds one job to 100 searches; the body-size limit bounds their samples.
pub const MAX_RECORDS: usize = 100;

/// Re-point an error of the single-motion parser at `/motions/{i}`.
pub(super) fn at_record(e: ApiError, i: usize) -> ApiError {
    let re = |t: &str| t.replacen("/motion", &format!("/motions/{i}"), 1);
    ApiError {
        detail: re(&e.detail),
        pointer: e.pointer.as_deref().map(re),
        ..e
    }
}

/// The records of `"motions"`: each a GroundMotion, optionally with a `"name"` (default
/// `motions/{i}`), parsed with the same rules as `"motion"`.
pub(super) fn parse_records(
    scene: &Value,
    items: &[Value],
    limits: &Limits,
) -> Result<(Scene, Vec<(String, GroundMotion)>), ApiError> {
    if items.is_empty() {
        return Err(ApiError::invalid_field(
            "/motions",
            "/motions: give at least one record",
        ));
    }
    if items.len() > MAX_RECORDS {
        return Err(ApiError::limit_exceeded(
            "/motions",
            format!(
                "/motions: {} records exceed the limit of {MAX_RECORDS} per search",
                items.len()
            ),
        ));
    }
    let mut parsed_scene = None;
    let mut records = Vec::new();
    for (i, item) in items.iter().enumerate() {
        let mut item = item.clone();
        let name = match item.as_object_mut().and_then(|o| o.remove("name")) {
            None => format!("motions/{i}"),
            Some(Value::String(n)) if !n.trim().is_empty() => n,
            Some(_) => {
                let p = format!("/motions/{i}/name");
                return Err(ApiError::invalid_field(
                    p.clone(),
                    format!("{p}: must be a non-empty string"),
                ));
            }
        };
        if item.is_null() {
            let p = format!("/motions/{i}");
            return Err(ApiError::invalid_field(
                p.clone(),
                format!("{p}: a record is required"),
            ));
        }
        let (sc, motion) =
            scene_and_motion(scene, Some(&item), limits).map_err(|e| at_record(e, i))?;
        if motion.horizontal.peak() <= 0.0 {
            let p = format!("/motions/{i}/horizontal");
            return Err(ApiError::invalid_field(
                p.clone(),
                format!(
                    "{p}: a PGA search scales the horizontal component, which is missing or zero"
                ),
            ));
        }
        if records.iter().any(|(n, _)| *n == name) {
            let p = format!("/motions/{i}/name");
            return Err(ApiError::invalid_field(
                p.clone(),
                format!("{p}: {name:?} names an earlier record too"),
            ));
        }
        parsed_scene.get_or_insert(sc);
        records.push((name, motion));
    }
    let scene =
        parsed_scene.ok_or_else(|| ApiError::invalid_field("/motions", "/motions: empty"))?;
    Ok((scene, records))
}

/// `POST /v1/pga-searches` body → search input (amplitudes converted to m/s²).
pub fn parse_pga(body: &Value, limits: &Limits) -> Result<Parsed, ApiError> {
    if !body.is_object() {
        return Err(ApiError::invalid_field(
            "",
            "the body must be a JSON object {\"scene\", \"motion\", \"criterion\", \"range\", \"tolerance\"}",
        ));
    }
    let b: PgaBody = typed("", body)?;
    let (scene, motion, records) = match &b.motions {
        Some(items) => {
            if !b.motion.is_null() {
                return Err(ApiError::invalid_field(
                    "/motions",
                    "/motions: give either \"motion\" (one record) or \"motions\" (several), not both",
                ));
            }
            let (scene, records) = parse_records(&b.scene, items, limits)?;
            (scene, records[0].1.clone(), records)
        }
        None => {
            if b.motion.is_null() {
                return Err(ApiError::invalid_field(
                    "/motion",
                    "/motion: a PGA search needs a ground motion to scale (or \"motions\": several records)",
                ));
            }
            let (scene, motion) = scene_and_motion(&b.scene, Some(&b.motion), limits)?;
            (scene, motion, Vec::new())
        }
    };
    let combine = match &b.combine {
        None => Combine::All,
        Some(t) => {
            Combine::parse(t).map_err(|e| ApiError::invalid_field("/combine", format!("/{e}")))?
        }
    };
    let fit = match &b.fit {
        None => Method::Interval,
        Some(t) => {
            Method::parse(t).map_err(|e| ApiError::invalid_field("/fit", format!("/fit: {e}")))?
        }
    };
    if b.fit.is_some() && records.is_empty() {
        return Err(ApiError::invalid_field(
            "/fit",
            "/fit: a fragility fit needs several records (\"motions\")",
        ));
    }
    if motion.horizontal.peak() <= 0.0 {
        return Err(ApiError::invalid_field(
            "/motion/horizontal",
            "/motion/horizontal: a PGA search scales the horizontal component, which is missing or zero",
        ));
    }
    let (texts, criteria): (Vec<String>, Vec<Criterion>) =
        parse_criteria(&b.criterion, "/criterion", &scene)?
            .into_iter()
            .unzip();
    let (min, max, tolerance, scan_points) =
        search_range(&b.range, b.tolerance.as_ref(), b.scan_points, limits)?;
    let runs = crate::service::request::budget::search_runs(
        records.len(),
        scan_points,
        max - min,
        tolerance,
    );
    // The longest record sets the length of every run (a scene's own duration overrides it).
    let duration = scene.control.duration.unwrap_or_else(|| {
        records
            .iter()
            .map(|(_, m)| m)
            .chain(std::iter::once(&motion))
            .filter_map(|m| m.duration().map(|d| d + 2.0))
            .fold(0.0, f64::max)
    });
    let steps = (duration / scene.control.time_step).ceil();
    crate::service::request::budget::check_search_work(runs, scene.blocks.len(), steps, limits)?;
    let request = PgaRequest {
        criteria,
        combine,
        min,
        max,
        tolerance,
        scan_points,
    };
    let mut motion_summary = motion_summary(&motion);
    if let (false, Some(obj)) = (records.is_empty(), motion_summary.as_object_mut()) {
        // The first record's summary, and every record's name and intensity.
        let list: Vec<Value> = records
            .iter()
            .map(|(name, m)| {
                serde_json::json!({"name": name, "pga": m.pga(), "duration": m.duration(), "provenance": m.provenance})
            })
            .collect();
        obj.insert("records".into(), Value::Array(list));
    }
    let joined = texts.join(",");
    let criterion = match combine {
        Combine::Any if texts.len() > 1 => format!("any({joined})"),
        _ => joined,
    };
    Ok(Parsed {
        input: JobInput::PgaSearch {
            scene,
            motion,
            request,
            criterion,
            records,
            fit,
        },
        motion_summary,
    })
}

/// The searched range of a request (`range`, `tolerance`, `scan_points`), amplitudes in m/s²:
/// (min, max, tolerance, scan points), each error naming its field.
pub(super) fn search_range(
    range: &RangeSpec,
    tolerance: Option<&Amplitude>,
    scan_points: Option<usize>,
    limits: &Limits,
) -> Result<(f64, f64, f64, usize), ApiError> {
    // Amplitudes in m/s² from here on.
    let units = range.units;
    let amplitude = |a: &Amplitude, p: &str| {
        a.to_si(units)
            .map_err(|e| ApiError::invalid_field(p, format!("{p}: {e}")))
    };
    let min = amplitude(&range.min, "/range/min")?;
    let max = amplitude(&range.max, "/range/max")?;
    if !(max.is_finite() && max > min) {
        return Err(ApiError::invalid_field(
            "/range/max",
            format!(
                "/range/max: must be finite and > range.min, got {} m/s² ≤ {} m/s²",
                crate::quantity::sig(max),
                crate::quantity::sig(min)
            ),
        ));
    }
    // Default resolution: 1 % of the searched range.
    let tolerance = match tolerance {
        Some(t) => amplitude(t, "/tolerance")?,
        None => (max - min) / 100.0,
    };
    if !(tolerance.is_finite() && tolerance > 0.0) {
        return Err(ApiError::invalid_field(
            "/tolerance",
            "/tolerance: must be a finite amplitude > 0",
        ));
    }
    let scan_points = scan_points.unwrap_or(DEFAULT_SCAN_POINTS);
    if !(2..=limits.max_scan_points).contains(&scan_points) {
        return Err(ApiError::invalid_field(
            "/scan_points",
            format!(
                "/scan_points: must lie in 2..={}, got {scan_points}",
                limits.max_scan_points
            ),
        ));
    }
    Ok((min, max, tolerance, scan_points))
}
