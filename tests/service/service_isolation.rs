//! Job isolation (`ashlar serve --isolation process`): each job runs in a child `ashlar
//! internal-run-job` process with resource limits. A job that exhausts its memory, crashes or
//! panics fails alone with a cause that names it, while another job on another worker
//! succeeds; progress and cancellation still flow through the child.
//!
//! The misbehaving jobs use the child's test-only fault trigger (debug builds with
//! `ASHLAR_TEST_FAULTS=1` in the child's environment; scenes named `fault:…`).
use crate::service_support;

use ashlar::service::runner::{Isolation, ProcessParams};
use ashlar::service::{analysis_runner, app, Service, ServiceConfig, WorkerParams};
use serde_json::{json, Value};
use service_support::*;
use std::time::Duration;

fn start(
    tag: &str,
    workers: usize,
    tune: impl FnOnce(&mut ProcessParams),
) -> (Service, axum::Router) {
    let dir = temp_dir(tag);
    let mut cfg = ServiceConfig::new(&dir);
    let mut p = ProcessParams::new(env!("CARGO_BIN_EXE_ashlar").into());
    p.env.push(("ASHLAR_TEST_FAULTS".into(), "1".into()));
    tune(&mut p);
    cfg.workers = WorkerParams {
        workers,
        idle_poll: Duration::from_millis(50),
        isolation: Isolation::Process(p),
        ..WorkerParams::default()
    };
    // The in-process runner is never used with process isolation: the child runs the engine.
    let svc = Service::start(cfg, analysis_runner()).expect("start");
    let router = app(svc.state());
    (svc, router)
}

fn faulty(name: &str) -> Value {
    let mut s = column_scene(1.0);
    s["name"] = json!(name);
    json!({"scene": s, "motion": pulse(3.0)})
}

async fn submit(app: &axum::Router, body: &Value) -> String {
    let r = call(app, post_json("/v1/jobs", body)).await;
    assert_eq!(r.status, 202, "{}", r.text());
    r.json()["id"].as_str().expect("id").to_string()
}

