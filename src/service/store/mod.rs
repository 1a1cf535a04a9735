//! Service: the durable job store, the service's memory. Routes write submissions here, workers
//! claim jobs from here, and a restarted server resumes from here. [`JobStore`] is the small
//! interface the rest of the service sees; [`SqliteStore`] (`sqlite.rs`) is the embedded
//! default (one file under `--data`), [`postgres::PgStore`] (`postgres.rs`, TLS in `tls.rs`)
//! the cluster store for many processes. Both apply the one job state machine of
//! [`super::jobs`] (which statuses an operation applies to, how a waiting search settles, what
//! recovery does) in their own SQL, and each keeps its schema as numbered migrations under
//! `src/service/migrations/{sqlite,postgres}/`. The store imports neither HTTP nor the worker.
pub mod postgres;
mod sqlite;
pub mod tls;

pub use super::jobs::{CancelOutcome, JobStatus};
pub use sqlite::SqliteStore;

use super::jobs::{self, Attempts, Event};
use serde::Serialize;
use std::time::{SystemTime, UNIX_EPOCH};
use uuid::Uuid;

/// What a job computes.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum JobKind {
    /// One run of a scene under a motion (`POST /v1/jobs`).
    Run,
    /// A PGA threshold search (`POST /v1/pga-searches`).
    PgaSearch,
    /// Several observations at one site over a set of records (`POST /v1/site-analyses`).
    SiteAnalysis,
    /// One run of a fanned-out PGA search at one amplitude: a child job (`parent` = the
    /// search), never submitted over HTTP nor listed by `GET /v1/jobs`.
    PgaRun,
}

impl JobKind {
    pub fn as_str(self) -> &'static str {
        match self {
            JobKind::Run => "run",
            JobKind::PgaSearch => "pga_search",
            JobKind::PgaRun => "pga_run",
            JobKind::SiteAnalysis => "site_analysis",
        }
    }
    pub(crate) fn parse(s: &str) -> Result<Self, StoreError> {
        match s {
            "run" => Ok(JobKind::Run),
            "pga_search" => Ok(JobKind::PgaSearch),
            "pga_run" => Ok(JobKind::PgaRun),
            "site_analysis" => Ok(JobKind::SiteAnalysis),
            other => Err(StoreError::corrupt("job kind", format!("{other:?}"))),
        }
    }
}

impl JobStatus {
    pub(crate) fn parse(s: &str) -> Result<Self, StoreError> {
        Ok(match s {
            "queued" => JobStatus::Queued,
            "running" => JobStatus::Running,
            "succeeded" => JobStatus::Succeeded,
            "failed" => JobStatus::Failed,
            "cancelled" => JobStatus::Cancelled,
            "waiting" => JobStatus::Waiting,
            other => return Err(StoreError::corrupt("job status", format!("{other:?}"))),
        })
    }
}

/// A job as stored.
#[derive(Debug, Clone, PartialEq)]
pub struct JobRecord {
    pub id: Uuid,
    pub kind: JobKind,
    pub status: JobStatus,
    /// The validated request body, as submitted (re-parsed by the worker).
    pub request: serde_json::Value,
    /// Intensity summary of the motion, computed at submission (`{"pga": …}`).
    pub motion: serde_json::Value,
    /// Simulated time / duration, 0..1.
    pub progress: f64,
    /// `summary.json` of a run or `result.json` of a PGA search, once done, as the JSON text
    /// the runner's value serialised to. Kept as text and served verbatim: re-parsing it with
    /// serde_json's default float parser could move a number by one ULP.
    pub result: Option<String>,
    /// Why the job failed (a message for the user; internals are logged, not stored here).
    pub error: Option<String>,
    pub cancel_requested: bool,
    /// How many times a worker has started the job.
    pub attempts: u32,
    /// Unix milliseconds.
    pub created_ms: i64,
    pub started_ms: Option<i64>,
    pub finished_ms: Option<i64>,
    /// The search a child run belongs to (`None` for jobs submitted over HTTP).
    pub parent: Option<Uuid>,
    /// The owner id of the token that submitted it ([`super::auth::owner_id`]); `None` when
    /// the server ran without tokens.
    pub owner: Option<String>,
}

