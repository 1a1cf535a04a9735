//! HTTP layer: what every job kind's resource does alike (submit, read, cancel, delete,
//! follow its events) and a job's JSON with its links. `jobs`, `pga` and `site` route to these
//! with their kind.
use super::problem::ApiError;
use super::state::{
    blocking, check_json_content_type, json_response, load, parse_id, ApiResult, AppState,
};
use crate::service::auth::Access;
use crate::service::events::{job_events, job_stream, EventParams, JobEvent};
use crate::service::request::budget;
use crate::service::request::{json_body, parse_pga, parse_run, parse_site};
use crate::service::store::{
    rfc3339, CancelOutcome, DeleteOutcome, JobKind, JobRecord, JobStatus, NewJob, QueueFull,
};
use crate::service::worker::Core;
use axum::body::Bytes;
use axum::extract::rejection::PathRejection;
use axum::extract::Path;
use axum::http::{header, HeaderValue, StatusCode};
use axum::response::sse::{KeepAlive, Sse};
use axum::response::IntoResponse;
use serde_json::{json, Value};
use std::sync::atomic::Ordering;
use std::time::Duration;
use uuid::Uuid;

pub(super) fn base(kind: JobKind) -> &'static str {
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
pub(super) async fn read_body(
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

pub(super) async fn submit(
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
        budget::prescan(&bytes, &limits)?;
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

/// `DELETE /v1/jobs/{id}`: a finished job and its artifacts go (204); a job still queued or
/// running is refused (409: cancel it first).
pub(super) async fn delete(
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
            blocking(move || core.remove_artifacts(id)).await?;
            Ok(StatusCode::NO_CONTENT.into_response())
        }
    }
}

pub(super) async fn cancel(
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

pub(super) async fn events(
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
    let events = job_events(
        j.id,
        current,
        s.core.store.clone(),
        &s.core.hub,
        s.core.shutdown_signal.subscribe(),
        EventParams::default(),
    );
    let stream = job_stream(j.id, events);
    Ok(Sse::new(stream)
        .keep_alive(KeepAlive::new().interval(Duration::from_secs(15)))
        .into_response())
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
pub(super) fn with_raw_field(obj: &Value, key: &str, raw: Option<&str>) -> String {
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

/// `GET /v1/{kind}/{id}`: the job as JSON (with signed links when the server signs them).
pub(super) async fn get(
    s: AppState,
    access: Access,
    id: Result<Path<String>, PathRejection>,
    kind: JobKind,
) -> ApiResult {
    let j = load(&s, &access, parse_id(id)?, kind).await?;
    Ok(json_response(
        StatusCode::OK,
        job_json_signed(&j, s.core.server.signing.as_ref()),
    ))
}

/// The paths of a job kind's resource: the collection (`POST` submits) and a job in it (`GET`
/// reads, `DELETE` removes), its event stream and its cancel.
pub(super) struct KindPaths {
    pub collection: &'static str,
    pub item: &'static str,
    pub events: &'static str,
    pub cancel: &'static str,
}

/// The five routes every job kind's resource has (submit, read, events, cancel, delete), each
/// handled by this module with `kind`.
pub(super) fn kind_routes(kind: JobKind, p: KindPaths) -> Vec<super::Route> {
    use axum::extract::{Request, State};
    use axum::http::Method;
    use axum::routing::{delete as delete_route, get as get_route, post};
    type Id = Result<Path<String>, PathRejection>;
    vec![
        (
            Method::POST,
            p.collection,
            post(move |State(s): State<AppState>, a: Access, r: Request| submit(s, a, r, kind)),
        ),
        (
            Method::GET,
            p.item,
            get_route(move |State(s): State<AppState>, a: Access, id: Id| get(s, a, id, kind)),
        ),
        (
            Method::GET,
            p.events,
            get_route(move |State(s): State<AppState>, a: Access, id: Id| events(s, a, id, kind)),
        ),
        (
            Method::POST,
            p.cancel,
            post(move |State(s): State<AppState>, a: Access, id: Id| cancel(s, a, id, kind)),
        ),
        (
            Method::DELETE,
            p.item,
            delete_route(move |State(s): State<AppState>, a: Access, id: Id| {
                delete(s, a, id, kind)
            }),
        ),
    ]
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
}
