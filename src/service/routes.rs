//! HTTP routes (docs/format.md §4, `openapi.yaml`): thin async handlers that validate, talk to the
//! store on the blocking pool, and answer. No simulation work happens here.
use super::events::{job_stream, EventParams, JobEvent};
use super::histories::Histories;
use super::problem::ApiError;
use super::request::{json_body, parse_pga, parse_run};
use super::store::{rfc3339, CancelOutcome, JobKind, JobRecord, JobStatus, NewJob};
use super::web;
use super::worker::Core;
use axum::body::{Body, Bytes};
use axum::extract::rejection::{BytesRejection, PathRejection, QueryRejection};
use axum::extract::{DefaultBodyLimit, Path, Query, State};
use axum::http::{header, HeaderMap, HeaderValue, Method, StatusCode};
use axum::response::sse::{KeepAlive, Sse};
use axum::response::{IntoResponse, Response};
use axum::routing::{get, post, MethodRouter};
use axum::Router;
use serde_json::{json, Value};
use std::sync::atomic::Ordering;
use std::sync::Arc;
use std::time::Duration;
use uuid::Uuid;

/// The hand-written OpenAPI 3.1 description, served at `/openapi.yaml`.
pub const OPENAPI_YAML: &str = include_str!("../../openapi.yaml");

/// Shared state of the handlers.
#[derive(Clone)]
pub struct AppState {
    pub core: Arc<Core>,
}

type ApiResult = Result<Response, ApiError>;

/// Every route: method, path, handler. `app` is built from this table, and the tests compare it
/// with `openapi.yaml` in both directions.
pub fn route_table() -> Vec<(Method, &'static str, MethodRouter<AppState>)> {
    vec![
        (Method::POST, "/v1/jobs", post(submit_job)),
        (Method::GET, "/v1/jobs/{id}", get(get_job)),
        (Method::GET, "/v1/jobs/{id}/histories", get(get_histories)),
        (
            Method::GET,
            "/v1/jobs/{id}/trajectory.mcap",
            get(get_trajectory),
        ),
        (Method::GET, "/v1/jobs/{id}/events", get(job_events)),
        (Method::POST, "/v1/jobs/{id}/cancel", post(cancel_job)),
        (Method::POST, "/v1/pga-searches", post(submit_pga)),
        (Method::GET, "/v1/pga-searches/{id}", get(get_pga)),
        (Method::GET, "/v1/pga-searches/{id}/events", get(pga_events)),
        (
            Method::GET,
            "/v1/pga-searches/{id}/fragility.svg",
            get(get_fragility_svg),
        ),
        (
            Method::POST,
            "/v1/pga-searches/{id}/cancel",
            post(cancel_pga),
        ),
        (Method::GET, "/healthz", get(healthz)),
        (Method::GET, "/openapi.yaml", get(openapi)),
        // The web page (docs/web.md) and the endpoints it needs: src/service/web.rs.
        (Method::GET, "/", get(web::index)),
        (Method::GET, "/assets/{name}", get(web::asset)),
        (Method::GET, "/v1/jobs", get(web::list_jobs)),
        (Method::GET, "/v1/jobs/{id}/scene", get(web::job_scene)),
        (Method::GET, "/v1/jobs/{id}/ground", get(web::job_ground)),
        (Method::POST, "/v1/motions/inspect", post(web::inspect)),
        (Method::GET, "/v1/examples", get(web::list_examples)),
        (Method::GET, "/v1/examples/{name}", get(web::get_example)),
        (Method::GET, "/v1/templates", get(super::templates::list)),
        (
            Method::POST,
            "/v1/templates/{name}",
            post(super::templates::build),
        ),
    ]
}

