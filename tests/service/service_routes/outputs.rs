//! A job's outputs served (summary, histories, trajectory), histories refused before the job
//! succeeds, health and the spec (see `mod.rs`).
use super::*;

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
    let p = cancel(&app, &id).await.problem(409);
    assert!(p["detail"]
        .as_str()
        .unwrap_or_default()
        .contains("succeeded"));
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
    let id = submit(&app, &column_job(30.0)).await;
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
