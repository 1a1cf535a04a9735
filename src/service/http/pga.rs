//! HTTP layer: `/v1/pga-searches`: a PGA search (one record or several; its fragility plot is
//! `fragility`).
use super::job::{kind_routes, KindPaths};
use super::state::AppState;
use super::Route;
use crate::service::store::JobKind;

/// The routes of this resource: method, path, handler (those of every job kind, `job`).
pub fn routes() -> Vec<Route> {
    kind_routes(
        JobKind::PgaSearch,
        KindPaths {
            collection: "/v1/pga-searches",
            item: "/v1/pga-searches/{id}",
            events: "/v1/pga-searches/{id}/events",
            cancel: "/v1/pga-searches/{id}/cancel",
        },
    )
}

/// This resource's router.
pub fn router() -> axum::Router<AppState> {
    super::router_of(routes())
}