/// The service's router (testable without a socket through `tower::ServiceExt::oneshot`).
pub fn app(state: AppState) -> Router {
    let mut by_path: Vec<(&'static str, MethodRouter<AppState>)> = Vec::new();
    for (_, path, handler) in route_table() {
        match by_path.iter_mut().find(|(p, _)| *p == path) {
            Some((_, existing)) => *existing = std::mem::take(existing).merge(handler),
            None => by_path.push((path, handler)),
        }
    }
    let mut router = Router::new();
    for (path, handler) in by_path {
        router = router.route(path, handler);
    }
    let limit = state.core.limits.max_body_bytes;
    let cors = tower_http::cors::CorsLayer::new()
        .allow_origin(tower_http::cors::Any)
        .allow_methods([Method::GET, Method::POST])
        .allow_headers(tower_http::cors::Any)
        .expose_headers([
            header::CONTENT_RANGE,
            header::ACCEPT_RANGES,
            header::CONTENT_LENGTH,
            header::LOCATION,
        ]);
    router
        .fallback(no_route)
        .layer(axum::middleware::map_response(problem_for_bare_errors))
        .layer(DefaultBodyLimit::max(limit))
        .layer(cors)
        .layer(tower_http::trace::TraceLayer::new_for_http())
        .with_state(state)
}

async fn no_route(uri: axum::http::Uri) -> ApiError {
    ApiError::no_route(uri.path())
}

/// axum answers a wrong method with a bare 405; give it a problem body (keeping `Allow`).
async fn problem_for_bare_errors(resp: Response) -> Response {
    if resp.status() == StatusCode::METHOD_NOT_ALLOWED
        && !resp.headers().contains_key(header::CONTENT_TYPE)
    {
        let allow = resp.headers().get(header::ALLOW).cloned();
        let body = json!({
            "type": "urn:ashlar:problem:method-not-allowed",
            "title": "Method not allowed",
            "status": 405,
            "detail": format!("this endpoint does not support that method; allowed: {}",
                allow.as_ref().and_then(|a| a.to_str().ok()).unwrap_or("see /openapi.yaml")),
        });
        let mut out = (StatusCode::METHOD_NOT_ALLOWED, body.to_string()).into_response();
        out.headers_mut().insert(
            header::CONTENT_TYPE,
            HeaderValue::from_static("application/problem+json"),
        );
        if let Some(a) = allow {
            out.headers_mut().insert(header::ALLOW, a);
        }
        return out;
    }
    resp
}

/// Run store work on the blocking pool (SQLite calls fsync; never stall the runtime's threads).
pub(super) async fn blocking<T: Send + 'static>(
    f: impl FnOnce() -> T + Send + 'static,
) -> Result<T, ApiError> {
    tokio::task::spawn_blocking(f)
        .await
        .map_err(ApiError::internal)
}

pub(super) fn parse_id(path: Result<Path<String>, PathRejection>) -> Result<Uuid, ApiError> {
    let Path(raw) = path.map_err(|e| ApiError::invalid_parameter("id", e.body_text()))?;
    Uuid::try_parse(&raw)
        .map_err(|_| ApiError::invalid_parameter("id", format!("id {raw:?} is not a UUID")))
}

pub(super) async fn load(state: &AppState, id: Uuid, kind: JobKind) -> Result<JobRecord, ApiError> {
    let store = state.core.store.clone();
    let job = blocking(move || store.get(id))
        .await?
        .map_err(ApiError::internal)?;
    let what = if kind == JobKind::Run {
        "job"
    } else {
        "PGA search"
    };
    match job {
        Some(j) if j.kind == kind => Ok(j),
        _ => Err(ApiError::not_found(what, id)),
    }
}

pub(super) fn check_json_content_type(headers: &HeaderMap) -> Result<(), ApiError> {
    let ct = headers
        .get(header::CONTENT_TYPE)
        .and_then(|v| v.to_str().ok())
        .unwrap_or("");
    let essence = ct
        .split(';')
        .next()
        .unwrap_or("")
        .trim()
        .to_ascii_lowercase();
    if essence == "application/json"
        || (essence.starts_with("application/") && essence.ends_with("+json"))
    {
        Ok(())
    } else {
        Err(ApiError::unsupported_media_type(ct))
    }
}

