//! Service: the embedded job store, [`JobStore`] on SQLite (one file under `--data`). Sits under
//! `store` beside `postgres`; applies the state machine of [`crate::service::jobs`]. Its schema
//! is the numbered migrations in `src/service/migrations/sqlite/`, the version kept in
//! `PRAGMA user_version`; files created before the migrations existed (version 0) are
//! recognised by their columns.
//!
//! Over 600 lines: the store itself is about 680 lines, one transaction per method, and the
//! tests of what only this store has (reopening a file, the schemas of older files) sit beside
//! it. Its behaviour as a [`JobStore`] is checked on both stores by
//! `tests/service/store_contract.rs`.
use super::{
    now_ms, set_sql, Backend, CancelOutcome, Counts, DeleteOutcome, Finish, JobKind, JobRecord,
    JobStatus, JobStore, NewJob, QueueFull, StoreError,
};
use crate::service::jobs::{self, Event};

/// The `SET` of `event` in SQLite's SQL ([`super::set_sql`]).
fn set(event: &Event, to: Option<JobStatus>) -> String {
    set_sql(Backend::Sqlite, event, to)
}
use rusqlite::{params, Connection, OptionalExtension};
use std::path::Path;
use std::sync::Mutex;
use std::time::Duration;
use uuid::Uuid;

impl From<rusqlite::Error> for StoreError {
    fn from(e: rusqlite::Error) -> Self {
        let busy = matches!(
            e.sqlite_error_code(),
            Some(rusqlite::ErrorCode::DatabaseBusy | rusqlite::ErrorCode::DatabaseLocked)
        );
        let (database, detail) = (Backend::Sqlite, e.to_string());
        if busy {
            StoreError::Busy { database, detail }
        } else {
            StoreError::Database { database, detail }
        }
    }
}

/// The embedded store: SQLite in WAL mode, `synchronous = FULL` so that a job acknowledged with
/// 202 survives even a power cut. One writer connection and one reader connection (WAL lets
/// readers proceed while a write commits), each behind a mutex.
pub struct SqliteStore {
    writer: Mutex<Connection>,
    reader: Mutex<Connection>,
}

/// Schema migrations, in order; migration k brings the schema to version k (kept in
/// `PRAGMA user_version`).
pub const MIGRATIONS: &[(i32, &str)] = &[
    (1, include_str!("../migrations/sqlite/0001_jobs.sql")),
    (2, include_str!("../migrations/sqlite/0002_parent.sql")),
    (3, include_str!("../migrations/sqlite/0003_owner.sql")),
];

/// The schema version this binary works with.
pub const SCHEMA_VERSION: i32 = 3;

/// The version of a file created before the migrations were numbered (`user_version` 0): the
/// code then built the schema inline, adding `parent` and later `owner` with an `ALTER TABLE`
/// on open, so the columns present tell how far it got (every such open also created the
/// indexes of the columns it added).
fn legacy_version(c: &Connection) -> rusqlite::Result<i32> {
    let has = |column: &str| -> rusqlite::Result<bool> {
        c.prepare("SELECT 1 FROM pragma_table_info('jobs') WHERE name = ?1")?
            .exists([column])
    };
    Ok(if !has("id")? {
        0
    } else if has("owner")? {
        3
    } else if has("parent")? {
        2
    } else {
        1
    })
}

/// Bring the schema to [`SCHEMA_VERSION`] in one immediate transaction, so that two processes
/// opening the same file migrate once (the second waits on the busy timeout, then finds the
/// version current).
fn migrate(c: &mut Connection) -> Result<(), StoreError> {
    let tx = c.transaction_with_behavior(rusqlite::TransactionBehavior::Immediate)?;
    let mut v: i32 = tx.query_row("PRAGMA user_version", [], |r| r.get(0))?;
    if v == 0 {
        v = legacy_version(&tx)?;
    }
    if v > SCHEMA_VERSION {
        return Err(StoreError::SchemaNewer {
            found: v,
            known: SCHEMA_VERSION,
        });
    }
    for &(version, sql) in MIGRATIONS.iter().filter(|(k, _)| *k > v) {
        tx.execute_batch(sql).map_err(|e| StoreError::Migration {
            version,
            database: Backend::Sqlite,
            detail: e.to_string(),
        })?;
        tracing::info!(version, "applied schema migration");
    }
    tx.pragma_update(None, "user_version", SCHEMA_VERSION)?;
    tx.commit()?;
    Ok(())
}

