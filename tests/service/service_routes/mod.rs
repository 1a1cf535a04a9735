//! Route tests without a socket: the router driven by `oneshot`, jobs run by the deterministic
//! fake runner (`ashlar::service::fake`), so these test the service's machinery (validation,
//! errors, queue, progress, cancellation, artifacts, restart) independently of the physics. By
//! topic: `outputs.rs` (a job's outputs, when histories are served, health and the spec),
//! `validation.rs` (bad requests and their problems), `lifecycle.rs` (cancel, progress events,
//! failures, searches, shutdown and restart). This file holds their shared setup.
mod lifecycle;
mod outputs;
mod validation;

use crate::service_support;

use ashlar::service::fake::{fake_runner, FAKE_TRAJECTORY_LEN};
use ashlar::service::{app, Limits, Service, ServiceConfig, WorkerParams};
use axum::body::Body;
use axum::http::Request;
use serde_json::{json, Value};
use service_support::*;
use std::time::{Duration, Instant};

/// Fake runner speed for most tests: 1 ms of wall time per simulated second, so a 1 s scene
/// finishes in about a millisecond.
const FAST: Duration = Duration::from_millis(1);

fn start(
    tag: &str,
    workers: usize,
    slowness: Duration,
    limits: Limits,
) -> (Service, axum::Router, std::path::PathBuf) {
    let dir = temp_dir(tag);
    let mut cfg = ServiceConfig::new(&dir);
    cfg.limits = limits;
    cfg.workers = WorkerParams {
        workers,
        idle_poll: Duration::from_millis(50),
        ..WorkerParams::default()
    };
    let server = ashlar::service::server::ServerParams {
        cors_origins: vec!["https://app.foxglove.dev".into()],
        ..Default::default()
    };
    let svc = Service::start_with(cfg, fake_runner(slowness), server).expect("start");
    let router = app(svc.state());
    (svc, router, dir)
}

async fn submit(app: &axum::Router, body: &Value) -> String {
    let r = call(app, post_json("/v1/jobs", body)).await;
    assert_eq!(r.status, 202, "{}", r.text());
    let id = r.json()["id"].as_str().expect("id").to_string();
    assert_eq!(
        r.header("location").as_deref(),
        Some(format!("/v1/jobs/{id}").as_str())
    );
    assert_eq!(r.json()["status"], "queued");
    id
}

/// `POST /v1/jobs/{id}/cancel`, empty body.
async fn cancel(app: &axum::Router, id: &str) -> Reply {
    call(
        app,
        post_raw(&format!("/v1/jobs/{id}/cancel"), "application/json", ""),
    )
    .await
}

/// A run of the column scene (`duration` s) under a 1 m/s² pulse, the job most tests submit.
fn column_job(duration: f64) -> Value {
    json!({"scene": column_scene(duration), "motion": pulse(1.0)})
}

/// Read a CSV file's columns back independently of the service's parser.
fn csv_columns(text: &str) -> (Vec<String>, Vec<Vec<f64>>) {
    let mut lines = text.lines();
    let header: Vec<String> = lines
        .next()
        .expect("header")
        .split(',')
        .map(str::to_string)
        .collect();
    let mut cols = vec![Vec::new(); header.len()];
    for l in lines.filter(|l| !l.is_empty()) {
        for (k, v) in l.split(',').enumerate() {
            cols[k].push(v.parse::<f64>().expect("number"));
        }
    }
    (header, cols)
}
