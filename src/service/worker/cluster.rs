//! Cluster mode's background threads, beside the worker pool: a process on the PostgreSQL store
//! listens for wake-ups and cancels from other processes, and keeps its leases (heartbeats)
//! and reaps expired ones. It drives the worker (`worker::Core`) from the store's signals, so it
//! sits above both: the store never imports the worker.
use super::pool::Core;
use crate::service::store::postgres::{PgStore, CHANNEL_CANCEL, CHANNEL_WORK};
use crate::service::store::JobStore;
use postgres::fallible_iterator::FallibleIterator;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::time::{Duration, Instant};
use uuid::Uuid;

/// The background threads of a process on the cluster store: the listener (wake-ups and
/// cancels from other processes) and the keeper (heartbeats and the reaper).
pub struct ClusterThreads {
    stop: Arc<AtomicBool>,
    handles: Vec<std::thread::JoinHandle<()>>,
}

impl ClusterThreads {
    /// Start both threads for `core`, whose store is `store`; `api`: this process takes
    /// submissions (`ashlar serve`). First publishes the limits this process enforces (see
    /// [`publish`]) and, in a worker, warns about each that differs from the API's.
    pub fn start(
        core: Arc<Core>,
        store: Arc<PgStore>,
        api: bool,
    ) -> Result<Self, super::ThreadStartError> {
        let roles = publish(&core, &store, api);
        if roles.contains(&"worker") && !api {
            for line in differences_from_api(&core, &store) {
                tracing::warn!("{line}");
            }
        }
        let stop = Arc::new(AtomicBool::new(false));
        let mut handles = Vec::new();
        {
            let (core, store, stop) = (core.clone(), store.clone(), stop.clone());
            handles.push(
                std::thread::Builder::new()
                    .name("ashlar-listen".into())
                    .spawn(move || listen_loop(&core, &store, &stop))
                    .map_err(super::ThreadStartError::of("the listener thread"))?,
            );
        }
        {
            let stop2 = stop.clone();
            handles.push(
                std::thread::Builder::new()
                    .name("ashlar-lease".into())
                    .spawn(move || {
                        keeper_loop(&core, &store, &stop2, &roles);
                        if let Err(e) = store.withdraw_limits() {
                            tracing::warn!(error = %e, "withdrawing this process's limits");
                        }
                    })
                    .map_err(super::ThreadStartError::of("the lease thread"))?,
            );
        }
        Ok(Self { stop, handles })
    }

    pub fn stop(self) {
        self.stop.store(true, Ordering::SeqCst);
        for h in self.handles {
            let _ = h.join();
        }
    }
}

fn listen_loop(core: &Core, store: &PgStore, stop: &AtomicBool) {
    let mut backoff = Duration::from_millis(200);
    while !stop.load(Ordering::SeqCst) {
        let mut client = match store.connect().and_then(|mut c| {
            c.batch_execute(&format!("LISTEN {CHANNEL_WORK}; LISTEN {CHANNEL_CANCEL}"))?;
            Ok(c)
        }) {
            Ok(c) => c,
            Err(e) => {
                tracing::warn!(error = %e, "LISTEN connection failed; retrying");
                std::thread::sleep(backoff);
                backoff = (backoff * 2).min(Duration::from_secs(5));
                continue;
            }
        };
        backoff = Duration::from_millis(200);
        // A wake-up may have been sent before LISTEN took effect: look once.
        core.notify_work();
        while !stop.load(Ordering::SeqCst) {
            let mut n = client.notifications();
            let mut it = n.timeout_iter(Duration::from_millis(500));
            match it.next() {
                Ok(Some(note)) => match note.channel() {
                    CHANNEL_WORK => core.notify_work(),
                    CHANNEL_CANCEL => {
                        if let Ok(id) = Uuid::parse_str(note.payload()) {
                            core.signal_cancel(id);
                        }
                    }
                    _ => {}
                },
                Ok(None) => {}
                Err(e) => {
                    tracing::warn!(error = %e, "LISTEN connection lost; reconnecting");
                    break;
                }
            }
        }
    }
}

