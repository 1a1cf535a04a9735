//! Service: the job state machine, once. Both job stores (`store::sqlite`, `store::postgres`)
//! ask this module what a job becomes and apply the answer in their own SQL; it knows no
//! database, no worker and no HTTP (imports go worker → jobs → store types, store → jobs).
//!
//! ```text
//!            claim             finish
//!   queued ─────────▶ running ─────────▶ succeeded | failed | cancelled
//!     ▲  ▲              │ │ │
//!     │  └── requeue ───┘ │ └── recover: requeue | fail | cancel  (server died, lease expired)
//!     │                   │ fan_out (attempts − 1)
//!     │  settle: requeue  ▼
//!     └────────────── waiting ── settle: fail ──▶ failed
//!   cancel: queued | waiting ──▶ cancelled; running ──▶ running with a cancel request
//! ```
//!
//! [`transition`] is the transition table (the status after an event and its effect on the
//! attempts count); the deciders ([`cancel`], [`settle`], [`recover`]) turn the facts a store
//! read into the event it applies; [`guard`] / [`guard_to`] give the SQL condition on the
//! current status under which an event applies and [`effect`] what it writes (the stores'
//! `SET`, `store::set_sql`), both generated from the table, so that every
//! `UPDATE … SET status … WHERE status …` of both stores is the table's own.
//!
//! Just over 600 lines: about 280 of code and docs; its tests (the whole table written out
//! cell by cell, each decider) make up the rest.
use serde::Serialize;

/// Life cycle: `queued → running → succeeded | failed | cancelled`; `running → queued` when a
/// server stops (or dies) while the job runs; `running → waiting → queued` when a fanned-out
/// search waits for its child runs (no worker holds it meanwhile; the end of its last child
/// queues it again).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum JobStatus {
    Queued,
    Running,
    Succeeded,
    Failed,
    Cancelled,
    /// A search parked until its child runs end (see [`JobStore::fan_out`]).
    Waiting,
}

impl JobStatus {
    pub fn as_str(self) -> &'static str {
        match self {
            JobStatus::Queued => "queued",
            JobStatus::Running => "running",
            JobStatus::Succeeded => "succeeded",
            JobStatus::Failed => "failed",
            JobStatus::Cancelled => "cancelled",
            JobStatus::Waiting => "waiting",
        }
    }
    /// No further change can happen.
    pub fn is_terminal(self) -> bool {
        matches!(
            self,
            JobStatus::Succeeded | JobStatus::Failed | JobStatus::Cancelled
        )
    }
}

/// What `request_cancel` did.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum CancelOutcome {
    /// The job was queued and is now cancelled.
    CancelledQueued,
    /// The job is running; its worker will stop it within one step.
    Requested,
    /// The job had already finished with this status; nothing changed.
    AlreadyFinished(JobStatus),
    NotFound,
}

/// Every status, in the order of [`JobStatus`]'s declaration.
pub const ALL: [JobStatus; 6] = [
    JobStatus::Queued,
    JobStatus::Running,
    JobStatus::Succeeded,
    JobStatus::Failed,
    JobStatus::Cancelled,
    JobStatus::Waiting,
];

/// How a running job ended (the status half of `store::Finish`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum End {
    Succeeded,
    Failed,
    Cancelled,
}

impl End {
    pub fn status(self) -> JobStatus {
        match self {
            End::Succeeded => JobStatus::Succeeded,
            End::Failed => JobStatus::Failed,
            End::Cancelled => JobStatus::Cancelled,
        }
    }
}

/// What [`settle`] decided for a waiting search.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Settlement {
    /// Some child runs are still queued or running: keep waiting.
    Wait,
    /// Every child ended well: back to the queue, where a worker replays the search from its
    /// children's results.
    Requeue,
    /// A child failed or was cancelled: the search fails with this error and its other
    /// children are cancelled.
    Fail(String),
}

