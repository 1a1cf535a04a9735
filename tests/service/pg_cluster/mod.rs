//! The PostgreSQL job queue with many processes (docs/cluster.md). Needs a server: `tests/pg/run.sh`
//! starts a throwaway one on loopback and sets `ASHLAR_TEST_DATABASE_URL`
//! (`postgresql://USER@127.0.0.1:PORT/postgres`); each test creates its own database there.
//! Without the variable every test prints a loud SKIPPED line and passes, so that a plain
//! `cargo test` works on a machine with no PostgreSQL; `.ci/run` always runs them through
//! `tests/pg/run.sh`, which fails if they skip. The store's own behaviour, the same on both
//! stores, is `tests/service/store_contract.rs`. By topic:
//!
//! - `queue.rs`: one API process + three worker processes, 100 real-engine jobs, one worker
//!   SIGKILLed mid-run: all succeed, each recorded exactly once, results equal to the embedded
//!   store's; lease expiry and the reaper (a lost lease's late result is discarded),
//!   heartbeats; cancellation and progress across processes (the API's SSE follows a remote
//!   job); NOTIFY wakes an idle worker long before its poll interval;
//! - `schema.rs`: migration of a version-1 database (fixture) to the current schema; bad URLs;
//! - `fanout.rs`: PGA searches fanned out over workers (and over the embedded store's one thread);
//! - `isolation.rs`: isolated workers (crashing runs fail alone) and the limits an API-only
//!   process reports for its workers.
//!
//! This file holds what they share: the server, fresh databases, a cluster of processes, the
//! job and search bodies, and the in-process references.
mod fanout;
mod isolation;
mod queue;
mod schema;
use crate::service_support;

use ashlar::service::store::postgres::{LeaseParams, PgStore, SCHEMA_VERSION};
use ashlar::service::store::{Finish, JobKind, JobStatus, JobStore, NewJob, StoreError};
use ashlar::service::{Service, ServiceConfig};
use postgres::NoTls;
use serde_json::{json, Value};
use service_support::*;
use std::io::Write as _;
use std::path::Path;
use std::process::Command;
use std::time::{Duration, Instant};
use uuid::Uuid;

/// The server to test against, or None (the test is skipped, loudly).
pub(crate) fn base_url(test: &str) -> Option<String> {
    match std::env::var("ASHLAR_TEST_DATABASE_URL") {
        Ok(u) if !u.is_empty() => Some(u),
        _ => {
            // Straight to the process's stderr, not through `eprintln!`, which the test harness
            // captures: a plain `cargo test` shows the skip beside the test's "ok".
            let _ = writeln!(
                std::io::stderr(),
                "SKIPPED {test}: ASHLAR_TEST_DATABASE_URL is not set (run tests/pg/run.sh to test the PostgreSQL store)"
            );
            None
        }
    }
}

/// A fresh, empty database on the test server; returns its URL.
pub(crate) fn fresh_db(base: &str, tag: &str) -> String {
    let mut c = postgres::Client::connect(base, NoTls).expect("connect to the test server");
    let name = format!("ashlar_{tag}_{}", &Uuid::new_v4().simple().to_string()[..8]);
    c.batch_execute(&format!("CREATE DATABASE {name}"))
        .expect("create database");
    let (prefix, _) = base
        .rsplit_once('/')
        .expect("ASHLAR_TEST_DATABASE_URL ends in /DBNAME");
    format!("{prefix}/{name}")
}

fn sql(url: &str) -> postgres::Client {
    postgres::Client::connect(url, NoTls).expect("connect")
}

/// An API process (`--workers 0`, 2 s leases) on `url`, its --data `root/api`, its artifacts
/// in `root/shared` through the object store; returns it and that storage's URL.
fn api_process(url: &str, root: &Path) -> (Server, String) {
    let shared = format!("file://{}", root.join("shared").display());
    let args = ["--database", url, "--workers", "0", "--lease", "2"];
    let api = Server::start(
        &root.join("api"),
        &[&args[..], &["--artifacts", &shared]].concat(),
    );
    (api, shared)
}

/// One API process (`--workers 0`) and `n` single-thread worker processes (2 s leases, `extra`
/// further worker arguments) on `url`. Every process has its own --data under `root` (as on
/// separate machines); artifacts meet in `root/shared` through the object store.
fn cluster(url: &str, root: &Path, n: usize, extra: &[&str]) -> (Server, Vec<Worker>) {
    let (api, shared) = api_process(url, root);
    let mut args = vec!["--workers", "1", "--lease", "2", "--artifacts", &shared];
    args.extend_from_slice(extra);
    let workers = (0..n)
        .map(|k| Worker::start(url, &root.join(format!("worker{k}")), &args))
        .collect();
    (api, workers)
}

/// SIGKILL `worker` once it holds an open claim in `job_attempts` (on a child run of a search
/// when `child`). Returns the worker's tag as matched in `job_attempts.worker`.
fn kill_while_claiming(db: &mut postgres::Client, worker: &mut Worker, child: bool) -> String {
    let victim = format!(":{}", worker.pid());
    let query = if child {
        "SELECT count(*) FROM job_attempts a JOIN jobs j ON j.id = a.job_id
         WHERE a.worker LIKE '%' || $1 AND a.outcome IS NULL AND j.parent IS NOT NULL"
    } else {
        "SELECT count(*) FROM job_attempts WHERE worker LIKE '%' || $1 AND outcome IS NULL"
    };
    let what = if child { "a child" } else { "a job" };
    wait_until(
        &format!("the worker runs {what}"),
        Duration::from_secs(120),
        || {
            let n: i64 = db.query_one(query, &[&victim]).expect("query").get(0);
            n > 0
        },
    );
    worker.kill();
    victim
}