const COLUMNS: &str =
    "id, kind, status, request, motion, progress, result, error, cancel_requested, attempts, created_ms, started_ms, finished_ms, parent, owner";

impl SqliteStore {
    /// Open (or create) the store at `path`.
    pub fn open(path: &Path) -> Result<Self, StoreError> {
        let open = || -> Result<Connection, StoreError> {
            let c = Connection::open(path).map_err(|e| StoreError::Open {
                path: path.display().to_string(),
                detail: e.to_string(),
            })?;
            // Writers from another process (a second server on the same data) wait instead of failing.
            c.busy_timeout(Duration::from_secs(10))?;
            c.pragma_update(None, "journal_mode", "WAL")?;
            c.pragma_update(None, "synchronous", "FULL")?;
            Ok(c)
        };
        let mut writer = open()?;
        migrate(&mut writer)?;
        let reader = open()?;
        Ok(Self {
            writer: Mutex::new(writer),
            reader: Mutex::new(reader),
        })
    }

    /// The installed schema version (`PRAGMA user_version`).
    pub fn schema_version(&self) -> Result<i32, StoreError> {
        self.read(|c| Ok(c.query_row("PRAGMA user_version", [], |r| r.get(0))?))
    }

    fn write<T>(
        &self,
        f: impl FnOnce(&mut Connection) -> Result<T, StoreError>,
    ) -> Result<T, StoreError> {
        let mut c = self
            .writer
            .lock()
            .map_err(|_| StoreError::Poisoned("writer"))?;
        f(&mut c)
    }

    fn read<T>(
        &self,
        f: impl FnOnce(&Connection) -> Result<T, StoreError>,
    ) -> Result<T, StoreError> {
        let c = self
            .reader
            .lock()
            .map_err(|_| StoreError::Poisoned("reader"))?;
        f(&c)
    }
}

fn json_col(s: Option<String>, what: &str) -> Result<Option<serde_json::Value>, StoreError> {
    s.map(|s| {
        serde_json::from_str(&s).map_err(|e| StoreError::corrupt(format!("{what} column"), e))
    })
    .transpose()
}

fn row_to_record(row: &rusqlite::Row<'_>) -> rusqlite::Result<Result<JobRecord, StoreError>> {
    let id: String = row.get(0)?;
    let kind: String = row.get(1)?;
    let status: String = row.get(2)?;
    let request: String = row.get(3)?;
    let motion: String = row.get(4)?;
    let progress: f64 = row.get(5)?;
    let result: Option<String> = row.get(6)?;
    let error: Option<String> = row.get(7)?;
    let cancel: i64 = row.get(8)?;
    let attempts: i64 = row.get(9)?;
    let created_ms: i64 = row.get(10)?;
    let started_ms: Option<i64> = row.get(11)?;
    let finished_ms: Option<i64> = row.get(12)?;
    let parent: Option<String> = row.get(13)?;
    let owner: Option<String> = row.get(14)?;
    Ok((|| {
        Ok(JobRecord {
            id: Uuid::parse_str(&id)
                .map_err(|e| StoreError::corrupt("id", format!("{id:?}: {e}")))?,
            kind: JobKind::parse(&kind)?,
            status: JobStatus::parse(&status)?,
            request: json_col(Some(request), "request")?.unwrap_or_default(),
            motion: json_col(Some(motion), "motion")?.unwrap_or_default(),
            progress,
            result,
            error,
            cancel_requested: cancel != 0,
            attempts: u32::try_from(attempts).unwrap_or(u32::MAX),
            created_ms,
            started_ms,
            finished_ms,
            parent: parent
                .map(|p| {
                    Uuid::parse_str(&p)
                        .map_err(|e| StoreError::corrupt("parent", format!("{p:?}: {e}")))
                })
                .transpose()?,
            owner,
        })
    })())
}

