//! `POST /v1/scenes/import`: a DXF drawing in, its scene (`ashlar.scene/1`) out, through
//! `scene::import::dxf` (docs/import.md). Thin: the body is `{"dxf": TEXT, "options": {...} |
//! null}`; a refused drawing is a 422 at `/dxf` whose detail names the entity handle and layer, a
//! bad option a 422 at `/options/...`. Importing runs no simulation; its validation is the one a
//! submitted scene gets, run on the blocking pool.
use super::problem::{dotted_to_pointer, point_at_named_field, ApiError};
use super::state::{blocking, check_json_content_type, AppState};
use super::Route;
use crate::scene::import::dxf::{self, DxfImportError, ImportOptions};
use crate::service::request::budget::check_ranges;
use crate::service::request::json_body;
use axum::body::Bytes;
use axum::extract::rejection::BytesRejection;
use axum::extract::State;
use axum::http::{HeaderMap, Method};
use axum::response::{IntoResponse, Response};
use axum::routing::post;
use serde_json::Value;

/// The routes of this resource: method, path, handler.
pub fn routes() -> Vec<Route> {
    vec![(Method::POST, "/v1/scenes/import", post(import))]
}

/// This resource's router.
pub fn router() -> axum::Router<AppState> {
    super::router_of(routes())
}

pub async fn import(
    State(s): State<AppState>,
    headers: HeaderMap,
    body: Result<Bytes, BytesRejection>,
) -> Result<Response, ApiError> {
    let bytes = body.map_err(|e| ApiError::unreadable_body(&e, s.core.limits.max_body_bytes))?;
    check_json_content_type(&headers)?;
    let body = json_body(&bytes)?;
    let (text, options) = parse(body)?;
    let imported = blocking(move || dxf::import(text.as_bytes(), &options))
        .await?
        .map_err(|e| problem(&e))?;
    Ok(axum::Json(imported.spec).into_response())
}

/// `{"dxf": TEXT, "options": {...} | null}`; `options` may be absent.
fn parse(body: Value) -> Result<(String, ImportOptions), ApiError> {
    let Value::Object(mut obj) = body else {
        return Err(ApiError::invalid_field(
            "",
            "expected a JSON object {\"dxf\": \"<the DXF file's text>\", \"options\": {...}}",
        ));
    };
    if let Some(k) = obj.keys().find(|k| *k != "dxf" && *k != "options") {
        let escaped = k.replace('~', "~0").replace('/', "~1");
        return Err(ApiError::invalid_field(
            format!("/{escaped}"),
            format!("unknown field `{k}`, expected `dxf` or `options`"),
        ));
    }
    let text = match obj.remove("dxf") {
        Some(Value::String(t)) => t,
        None => {
            return Err(ApiError::invalid_field(
                "/dxf",
                "missing field `dxf`: the DXF file's text",
            ))
        }
        Some(other) => {
            return Err(ApiError::invalid_field(
                "/dxf",
                format!("expected the DXF file's text as a string, got {other}"),
            ))
        }
    };
    let options = ImportOptions::from_value(obj.get("options").unwrap_or(&Value::Null))
        .map_err(|e| problem(&e))?;
    check_option_ranges(&options)?;
    Ok((text, options))
}

/// The options' material and joint values within the ranges a submitted scene's are held to
/// (`budget::check_ranges`, docs/format.md "Ranges"), so that the scene answered is one a job
/// accepts; the pointer is moved from the scene to the options.
fn check_option_ranges(options: &ImportOptions) -> Result<(), ApiError> {
    let mut joints = serde_json::Map::new();
    if let Some(j) = &options.joint {
        joints.insert(
            "joint".into(),
            serde_json::to_value(j).map_err(ApiError::internal)?,
        );
    }
    let as_scene = serde_json::json!({ "materials": options.materials, "joints": joints });
    check_ranges(&as_scene).map_err(|e| {
        let mut e = ApiError::from(e);
        if let Some(p) = &e.pointer {
            let moved = p.replacen("/scene/joints/joint", "/options/joint", 1);
            let moved = moved.replacen("/scene/", "/options/", 1);
            e.detail = e.detail.replacen(p.as_str(), &moved, 1);
            e.pointer = Some(moved);
        }
        e
    })
}

/// A refusal as a problem: at `/options/...` when an option is at fault, else at `/dxf`.
fn problem(e: &DxfImportError) -> ApiError {
    match e.options_path() {
        Some(path) => {
            let message = match e {
                DxfImportError::Options { message, .. } => message.as_str(),
                _ => "",
            };
            let pointer = point_at_named_field(dotted_to_pointer("/options", path), message);
            ApiError::invalid_field(pointer, e.to_string())
        }
        None => ApiError::invalid_field("/dxf", e.to_string()),
    }
}
