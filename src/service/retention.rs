//! Service: the retention policy (`ashlar serve --retain-finished FOR`), beside the routes and
//! the workers. A sweeper thread deletes finished jobs and searches (with a search's child runs)
//! and their artifacts once they ended longer ago than `FOR`, exactly as `DELETE
//! /v1/jobs/{id}` would. Opt-in and documented (docs/service.md "Retention"): deleting by a
//! stated policy is not losing a job. Queued, running and waiting jobs are never touched.
use super::store::{now_ms, DeleteOutcome};
use super::worker::{Core, ThreadStartError};
use std::sync::mpsc;
use std::sync::Arc;
use std::thread::JoinHandle;
use std::time::Duration;

/// A `--retain-finished` value that does not read (the text given).
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum RetentionError {
    #[error("{text:?}: expected a whole number and a unit, e.g. 7d, 12h, 30m, 90s")]
    Number { text: String },
    #[error("{text:?}: unknown unit {unit:?} (s, m, h or d, e.g. 7d)")]
    Unit { text: String, unit: String },
    #[error("{text:?}: the retention must be between 1 s and 10 years")]
    Range { text: String },
}

/// Parse a retention duration: a whole number with a unit, `s`, `m`, `h` or `d` (`7d`, `12h`,
/// `30m`, `90s`), from one second to ten years.
pub fn parse_duration(text: &str) -> Result<Duration, RetentionError> {
    let t = text.trim();
    let split = t.find(|c: char| !c.is_ascii_digit()).unwrap_or(t.len());
    let (n, unit) = t.split_at(split);
    let n: u64 = n.parse().map_err(|_| RetentionError::Number {
        text: text.to_string(),
    })?;
    let secs = match unit {
        "s" => Some(n),
        "m" => n.checked_mul(60),
        "h" => n.checked_mul(3600),
        "d" => n.checked_mul(86_400),
        other => {
            return Err(RetentionError::Unit {
                text: text.to_string(),
                unit: other.to_string(),
            })
        }
    };
    match secs {
        Some(s) if (1..=10 * 365 * 86_400).contains(&s) => Ok(Duration::from_secs(s)),
        _ => Err(RetentionError::Range {
            text: text.to_string(),
        }),
    }
}

/// How often the sweeper looks: a tenth of the retention, between 1 s and 10 min, so that a
/// job is gone at most 10 % (or 10 min) after its time.
pub fn sweep_interval(keep: Duration) -> Duration {
    (keep / 10).clamp(Duration::from_secs(1), Duration::from_secs(600))
}

/// Jobs deleted per store query, so that a first sweep over a large store holds no long
/// transaction.
const BATCH: usize = 200;

/// Delete every job that ended before `now - keep`; returns how many went.
pub fn sweep(core: &Core, keep: Duration) -> usize {
    let keep_ms = i64::try_from(keep.as_millis()).unwrap_or(i64::MAX);
    let cutoff = now_ms().saturating_sub(keep_ms);
    let mut deleted = 0;
    loop {
        let ids = match core.store.finished_before(cutoff, BATCH) {
            Ok(ids) => ids,
            Err(e) => {
                tracing::warn!(error = %e, "retention: listing finished jobs");
                return deleted;
            }
        };
        let n = ids.len();
        for id in ids {
            // Files first, then the record: once a swept job answers 404 its artifacts are
            // gone (the other order left a window in which a 404 job still had published
            // files). The job is finished, so only "deleted meanwhile" can refuse the delete.
            core.remove_artifacts(id);
            match core.store.delete(id) {
                Ok(DeleteOutcome::Deleted) => {
                    deleted += 1;
                }
                // Deleted meanwhile by its owner, or by another server's sweeper.
                Ok(_) => {}
                Err(e) => {
                    tracing::warn!(%id, error = %e, "retention: deleting a finished job");
                    return deleted;
                }
            }
        }
        if n < BATCH {
            return deleted;
        }
    }
}

/// The sweeper thread; stopped on shutdown.
#[derive(Debug)]
pub struct Sweeper {
    stop: mpsc::Sender<()>,
    thread: JoinHandle<()>,
}