impl JobStore for SqliteStore {
    fn insert(&self, job: &NewJob) -> Result<(), StoreError> {
        self.write(|c| {
            c.execute(
                "INSERT INTO jobs (id, kind, status, request, motion, created_ms, owner) VALUES (?1, ?2, 'queued', ?3, ?4, ?5, ?6)",
                params![job.id.to_string(), job.kind.as_str(), job.request.to_string(), job.motion.to_string(), now_ms(), job.owner],
            )?;
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
        self.write(|c| {
            // One statement: the counts and the insert see the same snapshot, and SQLite has
            // one writer at a time (across processes too), so no other insert interleaves.
            // A job without an owner (no tokens) meets only the server's limit.
            let n = c.execute(
                "INSERT INTO jobs (id, kind, status, request, motion, created_ms, owner)
                 SELECT ?1, ?2, 'queued', ?3, ?4, ?5, ?7
                 WHERE (SELECT COUNT(*) FROM jobs WHERE status = 'queued' AND parent IS NULL) < ?6
                   AND (?7 IS NULL OR (SELECT COUNT(*) FROM jobs
                        WHERE status = 'queued' AND parent IS NULL AND owner = ?7 AND kind = ?2) < ?8)",
                params![
                    job.id.to_string(),
                    job.kind.as_str(),
                    job.request.to_string(),
                    job.motion.to_string(),
                    now_ms(),
                    max,
                    job.owner,
                    max_owner
                ],
            )?;
            if n == 1 {
                return Ok(None);
            }
            let (queued, mine): (i64, i64) = c.query_row(
                "SELECT COUNT(*), COALESCE(SUM(owner IS NOT NULL AND owner = ?1 AND kind = ?2), 0)
                 FROM jobs WHERE status = 'queued' AND parent IS NULL",
                params![job.owner, job.kind.as_str()],
                |r| Ok((r.get(0)?, r.get(1)?)),
            )?;
            let n = |v: i64| u64::try_from(v).unwrap_or(0);
            Ok(Some(if queued >= max {
                QueueFull::Server(n(queued))
            } else {
                QueueFull::Owner(n(mine))
            }))
        })
    }

    fn finished_before(&self, cutoff_ms: i64, limit: usize) -> Result<Vec<Uuid>, StoreError> {
        let limit = i64::try_from(limit).unwrap_or(i64::MAX);
        self.read(|c| {
            let mut st = c.prepare(&format!(
                "SELECT id FROM jobs WHERE parent IS NULL AND finished_ms < ?1 AND {}
                 ORDER BY finished_ms LIMIT ?2",
                jobs::terminal_sql()
            ))?;
            let ids: Vec<String> = st
                .query_map(params![cutoff_ms, limit], |r| r.get(0))?
                .collect::<Result<_, _>>()?;
            ids.iter()
                .map(|i| {
                    Uuid::parse_str(i).map_err(|e| StoreError::corrupt("id", format!("{i:?}: {e}")))
                })
                .collect()
        })
    }

    fn delete(&self, id: Uuid) -> Result<DeleteOutcome, StoreError> {
        self.write(|c| {
            let tx = c.transaction()?;
            let status: Option<String> = tx
                .query_row(
                    "SELECT status FROM jobs WHERE id = ?1 AND parent IS NULL",
                    params![id.to_string()],
                    |r| r.get(0),
                )
                .optional()?;
            let Some(status) = status else {
                return Ok(DeleteOutcome::NotFound);
            };
            let status = JobStatus::parse(&status)?;
            if !status.is_terminal() {
                return Ok(DeleteOutcome::NotFinished(status));
            }
            tx.execute(
                "DELETE FROM jobs WHERE parent = ?1 OR id = ?1",
                params![id.to_string()],
            )?;
            tx.commit()?;
            Ok(DeleteOutcome::Deleted)
        })
    }

    fn get(&self, id: Uuid) -> Result<Option<JobRecord>, StoreError> {
        self.read(|c| {
            let sql = format!("SELECT {COLUMNS} FROM jobs WHERE id = ?1");
            c.query_row(&sql, params![id.to_string()], row_to_record)
                .optional()?
                .transpose()
        })
    }

    fn claim(&self) -> Result<Option<JobRecord>, StoreError> {
        self.write(|c| {
            // One statement: atomic even with other processes writing the same file.
            let sql = format!(
                "UPDATE jobs SET {}, started_ms = ?1,
                        progress = CASE WHEN kind = 'pga_search' THEN progress ELSE 0 END
                 WHERE seq = (SELECT seq FROM jobs WHERE {} ORDER BY seq LIMIT 1)
                 RETURNING {COLUMNS}",
                set(&Event::Claim, None),
                jobs::guard(&Event::Claim)
            );
            c.query_row(&sql, params![now_ms()], row_to_record)
                .optional()?
                .transpose()
        })
    }

    fn set_progress(&self, id: Uuid, progress: f64) -> Result<(), StoreError> {
        self.write(|c| {
            c.execute(
                &format!(
                    "UPDATE jobs SET progress = ?2 WHERE id = ?1 AND {}",
                    jobs::guard(&Event::Progress)
                ),
                params![id.to_string(), progress.clamp(0.0, 1.0)],
            )?;
            Ok(())
        })
    }

    fn finish(&self, id: Uuid, finish: &Finish) -> Result<(), StoreError> {
        let end = finish.end();
        let (result, error, progress) = finish.columns();
        let event = Event::Finish(end);
        self.write(|c| {
            let tx = c.transaction()?;
            let n = tx.execute(
                &format!(
                    "UPDATE jobs SET {}, result = ?2, error = ?3, progress = COALESCE(?4, progress), finished_ms = ?5
                     WHERE id = ?1 AND {}",
                    set(&event, None),
                    jobs::guard(&event)
                ),
                params![id.to_string(), result, error, progress, now_ms()],
            )?;
            if n == 1 {
                child_ended(&tx, id, end)?;
            }
            tx.commit()?;
            Ok(())
        })
    }

    fn requeue(&self, id: Uuid, refund: bool) -> Result<(), StoreError> {
        let event = Event::Requeue { refund };
        self.write(|c| {
            c.execute(
                &format!(
                    "UPDATE jobs SET {}, progress = 0, started_ms = NULL WHERE id = ?1 AND {}",
                    set(&event, None),
                    jobs::guard(&event)
                ),
                params![id.to_string()],
            )?;
            Ok(())
        })
    }

    fn request_cancel(&self, id: Uuid) -> Result<CancelOutcome, StoreError> {
        self.write(|c| {
            let tx = c.transaction()?;
            let status: Option<String> = tx
                .query_row(
                    "SELECT status FROM jobs WHERE id = ?1",
                    params![id.to_string()],
                    |r| r.get(0),
                )
                .optional()?;
            let out = jobs::cancel(status.as_deref().map(JobStatus::parse).transpose()?);
            match out {
                // No worker holds a queued job, nor a waiting search: it ends now.
                CancelOutcome::CancelledQueued => {
                    tx.execute(
                        &format!(
                            "UPDATE jobs SET {}, cancel_requested = 1, finished_ms = ?2 WHERE id = ?1",
                            set(&Event::Cancel, Some(JobStatus::Cancelled))
                        ),
                        params![id.to_string(), now_ms()],
                    )?;
                }
                // Its worker stops it within one step.
                CancelOutcome::Requested => {
                    tx.execute(
                        "UPDATE jobs SET cancel_requested = 1 WHERE id = ?1",
                        params![id.to_string()],
                    )?;
                }
                CancelOutcome::AlreadyFinished(_) | CancelOutcome::NotFound => {}
            }
            if jobs::cancel_reaches_children(out) {
                cancel_children(&tx, id)?;
            }
            tx.commit()?;
            Ok(out)
        })
    }

    /// Start-up recovery: every job left running belongs to a server that died (only one
    /// server runs jobs on a file), so each is recovered by [`jobs::recover`].
    fn recover(&self, max_attempts: u32) -> Result<(usize, usize), StoreError> {
        self.write(|c| {
            let tx = c.transaction()?;
            let running: Vec<(i64, i64, bool)> = tx
                .prepare(&format!(
                    "SELECT seq, attempts, cancel_requested != 0 FROM jobs WHERE {} ORDER BY seq",
                    jobs::guard(&Event::Recover(jobs::Recovery::Requeue))
                ))?
                .query_map([], |r| Ok((r.get(0)?, r.get(1)?, r.get(2)?)))?
                .collect::<Result<_, _>>()?;
            let (mut requeued, mut ended) = (0, 0);
            for (seq, attempts, cancel) in running {
                let attempts = u32::try_from(attempts).unwrap_or(u32::MAX);
                let decision =
                    jobs::recover(attempts, max_attempts, cancel, jobs::Abandoned::ServerStopped);
                let set = set(&Event::Recover(decision.clone()), None);
                match decision {
                    jobs::Recovery::Requeue => {
                        tx.execute(
                            &format!("UPDATE jobs SET {set}, progress = 0, started_ms = NULL WHERE seq = ?1"),
                            params![seq],
                        )?;
                        requeued += 1;
                    }
                    jobs::Recovery::Fail(error) => {
                        tx.execute(
                            &format!("UPDATE jobs SET {set}, finished_ms = ?2, error = ?3 WHERE seq = ?1"),
                            params![seq, now_ms(), error],
                        )?;
                        ended += 1;
                    }
                    jobs::Recovery::Cancel => {
                        tx.execute(
                            &format!("UPDATE jobs SET {set}, finished_ms = ?2 WHERE seq = ?1"),
                            params![seq, now_ms()],
                        )?;
                        ended += 1;
                    }
                }
            }
            // Children failed or cancelled above end their searches; and a search whose
            // children all ended is never left waiting.
            let parents: Vec<String> = tx
                .prepare(&format!(
                    "SELECT id FROM jobs WHERE {}",
                    jobs::guard(&Event::Settle(jobs::Settlement::Wait))
                ))?
                .query_map([], |r| r.get(0))?
                .collect::<Result<_, _>>()?;
            for p in parents {
                let p = Uuid::parse_str(&p)
                    .map_err(|e| StoreError::corrupt("id", format!("{p:?}: {e}")))?;
                settle(&tx, p)?;
            }
            tx.commit()?;
            Ok((requeued, ended))
        })
    }

    fn counts(&self) -> Result<Counts, StoreError> {
        self.read(|c| {
            let mut st = c.prepare("SELECT status, COUNT(*) FROM jobs GROUP BY status")?;
            let mut rows = st.query([])?;
            let mut out = Counts::default();
            while let Some(r) = rows.next()? {
                let s: String = r.get(0)?;
                let n: i64 = r.get(1)?;
                let n = u64::try_from(n).unwrap_or(0);
                out.set(JobStatus::parse(&s)?, n);
            }
            Ok(out)
        })
    }

    fn fan_out(&self, id: Uuid, children: &[NewJob], progress: f64) -> Result<bool, StoreError> {
        self.write(|c| {
            let tx = c.transaction()?;
            let n = tx.execute(
                &format!(
                    "UPDATE jobs SET {}, progress = MAX(progress, ?2) WHERE id = ?1 AND {}",
                    set(&Event::FanOut, None),
                    jobs::guard(&Event::FanOut)
                ),
                params![id.to_string(), progress.clamp(0.0, 1.0)],
            )?;
            if n == 0 {
                return Ok(false);
            }
            for ch in children {
                // A child run belongs to its search's owner.
                tx.execute(
                    "INSERT INTO jobs (id, kind, status, request, motion, created_ms, parent, owner)
                     VALUES (?1, ?2, 'queued', ?3, ?4, ?5, ?6, (SELECT owner FROM jobs WHERE id = ?6))",
                    params![ch.id.to_string(), ch.kind.as_str(), ch.request.to_string(), ch.motion.to_string(), now_ms(), id.to_string()],
                )?;
            }
            settle(&tx, id)?;
            tx.commit()?;
            Ok(true)
        })
    }

    fn children(&self, id: Uuid) -> Result<Vec<JobRecord>, StoreError> {
        self.read(|c| {
            let mut st = c.prepare(&format!(
                "SELECT {COLUMNS} FROM jobs WHERE parent = ?1 ORDER BY seq"
            ))?;
            let rows = st.query_map(params![id.to_string()], row_to_record)?;
            let mut out = Vec::new();
            for r in rows {
                out.push(r??);
            }
            Ok(out)
        })
    }

    fn list_owned(
        &self,
        limit: usize,
        kind: Option<JobKind>,
        owner: Option<&str>,
    ) -> Result<Vec<JobRecord>, StoreError> {
        let cols = COLUMNS.replace("request,", "'null',");
        let limit = i64::try_from(limit).unwrap_or(i64::MAX);
        self.read(|c| {
            let mut st = c.prepare(&format!(
                "SELECT {cols} FROM jobs WHERE parent IS NULL AND (?1 IS NULL OR kind = ?1)
                   AND (?3 IS NULL OR owner = ?3) ORDER BY seq DESC LIMIT ?2"
            ))?;
            let rows = st.query_map(
                params![kind.map(JobKind::as_str), limit, owner],
                row_to_record,
            )?;
            let mut out = Vec::new();
            for r in rows {
                out.push(r??);
            }
            Ok(out)
        })
    }
}

/// A job ended (`end`): if it is a child run, add its share to its waiting search's progress
/// and settle the search.
fn child_ended(tx: &rusqlite::Transaction<'_>, id: Uuid, end: jobs::End) -> Result<(), StoreError> {
    let parent: Option<String> = tx
        .query_row(
            "SELECT parent FROM jobs WHERE id = ?1",
            params![id.to_string()],
            |r| r.get(0),
        )
        .optional()?
        .flatten();
    let Some(parent) = parent else {
        return Ok(());
    };
    let parent = Uuid::parse_str(&parent)
        .map_err(|e| StoreError::corrupt("parent", format!("{parent:?}: {e}")))?;
    if end == jobs::End::Succeeded {
        tx.execute(
            &format!(
                "UPDATE jobs SET progress = MIN(?3, progress + COALESCE(
                     (SELECT json_extract(request, '$.progress_step') FROM jobs WHERE id = ?2), 0))
                 WHERE id = ?1 AND {}",
                jobs::guard(&Event::Settle(jobs::Settlement::Wait))
            ),
            params![parent.to_string(), id.to_string(), jobs::CHILD_PROGRESS_CAP],
        )?;
    }
    settle(tx, parent)
}

