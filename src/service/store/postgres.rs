//! The cluster job store: [`JobStore`] on PostgreSQL, for any number of API and worker
//! processes on any number of machines (`ashlar serve|worker --database postgres://…`).
//! Sits under `store` beside `sqlite` (the embedded store); applies the state machine of
//! [`crate::service::jobs`]. Its background threads (listener, keeper) live in
//! `service::cluster`, above the worker: the store does not know the worker.
//!
//! - **Claim**: `UPDATE … FROM (SELECT … FOR UPDATE SKIP LOCKED LIMIT 1)`: concurrent claimers
//!   skip each other's locked rows, so two workers never get the same job and never wait.
//! - **Lease**: a claim stamps the job with a fresh token, the claimer's name and an expiry
//!   (database clock, so machines' clocks need not agree). The owner's heartbeat extends it;
//!   progress, finish and requeue only apply while the token still matches, so a worker that
//!   lost its lease (paused, partitioned) can never overwrite the result of the worker that
//!   reran the job: each result is recorded exactly once.
//! - **Reaper**: any process requeues running jobs whose lease expired (their worker died),
//!   failing those already started `max_attempts` times.
//! - **Wake-up and cancel**: `NOTIFY ashlar_work` on every new or requeued job wakes idle
//!   workers at once; `NOTIFY ashlar_cancel, '<id>'` reaches the process running the job.
//! - **Migrations**: `src/service/migrations/postgres/NNNN_*.sql`, applied in order under an advisory lock, the
//!   version kept in `ashlar_schema_version`.
//!
//! Over 600 lines: one `JobStore` implementation plus its leases, heartbeats, attempt log and
//! migrations, which share its connection pool and SQL (its tests are `tests/service/pg_*.rs`).
//!
//! The sync `postgres` client fits the sync [`JobStore`] trait, which is called from worker
//! threads and `spawn_blocking` (never from the async runtime's own threads).
use super::{
    now_ms, set_sql, Backend, CancelOutcome, Counts, DeleteOutcome, Finish, JobKind, JobRecord,
    JobStatus, JobStore, NewJob, QueueFull, StoreError,
};
use crate::service::jobs::{self, Event};

/// The `SET` of `event` in PostgreSQL's SQL ([`super::set_sql`]).
fn set(event: &Event, to: Option<JobStatus>) -> String {
    set_sql(Backend::Postgres, event, to)
}
use postgres::{Client, Row};
use std::collections::HashMap;
use std::sync::Mutex;
use std::time::Duration;
use uuid::Uuid;

/// Schema migrations, in order; migration k brings the schema to version k.
pub const MIGRATIONS: &[(i32, &str)] = &[
    (1, include_str!("../migrations/postgres/0001_jobs.sql")),
    (2, include_str!("../migrations/postgres/0002_leases.sql")),
    (3, include_str!("../migrations/postgres/0003_owner.sql")),
    (
        4,
        include_str!("../migrations/postgres/0004_process_limits.sql"),
    ),
];

/// The schema version this binary works with.
pub const SCHEMA_VERSION: i32 = 4;

/// Advisory-lock key serialising migrations of concurrently starting processes ("ashlar" in ASCII).
const MIGRATION_LOCK: i64 = 0x61_73_68_6c_61_72;

/// Notification channels.
pub const CHANNEL_WORK: &str = "ashlar_work";
pub const CHANNEL_CANCEL: &str = "ashlar_cancel";
pub const CHANNEL_DONE: &str = "ashlar_done";

/// Tuning of leases.
#[derive(Debug, Clone, PartialEq)]
pub struct LeaseParams {
    /// How long a claim stays valid without a heartbeat. 30 s: a dead worker's job is rerun
    /// within half a minute, while a worker stalled by a slow disk or a GC-paused database
    /// (seconds) keeps its job.
    pub lease: Duration,
    /// Heartbeat period: a third of the lease, so two heartbeats may be lost before expiry.
    pub heartbeat: Duration,
    /// How often each process looks for expired leases (cheap: an index on running jobs).
    pub reap_every: Duration,
}

impl Default for LeaseParams {
    fn default() -> Self {
        Self {
            lease: Duration::from_secs(30),
            heartbeat: Duration::from_secs(10),
            reap_every: Duration::from_secs(5),
        }
    }
}

impl LeaseParams {
    /// A lease of `lease`, heartbeat a third of it, reaping twice per lease.
    pub fn with_lease(lease: Duration) -> Self {
        Self {
            lease,
            heartbeat: lease / 3,
            reap_every: lease / 2,
        }
    }
}

/// What one heartbeat learnt.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Heartbeat {
    /// Jobs whose lease this process no longer holds (reaped, maybe rerun elsewhere): stop them.
    pub lost: Vec<Uuid>,
    /// Jobs with a cancel request (in case the notification was missed).
    pub cancel: Vec<Uuid>,
}