fn keeper_loop(core: &Core, store: &PgStore, stop: &AtomicBool, roles: &[&str]) {
    let p = store.lease_params().clone();
    let mut next_beat = Instant::now() + p.heartbeat;
    let mut next_reap = Instant::now();
    while !stop.load(Ordering::SeqCst) {
        let now = Instant::now();
        if now >= next_beat {
            next_beat = now + p.heartbeat;
            let ids = core.running_ids();
            match store.heartbeat(&ids) {
                Ok(hb) => {
                    for id in hb.lost {
                        tracing::warn!(%id, "lost the lease of a running job; stopping it");
                        core.signal_lost(id);
                    }
                    for id in hb.cancel {
                        core.signal_cancel(id);
                    }
                }
                Err(e) => tracing::warn!(error = %e, "heartbeat failed"),
            }
        }
        if now >= next_reap {
            next_reap = now + p.reap_every;
            if let Err(e) = store.recover(core.params.max_attempts) {
                tracing::warn!(error = %e, "reaping expired leases failed");
            }
            let limits = job_limits(core).to_string();
            for role in roles {
                if let Err(e) = store.publish_limits(role, &limits) {
                    tracing::warn!(error = %e, "refreshing this process's published limits");
                }
            }
        }
        std::thread::sleep(Duration::from_millis(100).min(p.heartbeat));
    }
}

/// The limits a process applies to the jobs it runs and checks at submission (its `--isolation`,
/// `--job-memory-limit`, `--job-cpu-seconds`, `--max-job-seconds`, `--max-job-artifact-bytes`,
/// `--max-blocks`, `--max-record-samples`, `--max-total-steps`), as published in the store and
/// reported by `GET /v1/limits`.
pub fn job_limits(core: &Core) -> serde_json::Value {
    use super::runner::Isolation;
    let (mode, memory, cpu) = match &core.params.isolation {
        Isolation::Thread => ("thread", None, None),
        Isolation::Process(p) => ("process", Some(p.memory_limit), Some(p.cpu_seconds)),
    };
    let l = &core.limits;
    serde_json::json!({
        "isolation": mode,
        "job_memory_limit_bytes": memory,
        "job_cpu_seconds": cpu,
        "max_job_seconds": l.max_job_seconds,
        "max_job_artifact_bytes": l.max_job_artifact_bytes,
        "max_blocks": l.max_blocks,
        "max_record_samples": l.max_record_samples,
        "max_total_steps": l.max_total_steps,
    })
}

/// Publish this process's limits in the roles it has (`worker` when it runs jobs, `api` when
/// it takes submissions); returns the roles. A failure is logged: reporting must not stop a
/// process that can serve.
fn publish(core: &Core, store: &PgStore, api: bool) -> Vec<&'static str> {
    let mut roles = Vec::new();
    if core.params.workers > 0 {
        roles.push("worker");
    }
    if api {
        roles.push("api");
    }
    let limits = job_limits(core).to_string();
    for role in &roles {
        if let Err(e) = store.publish_limits(role, &limits) {
            tracing::warn!(error = %e, role, "publishing this process's limits");
        }
    }
    roles
}

/// One line per limit in which this worker differs from a live API process's published flags
/// (a job the API accepts could then be refused or stopped here, or the other way round).
fn differences_from_api(core: &Core, store: &PgStore) -> Vec<String> {
    let mine = job_limits(core);
    let apis = match store.published_limits("api") {
        Ok(a) => a,
        Err(e) => {
            tracing::warn!(error = %e, "reading the API processes' limits");
            return Vec::new();
        }
    };
    let flags = [
        ("max_blocks", "--max-blocks"),
        ("max_record_samples", "--max-record-samples"),
        ("max_total_steps", "--max-total-steps"),
        ("max_job_seconds", "--max-job-seconds"),
        ("max_job_artifact_bytes", "--max-job-artifact-bytes"),
    ];
    let mut out = Vec::new();
    for (process, text) in apis {
        let Ok(theirs) = serde_json::from_str::<serde_json::Value>(&text) else {
            continue;
        };
        for (key, flag) in flags {
            if theirs.get(key) != mine.get(key) {
                out.push(format!(
                    "this worker's {flag} {} differs from the API process {process}'s {}: give every process the same value (GET /v1/limits reports the workers')",
                    mine.get(key).unwrap_or(&serde_json::Value::Null),
                    theirs.get(key).unwrap_or(&serde_json::Value::Null),
                ));
            }
        }
    }
    out
}