/// Apply [`jobs::settle`] to a search: read its children's facts, write the decision (a failed
/// search also cancels its other children).
fn settle(tx: &rusqlite::Transaction<'_>, parent: Uuid) -> Result<(), StoreError> {
    let p = parent.to_string();
    let status: Option<String> = tx
        .query_row("SELECT status FROM jobs WHERE id = ?1", params![p], |r| {
            r.get(0)
        })
        .optional()?;
    let status = status.as_deref().map(JobStatus::parse).transpose()?;
    if status
        .and_then(|s| jobs::next(s, &Event::Settle(jobs::Settlement::Wait)))
        .is_none()
    {
        return Ok(());
    }
    let first_bad: Option<(String, Option<String>)> = tx
        .query_row(
            &format!(
                "SELECT status, error FROM jobs WHERE parent = ?1 AND {} ORDER BY seq LIMIT 1",
                jobs::child_bad_sql()
            ),
            params![p],
            |r| Ok((r.get(0)?, r.get(1)?)),
        )
        .optional()?;
    let unfinished: i64 = tx.query_row(
        &format!(
            "SELECT COUNT(*) FROM jobs WHERE parent = ?1 AND {}",
            jobs::child_unfinished_sql()
        ),
        params![p],
        |r| r.get(0),
    )?;
    let children = jobs::Children {
        first_bad: first_bad
            .map(|(s, e)| Ok::<_, StoreError>((JobStatus::parse(&s)?, e)))
            .transpose()?,
        unfinished: u64::try_from(unfinished).unwrap_or(0),
    };
    let decision = jobs::settle(&children);
    let set = set(&Event::Settle(decision.clone()), None);
    match decision {
        jobs::Settlement::Wait => {}
        jobs::Settlement::Requeue => {
            tx.execute(
                &format!("UPDATE jobs SET {set}, started_ms = NULL WHERE id = ?1"),
                params![p],
            )?;
        }
        jobs::Settlement::Fail(error) => {
            tx.execute(
                &format!("UPDATE jobs SET {set}, error = ?2, finished_ms = ?3 WHERE id = ?1"),
                params![p, error, now_ms()],
            )?;
            cancel_children(tx, parent)?;
        }
    }
    Ok(())
}

