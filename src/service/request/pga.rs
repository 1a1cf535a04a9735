//! Request bodies: `POST /v1/pga-searches`, a PGA search over one record or several (the
//! records and the search range are shared with site analyses).
use super::RequestError;
use super::{motion_summary, parse_criteria, scene_and_motion, typed, JobInput, Limits, Parsed};
use crate::analysis::fragility::Method;
use crate::analysis::pga::Criterion;
use crate::analysis::pga::{Combine, PgaRequest, ScanOrder};
use crate::motion::GroundMotion;
use crate::motion::{Amplitude, Units};
use crate::scene::Scene;
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
    /// `"full"` or `"lowest"` ([`ScanOrder`]).
    #[serde(default)]
    scan: Option<String>,
}

/// Scan points of a PGA search when the request does not say (as `ashlar pga`): 40 puts
/// them 0.49 m/s² apart over 0.05–2 g, finer than the failing intervals of a rocking column
/// under the bundled records (docs/pga.md); the search reports this resolution.
pub const DEFAULT_SCAN_POINTS: usize = 40;

/// Records of one multi-record search: 100 is more than any fragility study uses (FEMA P695
/// has 44), and bounds one job to 100 searches; the body-size limit bounds their samples.
pub const MAX_RECORDS: usize = 100;

/// The records of `"motions"`: each a GroundMotion, optionally with a `"name"` (default
/// `motions/{i}`), parsed with the same rules as `"motion"`.
pub(super) fn parse_records(
    scene: &Value,
    items: &[Value],
    limits: &Limits,
) -> Result<(Scene, Vec<(String, GroundMotion)>), RequestError> {
    if items.is_empty() {
        return Err(RequestError::NoRecords);
    }
    if items.len() > MAX_RECORDS {
        return Err(RequestError::TooManyRecords { count: items.len() });
    }
    let mut parsed_scene = None;
    let mut records = Vec::new();
    for (i, item) in items.iter().enumerate() {
        let mut item = item.clone();
        let name = match item.as_object_mut().and_then(|o| o.remove("name")) {
            None => format!("motions/{i}"),
            Some(Value::String(n)) if !n.trim().is_empty() => n,
            Some(_) => return Err(RequestError::RecordName { index: i }),
        };
        if item.is_null() {
            return Err(RequestError::RecordMissing { index: i });
        }
        let (sc, motion) =
            scene_and_motion(scene, Some(&item), limits).map_err(|e| RequestError::InRecord {
                index: i,
                source: Box::new(e),
            })?;
        if motion.horizontal.peak() <= 0.0 {
            return Err(RequestError::ZeroHorizontal {
                pointer: format!("/motions/{i}/horizontal"),
            });
        }
        if records.iter().any(|(n, _)| *n == name) {
            return Err(RequestError::DuplicateRecord { index: i, name });
        }
        parsed_scene.get_or_insert(sc);
        records.push((name, motion));
    }
    let scene = parsed_scene.ok_or(RequestError::NoRecords)?;
    Ok((scene, records))
}