/// Attempts of the worker tagged `victim` that the reaper expired.
fn expired_attempts(db: &mut postgres::Client, victim: &str) -> i64 {
    db.query_one(
        "SELECT count(*) FROM job_attempts WHERE worker LIKE '%' || $1 AND outcome = 'expired'",
        &[&victim],
    )
    .expect("query")
    .get(0)
}

/// Stop the surviving workers (index 1 on; 0 was killed) with SIGTERM, checking each exits
/// cleanly, then the API process; remove the cluster's directory.
fn shut_down(api: Server, mut workers: Vec<Worker>, root: &Path) {
    for w in workers.drain(1..) {
        assert!(w.terminate().success(), "SIGTERM stops a worker cleanly");
    }
    drop(api);
    std::fs::remove_dir_all(root).ok();
}

fn get_json(addr: &str, path: &str) -> Value {
    let (status, body) = http(addr, "GET", path, None).expect("GET");
    assert_eq!(status, 200, "GET {path}: {body}");
    serde_json::from_str(&body).expect("JSON")
}

fn submit(addr: &str, body: &Value) -> String {
    let (status, text) = http(addr, "POST", "/v1/jobs", Some(&body.to_string())).expect("POST");
    assert_eq!(status, 202, "{text}");
    let v: Value = serde_json::from_str(&text).expect("JSON");
    v["id"].as_str().expect("id").to_string()
}

/// Job k: the column under a pulse whose amplitude grows with k (2.00 … 6.95 m/s²), so every
/// job has its own result and a mix-up would show. (200 + 5k)/100 prints and parses exactly.
fn job_body(k: usize, duration: f64) -> Value {
    // `"model": "dda"`: real-engine jobs (the default `auto` would run the reduced rocking
    // model on this single column).
    let mut scene = column_scene(duration);
    scene["control"]["model"] = json!("dda");
    json!({"scene": scene, "motion": pulse((200 + 5 * k) as f64 / 100.0)})
}

/// Summary without the wall time (a measurement of the machine, not a result).
fn comparable(text: &str) -> Value {
    let mut v: Value = serde_json::from_str(text).expect("summary JSON");
    if let Some(o) = v.as_object_mut() {
        o.remove("wall_time_s");
    }
    v
}

/// The same 100 jobs through the embedded (SQLite) store, in process: the reference.
fn embedded_results(bodies: &[Value]) -> Vec<String> {
    let dir = temp_dir("pg-embedded-ref");
    let mut cfg = ServiceConfig::new(&dir);
    cfg.workers.workers = 2;
    let svc = Service::start(cfg, ashlar::service::analysis_runner()).expect("embedded service");
    let core = svc.state().core.clone();
    let limits = ashlar::service::Limits::default();
    let ids: Vec<Uuid> = bodies
        .iter()
        .map(|b| {
            // As the API does: parse, keep the request JSON and the motion summary.
            let parsed = ashlar::service::request::parse_run(b, &limits).expect("valid job");
            let id = Uuid::new_v4();
            core.store
                .insert(&NewJob {
                    id,
                    kind: JobKind::Run,
                    request: b.clone(),
                    motion: parsed.motion_summary,
                    owner: None,
                })
                .expect("insert");
            core.notify_work();
            id
        })
        .collect();
    wait_until(
        "the embedded store finishes",
        Duration::from_secs(600),
        || core.store.counts().expect("counts").succeeded == ids.len() as u64,
    );
    let out = ids
        .iter()
        .map(|&id| {
            core.store
                .get(id)
                .expect("get")
                .expect("job")
                .result
                .expect("result")
        })
        .collect();
    svc.shutdown(Duration::from_secs(5));
    std::fs::remove_dir_all(dir).ok();
    out
}

/// The two searches the fan-out tests submit: one record, and two records with two criteria
/// combined by `any` (a fragility study), over `duration` s of a rigid column.
fn search_bodies(duration: f64, tolerance: f64, scan_points: u32) -> (Value, Value) {
    let single = json!({
        "scene": rigid_column(duration),
        "motion": {"horizontal": half_sine(1.0, "")["horizontal"]},
        "criterion": "toppled:column",
        "range": {"min": 2.0, "max": 10.0, "units": "m/s2"},
        "tolerance": tolerance,
        "scan_points": scan_points
    });
    let multi = json!({
        "scene": rigid_column(duration),
        "motions": [half_sine(0.8, "T = 0.8 s"), half_sine(1.25, "T = 1.25 s")],
        "criterion": ["toppled:column", "rotation:column:20"],
        "combine": "any",
        "range": {"min": 2.0, "max": 10.0, "units": "m/s2"},
        "tolerance": tolerance,
        "scan_points": scan_points
    });
    (single, multi)
}

/// The same search in this process (the embedded in-process path), as result JSON text.
fn in_process(body: &Value) -> String {
    use ashlar::service::request::JobInput;
    let parsed = ashlar::service::request::parse_pga(body, &ashlar::service::Limits::default())
        .expect("valid");
    let JobInput::PgaSearch {
        scene,
        motion,
        request,
        records,
        fit,
        ..
    } = parsed.input
    else {
        panic!("a search")
    };
    let opts = ashlar::analysis::run::RunOptions::default();
    if records.is_empty() {
        let r = ashlar::analysis::pga::search(&scene, &motion, &request, &opts).expect("search");
        serde_json::to_string(&r).expect("json")
    } else {
        let r = ashlar::analysis::pga::search_records(&scene, &records, &request, fit, &opts)
            .expect("search");
        serde_json::to_string(&r).expect("json")
    }
}