/// A new job to enqueue.
#[derive(Debug, Clone)]
pub struct NewJob {
    pub id: Uuid,
    pub kind: JobKind,
    pub request: serde_json::Value,
    pub motion: serde_json::Value,
    /// See [`JobRecord::owner`].
    pub owner: Option<String>,
}

/// Why a bounded insert refused a job: the number of jobs already waiting.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum QueueFull {
    /// The whole server's queue (`--max-queued-jobs`) is full.
    Server(u64),
    /// The owner's own quota of queued jobs of this kind is used up.
    Owner(u64),
}

/// How a claimed job ended.
#[derive(Debug, Clone, PartialEq)]
pub enum Finish {
    Succeeded(serde_json::Value),
    Failed(String),
    /// Stopped by the user; `result` holds the partial summary where the runner gave one.
    Cancelled(Option<serde_json::Value>),
}

impl Finish {
    /// The state machine's end ([`super::jobs::End`]).
    pub fn end(&self) -> super::jobs::End {
        match self {
            Finish::Succeeded(_) => super::jobs::End::Succeeded,
            Finish::Failed(_) => super::jobs::End::Failed,
            Finish::Cancelled(_) => super::jobs::End::Cancelled,
        }
    }

    /// The columns a finish writes, in both stores: (result JSON text, error, progress; `None`
    /// keeps the progress reached).
    pub(crate) fn columns(&self) -> (Option<String>, Option<String>, Option<f64>) {
        match self {
            Finish::Succeeded(v) => (Some(v.to_string()), None, Some(1.0)),
            Finish::Failed(e) => (None, Some(e.clone()), None),
            Finish::Cancelled(v) => (v.as_ref().map(|v| v.to_string()), None, None),
        }
    }
}

/// What `delete` did.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum DeleteOutcome {
    /// The job (and a search's child runs) is gone from the store.
    Deleted,
    /// The job has not finished (queued, running or waiting): cancel it first.
    NotFinished(JobStatus),
    NotFound,
}

/// Queue depth by status, for `/healthz` and the load test.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize)]
pub struct Counts {
    pub queued: u64,
    pub running: u64,
    pub succeeded: u64,
    pub failed: u64,
    pub cancelled: u64,
    /// Searches waiting for their child runs.
    pub waiting: u64,
}

impl Counts {
    /// Record that `n` jobs are in `status` (one row of a `GROUP BY status`).
    pub(crate) fn set(&mut self, status: JobStatus, n: u64) {
        let field = match status {
            JobStatus::Queued => &mut self.queued,
            JobStatus::Running => &mut self.running,
            JobStatus::Succeeded => &mut self.succeeded,
            JobStatus::Failed => &mut self.failed,
            JobStatus::Cancelled => &mut self.cancelled,
            JobStatus::Waiting => &mut self.waiting,
        };
        *field = n;
    }
}

/// Which database a [`StoreError`] came from.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Backend {
    Sqlite,
    Postgres,
}

impl std::fmt::Display for Backend {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            Backend::Sqlite => "sqlite",
            Backend::Postgres => "postgres",
        })
    }
}

/// The `SET` assignments of `event` in `database`'s SQL, from the transition table
/// ([`super::jobs::effect`]): the status it writes and its attempts arithmetic, e.g.
/// `status = 'waiting', attempts = MAX(attempts - 1, 0)`. `to` picks the target of an event
/// with two (a cancel: see [`super::jobs::guard_to`]). Every status-changing `UPDATE` of both
/// stores starts its `SET` with this, so neither writes a status or attempts count by hand.
pub(crate) fn set_sql(database: Backend, event: &Event, to: Option<JobStatus>) -> String {
    let Some(t) = jobs::effect(event, to) else {
        // No transition (a programming error the jobs tests rule out): write nothing new.
        return "status = status".into();
    };
    let status = format!("status = '{}'", t.to.as_str());
    match (t.attempts, database) {
        (Attempts::Keep, _) => status,
        (Attempts::Increment, _) => format!("{status}, attempts = attempts + 1"),
        (Attempts::Decrement, Backend::Sqlite) => {
            format!("{status}, attempts = MAX(attempts - 1, 0)")
        }
        (Attempts::Decrement, Backend::Postgres) => {
            format!("{status}, attempts = GREATEST(attempts - 1, 0)")
        }
    }
}

