//! HTTP layer (docs/format.md §4, `openapi.yaml`): thin async handlers that validate, talk to
//! the store on the blocking pool, and answer; no simulation work happens here. One module per
//! resource, each with its `routes()` and `router()`, merged by [`app`], which adds the layers
//! every request crosses (authorization, header limits, body limit, CORS, problem bodies for
//! axum's bare errors). `service::request` (beside `jobs`, shared with the worker) parses
//! submissions into `JobInput`s; `problem` is the HTTP edge of every error. Imports go
//! resource → `job`/`state` → store and worker; `web` and the resources never import this
//! module's assembly, nor each other except `motion` → `web`'s plotting helpers.
mod downloads;
mod fragility;
mod health;
mod job;
mod jobs;
mod motion;
mod openapi;
mod pga;
pub mod problem;
pub mod scene_import;
mod site;
mod state;
pub mod templates;
pub mod web;

pub use downloads::MAX_JSON_HISTORY_BYTES;
pub use openapi::OPENAPI_YAML;
pub use state::AppState;

use crate::service::auth::Access;
use axum::extract::DefaultBodyLimit;
use axum::http::{header, HeaderMap, HeaderValue, Method, StatusCode};
use axum::response::{IntoResponse, Response};
use axum::routing::MethodRouter;
use axum::Router;
use problem::ApiError;
use serde_json::json;

/// One route: method, path, handler.
pub type Route = (Method, &'static str, MethodRouter<AppState>);

/// Every route of every resource: method, path, handler. The tests compare it with
/// `openapi.yaml` in both directions; a 405 names the methods it lists at the path.
pub fn route_table() -> Vec<Route> {
    [
        jobs::routes(),
        pga::routes(),
        fragility::routes(),
        site::routes(),
        motion::routes(),
        templates::routes(),
        scene_import::routes(),
        web::routes(),
        health::routes(),
        openapi::routes(),
    ]
    .concat()
}

/// A resource's router from its routes (two methods at one path share the path's router).
fn router_of(routes: Vec<Route>) -> Router<AppState> {
    routes
        .into_iter()
        .fold(Router::new(), |r, (_, path, handler)| {
            r.route(path, handler)
        })
}

/// The service's router (testable without a socket through `tower::ServiceExt::oneshot`).
pub fn app(state: AppState) -> Router {
    // Resources sharing a path (`/v1/jobs`: POST here, GET for the page) merge method by method.
    let router = Router::new()
        .merge(jobs::router())
        .merge(pga::router())
        .merge(fragility::router())
        .merge(site::router())
        .merge(motion::router())
        .merge(templates::router())
        .merge(scene_import::router())
        .merge(web::router())
        .merge(health::router())
        .merge(openapi::router());
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
