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
    /// Start both threads for `core`, whose store is `store`.
    pub fn start(core: Arc<Core>, store: Arc<PgStore>) -> Result<Self, String> {
        let stop = Arc::new(AtomicBool::new(false));
        let mut handles = Vec::new();
        {
            let (core, store, stop) = (core.clone(), store.clone(), stop.clone());
            handles.push(
                std::thread::Builder::new()
                    .name("ashlar-listen".into())
                    .spawn(move || listen_loop(&core, &store, &stop))
                    .map_err(|e| format!("starting the listener thread: {e}"))?,
            );
        }
        {
            let stop2 = stop.clone();
            handles.push(
                std::thread::Builder::new()
                    .name("ashlar-lease".into())
                    .spawn(move || keeper_loop(&core, &store, &stop2))
                    .map_err(|e| format!("starting the lease thread: {e}"))?,
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

fn keeper_loop(core: &Core, store: &PgStore, stop: &AtomicBool) {
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
        }
        std::thread::sleep(Duration::from_millis(100).min(p.heartbeat));
    }
}