/// A store failure, by cause, over both databases. Logged in full; the HTTP edge
/// (`ApiError::store`) gives clients a problem per cause without internals: `Busy` is
/// `unavailable` (503, retry), every other cause `internal` (500).
#[derive(Debug, thiserror::Error)]
pub enum StoreError {
    /// The database is busy or unreachable (SQLite locked past its busy timeout; PostgreSQL's
    /// connection lost or refused): a retry may succeed.
    #[error("job store: {database}: busy or unreachable: {detail}")]
    Busy { database: Backend, detail: String },
    /// Any other failure the database reported (I/O, a constraint, a server error).
    #[error("job store: {database}: {detail}")]
    Database { database: Backend, detail: String },
    /// The database URL or its TLS settings (`--database postgres://…`) are not usable.
    #[error("job store: {0}")]
    Config(#[from] tls::PgUrlError),
    /// The store file could not be opened.
    #[error("job store: {path}: {detail}")]
    Open { path: String, detail: String },
    /// A stored value this ashlar cannot read (`what`: a column, an id, a kind, a status).
    #[error("job store: corrupt {what}: {detail}")]
    Corrupt { what: String, detail: String },
    /// The database's schema (version `found`) is newer than this ashlar's (`known`).
    #[error(
        "job store: the database schema is version {found}, newer than this ashlar understands ({known}); upgrade ashlar"
    )]
    SchemaNewer { found: i32, known: i32 },
    /// A numbered migration (`version`) failed in `database` (`detail`: the database's message).
    #[error("job store: schema migration {version}: {database}: {detail}")]
    Migration {
        version: i32,
        database: Backend,
        detail: String,
    },
    /// This store does not implement the operation (`what`, e.g. "delete jobs").
    #[error("job store: this job store cannot {0}")]
    Unsupported(&'static str),
    /// A thread panicked holding the store's connection (`which`: "reader" or "writer").
    #[error("job store: {0} lock poisoned")]
    Poisoned(&'static str),
}

impl StoreError {
    /// A stored value that does not parse.
    pub(crate) fn corrupt(what: impl Into<String>, detail: impl std::fmt::Display) -> Self {
        StoreError::Corrupt {
            what: what.into(),
            detail: detail.to_string(),
        }
    }
}

/// The durable queue. Every method is one transaction; implementations must make `claim`
/// atomic across processes (two workers never get the same job).
pub trait JobStore: Send + Sync {
    fn insert(&self, job: &NewJob) -> Result<(), StoreError>;
    /// Insert unless `max_queued` submitted jobs (not child runs) are already queued, deciding
    /// in the insert's own transaction so that concurrent submissions cannot all slip under
    /// the limit. `Ok(None)`: inserted; `Ok(Some(n))`: refused, `n` jobs are waiting.
    fn insert_bounded(&self, job: &NewJob, max_queued: u64) -> Result<Option<u64>, StoreError> {
        Ok(self
            .insert_quota(job, max_queued, u64::MAX)?
            .map(|(QueueFull::Server(n) | QueueFull::Owner(n))| n))
    }
    /// [`JobStore::insert_bounded`], and also unless the job's owner (when it has one) already
    /// has `max_owner` jobs of the job's kind queued: both counts and the insert in one
    /// transaction.
    fn insert_quota(
        &self,
        job: &NewJob,
        max_queued: u64,
        max_owner: u64,
    ) -> Result<Option<QueueFull>, StoreError>;
    /// Top-level jobs (searches with their child runs) that ended before `cutoff_ms` (Unix
    /// ms), oldest first, at most `limit`: what the retention sweeper deletes.
    fn finished_before(&self, cutoff_ms: i64, limit: usize) -> Result<Vec<Uuid>, StoreError> {
        let _ = (cutoff_ms, limit);
        Ok(Vec::new())
    }
    /// Remove a finished job (and a search's child runs) from the store. The caller removes
    /// its artifacts.
    fn delete(&self, id: Uuid) -> Result<DeleteOutcome, StoreError> {
        let _ = id;
        Err(StoreError::Unsupported("delete jobs"))
    }
    fn get(&self, id: Uuid) -> Result<Option<JobRecord>, StoreError>;
    /// Atomically move the oldest queued job to `running` (attempts + 1) and return it.
    fn claim(&self) -> Result<Option<JobRecord>, StoreError>;
    /// Record progress of a running job (0..1).
    fn set_progress(&self, id: Uuid, progress: f64) -> Result<(), StoreError>;
    /// Move a running job to a terminal status.
    fn finish(&self, id: Uuid, finish: &Finish) -> Result<(), StoreError>;
    /// Put a running job back in the queue (graceful shutdown); `refund` gives back the attempt.
    fn requeue(&self, id: Uuid, refund: bool) -> Result<(), StoreError>;
    fn request_cancel(&self, id: Uuid) -> Result<CancelOutcome, StoreError>;
    /// Start-up recovery: jobs left `running` by a server that died go back to `queued`, unless
    /// they have already been started `max_attempts` times (then they fail: a job that keeps
    /// killing the server must not keep killing it; a job whose cancel was requested ends
    /// cancelled): each by [`super::jobs::recover`]. Returns (requeued, ended: failed or
    /// cancelled).
    fn recover(&self, max_attempts: u32) -> Result<(usize, usize), StoreError>;
    fn counts(&self) -> Result<Counts, StoreError>;
    /// The limits published by the live processes of a cluster in `role` (`api` or `worker`):
    /// (process name, JSON object as text). None for the embedded store, whose one process
    /// runs every job itself.
    fn published_limits(&self, role: &str) -> Result<Vec<(String, String)>, StoreError> {
        let _ = role;
        Ok(Vec::new())
    }
    /// The most recent jobs, newest first, at most `limit`, optionally of one kind, for the
    /// web page's queue (`GET /v1/jobs`). Their `request` is left out (`Null`): a record
    /// embedded in it can be megabytes, and a listing never needs it.
    fn list_recent(
        &self,
        limit: usize,
        kind: Option<JobKind>,
    ) -> Result<Vec<JobRecord>, StoreError> {
        self.list_owned(limit, kind, None)
    }
    /// [`JobStore::list_recent`] of one owner's jobs (`None`: everyone's).
    fn list_owned(
        &self,
        limit: usize,
        kind: Option<JobKind>,
        owner: Option<&str>,
    ) -> Result<Vec<JobRecord>, StoreError> {
        let _ = (limit, kind, owner);
        Err(StoreError::Unsupported("list jobs"))
    }
    /// Fan a running job out, in one transaction: insert `children` (queued, `parent` = `id`)
    /// and park the job in `waiting`, giving its claim back (attempts − 1: waiting is not a
    /// crash) and setting its progress. When no child of the job is left unfinished (they all
    /// ended before this call), the job goes straight back to the queue instead. The end of
    /// the last child requeues a waiting job (in the child's `finish` transaction); a child
    /// that fails fails it with the child's error; cancelling it cancels its children.
    /// Returns false, changing nothing, when `id` is not running (under this process's claim).
    fn fan_out(&self, id: Uuid, children: &[NewJob], progress: f64) -> Result<bool, StoreError> {
        let _ = (id, children, progress);
        Err(StoreError::Unsupported("fan jobs out"))
    }
    /// Every child job of `id`, oldest first, with requests and results.
    fn children(&self, id: Uuid) -> Result<Vec<JobRecord>, StoreError> {
        let _ = id;
        Ok(Vec::new())
    }
}

/// Unix time in milliseconds.
pub fn now_ms() -> i64 {
    SystemTime::now()
        .duration_since(UNIX_EPOCH)
        .map(|d| d.as_millis() as i64)
        .unwrap_or(0)
}

/// RFC 3339 UTC timestamp (`2026-11-22T12:00:00.000Z`) from Unix milliseconds.
pub fn rfc3339(ms: i64) -> String {
    let secs = ms.div_euclid(1000);
    let milli = ms.rem_euclid(1000);
    let days = secs.div_euclid(86_400);
    let sod = secs.rem_euclid(86_400);
    // Civil date from days since 1970-01-01 (H. Hinnant's algorithm).
    let z = days + 719_468;
    let era = z.div_euclid(146_097);
    let doe = z.rem_euclid(146_097);
    let yoe = (doe - doe / 1460 + doe / 36_524 - doe / 146_096) / 365;
    let doy = doe - (365 * yoe + yoe / 4 - yoe / 100);
    let mp = (5 * doy + 2) / 153;
    let d = doy - (153 * mp + 2) / 5 + 1;
    let m = if mp < 10 { mp + 3 } else { mp - 9 };
    let y = yoe + era * 400 + i64::from(m <= 2);
    format!(
        "{y:04}-{m:02}-{d:02}T{:02}:{:02}:{:02}.{milli:03}Z",
        sod / 3600,
        sod % 3600 / 60,
        sod % 60
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn set_clauses_are_the_tables_in_both_dialects() {
        use jobs::{End, Recovery, Settlement};
        let both = |e: &Event, to| {
            (
                set_sql(Backend::Sqlite, e, to),
                set_sql(Backend::Postgres, e, to),
            )
        };
        let same = |sql: &str| (sql.to_string(), sql.to_string());
        assert_eq!(
            both(&Event::Claim, None),
            same("status = 'running', attempts = attempts + 1")
        );
        for e in [Event::FanOut, Event::Requeue { refund: true }] {
            let to = jobs::effect(&e, None).map(|t| t.to.as_str()).unwrap_or("?");
            assert_eq!(
                both(&e, None),
                (
                    format!("status = '{to}', attempts = MAX(attempts - 1, 0)"),
                    format!("status = '{to}', attempts = GREATEST(attempts - 1, 0)")
                ),
                "{e:?}"
            );
        }
        for (e, to) in [
            (Event::Requeue { refund: false }, "queued"),
            (Event::Finish(End::Cancelled), "cancelled"),
            (Event::Settle(Settlement::Requeue), "queued"),
            (Event::Settle(Settlement::Fail("x".into())), "failed"),
            (Event::Recover(Recovery::Requeue), "queued"),
            (Event::Recover(Recovery::Fail("x".into())), "failed"),
        ] {
            assert_eq!(both(&e, None), same(&format!("status = '{to}'")), "{e:?}");
        }
        assert_eq!(
            both(&Event::Cancel, Some(JobStatus::Cancelled)),
            same("status = 'cancelled'")
        );
    }

    /// No store writes a status or an attempts count by hand: each comes from [`set_sql`].
    #[test]
    fn no_store_writes_a_status_or_attempts_by_hand() {
        for (file, text) in [
            ("sqlite.rs", include_str!("sqlite.rs")),
            ("postgres.rs", include_str!("postgres.rs")),
        ] {
            for hand in [
                "SET status",
                " status = ?",
                " status = $",
                "attempts + 1",
                "attempts - 1",
            ] {
                assert!(!text.contains(hand), "{file} writes `{hand}` by hand");
            }
        }
    }

    #[test]
    fn rfc3339_matches_known_instants() {
        // Reference values from `date -u -d @SECONDS`.
        assert_eq!(rfc3339(0), "1970-01-01T00:00:00.000Z");
        assert_eq!(rfc3339(951_782_400_123), "2000-02-29T00:00:00.123Z");
        assert_eq!(rfc3339(1_795_349_400_000), "2026-11-22T12:10:00.000Z");
    }
}
