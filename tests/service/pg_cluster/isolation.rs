//! Isolated workers in cluster mode, and the limits an API-only process reports for its workers
//! (see `mod.rs`).
use super::*;

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
    let (api, shared) = api_process(&url, &root);
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
    // The API's and the first worker's flags: the same but for isolation and job time.
    let flags = |workers, isolation, seconds| {
        [
            "--workers",
            workers,
            "--lease",
            "2",
            "--isolation",
            isolation,
            "--max-job-seconds",
            seconds,
        ]
    };
    let api_args = [
        &["--database", url.as_str()][..],
        &flags("0", "process", "100"),
    ]
    .concat();
    let api = Server::start(&root.join("api"), &api_args);
    let alone = get_json(&api.addr, "/v1/limits");
    assert_eq!(alone["isolation"], "process", "{alone}");
    assert_eq!(alone["max_job_seconds"], 100, "{alone}");
    assert_eq!(alone["worker_limits"], json!([]), "{alone}");
    let w = Worker::start(&url, &root.join("w0"), &flags("1", "thread", "50"));
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