/// What [`recover`] decided for a running job whose run was abandoned (the embedded server
/// died with it; a cluster worker's lease expired).
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Recovery {
    /// Back to the head of the queue (its place by submission order), progress reset.
    Requeue,
    /// Started too often: fail it with this error (a job that keeps killing its server must
    /// not keep killing it).
    Fail(String),
    /// A cancel was requested before the run was lost: honour it rather than rerun the job.
    Cancel,
}

/// Something that happens to a job.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Event {
    /// A worker takes the job (attempts + 1).
    Claim,
    /// The worker holding it records progress.
    Progress,
    /// The worker holding it records the end.
    Finish(End),
    /// The worker holding it gives it back (graceful shutdown); `refund` gives back the
    /// attempt.
    Requeue { refund: bool },
    /// A search parks itself until its child runs end, giving its claim back (attempts − 1:
    /// waiting is not a crash).
    FanOut,
    /// The user cancels it (or its search is cancelled or failed).
    Cancel,
    /// A waiting search's children changed.
    Settle(Settlement),
    /// Its run was abandoned.
    Recover(Recovery),
}

/// What an event does to the attempts count (how many times a worker has started the job).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Attempts {
    Keep,
    /// A worker starts the job.
    Increment,
    /// The start is given back (a refunded requeue; a fan-out: waiting is not a crash), never
    /// below zero.
    Decrement,
}

impl Attempts {
    /// The count after the effect.
    pub fn apply(self, attempts: u32) -> u32 {
        match self {
            Attempts::Keep => attempts,
            Attempts::Increment => attempts.saturating_add(1),
            Attempts::Decrement => attempts.saturating_sub(1),
        }
    }
}

/// One cell of the transition table: the status after the event and its effect on attempts.
/// The stores write both from it (`store::set_sql`), so each `SET status = …, attempts = …`
/// of theirs is the table's own.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Transition {
    pub to: JobStatus,
    pub attempts: Attempts,
}

/// The transition table: what becomes of a job in `from` after `event`, or `None` when the
/// event does not apply (the store then changes nothing). A cancel of a running job leaves it
/// running with a cancel request: its worker stops it within one step and finishes it
/// `cancelled`.
pub fn transition(from: JobStatus, event: &Event) -> Option<Transition> {
    use Attempts::{Decrement, Increment, Keep};
    use JobStatus as S;
    let (to, attempts) = match (from, event) {
        (S::Queued, Event::Claim) => (S::Running, Increment),
        (S::Running, Event::Progress) => (S::Running, Keep),
        (S::Running, Event::Finish(end)) => (end.status(), Keep),
        (S::Running, Event::Requeue { refund: true }) => (S::Queued, Decrement),
        (S::Running, Event::Requeue { refund: false }) => (S::Queued, Keep),
        (S::Running, Event::FanOut) => (S::Waiting, Decrement),
        (S::Queued | S::Waiting, Event::Cancel) => (S::Cancelled, Keep),
        (S::Running, Event::Cancel) => (S::Running, Keep),
        (S::Waiting, Event::Settle(s)) => (
            match s {
                Settlement::Wait => S::Waiting,
                Settlement::Requeue => S::Queued,
                Settlement::Fail(_) => S::Failed,
            },
            Keep,
        ),
        (S::Running, Event::Recover(r)) => (
            match r {
                Recovery::Requeue => S::Queued,
                Recovery::Fail(_) => S::Failed,
                Recovery::Cancel => S::Cancelled,
            },
            Keep,
        ),
        _ => return None,
    };
    Some(Transition { to, attempts })
}

/// The status a job in `from` has after `event` ([`transition`]'s `to`).
pub fn next(from: JobStatus, event: &Event) -> Option<JobStatus> {
    transition(from, event).map(|t| t.to)
}

