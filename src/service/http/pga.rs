//! HTTP layer: `/v1/pga-searches`: a PGA search (one record or several; its fragility plot is
//! `fragility`).
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
        (Method::POST, "/v1/pga-searches", post(submit)),
        (Method::GET, "/v1/pga-searches/{id}", get(read)),
        (Method::GET, "/v1/pga-searches/{id}/events", get(events)),
        (Method::POST, "/v1/pga-searches/{id}/cancel", post(cancel)),
        (Method::DELETE, "/v1/pga-searches/{id}", delete(remove)),
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
    job::submit(s, access, req, JobKind::PgaSearch).await
}

async fn read(
    State(s): State<AppState>,
    access: Access,
    id: Result<Path<String>, PathRejection>,
) -> ApiResult {
    job::get(s, access, id, JobKind::PgaSearch).await
}

async fn events(
    State(s): State<AppState>,
    access: Access,
    id: Result<Path<String>, PathRejection>,
) -> ApiResult {
    job::events(s, access, id, JobKind::PgaSearch).await
}

async fn cancel(
    State(s): State<AppState>,
    access: Access,
    id: Result<Path<String>, PathRejection>,
) -> ApiResult {
    job::cancel(s, access, id, JobKind::PgaSearch).await
}

async fn remove(
    State(s): State<AppState>,
    access: Access,
    id: Result<Path<String>, PathRejection>,
) -> ApiResult {
    job::delete(s, access, id, JobKind::PgaSearch).await
}
