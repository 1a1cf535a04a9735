//! HTTP layer, shared by every resource: the handlers' state and the steps each takes (parse
//! the id, load the job the caller may see, run store work off the async threads, check the
//! media type). Imports the store and the worker's `Core`, never a resource module.
use super::problem::ApiError;
use crate::service::auth::Access;
use crate::service::store::{JobKind, JobRecord};
use crate::service::worker::Core;
use axum::extract::rejection::PathRejection;
use axum::extract::Path;
use axum::http::{header, HeaderMap, HeaderValue, StatusCode};
use axum::response::{IntoResponse, Response};
use std::sync::Arc;
use uuid::Uuid;

/// Shared state of the handlers.
#[derive(Clone)]
pub struct AppState {
    pub core: Arc<Core>,
}

pub(super) type ApiResult = Result<Response, ApiError>;

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

pub(super) fn json_response(status: StatusCode, body: String) -> Response {
    let mut r = (status, body).into_response();
    r.headers_mut().insert(
        header::CONTENT_TYPE,
        HeaderValue::from_static("application/json"),
    );
    r
}
