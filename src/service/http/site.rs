//! HTTP layer: `/v1/site-analyses`: a site analysis (observations × records).
use super::job::{kind_routes, KindPaths};
use super::state::AppState;
use super::Route;
use crate::service::store::JobKind;

/// The routes of this resource: method, path, handler (those of every job kind, `job`).
pub fn routes() -> Vec<Route> {
    kind_routes(
        JobKind::SiteAnalysis,
        KindPaths {
            collection: "/v1/site-analyses",
            item: "/v1/site-analyses/{id}",
            events: "/v1/site-analyses/{id}/events",
            cancel: "/v1/site-analyses/{id}/cancel",
        },
    )
}

/// This resource's router.
pub fn router() -> axum::Router<AppState> {
    super::router_of(routes())
}