fn base(kind: JobKind) -> &'static str {
    match kind {
        JobKind::Run => "/v1/jobs",
        // Child runs are not served over HTTP; they belong to their search.
        JobKind::PgaSearch | JobKind::PgaRun => "/v1/pga-searches",
    }
}

fn links(kind: JobKind, id: Uuid) -> Value {
    let b = format!("{}/{id}", base(kind));
    match kind {
        JobKind::Run => json!({
            "self": b, "events": format!("{b}/events"), "cancel": format!("{b}/cancel"),
            "histories": format!("{b}/histories"), "trajectory": format!("{b}/trajectory.mcap"),
        }),
        JobKind::PgaSearch | JobKind::PgaRun => {
            json!({"self": b, "events": format!("{b}/events"), "cancel": format!("{b}/cancel")})
        }
    }
}

async fn submit(
    state: AppState,
    headers: HeaderMap,
    body: Result<Bytes, BytesRejection>,
    kind: JobKind,
) -> ApiResult {
    let core = state.core.clone();
    if core.shutting_down.load(Ordering::SeqCst) {
        return Err(ApiError::unavailable(
            "the server is shutting down; submit the job again to its successor",
            5,
        ));
    }
    check_json_content_type(&headers)?;
    let bytes = body.map_err(|e| {
        if e.status() == StatusCode::PAYLOAD_TOO_LARGE {
            ApiError::payload_too_large(core.limits.max_body_bytes)
        } else {
            ApiError::malformed_json(e.body_text()).with_pointer("")
        }
    })?;
    let limits = core.limits.clone();
    // Parsing an embedded record can take milliseconds: off the async threads.
    let parsed = blocking(move || {
        let value = json_body(&bytes)?;
        let parsed = match kind {
            JobKind::Run => parse_run(&value, &limits)?,
            JobKind::PgaSearch | JobKind::PgaRun => parse_pga(&value, &limits)?,
        };
        Ok::<_, ApiError>((value, parsed.motion_summary))
    })
    .await??;
    let (request, motion) = parsed;
    let id = Uuid::new_v4();
    let job = NewJob {
        id,
        kind,
        request,
        motion,
    };
    let store = core.store.clone();
    let max_queued = core.limits.max_queued_jobs;
    blocking(move || {
        let counts = store.counts().map_err(ApiError::internal)?;
        if counts.queued >= max_queued {
            return Err(ApiError::unavailable(
                format!(
                    "the queue is full ({} jobs waiting, limit {max_queued}); retry later",
                    counts.queued
                ),
                30,
            ));
        }
        store.insert(&job).map_err(ApiError::internal)
    })
    .await??;
    core.notify_work();
    let location = format!("{}/{id}", base(kind));
    let body =
        json!({"id": id, "kind": kind, "status": JobStatus::Queued, "links": links(kind, id)});
    let mut resp = (StatusCode::ACCEPTED, axum::Json(body)).into_response();
    if let Ok(v) = HeaderValue::from_str(&location) {
        resp.headers_mut().insert(header::LOCATION, v);
    }
    Ok(resp)
}

async fn submit_job(
    State(s): State<AppState>,
    headers: HeaderMap,
    body: Result<Bytes, BytesRejection>,
) -> ApiResult {
    submit(s, headers, body, JobKind::Run).await
}

async fn submit_pga(
    State(s): State<AppState>,
    headers: HeaderMap,
    body: Result<Bytes, BytesRejection>,
) -> ApiResult {
    submit(s, headers, body, JobKind::PgaSearch).await
}

pub(super) fn job_json(j: &JobRecord) -> String {
    let v = json!({
        "id": j.id,
        "kind": j.kind,
        "status": j.status,
        "progress": j.progress,
        "created_at": rfc3339(j.created_ms),
        "started_at": j.started_ms.map(rfc3339),
        "finished_at": j.finished_ms.map(rfc3339),
        "attempts": j.attempts,
        "cancel_requested": j.cancel_requested,
        "motion": j.motion,
        "error": j.error,
        "links": links(j.kind, j.id),
    });
    let key = if j.kind == JobKind::Run {
        "summary"
    } else {
        "result"
    };
    with_raw_field(&v, key, j.result.as_deref())
}

