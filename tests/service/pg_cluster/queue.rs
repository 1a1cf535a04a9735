//! The queue across processes: many jobs over workers with one killed, leases and the reaper,
//! cancellation and progress across processes, NOTIFY wake-ups (see `mod.rs`).
use super::*;

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
