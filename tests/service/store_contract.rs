//! The job store contract: one set of behaviour checks, written once over `&dyn JobStore`, run
//! on the embedded store (SQLite) always and on the cluster store (PostgreSQL) when
//! `ASHLAR_TEST_DATABASE_URL` names a server (`tests/pg/run.sh`, CI stage 6; without it the
//! PostgreSQL half prints SKIPPED). Queue order and claims, progress, finish and requeue,
//! cancel of queued and running jobs, recovery with `max_attempts`, the fan-out and settling of
//! a waiting search, quotas and a full queue, listing, retention and delete. What only one
//! store has stays beside it: reopening a SQLite file and its legacy schemas
//! (`store::sqlite`'s unit tests), leases and attempt logs (`pg_cluster`).

use crate::pg_cluster::{base_url, fresh_db};
use crate::service_support::temp_dir;
use ashlar::service::store::postgres::{LeaseParams, PgStore};
use ashlar::service::store::{
    CancelOutcome, DeleteOutcome, Finish, JobKind, JobStatus, JobStore, NewJob, QueueFull,
};
use ashlar::service::SqliteStore;
use serde_json::json;
use std::time::Duration;
use uuid::Uuid;

/// PostgreSQL's lease in these checks: short, so that `expire` (a wait just past it) makes a
/// claim look dead to the reaper; no heartbeat runs here, so a claim lives until then.
const LEASE: Duration = Duration::from_millis(1000);

/// Run `check` on a fresh SQLite store, then on a fresh PostgreSQL database when a server is
/// given; returns the PostgreSQL store for checks of its own. `check`'s second argument makes
/// the running jobs' claims look dead to `recover`: nothing for SQLite (its start-up recovery
/// takes every running job as abandoned), a wait past the lease for PostgreSQL.
fn on_both_stores(test: &str, check: impl Fn(&dyn JobStore, &dyn Fn())) -> Option<PgStore> {
    let dir = temp_dir(&format!("contract-{test}"));
    let sqlite = SqliteStore::open(&dir.join("jobs.sqlite")).expect("open sqlite");
    check(&sqlite, &|| {});
    drop(sqlite);
    std::fs::remove_dir_all(dir).ok();
    let base = base_url(&format!("store_contract::{test} (the PostgreSQL half)"))?;
    let pg = PgStore::open(&fresh_db(&base, "contract"), LeaseParams::with_lease(LEASE))
        .expect("open postgres");
    check(&pg, &|| std::thread::sleep(LEASE + LEASE * 3 / 10));
    Some(pg)
}

fn job(kind: JobKind) -> NewJob {
    NewJob {
        id: Uuid::new_v4(),
        kind,
        request: json!({"a": 1}),
        motion: json!({"pga": 2.0}),
        owner: None,
    }
}

fn owned(kind: JobKind, owner: &str) -> NewJob {
    NewJob {
        owner: Some(owner.into()),
        ..job(kind)
    }
}

