//! The browser page (`GET /`, docs/web.md) and the JSON endpoints it needs beyond the job API:
//! record inspection before submitting, the list of recent jobs, a job's geometry and ground
//! motion for the animation and plots, and the bundled examples (record inspection is
//! `motion`, which uses this module's plotting helpers). One resource of the HTTP layer; the
//! page itself is plain HTML/CSS/JS under `web/`, embedded in the binary.
use super::job::job_json_signed;
use super::problem::ApiError;
use super::state::{blocking, load, parse_id, ApiResult, AppState};
use super::Route;
use crate::geometry::polygon_moments;
use crate::motion::{GroundMotion, Signal};
use crate::scene::{BlockKind, Excitation, Scene};
use crate::service::store::{JobKind, JobRecord};
use axum::extract::rejection::{PathRejection, QueryRejection};
use axum::extract::{Path, Query, State};
use axum::http::{header, HeaderValue, Method, StatusCode};
use axum::response::{IntoResponse, Response};
use axum::routing::get;
use serde_json::{json, Value};

/// The routes of the page: method, path, handler.
pub fn routes() -> Vec<Route> {
    vec![
        (Method::GET, "/", get(index)),
        (Method::GET, "/assets/{name}", get(asset)),
        (Method::GET, "/v1/jobs", get(list_jobs)),
        (Method::GET, "/v1/jobs/{id}/scene", get(job_scene)),
        (Method::GET, "/v1/jobs/{id}/ground", get(job_ground)),
        (Method::GET, "/v1/examples", get(list_examples)),
        (Method::GET, "/v1/examples/{name}", get(get_example)),
    ]
}

/// The page's router.
pub fn router() -> axum::Router<AppState> {
    super::router_of(routes())
}

/// The page and its assets: (URL path below `/`, content type, body).
const ASSETS: &[(&str, &str, &str)] = &[
    (
        "index.html",
        "text/html; charset=utf-8",
        include_str!("../../../web/index.html"),
    ),
    (
        "app.js",
        "text/javascript; charset=utf-8",
        include_str!("../../../web/app.js"),
    ),
    (
        "plot.js",
        "text/javascript; charset=utf-8",
        include_str!("../../../web/plot.js"),
    ),
    (
        "app.css",
        "text/css; charset=utf-8",
        include_str!("../../../web/app.css"),
    ),
];

/// Bundled examples: (name, kind, title, JSON text). Served from the binary so that the page
/// works without the source tree.
pub const EXAMPLES: &[(&str, &str, &str, &str)] = &[
    (
        "column",
        "scene",
        "Free-standing column on a plinth (rocking, toppling)",
        include_str!("../../../examples/column.json"),
    ),
    (
        "incline",
        "scene",
        "Block on a 20° incline (sliding)",
        include_str!("../../../examples/incline.json"),
    ),
    (
        "two-columns",
        "scene",
        "Two columns side by side (one falls, one stands: site observations)",
        include_str!("../../../examples/two-columns.json"),
    ),
    (
        "doric-colonnade",
        "scene",
        "Doric colonnade: three seven-drum columns carrying architraves (template colonnade)",
        include_str!("../../../examples/doric-colonnade.json"),
    ),
    (
        "arch",
        "scene",
        "Semicircular arch of 15 voussoirs on two piers (template arch)",
        include_str!("../../../examples/arch.json"),
    ),
    (
        "wall-window",
        "scene",
        "Running-bond wall with a window and its lintel (template wall)",
        include_str!("../../../examples/wall-window.json"),
    ),
    (
        "half-sine-pulse",
        "motion",
        "Half-sine pulse, 5 m/s², 1 s period",
        include_str!("../../../examples/half-sine-pulse.json"),
    ),
];

/// Knobs of the page's endpoints.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct WebParams {
    /// Default and largest number of points of a sampled series sent to the page. 4000 is more
    /// than a laptop plot has pixels across, and keeps a 40-minute record's reply under 200 kB.
    pub series_points: usize,
    pub max_series_points: usize,
    /// Default and largest number of jobs listed by `GET /v1/jobs`.
    pub list_default: usize,
    pub list_max: usize,
    /// Work budget of one inspection, in oscillator substeps (samples × Σ substeps per period).
    /// The spectrum splits each record step so that a period spans ≥ 20 substeps; a record with
    /// a coarse step and many samples could otherwise tie a thread for minutes. 2·10⁹ is a few
    /// seconds of CPU; a real record (8000 samples at 5 ms) needs about 10⁷.
    pub inspect_budget: f64,
}

impl Default for WebParams {
    fn default() -> Self {
        Self {
            series_points: 4000,
            max_series_points: 100_000,
            list_default: 50,
            list_max: 500,
            inspect_budget: 2.0e9,
        }
    }
}

/// `GET /` and `GET /index.html`.
pub async fn index() -> Response {
    asset_response("index.html").unwrap_or_else(|e| e.into_response())
}