/// PostgreSQL job store. Connections are pooled (one per concurrently calling thread).
pub struct PgStore {
    /// Client configuration and TLS (`sslmode`, `sslrootcert`…), see `pg_tls`.
    target: super::tls::PgTarget,
    pool: Mutex<Vec<Client>>,
    /// `host:pid`, recorded with each claim.
    worker_name: String,
    params: LeaseParams,
    /// Lease tokens of the jobs this process claimed and still runs.
    tokens: Mutex<HashMap<Uuid, Uuid>>,
}

impl From<postgres::Error> for StoreError {
    fn from(e: postgres::Error) -> Self {
        // `Display` of a server error is terse; the source carries the server's message.
        let database = Backend::Postgres;
        match e.as_db_error() {
            Some(db) => StoreError::Database {
                database,
                detail: db.message().to_string(),
            },
            // The connection closed or its I/O failed: the server may be back on a retry.
            None if e.is_closed()
                || std::error::Error::source(&e).is_some_and(|s| s.is::<std::io::Error>()) =>
            {
                StoreError::Busy {
                    database,
                    detail: e.to_string(),
                }
            }
            None => StoreError::Database {
                database,
                detail: e.to_string(),
            },
        }
    }
}

const COLUMNS: &str = "id, kind, status, request, motion, progress, result, error, cancel_requested, attempts, created_ms, started_ms, finished_ms, parent, owner";

fn row_to_record(row: &Row) -> Result<JobRecord, StoreError> {
    let json = |k: usize, what: &str| -> Result<serde_json::Value, StoreError> {
        let s: String = row.try_get(k)?;
        serde_json::from_str(&s).map_err(|e| StoreError::corrupt(format!("{what} column"), e))
    };
    let kind: String = row.try_get(1)?;
    let status: String = row.try_get(2)?;
    let attempts: i32 = row.try_get(9)?;
    Ok(JobRecord {
        id: row.try_get(0)?,
        kind: JobKind::parse(&kind)?,
        status: JobStatus::parse(&status)?,
        request: json(3, "request")?,
        motion: json(4, "motion")?,
        progress: row.try_get(5)?,
        result: row.try_get(6)?,
        error: row.try_get(7)?,
        cancel_requested: row.try_get(8)?,
        attempts: u32::try_from(attempts).unwrap_or(0),
        created_ms: row.try_get(10)?,
        started_ms: row.try_get(11)?,
        finished_ms: row.try_get(12)?,
        parent: row.try_get(13)?,
        owner: row.try_get(14)?,
    })
}

/// Check a `--database` URL names PostgreSQL and parse it, TLS parameters included
/// (credentials are never echoed).
pub fn parse_url(url: &str) -> Result<super::tls::PgTarget, super::tls::PgUrlError> {
    if !(url.starts_with("postgres://") || url.starts_with("postgresql://")) {
        return Err(super::tls::PgUrlError::Scheme);
    }
    super::tls::parse(url)
}

impl PgStore {
    /// Connect, create or upgrade the schema, and return the store.
    pub fn open(url: &str, params: LeaseParams) -> Result<Self, StoreError> {
        // StoreError is Clone and compared in the store's tests: the URL's error is kept as text.
        let target = parse_url(url)?;
        let host = std::env::var("HOSTNAME")
            .ok()
            .or_else(|| {
                std::fs::read_to_string("/etc/hostname")
                    .ok()
                    .map(|s| s.trim().to_string())
            })
            .filter(|s| !s.is_empty())
            .unwrap_or_else(|| "localhost".into());
        let store = Self {
            target,
            pool: Mutex::new(Vec::new()),
            worker_name: format!("{host}:{}", std::process::id()),
            params,
            tokens: Mutex::new(HashMap::new()),
        };
        store.with(migrate)?;
        Ok(store)
    }

    /// The name this process claims jobs under (`host:pid`).
    pub fn worker_name(&self) -> &str {
        &self.worker_name
    }

    pub fn lease_params(&self) -> &LeaseParams {
        &self.params
    }

    /// A new connection (also used for `LISTEN`).
    pub fn connect(&self) -> Result<Client, StoreError> {
        self.target.connect().map_err(|e| StoreError::Busy {
            database: Backend::Postgres,
            detail: e.to_string(),
        })
    }

    /// Run `f` on a pooled connection; a connection that broke is dropped, not returned.
    fn with<T>(
        &self,
        f: impl FnOnce(&mut Client) -> Result<T, StoreError>,
    ) -> Result<T, StoreError> {
        let pooled = self.pool.lock().ok().and_then(|mut p| p.pop());
        let mut client = match pooled {
            Some(c) if !c.is_closed() => c,
            _ => self.connect()?,
        };
        let out = f(&mut client);
        if !client.is_closed() {
            if let Ok(mut p) = self.pool.lock() {
                p.push(client);
            }
        }
        out
    }