/// Cancel the unfinished children of a job as [`jobs::cancel`] says: queued ones end at once,
/// running ones get a cancel request.
fn cancel_children(tx: &rusqlite::Transaction<'_>, parent: Uuid) -> Result<(), StoreError> {
    let p = parent.to_string();
    tx.execute(
        &format!(
            "UPDATE jobs SET {}, cancel_requested = 1, finished_ms = ?2 WHERE parent = ?1 AND {}",
            set(&Event::Cancel, Some(JobStatus::Cancelled)),
            jobs::guard_to(&Event::Cancel, JobStatus::Cancelled)
        ),
        params![p, now_ms()],
    )?;
    tx.execute(
        &format!(
            "UPDATE jobs SET cancel_requested = 1 WHERE parent = ?1 AND {}",
            jobs::guard_to(&Event::Cancel, JobStatus::Running)
        ),
        params![p],
    )?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn temp_store() -> (SqliteStore, std::path::PathBuf) {
        let dir = std::env::temp_dir().join(format!("ashlar-store-{}", Uuid::new_v4()));
        std::fs::create_dir_all(&dir).expect("temp dir");
        (
            SqliteStore::open(&dir.join("jobs.sqlite")).expect("open"),
            dir,
        )
    }

    fn job(kind: JobKind) -> NewJob {
        NewJob {
            id: Uuid::new_v4(),
            kind,
            request: serde_json::json!({"a": 1}),
            motion: serde_json::json!({"pga": 2.0}),
            owner: None,
        }
    }

    #[test]
    fn survives_reopen_and_recovers_running_jobs() {
        let (s, dir) = temp_store();
        let a = job(JobKind::Run);
        let b = job(JobKind::Run);
        s.insert(&a).expect("insert");
        s.insert(&b).expect("insert");
        s.claim().expect("claim");
        drop(s); // as if killed: `a` is left running
        let s = SqliteStore::open(&dir.join("jobs.sqlite")).expect("reopen");
        assert_eq!(s.recover(3).expect("recover"), (1, 0));
        let c = s.counts().expect("counts");
        assert_eq!((c.queued, c.running), (2, 0));
        // The requeued job keeps its place at the head of the queue.
        assert_eq!(s.claim().expect("claim").expect("job").id, a.id);
        std::fs::remove_dir_all(dir).ok();
    }
}

