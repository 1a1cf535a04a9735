//! `GET /v1/templates` and `POST /v1/templates/{name}`: the parametric structures of
//! `scene::templates` over HTTP (docs/templates.md). Thin: parameters in, scene JSON out; building a
//! template is cheap (no simulation), so it runs on the request's task.
use super::problem::ApiError;
use super::state::{check_json_content_type, AppState};
use super::Route;
use crate::scene::templates::{self, TemplateError};
use crate::service::request::json_body;
use axum::body::Bytes;
use axum::extract::rejection::{BytesRejection, PathRejection};
use axum::extract::{Path, State};
use axum::http::{HeaderMap, Method};
use axum::response::{IntoResponse, Response};
use axum::routing::{get, post};
use serde_json::{json, Value};
use std::collections::BTreeMap;

/// The routes of this resource: method, path, handler.
pub fn routes() -> Vec<Route> {
    vec![
        (Method::GET, "/v1/templates", get(list)),
        (Method::POST, "/v1/templates/{name}", post(build)),
    ]
}

/// This resource's router.
pub fn router() -> axum::Router<AppState> {
    super::router_of(routes())
}

/// `GET /v1/templates`: `{"templates": [{name, description, parameters: [{name, units,
/// description, default, min, max, choices?}]}]}`.
pub async fn list() -> Response {
    axum::Json(json!({ "templates": templates::list() })).into_response()
}

/// `POST /v1/templates/{name}` with an optional body `{"parameters": {KEY: VALUE}}` → 200 and
/// the scene (`ashlar.scene/1`), ready to be sent as a job's `scene`. 404 for an unknown
/// template (`parameter: "name"`); 422 for a bad parameter (`pointer: /parameters/KEY`).
pub async fn build(
    State(s): State<AppState>,
    name: Result<Path<String>, PathRejection>,
    headers: HeaderMap,
    body: Result<Bytes, BytesRejection>,
) -> Result<Response, ApiError> {
    let Path(name) = name.map_err(|e| ApiError::invalid_parameter("name", e.body_text()))?;
    let template =
        templates::find(&name).map_err(|e| ApiError::not_found_parameter("name", e.to_string()))?;
    let bytes = body.map_err(|e| ApiError::unreadable_body(&e, s.core.limits.max_body_bytes))?;
    let given = if bytes.iter().all(|b| b.is_ascii_whitespace()) {
        BTreeMap::new()
    } else {
        check_json_content_type(&headers)?;
        parameters(&json_body(&bytes)?)?
    };
    let (spec, _) = template.build(&given).map_err(|e| match &e {
        TemplateError::Invalid { .. } => ApiError::internal(e),
        _ => {
            let key = e
                .parameter()
                .unwrap_or_default()
                .replace('~', "~0")
                .replace('/', "~1");
            ApiError::invalid_field(format!("/parameters/{key}"), e.to_string())
        }
    })?;
    Ok(axum::Json(spec).into_response())
}

/// `{"parameters": {...}}` (the only member; absent: every default).
fn parameters(body: &Value) -> Result<BTreeMap<String, Value>, ApiError> {
    let obj = body.as_object().ok_or_else(|| {
        ApiError::invalid_field("", "expected a JSON object {\"parameters\": {...}}")
    })?;
    if let Some(k) = obj.keys().find(|k| *k != "parameters") {
        return Err(ApiError::invalid_field(
            format!("/{k}"),
            format!("unknown field `{k}`, expected `parameters`"),
        ));
    }
    match obj.get("parameters") {
        None => Ok(BTreeMap::new()),
        Some(Value::Object(m)) => Ok(m.iter().map(|(k, v)| (k.clone(), v.clone())).collect()),
        Some(other) => Err(ApiError::invalid_field(
            "/parameters",
            format!("expected an object of parameter values, got {other}"),
        )),
    }
}