/// `GET /assets/{name}`.
pub async fn asset(name: Result<Path<String>, PathRejection>) -> ApiResult {
    let Path(name) = name.map_err(|e| ApiError::invalid_parameter("name", e.body_text()))?;
    asset_response(&name)
}

fn asset_response(name: &str) -> ApiResult {
    let (_, ct, body) = ASSETS
        .iter()
        .find(|(n, _, _)| *n == name)
        .ok_or_else(|| ApiError::not_found_parameter("name", format!("no asset {name:?}")))?;
    let mut r = (StatusCode::OK, *body).into_response();
    let h = r.headers_mut();
    h.insert(header::CONTENT_TYPE, HeaderValue::from_static(ct));
    // The assets change with the binary only; a short cache keeps upgrades visible.
    h.insert(
        header::CACHE_CONTROL,
        HeaderValue::from_static("public, max-age=60"),
    );
    Ok(r)
}

/// `GET /v1/examples`: the bundled scenes and motions.
pub async fn list_examples() -> Response {
    let items: Vec<Value> = EXAMPLES
        .iter()
        .map(|(name, kind, title, _)| {
            json!({"name": name, "kind": kind, "title": title, "url": format!("/v1/examples/{name}")})
        })
        .collect();
    axum::Json(json!({ "examples": items })).into_response()
}

/// `GET /v1/examples/{name}`: one bundled example, as JSON.
pub async fn get_example(name: Result<Path<String>, PathRejection>) -> ApiResult {
    let Path(name) = name.map_err(|e| ApiError::invalid_parameter("name", e.body_text()))?;
    let (_, _, _, text) = EXAMPLES
        .iter()
        .find(|(n, _, _, _)| *n == name)
        .ok_or_else(|| ApiError::not_found_parameter("name", format!("no example {name:?}")))?;
    let mut r = (StatusCode::OK, *text).into_response();
    r.headers_mut().insert(
        header::CONTENT_TYPE,
        HeaderValue::from_static("application/json"),
    );
    Ok(r)
}

pub(super) fn query_usize(
    query: &[(String, String)],
    name: &str,
    default: usize,
    max: usize,
) -> Result<usize, ApiError> {
    match query.iter().rev().find(|(k, _)| k == name) {
        None => Ok(default),
        Some((_, v)) => match v.parse::<usize>() {
            Ok(n) if (1..=max).contains(&n) => Ok(n),
            _ => Err(ApiError::invalid_parameter(
                name,
                format!("?{name}={v:?}: expected an integer in 1..={max}"),
            )),
        },
    }
}

/// `GET /v1/jobs?limit=N&kind=run|pga_search|site_analysis`: recent jobs and searches, newest first, each as
/// `GET /v1/jobs/{id}` (or `/v1/pga-searches/{id}`) answers.
pub async fn list_jobs(
    State(s): State<AppState>,
    access: crate::service::auth::Access,
    query: Result<Query<Vec<(String, String)>>, QueryRejection>,
) -> ApiResult {
    let Query(query) = query.map_err(|e| ApiError::invalid_parameter("query", e.body_text()))?;
    let p = WebParams::default();
    let limit = query_usize(&query, "limit", p.list_default, p.list_max)?;
    let kind = match query.iter().rev().find(|(k, _)| k == "kind") {
        None => None,
        Some((_, v)) => Some(match v.as_str() {
            "run" => JobKind::Run,
            "pga_search" => JobKind::PgaSearch,
            "site_analysis" => JobKind::SiteAnalysis,
            other => {
                return Err(ApiError::invalid_parameter(
                    "kind",
                    format!("?kind={other:?}: expected run, pga_search or site_analysis"),
                ))
            }
        }),
    };
    let store = s.core.store.clone();
    // A user token lists its own jobs; an admin token (or no tokens) everyone's.
    let owner = access.list_filter().map(str::to_string);
    let jobs = blocking(move || store.list_owned(limit, kind, owner.as_deref()))
        .await?
        .map_err(ApiError::store)?;
    let body = format!(
        "{{\"jobs\":[{}]}}",
        jobs.iter()
            .map(|j| job_json_signed(j, s.core.server.signing.as_ref()))
            .collect::<Vec<_>>()
            .join(",")
    );
    let mut r = (StatusCode::OK, body).into_response();
    r.headers_mut().insert(
        header::CONTENT_TYPE,
        HeaderValue::from_static("application/json"),
    );
    Ok(r)
}

/// The scene and motion of a stored run, re-read from its request (validated at submission).
fn stored_input(j: &JobRecord) -> Result<(Scene, GroundMotion), ApiError> {
    let scene = crate::scene::scene_from_value(&j.request["scene"])
        .map_err(|e| ApiError::internal(format!("stored scene of job {}: {e:?}", j.id)))?;
    let motion = match j.request.get("motion") {
        None | Some(Value::Null) => GroundMotion::none(),
        Some(m) => crate::motion::from_json(m)
            .map_err(|e| ApiError::internal(format!("stored motion of job {}: {e}", j.id)))?,
    };
    Ok((scene, motion))
}

