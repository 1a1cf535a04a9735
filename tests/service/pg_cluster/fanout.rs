//! Fanned-out PGA searches (docs/cluster.md): a search's runs are child jobs that every worker
//! shares (see `mod.rs`).
use super::*;

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
