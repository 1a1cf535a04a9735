//! Access control with `--tokens` through the router (`oneshot`, fake runner): jobs owned by the
//! token that submitted them (another user's answer 404, an admin sees all), per-token queue
//! quotas (429), signed short-lived URLs for the links a browser or Foxglove opens (401 when
//! altered or expired), the retention sweeper, and motion values outside their ranges (422).
use crate::service_support;

use ashlar::service::auth::{unix_now, SigningKey, Tokens};
use ashlar::service::fake::fake_runner;
use ashlar::service::server::ServerParams;
use ashlar::service::{app, Limits, Service, ServiceConfig, WorkerParams};
use axum::body::Body;
use axum::http::Request;
use serde_json::{json, Value};
use service_support::*;
use std::sync::Arc;
use std::time::Duration;

const ALICE: &str = "alice-user-token-0001";
const BOB: &str = "bob-user-token-000002";
const ROOT: &str = "root-admin-token-0003";
/// A fixed key, so that the tests can sign (and mis-sign) URLs themselves.
const KEY: &[u8] = b"a-signing-key-for-the-access-tests-0123456789";

fn start(
    tag: &str,
    slowness: Duration,
    limits: Limits,
    retain: Option<Duration>,
) -> (Service, axum::Router, std::path::PathBuf) {
    let dir = temp_dir(tag);
    let mut cfg = ServiceConfig::new(&dir);
    cfg.limits = Limits {
        retain_finished: retain,
        ..limits
    };
    cfg.workers = WorkerParams {
        workers: 1,
        idle_poll: Duration::from_millis(50),
        ..WorkerParams::default()
    };
    let tokens =
        Tokens::parse(&format!("user {ALICE}\nuser {BOB}\nadmin {ROOT}\n")).expect("tokens");
    let server = ServerParams {
        tokens: Some(Arc::new(tokens)),
        signing: Some(SigningKey::from_bytes(KEY, Duration::from_secs(900)).expect("key")),
        ..Default::default()
    };
    let svc = Service::start_with(cfg, fake_runner(slowness), server).expect("start");
    let router = app(svc.state());
    (svc, router, dir)
}

fn with_token(mut req: Request<Body>, token: &str) -> Request<Body> {
    req.headers_mut().insert(
        "authorization",
        format!("Bearer {token}").parse().expect("header"),
    );
    req
}

fn method(m: &str, uri: &str, token: &str) -> Request<Body> {
    with_token(
        Request::builder()
            .method(m)
            .uri(uri)
            .body(Body::empty())
            .expect("request"),
        token,
    )
}

async fn submit_as(app: &axum::Router, token: &str, body: &Value) -> String {
    let r = call(app, with_token(post_json("/v1/jobs", body), token)).await;
    assert_eq!(r.status, 202, "{}", r.text());
    r.json()["id"].as_str().expect("id").to_string()
}

async fn wait_done(app: &axum::Router, token: &str, id: &str) -> Value {
    let start = std::time::Instant::now();
    loop {
        let j = call(app, method("GET", &format!("/v1/jobs/{id}"), token))
            .await
            .json();
        if is_terminal(&j) {
            return j;
        }
        assert!(start.elapsed() < Duration::from_secs(20), "job {id}: {j}");
        tokio::time::sleep(Duration::from_millis(10)).await;
    }
}