/// The geometry the page draws: every block's outline (counter-clockwise, m), its centroid (the
/// point whose displacement `histories` reports and about which it rotates), area and role.
pub fn scene_geometry(scene: &Scene) -> Value {
    let driven = match scene.excitation {
        Excitation::DrivenBlock(i) => Some(i),
        Excitation::BaseAcceleration => None,
    };
    let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
    let blocks: Vec<Value> = scene
        .blocks
        .iter()
        .enumerate()
        .map(|(i, b)| {
            let m = polygon_moments(&b.vertices);
            for v in &b.vertices {
                lo = [lo[0].min(v.x), lo[1].min(v.y)];
                hi = [hi[0].max(v.x), hi[1].max(v.y)];
            }
            json!({
                "id": b.id,
                "fixed": matches!(b.kind, BlockKind::Fixed),
                "driven": driven == Some(i),
                "vertices": b.vertices.iter().map(|v| [v.x, v.y]).collect::<Vec<_>>(),
                "centroid": [m.centroid.x, m.centroid.y],
                "area": m.area,
            })
        })
        .collect();
    json!({
        "name": scene.name,
        "excitation": match driven {
            Some(i) => json!({"type": "driven_block", "block": scene.blocks[i].id}),
            None => json!({"type": "base_acceleration"}),
        },
        "bounds": {"min": lo, "max": hi},
        "blocks": blocks,
    })
}

/// `GET /v1/jobs/{id}/scene`.
pub async fn job_scene(
    State(s): State<AppState>,
    access: crate::service::auth::Access,
    id: Result<Path<String>, PathRejection>,
) -> ApiResult {
    let j = load(&s, &access, parse_id(id)?, JobKind::Run).await?;
    let body =
        blocking(move || stored_input(&j).map(|(scene, _)| scene_geometry(&scene))).await??;
    Ok(axum::Json(body).into_response())
}

/// Ground acceleration, velocity and displacement (scaled, m/s², m/s, m) on `n + 1` uniform
/// times over `[0, duration]`.
pub fn ground_series(motion: &GroundMotion, duration: f64, n: usize) -> Value {
    let n = n.max(1);
    let dt = duration / n as f64;
    let mut time = Vec::with_capacity(n + 1);
    let (mut a, mut v, mut d, mut av) = (
        Vec::with_capacity(n + 1),
        Vec::with_capacity(n + 1),
        Vec::with_capacity(n + 1),
        Vec::with_capacity(n + 1),
    );
    for i in 0..=n {
        let t = i as f64 * dt;
        let [acc, vel, disp] = motion.state(t);
        time.push(t);
        a.push(acc[0]);
        v.push(vel[0]);
        d.push(disp[0]);
        av.push(acc[1]);
    }
    let vertical = !matches!(motion.vertical, Signal::Zero);
    json!({
        "units": {"time": "s", "acceleration": "m/s2", "velocity": "m/s", "displacement": "m"},
        "pga": motion.pga(),
        "time": time,
        "acceleration": a,
        "velocity": v,
        "displacement": d,
        "vertical_acceleration": if vertical { json!(av) } else { Value::Null },
    })
}

/// `GET /v1/jobs/{id}/ground?points=N`: the ground motion the run felt, over its duration.
pub async fn job_ground(
    State(s): State<AppState>,
    access: crate::service::auth::Access,
    id: Result<Path<String>, PathRejection>,
    query: Result<Query<Vec<(String, String)>>, QueryRejection>,
) -> ApiResult {
    let Query(query) = query.map_err(|e| ApiError::invalid_parameter("query", e.body_text()))?;
    let p = WebParams::default();
    let points = query_usize(&query, "points", p.series_points, p.max_series_points)?;
    let j = load(&s, &access, parse_id(id)?, JobKind::Run).await?;
    let body = blocking(move || {
        let (scene, motion) = stored_input(&j)?;
        let duration = crate::analysis::run::duration(&scene, &motion).unwrap_or(0.0);
        // No more points than the record has samples over the run (no invented detail).
        let native = match &motion.horizontal {
            Signal::Sampled(x) if x.dt > 0.0 => (duration / x.dt).ceil() as usize,
            _ => points,
        };
        Ok::<_, ApiError>(ground_series(&motion, duration, points.min(native.max(1))))
    })
    .await??;
    Ok(axum::Json(body).into_response())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn assets_and_examples_are_embedded() {
        for (n, _, _, text) in EXAMPLES {
            let v: Value = serde_json::from_str(text).expect(n);
            assert!(v.is_object(), "{n}");
        }
        assert!(ASSETS.iter().any(|(n, _, _)| *n == "index.html"));
    }
}