    fn token(&self, id: Uuid) -> Option<Uuid> {
        self.tokens.lock().ok().and_then(|t| t.get(&id).copied())
    }

    fn drop_token(&self, id: Uuid) {
        if let Ok(mut t) = self.tokens.lock() {
            t.remove(&id);
        }
    }

    /// Record (or refresh) the limits this process enforces in `role` (`api` or `worker`),
    /// a JSON object as text, under its name (`host:pid`).
    pub fn publish_limits(&self, role: &str, limits: &str) -> Result<(), StoreError> {
        self.with(|c| {
            c.execute(
                "INSERT INTO process_limits (process, role, limits) VALUES ($1, $2, $3)
                 ON CONFLICT (process, role) DO UPDATE SET limits = $3, seen_at = now()",
                &[&self.worker_name(), &role, &limits],
            )?;
            Ok(())
        })
    }

    /// Remove this process's published limits (a clean stop).
    pub fn withdraw_limits(&self) -> Result<(), StoreError> {
        self.with(|c| {
            c.execute(
                "DELETE FROM process_limits WHERE process = $1",
                &[&self.worker_name()],
            )?;
            Ok(())
        })
    }

    /// The installed schema version (0 when none).
    pub fn schema_version(&self) -> Result<i32, StoreError> {
        self.with(current_version)
    }

    /// Extend the leases of `ids` (jobs this process runs); see [`Heartbeat`].
    pub fn heartbeat(&self, ids: &[Uuid]) -> Result<Heartbeat, StoreError> {
        let mine: Vec<(Uuid, Uuid)> = ids
            .iter()
            .filter_map(|&id| self.token(id).map(|t| (id, t)))
            .collect();
        if mine.is_empty() {
            return Ok(Heartbeat::default());
        }
        let tokens: Vec<Uuid> = mine.iter().map(|&(_, t)| t).collect();
        let secs = self.params.lease.as_secs_f64();
        let rows = self.with(|c| {
            Ok(c.query(
                "UPDATE jobs SET lease_until = now() + make_interval(secs => $2)
                 WHERE lease_token = ANY($1) AND status = 'running'
                 RETURNING id, cancel_requested",
                &[&tokens, &secs],
            )?)
        })?;
        let mut out = Heartbeat::default();
        let held: HashMap<Uuid, bool> = rows
            .iter()
            .filter_map(|r| Some((r.try_get(0).ok()?, r.try_get(1).ok()?)))
            .collect();
        for (id, _) in mine {
            match held.get(&id) {
                None => {
                    self.drop_token(id);
                    out.lost.push(id);
                }
                Some(true) => out.cancel.push(id),
                Some(false) => {}
            }
        }
        Ok(out)
    }

    /// Seconds left on a job's lease (negative when expired; None when not running). For tests
    /// and operators.
    pub fn lease_remaining(&self, id: Uuid) -> Result<Option<f64>, StoreError> {
        self.with(|c| {
            let row = c.query_opt(
                "SELECT EXTRACT(EPOCH FROM (lease_until - now()))::float8 FROM jobs
                 WHERE id = $1 AND status = 'running' AND lease_until IS NOT NULL",
                &[&id],
            )?;
            Ok(row.map(|r| r.try_get(0)).transpose()?)
        })
    }

    /// Every claim of a job, oldest first: (worker, outcome). `outcome` is None while running.
    pub fn attempts_of(&self, id: Uuid) -> Result<Vec<(String, Option<String>)>, StoreError> {
        self.with(|c| {
            let rows = c.query(
                "SELECT worker, outcome FROM job_attempts WHERE job_id = $1 ORDER BY claimed_at",
                &[&id],
            )?;
            rows.iter()
                .map(|r| Ok((r.try_get(0)?, r.try_get(1)?)))
                .collect()
        })
    }
}

fn current_version(c: &mut Client) -> Result<i32, StoreError> {
    let exists: bool = c
        .query_one(
            "SELECT to_regclass('ashlar_schema_version') IS NOT NULL",
            &[],
        )?
        .try_get(0)?;
    if !exists {
        return Ok(0);
    }
    let v: Option<i32> = c
        .query_one("SELECT max(version) FROM ashlar_schema_version", &[])?
        .try_get(0)?;
    Ok(v.unwrap_or(0))
}

