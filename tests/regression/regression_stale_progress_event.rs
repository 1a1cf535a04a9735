//! What broke: a job's event stream sent progress backwards. Workers publish every update to
//! the in-memory hub but write it to the store at most every `progress_write_interval`; when
//! the hub was silent for one poll (a slow batch under load) the stream re-read the store and
//! sent its older value: 0.995 → 0.9475 → 1.0, seen in
//! `service_site::a_site_analysis_runs_as_a_job_and_matches_the_library` at load ~10. The
//! stream now never lowers the progress it has sent (`service::events::never_back`).
use ashlar::service::events::{job_events, EventParams, Hub, JobEvent};
use ashlar::service::store::{Finish, JobKind, JobStatus, JobStore, NewJob};
use ashlar::service::SqliteStore;
use futures_util::StreamExt;
use std::sync::Arc;
use std::time::Duration;

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_stale_store_read_does_not_move_progress_back() {
    let dir = std::env::temp_dir().join(format!("ashlar-stale-progress-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("temp dir");
    let store = Arc::new(SqliteStore::open(&dir.join("jobs.sqlite")).expect("open sqlite"));
    let job = NewJob {
        id: uuid::Uuid::new_v4(),
        kind: JobKind::Run,
        request: serde_json::json!({}),
        motion: serde_json::json!({}),
        owner: None,
    };
    store.insert(&job).expect("insert");
    store.claim().expect("claim").expect("the job");
    // The store's last write: older than what the hub will carry.
    store.set_progress(job.id, 0.4).expect("progress");

    let hub = Hub::default();
    let (_shutdown_tx, shutdown) = tokio::sync::watch::channel(false);
    let running = |progress| JobEvent {
        status: JobStatus::Running,
        progress,
    };
    // A short poll, so the silence below makes the stream read the store.
    let params = EventParams {
        poll: Duration::from_millis(20),
    };
    let dyn_store: Arc<dyn JobStore> = store.clone();
    let events = job_events(job.id, running(0.4), dyn_store, &hub, shutdown, params);
    let collect = tokio::spawn(events.collect::<Vec<JobEvent>>());

    tokio::time::sleep(Duration::from_millis(50)).await;
    hub.publish(job.id, running(0.9));
    // Silence for several polls: the stream reads the store's 0.4.
    tokio::time::sleep(Duration::from_millis(200)).await;
    store
        .finish(job.id, &Finish::Cancelled(None))
        .expect("finish");
    let got = tokio::time::timeout(Duration::from_secs(10), collect)
        .await
        .expect("the stream ends after the terminal status")
        .expect("join");
    std::fs::remove_dir_all(&dir).ok();

    let progress: Vec<f64> = got.iter().map(|e| e.progress).collect();
    assert!(
        progress.contains(&0.9),
        "the hub's update was sent: {got:?}"
    );
    assert!(
        progress.windows(2).all(|w| w[0] <= w[1]),
        "progress never goes back: {got:?}"
    );
    assert!(
        got.last().is_some_and(|e| e.status.is_terminal()),
        "the last event is terminal: {got:?}"
    );
}
