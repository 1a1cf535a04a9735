//! HTTP routes (docs/format.md §4, `openapi.yaml`): thin async handlers that validate, talk to the
//! store on the blocking pool, and answer. No simulation work happens here.
pub mod budget;
pub mod problem;
pub mod request;
pub mod scene_import;
pub mod templates;
pub mod web;

use self::problem::ApiError;
use self::request::{json_body, parse_pga, parse_run, parse_site};
use crate::service::auth::Access;
use crate::service::events::{job_stream, EventParams, JobEvent};
use crate::service::histories::Histories;
use crate::service::store::{
    rfc3339, CancelOutcome, DeleteOutcome, JobKind, JobRecord, JobStatus, NewJob, QueueFull,
};
use crate::service::worker::Core;
use axum::body::{Body, Bytes};
use axum::extract::rejection::{PathRejection, QueryRejection};
use axum::extract::{DefaultBodyLimit, Path, Query, State};
use axum::http::{header, HeaderMap, HeaderValue, Method, StatusCode};
use axum::response::sse::{KeepAlive, Sse};
use axum::response::{IntoResponse, Response};
use axum::routing::{delete, get, post, MethodRouter};
use axum::Router;
use serde_json::{json, Value};
use std::sync::atomic::Ordering;
use std::sync::Arc;
use std::time::Duration;
use uuid::Uuid;