/// Bring the schema to [`SCHEMA_VERSION`], one transaction per migration, under an advisory
/// lock so that processes starting together migrate once.
fn migrate(c: &mut Client) -> Result<(), StoreError> {
    let mut tx = c.transaction()?;
    tx.execute("SELECT pg_advisory_xact_lock($1)", &[&MIGRATION_LOCK])?;
    tx.batch_execute(
        "CREATE TABLE IF NOT EXISTS ashlar_schema_version (
             version INTEGER PRIMARY KEY,
             applied_at TIMESTAMPTZ NOT NULL DEFAULT now())",
    )?;
    let v: Option<i32> = tx
        .query_one("SELECT max(version) FROM ashlar_schema_version", &[])?
        .try_get(0)?;
    let v = v.unwrap_or(0);
    if v > SCHEMA_VERSION {
        return Err(StoreError::SchemaNewer {
            found: v,
            known: SCHEMA_VERSION,
        });
    }
    for &(version, sql) in MIGRATIONS.iter().filter(|(k, _)| *k > v) {
        tx.batch_execute(sql).map_err(|e| {
            let detail = e
                .as_db_error()
                .map_or_else(|| e.to_string(), |db| db.message().to_string());
            StoreError::Migration {
                version,
                database: Backend::Postgres,
                detail,
            }
        })?;
        tx.execute(
            "INSERT INTO ashlar_schema_version (version) VALUES ($1)",
            &[&version],
        )?;
        tracing::info!(version, "applied schema migration");
    }
    tx.commit()?;
    Ok(())
}

/// Advisory lock key serialising bounded inserts (`insert_bounded`): "ashlarQ" in ASCII.
const QUEUE_LOCK: i64 = 0x61_73_68_6c_61_72_51;

impl JobStore for PgStore {
    fn insert(&self, job: &NewJob) -> Result<(), StoreError> {
        self.with(|c| {
            let mut tx = c.transaction()?;
            tx.execute(
                "INSERT INTO jobs (id, kind, status, request, motion, created_ms, owner) VALUES ($1, $2, 'queued', $3, $4, $5, $6)",
                &[&job.id, &job.kind.as_str(), &job.request.to_string(), &job.motion.to_string(), &now_ms(), &job.owner],
            )?;
            // Delivered at commit: a woken worker always finds the row.
            tx.execute("SELECT pg_notify($1, '')", &[&CHANNEL_WORK])?;
            tx.commit()?;
            Ok(())
        })
    }

    fn insert_quota(
        &self,
        job: &NewJob,
        max_queued: u64,
        max_owner: u64,
    ) -> Result<Option<QueueFull>, StoreError> {
        let max = i64::try_from(max_queued).unwrap_or(i64::MAX);
        let max_owner = i64::try_from(max_owner).unwrap_or(i64::MAX);
        self.with(|c| {
            let mut tx = c.transaction()?;
            // Concurrent submissions (from every API process) take this lock in turn, so the
            // counts below cannot be stale when the row goes in; released at commit.
            tx.execute("SELECT pg_advisory_xact_lock($1)", &[&QUEUE_LOCK])?;
            let row = tx.query_one(
                "SELECT COUNT(*), COUNT(*) FILTER (WHERE owner = $1 AND kind = $2)
                 FROM jobs WHERE status = 'queued' AND parent IS NULL",
                &[&job.owner, &job.kind.as_str()],
            )?;
            let (queued, mine): (i64, i64) = (row.try_get(0)?, row.try_get(1)?);
            let n = |v: i64| u64::try_from(v).unwrap_or(0);
            if queued >= max {
                return Ok(Some(QueueFull::Server(n(queued))));
            }
            if job.owner.is_some() && mine >= max_owner {
                return Ok(Some(QueueFull::Owner(n(mine))));
            }
            tx.execute(
                "INSERT INTO jobs (id, kind, status, request, motion, created_ms, owner) VALUES ($1, $2, 'queued', $3, $4, $5, $6)",
                &[&job.id, &job.kind.as_str(), &job.request.to_string(), &job.motion.to_string(), &now_ms(), &job.owner],
            )?;
            tx.execute("SELECT pg_notify($1, '')", &[&CHANNEL_WORK])?;
            tx.commit()?;
            Ok(None)
        })
    }

    fn delete(&self, id: Uuid) -> Result<DeleteOutcome, StoreError> {
        self.with(|c| {
            let mut tx = c.transaction()?;
            let row = tx.query_opt(
                "SELECT status FROM jobs WHERE id = $1 AND parent IS NULL FOR UPDATE",
                &[&id],
            )?;
            let Some(row) = row else {
                return Ok(DeleteOutcome::NotFound);
            };
            let status: String = row.try_get(0)?;
            let status = JobStatus::parse(&status)?;
            if !status.is_terminal() {
                return Ok(DeleteOutcome::NotFinished(status));
            }
            tx.execute("DELETE FROM jobs WHERE parent = $1 OR id = $1", &[&id])?;
            tx.commit()?;
            Ok(DeleteOutcome::Deleted)
        })
    }

    fn get(&self, id: Uuid) -> Result<Option<JobRecord>, StoreError> {
        self.with(|c| {
            let sql = format!("SELECT {COLUMNS} FROM jobs WHERE id = $1");
            c.query_opt(&sql, &[&id])?
                .map(|r| row_to_record(&r))
                .transpose()
        })
    }