/// Serialise `obj` with one more member whose value is JSON text spliced in verbatim (the
/// stored summary, so its numbers reach the client exactly as the runner produced them).
fn with_raw_field(obj: &Value, key: &str, raw: Option<&str>) -> String {
    let text = obj.to_string();
    let raw = raw
        .filter(|r| serde_json::from_str::<serde::de::IgnoredAny>(r).is_ok())
        .unwrap_or("null");
    match text.strip_suffix('}') {
        Some(head) if head.len() > 1 => format!("{head},{}:{raw}}}", Value::from(key)),
        Some(_) => format!("{{{}:{raw}}}", Value::from(key)),
        None => text,
    }
}

fn json_response(status: StatusCode, body: String) -> Response {
    let mut r = (status, body).into_response();
    r.headers_mut().insert(
        header::CONTENT_TYPE,
        HeaderValue::from_static("application/json"),
    );
    r
}

async fn get_job(State(s): State<AppState>, id: Result<Path<String>, PathRejection>) -> ApiResult {
    let j = load(&s, parse_id(id)?, JobKind::Run).await?;
    Ok(json_response(StatusCode::OK, job_json(&j)))
}

async fn get_pga(State(s): State<AppState>, id: Result<Path<String>, PathRejection>) -> ApiResult {
    let j = load(&s, parse_id(id)?, JobKind::PgaSearch).await?;
    Ok(json_response(StatusCode::OK, job_json(&j)))
}

async fn cancel(s: AppState, id: Result<Path<String>, PathRejection>, kind: JobKind) -> ApiResult {
    let id = parse_id(id)?;
    load(&s, id, kind).await?;
    let store = s.core.store.clone();
    let outcome = blocking(move || store.request_cancel(id))
        .await?
        .map_err(ApiError::internal)?;
    let status = match outcome {
        CancelOutcome::NotFound => return Err(ApiError::not_found("job", id)),
        CancelOutcome::CancelledQueued => {
            s.core.hub.publish(
                id,
                JobEvent {
                    status: JobStatus::Cancelled,
                    progress: 0.0,
                },
            );
            StatusCode::OK
        }
        CancelOutcome::Requested => {
            // Not running in this process (another server of a shared store, or between claim
            // and start): its worker sees the store's flag when it starts.
            s.core.signal_cancel(id);
            StatusCode::ACCEPTED
        }
        CancelOutcome::AlreadyFinished(st) => {
            return Err(ApiError::conflict(format!(
                "the job has already finished ({}); nothing to cancel",
                st.as_str()
            )))
        }
    };
    let j = load(&s, id, kind).await?;
    Ok(json_response(status, job_json(&j)))
}

async fn cancel_job(
    State(s): State<AppState>,
    id: Result<Path<String>, PathRejection>,
) -> ApiResult {
    cancel(s, id, JobKind::Run).await
}

async fn cancel_pga(
    State(s): State<AppState>,
    id: Result<Path<String>, PathRejection>,
) -> ApiResult {
    cancel(s, id, JobKind::PgaSearch).await
}

async fn events(s: AppState, id: Result<Path<String>, PathRejection>, kind: JobKind) -> ApiResult {
    let j = load(&s, parse_id(id)?, kind).await?;
    let current = JobEvent {
        status: j.status,
        progress: j.progress,
    };
    let stream = job_stream(
        j.id,
        current,
        s.core.store.clone(),
        &s.core.hub,
        s.core.shutdown_signal.subscribe(),
        EventParams::default(),
    );
    Ok(Sse::new(stream)
        .keep_alive(KeepAlive::new().interval(Duration::from_secs(15)))
        .into_response())
}

async fn job_events(
    State(s): State<AppState>,
    id: Result<Path<String>, PathRejection>,
) -> ApiResult {
    events(s, id, JobKind::Run).await
}

async fn pga_events(
    State(s): State<AppState>,
    id: Result<Path<String>, PathRejection>,
) -> ApiResult {
    events(s, id, JobKind::PgaSearch).await
}