/// Databases created before the migrations were numbered must still open.
#[cfg(test)]
mod legacy_schema_tests {
    use super::*;

    /// The schema exactly as the code before numbered migrations built it on open (its
    /// `SCHEMA` constant), without the columns added later: migration 1 is that constant
    /// verbatim, and a released migration never changes.
    const OLD_SCHEMA_V1: &str = MIGRATIONS[0].1;
    /// What that code's open then added (`add_column_if_missing` and the index constants).
    const OLD_PARENT: &str = "ALTER TABLE jobs ADD COLUMN parent TEXT;
CREATE INDEX IF NOT EXISTS jobs_parent ON jobs(parent) WHERE parent IS NOT NULL;";
    const OLD_OWNER: &str = "ALTER TABLE jobs ADD COLUMN owner TEXT;
CREATE INDEX IF NOT EXISTS jobs_owner ON jobs(owner, seq) WHERE owner IS NOT NULL;
CREATE INDEX IF NOT EXISTS jobs_finished ON jobs(finished_ms) WHERE parent IS NULL;";

    fn temp_path(name: &str) -> (std::path::PathBuf, std::path::PathBuf) {
        let dir = std::env::temp_dir().join(format!("ashlar-legacy-{name}-{}", Uuid::new_v4()));
        std::fs::create_dir_all(&dir).expect("temp dir");
        (dir.join("jobs.sqlite"), dir)
    }