    fn finished_before(&self, cutoff_ms: i64, limit: usize) -> Result<Vec<Uuid>, StoreError> {
        let limit = i64::try_from(limit).unwrap_or(i64::MAX);
        self.with(|c| {
            c.query(
                &format!(
                    "SELECT id FROM jobs WHERE parent IS NULL AND finished_ms < $1 AND {}
                     ORDER BY finished_ms LIMIT $2",
                    jobs::terminal_sql()
                ),
                &[&cutoff_ms, &limit],
            )?
            .iter()
            .map(|r| r.try_get(0).map_err(StoreError::from))
            .collect()
        })
    }

    fn list_owned(
        &self,
        limit: usize,
        kind: Option<JobKind>,
        owner: Option<&str>,
    ) -> Result<Vec<JobRecord>, StoreError> {
        // The request body can be large and the listing does not show it.
        let cols = COLUMNS.replace("request,", "'null',");
        let limit = i64::try_from(limit).unwrap_or(i64::MAX);
        let kind = kind.map(JobKind::as_str);
        self.with(|c| {
            let sql = format!(
                "SELECT {cols} FROM jobs WHERE parent IS NULL AND ($1::TEXT IS NULL OR kind = $1)
                   AND ($3::TEXT IS NULL OR owner = $3) ORDER BY seq DESC LIMIT $2"
            );
            c.query(&sql, &[&kind, &limit, &owner])?
                .iter()
                .map(row_to_record)
                .collect()
        })
    }

    fn claim(&self) -> Result<Option<JobRecord>, StoreError> {
        let token = Uuid::new_v4();
        let secs = self.params.lease.as_secs_f64();
        let rec = self.with(|c| {
            let mut tx = c.transaction()?;
            let sql = format!(
                "UPDATE jobs j SET {}, started_ms = $1,
                        progress = CASE WHEN j.kind = 'pga_search' THEN j.progress ELSE 0 END,
                        lease_token = $2, worker = $3,
                        lease_until = now() + make_interval(secs => $4)
                 FROM (SELECT seq FROM jobs WHERE {} ORDER BY seq
                       LIMIT 1 FOR UPDATE SKIP LOCKED) next
                 WHERE j.seq = next.seq
                 RETURNING {}",
                // `attempts` and `status` unqualified: `next` has only `seq`.
                set(&Event::Claim, None),
                jobs::guard(&Event::Claim),
                COLUMNS
                    .split(", ")
                    .map(|c| format!("j.{c}"))
                    .collect::<Vec<_>>()
                    .join(", ")
            );
            let row = tx.query_opt(&sql, &[&now_ms(), &token, &self.worker_name, &secs])?;
            let Some(row) = row else {
                return Ok(None);
            };
            let rec = row_to_record(&row)?;
            tx.execute(
                "INSERT INTO job_attempts (token, job_id, worker) VALUES ($1, $2, $3)",
                &[&token, &rec.id, &self.worker_name],
            )?;
            tx.commit()?;
            Ok(Some(rec))
        })?;
        if let Some(r) = &rec {
            if let Ok(mut t) = self.tokens.lock() {
                t.insert(r.id, token);
            }
        }
        Ok(rec)
    }

    fn set_progress(&self, id: Uuid, progress: f64) -> Result<(), StoreError> {
        let Some(token) = self.token(id) else {
            return Ok(());
        };
        self.with(|c| {
            c.execute(
                &format!(
                    "UPDATE jobs SET progress = $2 WHERE id = $1 AND {} AND lease_token = $3",
                    jobs::guard(&Event::Progress)
                ),
                &[&id, &progress.clamp(0.0, 1.0), &token],
            )?;
            Ok(())
        })
    }

