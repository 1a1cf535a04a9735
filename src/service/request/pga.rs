//! Request bodies: `POST /v1/pga-searches`, a PGA search over one record or several (the
//! records and the search range are shared with site analyses).
use super::RequestError;
use super::{motion_summary, parse_criteria, scene_and_motion, typed, JobInput, Limits, Parsed};
use crate::analysis::fragility::Method;
use crate::analysis::pga::Criterion;
use crate::analysis::pga::{default_resolution, Combine, PgaRequest, ScanOrder};
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

// `range`, `tolerance`, `scan_points` and `resolution` are declared here and again in
// `site::SiteBody`, not in one shared struct: they are top-level members of both bodies
// (openapi.yaml), so one struct would take `#[serde(flatten)]`. With serde 1.0.229 and
// serde_path_to_error 0.1.20 (checked on a scratch crate, session 40), an outer
// `deny_unknown_fields` still refuses an unknown member through `flatten`, but every error
// inside the flattened part loses its path: `"tolerance": "abc"`, `"range": {"max": "x"}` and
// `"scan_points": -3` are reported at the body's root instead of `/tolerance`, `/range/max` and
// `/scan_points` (the 422's pointer, which the web page puts beside the field), and an unknown
// member's message loses its list of the expected ones. Nesting them in a member of their own
// would change the contract. What they mean is shared: `RangeSpec` and `search_range`.
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
    /// A number in `range.units`, or a string with its own units ("0.05g"): the scan
    /// resolution asked for (instead of `scan_points`; default [`default_resolution`]).
    #[serde(default)]
    resolution: Option<Amplitude>,
    /// `"full"` or `"lowest"` ([`ScanOrder`]).
    #[serde(default)]
    scan: Option<String>,
}

/// Scan points of a PGA search over a wide range that asks for neither a resolution nor scan
/// points (as `ashlar pga`; [`crate::analysis::pga::default_resolution`]).
pub const DEFAULT_SCAN_POINTS: usize = crate::analysis::pga::DEFAULT_SCAN_POINTS;

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
    let range = search_range(
        &b.range,
        b.tolerance.as_ref(),
        b.scan_points,
        b.resolution.as_ref(),
        limits,
    )?;
    let request = PgaRequest {
        criteria,
        combine,
        scan,
        ..range
    };
    let runs = crate::service::request::budget::search_runs(records.len(), &request);
    let motions = records
        .iter()
        .map(|(_, m)| m)
        .chain(std::iter::once(&motion));
    check_records_work(&scene, motions, runs, limits)?;
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

/// The searched range of a request (`range`, `tolerance`, `scan_points`, `resolution`),
/// amplitudes in m/s²: a request with no criterion and a full scan, each error naming its
/// field. The resolution asked for: `resolution`, else that of `scan_points`, else
/// [`default_resolution`]; the scan points it asks for (span / resolution + 1) within
/// `max_scan_points` (the lattice may hold up to twice as many, which the work budget counts).
pub(super) fn search_range(
    range: &RangeSpec,
    tolerance: Option<&Amplitude>,
    scan_points: Option<usize>,
    resolution: Option<&Amplitude>,
    limits: &Limits,
) -> Result<PgaRequest, RequestError> {
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
    // The CLI's default, absolute: a tolerance relative to the range (1 % of it until session
    // 39) made the lattice, and so the answer, depend on the range.
    let tolerance = match tolerance {
        Some(t) => amplitude(t, "/tolerance")?,
        None => crate::analysis::pga::DEFAULT_TOLERANCE,
    };
    if !(tolerance.is_finite() && tolerance > 0.0) {
        return Err(RequestError::Tolerance);
    }
    let resolution = match (resolution, scan_points) {
        (Some(_), Some(_)) => return Err(RequestError::ResolutionAndScanPoints),
        (Some(r), None) => {
            let r = amplitude(r, "/resolution")?;
            if !(r.is_finite() && r > 0.0) {
                return Err(RequestError::Resolution);
            }
            Some(r)
        }
        (None, Some(_)) => None,
        (None, None) => Some(default_resolution(min, max)),
    };
    let scan_points = scan_points.unwrap_or(DEFAULT_SCAN_POINTS);
    if !(2..=limits.max_scan_points).contains(&scan_points) {
        return Err(RequestError::ScanPoints {
            got: scan_points,
            limit: limits.max_scan_points,
        });
    }
    if let Some(r) = resolution {
        // The points asked for, within a part in 10⁹ (a span that is a multiple of `r`).
        let asked = ((max - min) / r * (1.0 - 1e-9)).ceil() + 1.0;
        if asked > limits.max_scan_points as f64 {
            return Err(RequestError::ResolutionPoints {
                got: asked.min(usize::MAX as f64) as usize,
                limit: limits.max_scan_points,
            });
        }
    }
    Ok(PgaRequest {
        criteria: Vec::new(),
        combine: Combine::All,
        min,
        max,
        tolerance,
        scan_points,
        resolution,
        scan: ScanOrder::Full,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn range(body: Value) -> Result<PgaRequest, RequestError> {
        #[derive(Deserialize)]
        struct Body {
            range: RangeSpec,
            #[serde(default)]
            tolerance: Option<Amplitude>,
            #[serde(default)]
            scan_points: Option<usize>,
            #[serde(default)]
            resolution: Option<Amplitude>,
        }
        let b: Body = serde_json::from_value(body).expect("body");
        search_range(
            &b.range,
            b.tolerance.as_ref(),
            b.scan_points,
            b.resolution.as_ref(),
            &Limits::default(),
        )
    }

    #[test]
    fn the_resolution_is_asked_for_or_defaulted_and_checked() {
        let r = |extra: Value| {
            let mut b = serde_json::json!({"range": {"min": 0.05, "max": 2.0, "units": "g"},
                                           "tolerance": 0.01});
            if let (Some(o), Value::Object(e)) = (b.as_object_mut(), extra) {
                o.extend(e);
            }
            range(b)
        };
        // Neither: the default resolution (0.64 m/s² over a range narrower than 25 m/s²).
        let d = r(serde_json::json!({})).expect("default");
        assert_eq!(d.resolution, Some(crate::analysis::pga::DEFAULT_RESOLUTION));
        // In the range's units, or with its own.
        let g = r(serde_json::json!({"resolution": 0.05})).expect("in g");
        assert_eq!(g.resolution, Some(0.05 * crate::motion::STANDARD_GRAVITY));
        let own = r(serde_json::json!({"resolution": "0.32m/s2"})).expect("with units");
        assert_eq!(own.resolution, Some(0.32));
        // Scan points instead: the resolution follows from them.
        let n = r(serde_json::json!({"scan_points": 12})).expect("points");
        assert_eq!((n.resolution, n.scan_points), (None, 12));
        for (extra, want) in [
            (
                serde_json::json!({"resolution": 0.5, "scan_points": 8}),
                "not both",
            ),
            (serde_json::json!({"resolution": 0}), "> 0"),
            // 19.1 m/s² at 0.1 m/s² asks for 193 points, over the default limit of 64.
            (
                serde_json::json!({"resolution": "0.1m/s2"}),
                "193 scan points",
            ),
        ] {
            let text = r(extra).expect_err("refused").to_string();
            assert!(
                text.starts_with("/resolution") && text.contains(want),
                "{text}"
            );
        }
    }
}