impl Sweeper {
    pub fn start(core: Arc<Core>, keep: Duration) -> Result<Self, ThreadStartError> {
        let (stop, rx) = mpsc::channel::<()>();
        let every = sweep_interval(keep);
        let thread = std::thread::Builder::new()
            .name("ashlar-retention".into())
            .spawn(move || loop {
                let n = sweep(&core, keep);
                if n > 0 {
                    tracing::info!(
                        deleted = n,
                        retain_s = keep.as_secs(),
                        "retention: deleted finished jobs"
                    );
                }
                match rx.recv_timeout(every) {
                    Err(mpsc::RecvTimeoutError::Timeout) => {}
                    _ => return,
                }
            })
            .map_err(ThreadStartError::of("the retention sweeper"))?;
        Ok(Self { stop, thread })
    }

    pub fn stop(self) {
        let _ = self.stop.send(());
        let _ = self.thread.join();
    }
}

/// How often a process with shared `--artifacts` storage looks for cached copies of deleted
/// jobs: a job deleted through another API process (or by its sweeper) leaves this process's
/// cached copy behind, which this sweep removes. Serving never depends on it: every download
/// route loads the job from the store first, so a deleted job already answers 404 here.
pub const CACHE_SWEEP_EVERY: Duration = Duration::from_secs(60);

/// Remove the local directories (`--data/jobs/<uuid>/`) of jobs the store no longer has:
/// another process's `DELETE`, or its retention sweeper, removed the job and its published
/// files but could not reach this process's cached copy. Returns how many went. A directory
/// whose job the store cannot be asked about is kept.
pub fn sweep_cache(core: &Core) -> usize {
    let Ok(entries) = std::fs::read_dir(core.data_dir.join("jobs")) else {
        return 0;
    };
    let mut removed = 0;
    for e in entries.flatten() {
        let Some(id) = e
            .file_name()
            .to_str()
            .and_then(|n| uuid::Uuid::try_parse(n).ok())
        else {
            continue;
        };
        match core.store.get(id) {
            Ok(None) => {
                let dir = e.path();
                match std::fs::remove_dir_all(&dir) {
                    Ok(()) => removed += 1,
                    Err(err) if err.kind() == std::io::ErrorKind::NotFound => {}
                    Err(err) => {
                        tracing::warn!(dir = %dir.display(), error = %err, "removing a deleted job's cached artifacts")
                    }
                }
            }
            Ok(Some(_)) => {}
            Err(err) => {
                tracing::warn!(error = %err, "cache sweep: looking up a job");
                return removed;
            }
        }
    }
    if removed > 0 {
        core.forget_artifact_bytes();
    }
    removed
}

/// The cache sweeper thread of a process with shared `--artifacts` storage; stopped on
/// shutdown.
#[derive(Debug)]
pub struct CacheSweeper {
    stop: mpsc::Sender<()>,
    thread: JoinHandle<()>,
}

impl CacheSweeper {
    pub fn start(core: Arc<Core>, every: Duration) -> Result<Self, ThreadStartError> {
        let (stop, rx) = mpsc::channel::<()>();
        let thread = std::thread::Builder::new()
            .name("ashlar-cache-sweep".into())
            .spawn(move || loop {
                match rx.recv_timeout(every) {
                    Err(mpsc::RecvTimeoutError::Timeout) => {}
                    _ => return,
                }
                let n = sweep_cache(&core);
                if n > 0 {
                    tracing::info!(removed = n, "removed cached artifacts of deleted jobs");
                }
            })
            .map_err(ThreadStartError::of("the cache sweeper"))?;
        Ok(Self { stop, thread })
    }

    pub fn stop(self) {
        let _ = self.stop.send(());
        let _ = self.thread.join();
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn durations() {
        assert_eq!(parse_duration("7d"), Ok(Duration::from_secs(7 * 86_400)));
        assert_eq!(parse_duration("12h"), Ok(Duration::from_secs(43_200)));
        assert_eq!(parse_duration("30m"), Ok(Duration::from_secs(1800)));
        assert_eq!(parse_duration(" 90s "), Ok(Duration::from_secs(90)));
        for bad in [
            "",
            "7",
            "d",
            "7w",
            "0s",
            "-1d",
            "1.5h",
            "99999999999999999999d",
        ] {
            assert!(parse_duration(bad).is_err(), "{bad:?} accepted");
        }
        assert_eq!(
            sweep_interval(Duration::from_secs(2)),
            Duration::from_secs(1)
        );
        assert_eq!(
            sweep_interval(Duration::from_secs(7 * 86_400)),
            Duration::from_secs(600)
        );
    }
}
