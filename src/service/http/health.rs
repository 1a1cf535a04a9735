//! HTTP layer: `GET /healthz` (answered from memory) and `GET /v1/limits` (what a client may
//! send, and how this process runs jobs).
use super::problem::ApiError;
use super::state::{blocking, ApiResult, AppState};
use super::Route;
use crate::service::worker::Core;
use axum::extract::State;
use axum::http::Method;
use axum::response::IntoResponse;
use axum::routing::get;
use serde_json::{json, Value};
use std::sync::atomic::Ordering;

/// The routes of this resource: method, path, handler.
pub fn routes() -> Vec<Route> {
    vec![
        (Method::GET, "/healthz", get(healthz)),
        (Method::GET, "/v1/limits", get(get_limits)),
    ]
}

/// This resource's router.
pub fn router() -> axum::Router<AppState> {
    super::router_of(routes())
}

/// `GET /v1/limits`: the server's limits, so that a client can check a job before sending it.
async fn get_limits(State(s): State<AppState>) -> ApiResult {
    let l = &s.core.limits;
    let p = &s.core.server;
    let mut body = json!({
        "max_body_bytes": l.max_body_bytes,
        "max_json_values": l.max_json_values,
        "max_blocks": l.max_blocks,
        "max_block_vertices": l.max_block_vertices,
        "max_record_samples": l.max_record_samples,
        "max_total_steps": l.max_total_steps,
        "max_block_steps": l.max_block_steps,
        "max_block_frames": l.max_block_frames,
        "max_search_block_steps": l.max_search_block_steps,
        "max_scan_points": l.max_scan_points,
        "max_records": crate::service::request::MAX_RECORDS,
        "max_queued_jobs": l.max_queued_jobs,
        "max_queued_jobs_per_token": l.max_queued_jobs_per_token,
        "max_queued_searches_per_token": l.max_queued_searches_per_token,
        "retain_finished_s": l.retain_finished.map(|d| d.as_secs_f64()),
        "max_job_seconds": l.max_job_seconds,
        "max_job_artifact_bytes": l.max_job_artifact_bytes,
        "max_artifact_bytes": l.max_artifact_bytes,
        "max_connections": p.max_connections,
        "header_timeout_s": p.header_read_timeout.as_secs_f64(),
        "body_timeout_s": p.body_read_timeout.as_secs_f64(),
        "idle_timeout_s": p.idle_timeout.as_secs_f64(),
        "max_header_bytes": p.max_header_bytes,
        "max_headers": p.max_headers,
        "ranges": crate::service::request::budget::ranges_json(),
    });
    if let Some(o) = body.as_object_mut() {
        o.extend(process_limits(&s.core));
        let store = s.core.store.clone();
        let published = blocking(move || store.published_limits("worker"))
            .await?
            .unwrap_or_else(|e| {
                tracing::warn!(error = %e, "reading the workers' published limits");
                Vec::new()
            });
        let sets = worker_limit_sets(published);
        // An API-only process runs no job: what a job gets is what its workers apply (the
        // setting most of them share; `worker_limits` lists every one).
        if s.core.params.workers == 0 {
            if let Some(most) = sets.first() {
                for k in [
                    "isolation",
                    "job_memory_limit_bytes",
                    "job_cpu_seconds",
                    "max_job_seconds",
                    "max_job_artifact_bytes",
                ] {
                    if let Some(v) = most.get(k) {
                        o.insert(k.into(), v.clone());
                    }
                }
            }
        }
        o.insert("worker_limits".into(), Value::Array(sets));
    }
    Ok(axum::Json(body).into_response())
}

/// The distinct limit settings of a cluster's live workers (published `(process, JSON)`
/// pairs), each with the number of worker processes applying it, the most common first.
fn worker_limit_sets(published: Vec<(String, String)>) -> Vec<Value> {
    let mut counts: std::collections::BTreeMap<String, u64> = Default::default();
    for (_, text) in published {
        *counts.entry(text).or_default() += 1;
    }
    let mut sets: Vec<(u64, Value)> = counts
        .into_iter()
        .filter_map(|(text, n)| match serde_json::from_str::<Value>(&text) {
            Ok(Value::Object(mut m)) => {
                m.insert("processes".into(), json!(n));
                Some((n, Value::Object(m)))
            }
            _ => None,
        })
        .collect();
    sets.sort_by_key(|b| std::cmp::Reverse(b.0));
    sets.into_iter().map(|(_, v)| v).collect()
}

/// The limits of this process's job runs and of its request handling not in `Limits`: where
/// jobs run and the resource limits of a job's process (`--isolation`, `--job-memory-limit`,
/// `--job-cpu-seconds`; null with threads), crash retries, large bodies parsed at once, the
/// signed links' validity (null without `--tokens`).
fn process_limits(core: &Core) -> serde_json::Map<String, Value> {
    use crate::service::worker::runner::Isolation;
    let (mode, memory, cpu) = match &core.params.isolation {
        Isolation::Thread => ("thread", None, None),
        Isolation::Process(p) => ("process", Some(p.memory_limit), Some(p.cpu_seconds)),
    };
    let v = json!({
        "isolation": mode,
        "job_memory_limit_bytes": memory,
        "job_cpu_seconds": cpu,
        "max_job_attempts": core.params.max_attempts,
        "max_large_bodies": crate::service::worker::LARGE_BODIES,
        "large_body_bytes": crate::service::worker::LARGE_BODY_BYTES,
        "signed_url_seconds": core.server.signing.as_ref().map(|k| k.validity.as_secs()),
    });
    match v {
        Value::Object(m) => m,
        _ => serde_json::Map::new(),
    }
}

async fn healthz(State(s): State<AppState>) -> ApiResult {
    // Answered from memory only: it must stay fast while the store is busy with submissions.
    let c = &s.core;
    let alive = c.workers_alive.load(Ordering::SeqCst);
    if c.shutting_down.load(Ordering::SeqCst) {
        return Err(ApiError::unavailable("the server is shutting down", 5));
    }
    if alive == 0 && !c.remote_workers.load(Ordering::SeqCst) {
        return Err(ApiError::unavailable("no worker thread is running", 5));
    }
    if !c.store_healthy.load(Ordering::Relaxed) {
        return Err(ApiError::unavailable(
            "the job store is failing; see the server log",
            5,
        ));
    }
    let body = json!({
        "status": "ok",
        "version": env!("CARGO_PKG_VERSION"),
        "workers": alive,
        "running": c.running_here(),
    });
    Ok(axum::Json(body).into_response())
}
