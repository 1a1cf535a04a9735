//! HTTP layer: `POST /v1/motions/inspect`, a ground motion's intensity measures, spectrum and
//! scaled series before a job is submitted (the `ashlar motion` JSON). Errors point into the
//! body, which is the ground motion itself.
use super::problem::{dotted_to_pointer, ApiError};
use super::state::{blocking, check_json_content_type, ApiResult, AppState};
use super::web::{ground_series, query_usize, WebParams};
use super::Route;
use crate::motion::{report_with, ReportParams, Signal};
use crate::service::request::json_body;
use axum::body::Bytes;
use axum::extract::rejection::{BytesRejection, QueryRejection};
use axum::extract::{Query, State};
use axum::http::{HeaderMap, Method};
use axum::response::IntoResponse;
use axum::routing::post;
use serde_json::{json, Value};

/// The routes of this resource: method, path, handler.
pub fn routes() -> Vec<Route> {
    vec![(Method::POST, "/v1/motions/inspect", post(inspect))]
}

/// This resource's router.
pub fn router() -> axum::Router<AppState> {
    super::router_of(routes())
}

/// A motion error's origin (`motion.horizontal.pulse`) as a pointer into the inspected body,
/// which is the ground motion itself (`/horizontal/pulse`); serde's "unknown/missing field
/// `x`" messages point one level further.
fn motion_pointer(origin: &str, message: &str, body: &Value) -> String {
    let full = dotted_to_pointer("", origin);
    let mut p = full
        .strip_prefix("/motion")
        .map(str::to_string)
        .unwrap_or(full);
    // The parser names an analytic component (`/horizontal`) for errors inside its `pulse` or
    // `sine` object: point at that object.
    if let Some(c) = p.strip_prefix('/').and_then(|name| body.get(name)) {
        if let Some(form) = ["pulse", "sine"].into_iter().find(|f| c.get(f).is_some()) {
            p = format!("{p}/{form}");
        }
    }
    for marker in ["missing field `", "unknown field `"] {
        if let Some(name) = message
            .strip_prefix(marker)
            .and_then(|r| r.split('`').next())
        {
            let seg = format!("/{}", name.replace('~', "~0").replace('/', "~1"));
            if !p.ends_with(&seg) {
                p.push_str(&seg);
            }
        }
    }
    p
}

fn evaluated_samples(sig: &Signal, p: &ReportParams) -> f64 {
    match sig {
        Signal::Zero => 0.0,
        Signal::Sampled(s) => s.accel.len() as f64,
        other => other.duration().unwrap_or(p.steady_duration) / p.analytic_dt,
    }
}

/// Every number finite. serde_json writes a non-finite float as `null`, so a `null` counts as
/// non-finite: call this only on values that hold numbers alone.
fn all_finite(v: &Value) -> bool {
    match v {
        Value::Number(n) => n.as_f64().is_some_and(f64::is_finite),
        Value::Array(a) => a.iter().all(all_finite),
        Value::Object(o) => o.values().all(all_finite),
        Value::Null => false,
        _ => true,
    }
}