fn listed(r: &Reply) -> Vec<String> {
    r.json()["jobs"]
        .as_array()
        .expect("jobs")
        .iter()
        .map(|j| j["id"].as_str().expect("id").to_string())
        .collect()
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_user_sees_only_its_own_jobs_and_an_admin_all() {
    let (svc, app, dir) = start(
        "access-owner",
        Duration::from_millis(1),
        Limits::default(),
        None,
    );
    let body = json!({"scene": column_scene(1.0), "motion": pulse(3.0)});
    let a = submit_as(&app, ALICE, &body).await;
    let r = submit_as(&app, ROOT, &body).await;
    wait_done(&app, ALICE, &a).await;
    wait_done(&app, ROOT, &r).await;

    // Bob: Alice's job does not exist for him, by every route (404, not 403: ids do not leak).
    for (m, tail) in [
        ("GET", ""),
        ("GET", "/histories"),
        ("GET", "/trajectory.mcap"),
        ("GET", "/events"),
        ("GET", "/scene"),
        ("GET", "/ground"),
        ("POST", "/cancel"),
        ("DELETE", ""),
    ] {
        let reply = call(&app, method(m, &format!("/v1/jobs/{a}{tail}"), BOB)).await;
        let p = reply.problem(404);
        assert_eq!(p["type"], "urn:ashlar:problem:not-found", "{m} {tail}");
    }
    // Listings: each user its own, the admin everyone's.
    assert_eq!(
        listed(&call(&app, method("GET", "/v1/jobs", ALICE)).await),
        vec![a.clone()]
    );
    assert!(listed(&call(&app, method("GET", "/v1/jobs", BOB)).await).is_empty());
    let all = listed(&call(&app, method("GET", "/v1/jobs", ROOT)).await);
    assert!(all.contains(&a) && all.contains(&r), "{all:?}");
    // A user cannot delete an admin's job; the admin can delete a user's.
    call(&app, method("DELETE", &format!("/v1/jobs/{r}"), ALICE))
        .await
        .problem(404);
    assert_eq!(
        call(&app, method("GET", &format!("/v1/jobs/{r}"), ROOT))
            .await
            .status,
        200
    );
    assert_eq!(
        call(&app, method("GET", &format!("/v1/jobs/{a}"), ROOT))
            .await
            .status,
        200
    );
    assert_eq!(
        call(&app, method("DELETE", &format!("/v1/jobs/{a}"), ROOT))
            .await
            .status,
        204
    );
    call(&app, method("GET", &format!("/v1/jobs/{a}"), ALICE))
        .await
        .problem(404);
    svc.shutdown(Duration::from_secs(5));
    std::fs::remove_dir_all(dir).ok();
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn each_token_has_its_own_quota_of_queued_jobs() {
    // One worker, slow jobs (10 s each): everything after the first stays queued.
    let limits = Limits {
        max_queued_jobs_per_token: 2,
        ..Limits::default()
    };
    let (svc, app, dir) = start("access-quota", Duration::from_secs(1), limits, None);
    let body = json!({"scene": column_scene(10.0), "motion": pulse(3.0)});
    let mut accepted = 0;
    let refusal = loop {
        let r = call(&app, with_token(post_json("/v1/jobs", &body), ALICE)).await;
        if r.status == 202 {
            accepted += 1;
            assert!(accepted <= 3, "the quota of 2 queued jobs did not hold");
            continue;
        }
        break r;
    };
    // Two queued, and at most one taken by the worker meanwhile.
    assert!((2..=3).contains(&accepted), "{accepted} accepted");
    let p = refusal.problem(429);
    let detail = p["detail"].as_str().expect("detail");
    assert!(
        detail.contains("--max-queued-jobs-per-token") && detail.contains("2 waiting, limit 2"),
        "{detail}"
    );
    assert!(refusal.header("retry-after").is_some());
    // Bob's quota is his own; searches are counted apart from runs.
    submit_as(&app, BOB, &body).await;
    svc.shutdown(Duration::from_secs(0));
    std::fs::remove_dir_all(dir).ok();
}

fn query_param(url: &str, key: &str) -> String {
    url.split_once('?')
        .expect("query")
        .1
        .split('&')
        .find_map(|kv| kv.strip_prefix(&format!("{key}=")))
        .expect("param")
        .to_string()
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn signed_links_open_artifacts_without_a_header_until_they_expire() {
    let (svc, app, dir) = start(
        "access-signed",
        Duration::from_millis(1),
        Limits::default(),
        None,
    );
    let id = submit_as(
        &app,
        ALICE,
        &json!({"scene": column_scene(1.0), "motion": pulse(3.0)}),
    )
    .await;
    let j = wait_done(&app, ALICE, &id).await;
    assert_eq!(j["status"], "succeeded", "{j}");
    let links = &j["signed_links"];
    let traj = links["trajectory"].as_str().expect("signed trajectory");
    assert!(traj.starts_with(&format!("/v1/jobs/{id}/trajectory.mcap?expires=")));
    assert!(links["expires_at"].is_string());
    // Without a header, the signed links open; the unsigned ones do not.
    let r = call(&app, get(traj)).await;
    assert_eq!(r.status, 200, "{}", r.text());
    assert!(!r.body.is_empty());
    let hist = links["histories"].as_str().expect("signed histories");
    let r = call(&app, get(&format!("{hist}&format=csv"))).await;
    assert_eq!(r.status, 200, "{}", r.text());
    assert!(r.text().starts_with("time"), "{}", r.text());
    call(&app, get(&format!("/v1/jobs/{id}/trajectory.mcap")))
        .await
        .problem(401);
    // Altered: another job's path, a later expiry, a changed signature.
    let sig = query_param(traj, "sig");
    let expires: u64 = query_param(traj, "expires").parse().expect("expires");
    let other = uuid::Uuid::new_v4();
    for bad in [
        format!("/v1/jobs/{other}/trajectory.mcap?expires={expires}&sig={sig}"),
        format!(
            "/v1/jobs/{id}/trajectory.mcap?expires={}&sig={sig}",
            expires + 3600
        ),
        format!(
            "/v1/jobs/{id}/trajectory.mcap?expires={expires}&sig={}{}",
            if sig.starts_with('0') { "1" } else { "0" },
            &sig[1..]
        ),
        // A signature is only for its path: not the job resource itself.
        format!("/v1/jobs/{id}?expires={expires}&sig={sig}"),
    ] {
        let p = call(&app, get(&bad)).await.problem(401);
        assert_eq!(p["type"], "urn:ashlar:problem:unauthorized", "{bad}");
    }
    // Expired: signed with the server's key, valid until 20 min ago.
    let key = SigningKey::from_bytes(KEY, Duration::from_secs(600)).expect("key");
    let old = key.sign(&format!("/v1/jobs/{id}/trajectory.mcap"), unix_now() - 1800);
    let p = call(&app, get(&old)).await.problem(401);
    assert!(
        p["detail"].as_str().expect("detail").contains("expired"),
        "{p}"
    );
    // The same key, in date: accepted (the server checks the signature, not who made it).
    let fresh = key.sign(&format!("/v1/jobs/{id}/trajectory.mcap"), unix_now());
    assert_eq!(call(&app, get(&fresh)).await.status, 200);
    svc.shutdown(Duration::from_secs(5));
    std::fs::remove_dir_all(dir).ok();
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn finished_jobs_go_after_the_retention_period() {
    let (svc, app, dir) = start(
        "access-retain",
        Duration::from_millis(1),
        Limits::default(),
        Some(Duration::from_secs(1)),
    );
    let id = submit_as(
        &app,
        ALICE,
        &json!({"scene": column_scene(1.0), "motion": pulse(3.0)}),
    )
    .await;
    let j = wait_done(&app, ALICE, &id).await;
    assert_eq!(j["status"], "succeeded", "{j}");
    let jdir = dir.join("jobs").join(&id);
    assert!(jdir.exists());
    // Kept 1 s after it ended, swept at most 1 s later (the sweep interval is clamped to 1 s).
    let start = std::time::Instant::now();
    loop {
        let r = call(&app, method("GET", &format!("/v1/jobs/{id}"), ALICE)).await;
        if r.status == 404 {
            break;
        }
        assert!(
            start.elapsed() < Duration::from_secs(10),
            "not swept: {}",
            r.text()
        );
        tokio::time::sleep(Duration::from_millis(100)).await;
    }
    assert!(start.elapsed() >= Duration::from_millis(500), "swept early");
    assert!(!jdir.exists(), "its artifacts stay");
    svc.shutdown(Duration::from_secs(5));
    std::fs::remove_dir_all(dir).ok();
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn motion_values_outside_their_ranges_are_refused_with_their_pointer() {
    let (svc, app, dir) = start(
        "access-ranges",
        Duration::from_millis(1),
        Limits::default(),
        None,
    );
    let pulse_with = |k: &str, v: f64| {
        let mut p = pulse(3.0);
        p["horizontal"]["pulse"][k] = json!(v);
        p
    };
    let cases = [
        (
            pulse_with("amplitude", 1e308),
            "/motion/horizontal/pulse/amplitude",
        ),
        (
            pulse_with("period", 1e-9),
            "/motion/horizontal/pulse/period",
        ),
        (pulse_with("phase", -1e30), "/motion/horizontal/pulse/phase"),
        (
            json!({"horizontal": {"sine": {"amplitude": 0.1, "frequency": 1e9}}}),
            "/motion/horizontal/sine/frequency",
        ),
        (
            json!({"horizontal": {"sine": {"amplitude": -2e5, "frequency": 1.0}}}),
            "/motion/horizontal/sine/amplitude",
        ),
        (
            json!({"horizontal": {"samples": [0.0, 0.1, -0.2, 2e5, 0.0], "dt": 0.01}}),
            "/motion/horizontal/samples/3",
        ),
        (
            json!({"vertical": {"samples": [0.0, 0.1], "dt": 0.0}}),
            "/motion/vertical/dt",
        ),
        (
            json!({"horizontal": {"format": "csv", "content": "time,accel_g\n0,0\n0.01,0.1\n0.02,1e300\n0.03,0\n"},
                   "scale": {"factor": 1e-300}}),
            "/motion/horizontal/content",
        ),
    ];
    for (motion, pointer) in cases {
        let r = call(
            &app,
            with_token(
                post_json(
                    "/v1/jobs",
                    &json!({"scene": column_scene(1.0), "motion": motion}),
                ),
                ALICE,
            ),
        )
        .await;
        let p = r.problem(422);
        assert_eq!(p["pointer"], pointer, "{p}");
        let detail = p["detail"].as_str().expect("detail");
        assert!(detail.len() < 300, "{detail}");
        if pointer.ends_with("content") {
            assert!(detail.contains("sample 2"), "{detail}");
        }
    }
    // In a search's "motions", the pointer names the record.
    let search = json!({
        "scene": column_scene(1.0),
        "motions": [pulse(3.0), {"horizontal": {"samples": [0.0, 1e7], "dt": 0.01}}],
        "criterion": "toppled:column",
        "range": {"min": 0, "max": 1, "units": "g"},
    });
    let r = call(
        &app,
        with_token(post_json("/v1/pga-searches", &search), ALICE),
    )
    .await;
    assert_eq!(r.problem(422)["pointer"], "/motions/1/horizontal/samples/1");
    svc.shutdown(Duration::from_secs(5));
    std::fs::remove_dir_all(dir).ok();
}

/// Published artifacts (`--artifacts file:///DIR`, shared storage) go with their job: on
/// `DELETE /v1/jobs/{id}` and when the retention policy sweeps it, not only the local copy.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn deleting_a_job_removes_its_published_artifacts() {
    let dir = temp_dir("access-published");
    let shared = dir.join("shared");
    let mut cfg = ServiceConfig::new(dir.join("data"));
    cfg.artifacts = Some(format!("file://{}", shared.display()));
    cfg.workers = WorkerParams {
        workers: 1,
        idle_poll: Duration::from_millis(50),
        discard_local_artifacts: true,
        ..WorkerParams::default()
    };
    let svc = Service::start(cfg, fake_runner(Duration::from_millis(1))).expect("start");
    let app = ashlar::service::app(svc.state());
    let body = json!({"scene": column_scene(1.0), "motion": pulse(3.0)});
    let done = |id: String| {
        let app = app.clone();
        async move {
            let j = wait_for(
                &app,
                &format!("/v1/jobs/{id}"),
                Duration::from_secs(30),
                is_terminal,
            )
            .await;
            assert_eq!(j["status"], "succeeded", "{j}");
            id
        }
    };
    let submit = |b: Value| {
        let app = app.clone();
        async move {
            let r = call(&app, post_json("/v1/jobs", &b)).await;
            assert_eq!(r.status, 202, "{}", r.text());
            r.json()["id"].as_str().expect("id").to_string()
        }
    };
    let id = done(submit(body.clone()).await).await;
    let published = shared.join("jobs").join(&id);
    for f in ["summary.json", "histories.csv", "trajectory.mcap"] {
        assert!(published.join(f).is_file(), "{f} was not published");
    }
    // The worker's local copy was scratch: gone once published; served back from the shared
    // copy (and cached), which DELETE removes below with the cache.
    assert!(!dir.join("data/jobs").join(&id).exists(), "scratch kept");
    let r = call(&app, get(&format!("/v1/jobs/{id}/trajectory.mcap"))).await;
    assert_eq!(r.status, 200, "{}", r.text());
    assert!(dir
        .join("data/jobs")
        .join(&id)
        .join("trajectory.mcap")
        .is_file());
    let delete = Request::builder()
        .method("DELETE")
        .uri(format!("/v1/jobs/{id}"))
        .body(Body::empty())
        .expect("request");
    let r = call(&app, delete).await;
    assert_eq!(r.status, 204, "{}", r.text());
    assert!(!published.exists(), "published artifacts outlive DELETE");
    assert!(!dir.join("data/jobs").join(&id).exists());
    assert_eq!(
        call(&app, get(&format!("/v1/jobs/{id}/histories")))
            .await
            .status,
        404
    );
    assert!(shared.is_dir(), "the shared root stays");
    svc.shutdown(Duration::from_secs(5));

    // The retention sweeper removes them too (1 s policy, swept within about 2 s).
    let mut cfg = ServiceConfig::new(dir.join("data"));
    cfg.artifacts = Some(format!("file://{}", shared.display()));
    cfg.limits.retain_finished = Some(Duration::from_secs(1));
    cfg.workers = WorkerParams {
        workers: 1,
        idle_poll: Duration::from_millis(50),
        ..WorkerParams::default()
    };
    let svc = Service::start(cfg, fake_runner(Duration::from_millis(1))).expect("start");
    let router = ashlar::service::app(svc.state());
    let r = call(&router, post_json("/v1/jobs", &body)).await;
    assert_eq!(r.status, 202, "{}", r.text());
    let id = r.json()["id"].as_str().expect("id").to_string();
    let published = shared.join("jobs").join(&id);
    let start = std::time::Instant::now();
    let mut seen = false;
    loop {
        seen |= published.join("summary.json").is_file();
        if call(&router, get(&format!("/v1/jobs/{id}"))).await.status == 404 {
            break;
        }
        assert!(start.elapsed() < Duration::from_secs(20), "not swept");
        tokio::time::sleep(Duration::from_millis(50)).await;
    }
    assert!(seen, "the job's artifacts were never published");
    assert!(
        !published.exists(),
        "published artifacts outlive the retention"
    );
    svc.shutdown(Duration::from_secs(5));
    std::fs::remove_dir_all(dir).ok();
}

/// Two API processes on one store and one shared artifact storage (here two services on one
/// SQLite file, as two `ashlar serve --workers 0` on PostgreSQL): a job deleted through one
/// answers 404 through the other at once (every download loads the job first), and the other's
/// cached copy is removed by its cache sweep (before: it stayed in its `--data` for ever).
#[tokio::test]
async fn a_job_deleted_through_one_api_process_leaves_no_cached_copy_in_another() {
    let dir = temp_dir("access-two-apis");
    let shared = format!("file://{}", dir.join("shared").display());
    let config = |data: &str, workers: usize| {
        let mut cfg = ServiceConfig::new(dir.join(data));
        cfg.database = Some(dir.join("jobs.sqlite"));
        cfg.artifacts = Some(shared.clone());
        cfg.workers = WorkerParams {
            workers,
            idle_poll: Duration::from_millis(50),
            discard_local_artifacts: true,
            ..WorkerParams::default()
        };
        cfg
    };
    // Both started before any job exists: a starting embedded store requeues running jobs.
    let a = Service::start(config("a", 1), fake_runner(Duration::from_millis(1))).expect("a");
    let b = Service::start(config("b", 0), fake_runner(Duration::from_millis(1))).expect("b");
    let (app_a, app_b) = (app(a.state()), app(b.state()));
    let r = call(
        &app_a,
        post_json(
            "/v1/jobs",
            &json!({"scene": column_scene(1.0), "motion": pulse(3.0)}),
        ),
    )
    .await;
    assert_eq!(r.status, 202, "{}", r.text());
    let id = r.json()["id"].as_str().expect("id").to_string();
    let j = wait_for(
        &app_a,
        &format!("/v1/jobs/{id}"),
        Duration::from_secs(30),
        is_terminal,
    )
    .await;
    assert_eq!(j["status"], "succeeded", "{j}");
    // B serves the trajectory from the shared storage and keeps a copy.
    let r = call(&app_b, get(&format!("/v1/jobs/{id}/trajectory.mcap"))).await;
    assert_eq!(r.status, 200, "{}", r.text());
    let cached = dir.join("b/jobs").join(&id);
    assert!(cached.join("trajectory.mcap").is_file(), "B did not cache");
    let delete = Request::builder()
        .method("DELETE")
        .uri(format!("/v1/jobs/{id}"))
        .body(Body::empty())
        .expect("request");
    assert_eq!(call(&app_a, delete).await.status, 204);
    // B never serves its stale copy...
    for tail in ["/trajectory.mcap", "/histories", ""] {
        let r = call(&app_b, get(&format!("/v1/jobs/{id}{tail}"))).await;
        assert_eq!(r.status, 404, "{tail}: {}", r.text());
    }
    // ...and its cache sweep removes it, keeping the directories of jobs that exist.
    let r = call(
        &app_a,
        post_json(
            "/v1/jobs",
            &json!({"scene": column_scene(1.0), "motion": pulse(3.0)}),
        ),
    )
    .await;
    let live = r.json()["id"].as_str().expect("id").to_string();
    let live_dir = dir.join("b/jobs").join(&live);
    std::fs::create_dir_all(&live_dir).expect("dir");
    std::fs::create_dir_all(dir.join("b/jobs/not-a-job")).expect("dir");
    assert!(cached.is_dir(), "the copy is still there before the sweep");
    let core = b.state().core;
    let removed =
        tokio::task::spawn_blocking(move || ashlar::service::retention::sweep_cache(&core))
            .await
            .expect("sweep");
    assert_eq!(removed, 1);
    assert!(!cached.exists(), "B's cached copy of the deleted job stays");
    assert!(live_dir.is_dir(), "a live job's directory was removed");
    assert!(
        dir.join("b/jobs/not-a-job").is_dir(),
        "a foreign directory was removed"
    );
    a.shutdown(Duration::from_secs(5));
    b.shutdown(Duration::from_secs(5));
    std::fs::remove_dir_all(dir).ok();
}