/// The transition `event` makes from the statuses [`guard_to`]`(event, to)` selects, or from
/// every status it applies to when `to` is `None` (they then agree: every event but a cancel
/// has one target and one attempts effect, see the tests). `None`: it applies to no status.
pub fn effect(event: &Event, to: Option<JobStatus>) -> Option<Transition> {
    ALL.into_iter()
        .filter_map(|s| transition(s, event))
        .find(|t| to.is_none_or(|to| t.to == to))
}

/// The attempts count after `event` (how many times a worker has started the job).
pub fn attempts_after(event: &Event, attempts: u32) -> u32 {
    effect(event, None).map_or(attempts, |t| t.attempts.apply(attempts))
}

/// The statuses `event` applies to.
pub fn sources(event: &Event) -> Vec<JobStatus> {
    ALL.into_iter()
        .filter(|&s| next(s, event).is_some())
        .collect()
}

/// SQL condition (both dialects) on the `status` column: the statuses `event` applies to,
/// e.g. `status IN ('running')`.
pub fn guard(event: &Event) -> String {
    status_in(&sources(event))
}

/// SQL condition on `status`: the statuses `event` takes to `to` (e.g. a cancel ends a queued
/// or waiting job at once, and only flags a running one).
pub fn guard_to(event: &Event, to: JobStatus) -> String {
    let from: Vec<JobStatus> = ALL
        .into_iter()
        .filter(|&s| next(s, event) == Some(to))
        .collect();
    status_in(&from)
}

fn status_in(statuses: &[JobStatus]) -> String {
    let list: Vec<String> = statuses
        .iter()
        .map(|s| format!("'{}'", s.as_str()))
        .collect();
    format!("status IN ({})", list.join(", "))
}

/// What a cancel request does to a job in `status` (`None`: no such job).
pub fn cancel(status: Option<JobStatus>) -> CancelOutcome {
    let Some(status) = status else {
        return CancelOutcome::NotFound;
    };
    match next(status, &Event::Cancel) {
        Some(JobStatus::Cancelled) => CancelOutcome::CancelledQueued,
        Some(_) => CancelOutcome::Requested,
        None => CancelOutcome::AlreadyFinished(status),
    }
}

/// Whether a cancel that did `outcome` also cancels the job's children (a search's runs):
/// whenever it changed the job.
pub fn cancel_reaches_children(outcome: CancelOutcome) -> bool {
    matches!(
        outcome,
        CancelOutcome::CancelledQueued | CancelOutcome::Requested
    )
}

/// What a store knows of a waiting search's children.
#[derive(Debug, Clone, PartialEq, Eq, Default)]
pub struct Children {
    /// The first child (in submission order) that failed or was cancelled: its status and
    /// error.
    pub first_bad: Option<(JobStatus, Option<String>)>,
    /// Children still queued or running.
    pub unfinished: u64,
}

/// Statuses of a child that ended badly, and of one not yet ended ([`Children`]).
pub const CHILD_BAD: [JobStatus; 2] = [JobStatus::Failed, JobStatus::Cancelled];
pub const CHILD_UNFINISHED: [JobStatus; 2] = [JobStatus::Queued, JobStatus::Running];

/// SQL condition on `status`: the job has ended (no event applies to it any more).
pub fn terminal_sql() -> String {
    let ended: Vec<JobStatus> = ALL.into_iter().filter(|s| s.is_terminal()).collect();
    status_in(&ended)
}

/// SQL condition on `status` for [`CHILD_BAD`] / [`CHILD_UNFINISHED`].
pub fn child_bad_sql() -> String {
    status_in(&CHILD_BAD)
}
pub fn child_unfinished_sql() -> String {
    status_in(&CHILD_UNFINISHED)
}

/// Settle a waiting search from its children: a failed (or cancelled) child fails it with
/// the child's error; when no child is left unfinished it goes back to the queue.
pub fn settle(children: &Children) -> Settlement {
    if let Some((status, error)) = &children.first_bad {
        return Settlement::Fail(child_error(status.as_str(), error.clone()));
    }
    if children.unfinished == 0 {
        Settlement::Requeue
    } else {
        Settlement::Wait
    }
}

