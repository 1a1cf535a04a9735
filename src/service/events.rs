//! Progress fan-out: workers publish each job's status and progress into an in-memory hub; the
//! `/events` routes turn it into server-sent events. The store stays the source of truth: a
//! stream re-reads it every [`EventParams::poll`] so it also follows jobs run by another process
//! and can never miss a final status.
use super::store::{JobStatus, JobStore};
use axum::response::sse::Event;
use futures_util::Stream;
use serde::Serialize;
use std::collections::HashMap;
use std::sync::{Arc, Mutex};
use std::time::Duration;
use tokio::sync::watch;
use uuid::Uuid;

/// One update of a job.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct JobEvent {
    pub status: JobStatus,
    /// Simulated time / duration, 0..1.
    pub progress: f64,
}

/// Latest event per job with subscribers or a running worker.
#[derive(Default)]
pub struct Hub {
    senders: Mutex<HashMap<Uuid, watch::Sender<JobEvent>>>,
}

impl Hub {
    /// Publish an update; a terminal status also drops the job's channel (subscribers see the
    /// value, then the end of the channel).
    pub fn publish(&self, id: Uuid, ev: JobEvent) {
        let Ok(mut m) = self.senders.lock() else {
            return;
        };
        if let Some(tx) = m.get(&id) {
            tx.send_replace(ev);
        }
        if ev.status.is_terminal() {
            m.remove(&id);
        }
    }

    /// Follow a job, starting from `current` (read from the store).
    pub fn subscribe(&self, id: Uuid, current: JobEvent) -> Option<watch::Receiver<JobEvent>> {
        let mut m = self.senders.lock().ok()?;
        // Forget channels nobody listens to any more (their jobs publish into nothing until a
        // new subscriber comes).
        m.retain(|_, tx| tx.receiver_count() > 0);
        Some(
            m.entry(id)
                .or_insert_with(|| watch::channel(current).0)
                .subscribe(),
        )
    }
}

/// Tuning of event streams.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct EventParams {
    /// How often a stream re-reads the store when the hub is silent (1 s: a final status that
    /// the hub missed, e.g. from another process, shows within a second).
    pub poll: Duration,
}

impl Default for EventParams {
    fn default() -> Self {
        Self {
            poll: Duration::from_secs(1),
        }
    }
}

struct StreamState {
    id: Uuid,
    store: Arc<dyn JobStore>,
    rx: Option<watch::Receiver<JobEvent>>,
    shutdown: watch::Receiver<bool>,
    last: Option<JobEvent>,
    pending: JobEvent,
    done: bool,
    params: EventParams,
}

/// `next` with its progress raised to the last one sent (a stale store read, or a worker's
/// late report, must not move a client's progress bar back).
fn never_back(last: Option<JobEvent>, next: JobEvent) -> JobEvent {
    match last {
        Some(l) if l.progress > next.progress => JobEvent {
            progress: l.progress,
            ..next
        },
        _ => next,
    }
}

fn sse_event(id: Uuid, ev: JobEvent) -> Event {
    let name = if ev.status.is_terminal() {
        "end"
    } else {
        "progress"
    };
    let data = serde_json::json!({"id": id, "status": ev.status, "progress": ev.progress});
    Event::default().event(name).data(data.to_string())
}

/// Server-sent events for one job: a `progress` event whenever status or progress changes
/// (starting with the current state), and a final `end` event with the terminal status, after
/// which the stream closes. It also closes when the server shuts down.
/// `events` is [`job_events`] of job `id`.
pub fn job_stream(
    id: Uuid,
    events: impl Stream<Item = JobEvent>,
) -> impl Stream<Item = Result<Event, std::convert::Infallible>> {
    use futures_util::StreamExt;
    events.map(move |ev| Ok(sse_event(id, ev)))
}

/// The updates [`job_stream`] sends, as plain events: each differs from the one before, the
/// last is terminal (unless the server shuts down), and progress never goes back. The hub
/// carries every update while the store is written at most every `progress_write_interval`,
/// so a store read after a silence can be older than the last hub value; it may change the
/// status but not lower the progress already sent.
pub fn job_events(
    id: Uuid,
    current: JobEvent,
    store: Arc<dyn JobStore>,
    hub: &Hub,
    shutdown: watch::Receiver<bool>,
    params: EventParams,
) -> impl Stream<Item = JobEvent> {
    let rx = if current.status.is_terminal() {
        None
    } else {
        hub.subscribe(id, current)
    };
    let state = StreamState {
        id,
        store,
        rx,
        shutdown,
        last: None,
        pending: current,
        done: false,
        params,
    };
    futures_util::stream::unfold(state, |mut s| async move {
        loop {
            if s.done {
                return None;
            }
            let ev = never_back(s.last, s.pending);
            if s.last != Some(ev) {
                s.last = Some(ev);
                s.done = ev.status.is_terminal();
                return Some((ev, s));
            }
            if *s.shutdown.borrow() {
                return None;
            }
            let changed = match s.rx.as_mut() {
                Some(rx) => tokio::select! {
                    r = tokio::time::timeout(s.params.poll, rx.changed()) => match r {
                        Ok(Ok(())) => Some(*rx.borrow_and_update()),
                        Ok(Err(_)) => { s.rx = None; None }
                        Err(_) => None,
                    },
                    _ = s.shutdown.changed() => None,
                },
                None => {
                    tokio::select! {
                        _ = tokio::time::sleep(s.params.poll) => {},
                        _ = s.shutdown.changed() => {},
                    }
                    None
                }
            };
            match changed {
                Some(ev) => s.pending = ev,
                None => {
                    // Silence, a closed channel or shutdown: ask the store.
                    let store = s.store.clone();
                    let id = s.id;
                    let got = tokio::task::spawn_blocking(move || store.get(id)).await;
                    match got {
                        Ok(Ok(Some(j))) => {
                            s.pending = JobEvent {
                                status: j.status,
                                progress: j.progress,
                            }
                        }
                        Ok(Ok(None)) => return None,
                        Ok(Err(e)) => {
                            tracing::warn!(error = %e, "event stream: store read failed");
                        }
                        Err(e) => {
                            tracing::warn!(error = %e, "event stream: store read task failed");
                        }
                    }
                }
            }
        }
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn hub_delivers_latest_and_closes_on_terminal() {
        let hub = Hub::default();
        let id = Uuid::new_v4();
        let mut rx = hub
            .subscribe(
                id,
                JobEvent {
                    status: JobStatus::Queued,
                    progress: 0.0,
                },
            )
            .expect("rx");
        hub.publish(
            id,
            JobEvent {
                status: JobStatus::Running,
                progress: 0.25,
            },
        );
        hub.publish(
            id,
            JobEvent {
                status: JobStatus::Running,
                progress: 0.5,
            },
        );
        assert!(rx.has_changed().expect("open"));
        assert_eq!(
            rx.borrow_and_update().progress,
            0.5,
            "a slow subscriber gets the latest value"
        );
        hub.publish(
            id,
            JobEvent {
                status: JobStatus::Succeeded,
                progress: 1.0,
            },
        );
        assert_eq!(rx.borrow_and_update().status, JobStatus::Succeeded);
        assert!(
            rx.has_changed().is_err(),
            "the channel closes after a terminal status"
        );
    }
}