async fn finished(app: &axum::Router, id: &str, secs: u64) -> Value {
    wait_for(
        app,
        &format!("/v1/jobs/{id}"),
        Duration::from_secs(secs),
        is_terminal,
    )
    .await
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_crashing_or_memory_hungry_job_fails_alone() {
    // 512 MiB of address space: the engine's child for the column needs well under that
    // (measured VmPeak ~100 MB), the allocating fault goes past it within a second.
    let (svc, app) = start("isolation-faults", 2, |p| p.memory_limit = 512 << 20);
    // A real run long enough (20 s simulated, 20 000 steps) to be running while the faulty
    // jobs crash one after another on the other worker.
    let good = submit(
        &app,
        &json!({"scene": column_scene(20.0), "motion": pulse(3.0)}),
    )
    .await;
    let cases = [
        ("fault:alloc", "job memory limit of 536870912 bytes"),
        ("fault:segv", "signal 11"),
        ("fault:abort", "signal 6"),
        ("fault:panic", "the computation crashed"),
    ];
    let mut ids = Vec::new();
    for (name, _) in cases {
        ids.push(submit(&app, &faulty(name)).await);
    }
    for ((name, cause), id) in cases.iter().zip(&ids) {
        let j = finished(&app, id, 120).await;
        assert_eq!(j["status"], "failed", "{name}: {j}");
        let err = j["error"].as_str().unwrap_or("");
        assert!(err.contains(cause), "{name}: expected {cause:?} in {err:?}");
        if *name == "fault:alloc" {
            assert!(err.contains("--job-memory-limit"), "{err}");
        }
    }
    let j = finished(&app, &good, 300).await;
    assert_eq!(j["status"], "succeeded", "{j}");
    assert_eq!(j["progress"], 1.0);
    assert!(j["summary"]["blocks"].is_array(), "{j}");
    // The service is still answering, and the worker threads are all alive.
    let h = call(&app, get("/healthz")).await;
    assert_eq!(h.status, 200, "{}", h.text());
    // Another job after the crashes runs normally.
    let again = submit(
        &app,
        &json!({"scene": column_scene(1.0), "motion": pulse(3.0)}),
    )
    .await;
    assert_eq!(finished(&app, &again, 120).await["status"], "succeeded");
    svc.shutdown(Duration::from_secs(5));
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_job_over_its_cpu_time_fails_with_the_limit_named() {
    let (svc, app) = start("isolation-cpu", 1, |p| p.cpu_seconds = 1);
    let id = submit(&app, &faulty("fault:spin")).await;
    let j = finished(&app, &id, 60).await;
    assert_eq!(j["status"], "failed", "{j}");
    let err = j["error"].as_str().unwrap_or("");
    assert!(
        err.contains("CPU-time limit of 1 s") && err.contains("--job-cpu-seconds"),
        "{err}"
    );
    svc.shutdown(Duration::from_secs(5));
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn progress_and_cancel_reach_the_child() {
    let (svc, app) = start("isolation-cancel", 1, |_| {});
    // 2000 s simulated: minutes of work, so only the cancel ends it.
    let id = submit(
        &app,
        &json!({"scene": column_scene(2000.0), "motion": pulse(3.0)}),
    )
    .await;
    let uri = format!("/v1/jobs/{id}");
    // Progress written by the child reaches the store (every 250 ms at most).
    let j = wait_for(&app, &uri, Duration::from_secs(60), |j| {
        j["status"] == "running" && j["progress"].as_f64().unwrap_or(0.0) > 0.0
    })
    .await;
    assert!(j["progress"].as_f64().unwrap_or(1.0) < 1.0, "{j}");
    let r = call(&app, post_json(&format!("{uri}/cancel"), &json!({}))).await;
    assert!(r.status < 300, "{} {}", r.status, r.text());
    let j = finished(&app, &id, 30).await;
    assert_eq!(j["status"], "cancelled", "{j}");
    // The child stopped at its next step and handed back its partial summary.
    assert!(j["summary"]["blocks"].is_array(), "{j}");
    svc.shutdown(Duration::from_secs(5));
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn limits_report_the_isolation_and_its_resource_limits() {
    // Process isolation: the flags' values as the server applies them.
    let (svc, app) = start("isolation-limits", 1, |p| {
        p.memory_limit = 512 << 20;
        p.cpu_seconds = 77;
    });
    let r = call(&app, get("/v1/limits")).await;
    assert_eq!(r.status, 200, "{}", r.text());
    let l = r.json();
    assert_eq!(l["isolation"], "process", "{l}");
    assert_eq!(l["job_memory_limit_bytes"], json!(512u64 << 20), "{l}");
    assert_eq!(l["job_cpu_seconds"], 77, "{l}");
    assert_eq!(l["max_job_attempts"], 3, "{l}");
    assert_eq!(l["max_large_bodies"], 2, "{l}");
    assert_eq!(l["large_body_bytes"], json!(1u64 << 20), "{l}");
    // No --tokens: no signed links.
    assert!(l["signed_url_seconds"].is_null(), "{l}");
    // Every field the schema requires is there (the contract test checks types and values).
    // (The spec is hand-written with the list on one line: `required: [a, b, …]`.)
    let yaml = ashlar::service::OPENAPI_YAML;
    let at = yaml
        .find("\n  /v1/limits:")
        .expect("/v1/limits in openapi.yaml");
    let line = yaml[at..]
        .lines()
        .find(|l| l.trim_start().starts_with("required: ["))
        .expect("its required list");
    let required: Vec<Value> = line
        .trim()
        .trim_start_matches("required: [")
        .trim_end_matches(']')
        .split(',')
        .map(|k| json!(k.trim()))
        .collect();
    for k in &required {
        let k = k.as_str().expect("name");
        assert!(l.get(k).is_some(), "GET /v1/limits lacks {k}: {l}");
    }
    for k in ["isolation", "job_memory_limit_bytes", "job_cpu_seconds"] {
        assert!(
            required.contains(&json!(k)),
            "openapi.yaml does not require {k}"
        );
    }
    svc.shutdown(Duration::from_secs(5));
    // Threads: no process, so no process limits.
    let (svc, app, _dir) = start_fake("isolation-limits-thread");
    let l = call(&app, get("/v1/limits")).await.json();
    assert_eq!(l["isolation"], "thread", "{l}");
    assert!(l["job_memory_limit_bytes"].is_null(), "{l}");
    assert!(l["job_cpu_seconds"].is_null(), "{l}");
    svc.shutdown(Duration::from_secs(5));
}
