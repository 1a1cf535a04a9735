//! Durability: a job accepted with 202 is never lost. The real binary is started, 20 jobs are
//! submitted, the server is SIGKILLed while jobs are queued and running, a new server is started
//! on the same data directory, and all 20 must succeed with exactly the results of an
//! uninterrupted computation of the same inputs (histories byte for byte, summaries equal but
//! for the wall time).
//!
//! Two runners: the real engine (the point of the test), and the service's deterministic fake
//! (`--fake-runner`), which exercises the same kill-and-recover path independently of the physics.
use crate::service_support;

use ashlar::service::request::{parse_run, Limits};
use ashlar::service::{RunHooks, RunnerOutcome};
use serde_json::{json, Value};
use service_support::*;
use std::path::Path;
use std::sync::atomic::AtomicBool;
use std::time::{Duration, Instant};

const JOBS: usize = 20;

/// Job k: the column under a pulse whose amplitude grows with k (2.00 … 2.95 m/s²), so every
/// job has its own result and a mix-up between jobs would show.
fn job_body(k: usize, duration: f64) -> Value {
    // (200 + 5k) / 100 is the double nearest the short decimal, so the JSON text is short and
    // parses back exactly (see `uninterrupted`).
    // `"model": "dda"`: the full engine, which this test is about (the default `auto` would
    // run the reduced rocking model on this single column).
    let mut scene = column_scene(duration);
    scene["control"]["model"] = json!("dda");
    json!({"scene": scene, "motion": pulse((200 + 5 * k) as f64 / 100.0)})
}

fn get_json(addr: &str, path: &str) -> Value {
    let (status, body) = http(addr, "GET", path, None).expect("GET");
    assert_eq!(status, 200, "GET {path}: {body}");
    serde_json::from_str(&body).expect("JSON")
}

fn counts(addr: &str, ids: &[String]) -> (usize, usize) {
    let mut done = 0;
    let mut running = 0;
    for id in ids {
        match get_json(addr, &format!("/v1/jobs/{id}"))["status"].as_str() {
            Some("succeeded") => done += 1,
            Some("running") => running += 1,
            _ => {}
        }
    }
    (done, running)
}

/// Summary without the fields that legitimately differ between two computations. Both sides
/// pass through JSON text once (the served one came over HTTP), so both meet the same float
/// parser.
fn comparable(summary: Value) -> Value {
    let mut summary: Value = serde_json::from_str(&summary.to_string()).expect("JSON");
    if let Some(o) = summary.as_object_mut() {
        o.remove("wall_time_s");
    }
    summary
}

/// Submit, kill mid-run, restart, and check every job against `reference(k, out_dir)`.
fn kill_and_recover(
    tag: &str,
    extra: &[&str],
    duration: f64,
    rel_tol: f64,
    reference: impl Fn(&Value, &Path) -> Value,
) {
    let data = temp_dir(tag);
    let server = Server::start(&data, extra);
    let mut ids = Vec::new();
    for k in 0..JOBS {
        let (status, body) = http(
            &server.addr,
            "POST",
            "/v1/jobs",
            Some(&job_body(k, duration).to_string()),
        )
        .expect("POST");
        assert_eq!(status, 202, "{body}");
        let v: Value = serde_json::from_str(&body).expect("JSON");
        ids.push(v["id"].as_str().expect("id").to_string());
    }
    // Kill once some jobs have finished and others are running: the interesting moment.
    let start = Instant::now();
    loop {
        let (done, running) = counts(&server.addr, &ids);
        if done >= 2 && running >= 1 && done < JOBS - 4 {
            break;
        }
        assert!(
            done < JOBS - 4,
            "jobs ran too fast to kill mid-run ({done} done); lengthen them"
        );
        assert!(
            start.elapsed() < Duration::from_secs(300),
            "jobs did not start"
        );
        std::thread::sleep(Duration::from_millis(20));
    }
    server.kill();

    let server = Server::start(&data, extra);
    let start = Instant::now();
    let mut restarted = 0;
    loop {
        let (done, _) = counts(&server.addr, &ids);
        if done == JOBS {
            break;
        }
        let failed: Vec<Value> = ids
            .iter()
            .map(|id| get_json(&server.addr, &format!("/v1/jobs/{id}")))
            .filter(|j| matches!(j["status"].as_str(), Some("failed" | "cancelled")))
            .collect();
        assert!(
            failed.is_empty(),
            "a job was lost or failed after the restart: {failed:?}"
        );
        assert!(
            start.elapsed() < Duration::from_secs(600),
            "not all jobs finished after the restart"
        );
        std::thread::sleep(Duration::from_millis(100));
    }
    for (k, id) in ids.iter().enumerate() {
        let j = get_json(&server.addr, &format!("/v1/jobs/{id}"));
        if j["attempts"].as_u64() == Some(2) {
            restarted += 1;
        }
        let out = temp_dir(&format!("{tag}-ref"));
        let expected = reference(&job_body(k, duration), &out);
        let (a, b) = (comparable(j["summary"].clone()), comparable(expected));
        assert!(
            close_json(&a, &b, rel_tol),
            "job {k}: summary differs from an uninterrupted run:\n{a}\n{b}"
        );
        let served = std::fs::read_to_string(data.join("jobs").join(id).join("histories.csv"))
            .expect("served histories");
        let fresh =
            std::fs::read_to_string(out.join("histories.csv")).expect("reference histories");
        assert!(
            close_csv(&served, &fresh, rel_tol),
            "job {k}: histories.csv differs from an uninterrupted run"
        );
        std::fs::remove_dir_all(out).ok();
    }
    assert!(
        restarted >= 1,
        "at least one job was running when the server was killed and ran again"
    );
    let status = server.terminate();
    assert!(
        status.success(),
        "SIGTERM ends the server cleanly: {status:?}"
    );
    std::fs::remove_dir_all(data).ok();
}

