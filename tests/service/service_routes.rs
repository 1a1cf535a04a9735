//! Route tests without a socket: the router driven by `oneshot`, jobs run by the deterministic
//! fake runner (`ashlar::service::fake`), so these test the service's machinery (validation,
//! errors, queue, progress, cancellation, artifacts, restart) independently of the physics.
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

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_job_runs_and_its_outputs_are_served() {
    let (svc, app, dir) = start("routes-happy", 2, FAST, Limits::default());
    let id = submit(
        &app,
        &json!({"scene": column_scene(1.0), "motion": pulse(3.0)}),
    )
    .await;
    let uri = format!("/v1/jobs/{id}");
    let j = wait_for(&app, &uri, Duration::from_secs(20), is_terminal).await;
    assert_eq!(j["status"], "succeeded", "{j}");
    assert_eq!(j["progress"], 1.0);
    assert_eq!(j["attempts"], 1);
    assert_eq!(j["kind"], "run");
    assert!(j["error"].is_null());
    // The motion summary: a 3 m/s² half-sine pulse has PGA 3 m/s² and lasts 0.2 s (to rounding
    // of the dense sampling used for the peak: 1e-9 relative).
    assert!(
        (j["motion"]["pga"].as_f64().expect("pga") - 3.0).abs() < 3e-9,
        "{j}"
    );
    assert!((j["motion"]["duration"].as_f64().expect("duration") - 0.2).abs() < 1e-12);
    assert_eq!(j["summary"]["model"], "fake");
    assert_eq!(j["summary"]["blocks"][0]["id"], "column");

    // Histories: the JSON holds exactly the numbers of the runner's histories.csv.
    let file = std::fs::read_to_string(dir.join("jobs").join(&id).join("histories.csv"))
        .expect("histories.csv");
    let (header, cols) = csv_columns(&file);
    assert_eq!(
        header,
        vec!["time_s", "column.x_m", "column.y_m", "column.rotation_rad"]
    );
    let h = call(&app, get(&format!("{uri}/histories"))).await;
    assert_eq!(h.status, 200);
    assert_eq!(
        h.header("content-type").as_deref(),
        Some("application/json")
    );
    let h = h.json();
    let nums = |v: &Value| {
        v.as_array()
            .expect("array")
            .iter()
            .map(|x| x.as_f64().expect("number"))
            .collect::<Vec<_>>()
    };
    // Within one ULP: the server prints the shortest round-trip form (the CSV comparison below
    // is exact), but serde_json's default float parser, used here to read the JSON, may be off
    // by one ULP.
    let same = |a: Vec<f64>, b: &Vec<f64>| {
        a.len() == b.len()
            && a.iter()
                .zip(b)
                .all(|(x, y)| (x - y).abs() <= f64::EPSILON * x.abs().max(y.abs()))
    };
    assert!(same(nums(&h["time"]), &cols[0]), "time");
    assert!(same(nums(&h["blocks"]["column"]["x"]), &cols[1]), "x");
    assert!(same(nums(&h["blocks"]["column"]["y"]), &cols[2]), "y");
    assert!(
        same(nums(&h["blocks"]["column"]["rotation"]), &cols[3]),
        "rotation"
    );
    assert_eq!(
        cols[0].len(),
        101,
        "1 s at the default 0.01 s output interval, both ends included"
    );

    // CSV, by query and by Accept: same columns, same values as the file.
    let c = call(&app, get(&format!("{uri}/histories?format=csv"))).await;
    assert_eq!(c.status, 200);
    assert!(c
        .header("content-type")
        .unwrap_or_default()
        .starts_with("text/csv"));
    assert_eq!(csv_columns(&c.text()), (header.clone(), cols.clone()));
    let req = Request::builder()
        .uri(format!("{uri}/histories"))
        .header("accept", "text/csv")
        .body(Body::empty())
        .expect("req");
    assert_eq!(csv_columns(&call(&app, req).await.text()), (header, cols));
    let f = call(
        &app,
        get(&format!("{uri}/histories?block=column&format=json")),
    )
    .await;
    assert_eq!(f.json()["blocks"].as_object().expect("blocks").len(), 1);

    // Trajectory: whole file, ranges, CORS for Foxglove.
    let expected: Vec<u8> = (0..FAKE_TRAJECTORY_LEN).map(|k| (k % 251) as u8).collect();
    let req = Request::builder()
        .uri(format!("{uri}/trajectory.mcap"))
        .header("origin", "https://app.foxglove.dev")
        .body(Body::empty())
        .expect("req");
    let t = call(&app, req).await;
    assert_eq!(t.status, 200);
    assert_eq!(t.body, expected);
    assert_eq!(
        t.header("content-type").as_deref(),
        Some("application/octet-stream")
    );
    assert_eq!(t.header("accept-ranges").as_deref(), Some("bytes"));
    assert_eq!(
        t.header("access-control-allow-origin").as_deref(),
        Some("https://app.foxglove.dev")
    );
    // Only the origins given with --cors-origin: any other page in the browser gets nothing.
    let req = Request::builder()
        .uri(format!("{uri}/trajectory.mcap"))
        .header("origin", "https://evil.example")
        .body(Body::empty())
        .expect("req");
    let t = call(&app, req).await;
    assert_eq!(t.header("access-control-allow-origin"), None);
    for (range, a, b) in [
        ("bytes=0-99", 0, 99),
        ("bytes=9990-", 9990, 9999),
        ("bytes=-10", 9990, 9999),
        ("bytes=500-20000", 500, 9999),
    ] {
        let req = Request::builder()
            .uri(format!("{uri}/trajectory.mcap"))
            .header("range", range)
            .body(Body::empty())
            .expect("req");
        let p = call(&app, req).await;
        assert_eq!(p.status, 206, "{range}");
        assert_eq!(p.body, expected[a..=b].to_vec(), "{range}");
        assert_eq!(
            p.header("content-range"),
            Some(format!("bytes {a}-{b}/{FAKE_TRAJECTORY_LEN}"))
        );
    }
    let req = Request::builder()
        .uri(format!("{uri}/trajectory.mcap"))
        .header("range", "bytes=20000-")
        .body(Body::empty())
        .expect("req");
    let p = call(&app, req).await;
    p.problem(416);
    assert_eq!(
        p.header("content-range"),
        Some(format!("bytes */{FAKE_TRAJECTORY_LEN}"))
    );

    // A finished job cannot be cancelled.
    let p = call(
        &app,
        post_raw(&format!("{uri}/cancel"), "application/json", ""),
    )
    .await
    .problem(409);
    assert!(p["detail"]
        .as_str()
        .unwrap_or_default()
        .contains("succeeded"));
    svc.shutdown(Duration::from_secs(5));
    std::fs::remove_dir_all(dir).ok();
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn bad_requests_get_problems_naming_the_field() {
    let limits = Limits {
        max_body_bytes: 20_000,
        max_blocks: 3,
        max_record_samples: 100,
        max_total_steps: 5000,
        ..Limits::default()
    };
    let (svc, app, dir) = start("routes-errors", 1, FAST, limits);
    let scene = column_scene(1.0);

    // JSON syntax error: 400, with line and column.
    let p = call(
        &app,
        post_raw("/v1/jobs", "application/json", "{\"scene\": {,}"),
    )
    .await
    .problem(400);
    assert!(
        p["detail"]
            .as_str()
            .unwrap_or_default()
            .contains("line 1, column"),
        "{p}"
    );
    let p = call(&app, post_raw("/v1/jobs", "application/json", ""))
        .await
        .problem(400);
    assert!(
        p["detail"].as_str().unwrap_or_default().contains("empty"),
        "{p}"
    );
    // Not JSON content: 415 naming the header.
    let p = call(&app, post_raw("/v1/jobs", "text/plain", scene.to_string()))
        .await
        .problem(415);
    assert_eq!(p["parameter"], "Content-Type");
    // Body over the size limit: 413.
    let big = json!({"scene": scene, "motion": {"horizontal": {"samples": vec![0.125; 5000], "dt": 0.01}}});
    call(&app, post_json("/v1/jobs", &big)).await.problem(413);

    // Schema and semantic errors: 422 with a JSON pointer to the field.
    let cases: Vec<(Value, &str)> = vec![
        (json!([1, 2]), ""),
        (json!({"motion": null}), "/scene"),
        (json!({"scene": scene, "extra": true}), "/extra"),
        (
            json!({"scene": {"format": "ashlar.scene/1"}}),
            "/scene/materials",
        ),
        (
            {
                let mut s = scene.clone();
                s["blocks"][1]["vertices"] = json!([[0, 0], [1, 1]]);
                json!({"scene": s})
            },
            "/scene/blocks/1/vertices",
        ),
        (
            {
                let mut s = scene.clone();
                s["blocks"][1]["material"] = json!("granite");
                json!({"scene": s})
            },
            "/scene/blocks/1/material",
        ),
        (
            {
                let mut s = scene.clone();
                s["control"]["time_stpe"] = json!(0.001);
                json!({"scene": s})
            },
            "/scene/control/time_stpe",
        ),
        (
            {
                let mut s = scene.clone();
                s["joints"]["dry"]["friction_angle"] = json!(95);
                json!({"scene": s})
            },
            "/scene/joints/dry/friction_angle",
        ),
        (
            {
                let mut s = scene.clone();
                s["excitation"] = json!({"type": "base_acceleration", "block": "x"});
                json!({"scene": s})
            },
            "/scene/excitation/block",
        ),
        (
            // The range check (docs/format.md "Ranges") names the member itself.
            json!({"scene": scene, "motion": {"horizontal": {"pulse": {"amplitude": 1, "period": 0}}}}),
            "/motion/horizontal/pulse/period",
        ),
        (
            json!({"scene": scene, "motion": {"horizontal": {"pulse": {"amplitude": 1, "period": 1}, "sine": {}}}}),
            "/motion/horizontal/sine",
        ),
        (
            json!({"scene": scene, "motion": {"horizontal": {"sine": {"amplitude": 1, "frequency": 1}}, "wobble": 1}}),
            "/motion/wobble",
        ),
        (
            json!({"scene": scene, "motion": {"horizontal": {"sine": {"amplitude": 1, "frequency": 1}},
                   "scale": {"target_pga": 1.0, "units": null}}}),
            "/motion/scale/units",
        ),
        (
            {
                let mut s = scene.clone();
                s["control"] = json!({});
                json!({"scene": s})
            },
            "/scene/control/duration",
        ),
        (
            // A forced reduced model on a scene it cannot represent: refused at submission,
            // not failed later by a worker.
            {
                let mut s = scene.clone();
                s["control"]["model"] = json!("rocking");
                s["blocks"]
                    .as_array_mut()
                    .expect("blocks")
                    .push(json!({"id": "b2", "material": "limestone",
                    "vertices": [[2.0, 0.0], [2.5, 0.0], [2.5, 0.5]]}));
                json!({"scene": s})
            },
            "/scene/control/model",
        ),
        (
            // A dual-solver knob with the penalty solver: refused, not silently ignored.
            {
                let mut s = scene.clone();
                s["control"]["dual_tolerance"] = json!(1e-4);
                json!({"scene": s})
            },
            "/scene/control/dual_tolerance",
        ),
    ];
    for (body, pointer) in cases {
        let r = call(&app, post_json("/v1/jobs", &body)).await;
        let p = r.problem(422);
        assert_eq!(p["pointer"], pointer, "body {body}: {p}");
        assert!(p["detail"].as_str().unwrap_or_default().len() > 10, "{p}");
    }
    // Limits: blocks, record length, steps, frames; each 422 naming the field and the flag.
    let mut s = scene.clone();
    let extra: Vec<Value> = (0..3)
        .map(|k| {
            json!({"id": format!("b{k}"), "material": "limestone",
        "vertices": [[2.0 + k as f64, 0.0], [2.5 + k as f64, 0.0], [2.5 + k as f64, 0.5]]})
        })
        .collect();
    s["blocks"].as_array_mut().expect("blocks").extend(extra);
    let p = call(&app, post_json("/v1/jobs", &json!({"scene": s})))
        .await
        .problem(422);
    assert_eq!(
        (p["pointer"].as_str(), p["type"].as_str()),
        (
            Some("/scene/blocks"),
            Some("urn:ashlar:problem:limit-exceeded")
        )
    );
    assert!(p["detail"]
        .as_str()
        .unwrap_or_default()
        .contains("--max-blocks"));
    let m = json!({"horizontal": {"samples": vec![0.0; 101], "dt": 0.01}});
    assert_eq!(
        call(
            &app,
            post_json("/v1/jobs", &json!({"scene": scene, "motion": m}))
        )
        .await
        .problem(422)["pointer"],
        "/motion"
    );
    let mut s = scene.clone();
    s["control"]["duration"] = json!(6.0); // 6000 steps of 1 ms > 5000
    assert_eq!(
        call(&app, post_json("/v1/jobs", &json!({"scene": s})))
            .await
            .problem(422)["pointer"],
        "/scene/control/duration"
    );
    let mut s = scene.clone();
    s["control"] = json!({"duration": 1.0, "time_step": 0.01, "output_interval": 1e-4}); // 10000 frames
    assert_eq!(
        call(&app, post_json("/v1/jobs", &json!({"scene": s})))
            .await
            .problem(422)["pointer"],
        "/scene/control/output_interval"
    );

    // Path and query parameters.
    assert_eq!(
        call(&app, get("/v1/jobs/not-a-uuid")).await.problem(400)["parameter"],
        "id"
    );
    let unknown = uuid::Uuid::new_v4();
    assert_eq!(
        call(&app, get(&format!("/v1/jobs/{unknown}")))
            .await
            .problem(404)["parameter"],
        "id"
    );
    call(&app, get(&format!("/v1/jobs/{unknown}/histories")))
        .await
        .problem(404);
    call(&app, get(&format!("/v1/jobs/{unknown}/trajectory.mcap")))
        .await
        .problem(404);
    call(&app, get(&format!("/v1/jobs/{unknown}/events")))
        .await
        .problem(404);
    call(
        &app,
        post_raw(
            &format!("/v1/jobs/{unknown}/cancel"),
            "application/json",
            "",
        ),
    )
    .await
    .problem(404);
    call(&app, get(&format!("/v1/pga-searches/{unknown}")))
        .await
        .problem(404);

    let id = submit(&app, &json!({"scene": scene, "motion": pulse(2.0)})).await;
    let uri = format!("/v1/jobs/{id}");
    // A run id is not a PGA search id.
    call(&app, get(&format!("/v1/pga-searches/{id}")))
        .await
        .problem(404);
    wait_for(&app, &uri, Duration::from_secs(20), is_terminal).await;
    assert_eq!(
        call(&app, get(&format!("{uri}/histories?format=xml")))
            .await
            .problem(400)["parameter"],
        "format"
    );
    assert_eq!(
        call(&app, get(&format!("{uri}/histories?blok=column")))
            .await
            .problem(400)["parameter"],
        "blok"
    );
    let p = call(&app, get(&format!("{uri}/histories?block=plinth")))
        .await
        .problem(404);
    assert_eq!(p["parameter"], "block");
    assert!(
        p["detail"]
            .as_str()
            .unwrap_or_default()
            .contains("\"plinth\""),
        "{p}"
    );
    let req = Request::builder()
        .uri(format!("{uri}/histories"))
        .header("accept", "image/png")
        .body(Body::empty())
        .expect("req");
    call(&app, req).await.problem(406);

    // Unknown endpoints and methods are problems too.
    assert_eq!(
        call(&app, get("/v2/nothing")).await.problem(404)["type"],
        "urn:ashlar:problem:no-route"
    );
    let req = Request::builder()
        .method("PUT")
        .uri(&uri)
        .body(Body::empty())
        .expect("req");
    let r = call(&app, req).await;
    let p = r.problem(405);
    assert!(r.header("allow").unwrap_or_default().contains("GET"));
    // The detail names the methods the path takes (it used to say "see /openapi.yaml").
    let detail = p["detail"].as_str().unwrap_or_default();
    assert!(
        detail.contains("GET") && detail.contains("DELETE"),
        "{detail}"
    );
    svc.shutdown(Duration::from_secs(5));
    std::fs::remove_dir_all(dir).ok();
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn histories_are_not_served_before_the_job_succeeds() {
    // 100 ms wall per simulated second: a 30 s scene runs 3 s.
    let (svc, app, dir) = start(
        "routes-409",
        1,
        Duration::from_millis(100),
        Limits::default(),
    );
    let id = submit(
        &app,
        &json!({"scene": column_scene(30.0), "motion": pulse(1.0)}),
    )
    .await;
    let uri = format!("/v1/jobs/{id}");
    let p = call(&app, get(&format!("{uri}/histories")))
        .await
        .problem(409);
    assert!(
        p["detail"]
            .as_str()
            .unwrap_or_default()
            .contains("available once it has succeeded"),
        "{p}"
    );
    call(&app, get(&format!("{uri}/trajectory.mcap")))
        .await
        .problem(409);
    svc.shutdown(Duration::ZERO);
    std::fs::remove_dir_all(dir).ok();
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn cancelling_a_running_job_stops_it_within_one_frame() {
    // 100 ms wall per simulated second, frames every 0.01 s: a frame takes 1 ms of wall time.
    let (svc, app, dir) = start(
        "routes-cancel",
        1,
        Duration::from_millis(100),
        Limits::default(),
    );
    let id = submit(
        &app,
        &json!({"scene": column_scene(60.0), "motion": pulse(1.0)}),
    )
    .await;
    let uri = format!("/v1/jobs/{id}");
    let running = wait_for(&app, &uri, Duration::from_secs(20), |j| {
        j["status"] == "running"
    })
    .await;
    assert_eq!(running["status"], "running");
    // Progress reaches the store while it runs (written at most every 250 ms).
    let j = wait_for(&app, &uri, Duration::from_secs(5), |j| {
        j["progress"].as_f64().unwrap_or(0.0) > 0.0
    })
    .await;
    assert!(j["progress"].as_f64().unwrap_or(1.0) < 1.0);
    let t0 = Instant::now();
    let r = call(
        &app,
        post_raw(&format!("{uri}/cancel"), "application/json", ""),
    )
    .await;
    assert_eq!(r.status, 202, "{}", r.text());
    assert_eq!(r.json()["cancel_requested"], true);
    let j = wait_for(&app, &uri, Duration::from_secs(5), is_terminal).await;
    let took = t0.elapsed();
    assert_eq!(j["status"], "cancelled", "{j}");
    // Within one frame (1 ms) plus polling (10 ms) and scheduling slack on a loaded 2-core
    // machine: 1 s is far below the 6 s the run had left, so it cannot pass by finishing.
    assert!(took < Duration::from_secs(1), "cancellation took {took:?}");
    // The partial outputs stay available, shorter than the full 6001 frames.
    let h = call(&app, get(&format!("{uri}/histories"))).await.json();
    let n = h["time"].as_array().map(Vec::len).unwrap_or(0);
    assert!(n > 0 && n < 6001, "{n} frames");
    assert_eq!(j["summary"]["completed"], false);
    svc.shutdown(Duration::ZERO);
    std::fs::remove_dir_all(dir).ok();
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn cancelling_a_queued_job_is_immediate_and_it_never_runs() {
    let (svc, app, dir) = start(
        "routes-cancel-queued",
        1,
        Duration::from_millis(100),
        Limits::default(),
    );
    let first = submit(
        &app,
        &json!({"scene": column_scene(10.0), "motion": pulse(1.0)}),
    )
    .await;
    let second = submit(
        &app,
        &json!({"scene": column_scene(1.0), "motion": pulse(1.0)}),
    )
    .await;
    wait_for(
        &app,
        &format!("/v1/jobs/{first}"),
        Duration::from_secs(20),
        |j| j["status"] == "running",
    )
    .await;
    let r = call(
        &app,
        post_raw(&format!("/v1/jobs/{second}/cancel"), "application/json", ""),
    )
    .await;
    assert_eq!(r.status, 200, "{}", r.text());
    assert_eq!(r.json()["status"], "cancelled");
    call(
        &app,
        post_raw(&format!("/v1/jobs/{first}/cancel"), "application/json", ""),
    )
    .await;
    wait_for(
        &app,
        &format!("/v1/jobs/{first}"),
        Duration::from_secs(5),
        is_terminal,
    )
    .await;
    // The worker is free now; the cancelled job must still never have started.
    tokio::time::sleep(Duration::from_millis(200)).await;
    let j = call(&app, get(&format!("/v1/jobs/{second}"))).await.json();
    assert_eq!(
        (j["status"].as_str(), j["attempts"].as_u64()),
        (Some("cancelled"), Some(0)),
        "{j}"
    );
    assert!(
        !dir.join("jobs").join(&second).exists(),
        "a cancelled queued job writes nothing"
    );
    svc.shutdown(Duration::ZERO);
    std::fs::remove_dir_all(dir).ok();
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn progress_streams_as_server_sent_events_until_the_end() {
    // 20 ms per simulated second: a 5 s scene takes 100 ms, long enough to see progress events.
    let (svc, app, dir) = start(
        "routes-sse",
        1,
        Duration::from_millis(20),
        Limits::default(),
    );
    let id = submit(
        &app,
        &json!({"scene": column_scene(5.0), "motion": pulse(1.0)}),
    )
    .await;
    let r = call(&app, get(&format!("/v1/jobs/{id}/events"))).await;
    assert_eq!(r.status, 200);
    assert_eq!(
        r.header("content-type").as_deref(),
        Some("text/event-stream")
    );
    let text = r.text();
    let mut events: Vec<(String, Value)> = Vec::new();
    for block in text.split("\n\n").filter(|b| b.contains("data:")) {
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
        events.push((
            name,
            serde_json::from_str(data).expect("event data is JSON"),
        ));
    }
    assert!(events.len() >= 3, "expected several events, got {text}");
    let (last_name, last) = events.last().expect("events");
    assert_eq!(
        (last_name.as_str(), last["status"].as_str()),
        ("end", Some("succeeded"))
    );
    assert_eq!(last["progress"], 1.0);
    let p: Vec<f64> = events
        .iter()
        .map(|(_, e)| e["progress"].as_f64().unwrap_or(-1.0))
        .collect();
    assert!(
        p.windows(2).all(|w| w[0] <= w[1]),
        "progress never goes back: {p:?}"
    );
    assert!(
        p.iter().any(|&x| x > 0.0 && x < 1.0),
        "intermediate progress seen: {p:?}"
    );
    // A finished job's stream is one `end` event.
    let again = call(&app, get(&format!("/v1/jobs/{id}/events")))
        .await
        .text();
    assert_eq!(again.matches("data:").count(), 1, "{again}");
    assert!(again.contains("event: end"));
    svc.shutdown(Duration::ZERO);
    std::fs::remove_dir_all(dir).ok();
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn failures_and_panics_fail_the_job_not_the_worker() {
    let (svc, app, dir) = start("routes-fail", 1, FAST, Limits::default());
    let mut s = column_scene(1.0);
    s["name"] = json!("fake:fail");
    let failing = submit(&app, &json!({"scene": s})).await;
    s["name"] = json!("fake:panic");
    let panicking = submit(&app, &json!({"scene": s})).await;
    let fine = submit(&app, &json!({"scene": column_scene(1.0)})).await;
    let j = wait_for(
        &app,
        &format!("/v1/jobs/{failing}"),
        Duration::from_secs(20),
        is_terminal,
    )
    .await;
    assert_eq!(j["status"], "failed");
    assert!(
        j["error"]
            .as_str()
            .unwrap_or_default()
            .contains("fake failure"),
        "{j}"
    );
    let j = wait_for(
        &app,
        &format!("/v1/jobs/{panicking}"),
        Duration::from_secs(20),
        is_terminal,
    )
    .await;
    assert_eq!(j["status"], "failed");
    assert!(
        j["error"]
            .as_str()
            .unwrap_or_default()
            .contains("internal error"),
        "{j}"
    );
    assert!(
        !j["error"]
            .as_str()
            .unwrap_or_default()
            .contains("fake panic"),
        "panic text stays in the log"
    );
    // The single worker survived both.
    let j = wait_for(
        &app,
        &format!("/v1/jobs/{fine}"),
        Duration::from_secs(20),
        is_terminal,
    )
    .await;
    assert_eq!(j["status"], "succeeded");
    call(&app, get(&format!("/v1/jobs/{failing}/histories")))
        .await
        .problem(409);
    assert_eq!(call(&app, get("/healthz")).await.status, 200);
    svc.shutdown(Duration::ZERO);
    std::fs::remove_dir_all(dir).ok();
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn pga_searches_run_and_report_the_result() {
    let (svc, app, dir) = start("routes-pga", 1, FAST, Limits::default());
    let body = json!({"scene": column_scene(1.0), "motion": pulse(1.0), "criterion": "toppled:column",
                      "range": {"min": 0.0, "max": 1.0, "units": "g"}, "tolerance": 0.01});
    let r = call(&app, post_json("/v1/pga-searches", &body)).await;
    assert_eq!(r.status, 202, "{}", r.text());
    let id = r.json()["id"].as_str().expect("id").to_string();
    assert_eq!(r.header("location"), Some(format!("/v1/pga-searches/{id}")));
    let j = wait_for(
        &app,
        &format!("/v1/pga-searches/{id}"),
        Duration::from_secs(20),
        is_terminal,
    )
    .await;
    assert_eq!(j["status"], "succeeded", "{j}");
    let res = &j["result"];
    // The fake's threshold is mid-range, 0.5 g; the result brackets it within the tolerance
    // (0.01 g), both in m/s².
    let (safe, failing) = (
        res["safe_pga"].as_f64().expect("safe"),
        res["failing_pga"].as_f64().expect("failing"),
    );
    let g = 9.80665;
    assert!(
        safe < 0.5 * g && failing >= 0.5 * g && failing - safe <= 0.01 * g + 1e-12,
        "{res}"
    );
    assert_eq!(res["criterion"], "toppled:column");
    assert_eq!(res["units"], "m/s2");
    // A search id is not a job id; errors name the field.
    call(&app, get(&format!("/v1/jobs/{id}")))
        .await
        .problem(404);
    let mut bad = body.clone();
    bad["criterion"] = json!("toppled:tower");
    assert_eq!(
        call(&app, post_json("/v1/pga-searches", &bad))
            .await
            .problem(422)["pointer"],
        "/criterion"
    );
    let mut bad = body.clone();
    bad["range"] = json!({"min": 2.0, "max": 1.0});
    assert_eq!(
        call(&app, post_json("/v1/pga-searches", &bad))
            .await
            .problem(422)["pointer"],
        "/range/max"
    );
    let mut bad = body;
    bad.as_object_mut().expect("object").remove("motion");
    assert_eq!(
        call(&app, post_json("/v1/pga-searches", &bad))
            .await
            .problem(422)["pointer"],
        "/motion"
    );
    svc.shutdown(Duration::ZERO);
    std::fs::remove_dir_all(dir).ok();
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn shutdown_requeues_running_jobs_and_a_new_server_finishes_them() {
    let dir = temp_dir("routes-restart");
    let cfg = |workers| {
        let mut c = ServiceConfig::new(&dir);
        c.workers = WorkerParams {
            workers,
            idle_poll: Duration::from_millis(50),
            ..WorkerParams::default()
        };
        c
    };
    // First server: slow (a 20 s scene takes 2 s), shut down with no grace while both run.
    let svc = Service::start(cfg(2), fake_runner(Duration::from_millis(100))).expect("start");
    let app1 = app(svc.state());
    let mut ids = Vec::new();
    for _ in 0..3 {
        ids.push(
            submit(
                &app1,
                &json!({"scene": column_scene(20.0), "motion": pulse(2.0)}),
            )
            .await,
        );
    }
    // Both workers must have claimed a job before the shutdown (under load the second claim
    // can lag the first by a poll interval).
    for id in &ids[..2] {
        wait_for(
            &app1,
            &format!("/v1/jobs/{id}"),
            Duration::from_secs(20),
            |j| j["status"] == "running",
        )
        .await;
    }
    assert_eq!(
        svc.shutdown(Duration::ZERO),
        2,
        "both running jobs were interrupted"
    );
    assert_eq!(
        call(&app1, get("/healthz")).await.problem(503)["type"],
        "urn:ashlar:problem:unavailable"
    );
    call(
        &app1,
        post_json("/v1/jobs", &json!({"scene": column_scene(1.0)})),
    )
    .await
    .problem(503);
    for id in &ids {
        let j = call(&app1, get(&format!("/v1/jobs/{id}"))).await.json();
        assert_eq!(j["status"], "queued", "{j}");
        assert_eq!(
            j["attempts"], 0,
            "a graceful requeue gives the attempt back"
        );
    }
    // Second server on the same data: all three complete.
    let svc2 = Service::start(cfg(2), fake_runner(FAST)).expect("restart");
    let app2 = app(svc2.state());
    for id in &ids {
        let j = wait_for(
            &app2,
            &format!("/v1/jobs/{id}"),
            Duration::from_secs(30),
            is_terminal,
        )
        .await;
        assert_eq!(j["status"], "succeeded", "{j}");
        assert_eq!(j["summary"]["completed"], true);
    }
    svc2.shutdown(Duration::ZERO);
    std::fs::remove_dir_all(dir).ok();
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn graceful_shutdown_lets_running_jobs_finish_within_the_grace() {
    let (svc, app, dir) = start(
        "routes-grace",
        1,
        Duration::from_millis(100),
        Limits::default(),
    );
    let id = submit(
        &app,
        &json!({"scene": column_scene(3.0), "motion": pulse(1.0)}),
    )
    .await; // 300 ms
    wait_for(
        &app,
        &format!("/v1/jobs/{id}"),
        Duration::from_secs(20),
        |j| j["status"] == "running",
    )
    .await;
    assert_eq!(
        svc.shutdown(Duration::from_secs(20)),
        0,
        "nothing needed interrupting"
    );
    assert_eq!(
        call(&app, get(&format!("/v1/jobs/{id}"))).await.json()["status"],
        "succeeded"
    );
    std::fs::remove_dir_all(dir).ok();
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn health_and_spec_are_served() {
    let (svc, app, dir) = start("routes-health", 2, FAST, Limits::default());
    let h = call(&app, get("/healthz")).await;
    assert_eq!(h.status, 200);
    assert_eq!(h.json()["status"], "ok");
    assert_eq!(h.json()["workers"], 2);
    let s = call(&app, get("/openapi.yaml")).await;
    assert_eq!(s.status, 200);
    assert_eq!(
        s.header("content-type").as_deref(),
        Some("application/yaml")
    );
    assert!(s.text().starts_with("openapi: 3.1"));
    svc.shutdown(Duration::ZERO);
    std::fs::remove_dir_all(dir).ok();
}
