//! Shared helpers of the service tests: an in-process service with the fake runner (driven
//! through `oneshot`, no socket), a tiny HTTP/1.1 client for the tests that run the binary, and
//! the scenes they submit.
#![allow(dead_code)]
use axum::body::Body;
use axum::http::{Request, Response};
use http_body_util::BodyExt;
use serde_json::Value;
use std::path::PathBuf;
use std::time::{Duration, Instant};
use tower::ServiceExt;

/// A fresh data directory under the system temp dir.
pub fn temp_dir(tag: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("ashlar-{tag}-{}", uuid::Uuid::new_v4()));
    std::fs::create_dir_all(&d).expect("temp dir");
    d
}

/// A column on a plinth, free to rock; `duration` s of simulation
/// ([`ashlar::presets::plinth_column_json`]).
pub fn column_scene(duration: f64) -> Value {
    ashlar::presets::plinth_column_json(duration)
}

/// A half-sine pulse of `amplitude` m/s² and period 0.4 s.
pub fn pulse(amplitude: f64) -> Value {
    ashlar::presets::half_sine_json(amplitude, 0.4)
}

/// [`column_scene`] with rigid blocks on the full engine (the default `auto` would run the
/// reduced rocking model on one column): the scene of the real-engine PGA searches.
pub fn rigid_column(duration: f64) -> Value {
    let mut s = column_scene(duration);
    s["control"]["block_model"] = serde_json::json!("rigid");
    s["control"]["model"] = serde_json::json!("dda");
    s
}

/// A named motion of one half-sine pulse of 1 m/s² and `period` s, as a search's `motions`
/// entry.
pub fn half_sine(period: f64, name: &str) -> Value {
    serde_json::json!({"name": name, "horizontal": {"pulse": {"amplitude": 1.0, "period": period, "cycles": 0.5, "units": "m/s2"}}})
}

/// Equal structure and strings; numbers within `rel` of each other (relative to the larger,
/// with 1e-300 absolute so exact zeros compare). `rel = 0` demands identical numbers.
pub fn close_num(a: f64, b: f64, rel: f64) -> bool {
    a == b || (a - b).abs() <= rel * a.abs().max(b.abs()) + 1e-300
}