/// Artifacts exist for finished runs; a cancelled run keeps what it wrote before stopping.
fn artifact_available(j: &JobRecord, what: &str) -> Result<(), ApiError> {
    match j.status {
        JobStatus::Succeeded | JobStatus::Cancelled => Ok(()),
        s => Err(ApiError::conflict(format!(
            "the job is {}; its {what} {}",
            s.as_str(),
            if s == JobStatus::Failed {
                "were never written"
            } else {
                "are available once it has succeeded"
            }
        ))),
    }
}

enum HistoryFormat {
    Json,
    Csv,
}

fn history_format(
    query: &[(String, String)],
    headers: &HeaderMap,
) -> Result<HistoryFormat, ApiError> {
    if let Some((_, f)) = query.iter().find(|(k, _)| k == "format") {
        return match f.as_str() {
            "json" => Ok(HistoryFormat::Json),
            "csv" => Ok(HistoryFormat::Csv),
            other => Err(ApiError::invalid_parameter(
                "format",
                format!("format {other:?} is not one of \"json\", \"csv\""),
            )),
        };
    }
    let accept = headers
        .get(header::ACCEPT)
        .and_then(|v| v.to_str().ok())
        .unwrap_or("")
        .to_ascii_lowercase();
    let types: Vec<&str> = accept
        .split(',')
        .map(|t| t.split(';').next().unwrap_or("").trim())
        .filter(|t| !t.is_empty())
        .collect();
    if types.is_empty() {
        return Ok(HistoryFormat::Json);
    }
    // The first acceptable type wins (q-values are not weighed: clients ask for one format).
    for t in types {
        match t {
            "application/json" | "application/*" | "*/*" => return Ok(HistoryFormat::Json),
            "text/csv" | "text/*" => return Ok(HistoryFormat::Csv),
            _ => {}
        }
    }
    Err(ApiError::not_acceptable(format!(
        "cannot produce {accept:?}; histories come as application/json or text/csv"
    )))
}

async fn get_histories(
    State(s): State<AppState>,
    id: Result<Path<String>, PathRejection>,
    query: Result<Query<Vec<(String, String)>>, QueryRejection>,
    headers: HeaderMap,
) -> ApiResult {
    let id = parse_id(id)?;
    let Query(query) = query.map_err(|e| ApiError::invalid_parameter("query", e.body_text()))?;
    if let Some((k, _)) = query.iter().find(|(k, _)| k != "format" && k != "block") {
        return Err(ApiError::invalid_parameter(
            k.clone(),
            format!("unknown query parameter {k:?} (known: block, format)"),
        ));
    }
    let format = history_format(&query, &headers)?;
    let blocks: Vec<String> = query
        .iter()
        .filter(|(k, _)| k == "block")
        .map(|(_, v)| v.clone())
        .collect();
    let j = load(&s, id, JobKind::Run).await?;
    artifact_available(&j, "histories")?;
    super::artifacts::ensure_local(&s.core, id, "histories.csv").await;
    let path = s.core.job_dir(id).join("histories.csv");
    let text = match tokio::fs::read_to_string(&path).await {
        Ok(t) => t,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => {
            return Err(ApiError::conflict(
                "the job finished without recording histories",
            ));
        }
        Err(e) => return Err(ApiError::internal(format!("{}: {e}", path.display()))),
    };
    let h = blocking(move || Histories::parse_csv(&text))
        .await?
        .map_err(ApiError::internal)?;
    let known = h.block_ids().collect::<Vec<_>>().join(", ");
    let h = h.select(&blocks).map_err(|unknown| {
        ApiError::not_found_parameter(
            "block",
            format!("the job has no history for block {unknown:?} (it has: {known})"),
        )
    })?;
    Ok(match format {
        HistoryFormat::Json => axum::Json(h.to_json()).into_response(),
        HistoryFormat::Csv => {
            let mut r = h.to_csv().into_response();
            r.headers_mut().insert(
                header::CONTENT_TYPE,
                HeaderValue::from_static("text/csv; charset=utf-8"),
            );
            r
        }
    })
}

