//! HTTP layer: `GET /v1/pga-searches/{id}/fragility.svg`, the fragility plot a finished
//! multi-record search wrote.
use super::problem::ApiError;
use super::state::{load, parse_id, ApiResult, AppState};
use super::Route;
use crate::service::auth::Access;
use crate::service::store::{JobKind, JobStatus};
use axum::body::Body;
use axum::extract::rejection::PathRejection;
use axum::extract::{Path, State};
use axum::http::{header, Method};
use axum::response::IntoResponse;
use axum::routing::get;

/// The routes of this resource: method, path, handler.
pub fn routes() -> Vec<Route> {
    vec![(
        Method::GET,
        "/v1/pga-searches/{id}/fragility.svg",
        get(get_fragility_svg),
    )]
}

/// This resource's router.
pub fn router() -> axum::Router<AppState> {
    super::router_of(routes())
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
    super::downloads::ensure_local(&s.core, id, "fragility.svg").await;
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