    /// Write an old-style file: `ddl`, then one queued and one succeeded job as the old code
    /// inserted them (no user_version set: 0).
    fn old_file(path: &Path, ddl: &[&str]) -> (Uuid, Uuid) {
        let c = Connection::open(path).expect("open raw");
        c.pragma_update(None, "journal_mode", "WAL").expect("wal");
        for d in ddl {
            c.execute_batch(d).expect("old ddl");
        }
        let (q, s) = (Uuid::new_v4(), Uuid::new_v4());
        c.execute(
            "INSERT INTO jobs (id, kind, status, request, motion, created_ms) VALUES (?1, 'run', 'queued', '{\"a\":1}', '{\"pga\":2.0}', 1)",
            params![q.to_string()],
        )
        .expect("insert queued");
        c.execute(
            "INSERT INTO jobs (id, kind, status, request, motion, created_ms, finished_ms, result, progress, attempts)
             VALUES (?1, 'pga_search', 'succeeded', '{}', '{}', 2, 3, '{\"ok\":true}', 1.0, 1)",
            params![s.to_string()],
        )
        .expect("insert done");
        let v: i32 = c
            .query_row("PRAGMA user_version", [], |r| r.get(0))
            .expect("version");
        assert_eq!(v, 0, "old files carry no schema version");
        (q, s)
    }

    fn columns(path: &Path) -> Vec<String> {
        let c = Connection::open(path).expect("open raw");
        let mut st = c
            .prepare("SELECT name FROM pragma_table_info('jobs') ORDER BY cid")
            .expect("prepare");
        st.query_map([], |r| r.get(0))
            .expect("query")
            .collect::<Result<_, _>>()
            .expect("rows")
    }

