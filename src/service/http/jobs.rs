//! HTTP layer: `/v1/jobs`: one run of the engine (submit, read, follow, cancel, delete; its histories and
//! trajectory are `downloads`).
use super::job::{kind_routes, KindPaths};
use super::state::AppState;
use super::Route;
use crate::service::store::JobKind;
use axum::http::Method;
use axum::routing::get;

/// The routes of this resource: method, path, handler (those of every job kind, `job`, and a
/// run's downloads).
pub fn routes() -> Vec<Route> {
    let mut routes = kind_routes(
        JobKind::Run,
        KindPaths {
            collection: "/v1/jobs",
            item: "/v1/jobs/{id}",
            events: "/v1/jobs/{id}/events",
            cancel: "/v1/jobs/{id}/cancel",
        },
    );
    routes.extend([
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
    ]);
    routes
}

/// This resource's router.
pub fn router() -> axum::Router<AppState> {
    super::router_of(routes())
}
