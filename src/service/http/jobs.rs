//! HTTP layer: `/v1/jobs`: one run of the engine (submit, read, follow, cancel, delete; its histories and
//! trajectory are `downloads`).
use super::state::{ApiResult, AppState};
use super::{job, Route};
use crate::service::auth::Access;
use crate::service::store::JobKind;
use axum::extract::rejection::PathRejection;
use axum::extract::{Path, State};
use axum::http::Method;
use axum::routing::{delete, get, post};

/// The routes of this resource: method, path, handler.
pub fn routes() -> Vec<Route> {
    vec![
        (Method::POST, "/v1/jobs", post(submit)),
        (Method::GET, "/v1/jobs/{id}", get(read)),
        (Method::GET, "/v1/jobs/{id}/events", get(events)),
        (Method::POST, "/v1/jobs/{id}/cancel", post(cancel)),
        (Method::DELETE, "/v1/jobs/{id}", delete(remove)),
        (
            Method::GET,
            "/v1/jobs/{id}/histories",
            get(super::downloads::get_histories),
        ),
        (
            Method::GET,
            "/v1/jobs/{id}/trajectory.mcap",
            get(super::downloads::get_trajectory),
        ),
    ]
}

/// This resource's router.
pub fn router() -> axum::Router<AppState> {
    super::router_of(routes())
}

async fn submit(
    State(s): State<AppState>,
    access: Access,
    req: axum::extract::Request,
) -> ApiResult {
    job::submit(s, access, req, JobKind::Run).await
}

async fn read(
    State(s): State<AppState>,
    access: Access,
    id: Result<Path<String>, PathRejection>,
) -> ApiResult {
    job::get(s, access, id, JobKind::Run).await
}

async fn events(
    State(s): State<AppState>,
    access: Access,
    id: Result<Path<String>, PathRejection>,
) -> ApiResult {
    job::events(s, access, id, JobKind::Run).await
}

async fn cancel(
    State(s): State<AppState>,
    access: Access,
    id: Result<Path<String>, PathRejection>,
) -> ApiResult {
    job::cancel(s, access, id, JobKind::Run).await
}

async fn remove(
    State(s): State<AppState>,
    access: Access,
    id: Result<Path<String>, PathRejection>,
) -> ApiResult {
    job::delete(s, access, id, JobKind::Run).await
}