    fn finish(&self, id: Uuid, finish: &Finish) -> Result<(), StoreError> {
        let Some(token) = self.token(id) else {
            tracing::warn!(%id, "finishing a job this process does not hold; result discarded");
            return Ok(());
        };
        let end = finish.end();
        let (result, error, progress) = finish.columns();
        let status = end.status().as_str();
        let n = self.with(|c| {
            let mut tx = c.transaction()?;
            // A child run locks its search's row first: every transaction touching both
            // (cancel, fan-out, this) takes the parent before the child, so none deadlock.
            let parent: Option<Uuid> = tx
                .query_opt("SELECT parent FROM jobs WHERE id = $1", &[&id])?
                .map(|r| r.try_get(0))
                .transpose()?
                .flatten();
            if let Some(p) = parent {
                tx.execute("SELECT 1 FROM jobs WHERE id = $1 FOR UPDATE", &[&p])?;
            }
            let n = tx.execute(
                &format!(
                    "UPDATE jobs SET {}, result = $2, error = $3, progress = COALESCE($4, progress),
                            finished_ms = $5, lease_token = NULL, lease_until = NULL
                     WHERE id = $1 AND {} AND lease_token = $6",
                    set(&Event::Finish(end), None),
                    jobs::guard(&Event::Finish(end))
                ),
                &[&id, &result, &error, &progress, &now_ms(), &token],
            )?;
            if let (1, Some(p)) = (n, parent) {
                if end == jobs::End::Succeeded {
                    tx.execute(
                        &format!(
                            "UPDATE jobs SET progress = LEAST($3, progress + COALESCE(
                                 (SELECT (request::jsonb ->> 'progress_step')::float8 FROM jobs WHERE id = $2), 0))
                             WHERE id = $1 AND {}",
                            jobs::guard(&Event::Settle(jobs::Settlement::Wait))
                        ),
                        &[&p, &id, &jobs::CHILD_PROGRESS_CAP],
                    )?;
                }
                settle(&mut tx, p)?;
            }
            if n == 1 {
                tx.execute(
                    "UPDATE job_attempts SET outcome = $2, ended_at = now() WHERE token = $1",
                    &[&token, &status],
                )?;
                tx.execute("SELECT pg_notify($1, $2)", &[&CHANNEL_DONE, &id.to_string()])?;
            }
            tx.commit()?;
            Ok(n)
        })?;
        self.drop_token(id);
        if n == 0 {
            tracing::warn!(%id, "this worker's lease had expired; its result was discarded (the job was requeued)");
        }
        Ok(())
    }

    fn requeue(&self, id: Uuid, refund: bool) -> Result<(), StoreError> {
        let Some(token) = self.token(id) else {
            return Ok(());
        };
        self.with(|c| {
            let mut tx = c.transaction()?;
            let event = Event::Requeue { refund };
            let n = tx.execute(
                &format!(
                    "UPDATE jobs SET {}, progress = 0, started_ms = NULL,
                            lease_token = NULL, lease_until = NULL, worker = NULL
                     WHERE id = $1 AND {} AND lease_token = $2",
                    set(&event, None),
                    jobs::guard(&event)
                ),
                &[&id, &token],
            )?;
            if n == 1 {
                tx.execute(
                    "UPDATE job_attempts SET outcome = 'requeued', ended_at = now() WHERE token = $1",
                    &[&token],
                )?;
                tx.execute("SELECT pg_notify($1, '')", &[&CHANNEL_WORK])?;
            }
            tx.commit()?;
            Ok(())
        })?;
        self.drop_token(id);
        Ok(())
    }

    fn request_cancel(&self, id: Uuid) -> Result<CancelOutcome, StoreError> {
        self.with(|c| {
            let mut tx = c.transaction()?;
            let row = tx.query_opt("SELECT status FROM jobs WHERE id = $1 FOR UPDATE", &[&id])?;
            let status = row
                .map(|r| r.try_get::<_, String>(0))
                .transpose()?
                .map(|s| JobStatus::parse(&s))
                .transpose()?;
            let out = jobs::cancel(status);
            match out {
                // No worker holds a queued job, nor a waiting search: it ends now.
                CancelOutcome::CancelledQueued => {
                    tx.execute(
                        &format!(
                            "UPDATE jobs SET {}, cancel_requested = TRUE, finished_ms = $2 WHERE id = $1",
                            set(&Event::Cancel, Some(JobStatus::Cancelled))
                        ),
                        &[&id, &now_ms()],
                    )?;
                    tx.execute("SELECT pg_notify($1, $2)", &[&CHANNEL_DONE, &id.to_string()])?;
                }
                CancelOutcome::Requested => {
                    tx.execute(
                        "UPDATE jobs SET cancel_requested = TRUE WHERE id = $1",
                        &[&id],
                    )?;
                    // Reaches the process running the job, wherever it is.
                    tx.execute("SELECT pg_notify($1, $2)", &[&CHANNEL_CANCEL, &id.to_string()])?;
                }
                CancelOutcome::AlreadyFinished(_) | CancelOutcome::NotFound => {}
            }
            if jobs::cancel_reaches_children(out) {
                cancel_children(&mut tx, id)?;
            }
            tx.commit()?;
            Ok(out)
        })
    }

    /// The reaper: running jobs whose lease expired go back to the queue (or fail after
    /// `max_attempts` starts; or end cancelled when a cancel was requested). Unlike the
    /// embedded store's start-up recovery, jobs with a live lease are left alone: their
    /// workers, in other processes, are running them.
    fn recover(&self, max_attempts: u32) -> Result<(usize, usize), StoreError> {
        self.with(|c| {
            let mut tx = c.transaction()?;
            let rows = tx.query(
                &format!(
                    "SELECT seq, lease_token, attempts, cancel_requested FROM jobs
                     WHERE {} AND (lease_until IS NULL OR lease_until < now())
                     FOR UPDATE SKIP LOCKED",
                    jobs::guard(&Event::Recover(jobs::Recovery::Requeue))
                ),
                &[],
            )?;
            let (mut requeued, mut failed) = (0, 0);
            for r in &rows {
                let seq: i64 = r.try_get(0)?;
                let token: Option<Uuid> = r.try_get(1)?;
                let attempts: i32 = r.try_get(2)?;
                let cancel: bool = r.try_get(3)?;
                if let Some(t) = token {
                    tx.execute(
                        "UPDATE job_attempts SET outcome = 'expired', ended_at = now() WHERE token = $1",
                        &[&t],
                    )?;
                }
                let attempts = u32::try_from(attempts).unwrap_or(0);
                let decision =
                    jobs::recover(attempts, max_attempts, cancel, jobs::Abandoned::WorkerDied);
                let set = set(&Event::Recover(decision.clone()), None);
                match decision {
                    jobs::Recovery::Cancel => {
                        tx.execute(
                            &format!("UPDATE jobs SET {set}, finished_ms = $2, lease_token = NULL, lease_until = NULL WHERE seq = $1"),
                            &[&seq, &now_ms()],
                        )?;
                        failed += 1;
                    }
                    jobs::Recovery::Fail(error) => {
                        tx.execute(
                            &format!(
                                "UPDATE jobs SET {set}, finished_ms = $2, lease_token = NULL, lease_until = NULL,
                                        error = $3
                                 WHERE seq = $1"
                            ),
                            &[&seq, &now_ms(), &error],
                        )?;
                        failed += 1;
                    }
                    jobs::Recovery::Requeue => {
                        tx.execute(
                            &format!(
                                "UPDATE jobs SET {set}, progress = 0, started_ms = NULL,
                                        lease_token = NULL, lease_until = NULL, worker = NULL
                                 WHERE seq = $1"
                            ),
                            &[&seq],
                        )?;
                        requeued += 1;
                    }
                }
            }
            if requeued > 0 {
                tx.execute("SELECT pg_notify($1, '')", &[&CHANNEL_WORK])?;
            }
            tx.commit()?;
            if requeued + failed > 0 {
                tracing::info!(requeued, failed, "reaped jobs whose worker's lease expired");
            }
            // Searches whose children all ended (or one failed, e.g. reaped too often) are
            // settled, each in its own transaction (parent row first, as everywhere).
            let parents: Vec<Uuid> = c
                .query(
                    &format!(
                        "SELECT p.id FROM jobs p WHERE p.{} AND (
                             NOT EXISTS (SELECT 1 FROM jobs k WHERE k.parent = p.id AND k.{})
                             OR EXISTS (SELECT 1 FROM jobs k WHERE k.parent = p.id AND k.{}))",
                        jobs::guard(&Event::Settle(jobs::Settlement::Wait)),
                        jobs::child_unfinished_sql(),
                        jobs::child_bad_sql()
                    ),
                    &[],
                )?
                .iter()
                .map(|r| r.try_get(0))
                .collect::<Result<_, _>>()?;
            for p in parents {
                let mut tx = c.transaction()?;
                tx.execute("SELECT 1 FROM jobs WHERE id = $1 FOR UPDATE", &[&p])?;
                settle(&mut tx, p)?;
                tx.commit()?;
            }
            Ok((requeued, failed))
        })
    }

    fn fan_out(&self, id: Uuid, children: &[NewJob], progress: f64) -> Result<bool, StoreError> {
        let Some(token) = self.token(id) else {
            return Ok(false);
        };
        let ok = self.with(|c| {
            let mut tx = c.transaction()?;
            let n = tx.execute(
                &format!(
                    "UPDATE jobs SET {}, progress = GREATEST(progress, $3),
                            lease_token = NULL, lease_until = NULL, worker = NULL
                     WHERE id = $1 AND {} AND lease_token = $2",
                    set(&Event::FanOut, None),
                    jobs::guard(&Event::FanOut)
                ),
                &[&id, &token, &progress.clamp(0.0, 1.0)],
            )?;
            if n == 0 {
                return Ok(false);
            }
            tx.execute(
                "UPDATE job_attempts SET outcome = 'waiting', ended_at = now() WHERE token = $1",
                &[&token],
            )?;
            let now = now_ms();
            for ch in children {
                // A child run belongs to its search's owner.
                tx.execute(
                    "INSERT INTO jobs (id, kind, status, request, motion, created_ms, parent, owner)
                     VALUES ($1, $2, 'queued', $3, $4, $5, $6, (SELECT owner FROM jobs WHERE id = $6))",
                    &[&ch.id, &ch.kind.as_str(), &ch.request.to_string(), &ch.motion.to_string(), &now, &id],
                )?;
            }
            settle(&mut tx, id)?;
            tx.execute("SELECT pg_notify($1, '')", &[&CHANNEL_WORK])?;
            tx.commit()?;
            Ok(true)
        })?;
        self.drop_token(id);
        Ok(ok)
    }

    fn children(&self, id: Uuid) -> Result<Vec<JobRecord>, StoreError> {
        self.with(|c| {
            let sql = format!("SELECT {COLUMNS} FROM jobs WHERE parent = $1 ORDER BY seq");
            c.query(&sql, &[&id])?.iter().map(row_to_record).collect()
        })
    }

    fn published_limits(&self, role: &str) -> Result<Vec<(String, String)>, StoreError> {
        // Refreshed every lease/2: a process unseen for three leases is gone.
        let fresh = self.lease_params().lease.as_secs_f64() * 3.0;
        self.with(|c| {
            let rows = c.query(
                "SELECT process, limits FROM process_limits
                 WHERE role = $1 AND seen_at > now() - make_interval(secs => $2)
                 ORDER BY process",
                &[&role, &fresh],
            )?;
            rows.iter()
                .map(|r| Ok((r.try_get(0)?, r.try_get(1)?)))
                .collect()
        })
    }

    fn counts(&self) -> Result<Counts, StoreError> {
        self.with(|c| {
            let mut out = Counts::default();
            for r in c.query("SELECT status, count(*) FROM jobs GROUP BY status", &[])? {
                let s: String = r.try_get(0)?;
                let n: i64 = r.try_get(1)?;
                let n = u64::try_from(n).unwrap_or(0);
                out.set(JobStatus::parse(&s)?, n);
            }
            Ok(out)
        })
    }
}

