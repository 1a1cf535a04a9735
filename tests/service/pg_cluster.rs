//! The PostgreSQL job queue with many processes (docs/cluster.md). Needs a server: `tests/pg/run.sh`
//! starts a throwaway one on loopback and sets `ASHLAR_TEST_DATABASE_URL`
//! (`postgresql://USER@127.0.0.1:PORT/postgres`); each test creates its own database there.
//! Without the variable every test prints a loud SKIPPED line and passes, so that a plain
//! `cargo test` works on a machine with no PostgreSQL; `.ci/run` always runs them through
//! `tests/pg/run.sh`, which fails if they skip.
//!
//! - one API process + three worker processes, 100 real-engine jobs, one worker SIGKILLed
//!   mid-run: all succeed, each recorded exactly once, results equal to the embedded store's;
//! - lease expiry and the reaper (a lost lease's late result is discarded), heartbeats;
//! - cancellation and progress across processes (the API's SSE follows a remote job);
//! - NOTIFY wakes an idle worker long before its poll interval;
//! - migration of a version-1 database (fixture) to the current schema.
use crate::service_support;

use ashlar::service::store::postgres::{LeaseParams, PgStore, SCHEMA_VERSION};
use ashlar::service::store::{Finish, JobKind, JobStatus, JobStore, NewJob, QueueFull, StoreError};
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
fn base_url(test: &str) -> Option<String> {
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
fn fresh_db(base: &str, tag: &str) -> String {
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

/// One API process (`--workers 0`) and `n` single-thread worker processes (2 s leases, `extra`
/// further worker arguments) on `url`. Every process has its own --data under `root` (as on
/// separate machines); artifacts meet in `root/shared` through the object store.
fn cluster(url: &str, root: &Path, n: usize, extra: &[&str]) -> (Server, Vec<Worker>) {
    let shared = format!("file://{}", root.join("shared").display());
    let api = Server::start(
        &root.join("api"),
        &[
            "--database",
            url,
            "--workers",
            "0",
            "--lease",
            "2",
            "--artifacts",
            &shared,
        ],
    );
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

/// Equal structure and strings; numbers within `rel` (relative to the larger).
fn close_json(a: &Value, b: &Value, rel: f64) -> bool {
    match (a, b) {
        (Value::Number(x), Value::Number(y)) => {
            let (x, y) = (
                x.as_f64().unwrap_or(f64::NAN),
                y.as_f64().unwrap_or(f64::NAN),
            );
            x == y || (x - y).abs() <= rel * x.abs().max(y.abs()) + 1e-300
        }
        (Value::Array(x), Value::Array(y)) => {
            x.len() == y.len() && x.iter().zip(y).all(|(p, q)| close_json(p, q, rel))
        }
        (Value::Object(x), Value::Object(y)) => {
            x.len() == y.len()
                && x.iter()
                    .all(|(k, v)| y.get(k).is_some_and(|w| close_json(v, w, rel)))
        }
        _ => a == b,
    }
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

#[test]
fn hundred_jobs_three_workers_one_killed() {
    let Some(base) = base_url("hundred_jobs_three_workers_one_killed") else {
        return;
    };
    let url = fresh_db(&base, "hundred");
    let root = temp_dir("pg-hundred");
    let (api, mut workers) = cluster(&url, &root, 3, &[]);
    // 30 s simulated: a column that rocks then rests, a fraction of a second of CPU per job.
    let bodies: Vec<Value> = (0..100).map(|k| job_body(k, 30.0)).collect();
    let ids: Vec<String> = bodies.iter().map(|b| submit(&api.addr, b)).collect();

    // SIGKILL worker 0 while it runs a job (its claim is open in job_attempts).
    let mut db = sql(&url);
    let victim = kill_while_claiming(&mut db, &mut workers[0], false);

    wait_until("all 100 jobs succeed", Duration::from_secs(600), || {
        let c: i64 = db
            .query_one(
                "SELECT count(*) FROM jobs WHERE status IN ('succeeded', 'failed', 'cancelled')",
                &[],
            )
            .expect("query")
            .get(0);
        c == 100
    });
    for id in &ids {
        let j = get_json(&api.addr, &format!("/v1/jobs/{id}"));
        assert_eq!(j["status"], "succeeded", "{j}");
    }
    // Exactly once: one successful attempt per job, no other outcome but the killed worker's.
    let rows = db
        .query(
            "SELECT j.id::text, count(*) FILTER (WHERE a.outcome = 'succeeded'),
                    count(*) FILTER (WHERE a.outcome = 'expired'),
                    count(*) FILTER (WHERE a.outcome IS NULL OR a.outcome NOT IN ('succeeded', 'expired'))
             FROM jobs j JOIN job_attempts a ON a.job_id = j.id GROUP BY j.id",
            &[],
        )
        .expect("query");
    assert_eq!(rows.len(), 100);
    let mut expired_total = 0;
    for r in &rows {
        let (id, ok, expired, other): (String, i64, i64, i64) =
            (r.get(0), r.get(1), r.get(2), r.get(3));
        assert_eq!(
            (ok, other),
            (1, 0),
            "job {id}: {ok} successful and {other} other attempts"
        );
        expired_total += expired;
    }
    let victim_expired = expired_attempts(&mut db, &victim);
    assert_eq!(victim_expired, 1, "the killed worker's job was reaped once");
    assert_eq!(expired_total, 1);

    // The same jobs through the embedded store give the same results. The engine is not
    // bit-reproducible across processes (last-bit differences seen in max_penetration, see
    // tests/service/service_durability.rs), so numbers agree to 1e-9 relative: far below any
    // physical meaning, far above rounding noise.
    let reference = embedded_results(&bodies);
    for (k, id) in ids.iter().enumerate() {
        let j = get_json(&api.addr, &format!("/v1/jobs/{id}"));
        let got = comparable(&j["summary"].to_string());
        let want = comparable(&reference[k]);
        assert!(
            close_json(&got, &want, 1e-9),
            "job {k}: the cluster's summary differs from the embedded store's:\n{got}\n{want}"
        );
    }
    // Artifacts: the API process ran nothing, yet serves every job's histories (fetched from
    // the shared store); spot-check the first and the last.
    for id in [&ids[0], &ids[99]] {
        let (status, csv) = http(
            &api.addr,
            "GET",
            &format!("/v1/jobs/{id}/histories?format=csv"),
            None,
        )
        .expect("GET");
        assert_eq!(status, 200, "{csv}");
        assert!(
            csv.starts_with("time_s,column.x_m,column.y_m,column.rotation_rad"),
            "{csv:.200}"
        );
    }
    shut_down(api, workers, &root);
}

#[test]
fn lease_expiry_requeues_and_discards_the_late_result() {
    let Some(base) = base_url("lease_expiry_requeues_and_discards_the_late_result") else {
        return;
    };
    let url = fresh_db(&base, "lease");
    let lease = LeaseParams::with_lease(Duration::from_millis(1500));
    // Two stores = two processes as far as leases go (each keeps its own tokens).
    let a = PgStore::open(&url, lease.clone()).expect("open a");
    let b = PgStore::open(&url, lease).expect("open b");
    let job = NewJob {
        id: Uuid::new_v4(),
        kind: JobKind::Run,
        request: json!({"k": 1}),
        motion: json!({"pga": 1.0}),
        owner: None,
    };
    a.insert(&job).expect("insert");
    assert_eq!(a.claim().expect("claim").expect("job").id, job.id);
    assert!(
        b.claim().expect("claim").is_none(),
        "a claimed job is not claimed twice"
    );

    // Heartbeats keep the lease alive past its length.
    for _ in 0..4 {
        std::thread::sleep(Duration::from_millis(500));
        let hb = a.heartbeat(&[job.id]).expect("heartbeat");
        assert!(hb.lost.is_empty() && hb.cancel.is_empty(), "{hb:?}");
        assert_eq!(
            b.recover(3).expect("reap"),
            (0, 0),
            "a live lease is not reaped"
        );
    }
    let left = a.lease_remaining(job.id).expect("lease").expect("running");
    assert!(
        left > 1.0 && left <= 1.5,
        "lease extended to ~1.5 s, {left} s left"
    );

    // Silence: the lease expires, another process reaps and reruns the job.
    std::thread::sleep(Duration::from_millis(1700));
    assert_eq!(b.recover(3).expect("reap"), (1, 0));
    let again = b.claim().expect("claim").expect("requeued job");
    assert_eq!((again.id, again.attempts), (job.id, 2));
    // The first owner wakes up: it learns it lost the job, and its result is discarded.
    assert_eq!(
        a.heartbeat(&[job.id]).expect("heartbeat").lost,
        vec![job.id]
    );
    a.finish(job.id, &Finish::Succeeded(json!({"by": "a"})))
        .expect("finish a");
    assert_eq!(
        a.get(job.id).expect("get").expect("job").status,
        JobStatus::Running
    );
    b.finish(job.id, &Finish::Succeeded(json!({"by": "b"})))
        .expect("finish b");
    let r = b.get(job.id).expect("get").expect("job");
    assert_eq!(r.status, JobStatus::Succeeded);
    assert_eq!(r.result.as_deref(), Some(r#"{"by":"b"}"#));
    let attempts = b.attempts_of(job.id).expect("attempts");
    let outcomes: Vec<Option<&str>> = attempts.iter().map(|(_, o)| o.as_deref()).collect();
    assert_eq!(outcomes, vec![Some("expired"), Some("succeeded")]);

    // A job whose worker keeps dying fails after max_attempts starts.
    let doomed = NewJob {
        id: Uuid::new_v4(),
        ..job.clone()
    };
    a.insert(&doomed).expect("insert");
    for attempt in 1..=2u32 {
        assert_eq!(a.claim().expect("claim").expect("job").attempts, attempt);
        std::thread::sleep(Duration::from_millis(1600));
        assert_eq!(
            b.recover(2).expect("reap"),
            if attempt < 2 { (1, 0) } else { (0, 1) }
        );
    }
    let r = b.get(doomed.id).expect("get").expect("job");
    assert_eq!(r.status, JobStatus::Failed);
    assert!(r.error.unwrap_or_default().contains("2 times"));
}

#[test]
fn store_contract_matches_the_embedded_store() {
    // The sequence of the SQLite store's unit tests, on PostgreSQL.
    let Some(base) = base_url("store_contract_matches_the_embedded_store") else {
        return;
    };
    let url = fresh_db(&base, "contract");
    let s = PgStore::open(&url, LeaseParams::default()).expect("open");
    let job = |kind| NewJob {
        id: Uuid::new_v4(),
        kind,
        request: json!({"a": 1}),
        motion: json!({"pga": 2.0}),
        owner: None,
    };
    let (a, b) = (job(JobKind::Run), job(JobKind::PgaSearch));
    s.insert(&a).expect("insert");
    s.insert(&b).expect("insert");
    let first = s.claim().expect("claim").expect("a job");
    assert_eq!(
        (first.id, first.status, first.attempts),
        (a.id, JobStatus::Running, 1)
    );
    assert_eq!(first.request, json!({"a": 1}));
    let second = s.claim().expect("claim").expect("a job");
    assert_eq!((second.id, second.kind), (b.id, JobKind::PgaSearch));
    assert!(s.claim().expect("claim").is_none());
    assert_eq!(s.counts().expect("counts").running, 2);
    s.set_progress(a.id, 0.5).expect("progress");
    assert_eq!(s.get(a.id).expect("get").expect("job").progress, 0.5);
    s.requeue(a.id, true).expect("requeue");
    let r = s.get(a.id).expect("get").expect("job");
    assert_eq!(
        (r.status, r.attempts, r.progress),
        (JobStatus::Queued, 0, 0.0)
    );
    s.claim().expect("claim");
    s.finish(a.id, &Finish::Succeeded(json!({"ok": true})))
        .expect("finish");
    let r = s.get(a.id).expect("get").expect("job");
    assert_eq!((r.status, r.progress), (JobStatus::Succeeded, 1.0));
    assert_eq!(r.result.as_deref(), Some(r#"{"ok":true}"#));
    use ashlar::service::store::CancelOutcome;
    let q = job(JobKind::Run);
    s.insert(&q).expect("insert");
    assert_eq!(
        s.request_cancel(q.id).expect("cancel"),
        CancelOutcome::CancelledQueued
    );
    assert!(
        s.claim().expect("claim").is_none(),
        "a cancelled job is never claimed"
    );
    assert_eq!(
        s.request_cancel(b.id).expect("cancel"),
        CancelOutcome::Requested
    );
    assert!(s.get(b.id).expect("get").expect("job").cancel_requested);
    s.finish(b.id, &Finish::Cancelled(None)).expect("finish");
    assert_eq!(
        s.request_cancel(b.id).expect("cancel"),
        CancelOutcome::AlreadyFinished(JobStatus::Cancelled)
    );
    assert_eq!(
        s.request_cancel(Uuid::new_v4()).expect("cancel"),
        CancelOutcome::NotFound
    );
    // The job list of the web page (`GET /v1/jobs`): newest first, filtered by kind.
    let all = s.list_recent(10, None).expect("list");
    let ids: Vec<Uuid> = all.iter().map(|r| r.id).collect();
    assert_eq!(ids, vec![q.id, b.id, a.id]);
    let searches = s.list_recent(10, Some(JobKind::PgaSearch)).expect("list");
    assert_eq!(
        searches.iter().map(|r| r.id).collect::<Vec<_>>(),
        vec![b.id]
    );
    assert_eq!(s.list_recent(1, None).expect("list").len(), 1);
}

#[test]
fn cancel_and_progress_cross_processes() {
    let Some(base) = base_url("cancel_and_progress_cross_processes") else {
        return;
    };
    let url = fresh_db(&base, "cancel");
    let root = temp_dir("pg-cancel");
    let api = Server::start(&root.join("api"), &["--database", &url, "--workers", "0"]);
    // The fake runner: 500 ms per simulated second, a 60 s scene runs 30 s unless cancelled.
    let _worker = Worker::start(
        &url,
        &root.join("w"),
        &["--workers", "1", "--fake-runner-ms", "500"],
    );
    let id = submit(
        &api.addr,
        &json!({"scene": column_scene(60.0), "motion": pulse(2.0)}),
    );
    // The API process follows the remote job's progress: through GET and through SSE.
    let addr = api.addr.clone();
    let path = format!("/v1/jobs/{id}/events");
    let sse = std::thread::spawn(move || http(&addr, "GET", &path, None).expect("SSE"));
    // Progress 0.1 is 3 s of running: the SSE stream re-reads the store every second
    // (`EventParams::poll`), so it has seen the job running by then. (Waiting for 0.02, 0.6 s,
    // let the cancel overtake the stream's first poll on a loaded machine.)
    wait_until(
        "progress written by the worker process shows in the API",
        Duration::from_secs(30),
        || {
            get_json(&api.addr, &format!("/v1/jobs/{id}"))["progress"]
                .as_f64()
                .unwrap_or(0.0)
                > 0.1
        },
    );
    let asked = Instant::now();
    let (status, body) = http(
        &api.addr,
        "POST",
        &format!("/v1/jobs/{id}/cancel"),
        Some(""),
    )
    .expect("cancel");
    assert!(status == 202 || status == 200, "{status} {body}");
    wait_until(
        "the worker process stops the job",
        Duration::from_secs(10),
        || get_json(&api.addr, &format!("/v1/jobs/{id}"))["status"] == "cancelled",
    );
    // NOTIFY reaches the worker at once; the heartbeat (10 s) would be the fallback.
    assert!(
        asked.elapsed() < Duration::from_secs(5),
        "cancel took {:?}",
        asked.elapsed()
    );
    let j = get_json(&api.addr, &format!("/v1/jobs/{id}"));
    let p = j["progress"].as_f64().unwrap_or(1.0);
    assert!(p > 0.0 && p < 0.5, "cancelled part way: progress {p}");
    let (sse_status, events) = sse.join().expect("SSE thread");
    assert_eq!(sse_status, 200);
    let data: Vec<Value> = events
        .lines()
        .filter_map(|l| l.strip_prefix("data:"))
        .filter_map(|d| serde_json::from_str(d.trim()).ok())
        .collect();
    assert!(
        data.iter()
            .any(|d| d["status"] == "running" && d["progress"].as_f64().unwrap_or(0.0) > 0.0),
        "the stream showed the remote job's progress: {events}"
    );
    assert_eq!(
        data.last().map(|d| d["status"].clone()),
        Some(json!("cancelled")),
        "{events}"
    );
    drop(api);
    std::fs::remove_dir_all(root).ok();
}

#[test]
fn notify_wakes_an_idle_worker() {
    let Some(base) = base_url("notify_wakes_an_idle_worker") else {
        return;
    };
    let url = fresh_db(&base, "notify");
    let root = temp_dir("pg-notify");
    // Polling every 120 s: only a notification can make it pick the job up quickly.
    let _worker = Worker::start(
        &url,
        &root.join("w"),
        &[
            "--workers",
            "1",
            "--idle-poll",
            "120",
            "--fake-runner-ms",
            "1",
        ],
    );
    std::thread::sleep(Duration::from_secs(1)); // idle, waiting
    let store = PgStore::open(&url, LeaseParams::default()).expect("open");
    for round in 0..3 {
        let id = Uuid::new_v4();
        let body = json!({"scene": column_scene(0.5), "motion": pulse(2.0)});
        store
            .insert(&NewJob {
                id,
                kind: JobKind::Run,
                request: body,
                motion: json!({"pga": 2.0}),
                owner: None,
            })
            .expect("insert");
        let t = Instant::now();
        wait_until(
            "the woken worker finishes the job",
            Duration::from_secs(20),
            || store.get(id).expect("get").expect("job").status == JobStatus::Succeeded,
        );
        assert!(
            t.elapsed() < Duration::from_secs(5),
            "round {round}: picked up after {:?}, not by notification",
            t.elapsed()
        );
        std::thread::sleep(Duration::from_millis(500)); // idle again
    }
    std::fs::remove_dir_all(root).ok();
}

#[test]
fn migrates_a_version_1_database() {
    let Some(base) = base_url("migrates_a_version_1_database") else {
        return;
    };
    let url = fresh_db(&base, "migrate");
    // A database as the first PostgreSQL-backed ashlar left it: schema version 1, a queued job,
    // a job running under a server that no longer exists, and a finished one.
    sql(&url)
        .batch_execute(include_str!("../fixtures/pg_schema_v1.sql"))
        .expect("load the v1 fixture");
    let s = PgStore::open(&url, LeaseParams::default()).expect("open upgrades");
    assert_eq!(s.schema_version().expect("version"), SCHEMA_VERSION);
    let mut c = sql(&url);
    let versions: Vec<i32> = c
        .query(
            "SELECT version FROM ashlar_schema_version ORDER BY version",
            &[],
        )
        .expect("versions")
        .iter()
        .map(|r| r.get(0))
        .collect();
    assert_eq!(versions, (1..=SCHEMA_VERSION).collect::<Vec<_>>());
    let done = Uuid::parse_str("00000000-0000-4000-8000-000000000003").expect("uuid");
    let r = s.get(done).expect("get").expect("kept");
    assert_eq!(r.status, JobStatus::Succeeded);
    assert_eq!(r.result.as_deref(), Some(r#"{"completed":true,"pga":2.5}"#));
    // The v1 running job has no lease: the reaper requeues it, and it keeps its place.
    assert_eq!(s.recover(3).expect("reap"), (1, 0));
    let first = s.claim().expect("claim").expect("job");
    assert_eq!(first.id.to_string(), "00000000-0000-4000-8000-000000000001");
    let second = s.claim().expect("claim").expect("job");
    assert_eq!(
        second.id.to_string(),
        "00000000-0000-4000-8000-000000000002"
    );
    assert_eq!(second.attempts, 2, "the old attempt still counts");
    // Opening again is a no-op; a newer schema is refused with a clear message.
    drop(s);
    PgStore::open(&url, LeaseParams::default()).expect("reopen");
    c.execute(
        "INSERT INTO ashlar_schema_version (version) VALUES (99)",
        &[],
    )
    .expect("bump");
    let e = PgStore::open(&url, LeaseParams::default())
        .err()
        .expect("refused");
    assert!(
        matches!(&e, StoreError::Schema(m) if m.contains("version 99") && m.contains("upgrade ashlar")),
        "{e}"
    );
}

#[test]
fn bad_database_urls_are_named() {
    // No server needed.
    let e = PgStore::open("mysql://x", LeaseParams::default())
        .err()
        .expect("refused");
    assert!(
        matches!(&e, StoreError::Config(m) if m.contains("--database")),
        "{e}"
    );
    let out = Command::new(env!("CARGO_BIN_EXE_ashlar"))
        .args(["worker", "--database", "sqlite:/tmp/x.sqlite"])
        .output()
        .expect("run");
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("PostgreSQL"), "{err}");
    let out = Command::new(env!("CARGO_BIN_EXE_ashlar"))
        .args(["worker", "--database", "postgres://nobody@127.0.0.1:1/none"])
        .output()
        .expect("run");
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("connecting to PostgreSQL"), "{err}");
}

// ---------------------------------------------------------------------------------------------
// Fanned-out PGA searches (docs/cluster.md): a search's runs are child jobs that every worker shares.

fn child(parent: Uuid, pga: f64, step: f64) -> NewJob {
    NewJob {
        id: Uuid::new_v4(),
        kind: JobKind::PgaRun,
        request: json!({"parent": parent, "record": 0, "pga": pga, "pga_bits": pga.to_bits(),
                        "width": 2, "progress_step": step}),
        motion: json!({"pga": pga}),
        owner: None,
    }
}

fn new_search() -> NewJob {
    NewJob {
        id: Uuid::new_v4(),
        kind: JobKind::PgaSearch,
        request: json!({"a": 1}),
        motion: json!({"pga": 1.0}),
        owner: None,
    }
}

fn status_of(s: &dyn JobStore, id: Uuid) -> JobStatus {
    s.get(id).expect("get").expect("job").status
}

/// The fan-out contract every [`JobStore`] keeps: waiting, children, requeue of the search by
/// its last child (same transaction), a failed child failing the search, cancel cascading to
/// children, and recovery of children that keep dying. `expire` makes the running jobs'
/// claims look dead to `recover` (a restart for SQLite, an expired lease for PostgreSQL).
fn fan_out_contract(s: &dyn JobStore, expire: &dyn Fn()) {
    use ashlar::service::store::CancelOutcome;
    let p = new_search();
    s.insert(&p).expect("insert");
    let claimed = s.claim().expect("claim").expect("the search");
    assert_eq!(
        (claimed.id, claimed.attempts, claimed.parent),
        (p.id, 1, None)
    );
    let (c1, c2) = (child(p.id, 1.0, 0.25), child(p.id, 2.0, 0.25));
    assert!(s
        .fan_out(p.id, &[c1.clone(), c2.clone()], 0.2)
        .expect("fan out"));
    let w = s.get(p.id).expect("get").expect("job");
    // Waiting gives the claim back: waiting is not a crash, max_attempts must not count it.
    assert_eq!(
        (w.status, w.attempts, w.progress),
        (JobStatus::Waiting, 0, 0.2)
    );
    assert_eq!(s.counts().expect("counts").waiting, 1);
    assert!(
        !s.fan_out(p.id, &[child(p.id, 3.0, 0.1)], 0.3)
            .expect("fan out"),
        "a waiting search cannot fan out again"
    );
    let kids = s.children(p.id).expect("children");
    assert_eq!(
        kids.iter()
            .map(|k| (k.id, k.kind, k.parent, k.status))
            .collect::<Vec<_>>(),
        vec![
            (c1.id, JobKind::PgaRun, Some(p.id), JobStatus::Queued),
            (c2.id, JobKind::PgaRun, Some(p.id), JobStatus::Queued)
        ]
    );
    assert_eq!(kids[0].request["pga_bits"], json!(1.0f64.to_bits()));
    // Children never show in the job list.
    let listed: Vec<Uuid> = s
        .list_recent(10, None)
        .expect("list")
        .iter()
        .map(|j| j.id)
        .collect();
    assert_eq!(listed, vec![p.id]);
    assert!(s
        .list_recent(10, Some(JobKind::PgaRun))
        .expect("list")
        .is_empty());

    // The waiting search is not claimable; its children are, in order.
    assert_eq!(s.claim().expect("claim").expect("c1").id, c1.id);
    s.finish(
        c1.id,
        &Finish::Succeeded(json!({"pga": 1.0, "failed": false})),
    )
    .expect("finish");
    let w = s.get(p.id).expect("get").expect("job");
    assert_eq!(w.status, JobStatus::Waiting, "one child still runs");
    assert!(
        (w.progress - 0.45).abs() < 1e-12,
        "progress + the child's share: {}",
        w.progress
    );
    assert_eq!(s.claim().expect("claim").expect("c2").id, c2.id);
    s.finish(
        c2.id,
        &Finish::Succeeded(json!({"pga": 2.0, "failed": true})),
    )
    .expect("finish");
    // The last child queued the search again, and it is claimable at once.
    assert_eq!(status_of(s, p.id), JobStatus::Queued);
    let again = s.claim().expect("claim").expect("the search again");
    assert_eq!((again.id, again.attempts), (p.id, 1));
    let kids = s.children(p.id).expect("children");
    assert_eq!(
        kids[1].result.as_deref(),
        Some(r#"{"failed":true,"pga":2.0}"#)
    );
    // Fanning out nothing new while every child has ended queues the search straight away.
    assert!(s.fan_out(p.id, &[], 0.5).expect("fan out"));
    assert_eq!(status_of(s, p.id), JobStatus::Queued);
    assert_eq!(s.claim().expect("claim").expect("search").id, p.id);

    // A failed child fails its search with the child's error and cancels its siblings.
    let (c3, c4) = (child(p.id, 1.5, 0.1), child(p.id, 1.75, 0.1));
    assert!(s
        .fan_out(p.id, &[c3.clone(), c4.clone()], 0.6)
        .expect("fan out"));
    assert_eq!(s.claim().expect("claim").expect("c3").id, c3.id);
    s.finish(c3.id, &Finish::Failed("simulation diverged at 1.5".into()))
        .expect("finish");
    let f = s.get(p.id).expect("get").expect("job");
    assert_eq!(f.status, JobStatus::Failed);
    assert_eq!(f.error.as_deref(), Some("simulation diverged at 1.5"));
    assert!(f.finished_ms.is_some());
    assert_eq!(status_of(s, c4.id), JobStatus::Cancelled);
    assert!(s.claim().expect("claim").is_none());

    // Cancelling a waiting search ends it at once and cancels its children: queued ones at
    // once, running ones by request (their end then changes nothing).
    let q = new_search();
    s.insert(&q).expect("insert");
    s.claim().expect("claim").expect("q");
    let (d1, d2) = (child(q.id, 1.0, 0.5), child(q.id, 2.0, 0.5));
    assert!(s
        .fan_out(q.id, &[d1.clone(), d2.clone()], 0.0)
        .expect("fan out"));
    assert_eq!(s.claim().expect("claim").expect("d1").id, d1.id);
    assert_eq!(
        s.request_cancel(q.id).expect("cancel"),
        CancelOutcome::CancelledQueued
    );
    assert_eq!(status_of(s, q.id), JobStatus::Cancelled);
    assert_eq!(status_of(s, d2.id), JobStatus::Cancelled);
    let r1 = s.get(d1.id).expect("get").expect("d1");
    assert_eq!((r1.status, r1.cancel_requested), (JobStatus::Running, true));
    s.finish(d1.id, &Finish::Cancelled(None)).expect("finish");
    assert_eq!(status_of(s, q.id), JobStatus::Cancelled);
    assert_eq!(
        s.request_cancel(q.id).expect("cancel"),
        CancelOutcome::AlreadyFinished(JobStatus::Cancelled)
    );

    // A child whose worker keeps dying fails after max_attempts, and fails its search.
    let r = new_search();
    s.insert(&r).expect("insert");
    s.claim().expect("claim").expect("r");
    let e1 = child(r.id, 1.0, 0.5);
    assert!(s
        .fan_out(r.id, std::slice::from_ref(&e1), 0.0)
        .expect("fan out"));
    assert_eq!(s.claim().expect("claim").expect("e1").id, e1.id);
    expire();
    assert_eq!(s.recover(1).expect("recover"), (0, 1));
    let rr = s.get(r.id).expect("get").expect("r");
    assert_eq!(rr.status, JobStatus::Failed);
    assert!(
        rr.error.unwrap_or_default().contains("1 times"),
        "the child's error"
    );
    assert_eq!(s.counts().expect("counts").waiting, 0);
}

#[test]
fn fan_out_contract_sqlite_and_postgres() {
    let dir = temp_dir("fanout-contract");
    let sqlite = ashlar::service::SqliteStore::open(&dir.join("jobs.sqlite")).expect("open sqlite");
    fan_out_contract(&sqlite, &|| {});
    std::fs::remove_dir_all(dir).ok();
    let Some(base) = base_url("fan_out_contract_sqlite_and_postgres (PostgreSQL part)") else {
        return;
    };
    let url = fresh_db(&base, "fanout");
    let lease = LeaseParams::with_lease(Duration::from_millis(1000));
    let pg = PgStore::open(&url, lease).expect("open");
    fan_out_contract(&pg, &|| std::thread::sleep(Duration::from_millis(1300)));
    // Every claim is logged; a search parked for its children ends its attempt `waiting`.
    let outcomes: Vec<Option<String>> = pg
        .attempts_of(pg.list_recent(10, Some(JobKind::PgaSearch)).expect("list")[2].id)
        .expect("attempts")
        .into_iter()
        .map(|(_, o)| o)
        .collect();
    assert_eq!(
        outcomes,
        vec![
            Some("waiting".into()),
            Some("waiting".into()),
            Some("waiting".into())
        ]
    );
}

fn rigid_column(duration: f64) -> Value {
    let mut s = column_scene(duration);
    s["control"]["block_model"] = json!("rigid");
    // The full engine, as in the other real-engine tests here.
    s["control"]["model"] = json!("dda");
    s
}

fn half_sine(period: f64, name: &str) -> Value {
    json!({"name": name, "horizontal": {"pulse": {"amplitude": 1.0, "period": period, "cycles": 0.5, "units": "m/s2"}}})
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

#[test]
fn pga_searches_fan_out_over_three_workers_one_killed() {
    let Some(base) = base_url("pga_searches_fan_out_over_three_workers_one_killed") else {
        return;
    };
    let url = fresh_db(&base, "fanout_http");
    let root = temp_dir("pg-fanout");
    // The width of this process's rayon pool: the workers' k-section then plans exactly the
    // amplitudes the in-process search of this process plans.
    let width = rayon::current_num_threads().to_string();
    let (api, mut workers) = cluster(&url, &root, 3, &["--fanout-width", &width]);
    let (single, multi) = search_bodies(20.0, 0.02, 6);
    let post = |b: &Value| {
        let (status, text) =
            http(&api.addr, "POST", "/v1/pga-searches", Some(&b.to_string())).expect("POST");
        assert_eq!(status, 202, "{text}");
        let v: Value = serde_json::from_str(&text).expect("JSON");
        Uuid::parse_str(v["id"].as_str().expect("id")).expect("uuid")
    };
    let ids = [post(&single), post(&multi)];

    // SIGKILL worker 0 while it runs a child run (its claim is open in job_attempts).
    let mut db = sql(&url);
    let victim = kill_while_claiming(&mut db, &mut workers[0], true);

    let mut seen_waiting = false;
    wait_until("both searches end", Duration::from_secs(900), || {
        ids.iter().all(|id| {
            let j = get_json(&api.addr, &format!("/v1/pga-searches/{id}"));
            seen_waiting |= j["status"] == "waiting";
            is_terminal(&j)
        })
    });
    assert!(seen_waiting, "the API shows a search waiting for its runs");
    let reference = [in_process(&single), in_process(&multi)];
    for (id, want) in ids.iter().zip(&reference) {
        let j = get_json(&api.addr, &format!("/v1/pga-searches/{id}"));
        assert_eq!(j["status"], "succeeded", "{j}");
        assert_eq!(j["progress"], json!(1.0));
        // Exactly the in-process result: same amplitudes (planned from the same bits), same
        // verdicts, same bracket, same fragility fit.
        let want: Value = serde_json::from_str(want).expect("JSON");
        assert_eq!(j["result"], want, "search {id}: cluster vs in-process");
        // The runs were shared: children executed by at least two distinct workers.
        let n: i64 = db
            .query_one(
                "SELECT count(DISTINCT a.worker) FROM job_attempts a JOIN jobs j ON j.id = a.job_id
                 WHERE j.parent = $1 AND a.outcome = 'succeeded'",
                &[id],
            )
            .expect("query")
            .get(0);
        assert!(n >= 2, "search {id}: children ran on {n} worker(s)");
        // One child per run of the result, each succeeded once.
        let runs = if want.get("records").is_some() {
            want["records"]
                .as_array()
                .expect("records")
                .iter()
                .map(|r| r["runs"].as_array().expect("runs").len())
                .sum::<usize>()
        } else {
            want["runs"].as_array().expect("runs").len()
        };
        let kids: i64 = db
            .query_one(
                "SELECT count(*) FROM jobs WHERE parent = $1 AND status = 'succeeded'",
                &[id],
            )
            .expect("query")
            .get(0);
        assert_eq!(kids as usize, runs, "search {id}");
    }
    // The killed worker's child was reaped once and rerun.
    let victim_expired = expired_attempts(&mut db, &victim);
    assert_eq!(victim_expired, 1);
    // Children stay out of the job list.
    let list = get_json(&api.addr, "/v1/jobs?limit=100");
    let listed = list["jobs"].as_array().map(Vec::len).unwrap_or(usize::MAX);
    assert_eq!(listed, 2, "{list}");
    // The multi-record search's plot was published by whichever worker finished it (when a
    // curve could be fitted: as in-process, a fit that fails is reported, not plotted).
    let (status, svg) = http(
        &api.addr,
        "GET",
        &format!("/v1/pga-searches/{}/fragility.svg", ids[1]),
        None,
    )
    .expect("GET");
    let fitted =
        !serde_json::from_str::<Value>(&reference[1]).expect("JSON")["fragility"].is_null();
    assert_eq!(status, if fitted { 200 } else { 409 }, "{svg:.300}");
    shut_down(api, workers, &root);
}

/// The embedded (SQLite) store fans out too when asked (`--fanout-width`): with ONE worker
/// thread, a search parks itself, the thread runs its children, the last child requeues it,
/// and so on to the end (no thread ever waits on children, so one thread cannot deadlock).
/// The results are exactly the in-process search's. Needs no PostgreSQL.
#[test]
fn embedded_store_fans_out_with_one_worker_thread() {
    let dir = temp_dir("fanout-embedded");
    let mut cfg = ServiceConfig::new(&dir);
    cfg.workers.workers = 1;
    cfg.workers.idle_poll = Duration::from_millis(50);
    cfg.workers.fanout_width = Some(rayon::current_num_threads());
    let svc = Service::start(cfg, ashlar::service::analysis_runner()).expect("embedded service");
    let core = svc.state().core.clone();
    let (single, multi) = search_bodies(3.0, 0.05, 5);
    let limits = ashlar::service::Limits::default();
    let ids: Vec<Uuid> = [&single, &multi]
        .iter()
        .map(|b| {
            let parsed = ashlar::service::request::parse_pga(b, &limits).expect("valid");
            let id = Uuid::new_v4();
            core.store
                .insert(&NewJob {
                    id,
                    kind: JobKind::PgaSearch,
                    request: (*b).clone(),
                    motion: parsed.motion_summary,
                    owner: None,
                })
                .expect("insert");
            core.notify_work();
            id
        })
        .collect();
    let mut progress = [0.0f64; 2];
    wait_until("both searches end", Duration::from_secs(600), || {
        ids.iter().enumerate().all(|(k, &id)| {
            let j = core.store.get(id).expect("get").expect("job");
            assert!(
                j.progress >= progress[k],
                "progress went back: {} after {}",
                j.progress,
                progress[k]
            );
            progress[k] = j.progress;
            j.status.is_terminal()
        })
    });
    for (id, body) in ids.iter().zip([&single, &multi]) {
        let j = core.store.get(*id).expect("get").expect("job");
        assert_eq!(j.status, JobStatus::Succeeded, "{:?}", j.error);
        let got: Value = serde_json::from_str(j.result.as_deref().expect("result")).expect("JSON");
        let want: Value = serde_json::from_str(&in_process(body)).expect("JSON");
        assert_eq!(got, want, "fanned out vs in-process");
        let kids = core.store.children(*id).expect("children");
        assert!(kids.len() > 5, "{} children", kids.len());
        assert!(kids.iter().all(|k| k.status == JobStatus::Succeeded));
    }
    // The multi-record search wrote its plot like the in-process runner does.
    assert!(core.job_dir(ids[1]).join("fragility.svg").exists());
    svc.shutdown(Duration::from_secs(5));
    std::fs::remove_dir_all(dir).ok();
}

#[test]
fn owners_quotas_and_retention_lookup_match_the_embedded_store() {
    // The SQLite store's `owner_quota_and_listing` unit test, on PostgreSQL (migration 3).
    let Some(base) = base_url("owners_quotas_and_retention_lookup_match_the_embedded_store") else {
        return;
    };
    let url = fresh_db(&base, "owner");
    let s = PgStore::open(&url, LeaseParams::default()).expect("open");
    let job = |kind, owner: Option<&str>| NewJob {
        id: Uuid::new_v4(),
        kind,
        request: json!({"a": 1}),
        motion: json!({"pga": 2.0}),
        owner: owner.map(str::to_string),
    };
    let mine = |kind| job(kind, Some("aaaa"));
    assert_eq!(s.insert_quota(&mine(JobKind::Run), 10, 2).expect("i"), None);
    assert_eq!(s.insert_quota(&mine(JobKind::Run), 10, 2).expect("i"), None);
    assert_eq!(
        s.insert_quota(&mine(JobKind::Run), 10, 2).expect("i"),
        Some(QueueFull::Owner(2))
    );
    assert_eq!(
        s.insert_quota(&mine(JobKind::PgaSearch), 10, 2).expect("i"),
        None
    );
    let theirs = job(JobKind::Run, Some("bbbb"));
    assert_eq!(s.insert_quota(&theirs, 10, 2).expect("i"), None);
    assert_eq!(
        s.insert_quota(&job(JobKind::Run, None), 10, 0).expect("i"),
        None
    );
    assert_eq!(
        s.insert_quota(&job(JobKind::Run, Some("bbbb")), 5, 2)
            .expect("i"),
        Some(QueueFull::Server(5))
    );
    assert_eq!(s.list_owned(10, None, Some("aaaa")).expect("l").len(), 3);
    let b = s.list_owned(10, None, Some("bbbb")).expect("l");
    assert_eq!(b.len(), 1);
    assert_eq!(b[0].owner.as_deref(), Some("bbbb"));
    assert_eq!(s.list_recent(10, None).expect("l").len(), 5);
    // Retention: only a finished top-level job that ended before the cutoff is listed.
    assert!(s
        .finished_before(i64::MAX, 10)
        .expect("finished")
        .is_empty());
    s.request_cancel(theirs.id).expect("cancel");
    assert_eq!(
        s.finished_before(i64::MAX, 10).expect("finished"),
        vec![theirs.id]
    );
    assert!(s.finished_before(0, 10).expect("finished").is_empty());
}

/// Isolation in cluster mode: `ashlar worker --isolation process` runs every job AND
/// every `pga_run` child of a fanned-out search in its own `ashlar internal-run-job` process
/// with resource limits. A search whose runs crash (SIGSEGV) or exhaust their memory fails with
/// the cause and the amplitude named, a run that aborts fails alone, and meanwhile a good run and
/// a good search on the same two workers succeed (the search with exactly the in-process result).
/// Neither worker dies, so no lease ever expires (a worker crash would be recovered by lease,
/// and would fail or rerun other people's jobs). Faults: the child's debug-only trigger
/// (`ASHLAR_TEST_FAULTS=1`, scenes named `fault:…`, as in tests/service/service_isolation.rs).
#[test]
fn crashing_runs_and_search_runs_fail_alone_on_isolated_workers() {
    let Some(base) = base_url("crashing_runs_and_search_runs_fail_alone_on_isolated_workers")
    else {
        return;
    };
    let url = fresh_db(&base, "isolation");
    let root = temp_dir("pg-isolation");
    let shared = format!("file://{}", root.join("shared").display());
    let api = Server::start(
        &root.join("api"),
        &[
            "--database",
            &url,
            "--workers",
            "0",
            "--lease",
            "2",
            "--artifacts",
            &shared,
        ],
    );
    let width = rayon::current_num_threads().to_string();
    // 512 MiB of address space: a column run's process needs well under that (VmPeak ~100 MB,
    // tests/service/service_isolation.rs), the allocating fault passes it within a second.
    let args = [
        "--workers",
        "1",
        "--lease",
        "2",
        "--artifacts",
        &shared,
        "--fanout-width",
        &width,
        "--isolation",
        "process",
        "--job-memory-limit",
        "512M",
    ];
    let mut workers: Vec<Worker> = (0..2)
        .map(|k| {
            Worker::start_env(
                &url,
                &root.join(format!("worker{k}")),
                &args,
                &[("ASHLAR_TEST_FAULTS", "1")],
            )
        })
        .collect();
    let post = |path: &str, b: &Value| {
        let (status, text) = http(&api.addr, "POST", path, Some(&b.to_string())).expect("POST");
        assert_eq!(status, 202, "{text}");
        let v: Value = serde_json::from_str(&text).expect("JSON");
        v["id"].as_str().expect("id").to_string()
    };
    let (good_search, _) = search_bodies(3.0, 0.05, 5);
    let faulty_search = |name: &str, body: &Value| {
        let mut b = body.clone();
        b["scene"]["name"] = json!(name);
        b
    };
    let (single, multi) = search_bodies(3.0, 0.05, 5);
    let segv_search = post("/v1/pga-searches", &faulty_search("fault:segv", &single));
    let alloc_search = post("/v1/pga-searches", &faulty_search("fault:alloc", &multi));
    let mut abort_run = job_body(0, 1.0);
    abort_run["scene"]["name"] = json!("fault:abort");
    let abort_run = post("/v1/jobs", &abort_run);
    let good_run = post("/v1/jobs", &job_body(1, 10.0));
    let good = post("/v1/pga-searches", &good_search);

    let all = [
        ("/v1/pga-searches", &segv_search),
        ("/v1/pga-searches", &alloc_search),
        ("/v1/jobs", &abort_run),
        ("/v1/jobs", &good_run),
        ("/v1/pga-searches", &good),
    ];
    wait_until("every job ends", Duration::from_secs(600), || {
        all.iter()
            .all(|(p, id)| is_terminal(&get_json(&api.addr, &format!("{p}/{id}"))))
    });
    let job = |p: &str, id: &str| get_json(&api.addr, &format!("{p}/{id}"));
    let failed_with = |p: &str, id: &str, causes: &[&str]| {
        let j = job(p, id);
        assert_eq!(j["status"], "failed", "{j}");
        let err = j["error"].as_str().unwrap_or("");
        for c in causes {
            assert!(err.contains(c), "expected {c:?} in {err:?}");
        }
    };
    failed_with(
        "/v1/pga-searches",
        &segv_search,
        &["the search's run at", "signal 11, SIGSEGV"],
    );
    failed_with(
        "/v1/pga-searches",
        &alloc_search,
        &[
            "the search's run at",
            "job memory limit of 536870912 bytes",
            "--job-memory-limit",
        ],
    );
    failed_with("/v1/jobs", &abort_run, &["signal 6, SIGABRT"]);
    let j = job("/v1/jobs", &good_run);
    assert_eq!(j["status"], "succeeded", "{j}");
    assert!(j["summary"]["blocks"].is_array(), "{j}");
    let j = job("/v1/pga-searches", &good);
    assert_eq!(j["status"], "succeeded", "{j}");
    let want: Value = serde_json::from_str(&in_process(&good_search)).expect("JSON");
    assert_eq!(
        j["result"], want,
        "children run in processes vs in-process search"
    );

    // Both workers are alive; no claim was lost to a dead worker; the crashing children failed
    // once each (not retried), and every child of the failed searches has ended.
    for w in &mut workers {
        assert!(w.alive(), "a worker died");
    }
    let mut db = sql(&url);
    let expired: i64 = db
        .query_one(
            "SELECT count(*) FROM job_attempts WHERE outcome = 'expired'",
            &[],
        )
        .expect("query")
        .get(0);
    assert_eq!(expired, 0, "a lease expired: a worker died under a job");
    for id in [&segv_search, &alloc_search] {
        let id = Uuid::parse_str(id).expect("uuid");
        let (failed, open, retried): (i64, i64, i64) = {
            let r = db
                .query_one(
                    "SELECT count(*) FILTER (WHERE status = 'failed'),
                            count(*) FILTER (WHERE status IN ('queued', 'running')),
                            count(*) FILTER (WHERE attempts > 1)
                     FROM jobs WHERE parent = $1",
                    &[&id],
                )
                .expect("query");
            (r.get(0), r.get(1), r.get(2))
        };
        assert!(failed >= 1, "search {id}: no failed child");
        assert_eq!(open, 0, "search {id}: children left unfinished");
        assert_eq!(retried, 0, "search {id}: a crashing child was retried");
    }
    // The workers still take work after the crashes.
    let again = post("/v1/jobs", &job_body(2, 1.0));
    wait_until("a job after the crashes", Duration::from_secs(120), || {
        is_terminal(&job("/v1/jobs", &again))
    });
    assert_eq!(job("/v1/jobs", &again)["status"], "succeeded");
    for w in workers.drain(..) {
        assert!(w.terminate().success(), "SIGTERM stops a worker cleanly");
    }
    drop(api);
    std::fs::remove_dir_all(root).ok();
}

/// docs/cluster.md, "Limits": an API-only process (`--workers 0`) reports in `/v1/limits` the
/// limits its workers apply, not its own flags (before: its own `--isolation process` and
/// `--max-job-seconds` while the worker ran jobs in threads for 50 s at most), lists every
/// distinct setting of the live workers, and a worker whose flags differ from the API's warns
/// at start, naming each flag. A worker that stops takes its setting with it.
#[test]
fn an_api_only_process_reports_its_workers_limits() {
    let Some(base) = base_url("an_api_only_process_reports_its_workers_limits") else {
        return;
    };
    let url = fresh_db(&base, "limits");
    let root = temp_dir("pg-limits");
    let api = Server::start(
        &root.join("api"),
        &[
            "--database",
            &url,
            "--workers",
            "0",
            "--lease",
            "2",
            "--isolation",
            "process",
            "--max-job-seconds",
            "100",
        ],
    );
    let alone = get_json(&api.addr, "/v1/limits");
    assert_eq!(alone["isolation"], "process", "{alone}");
    assert_eq!(alone["max_job_seconds"], 100, "{alone}");
    assert_eq!(alone["worker_limits"], json!([]), "{alone}");
    let w = Worker::start(
        &url,
        &root.join("w0"),
        &[
            "--workers",
            "1",
            "--lease",
            "2",
            "--isolation",
            "thread",
            "--max-job-seconds",
            "50",
        ],
    );
    let l = get_json(&api.addr, "/v1/limits");
    assert_eq!(l["isolation"], "thread", "{l}");
    assert_eq!(l["max_job_seconds"], 50, "{l}");
    assert!(l["job_memory_limit_bytes"].is_null(), "{l}");
    assert_eq!(
        l["max_blocks"], alone["max_blocks"],
        "submission limits stay the API's"
    );
    let sets = l["worker_limits"].as_array().expect("worker_limits");
    assert_eq!(sets.len(), 1, "{l}");
    assert_eq!(sets[0]["processes"], 1, "{l}");
    assert_eq!(sets[0]["max_job_seconds"], 50, "{l}");
    let log = std::fs::read_to_string(root.join("w0/worker.log")).expect("worker log");
    assert!(
        log.contains("--max-job-seconds 50 differs from the API process"),
        "no warning about the differing flag: {log}"
    );
    assert!(
        !log.contains("--max-blocks"),
        "a flag that agrees was named: {log}"
    );
    // A second worker with other limits: both settings listed, the API's fields follow one.
    let w2 = Worker::start(
        &url,
        &root.join("w1"),
        &["--workers", "1", "--lease", "2", "--max-job-seconds", "100"],
    );
    let l = get_json(&api.addr, "/v1/limits");
    assert_eq!(l["worker_limits"].as_array().map(Vec::len), Some(2), "{l}");
    let log = std::fs::read_to_string(root.join("w1/worker.log")).expect("worker log");
    assert!(!log.contains("differs from the API"), "flags agree: {log}");
    assert!(w.terminate().success());
    assert!(w2.terminate().success());
    let back = get_json(&api.addr, "/v1/limits");
    assert_eq!(back["worker_limits"], json!([]), "{back}");
    assert_eq!(back["isolation"], "process", "{back}");
    drop(api);
    std::fs::remove_dir_all(root).ok();
}