/// A succeeded child adds its share (its request's `progress_step`) to its waiting search's
/// progress, up to this: the search reaches 1 only when its replay succeeds.
pub const CHILD_PROGRESS_CAP: f64 = 0.99;

/// The error a search fails with when one of its child runs ended `status` with `error`.
pub fn child_error(status: &str, error: Option<String>) -> String {
    match (status, error) {
        (_, Some(e)) => e,
        ("cancelled", None) => "a run of the search was cancelled".into(),
        (_, None) => "a run of the search failed".into(),
    }
}

/// Who lost an abandoned run: the words of [`Recovery::Fail`]'s error.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Abandoned {
    /// The embedded store's server stopped (crashed, killed) while running the job.
    ServerStopped,
    /// A cluster worker's lease expired (the worker died or was cut off).
    WorkerDied,
}

/// What becomes of a running job whose run was abandoned, started `attempts` times, at most
/// `max_attempts` allowed, with or without a cancel request. A requested cancel wins: the
/// user asked the job to stop, so it ends cancelled rather than failed or rerun.
pub fn recover(
    attempts: u32,
    max_attempts: u32,
    cancel_requested: bool,
    who: Abandoned,
) -> Recovery {
    if cancel_requested {
        Recovery::Cancel
    } else if attempts >= max_attempts {
        Recovery::Fail(match who {
            Abandoned::ServerStopped => format!(
                "the server stopped {attempts} times while running this job; not retried again"
            ),
            Abandoned::WorkerDied => {
                format!("the worker running this job died {attempts} times; not retried again")
            }
        })
    } else {
        Recovery::Requeue
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use JobStatus as S;

    fn events() -> Vec<Event> {
        vec![
            Event::Claim,
            Event::Progress,
            Event::Finish(End::Succeeded),
            Event::Finish(End::Failed),
            Event::Finish(End::Cancelled),
            Event::Requeue { refund: false },
            Event::Requeue { refund: true },
            Event::FanOut,
            Event::Cancel,
            Event::Settle(Settlement::Wait),
            Event::Settle(Settlement::Requeue),
            Event::Settle(Settlement::Fail("x".into())),
            Event::Recover(Recovery::Requeue),
            Event::Recover(Recovery::Fail("x".into())),
            Event::Recover(Recovery::Cancel),
        ]
    }

    /// The whole table, written out by hand as the life cycle in the module's doc and
    /// `JobStatus`'s doc state it, compared cell by cell with [`next`].
    #[test]
    fn every_transition_is_the_documented_one() {
        let expected = |from: S, e: &Event| -> Option<S> {
            match e {
                Event::Claim => (from == S::Queued).then_some(S::Running),
                Event::Progress => (from == S::Running).then_some(S::Running),
                Event::Finish(End::Succeeded) => (from == S::Running).then_some(S::Succeeded),
                Event::Finish(End::Failed) => (from == S::Running).then_some(S::Failed),
                Event::Finish(End::Cancelled) => (from == S::Running).then_some(S::Cancelled),
                Event::Requeue { .. } => (from == S::Running).then_some(S::Queued),
                Event::FanOut => (from == S::Running).then_some(S::Waiting),
                Event::Cancel => match from {
                    S::Queued | S::Waiting => Some(S::Cancelled),
                    S::Running => Some(S::Running),
                    _ => None,
                },
                Event::Settle(Settlement::Wait) => (from == S::Waiting).then_some(S::Waiting),
                Event::Settle(Settlement::Requeue) => (from == S::Waiting).then_some(S::Queued),
                Event::Settle(Settlement::Fail(_)) => (from == S::Waiting).then_some(S::Failed),
                Event::Recover(Recovery::Requeue) => (from == S::Running).then_some(S::Queued),
                Event::Recover(Recovery::Fail(_)) => (from == S::Running).then_some(S::Failed),
                Event::Recover(Recovery::Cancel) => (from == S::Running).then_some(S::Cancelled),
            }
        };
        let mut cells = 0;
        for from in ALL {
            for e in events() {
                assert_eq!(next(from, &e), expected(from, &e), "{from:?} on {e:?}");
                cells += 1;
            }
        }
        assert_eq!(cells, 6 * 15);
    }

    /// One `SET` per event: every event but a cancel makes the same transition (target status
    /// and attempts effect) from every status it applies to, so [`effect`] is the whole of it;
    /// a cancel's two targets are told apart by [`guard_to`].
    #[test]
    fn each_event_has_one_effect_but_cancel_two() {
        for e in events() {
            let cells: Vec<Transition> =
                ALL.into_iter().filter_map(|s| transition(s, &e)).collect();
            assert!(!cells.is_empty(), "{e:?} applies to no status");
            if e == Event::Cancel {
                assert_eq!(
                    effect(&e, Some(S::Cancelled)).map(|t| t.to),
                    Some(S::Cancelled)
                );
                assert_eq!(effect(&e, Some(S::Running)).map(|t| t.to), Some(S::Running));
                continue;
            }
            assert!(cells.iter().all(|t| *t == cells[0]), "{e:?}: {cells:?}");
            assert_eq!(effect(&e, None), Some(cells[0]), "{e:?}");
        }
        assert_eq!(
            effect(&Event::Claim, None).map(|t| t.attempts),
            Some(Attempts::Increment)
        );
        assert_eq!(
            effect(&Event::FanOut, None).map(|t| t.attempts),
            Some(Attempts::Decrement)
        );
    }

    #[test]
    fn terminal_statuses_never_change() {
        for from in ALL.into_iter().filter(|s| s.is_terminal()) {
            for e in events() {
                assert_eq!(next(from, &e), None, "{from:?} on {e:?}");
            }
        }
    }

    #[test]
    fn attempts_count_claims_and_refunds_never_below_zero() {
        assert_eq!(attempts_after(&Event::Claim, 0), 1);
        assert_eq!(attempts_after(&Event::Claim, u32::MAX), u32::MAX);
        assert_eq!(attempts_after(&Event::Requeue { refund: true }, 2), 1);
        assert_eq!(attempts_after(&Event::Requeue { refund: true }, 0), 0);
        assert_eq!(attempts_after(&Event::Requeue { refund: false }, 2), 2);
        assert_eq!(attempts_after(&Event::FanOut, 1), 0);
        assert_eq!(attempts_after(&Event::FanOut, 0), 0);
        for e in [
            Event::Progress,
            Event::Finish(End::Failed),
            Event::Cancel,
            Event::Settle(Settlement::Requeue),
            Event::Recover(Recovery::Requeue),
        ] {
            assert_eq!(attempts_after(&e, 3), 3, "{e:?}");
        }
    }

    #[test]
    fn guards_are_the_tables_sources() {
        assert_eq!(guard(&Event::Claim), "status IN ('queued')");
        assert_eq!(guard(&Event::Finish(End::Failed)), "status IN ('running')");
        assert_eq!(guard(&Event::FanOut), "status IN ('running')");
        assert_eq!(
            guard(&Event::Cancel),
            "status IN ('queued', 'running', 'waiting')"
        );
        assert_eq!(
            guard_to(&Event::Cancel, S::Cancelled),
            "status IN ('queued', 'waiting')"
        );
        assert_eq!(
            guard_to(&Event::Cancel, S::Running),
            "status IN ('running')"
        );
        assert_eq!(
            guard(&Event::Settle(Settlement::Requeue)),
            "status IN ('waiting')"
        );
        assert_eq!(child_bad_sql(), "status IN ('failed', 'cancelled')");
        assert_eq!(
            terminal_sql(),
            "status IN ('succeeded', 'failed', 'cancelled')"
        );
        assert_eq!(child_unfinished_sql(), "status IN ('queued', 'running')");
    }

    #[test]
    fn cancel_ends_queued_and_waiting_flags_running_leaves_finished() {
        assert_eq!(cancel(None), CancelOutcome::NotFound);
        assert_eq!(cancel(Some(S::Queued)), CancelOutcome::CancelledQueued);
        assert_eq!(cancel(Some(S::Waiting)), CancelOutcome::CancelledQueued);
        assert_eq!(cancel(Some(S::Running)), CancelOutcome::Requested);
        for s in [S::Succeeded, S::Failed, S::Cancelled] {
            assert_eq!(cancel(Some(s)), CancelOutcome::AlreadyFinished(s));
            assert!(!cancel_reaches_children(cancel(Some(s))));
        }
        assert!(cancel_reaches_children(CancelOutcome::CancelledQueued));
        assert!(cancel_reaches_children(CancelOutcome::Requested));
        assert!(!cancel_reaches_children(CancelOutcome::NotFound));
    }

    #[test]
    fn settle_fails_on_the_first_bad_child_else_waits_for_the_last() {
        let waiting = Children {
            first_bad: None,
            unfinished: 2,
        };
        assert_eq!(settle(&waiting), Settlement::Wait);
        assert_eq!(settle(&Children::default()), Settlement::Requeue);
        // A bad child fails the search even while others are still running.
        let failed = Children {
            first_bad: Some((S::Failed, Some("diverged at 3.2 m/s²".into()))),
            unfinished: 3,
        };
        assert_eq!(
            settle(&failed),
            Settlement::Fail("diverged at 3.2 m/s²".into())
        );
        let cancelled = Children {
            first_bad: Some((S::Cancelled, None)),
            unfinished: 0,
        };
        assert_eq!(
            settle(&cancelled),
            Settlement::Fail("a run of the search was cancelled".into())
        );
        let failed_quietly = Children {
            first_bad: Some((S::Failed, None)),
            unfinished: 0,
        };
        assert_eq!(
            settle(&failed_quietly),
            Settlement::Fail("a run of the search failed".into())
        );
    }

    #[test]
    fn recover_requeues_until_max_attempts_and_honours_cancels() {
        let who = Abandoned::ServerStopped;
        assert_eq!(recover(1, 3, false, who), Recovery::Requeue);
        assert_eq!(recover(2, 3, false, who), Recovery::Requeue);
        let Recovery::Fail(e) = recover(3, 3, false, who) else {
            panic!("the third abandoned start fails the job")
        };
        assert!(e.contains("server stopped 3 times"), "{e}");
        let Recovery::Fail(e) = recover(1, 1, false, Abandoned::WorkerDied) else {
            panic!("max_attempts 1: the first abandoned start fails the job")
        };
        assert!(e.contains("worker running this job died 1 times"), "{e}");
        // A cancel requested before the run was lost wins over both.
        assert_eq!(recover(1, 3, true, who), Recovery::Cancel);
        assert_eq!(recover(3, 3, true, who), Recovery::Cancel);
    }

    /// A whole life walked through the table: a search fans out, one child fails, the search
    /// fails; the attempts count follows.
    #[test]
    fn a_search_that_fans_out_and_loses_a_child() {
        let (mut s, mut attempts) = (S::Queued, 0);
        let mut apply = |e: Event| {
            s = next(s, &e).unwrap_or_else(|| panic!("{e:?} from {s:?}"));
            attempts = attempts_after(&e, attempts);
            (s, attempts)
        };
        assert_eq!(apply(Event::Claim), (S::Running, 1));
        assert_eq!(apply(Event::FanOut), (S::Waiting, 0));
        let children = Children {
            first_bad: Some((S::Failed, Some("boom".into()))),
            unfinished: 1,
        };
        assert_eq!(apply(Event::Settle(settle(&children))), (S::Failed, 0));
    }
}