/// Apply [`jobs::settle`] to a search whose row the caller has locked: read its children's
/// facts, write the decision (a failed search also cancels its other children; a requeued one
/// wakes a worker, which replays it).
fn settle(tx: &mut postgres::Transaction<'_>, parent: Uuid) -> Result<(), StoreError> {
    let status = tx
        .query_opt("SELECT status FROM jobs WHERE id = $1", &[&parent])?
        .map(|r| r.try_get::<_, String>(0))
        .transpose()?
        .map(|s| JobStatus::parse(&s))
        .transpose()?;
    if status
        .and_then(|s| jobs::next(s, &Event::Settle(jobs::Settlement::Wait)))
        .is_none()
    {
        return Ok(());
    }
    let first_bad = tx
        .query_opt(
            &format!(
                "SELECT status, error FROM jobs WHERE parent = $1 AND {} ORDER BY seq LIMIT 1",
                jobs::child_bad_sql()
            ),
            &[&parent],
        )?
        .map(|r| -> Result<_, StoreError> {
            let st: String = r.try_get(0)?;
            Ok((JobStatus::parse(&st)?, r.try_get::<_, Option<String>>(1)?))
        })
        .transpose()?;
    let unfinished: i64 = tx
        .query_one(
            &format!(
                "SELECT count(*) FROM jobs WHERE parent = $1 AND {}",
                jobs::child_unfinished_sql()
            ),
            &[&parent],
        )?
        .try_get(0)?;
    let children = jobs::Children {
        first_bad,
        unfinished: u64::try_from(unfinished).unwrap_or(0),
    };
    let decision = jobs::settle(&children);
    let set = set(&Event::Settle(decision.clone()), None);
    match decision {
        jobs::Settlement::Wait => {}
        jobs::Settlement::Requeue => {
            tx.execute(
                &format!("UPDATE jobs SET {set}, started_ms = NULL WHERE id = $1"),
                &[&parent],
            )?;
            tx.execute("SELECT pg_notify($1, '')", &[&CHANNEL_WORK])?;
        }
        jobs::Settlement::Fail(error) => {
            tx.execute(
                &format!("UPDATE jobs SET {set}, error = $2, finished_ms = $3 WHERE id = $1"),
                &[&parent, &error, &now_ms()],
            )?;
            tx.execute(
                "SELECT pg_notify($1, $2)",
                &[&CHANNEL_DONE, &parent.to_string()],
            )?;
            cancel_children(tx, parent)?;
        }
    }
    Ok(())
}

/// Cancel the unfinished children of a job as [`jobs::cancel`] says: queued ones end at once,
/// running ones get a cancel request (their processes hear it on the cancel channel).
fn cancel_children(tx: &mut postgres::Transaction<'_>, parent: Uuid) -> Result<(), StoreError> {
    tx.execute(
        &format!(
            "UPDATE jobs SET {}, cancel_requested = TRUE, finished_ms = $2 WHERE parent = $1 AND {}",
            set(&Event::Cancel, Some(JobStatus::Cancelled)),
            jobs::guard_to(&Event::Cancel, JobStatus::Cancelled)
        ),
        &[&parent, &now_ms()],
    )?;
    let running = tx.query(
        &format!(
            "UPDATE jobs SET cancel_requested = TRUE WHERE parent = $1 AND {} RETURNING id",
            jobs::guard_to(&Event::Cancel, JobStatus::Running)
        ),
        &[&parent],
    )?;
    for r in running {
        let id: Uuid = r.try_get(0)?;
        tx.execute(
            "SELECT pg_notify($1, $2)",
            &[&CHANNEL_CANCEL, &id.to_string()],
        )?;
    }
    Ok(())
}
