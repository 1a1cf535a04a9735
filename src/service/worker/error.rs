//! Workers: how a job's computation fails, by cause ([`JobError`]), from the analysis's typed
//! `RunError` up to the text a failed job shows as its `error` (docs/architecture.md, "Errors").
//! The one place the worker turns an error into text is `pool::run_job`, when it records the
//! job as failed; the messages are the ones the worker wrote before the error was typed.
use crate::analysis::run::RunError;
use crate::service::store::StoreError;

/// Write an artifact `file` into the job's directory `dir`, naming the file if it fails.
pub(crate) fn write_artifact(
    dir: &std::path::Path,
    file: &'static str,
    contents: impl AsRef<[u8]>,
) -> Result<(), JobError> {
    std::fs::write(dir.join(file), contents).map_err(|source| JobError::Write { file, source })
}

/// Why a job's computation failed. Its `Display` is what the user reads in the job's `error`.
#[derive(Debug, thiserror::Error)]
pub enum JobError {
    /// The analysis refused the inputs or stopped (the field, the block, the time and what to
    /// change are in the `RunError`).
    #[error(transparent)]
    Run(#[from] RunError),
    /// A result could not be encoded as JSON.
    #[error(transparent)]
    Json(#[from] serde_json::Error),
    /// Writing an artifact (`result.json`, `fragility.svg`, …) into the job's directory.
    #[error("writing {file}: {source}")]
    Write {
        file: &'static str,
        #[source]
        source: std::io::Error,
    },
    /// The job's directory could not be cleared (`clear`) or created; the cause is logged.
    #[error("the server could not {} the job's output directory", if *.clear { "prepare" } else { "create" })]
    Directory {
        clear: bool,
        #[source]
        source: std::io::Error,
    },
    /// This version's parser no longer accepts the stored request (the cause names the field).
    #[error("the stored request is no longer accepted: {0}")]
    Rejected(#[source] crate::service::request::RequestError),
    /// The store failed while a search read or wrote its child runs; the cause is logged.
    #[error("the job store failed while running the search; see the server log")]
    Store(#[source] StoreError),
    /// A stored JSON column of a search's child run does not read (`what` names it).
    #[error("{what}: {source}")]
    Corrupt {
        what: &'static str,
        #[source]
        source: serde_json::Error,
    },
    /// The stored jobs do not fit together (a child run whose parent is gone or not a search, a
    /// record index the search lacks, a job kind that does not run on this path).
    #[error("{0}")]
    Inconsistent(Inconsistent),
    /// A child run of a fanned-out search ended `failed` or `cancelled`: its stored `error`
    /// (text in the store, written by the worker that ran it).
    #[error("{}", crate::service::jobs::child_error(status, error.clone()))]
    ChildEnded {
        status: &'static str,
        error: Option<String>,
    },
    /// One child run of a search failed in its process (the amplitude and record named).
    #[error("the search's run at {pga} m/s² (record {record}) failed: {source}")]
    ChildRun {
        pga: f64,
        record: usize,
        #[source]
        source: Box<JobError>,
    },
    /// The job's process (`--isolation process`) failed or ended without a result.
    #[error(transparent)]
    Process(#[from] ProcessError),
    /// The computation panicked; the panic's text is logged.
    #[error("the computation crashed (an internal error in ashlar; the cause has been logged)")]
    Panicked,
    /// Publishing the artifacts to shared storage failed (`ArtifactStore::publish_dir`; the
    /// cause is logged, the user reads a sentence).
    #[error(transparent)]
    Publish(super::artifacts::ArtifactError),
    /// The test runner's failure asked for by the scene's name `fake:fail`.
    #[error("fake failure requested by the scene name")]
    Fake,
}

/// A thread the service starts (a worker, the cluster's listener or lease keeper, a sweeper)
/// could not be started; `thread` says which ("worker thread", "the retention sweeper", …).
#[derive(Debug, thiserror::Error)]
#[error("starting {thread}: {source}")]
pub struct ThreadStartError {
    pub thread: &'static str,
    #[source]
    pub source: std::io::Error,
}

impl ThreadStartError {
    /// A `map_err` for `std::thread::Builder::spawn` naming `thread`.
    pub(crate) fn of(thread: &'static str) -> impl FnOnce(std::io::Error) -> Self {
        move |source| ThreadStartError { thread, source }
    }
}

/// How stored jobs can fail to fit together (see [`JobError::Inconsistent`]).
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum Inconsistent {
    #[error("not a PGA search")]
    NotASearch,
    #[error("the parent of a child run is not a PGA search")]
    ParentNotASearch,
    #[error("the search of this run no longer exists")]
    ParentGone,
    #[error("a child run has no request of its own")]
    ChildHasNoRequest,
    #[error("a pga_run job's process was not told which run")]
    ChildNotTold,
    #[error("the search has no result")]
    NoResult,
    #[error("the search has no record {0}")]
    NoRecord(usize),
    #[error("a job of kind {0} does not run in a child process")]
    NotInChild(String),
}

impl From<Inconsistent> for JobError {
    fn from(e: Inconsistent) -> Self {
        JobError::Inconsistent(e)
    }
}

impl JobError {
    /// A store failure during a search, logged in full here (the user reads a sentence).
    pub(crate) fn store(e: StoreError) -> Self {
        tracing::error!(error = %e, "job store");
        JobError::Store(e)
    }

    /// A stored request the parser now refuses.
    pub(crate) fn rejected(e: crate::service::request::RequestError) -> Self {
        JobError::Rejected(e)
    }
}

/// How a job's child process (`ashlar internal-run-job`) failed, as the server saw it.
#[derive(Debug, thiserror::Error)]
pub enum ProcessError {
    /// The process could not be started, talked to or waited for; the cause is logged.
    #[error("the server could not start the job's process; see the server log")]
    Spawn(#[source] std::io::Error),
    #[error("the server could not talk to the job's process")]
    Pipes,
    #[error("the server lost track of the job's process; see the server log")]
    Wait(#[source] std::io::Error),
    /// The run failed and the process said why (its message, text over the pipe).
    #[error("{0}")]
    Reported(String),
    /// The process ended without saying how its run went; the cause read from its end.
    #[error(transparent)]
    Ended(#[from] ProcessEnd),
}

/// Why a child process ended without a result, read from its exit status and standard error.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum ProcessEnd {
    /// Out of memory under `--job-memory-limit` (bytes, and the same in words).
    #[error("the run exceeded the job memory limit of {bytes} bytes ({human}) (ashlar serve --job-memory-limit) and was stopped")]
    MemoryLimit { bytes: u64, human: String },
    #[error("the run ran out of memory")]
    OutOfMemory,
    #[error("the run did not stop when asked and was killed")]
    KilledAfterCancel,
    #[error("the run was killed (signal 9, SIGKILL; e.g. by the system's out-of-memory killer)")]
    Killed,
    /// SIGXCPU under `--job-cpu-seconds` (s).
    #[error("the run exceeded the job CPU-time limit of {seconds} s (ashlar serve --job-cpu-seconds) and was stopped")]
    CpuLimit { seconds: u64 },
    /// SIGXFSZ under `--max-job-artifact-bytes`.
    #[error("the run wrote a file over the server's limit of {bytes} bytes per job (ashlar serve --max-job-artifact-bytes) and was stopped")]
    FileLimit { bytes: u64 },
    #[error("the run crashed (signal {signal}, {name}): an internal error in ashlar, the cause has been logged")]
    Crashed { signal: i32, name: &'static str },
    #[error("the run's process ended with exit status {code} without a result: an internal error in ashlar, the cause has been logged")]
    Exited { code: i32 },
}