/// A single byte range, resolved against the file length (RFC 9110 §14.1.2).
#[derive(Debug, PartialEq)]
enum RangeAsk {
    Whole,
    Part(u64, u64),
    Unsatisfiable,
}

fn parse_range(value: Option<&str>, len: u64) -> RangeAsk {
    let Some(spec) = value.and_then(|v| v.trim().strip_prefix("bytes=")) else {
        return RangeAsk::Whole;
    };
    // Several ranges (multipart answers) are not supported: serve the whole file, as allowed.
    if spec.contains(',') {
        return RangeAsk::Whole;
    }
    let Some((a, b)) = spec.split_once('-') else {
        return RangeAsk::Whole;
    };
    let (a, b) = (a.trim(), b.trim());
    let parsed = match (a.parse::<u64>().ok(), b.parse::<u64>().ok()) {
        (Some(start), Some(end)) if a.len() + b.len() > 0 && end >= start => {
            Some((start, end.min(len.saturating_sub(1))))
        }
        (Some(_), Some(_)) => return RangeAsk::Whole, // end < start: invalid, ignored
        (Some(start), None) if b.is_empty() => Some((start, len.saturating_sub(1))),
        (None, Some(n)) if a.is_empty() => {
            if n == 0 {
                return RangeAsk::Unsatisfiable;
            }
            Some((len.saturating_sub(n), len.saturating_sub(1)))
        }
        _ => return RangeAsk::Whole,
    };
    match parsed {
        Some((start, end)) if start < len && start <= end => RangeAsk::Part(start, end),
        _ => RangeAsk::Unsatisfiable,
    }
}

async fn get_trajectory(
    State(s): State<AppState>,
    id: Result<Path<String>, PathRejection>,
    headers: HeaderMap,
) -> ApiResult {
    let id = parse_id(id)?;
    let j = load(&s, id, JobKind::Run).await?;
    artifact_available(&j, "trajectory")?;
    super::artifacts::ensure_local(&s.core, id, "trajectory.mcap").await;
    let path = s.core.job_dir(id).join("trajectory.mcap");
    let bytes = match tokio::fs::read(&path).await {
        Ok(b) => b,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => {
            return Err(ApiError::conflict(
                "the job finished without recording a trajectory",
            ));
        }
        Err(e) => return Err(ApiError::internal(format!("{}: {e}", path.display()))),
    };
    let len = bytes.len() as u64;
    let range = parse_range(
        headers.get(header::RANGE).and_then(|v| v.to_str().ok()),
        len,
    );
    let mut resp = match range {
        RangeAsk::Whole => (StatusCode::OK, Body::from(bytes)).into_response(),
        RangeAsk::Part(a, b) => {
            let part = bytes[a as usize..=b as usize].to_vec();
            let mut r = (StatusCode::PARTIAL_CONTENT, Body::from(part)).into_response();
            if let Ok(v) = HeaderValue::from_str(&format!("bytes {a}-{b}/{len}")) {
                r.headers_mut().insert(header::CONTENT_RANGE, v);
            }
            r
        }
        RangeAsk::Unsatisfiable => {
            let mut r = ApiError::range_not_satisfiable(format!("the trajectory has {len} bytes"))
                .into_response();
            if let Ok(v) = HeaderValue::from_str(&format!("bytes */{len}")) {
                r.headers_mut().insert(header::CONTENT_RANGE, v);
            }
            return Ok(r);
        }
    };
    let h = resp.headers_mut();
    h.insert(
        header::CONTENT_TYPE,
        HeaderValue::from_static("application/octet-stream"),
    );
    h.insert(header::ACCEPT_RANGES, HeaderValue::from_static("bytes"));
    h.insert(
        header::CONTENT_DISPOSITION,
        HeaderValue::from_static("attachment; filename=\"trajectory.mcap\""),
    );
    Ok(resp)
}