fn close_csv(a: &str, b: &str, rel: f64) -> bool {
    let (la, lb): (Vec<&str>, Vec<&str>) = (a.lines().collect(), b.lines().collect());
    la.len() == lb.len()
        && la.first() == lb.first()
        && la.iter().zip(&lb).skip(1).all(|(x, y)| {
            let (xs, ys): (Vec<&str>, Vec<&str>) = (x.split(',').collect(), y.split(',').collect());
            xs.len() == ys.len()
                && xs
                    .iter()
                    .zip(&ys)
                    .all(|(p, q)| match (p.parse::<f64>(), q.parse::<f64>()) {
                        (Ok(p), Ok(q)) => close_num(p, q, rel),
                        _ => p == q,
                    })
        })
}

fn uninterrupted(runner: ashlar::service::JobRunner, body: &Value, out: &Path) -> Value {
    // The server parses the request text, stores it as JSON text and parses that again: do the
    // same, so that both computations start from identical numbers even where serde_json's
    // default float parser is not exact (it may be one ULP off on 17-digit decimals).
    let once: Value = serde_json::from_str(&body.to_string()).expect("JSON");
    let twice: Value = serde_json::from_str(&once.to_string()).expect("JSON");
    let parsed = parse_run(&twice, &Limits::default()).expect("valid job");
    let cancel = AtomicBool::new(false);
    let progress = |_: f64| {};
    let hooks = RunHooks {
        out_dir: out,
        cancel: &cancel,
        progress: &progress,
    };
    match runner(&parsed.input, &hooks).expect("reference run") {
        RunnerOutcome::Completed(v) => v,
        other => panic!("reference run did not complete: {other:?}"),
    }
}

#[test]
fn killed_server_loses_no_job_fake_runner() {
    // The fake runner in the binary spends 200 ms per simulated second: 2 s scenes take 0.4 s,
    // 20 of them on 2 workers about 4 s.
    let runner = ashlar::service::fake::fake_runner(Duration::ZERO);
    kill_and_recover(
        "durability-fake",
        &["--fake-runner", "--workers", "2"],
        2.0,
        0.0, // the fake is exactly reproducible
        |body, out| uninterrupted(runner.clone(), body, out),
    );
}

#[test]
fn killed_server_loses_no_job_real_engine() {
    let runner = ashlar::service::analysis_runner();
    kill_and_recover(
        "durability-engine",
        &["--workers", "2"],
        // 120 s simulated at the default 1 ms step: about half a second of CPU per job here.
        120.0,
        // The engine is not bit-reproducible across processes (last-bit differences seen in
        // max_penetration, presumably from an iteration order seeded per process); 1e-9 relative
        // is far below any physical meaning and far above rounding noise.
        1e-9,
        |body, out| uninterrupted(runner.clone(), body, out),
    );
}