/// Intensity measures (the `ashlar motion` JSON) of a ground motion, plus the scaled horizontal
/// acceleration as `series` (at most `points` + 1 uniform samples) for a plot.
pub fn inspect_motion(
    body: &Value,
    max_record_samples: usize,
    points: usize,
) -> Result<Value, ApiError> {
    if !body.is_object() {
        return Err(ApiError::invalid_field(
            "",
            "the body must be a ground motion object {\"horizontal\": …, \"vertical\": …, \"scale\": …} (docs/format.md §2)",
        ));
    }
    // Values outside docs/format.md "Ranges", as a submission's motion (pointers relative to
    // the body: `/horizontal/pulse/amplitude`).
    crate::service::request::budget::check_motion_ranges("", body)?;
    // Read as a `MotionSpec` (unknown members, members of another form and nulls refused),
    // without the command-line extension `processing`.
    let problem = |e: crate::motion::MotionError| {
        ApiError::motion(motion_pointer(&e.origin, &e.message, body), e)
    };
    let spec = crate::motion::MotionSpec::from_value(body).map_err(problem)?;
    for (name, c) in spec.components() {
        if let Some(e) = c.processing_refused(&format!("motion.{name}")) {
            return Err(problem(e));
        }
    }
    let gm = spec.build(&Default::default()).map_err(problem)?;
    if matches!(gm.horizontal, Signal::Zero) {
        return Err(ApiError::invalid_field(
            "/horizontal",
            "/horizontal: nothing to inspect: the horizontal component is missing",
        ));
    }
    let rp = ReportParams::default();
    let n = evaluated_samples(&gm.horizontal, &rp);
    if n > max_record_samples as f64 {
        let p = match gm.horizontal {
            Signal::Sampled(_) => "/horizontal",
            Signal::Pulse { .. } => "/horizontal/pulse/cycles",
            _ => "/horizontal/sine",
        };
        return Err(ApiError::limit_exceeded(
            p,
            format!(
                "{p}: {n:.0} samples to evaluate exceed the server's limit of {max_record_samples} (ashlar serve --max-record-samples)"
            ),
        ));
    }
    if let Signal::Sampled(s) = &gm.horizontal {
        let periods = crate::motion::log_periods(rp.period_range.0, rp.period_range.1, rp.periods);
        let work: f64 = periods
            .iter()
            .map(|t| (20.0 * s.dt / t).ceil().clamp(1.0, 10_000.0))
            .sum::<f64>()
            * n;
        if work > WebParams::default().inspect_budget {
            return Err(ApiError::limit_exceeded(
                "/horizontal",
                format!(
                    "/horizontal: {n:.0} samples at a step of {} s need {work:.1e} oscillator steps for the spectrum, over the server's budget of {:.0e}",
                    crate::quantity::sig(s.dt),
                    WebParams::default().inspect_budget
                ),
            ));
        }
    }
    let im = report_with(&gm, &rp);
    let measures_finite = [
        im.dt,
        im.duration,
        im.pga,
        im.pga_original_units,
        im.pgv,
        im.pgd,
        im.arias_intensity,
        im.significant_duration_5_95,
        im.cav,
        im.mean_period,
    ]
    .iter()
    .chain(&im.spectrum.psa)
    .all(|v| v.is_finite());
    let mut out = serde_json::to_value(&im).map_err(ApiError::internal)?;
    let duration = gm.duration().unwrap_or(rp.steady_duration);
    let native = (im.npts.max(2) - 1).max(1);
    let series = ground_series(&gm, duration, points.min(native));
    let pointer = if gm.scale != 1.0 {
        "/scale"
    } else {
        "/horizontal"
    };
    if !measures_finite || !all_finite(&series["time"]) || !all_finite(&series["acceleration"]) {
        return Err(ApiError::invalid_field(
            pointer,
            format!("{pointer}: the scaled record overflows (values beyond the range of a double)"),
        ));
    }
    out["scale"] = json!(gm.scale);
    out["units"]["scale"] = json!("1");
    out["units"]["series"] = json!({"time": "s", "acceleration": "m/s2"});
    out["series"] = json!({
        "time": series["time"],
        "acceleration": series["acceleration"],
    });
    Ok(out)
}

/// `POST /v1/motions/inspect?points=N`: the record's intensity measures and spectrum before a
/// job is submitted. Errors point into the body (the ground motion).
pub async fn inspect(
    State(s): State<AppState>,
    headers: HeaderMap,
    query: Result<Query<Vec<(String, String)>>, QueryRejection>,
    body: Result<Bytes, BytesRejection>,
) -> ApiResult {
    let Query(query) = query.map_err(|e| ApiError::invalid_parameter("query", e.body_text()))?;
    let p = WebParams::default();
    let points = query_usize(&query, "points", p.series_points, p.max_series_points)?;
    check_json_content_type(&headers)?;
    let max_body = s.core.limits.max_body_bytes;
    let bytes = body.map_err(|e| ApiError::unreadable_body(&e, max_body))?;
    let max_samples = s.core.limits.max_record_samples;
    let out = blocking(move || inspect_motion(&json_body(&bytes)?, max_samples, points)).await??;
    Ok(axum::Json(out).into_response())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pointers_are_relative_to_the_motion() {
        let rec = json!({"horizontal": {"format": "at2", "content": ""}});
        let pulse = json!({"horizontal": {"pulse": {}}});
        assert_eq!(
            motion_pointer("motion.horizontal.pulse", "bad", &pulse),
            "/horizontal/pulse"
        );
        assert_eq!(
            motion_pointer(
                "motion.horizontal",
                "unknown field `foo`, expected one of",
                &rec
            ),
            "/horizontal/foo"
        );
        assert_eq!(
            motion_pointer("motion.horizontal", "missing field `period`", &pulse),
            "/horizontal/pulse/period"
        );
        assert_eq!(motion_pointer("motion", "x", &rec), "");
    }
}