/// The fragility plot of a finished multi-record search.
async fn get_fragility_svg(
    State(s): State<AppState>,
    id: Result<Path<String>, PathRejection>,
) -> ApiResult {
    let id = parse_id(id)?;
    let j = load(&s, id, JobKind::PgaSearch).await?;
    if j.status != JobStatus::Succeeded {
        return Err(ApiError::conflict(format!(
            "the search is {}; its fragility plot is available once it has succeeded",
            j.status.as_str()
        )));
    }
    // Written by whichever worker finished the search: fetched from shared storage if need be.
    super::artifacts::ensure_local(&s.core, id, "fragility.svg").await;
    let path = s.core.job_dir(id).join("fragility.svg");
    match tokio::fs::read(&path).await {
        Ok(bytes) => Ok((
            [(header::CONTENT_TYPE, "image/svg+xml")],
            Body::from(bytes),
        )
            .into_response()),
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => Err(ApiError::conflict(
            "the search has no fragility curve: it ran one record (give \"motions\" for several), or the fit failed (see result.fragility_error)",
        )),
        Err(e) => Err(ApiError::internal(format!("{}: {e}", path.display()))),
    }
}

async fn healthz(State(s): State<AppState>) -> ApiResult {
    // Answered from memory only: it must stay fast while the store is busy with submissions.
    let c = &s.core;
    let alive = c.workers_alive.load(Ordering::SeqCst);
    if c.shutting_down.load(Ordering::SeqCst) {
        return Err(ApiError::unavailable("the server is shutting down", 5));
    }
    if alive == 0 && !c.remote_workers.load(Ordering::SeqCst) {
        return Err(ApiError::unavailable("no worker thread is running", 5));
    }
    if !c.store_healthy.load(Ordering::Relaxed) {
        return Err(ApiError::unavailable(
            "the job store is failing; see the server log",
            5,
        ));
    }
    let body = json!({
        "status": "ok",
        "version": env!("CARGO_PKG_VERSION"),
        "workers": alive,
        "running": c.running_here(),
    });
    Ok(axum::Json(body).into_response())
}

async fn openapi() -> Response {
    ([(header::CONTENT_TYPE, "application/yaml")], OPENAPI_YAML).into_response()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn raw_fields_are_spliced_verbatim() {
        let obj = json!({"id": 1});
        assert_eq!(
            with_raw_field(&obj, "summary", Some("{\"x\":0.41000000000000003}")),
            r#"{"id":1,"summary":{"x":0.41000000000000003}}"#
        );
        assert_eq!(
            with_raw_field(&obj, "summary", None),
            r#"{"id":1,"summary":null}"#
        );
        assert_eq!(
            with_raw_field(&obj, "summary", Some("{broken")),
            r#"{"id":1,"summary":null}"#
        );
        assert_eq!(with_raw_field(&json!({}), "k", Some("[1]")), r#"{"k":[1]}"#);
    }

    #[test]
    fn byte_ranges() {
        assert_eq!(parse_range(None, 100), RangeAsk::Whole);
        assert_eq!(parse_range(Some("bytes=0-9"), 100), RangeAsk::Part(0, 9));
        assert_eq!(parse_range(Some("bytes=90-"), 100), RangeAsk::Part(90, 99));
        assert_eq!(parse_range(Some("bytes=-10"), 100), RangeAsk::Part(90, 99));
        assert_eq!(
            parse_range(Some("bytes=50-1000"), 100),
            RangeAsk::Part(50, 99)
        );
        assert_eq!(parse_range(Some("bytes=-1000"), 100), RangeAsk::Part(0, 99));
        assert_eq!(
            parse_range(Some("bytes=100-"), 100),
            RangeAsk::Unsatisfiable
        );
        assert_eq!(parse_range(Some("bytes=-0"), 100), RangeAsk::Unsatisfiable);
        assert_eq!(parse_range(Some("bytes=5-2"), 100), RangeAsk::Whole);
        assert_eq!(parse_range(Some("bytes=0-1,5-6"), 100), RangeAsk::Whole);
        assert_eq!(parse_range(Some("items=0-1"), 100), RangeAsk::Whole);
    }
}
