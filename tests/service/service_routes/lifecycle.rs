//! A job's life through the routes: cancel (running, queued), progress as server-sent events,
//! failures and panics, PGA searches, shutdown and restart (see `mod.rs`).
use super::*;

/// Where the cancel tests start: one worker at 100 ms of wall time per simulated second (frames
/// every 0.01 s: a frame takes 1 ms), and a column job of `duration` s submitted and seen
/// running. Returns the service, its router and directory, and the job's id.
async fn one_running_job(
    tag: &str,
    duration: f64,
) -> (Service, axum::Router, std::path::PathBuf, String) {
    let (svc, app, dir) = start(tag, 1, Duration::from_millis(100), Limits::default());
    let id = submit(&app, &column_job(duration)).await;
    let running = wait_for(
        &app,
        &format!("/v1/jobs/{id}"),
        Duration::from_secs(20),
        |j| j["status"] == "running",
    )
    .await;
    assert_eq!(running["status"], "running");
    (svc, app, dir, id)
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn cancelling_a_running_job_stops_it_within_one_frame() {
    let (svc, app, dir, id) = one_running_job("routes-cancel", 60.0).await;
    let uri = format!("/v1/jobs/{id}");
    // Progress reaches the store while it runs (written at most every 250 ms).
    let j = wait_for(&app, &uri, Duration::from_secs(5), |j| {
        j["progress"].as_f64().unwrap_or(0.0) > 0.0
    })
    .await;
    assert!(j["progress"].as_f64().unwrap_or(1.0) < 1.0);
    let t0 = Instant::now();
    let r = cancel(&app, &id).await;
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
    // The one worker is busy with `first`: `second` waits in the queue.
    let (svc, app, dir, first) = one_running_job("routes-cancel-queued", 10.0).await;
    let second = submit(&app, &column_job(1.0)).await;
    let r = cancel(&app, &second).await;
    assert_eq!(r.status, 200, "{}", r.text());
    assert_eq!(r.json()["status"], "cancelled");
    cancel(&app, &first).await;
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
    let id = submit(&app, &column_job(5.0)).await;
    let r = call(&app, get(&format!("/v1/jobs/{id}/events"))).await;
    assert_eq!(r.status, 200);
    assert_eq!(
        r.header("content-type").as_deref(),
        Some("text/event-stream")
    );
    let text = r.text();
    let events = sse_events(&text);
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
    // Job `id` once it has ended, and its error message.
    let ended = |id: String| {
        let app = app.clone();
        async move {
            let uri = format!("/v1/jobs/{id}");
            wait_for(&app, &uri, Duration::from_secs(20), is_terminal).await
        }
    };
    let error = |j: &Value| j["error"].as_str().unwrap_or_default().to_string();
    let j = ended(failing.clone()).await;
    assert_eq!(j["status"], "failed");
    assert!(error(&j).contains("fake failure"), "{j}");
    let j = ended(panicking).await;
    assert_eq!(j["status"], "failed");
    assert!(error(&j).contains("internal error"), "{j}");
    assert!(
        !error(&j).contains("fake panic"),
        "panic text stays in the log"
    );
    // The single worker survived both.
    let j = ended(fine).await;
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
    let id = submit(&app, &column_job(3.0)).await; // 300 ms
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