    /// Open an old file with the new code and use it: its jobs read back, the queue order
    /// holds, a search fans out (needs `parent`), owners are listed (needs `owner`).
    fn opens_and_works(path: &Path, queued: Uuid, done: Uuid) {
        let s = SqliteStore::open(path).expect("the new code opens the old file");
        assert_eq!(s.schema_version().expect("version"), SCHEMA_VERSION);
        let d = s.get(done).expect("get").expect("old finished job");
        assert_eq!(d.status, JobStatus::Succeeded);
        assert_eq!(d.result.as_deref(), Some(r#"{"ok":true}"#));
        assert_eq!((d.parent, d.owner), (None, None));
        let mine = NewJob {
            id: Uuid::new_v4(),
            kind: JobKind::PgaSearch,
            request: serde_json::json!({}),
            motion: serde_json::json!({}),
            owner: Some("aaaa".into()),
        };
        s.insert(&mine).expect("insert new");
        let first = s.claim().expect("claim").expect("the old queued job");
        assert_eq!((first.id, first.attempts), (queued, 1));
        let search = s.claim().expect("claim").expect("the new job");
        assert_eq!(search.id, mine.id);
        let child = NewJob {
            id: Uuid::new_v4(),
            kind: JobKind::PgaRun,
            request: serde_json::json!({"progress_step": 0.5}),
            motion: serde_json::json!({}),
            owner: None,
        };
        assert!(s
            .fan_out(mine.id, std::slice::from_ref(&child), 0.1)
            .expect("fan out"));
        let c = s.get(child.id).expect("get").expect("child");
        assert_eq!(
            (c.parent, c.owner.as_deref()),
            (Some(mine.id), Some("aaaa"))
        );
        assert_eq!(s.list_owned(10, None, Some("aaaa")).expect("list").len(), 1);
        drop(s);
        // Reopening a migrated file changes nothing.
        let s = SqliteStore::open(path).expect("reopen");
        assert_eq!(s.schema_version().expect("version"), SCHEMA_VERSION);
        assert_eq!(s.counts().expect("counts").waiting, 1);
    }

    #[test]
    fn a_file_of_the_last_inline_schema_opens() {
        let (path, dir) = temp_path("v3");
        let (q, d) = old_file(&path, &[OLD_SCHEMA_V1, OLD_PARENT, OLD_OWNER]);
        let before = columns(&path);
        opens_and_works(&path, q, d);
        assert_eq!(columns(&path), before, "no column added or lost");
        std::fs::remove_dir_all(dir).ok();
    }

    #[test]
    fn files_from_before_parent_and_owner_get_both_columns() {
        for (name, ddl) in [
            ("v1", &[OLD_SCHEMA_V1][..]),
            ("v2", &[OLD_SCHEMA_V1, OLD_PARENT][..]),
        ] {
            let (path, dir) = temp_path(name);
            let (q, d) = old_file(&path, ddl);
            opens_and_works(&path, q, d);
            let cols = columns(&path);
            assert_eq!(&cols[cols.len() - 2..], ["parent", "owner"], "{name}");
            std::fs::remove_dir_all(dir).ok();
        }
    }

    #[test]
    fn a_fresh_file_has_the_same_columns_as_a_migrated_old_one() {
        let (fresh, dir) = temp_path("fresh");
        drop(SqliteStore::open(&fresh).expect("open"));
        let (old, dir2) = temp_path("old");
        old_file(&old, &[OLD_SCHEMA_V1, OLD_PARENT, OLD_OWNER]);
        drop(SqliteStore::open(&old).expect("open"));
        assert_eq!(columns(&fresh), columns(&old));
        std::fs::remove_dir_all(dir).ok();
        std::fs::remove_dir_all(dir2).ok();
    }

    #[test]
    fn a_newer_schema_is_refused() {
        let (path, dir) = temp_path("newer");
        drop(SqliteStore::open(&path).expect("open"));
        let c = Connection::open(&path).expect("raw");
        c.pragma_update(None, "user_version", 99).expect("set");
        drop(c);
        let e = match SqliteStore::open(&path) {
            Ok(_) => panic!("a newer schema must be refused"),
            Err(e) => e,
        };
        assert!(
            matches!(&e, StoreError::SchemaNewer { found: 99, .. })
                && e.to_string().contains("upgrade ashlar"),
            "{e}"
        );
        std::fs::remove_dir_all(dir).ok();
    }
}