fn claims_in_order_and_finish_and_requeue_touch_running_jobs(s: &dyn JobStore, _: &dyn Fn()) {
    let (a, b) = (job(JobKind::Run), job(JobKind::PgaSearch));
    s.insert(&a).expect("insert");
    s.insert(&b).expect("insert");
    // Not running yet: finish and progress change nothing.
    s.finish(a.id, &Finish::Failed("x".into())).expect("finish");
    s.set_progress(a.id, 0.5).expect("progress");
    let r = s.get(a.id).expect("get").expect("job");
    assert_eq!((r.status, r.progress), (JobStatus::Queued, 0.0));
    let first = s.claim().expect("claim").expect("a job");
    assert_eq!(
        (first.id, first.status, first.attempts),
        (a.id, JobStatus::Running, 1)
    );
    assert_eq!(first.request, json!({"a": 1}));
    assert!(first.started_ms.is_some());
    let second = s.claim().expect("claim").expect("a job");
    assert_eq!((second.id, second.kind), (b.id, JobKind::PgaSearch));
    assert!(
        s.claim().expect("claim").is_none(),
        "each job is claimed once"
    );
    assert_eq!(s.counts().expect("counts").running, 2);
    s.set_progress(a.id, 0.5).expect("progress");
    assert_eq!(s.get(a.id).expect("get").expect("job").progress, 0.5);
    // A refunded requeue gives the attempt back; an unrefunded one keeps it.
    s.requeue(a.id, true).expect("requeue");
    let r = s.get(a.id).expect("get").expect("job");
    assert_eq!(
        (r.status, r.attempts, r.progress, r.started_ms),
        (JobStatus::Queued, 0, 0.0, None)
    );
    assert_eq!(s.claim().expect("claim").expect("a again").attempts, 1);
    s.requeue(a.id, false).expect("requeue");
    assert_eq!(s.claim().expect("claim").expect("a again").attempts, 2);
    s.finish(a.id, &Finish::Succeeded(json!({"ok": true})))
        .expect("finish");
    let r = s.get(a.id).expect("get").expect("job");
    assert_eq!((r.status, r.progress), (JobStatus::Succeeded, 1.0));
    assert_eq!(r.result.as_deref(), Some(r#"{"ok":true}"#));
    assert!(r.finished_ms.is_some());
    // A finished job is neither requeued nor finished again.
    s.requeue(a.id, true).expect("requeue");
    s.finish(a.id, &Finish::Failed("late".into()))
        .expect("finish");
    let r = s.get(a.id).expect("get").expect("job");
    assert_eq!(
        (r.status, r.attempts, r.error),
        (JobStatus::Succeeded, 2, None)
    );
    s.finish(b.id, &Finish::Failed("diverged".into()))
        .expect("finish");
    let r = s.get(b.id).expect("get").expect("job");
    assert_eq!(
        (r.status, r.error.as_deref(), r.result),
        (JobStatus::Failed, Some("diverged"), None)
    );
    // The job list of the web page (`GET /v1/jobs`): newest first, filtered by kind, without
    // requests.
    let ids =
        |v: Vec<ashlar::service::store::JobRecord>| v.iter().map(|r| r.id).collect::<Vec<_>>();
    assert_eq!(
        ids(s.list_recent(10, None).expect("list")),
        vec![b.id, a.id]
    );
    assert_eq!(
        ids(s.list_recent(10, Some(JobKind::PgaSearch)).expect("list")),
        vec![b.id]
    );
    assert_eq!(s.list_recent(1, None).expect("list").len(), 1);
    assert_eq!(
        s.list_recent(1, None).expect("list")[0].request,
        json!(null)
    );
}

fn cancel_ends_queued_jobs_and_flags_running_ones(s: &dyn JobStore, _: &dyn Fn()) {
    let q = job(JobKind::Run);
    s.insert(&q).expect("insert");
    assert_eq!(
        s.request_cancel(q.id).expect("cancel"),
        CancelOutcome::CancelledQueued
    );
    let r = s.get(q.id).expect("get").expect("job");
    assert_eq!((r.status, r.cancel_requested), (JobStatus::Cancelled, true));
    assert!(r.finished_ms.is_some());
    assert!(
        s.claim().expect("claim").is_none(),
        "a cancelled job is never claimed"
    );
    let r = job(JobKind::Run);
    s.insert(&r).expect("insert");
    s.claim().expect("claim");
    assert_eq!(
        s.request_cancel(r.id).expect("cancel"),
        CancelOutcome::Requested
    );
    let running = s.get(r.id).expect("get").expect("job");
    assert_eq!(
        (running.status, running.cancel_requested),
        (JobStatus::Running, true)
    );
    s.finish(r.id, &Finish::Cancelled(Some(json!({"partial": true}))))
        .expect("finish");
    let done = s.get(r.id).expect("get").expect("job");
    assert_eq!(done.status, JobStatus::Cancelled);
    assert_eq!(done.result.as_deref(), Some(r#"{"partial":true}"#));
    assert_eq!(
        s.request_cancel(r.id).expect("cancel"),
        CancelOutcome::AlreadyFinished(JobStatus::Cancelled)
    );
    assert_eq!(
        s.request_cancel(Uuid::new_v4()).expect("cancel"),
        CancelOutcome::NotFound
    );
}

fn recovery_requeues_in_place_fails_at_max_attempts_and_honours_cancels(
    s: &dyn JobStore,
    expire: &dyn Fn(),
) {
    let (a, b) = (job(JobKind::Run), job(JobKind::Run));
    s.insert(&a).expect("insert");
    s.insert(&b).expect("insert");
    // max_attempts = 3: the first two lost runs requeue `a`, at the head of the queue (its
    // place by submission order); the third fails it.
    for attempt in 1..=2 {
        let c = s.claim().expect("claim").expect("a");
        assert_eq!((c.id, c.attempts), (a.id, attempt));
        expire();
        assert_eq!(s.recover(3).expect("recover"), (1, 0));
        let c = s.counts().expect("counts");
        assert_eq!((c.queued, c.running), (2, 0));
    }
    assert_eq!(s.claim().expect("claim").expect("a").attempts, 3);
    expire();
    assert_eq!(s.recover(3).expect("recover"), (0, 1));
    let r = s.get(a.id).expect("get").expect("a");
    assert_eq!(r.status, JobStatus::Failed);
    assert!(r.error.unwrap_or_default().contains("3 times"));
    assert!(r.finished_ms.is_some());
    // A cancel requested before the run was lost wins over the attempts limit.
    assert_eq!(s.claim().expect("claim").expect("b").id, b.id);
    s.request_cancel(b.id).expect("cancel");
    expire();
    assert_eq!(s.recover(1).expect("recover"), (0, 1));
    let r = s.get(b.id).expect("get").expect("b");
    assert_eq!((r.status, r.error), (JobStatus::Cancelled, None));
    assert_eq!(s.recover(3).expect("nothing left"), (0, 0));
}

fn quotas_listing_retention_and_delete(s: &dyn JobStore, _: &dyn Fn()) {
    let mine = |kind| owned(kind, "aaaa");
    assert_eq!(s.insert_quota(&mine(JobKind::Run), 10, 2).expect("i"), None);
    assert_eq!(s.insert_quota(&mine(JobKind::Run), 10, 2).expect("i"), None);
    assert_eq!(
        s.insert_quota(&mine(JobKind::Run), 10, 2).expect("i"),
        Some(QueueFull::Owner(2))
    );
    // Another kind, another owner, no owner: their own counts.
    assert_eq!(
        s.insert_quota(&mine(JobKind::PgaSearch), 10, 2).expect("i"),
        None
    );
    let theirs = owned(JobKind::Run, "bbbb");
    assert_eq!(s.insert_quota(&theirs, 10, 2).expect("i"), None);
    assert_eq!(s.insert_quota(&job(JobKind::Run), 10, 0).expect("i"), None);
    assert_eq!(
        s.insert_quota(&owned(JobKind::Run, "bbbb"), 5, 2)
            .expect("i"),
        Some(QueueFull::Server(5))
    );
    assert_eq!(
        s.insert_bounded(&job(JobKind::Run), 5).expect("i"),
        Some(5),
        "the queue is full"
    );
    assert_eq!(s.list_owned(10, None, Some("aaaa")).expect("list").len(), 3);
    let b = s.list_owned(10, None, Some("bbbb")).expect("list");
    assert_eq!(b.len(), 1);
    assert_eq!(b[0].owner.as_deref(), Some("bbbb"));
    assert_eq!(s.list_recent(10, None).expect("list").len(), 5);
    // Retention lists a finished top-level job that ended before the cutoff; only a finished
    // job is deleted, and then it is gone.
    assert!(s
        .finished_before(i64::MAX, 10)
        .expect("finished")
        .is_empty());
    assert_eq!(
        s.delete(theirs.id).expect("delete"),
        DeleteOutcome::NotFinished(JobStatus::Queued)
    );
    s.request_cancel(theirs.id).expect("cancel");
    assert_eq!(
        s.finished_before(i64::MAX, 10).expect("finished"),
        vec![theirs.id]
    );
    assert!(s.finished_before(0, 10).expect("finished").is_empty());
    assert_eq!(s.delete(theirs.id).expect("delete"), DeleteOutcome::Deleted);
    assert!(s.get(theirs.id).expect("get").is_none());
    assert_eq!(
        s.delete(theirs.id).expect("delete"),
        DeleteOutcome::NotFound
    );
    assert_eq!(s.counts().expect("counts").queued, 4);
}

fn a_full_queue_admits_exactly_its_limit_under_concurrency(s: &dyn JobStore, _: &dyn Fn()) {
    let accepted = std::sync::atomic::AtomicUsize::new(0);
    std::thread::scope(|sc| {
        for _ in 0..12 {
            sc.spawn(|| {
                for _ in 0..5 {
                    if s.insert_bounded(&job(JobKind::Run), 20)
                        .expect("insert")
                        .is_none()
                    {
                        accepted.fetch_add(1, std::sync::atomic::Ordering::SeqCst);
                    }
                }
            });
        }
    });
    assert_eq!(accepted.into_inner(), 20);
    assert_eq!(s.counts().expect("counts").queued, 20);
}

fn child(parent: Uuid, pga: f64, step: f64) -> NewJob {
    NewJob {
        id: Uuid::new_v4(),
        kind: JobKind::PgaRun,
        request: json!({"parent": parent, "record": 0, "pga": pga, "pga_bits": pga.to_bits(),
                        "width": 2, "progress_step": step}),
        motion: json!({"pga": pga}),
        owner: None,
    }
}

fn new_search() -> NewJob {
    NewJob {
        id: Uuid::new_v4(),
        kind: JobKind::PgaSearch,
        request: json!({"a": 1}),
        motion: json!({"pga": 1.0}),
        owner: None,
    }
}

fn status_of(s: &dyn JobStore, id: Uuid) -> JobStatus {
    s.get(id).expect("get").expect("job").status
}

/// The fan-out contract every [`JobStore`] keeps: waiting, children, requeue of the search by
/// its last child (same transaction), a failed child failing the search, cancel cascading to
/// children, and recovery of children that keep dying. `expire` makes the running jobs'
/// claims look dead to `recover` (a restart for SQLite, an expired lease for PostgreSQL).
fn fan_out_and_settle(s: &dyn JobStore, expire: &dyn Fn()) {
    let p = new_search();
    s.insert(&p).expect("insert");
    let claimed = s.claim().expect("claim").expect("the search");
    assert_eq!(
        (claimed.id, claimed.attempts, claimed.parent),
        (p.id, 1, None)
    );
    let (c1, c2) = (child(p.id, 1.0, 0.25), child(p.id, 2.0, 0.25));
    assert!(s
        .fan_out(p.id, &[c1.clone(), c2.clone()], 0.2)
        .expect("fan out"));
    let w = s.get(p.id).expect("get").expect("job");
    // Waiting gives the claim back: waiting is not a crash, max_attempts must not count it.
    assert_eq!(
        (w.status, w.attempts, w.progress),
        (JobStatus::Waiting, 0, 0.2)
    );
    assert_eq!(s.counts().expect("counts").waiting, 1);
    assert!(
        !s.fan_out(p.id, &[child(p.id, 3.0, 0.1)], 0.3)
            .expect("fan out"),
        "a waiting search cannot fan out again"
    );
    let kids = s.children(p.id).expect("children");
    assert_eq!(
        kids.iter()
            .map(|k| (k.id, k.kind, k.parent, k.status))
            .collect::<Vec<_>>(),
        vec![
            (c1.id, JobKind::PgaRun, Some(p.id), JobStatus::Queued),
            (c2.id, JobKind::PgaRun, Some(p.id), JobStatus::Queued)
        ]
    );
    assert_eq!(kids[0].request["pga_bits"], json!(1.0f64.to_bits()));
    // Children never show in the job list.
    let listed: Vec<Uuid> = s
        .list_recent(10, None)
        .expect("list")
        .iter()
        .map(|j| j.id)
        .collect();
    assert_eq!(listed, vec![p.id]);
    assert!(s
        .list_recent(10, Some(JobKind::PgaRun))
        .expect("list")
        .is_empty());

    // The waiting search is not claimable; its children are, in order.
    assert_eq!(s.claim().expect("claim").expect("c1").id, c1.id);
    s.finish(
        c1.id,
        &Finish::Succeeded(json!({"pga": 1.0, "failed": false})),
    )
    .expect("finish");
    let w = s.get(p.id).expect("get").expect("job");
    assert_eq!(w.status, JobStatus::Waiting, "one child still runs");
    assert!(
        (w.progress - 0.45).abs() < 1e-12,
        "progress + the child's share: {}",
        w.progress
    );
    assert_eq!(s.claim().expect("claim").expect("c2").id, c2.id);
    s.finish(
        c2.id,
        &Finish::Succeeded(json!({"pga": 2.0, "failed": true})),
    )
    .expect("finish");
    // The last child queued the search again, and it is claimable at once.
    assert_eq!(status_of(s, p.id), JobStatus::Queued);
    let again = s.claim().expect("claim").expect("the search again");
    assert_eq!((again.id, again.attempts), (p.id, 1));
    let kids = s.children(p.id).expect("children");
    assert_eq!(
        kids[1].result.as_deref(),
        Some(r#"{"failed":true,"pga":2.0}"#)
    );
    // Fanning out nothing new while every child has ended queues the search straight away.
    assert!(s.fan_out(p.id, &[], 0.5).expect("fan out"));
    assert_eq!(status_of(s, p.id), JobStatus::Queued);
    assert_eq!(s.claim().expect("claim").expect("search").id, p.id);

    // A failed child fails its search with the child's error and cancels its siblings.
    let (c3, c4) = (child(p.id, 1.5, 0.1), child(p.id, 1.75, 0.1));
    assert!(s
        .fan_out(p.id, &[c3.clone(), c4.clone()], 0.6)
        .expect("fan out"));
    assert_eq!(s.claim().expect("claim").expect("c3").id, c3.id);
    s.finish(c3.id, &Finish::Failed("simulation diverged at 1.5".into()))
        .expect("finish");
    let f = s.get(p.id).expect("get").expect("job");
    assert_eq!(f.status, JobStatus::Failed);
    assert_eq!(f.error.as_deref(), Some("simulation diverged at 1.5"));
    assert!(f.finished_ms.is_some());
    assert_eq!(status_of(s, c4.id), JobStatus::Cancelled);
    assert!(s.claim().expect("claim").is_none());

    // Cancelling a waiting search ends it at once and cancels its children: queued ones at
    // once, running ones by request (their end then changes nothing).
    let q = new_search();
    s.insert(&q).expect("insert");
    s.claim().expect("claim").expect("q");
    let (d1, d2) = (child(q.id, 1.0, 0.5), child(q.id, 2.0, 0.5));
    assert!(s
        .fan_out(q.id, &[d1.clone(), d2.clone()], 0.0)
        .expect("fan out"));
    assert_eq!(s.claim().expect("claim").expect("d1").id, d1.id);
    assert_eq!(
        s.request_cancel(q.id).expect("cancel"),
        CancelOutcome::CancelledQueued
    );
    assert_eq!(status_of(s, q.id), JobStatus::Cancelled);
    assert_eq!(status_of(s, d2.id), JobStatus::Cancelled);
    let r1 = s.get(d1.id).expect("get").expect("d1");
    assert_eq!((r1.status, r1.cancel_requested), (JobStatus::Running, true));
    s.finish(d1.id, &Finish::Cancelled(None)).expect("finish");
    assert_eq!(status_of(s, q.id), JobStatus::Cancelled);
    assert_eq!(
        s.request_cancel(q.id).expect("cancel"),
        CancelOutcome::AlreadyFinished(JobStatus::Cancelled)
    );

    // A child whose worker keeps dying fails after max_attempts, and fails its search.
    let r = new_search();
    s.insert(&r).expect("insert");
    s.claim().expect("claim").expect("r");
    let e1 = child(r.id, 1.0, 0.5);
    assert!(s
        .fan_out(r.id, std::slice::from_ref(&e1), 0.0)
        .expect("fan out"));
    assert_eq!(s.claim().expect("claim").expect("e1").id, e1.id);
    expire();
    assert_eq!(s.recover(1).expect("recover"), (0, 1));
    let rr = s.get(r.id).expect("get").expect("r");
    assert_eq!(rr.status, JobStatus::Failed);
    assert!(
        rr.error.unwrap_or_default().contains("1 times"),
        "the child's error"
    );
    assert_eq!(s.counts().expect("counts").waiting, 0);
}

#[test]
fn claims_in_order_and_finish_and_requeue_touch_running_jobs_on_both_stores() {
    on_both_stores(
        "claims",
        claims_in_order_and_finish_and_requeue_touch_running_jobs,
    );
}

#[test]
fn cancel_ends_queued_jobs_and_flags_running_ones_on_both_stores() {
    on_both_stores("cancel", cancel_ends_queued_jobs_and_flags_running_ones);
}

#[test]
fn recovery_requeues_in_place_fails_at_max_attempts_and_honours_cancels_on_both_stores() {
    on_both_stores(
        "recover",
        recovery_requeues_in_place_fails_at_max_attempts_and_honours_cancels,
    );
}

#[test]
fn quotas_listing_retention_and_delete_on_both_stores() {
    on_both_stores("quotas", quotas_listing_retention_and_delete);
}

#[test]
fn a_full_queue_admits_exactly_its_limit_under_concurrency_on_both_stores() {
    on_both_stores(
        "bounded",
        a_full_queue_admits_exactly_its_limit_under_concurrency,
    );
}

#[test]
fn fan_out_and_settle_on_both_stores() {
    let Some(pg) = on_both_stores("fanout", fan_out_and_settle) else {
        return;
    };
    // PostgreSQL logs every claim; a search parked for its children ends its attempt
    // `waiting`.
    let outcomes: Vec<Option<String>> = pg
        .attempts_of(pg.list_recent(10, Some(JobKind::PgaSearch)).expect("list")[2].id)
        .expect("attempts")
        .into_iter()
        .map(|(_, o)| o)
        .collect();
    assert_eq!(outcomes, vec![Some("waiting".into()); 3]);
}