/// `POST /v1/pga-searches` body → search input (amplitudes converted to m/s²).
pub fn parse_pga(body: &Value, limits: &Limits) -> Result<Parsed, RequestError> {
    if !body.is_object() {
        return Err(RequestError::NotAnObject {
            members: "{\"scene\", \"motion\", \"criterion\", \"range\", \"tolerance\"}",
        });
    }
    let b: PgaBody = typed("", body)?;
    let (scene, motion, records) = match &b.motions {
        Some(items) => {
            if !b.motion.is_null() {
                return Err(RequestError::MotionAndMotions);
            }
            let (scene, records) = parse_records(&b.scene, items, limits)?;
            (scene, records[0].1.clone(), records)
        }
        None => {
            if b.motion.is_null() {
                return Err(RequestError::NoMotion);
            }
            let (scene, motion) = scene_and_motion(&b.scene, Some(&b.motion), limits)?;
            (scene, motion, Vec::new())
        }
    };
    let combine = match &b.combine {
        None => Combine::All,
        Some(t) => Combine::parse(t).map_err(RequestError::Combine)?,
    };
    let scan = match &b.scan {
        None => ScanOrder::Full,
        Some(t) => ScanOrder::parse(t).map_err(RequestError::Scan)?,
    };
    let fit = match &b.fit {
        None => Method::Interval,
        Some(t) => Method::parse(t).map_err(RequestError::Fit)?,
    };
    if b.fit.is_some() && records.is_empty() {
        return Err(RequestError::FitNeedsRecords);
    }
    if motion.horizontal.peak() <= 0.0 {
        return Err(RequestError::ZeroHorizontal {
            pointer: "/motion/horizontal".into(),
        });
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
    let motions = records
        .iter()
        .map(|(_, m)| m)
        .chain(std::iter::once(&motion));
    check_records_work(&scene, motions, runs, limits)?;
    let request = PgaRequest {
        criteria,
        combine,
        min,
        max,
        tolerance,
        scan_points,
        scan,
    };
    let motion_summary = summary_with_records(&motion, &records);
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

/// The work budget of a search over `motions` (`runs` runs): the longest record sets the length
/// of every run (a scene's own duration overrides it, as in `analysis::run::duration`).
pub(super) fn check_records_work<'a>(
    scene: &Scene,
    motions: impl Iterator<Item = &'a GroundMotion>,
    runs: f64,
    limits: &Limits,
) -> Result<(), RequestError> {
    let duration = motions
        .filter_map(|m| crate::analysis::run::duration(scene, m).ok())
        .fold(scene.control.duration.unwrap_or(0.0), f64::max);
    let steps = (duration / scene.control.time_step).ceil();
    crate::service::request::budget::check_search_work(runs, scene.blocks.len(), steps, limits)
}

/// The summary of `motion` (a search's first record) with every record's name and intensity
/// beside it (`records`, when there are any).
pub(super) fn summary_with_records(
    motion: &GroundMotion,
    records: &[(String, GroundMotion)],
) -> Value {
    let mut summary = motion_summary(motion);
    if let (false, Some(obj)) = (records.is_empty(), summary.as_object_mut()) {
        let list: Vec<Value> = records
            .iter()
            .map(|(name, m)| {
                serde_json::json!({"name": name, "pga": m.pga(), "duration": m.duration(), "provenance": m.provenance})
            })
            .collect();
        obj.insert("records".into(), Value::Array(list));
    }
    summary
}

/// The searched range of a request (`range`, `tolerance`, `scan_points`), amplitudes in m/s²:
/// (min, max, tolerance, scan points), each error naming its field.
pub(super) fn search_range(
    range: &RangeSpec,
    tolerance: Option<&Amplitude>,
    scan_points: Option<usize>,
    limits: &Limits,
) -> Result<(f64, f64, f64, usize), RequestError> {
    // Amplitudes in m/s² from here on.
    let units = range.units;
    let amplitude = |a: &Amplitude, p: &str| {
        a.to_si(units).map_err(|source| RequestError::Amplitude {
            pointer: p.to_string(),
            source,
        })
    };
    let min = amplitude(&range.min, "/range/min")?;
    let max = amplitude(&range.max, "/range/max")?;
    if !(max.is_finite() && max > min) {
        return Err(RequestError::RangeOrder { min, max });
    }
    // Default resolution: 1 % of the searched range.
    let tolerance = match tolerance {
        Some(t) => amplitude(t, "/tolerance")?,
        None => (max - min) / 100.0,
    };
    if !(tolerance.is_finite() && tolerance > 0.0) {
        return Err(RequestError::Tolerance);
    }
    let scan_points = scan_points.unwrap_or(DEFAULT_SCAN_POINTS);
    if !(2..=limits.max_scan_points).contains(&scan_points) {
        return Err(RequestError::ScanPoints {
            got: scan_points,
            limit: limits.max_scan_points,
        });
    }
    Ok((min, max, tolerance, scan_points))
}