/// The hand-written OpenAPI 3.1 description, served at `/openapi.yaml`.
pub const OPENAPI_YAML: &str = include_str!("../../../openapi.yaml");

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
        (Method::DELETE, "/v1/jobs/{id}", delete(delete_job)),
        (Method::DELETE, "/v1/pga-searches/{id}", delete(delete_pga)),
        (Method::GET, "/v1/limits", get(get_limits)),
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
        (Method::POST, "/v1/site-analyses", post(submit_site)),
        (Method::GET, "/v1/site-analyses/{id}", get(get_site)),
        (
            Method::GET,
            "/v1/site-analyses/{id}/events",
            get(site_events),
        ),
        (
            Method::POST,
            "/v1/site-analyses/{id}/cancel",
            post(cancel_site),
        ),
        (
            Method::DELETE,
            "/v1/site-analyses/{id}",
            delete(delete_site),
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
        (Method::GET, "/v1/templates", get(self::templates::list)),
        (
            Method::POST,
            "/v1/templates/{name}",
            post(self::templates::build),
        ),
        (
            Method::POST,
            "/v1/scenes/import",
            post(self::scene_import::import),
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
    let origins: Vec<HeaderValue> = state
        .core
        .server
        .cors_origins
        .iter()
        .filter_map(|o| HeaderValue::from_str(o).ok())
        .collect();
    let cors = tower_http::cors::CorsLayer::new()
        .allow_origin(tower_http::cors::AllowOrigin::list(origins))
        .allow_methods([Method::GET, Method::POST, Method::DELETE])
        .allow_headers(tower_http::cors::Any)
        .expose_headers([
            header::CONTENT_RANGE,
            header::ACCEPT_RANGES,
            header::CONTENT_LENGTH,
            header::LOCATION,
        ]);
    let header_limits = state.core.server.clone();
    let tokens = state.core.server.tokens.clone();
    let signing = state.core.server.signing.clone();
    router
        .fallback(no_route)
        .layer(axum::middleware::map_response(problem_for_bare_errors))
        .layer(axum::middleware::from_fn(
            move |req: axum::extract::Request, next: axum::middleware::Next| {
                let limits = header_limits.clone();
                async move {
                    match check_headers(req.headers(), &limits) {
                        Ok(()) => next.run(req).await,
                        Err(e) => e.into_response(),
                    }
                }
            },
        ))
        .layer(axum::middleware::from_fn(
            move |mut req: axum::extract::Request, next: axum::middleware::Next| {
                let tokens = tokens.clone();
                let signing = signing.clone();
                async move {
                    match authorize(tokens.as_deref(), signing.as_ref(), &req) {
                        Ok(access) => {
                            req.extensions_mut().insert(access);
                            next.run(req).await
                        }
                        Err(e) => e.into_response(),
                    }
                }
            },
        ))
        .layer(DefaultBodyLimit::max(limit))
        .layer(cors)
        .layer(tower_http::trace::TraceLayer::new_for_http())
        .with_state(state)
}

async fn no_route(uri: axum::http::Uri) -> ApiError {
    ApiError::no_route(uri.path())
}

/// With `--tokens`, every `/v1/…` request needs a valid bearer token (the page, its assets,
/// `/healthz` and `/openapi.yaml` stay open), or, on the GET routes a browser or Foxglove opens
/// without headers ([`signable`]), a valid signed URL. Says who the caller is.
fn authorize(
    tokens: Option<&crate::service::auth::Tokens>,
    signing: Option<&crate::service::auth::SigningKey>,
    req: &axum::extract::Request,
) -> Result<Access, ApiError> {
    let Some(tokens) = tokens else {
        return Ok(Access::Open);
    };
    let path = req.uri().path();
    if !path.starts_with("/v1/") {
        return Ok(Access::Open);
    }
    let presented = req
        .headers()
        .get(header::AUTHORIZATION)
        .and_then(|v| v.to_str().ok())
        .and_then(crate::service::auth::bearer);
    let query: Vec<(String, String)> = req
        .uri()
        .query()
        .map(|q| {
            url::form_urlencoded::parse(q.as_bytes())
                .into_owned()
                .collect()
        })
        .unwrap_or_default();
    let param = |k: &str| {
        query
            .iter()
            .rev()
            .find(|(n, _)| n == k)
            .map(|(_, v)| v.as_str())
    };
    match presented {
        Some(t) => match tokens.identify(t) {
            Some(identity) => Ok(Access::Token(identity)),
            None => Err(ApiError::unauthorized("the token is not accepted")),
        },
        None if param("sig").is_some() || param("expires").is_some() => {
            if !(req.method() == Method::GET && signable(path)) {
                return Err(ApiError::unauthorized(
                    "signed links are accepted only on GET of a job's trajectory, histories and events and a search's events and fragility plot; send Authorization: Bearer TOKEN",
                ));
            }
            let Some(key) = signing else {
                return Err(ApiError::unauthorized("this server does not sign links"));
            };
            key.verify(
                path,
                param("expires"),
                param("sig"),
                crate::service::auth::unix_now(),
            )
            .map_err(|e| ApiError::unauthorized(e.to_string()).with_parameter("sig"))?;
            Ok(Access::Signed)
        }
        None => Err(ApiError::unauthorized(
            "this server requires a token: send Authorization: Bearer TOKEN",
        )),
    }
}

/// The routes a signed URL opens (GET only): what a browser or Foxglove fetches by URL.
fn signable(path: &str) -> bool {
    let segs: Vec<&str> = path.split('/').collect();
    matches!(
        segs.as_slice(),
        ["", "v1", "jobs", id, "trajectory.mcap" | "histories" | "events"]
            | ["", "v1", "pga-searches", id, "events" | "fragility.svg"]
            | ["", "v1", "site-analyses", id, "events"]
            if !id.is_empty()
    )
}

/// Request headers within `--max-header-bytes` and `--max-headers`, else 431 as a problem.
fn check_headers(
    headers: &HeaderMap,
    limits: &crate::service::server::ServerParams,
) -> Result<(), ApiError> {
    let n = headers.len();
    let bytes: usize = headers
        .iter()
        .map(|(k, v)| k.as_str().len() + v.len() + 4)
        .sum();
    if n > limits.max_headers || bytes > limits.max_header_bytes {
        return Err(ApiError::headers_too_large(format!(
            "the request has {n} header fields, {bytes} bytes; the server takes at most {} fields and {} bytes",
            limits.max_headers, limits.max_header_bytes
        )));
    }
    Ok(())
}

/// The methods routed at a concrete path (templates' `{x}` match one segment).
fn methods_at(path: &str) -> Vec<Method> {
    let segs: Vec<&str> = path.trim_end_matches('/').split('/').collect();
    route_table()
        .into_iter()
        .filter(|(_, t, _)| {
            let ts: Vec<&str> = t.split('/').collect();
            ts.len() == segs.len()
                && ts
                    .iter()
                    .zip(&segs)
                    .all(|(t, s)| t == s || (t.starts_with('{') && !s.is_empty()))
        })
        .map(|(m, _, _)| m)
        .collect()
}

/// axum answers a wrong method with a bare 405; give it a problem body naming the methods
/// the path takes (and an `Allow` header listing them).
async fn problem_for_bare_errors(uri: axum::http::Uri, resp: Response) -> Response {
    if resp.status() == StatusCode::METHOD_NOT_ALLOWED
        && !resp.headers().contains_key(header::CONTENT_TYPE)
    {
        let mut methods: Vec<String> = methods_at(uri.path())
            .iter()
            .map(|m| m.as_str().to_string())
            .collect();
        if methods.iter().any(|m| m == "GET") {
            methods.push("HEAD".into());
        }
        methods.dedup();
        let allow = methods.join(", ");
        let body = json!({
            "type": "urn:ashlar:problem:method-not-allowed",
            "title": "Method not allowed",
            "status": 405,
            "detail": format!("{} takes {}", uri.path(),
                if allow.is_empty() { "no method here (see /openapi.yaml)".to_string() } else { allow.clone() }),
        });
        let mut out = (StatusCode::METHOD_NOT_ALLOWED, body.to_string()).into_response();
        out.headers_mut().insert(
            header::CONTENT_TYPE,
            HeaderValue::from_static("application/problem+json"),
        );
        if let Ok(a) = HeaderValue::from_str(&allow) {
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

/// The job `id` of `kind`, if `access` may see it: another token's job answers 404, like a job
/// that does not exist, so that ids do not leak.
pub(super) async fn load(
    state: &AppState,
    access: &Access,
    id: Uuid,
    kind: JobKind,
) -> Result<JobRecord, ApiError> {
    let store = state.core.store.clone();
    let job = blocking(move || store.get(id))
        .await?
        .map_err(ApiError::store)?;
    let what = match kind {
        JobKind::Run => "job",
        JobKind::SiteAnalysis => "site analysis",
        JobKind::PgaSearch | JobKind::PgaRun => "PGA search",
    };
    match job {
        Some(j) if j.kind == kind && access.may_see(j.owner.as_deref()) => Ok(j),
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
        JobKind::SiteAnalysis => "/v1/site-analyses",
    }
}

fn links(kind: JobKind, id: Uuid) -> Value {
    let b = format!("{}/{id}", base(kind));
    match kind {
        JobKind::Run => json!({
            "self": b, "events": format!("{b}/events"), "cancel": format!("{b}/cancel"),
            "histories": format!("{b}/histories"), "trajectory": format!("{b}/trajectory.mcap"),
        }),
        JobKind::PgaSearch | JobKind::PgaRun | JobKind::SiteAnalysis => {
            json!({"self": b, "events": format!("{b}/events"), "cancel": format!("{b}/cancel")})
        }
    }
}

/// Read a submission's body: refused with 413 while reading once it passes
/// `--max-body-bytes` (at once when Content-Length says so), 408 when it does not arrive within
/// `--body-timeout`. A large body first waits for one of the few large-body slots.
async fn read_body(
    core: &Core,
    req: axum::extract::Request,
) -> Result<(Bytes, Option<tokio::sync::OwnedSemaphorePermit>), ApiError> {
    let limit = core.limits.max_body_bytes;
    let declared = req
        .headers()
        .get(header::CONTENT_LENGTH)
        .and_then(|v| v.to_str().ok())
        .and_then(|v| v.trim().parse::<u64>().ok());
    if declared.is_some_and(|n| n > limit as u64) {
        return Err(ApiError::payload_too_large(limit));
    }
    let timeout = core.server.body_read_timeout;
    let permit = if declared.is_none_or(|n| n > crate::service::worker::LARGE_BODY_BYTES) {
        let slot = tokio::time::timeout(timeout, core.large_bodies.clone().acquire_owned()).await;
        match slot {
            Ok(Ok(p)) => Some(p),
            _ => {
                return Err(ApiError::unavailable(
                    "too many large submissions are being read at once; retry shortly",
                    5,
                ))
            }
        }
    } else {
        None
    };
    let body = req.into_body();
    match tokio::time::timeout(timeout, axum::body::to_bytes(body, limit)).await {
        Err(_) => Err(ApiError::request_timeout(timeout.as_secs_f64())),
        Ok(Ok(b)) => Ok((b, permit)),
        Ok(Err(e)) => {
            let too_large = std::error::Error::source(&e)
                .is_some_and(|s| s.is::<http_body_util::LengthLimitError>());
            if too_large {
                Err(ApiError::payload_too_large(limit))
            } else {
                Err(ApiError::malformed_json(format!("reading the body: {e}")).with_pointer(""))
            }
        }
    }
}

async fn submit(
    state: AppState,
    access: Access,
    req: axum::extract::Request,
    kind: JobKind,
) -> ApiResult {
    let core = state.core.clone();
    if core.shutting_down.load(Ordering::SeqCst) {
        return Err(ApiError::unavailable(
            "the server is shutting down; submit the job again to its successor",
            5,
        ));
    }
    check_json_content_type(req.headers())?;
    let (bytes, permit) = read_body(&core, req).await?;
    let limits = core.limits.clone();
    // Parsing an embedded record can take milliseconds: off the async threads. The pre-scan
    // refuses an oversized document before it is built in memory.
    let parsed = blocking(move || {
        self::budget::prescan(&bytes, &limits)?;
        let value = json_body(&bytes)?;
        drop(bytes);
        let parsed = match kind {
            JobKind::Run => parse_run(&value, &limits)?,
            JobKind::PgaSearch | JobKind::PgaRun => parse_pga(&value, &limits)?,
            JobKind::SiteAnalysis => parse_site(&value, &limits)?,
        };
        Ok::<_, ApiError>((value, parsed.motion_summary))
    })
    .await??;
    drop(permit);
    let (request, motion) = parsed;
    let c = core.clone();
    let used = blocking(move || c.artifact_bytes()).await?;
    if used >= core.limits.max_artifact_bytes {
        return Err(ApiError::insufficient_storage(format!(
            "the server's artifacts take {used} bytes, at its quota of {} (ashlar serve --max-artifact-bytes); \
             delete finished jobs (DELETE /v1/jobs/{{id}}) to make room",
            core.limits.max_artifact_bytes
        )));
    }
    let id = Uuid::new_v4();
    let job = NewJob {
        id,
        kind,
        request,
        motion,
        owner: access.owner(),
    };
    let store = core.store.clone();
    let max_queued = core.limits.max_queued_jobs;
    let (max_owner, what, flag) = match kind {
        JobKind::Run => (
            core.limits.max_queued_jobs_per_token,
            "jobs",
            "--max-queued-jobs-per-token",
        ),
        JobKind::PgaSearch | JobKind::PgaRun => (
            core.limits.max_queued_searches_per_token,
            "PGA searches",
            "--max-queued-searches-per-token",
        ),
        // A site analysis is searches too (one per observation and record); its own count.
        JobKind::SiteAnalysis => (
            core.limits.max_queued_searches_per_token,
            "site analyses",
            "--max-queued-searches-per-token",
        ),
    };
    let refused = blocking(move || store.insert_quota(&job, max_queued, max_owner))
        .await?
        .map_err(ApiError::store)?;
    match refused {
        None => {}
        Some(QueueFull::Server(queued)) => {
            return Err(ApiError::quota_exceeded(
                format!(
                    "the queue is full: {queued} jobs waiting, limit {max_queued} (ashlar serve --max-queued-jobs); retry later"
                ),
                30,
            ))
        }
        Some(QueueFull::Owner(queued)) => {
            return Err(ApiError::quota_exceeded(
                format!(
                    "this token's quota of queued {what} is used up: {queued} waiting, limit {max_owner} (ashlar serve {flag}); retry when some have started"
                ),
                30,
            ))
        }
    }
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
    access: Access,
    req: axum::extract::Request,
) -> ApiResult {
    submit(s, access, req, JobKind::Run).await
}

async fn submit_site(
    State(s): State<AppState>,
    access: Access,
    req: axum::extract::Request,
) -> ApiResult {
    submit(s, access, req, JobKind::SiteAnalysis).await
}

async fn get_site(
    State(s): State<AppState>,
    access: Access,
    id: Result<Path<String>, PathRejection>,
) -> ApiResult {
    let j = load(&s, &access, parse_id(id)?, JobKind::SiteAnalysis).await?;
    Ok(json_response(
        StatusCode::OK,
        job_json_signed(&j, s.core.server.signing.as_ref()),
    ))
}

async fn site_events(
    State(s): State<AppState>,
    access: Access,
    id: Result<Path<String>, PathRejection>,
) -> ApiResult {
    events(s, access, id, JobKind::SiteAnalysis).await
}

async fn cancel_site(
    State(s): State<AppState>,
    access: Access,
    id: Result<Path<String>, PathRejection>,
) -> ApiResult {
    cancel(s, access, id, JobKind::SiteAnalysis).await
}

async fn delete_site(
    State(s): State<AppState>,
    access: Access,
    id: Result<Path<String>, PathRejection>,
) -> ApiResult {
    delete_kind(s, access, id, JobKind::SiteAnalysis).await
}

async fn submit_pga(
    State(s): State<AppState>,
    access: Access,
    req: axum::extract::Request,
) -> ApiResult {
    submit(s, access, req, JobKind::PgaSearch).await
}

/// `DELETE /v1/jobs/{id}`: a finished job and its artifacts go (204); a job still queued or
/// running is refused (409: cancel it first).
async fn delete_kind(
    s: AppState,
    access: Access,
    id: Result<Path<String>, PathRejection>,
    kind: JobKind,
) -> ApiResult {
    let id = parse_id(id)?;
    load(&s, &access, id, kind).await?;
    let store = s.core.store.clone();
    let outcome = blocking(move || store.delete(id))
        .await?
        .map_err(ApiError::store)?;
    match outcome {
        DeleteOutcome::NotFound => Err(ApiError::not_found("job", id)),
        DeleteOutcome::NotFinished(st) => Err(ApiError::conflict(format!(
            "the job is {}; cancel it first (POST …/cancel), then delete it once it has ended",
            st.as_str()
        ))),
        DeleteOutcome::Deleted => {
            // Off the async threads: removing published artifacts blocks on the object store.
            let core = s.core.clone();
            blocking(move || remove_artifacts(&core, id)).await?;
            Ok(StatusCode::NO_CONTENT.into_response())
        }
    }
}

/// Remove a deleted job's artifacts: its local directory and, with `--artifacts`, what was
/// published to shared storage (also used by the retention sweeper). Blocking.
pub(crate) fn remove_artifacts(core: &Core, id: Uuid) {
    if let Some(a) = &core.artifacts {
        if let Err(e) = a.remove(id) {
            tracing::warn!(%id, error = %e, "removing a deleted job's published artifacts");
        }
    }
    let dir = core.job_dir(id);
    if let Err(e) = std::fs::remove_dir_all(&dir) {
        if e.kind() != std::io::ErrorKind::NotFound {
            tracing::warn!(dir = %dir.display(), error = %e, "removing a deleted job's artifacts");
        }
    }
    core.forget_artifact_bytes();
}

async fn delete_job(
    State(s): State<AppState>,
    access: Access,
    id: Result<Path<String>, PathRejection>,
) -> ApiResult {
    delete_kind(s, access, id, JobKind::Run).await
}

async fn delete_pga(
    State(s): State<AppState>,
    access: Access,
    id: Result<Path<String>, PathRejection>,
) -> ApiResult {
    delete_kind(s, access, id, JobKind::PgaSearch).await
}

/// `GET /v1/limits`: the server's limits, so that a client can check a job before sending it.
async fn get_limits(State(s): State<AppState>) -> ApiResult {
    let l = &s.core.limits;
    let p = &s.core.server;
    let mut body = json!({
        "max_body_bytes": l.max_body_bytes,
        "max_json_values": l.max_json_values,
        "max_blocks": l.max_blocks,
        "max_block_vertices": l.max_block_vertices,
        "max_record_samples": l.max_record_samples,
        "max_total_steps": l.max_total_steps,
        "max_block_steps": l.max_block_steps,
        "max_block_frames": l.max_block_frames,
        "max_search_block_steps": l.max_search_block_steps,
        "max_scan_points": l.max_scan_points,
        "max_records": self::request::MAX_RECORDS,
        "max_queued_jobs": l.max_queued_jobs,
        "max_queued_jobs_per_token": l.max_queued_jobs_per_token,
        "max_queued_searches_per_token": l.max_queued_searches_per_token,
        "retain_finished_s": l.retain_finished.map(|d| d.as_secs_f64()),
        "max_job_seconds": l.max_job_seconds,
        "max_job_artifact_bytes": l.max_job_artifact_bytes,
        "max_artifact_bytes": l.max_artifact_bytes,
        "max_connections": p.max_connections,
        "header_timeout_s": p.header_read_timeout.as_secs_f64(),
        "body_timeout_s": p.body_read_timeout.as_secs_f64(),
        "idle_timeout_s": p.idle_timeout.as_secs_f64(),
        "max_header_bytes": p.max_header_bytes,
        "max_headers": p.max_headers,
        "ranges": self::budget::ranges_json(),
    });
    if let Some(o) = body.as_object_mut() {
        o.extend(process_limits(&s.core));
    }
    Ok(axum::Json(body).into_response())
}

/// The limits of this process's job runs and of its request handling not in `Limits`: where
/// jobs run and the resource limits of a job's process (`--isolation`, `--job-memory-limit`,
/// `--job-cpu-seconds`; null with threads), crash retries, large bodies parsed at once, the
/// signed links' validity (null without `--tokens`).
fn process_limits(core: &Core) -> serde_json::Map<String, Value> {
    use crate::service::worker::runner::Isolation;
    let (mode, memory, cpu) = match &core.params.isolation {
        Isolation::Thread => ("thread", None, None),
        Isolation::Process(p) => ("process", Some(p.memory_limit), Some(p.cpu_seconds)),
    };
    let v = json!({
        "isolation": mode,
        "job_memory_limit_bytes": memory,
        "job_cpu_seconds": cpu,
        "max_job_attempts": core.params.max_attempts,
        "max_large_bodies": crate::service::worker::LARGE_BODIES,
        "large_body_bytes": crate::service::worker::LARGE_BODY_BYTES,
        "signed_url_seconds": core.server.signing.as_ref().map(|k| k.validity.as_secs()),
    });
    match v {
        Value::Object(m) => m,
        _ => serde_json::Map::new(),
    }
}

/// Links of a job that a browser or Foxglove opens without headers, signed for
/// [`crate::service::auth::SigningKey::validity`] from now (with `--tokens` only).
fn signed_links(kind: JobKind, id: Uuid, key: &crate::service::auth::SigningKey) -> Value {
    let now = crate::service::auth::unix_now();
    let b = format!("{}/{id}", base(kind));
    let sign = |tail: &str| key.sign(&format!("{b}/{tail}"), now);
    let mut v = match kind {
        JobKind::Run => json!({
            "events": sign("events"), "histories": sign("histories"),
            "trajectory": sign("trajectory.mcap"),
        }),
        JobKind::PgaSearch | JobKind::PgaRun => {
            json!({"events": sign("events"), "fragility": sign("fragility.svg")})
        }
        JobKind::SiteAnalysis => json!({"events": sign("events")}),
    };
    v["expires_at"] = json!(rfc3339(
        i64::try_from(now + key.validity.as_secs()).unwrap_or(i64::MAX / 1000) * 1000
    ));
    v
}

/// [`job_json`], with `signed_links` when the server signs links.
pub(super) fn job_json_signed(
    j: &JobRecord,
    key: Option<&crate::service::auth::SigningKey>,
) -> String {
    let mut v = json!({
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
    if let Some(k) = key {
        v["signed_links"] = signed_links(j.kind, j.id, k);
    }
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

async fn get_job(
    State(s): State<AppState>,
    access: Access,
    id: Result<Path<String>, PathRejection>,
) -> ApiResult {
    let j = load(&s, &access, parse_id(id)?, JobKind::Run).await?;
    Ok(json_response(
        StatusCode::OK,
        job_json_signed(&j, s.core.server.signing.as_ref()),
    ))
}

async fn get_pga(
    State(s): State<AppState>,
    access: Access,
    id: Result<Path<String>, PathRejection>,
) -> ApiResult {
    let j = load(&s, &access, parse_id(id)?, JobKind::PgaSearch).await?;
    Ok(json_response(
        StatusCode::OK,
        job_json_signed(&j, s.core.server.signing.as_ref()),
    ))
}

async fn cancel(
    s: AppState,
    access: Access,
    id: Result<Path<String>, PathRejection>,
    kind: JobKind,
) -> ApiResult {
    let id = parse_id(id)?;
    load(&s, &access, id, kind).await?;
    let store = s.core.store.clone();
    let outcome = blocking(move || store.request_cancel(id))
        .await?
        .map_err(ApiError::store)?;
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
    let j = load(&s, &access, id, kind).await?;
    Ok(json_response(
        status,
        job_json_signed(&j, s.core.server.signing.as_ref()),
    ))
}

async fn cancel_job(
    State(s): State<AppState>,
    access: Access,
    id: Result<Path<String>, PathRejection>,
) -> ApiResult {
    cancel(s, access, id, JobKind::Run).await
}

async fn cancel_pga(
    State(s): State<AppState>,
    access: Access,
    id: Result<Path<String>, PathRejection>,
) -> ApiResult {
    cancel(s, access, id, JobKind::PgaSearch).await
}

async fn events(
    s: AppState,
    access: Access,
    id: Result<Path<String>, PathRejection>,
    kind: JobKind,
) -> ApiResult {
    let j = load(&s, &access, parse_id(id)?, kind).await?;
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
    access: Access,
    id: Result<Path<String>, PathRejection>,
) -> ApiResult {
    events(s, access, id, JobKind::Run).await
}

async fn pga_events(
    State(s): State<AppState>,
    access: Access,
    id: Result<Path<String>, PathRejection>,
) -> ApiResult {
    events(s, access, id, JobKind::PgaSearch).await
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

/// Largest history (bytes of `histories.csv`, after `every`) answered as JSON: the JSON form is
/// built in memory (~3× the text). Larger ones come as CSV, which is streamed.
pub const MAX_JSON_HISTORY_BYTES: u64 = 32 << 20;

/// Bytes per chunk of a streamed file or history.
const CHUNK: usize = 64 * 1024;

async fn get_histories(
    State(s): State<AppState>,
    access: Access,
    id: Result<Path<String>, PathRejection>,
    query: Result<Query<Vec<(String, String)>>, QueryRejection>,
    headers: HeaderMap,
) -> ApiResult {
    use tokio::io::AsyncBufReadExt;
    let id = parse_id(id)?;
    let Query(query) = query.map_err(|e| ApiError::invalid_parameter("query", e.body_text()))?;
    if let Some((k, _)) = query
        .iter()
        .find(|(k, _)| !matches!(k.as_str(), "format" | "block" | "every" | "expires" | "sig"))
    {
        return Err(ApiError::invalid_parameter(
            k.clone(),
            format!("unknown query parameter {k:?} (known: block, format, every)"),
        ));
    }
    let format = history_format(&query, &headers)?;
    let every = match query.iter().find(|(k, _)| k == "every") {
        None => 1u64,
        Some((_, v)) => match v.parse::<u64>() {
            Ok(n) if n >= 1 => n,
            _ => {
                return Err(ApiError::invalid_parameter(
                    "every",
                    format!(
                        "every {v:?} is not a whole number ≥ 1 (keep every n-th recorded frame)"
                    ),
                ))
            }
        },
    };
    let mut blocks: Vec<String> = Vec::new();
    for (_, v) in query.iter().filter(|(k, _)| k == "block") {
        if !blocks.contains(v) {
            blocks.push(v.clone());
        }
    }
    let j = load(&s, &access, id, JobKind::Run).await?;
    artifact_available(&j, "histories")?;
    crate::service::worker::artifacts::ensure_local(&s.core, id, "histories.csv").await;
    let path = s.core.job_dir(id).join("histories.csv");
    let file = match tokio::fs::File::open(&path).await {
        Ok(f) => f,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => {
            return Err(ApiError::conflict(
                "the job finished without recording histories",
            ));
        }
        Err(e) => return Err(ApiError::internal(format!("{}: {e}", path.display()))),
    };
    let size = file
        .metadata()
        .await
        .map_err(|e| ApiError::internal(format!("{}: {e}", path.display())))?
        .len();
    let mut reader = tokio::io::BufReader::with_capacity(CHUNK, file);
    let mut header = String::new();
    reader
        .read_line(&mut header)
        .await
        .map_err(|e| ApiError::internal(format!("{}: {e}", path.display())))?;
    let head = Histories::parse_csv(header.trim_end()).map_err(ApiError::internal)?;
    let ids: Vec<String> = head.block_ids().map(str::to_string).collect();
    let mut selected: Vec<usize> = Vec::new();
    for b in &blocks {
        match ids.iter().position(|i| i == b) {
            Some(k) => selected.push(k),
            None => {
                return Err(ApiError::not_found_parameter(
                    "block",
                    format!(
                        "the job has no history for block {b:?} (it has: {})",
                        ids.join(", ")
                    ),
                ))
            }
        }
    }
    if blocks.is_empty() {
        selected = (0..ids.len()).collect();
    }
    match format {
        HistoryFormat::Json => {
            if size / every > MAX_JSON_HISTORY_BYTES {
                return Err(ApiError::not_acceptable(format!(
                    "these histories are {size} bytes of CSV; JSON is offered up to {MAX_JSON_HISTORY_BYTES} bytes \
                     (after ?every=N). Ask for format=csv (streamed), a larger ?every, or fewer ?block="
                )));
            }
            let mut text = header.clone();
            let mut lines = reader.lines();
            let mut row = 0u64;
            while let Some(line) = lines
                .next_line()
                .await
                .map_err(|e| ApiError::internal(format!("{}: {e}", path.display())))?
            {
                if line.trim().is_empty() {
                    continue;
                }
                if row % every == 0 {
                    text.push_str(&line);
                    text.push('\n');
                }
                row += 1;
            }
            let json = blocking(move || {
                let h = Histories::parse_csv(&text)?;
                let h = h
                    .select(&blocks)
                    .map_err(|b| format!("block {b:?} vanished"))?;
                Ok::<_, String>(h.to_json())
            })
            .await?
            .map_err(ApiError::internal)?;
            Ok(axum::Json(json).into_response())
        }
        HistoryFormat::Csv => {
            let mut first =
                crate::record::histories::header_line(selected.iter().map(|&k| ids[k].as_str()));
            first.push('\n');
            let all = blocks.is_empty();
            let lines = reader.lines();
            let stream = futures_util::stream::unfold(
                (lines, Some(first), 0u64, false),
                move |(mut lines, mut pending, mut row, mut done)| {
                    let selected = selected.clone();
                    async move {
                        if done {
                            return None;
                        }
                        let mut out = pending.take().unwrap_or_default();
                        while out.len() < CHUNK {
                            match lines.next_line().await {
                                Ok(Some(line)) => {
                                    if line.trim().is_empty() {
                                        continue;
                                    }
                                    let keep = row % every == 0;
                                    row += 1;
                                    if !keep {
                                        continue;
                                    }
                                    if all {
                                        out.push_str(&line);
                                    } else {
                                        let vals: Vec<&str> = line.split(',').collect();
                                        out.push_str(vals.first().copied().unwrap_or(""));
                                        for &k in &selected {
                                            for c in 1 + 3 * k..4 + 3 * k {
                                                out.push(',');
                                                out.push_str(vals.get(c).copied().unwrap_or(""));
                                            }
                                        }
                                    }
                                    out.push('\n');
                                }
                                Ok(None) => {
                                    done = true;
                                    break;
                                }
                                Err(e) => {
                                    return Some((Err(e), (lines, None, row, true)));
                                }
                            }
                        }
                        if out.is_empty() {
                            return None;
                        }
                        Some((Ok(Bytes::from(out)), (lines, None, row, done)))
                    }
                },
            );
            let mut r = Body::from_stream(stream).into_response();
            r.headers_mut().insert(
                header::CONTENT_TYPE,
                HeaderValue::from_static("text/csv; charset=utf-8"),
            );
            Ok(r)
        }
    }
}

/// `len` bytes of `file` from `start`, read and sent in chunks of [`CHUNK`]: memory stays
/// one chunk per response whatever the file's size.
fn file_body(file: tokio::fs::File, start: u64, len: u64) -> Body {
    use tokio::io::{AsyncReadExt, AsyncSeekExt};
    let stream = futures_util::stream::unfold(
        (file, start, len, false),
        |(mut f, pos, left, seeked)| async move {
            if left == 0 {
                return None;
            }
            if !seeked {
                if let Err(e) = f.seek(std::io::SeekFrom::Start(pos)).await {
                    return Some((Err(e), (f, pos, 0, true)));
                }
            }
            let mut buf = vec![0u8; usize::try_from(left).unwrap_or(CHUNK).min(CHUNK)];
            match f.read(&mut buf).await {
                Ok(0) => None,
                Ok(n) => {
                    buf.truncate(n);
                    Some((
                        Ok(Bytes::from(buf)),
                        (f, pos + n as u64, left - n as u64, true),
                    ))
                }
                Err(e) => Some((Err(e), (f, pos, 0, true))),
            }
        },
    );
    Body::from_stream(stream)
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
    access: Access,
    id: Result<Path<String>, PathRejection>,
    headers: HeaderMap,
) -> ApiResult {
    let id = parse_id(id)?;
    let j = load(&s, &access, id, JobKind::Run).await?;
    artifact_available(&j, "trajectory")?;
    crate::service::worker::artifacts::ensure_local(&s.core, id, "trajectory.mcap").await;
    let path = s.core.job_dir(id).join("trajectory.mcap");
    let file = match tokio::fs::File::open(&path).await {
        Ok(f) => f,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => {
            return Err(ApiError::conflict(
                "the job finished without recording a trajectory",
            ));
        }
        Err(e) => return Err(ApiError::internal(format!("{}: {e}", path.display()))),
    };
    let len = file
        .metadata()
        .await
        .map_err(|e| ApiError::internal(format!("{}: {e}", path.display())))?
        .len();
    let range = parse_range(
        headers.get(header::RANGE).and_then(|v| v.to_str().ok()),
        len,
    );
    let mut resp = match range {
        RangeAsk::Whole => {
            let mut r = (StatusCode::OK, file_body(file, 0, len)).into_response();
            r.headers_mut()
                .insert(header::CONTENT_LENGTH, HeaderValue::from(len));
            r
        }
        RangeAsk::Part(a, b) => {
            let mut r =
                (StatusCode::PARTIAL_CONTENT, file_body(file, a, b - a + 1)).into_response();
            if let Ok(v) = HeaderValue::from_str(&format!("bytes {a}-{b}/{len}")) {
                r.headers_mut().insert(header::CONTENT_RANGE, v);
            }
            r.headers_mut()
                .insert(header::CONTENT_LENGTH, HeaderValue::from(b - a + 1));
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
    access: Access,
    id: Result<Path<String>, PathRejection>,
) -> ApiResult {
    let id = parse_id(id)?;
    let j = load(&s, &access, id, JobKind::PgaSearch).await?;
    if j.status != JobStatus::Succeeded {
        return Err(ApiError::conflict(format!(
            "the search is {}; its fragility plot is available once it has succeeded",
            j.status.as_str()
        )));
    }
    // Written by whichever worker finished the search: fetched from shared storage if need be.
    crate::service::worker::artifacts::ensure_local(&s.core, id, "fragility.svg").await;
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
