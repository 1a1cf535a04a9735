//! HTTP layer: `GET /openapi.yaml`, the hand-written OpenAPI description of every route
//! (`tests/service/service_openapi.rs` compares it with `route_table` both ways).
use super::state::AppState;
use super::Route;
use axum::http::{header, Method};
use axum::response::{IntoResponse, Response};
use axum::routing::get;

/// The routes of this resource: method, path, handler.
pub fn routes() -> Vec<Route> {
    vec![(Method::GET, "/openapi.yaml", get(openapi))]
}

/// This resource's router.
pub fn router() -> axum::Router<AppState> {
    super::router_of(routes())
}

/// The hand-written OpenAPI 3.1 description, served at `/openapi.yaml`.
pub const OPENAPI_YAML: &str = include_str!("../../../openapi.yaml");

async fn openapi() -> Response {
    ([(header::CONTENT_TYPE, "application/yaml")], OPENAPI_YAML).into_response()
}