pub fn close_json(a: &Value, b: &Value, rel: f64) -> bool {
    match (a, b) {
        (Value::Number(x), Value::Number(y)) => close_num(
            x.as_f64().unwrap_or(f64::NAN),
            y.as_f64().unwrap_or(f64::NAN),
            rel,
        ),
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

/// A response with its body collected.
pub struct Reply {
    pub status: u16,
    pub headers: axum::http::HeaderMap,
    pub body: Vec<u8>,
}

impl Reply {
    pub fn json(&self) -> Value {
        serde_json::from_slice(&self.body)
            .unwrap_or_else(|e| panic!("not JSON ({e}): {}", String::from_utf8_lossy(&self.body)))
    }
    pub fn text(&self) -> String {
        String::from_utf8_lossy(&self.body).into_owned()
    }
    pub fn header(&self, name: &str) -> Option<String> {
        self.headers
            .get(name)
            .and_then(|v| v.to_str().ok())
            .map(str::to_string)
    }
    /// Assert an RFC 9457 problem with this status; returns the problem object.
    pub fn problem(&self, status: u16) -> Value {
        assert_eq!(self.status, status, "status; body: {}", self.text());
        assert_eq!(
            self.header("content-type").as_deref(),
            Some("application/problem+json"),
            "body: {}",
            self.text()
        );
        let p = self.json();
        for k in ["type", "title", "status", "detail"] {
            assert!(p.get(k).is_some(), "problem lacks {k}: {p}");
        }
        assert_eq!(p["status"], status);
        p
    }
}

/// Send one request through the router (no socket).
pub async fn call(app: &axum::Router, req: Request<Body>) -> Reply {
    let resp: Response<Body> = app.clone().oneshot(req).await.expect("infallible router");
    let status = resp.status().as_u16();
    let headers = resp.headers().clone();
    let body = resp
        .into_body()
        .collect()
        .await
        .expect("body")
        .to_bytes()
        .to_vec();
    Reply {
        status,
        headers,
        body,
    }
}

pub fn get(uri: &str) -> Request<Body> {
    Request::builder()
        .uri(uri)
        .body(Body::empty())
        .expect("request")
}

pub fn post_json(uri: &str, body: &Value) -> Request<Body> {
    post_raw(uri, "application/json", body.to_string())
}

pub fn post_raw(uri: &str, content_type: &str, body: impl Into<Body>) -> Request<Body> {
    Request::builder()
        .method("POST")
        .uri(uri)
        .header("content-type", content_type)
        .body(body.into())
        .expect("request")
}

/// Poll a job until `done(job)` or the timeout; returns the last job JSON.
pub async fn wait_for(
    app: &axum::Router,
    uri: &str,
    timeout: Duration,
    done: impl Fn(&Value) -> bool,
) -> Value {
    let start = Instant::now();
    loop {
        let j = call(app, get(uri)).await.json();
        if done(&j) {
            return j;
        }
        assert!(
            start.elapsed() < timeout,
            "timed out after {timeout:?} waiting on {uri}; last: {j}"
        );
        tokio::time::sleep(Duration::from_millis(10)).await;
    }
}

/// A server-sent event stream's events: (event name, `data` as JSON), in order.
pub fn sse_events(text: &str) -> Vec<(String, Value)> {
    text.split("\n\n")
        .filter(|b| b.contains("data:"))
        .map(|block| {
            let name = block
                .lines()
                .find_map(|l| l.strip_prefix("event:"))
                .unwrap_or("")
                .trim()
                .to_string();
            let data = block
                .lines()
                .find_map(|l| l.strip_prefix("data:"))
                .unwrap_or("")
                .trim();
            (
                name,
                serde_json::from_str(data).expect("event data is JSON"),
            )
        })
        .collect()
}

pub fn is_terminal(j: &Value) -> bool {
    matches!(
        j["status"].as_str(),
        Some("succeeded" | "failed" | "cancelled")
    )
}

// ---- a minimal HTTP/1.1 client over std, for tests and tools that run the real binary ----
mod http_client;
pub use http_client::http;

/// The `ashlar serve` binary, started on a free loopback port.
pub struct Server {
    pub child: std::process::Child,
    pub addr: String,
}

impl Server {
    pub fn start(data: &std::path::Path, extra: &[&str]) -> Self {
        use std::io::BufRead;
        let mut child = std::process::Command::new(env!("CARGO_BIN_EXE_ashlar"))
            .args(["serve", "--addr", "127.0.0.1:0", "--data"])
            .arg(data)
            .args(extra)
            .stdout(std::process::Stdio::piped())
            .stderr(std::process::Stdio::null())
            .spawn()
            .expect("spawn ashlar serve");
        let stdout = child.stdout.take().expect("stdout");
        let mut line = String::new();
        std::io::BufReader::new(stdout)
            .read_line(&mut line)
            .expect("read the listening line");
        let addr = line
            .trim()
            .rsplit("http://")
            .next()
            .map(str::to_string)
            .unwrap_or_else(|| panic!("unexpected first line {line:?}"));
        Self { child, addr }
    }

    /// SIGKILL: no chance to clean up.
    pub fn kill(mut self) {
        self.child.kill().expect("kill");
        self.child.wait().expect("wait");
    }

    /// SIGTERM and wait for a clean exit.
    pub fn terminate(mut self) -> std::process::ExitStatus {
        let pid = self.child.id().to_string();
        std::process::Command::new("kill")
            .args(["-TERM", &pid])
            .status()
            .expect("kill -TERM");
        self.child.wait().expect("wait")
    }
}

impl Drop for Server {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

/// Poll `done` until it holds, failing after `timeout` with `what` (for the tests that drive
/// separate processes, where no event can be awaited).
pub fn wait_until(what: &str, timeout: Duration, mut done: impl FnMut() -> bool) {
    let start = Instant::now();
    while !done() {
        assert!(
            start.elapsed() < timeout,
            "timed out after {timeout:?}: {what}"
        );
        std::thread::sleep(Duration::from_millis(50));
    }
}

/// An `ashlar worker` process on `--database url`; its log goes to `<data>/worker.log`.
pub struct Worker {
    child: std::process::Child,
}

impl Worker {
    /// Start it and wait for its ready line; `extra` are further arguments.
    pub fn start(url: &str, data: &std::path::Path, extra: &[&str]) -> Self {
        Self::start_env(url, data, extra, &[])
    }

    /// [`Worker::start`] with extra environment variables (e.g. the isolation tests' fault
    /// trigger, which the worker's job processes inherit).
    pub fn start_env(
        url: &str,
        data: &std::path::Path,
        extra: &[&str],
        env: &[(&str, &str)],
    ) -> Self {
        use std::io::BufRead;
        std::fs::create_dir_all(data).expect("data dir");
        let log = std::fs::File::create(data.join("worker.log")).expect("log file");
        let mut child = std::process::Command::new(env!("CARGO_BIN_EXE_ashlar"))
            .args(["worker", "--database", url, "--data"])
            .arg(data)
            .args(extra)
            .envs(env.iter().copied())
            .stdout(std::process::Stdio::piped())
            .stderr(std::process::Stdio::from(log))
            .spawn()
            .expect("spawn ashlar worker");
        let mut line = String::new();
        std::io::BufReader::new(child.stdout.take().expect("stdout"))
            .read_line(&mut line)
            .expect("read the ready line");
        assert!(
            line.starts_with("ashlar worker: running"),
            "worker did not start: {line:?} (log: {})",
            std::fs::read_to_string(data.join("worker.log")).unwrap_or_default()
        );
        Self { child }
    }

    pub fn pid(&self) -> u32 {
        self.child.id()
    }

    /// The process has not exited.
    pub fn alive(&mut self) -> bool {
        matches!(self.child.try_wait(), Ok(None))
    }

    /// SIGKILL: no chance to clean up.
    pub fn kill(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }

    /// SIGTERM and wait for a clean exit.
    pub fn terminate(mut self) -> std::process::ExitStatus {
        std::process::Command::new("kill")
            .args(["-TERM", &self.child.id().to_string()])
            .status()
            .expect("kill -TERM");
        self.child.wait().expect("wait")
    }
}

impl Drop for Worker {
    fn drop(&mut self) {
        self.kill();
    }
}

/// A service in a fresh temporary directory with one worker and the fake runner (1 ms a job),
/// and its router: for tests of requests and routes, not of the engine.
pub fn start_fake(tag: &str) -> (ashlar::service::Service, axum::Router, PathBuf) {
    use ashlar::service::{app, Service, ServiceConfig, WorkerParams};
    let dir = temp_dir(tag);
    let mut cfg = ServiceConfig::new(&dir);
    cfg.workers = WorkerParams {
        workers: 1,
        ..WorkerParams::default()
    };
    let svc = Service::start(
        cfg,
        ashlar::service::fake::fake_runner(Duration::from_millis(1)),
    )
    .expect("start");
    let router = app(svc.state());
    (svc, router, dir)
}

/// A service in a fresh temporary directory with one worker running the real engine
/// (`analysis_runner`, polling every 50 ms) under `limits`, and its router: for tests of what
/// a job computes.
pub fn start_analysis(
    tag: &str,
    limits: ashlar::service::Limits,
) -> (ashlar::service::Service, axum::Router, PathBuf) {
    use ashlar::service::{analysis_runner, app, Service, ServiceConfig, WorkerParams};
    let dir = temp_dir(tag);
    let mut cfg = ServiceConfig::new(&dir);
    cfg.limits = limits;
    cfg.workers = WorkerParams {
        workers: 1,
        idle_poll: Duration::from_millis(50),
        ..WorkerParams::default()
    };
    let svc = Service::start(cfg, analysis_runner()).expect("start");
    let router = app(svc.state());
    (svc, router, dir)
}

/// Submit `body` to `collection` (e.g. `/v1/pga-searches`), wait until the job runs (or has
/// already ended), and ask to cancel it (200 or 202). Returns the job's URI.
pub async fn submit_and_cancel_when_running(
    app: &axum::Router,
    collection: &str,
    body: &Value,
) -> String {
    let r = call(app, post_json(collection, body)).await;
    assert_eq!(r.status, 202, "{}", r.text());
    let id = r.json()["id"].as_str().expect("id").to_string();
    let uri = format!("{collection}/{id}");
    wait_for(app, &uri, Duration::from_secs(60), |j| {
        j["status"] == "running" || is_terminal(j)
    })
    .await;
    let c = call(
        app,
        post_raw(&format!("{uri}/cancel"), "application/json", ""),
    )
    .await;
    assert!(matches!(c.status, 200 | 202), "{}", c.text());
    uri
}

/// Submit `body` to `collection` (202 asserted) and wait up to `timeout` for the job to end.
/// Returns the job's URI and its final JSON.
pub async fn submit_and_wait(
    app: &axum::Router,
    collection: &str,
    body: &Value,
    timeout: Duration,
) -> (String, Value) {
    let r = call(app, post_json(collection, body)).await;
    assert_eq!(r.status, 202, "{}", r.text());
    let id = r.json()["id"].as_str().expect("id").to_string();
    let uri = format!("{collection}/{id}");
    let j = wait_for(app, &uri, timeout, is_terminal).await;
    (uri, j)
}
