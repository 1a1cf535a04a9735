//! Workers: a fixed pool of std threads that claim jobs from the store and run them through a
//! [`JobRunner`] (`run`; the physics never runs on the async runtime), with the watchdog of each
//! run's time and disk. Also the shared core the HTTP layer sees ([`Core`]): store, limits,
//! progress hub, the stop switches of running jobs. A search that fans out goes to `fanout`.
//!
//! Length (over 600 lines): `Core` and the pool's threads and watchdog read and write the same
//! running-job table and stop switches; `Core` could move to its own file.
use super::error::{Inconsistent, JobError};
use super::fanout::{fan_out_search, fans_out, run_child};
use super::run::{JobRunner, RunHooks, RunnerOutcome};
use crate::service::events::{Hub, JobEvent};
use crate::service::request::{parse_pga, parse_run, parse_site, JobInput, Limits};
use crate::service::store::{Finish, JobKind, JobRecord, JobStatus, JobStore};
use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, AtomicU8, AtomicUsize, Ordering};
use std::sync::{Arc, Condvar, Mutex};
use std::time::{Duration, Instant};
use uuid::Uuid;

/// Why a running job's stop switch was thrown.
const STOP_NONE: u8 = 0;
const STOP_USER: u8 = 1;
const STOP_SHUTDOWN: u8 = 2;
/// Over the per-job wall-clock or artifact limit (`--max-job-seconds`, `--max-job-artifact-bytes`).
const STOP_LIMIT: u8 = 3;

/// The stop switch of one running job.
#[derive(Default)]
pub struct RunControl {
    pub stop: AtomicBool,
    reason: AtomicU8,
    /// Which limit stopped the job (with `STOP_LIMIT`), for its error.
    limit: Mutex<Option<String>>,
}

impl RunControl {
    fn throw(&self, reason: u8) {
        // The first reason wins: a user cancel stays a cancel even if shutdown follows.
        let _ = self
            .reason
            .compare_exchange(STOP_NONE, reason, Ordering::SeqCst, Ordering::SeqCst);
        self.stop.store(true, Ordering::SeqCst);
    }
}

/// Tuning of the worker pool.
#[derive(Debug, Clone, PartialEq)]
pub struct WorkerParams {
    /// Threads running jobs. Default: the number of cores (each job is single-threaded CPU work).
    pub workers: usize,
    /// How often an idle worker looks at the store even without a wake-up: picks up jobs that
    /// another process added to a shared store. 500 ms is invisible next to a run's length.
    pub idle_poll: Duration,
    /// Least time between two progress writes to the store for one job. Subscribers to
    /// `/events` get every update from memory; the store only needs a recent value, and 250 ms
    /// keeps a fast run from turning into a stream of fsyncs.
    pub progress_write_interval: Duration,
    /// A job found `running` at start-up this many times (the server died under it each time)
    /// is failed instead of retried.
    pub max_attempts: u32,
    /// Fan PGA searches out as child jobs (`pga_run`, one per amplitude) that every worker of
    /// every process sharing the store runs, with this many interior points per k-section
    /// round. None: a search runs on the rayon pool of the worker that claimed it (the
    /// default of the embedded store; `ashlar serve|worker` with PostgreSQL fan out). A search
    /// that already has children is always replayed from them, whatever this says.
    pub fanout_width: Option<usize>,
    /// Where runs and in-process searches execute: on the worker thread, or in a child process
    /// with resource limits ([`super::runner`]), as are a fanned-out search's `pga_run`
    /// children; only a fan-out step (planning from the store, no engine) stays on the thread.
    pub isolation: super::runner::Isolation,
    /// Remove a job's local directory once its outcome is recorded, when its artifacts go to
    /// shared `--artifacts` storage. `ashlar worker` sets it (it serves nothing from that
    /// directory); an API process keeps its copies to serve them, and DELETE removes them.
    pub discard_local_artifacts: bool,
}

impl Default for WorkerParams {
    fn default() -> Self {
        Self {
            workers: std::thread::available_parallelism()
                .map(|n| n.get())
                .unwrap_or(1),
            idle_poll: Duration::from_millis(500),
            progress_write_interval: Duration::from_millis(250),
            max_attempts: 3,
            fanout_width: None,
            isolation: super::runner::Isolation::Thread,
            discard_local_artifacts: false,
        }
    }
}

/// Large bodies (over [`LARGE_BODY_BYTES`]) read and parsed at once. Two: a 16 MB body of
/// the most values allowed costs ~200 MB while parsed, and the server must stay far below the
/// memory of a small machine; small bodies (every example, most jobs) are never held back.
pub const LARGE_BODIES: usize = 2;
/// A body over this many bytes (or of unknown length) waits for one of [`LARGE_BODIES`].
pub const LARGE_BODY_BYTES: u64 = 1 << 20;

/// Everything routes and workers share.
pub struct Core {
    pub store: Arc<dyn JobStore>,
    pub data_dir: PathBuf,
    pub limits: Limits,
    pub params: WorkerParams,
    pub hub: Hub,
    pub runner: JobRunner,
    running: Mutex<HashMap<Uuid, Arc<RunControl>>>,
    wake: (Mutex<u64>, Condvar),
    /// Set on SIGINT/SIGTERM: stop accepting jobs, stop claiming.
    pub shutting_down: AtomicBool,
    /// Flips to true on shutdown so that open event streams end.
    pub shutdown_signal: tokio::sync::watch::Sender<bool>,
    pub workers_alive: AtomicUsize,
    /// False after a store operation of a worker failed, true again after one succeeds.
    pub store_healthy: AtomicBool,
    /// Jobs are run by other processes sharing the store (`ashlar worker`): an API process
    /// with no worker threads of its own can still take jobs.
    pub remote_workers: AtomicBool,
    /// Where finished jobs' artifacts are published for every process (None: they stay in
    /// `data_dir`, which all processes then share).
    pub artifacts: Option<Arc<super::artifacts::ArtifactStore>>,
    /// Connection and timeout settings of the HTTP server (the routes read the body timeout).
    pub server: crate::service::server::ServerParams,
    /// Large request bodies read and parsed at once: each can cost up to a few hundred MB
    /// while parsed, so their number is what bounds the server's memory.
    pub large_bodies: Arc<tokio::sync::Semaphore>,
    /// Bytes under `<data>/jobs` and when they were counted (a cache for the disk quota).
    pub disk_used: Mutex<Option<(Instant, u64)>>,
}

impl Core {
    /// The job's progress as the store has it (which may be ahead of this process's, for a
    /// search whose children ran elsewhere), or `otherwise` when it cannot be read.
    fn stored_progress(&self, id: Uuid, otherwise: f64) -> f64 {
        self.store
            .get(id)
            .ok()
            .flatten()
            .map_or(otherwise, |j| j.progress)
    }

    pub fn new(
        store: Arc<dyn JobStore>,
        data_dir: PathBuf,
        limits: Limits,
        params: WorkerParams,
        runner: JobRunner,
    ) -> Self {
        Self {
            store,
            data_dir,
            limits,
            params,
            hub: Hub::default(),
            runner,
            running: Mutex::new(HashMap::new()),
            wake: (Mutex::new(0), Condvar::new()),
            shutting_down: AtomicBool::new(false),
            shutdown_signal: tokio::sync::watch::channel(false).0,
            workers_alive: AtomicUsize::new(0),
            store_healthy: AtomicBool::new(true),
            remote_workers: AtomicBool::new(false),
            artifacts: None,
            server: crate::service::server::ServerParams::default(),
            large_bodies: Arc::new(tokio::sync::Semaphore::new(LARGE_BODIES)),
            disk_used: Mutex::new(None),
        }
    }

    /// Bytes of all jobs' artifacts under `<data>/jobs` (with `--artifacts`, in the shared
    /// storage), counted at most every 10 s (the disk quota is a guard against filling the
    /// disk, not an exact account).
    pub fn artifact_bytes(&self) -> u64 {
        let fresh = self
            .disk_used
            .lock()
            .ok()
            .and_then(|g| *g)
            .filter(|(t, _)| t.elapsed() < Duration::from_secs(10));
        if let Some((_, b)) = fresh {
            return b;
        }
        let jobs = self.data_dir.join("jobs");
        let local = || {
            std::fs::read_dir(&jobs)
                .map(|rd| {
                    rd.filter_map(Result::ok)
                        .map(|e| dir_bytes(&e.path()))
                        .sum()
                })
                .unwrap_or(0)
        };
        // With shared storage the published files are the artifacts (the local directory only
        // caches them, and workers elsewhere keep none): count those.
        let total = match &self.artifacts {
            Some(a) => a.total_bytes().unwrap_or_else(|e| {
                tracing::warn!(error = %e, "counting published artifacts; counting the local ones");
                local()
            }),
            None => local(),
        };
        if let Ok(mut g) = self.disk_used.lock() {
            *g = Some((Instant::now(), total));
        }
        total
    }

    /// Remove a deleted job's artifacts: its local directory and, with `--artifacts`, what was
    /// published to shared storage (`DELETE` of a job and the retention sweeper). Blocking.
    pub fn remove_artifacts(&self, id: Uuid) {
        if let Some(a) = &self.artifacts {
            if let Err(e) = a.remove(id) {
                tracing::warn!(%id, error = %e, "removing a deleted job's published artifacts");
            }
        }
        let dir = self.job_dir(id);
        if let Err(e) = std::fs::remove_dir_all(&dir) {
            if e.kind() != std::io::ErrorKind::NotFound {
                tracing::warn!(dir = %dir.display(), error = %e, "removing a deleted job's artifacts");
            }
        }
        self.forget_artifact_bytes();
    }

    /// Forget the cached artifact total (after a delete).
    pub fn forget_artifact_bytes(&self) {
        if let Ok(mut g) = self.disk_used.lock() {
            *g = None;
        }
    }

    /// Ids of the jobs running in this process.
    pub fn running_ids(&self) -> Vec<Uuid> {
        self.running
            .lock()
            .map(|m| m.keys().copied().collect())
            .unwrap_or_default()
    }

    /// Stop a running job whose lease this process lost (another worker may be rerunning it):
    /// stopped like at shutdown, so nothing is recorded for it here.
    pub fn signal_lost(&self, id: Uuid) {
        if let Some(c) = self.running.lock().ok().and_then(|m| m.get(&id).cloned()) {
            c.throw(STOP_SHUTDOWN);
        }
    }

    /// Directory of a job's artifacts. Built from the UUID only, never from user text.
    pub fn job_dir(&self, id: Uuid) -> PathBuf {
        self.data_dir.join("jobs").join(id.hyphenated().to_string())
    }

    /// Wake one idle worker (a job was queued).
    pub fn notify_work(&self) {
        if let Ok(mut n) = self.wake.0.lock() {
            *n = n.wrapping_add(1);
        }
        self.wake.1.notify_one();
    }

    /// The wake-up counter, read before looking at the queue: a wake-up that arrives between
    /// an empty claim and the wait is then not missed.
    fn wake_seq(&self) -> u64 {
        self.wake.0.lock().map(|g| *g).unwrap_or(0)
    }

    fn wait_for_work(&self, seen: u64, timeout: Duration) {
        if let Ok(g) = self.wake.0.lock() {
            let _ = self.wake.1.wait_timeout_while(g, timeout, |n| {
                *n == seen && !self.shutting_down.load(Ordering::SeqCst)
            });
        }
    }

    /// Throw the stop switch of a running job in this process (after the store has recorded the
    /// cancel request). Returns whether the job runs here.
    pub fn signal_cancel(&self, id: Uuid) -> bool {
        let ctl = self.running.lock().ok().and_then(|m| m.get(&id).cloned());
        match ctl {
            Some(c) => {
                c.throw(STOP_USER);
                true
            }
            None => false,
        }
    }

    pub fn running_here(&self) -> usize {
        self.running.lock().map(|m| m.len()).unwrap_or(0)
    }

    /// Stop accepting and claiming; end event streams.
    pub fn begin_shutdown(&self) {
        self.shutting_down.store(true, Ordering::SeqCst);
        self.shutdown_signal.send_replace(true);
        self.wake.1.notify_all();
    }

    fn register(&self, id: Uuid) -> Arc<RunControl> {
        let ctl = Arc::new(RunControl::default());
        if let Ok(mut m) = self.running.lock() {
            m.insert(id, ctl.clone());
        }
        ctl
    }

    fn unregister(&self, id: Uuid) {
        if let Ok(mut m) = self.running.lock() {
            m.remove(&id);
        }
    }

    fn store_result<T>(
        &self,
        what: &str,
        r: Result<T, crate::service::store::StoreError>,
    ) -> Option<T> {
        match r {
            Ok(v) => {
                self.store_healthy.store(true, Ordering::Relaxed);
                Some(v)
            }
            Err(e) => {
                self.store_healthy.store(false, Ordering::Relaxed);
                tracing::error!(error = %e, "{what}");
                None
            }
        }
    }
}

/// The running worker threads.
pub struct Pool {
    core: Arc<Core>,
    handles: Vec<std::thread::JoinHandle<()>>,
}

impl Pool {
    /// Start `core.params.workers` threads.
    pub fn start(core: Arc<Core>) -> Result<Self, super::ThreadStartError> {
        let mut handles = Vec::new();
        for k in 0..core.params.workers {
            let c = core.clone();
            // Counted before the thread starts, so /healthz never sees a pool still spinning up.
            core.workers_alive.fetch_add(1, Ordering::SeqCst);
            let h = std::thread::Builder::new()
                .name(format!("ashlar-worker-{k}"))
                .spawn(move || worker_loop(&c))
                .map_err(|source| {
                    core.workers_alive.fetch_sub(1, Ordering::SeqCst);
                    super::ThreadStartError {
                        thread: "worker thread",
                        source,
                    }
                })?;
            handles.push(h);
        }
        Ok(Self { core, handles })
    }

    /// Graceful stop: no new claims; running jobs get `grace` to finish, then are stopped and
    /// put back in the queue (they rerun from the start on the next server). Returns how many
    /// were requeued.
    pub fn shutdown(self, grace: Duration) -> usize {
        self.core.begin_shutdown();
        let deadline = Instant::now() + grace;
        while self.core.running_here() > 0 && Instant::now() < deadline {
            std::thread::sleep(Duration::from_millis(20));
        }
        let interrupted: Vec<Arc<RunControl>> = self
            .core
            .running
            .lock()
            .map(|m| m.values().cloned().collect())
            .unwrap_or_default();
        for c in &interrupted {
            c.throw(STOP_SHUTDOWN);
        }
        for h in self.handles {
            if h.join().is_err() {
                tracing::error!("a worker thread panicked outside a job");
            }
        }
        interrupted.len()
    }
}

fn worker_loop(core: &Core) {
    while !core.shutting_down.load(Ordering::SeqCst) {
        let seen = core.wake_seq();
        match core.store.claim() {
            Ok(Some(job)) => {
                core.store_healthy.store(true, Ordering::Relaxed);
                // One wake-up may stand for many jobs (a fan-out queues dozens at once, and
                // NOTIFYs of one transaction fold into one): pass it on to an idle thread.
                core.notify_work();
                run_job(core, job);
            }
            Ok(None) => core.wait_for_work(seen, core.params.idle_poll),
            Err(e) => {
                core.store_result::<()>("claiming a job", Err(e));
                std::thread::sleep(core.params.idle_poll);
            }
        }
    }
    core.workers_alive.fetch_sub(1, Ordering::SeqCst);
}

fn parse_stored(core: &Core, job: &JobRecord) -> Result<JobInput, JobError> {
    let parsed = match job.kind {
        JobKind::Run => parse_run(&job.request, &core.limits),
        JobKind::PgaSearch => parse_pga(&job.request, &core.limits),
        JobKind::SiteAnalysis => parse_site(&job.request, &core.limits),
        JobKind::PgaRun => return Err(Inconsistent::ChildHasNoRequest.into()),
    };
    parsed.map(|p| p.input).map_err(JobError::rejected)
}

/// Run one claimed job to a terminal status (or back to the queue on shutdown).
fn run_job(core: &Core, job: JobRecord) {
    let id = job.id;
    let ctl = core.register(id);
    // The cancel endpoint writes the store, then looks for the switch; we registered the switch,
    // then read the store: whichever came second sees the other.
    let cancel_pending = match core.store.get(id) {
        Ok(Some(j)) => j.cancel_requested,
        _ => job.cancel_requested,
    };
    if cancel_pending {
        ctl.throw(STOP_USER);
    }
    // A fanned-out search claimed again keeps the progress its children brought it.
    core.hub.publish(
        id,
        JobEvent {
            status: JobStatus::Running,
            progress: job.progress,
        },
    );
    let dir = core.job_dir(id);
    // A child run writes no artifacts (its outcome goes to the store): no directory.
    let outcome = if job.kind == JobKind::PgaRun {
        execute(core, id, &dir, &ctl, |hooks| run_child(core, &job, hooks)).map(Some)
    } else {
        prepare_dir(&dir).and_then(|()| {
            let input = parse_stored(core, &job)?;
            match &input {
                JobInput::PgaSearch { .. } if fans_out(core, &job) => {
                    execute(core, id, &dir, &ctl, |hooks| {
                        fan_out_search(core, &job, &input, hooks)
                    })
                }
                _ => match &core.params.isolation {
                    super::runner::Isolation::Process(p) => {
                        execute(core, id, &dir, &ctl, |hooks| {
                            super::runner::run_in_child(
                                p,
                                job.kind,
                                &job.request,
                                &core.limits,
                                hooks,
                            )
                        })
                        .map(Some)
                    }
                    super::runner::Isolation::Thread => {
                        let runner = core.runner.clone();
                        execute(core, id, &dir, &ctl, |hooks| runner(&input, hooks)).map(Some)
                    }
                },
            }
        })
    };
    let outcome = match outcome {
        Ok(Some(o)) => Ok(o),
        Err(e) => Err(e),
        Ok(None) => {
            // Parked in `waiting` by the store; its last child queues it again.
            core.unregister(id);
            let progress = core.stored_progress(id, 0.0);
            core.hub.publish(
                id,
                JobEvent {
                    status: JobStatus::Waiting,
                    progress,
                },
            );
            return;
        }
    };
    let outcome = match (outcome, &core.artifacts) {
        (Ok(o), Some(a))
            if ctl.reason.load(Ordering::SeqCst) != STOP_SHUTDOWN
                && job.kind != JobKind::PgaRun =>
        {
            a.publish_dir(id, &dir)
                .map(|()| o)
                .map_err(JobError::Publish)
        }
        (o, _) => o,
    };
    if core.params.discard_local_artifacts
        && core.artifacts.is_some()
        && job.kind != JobKind::PgaRun
    {
        // A worker-only process with shared storage: its directory is scratch (what is served
        // was published; API processes fetch it from there). Left behind, every job's files
        // would stay on this worker's disk forever, out of reach of DELETE and retention.
        if let Err(e) = std::fs::remove_dir_all(&dir) {
            if e.kind() != std::io::ErrorKind::NotFound {
                tracing::warn!(dir = %dir.display(), error = %e, "removing a job's scratch directory");
            }
        }
    }
    let reason = ctl.reason.load(Ordering::SeqCst);
    core.unregister(id);
    let finish = match outcome {
        Ok(RunnerOutcome::Completed(v)) => Finish::Succeeded(v),
        Ok(RunnerOutcome::Cancelled(_)) | Err(_) if reason == STOP_SHUTDOWN => {
            tracing::info!(%id, "job interrupted by shutdown; back in the queue");
            core.store_result("requeueing a job", core.store.requeue(id, true));
            core.hub.publish(
                id,
                JobEvent {
                    status: JobStatus::Queued,
                    progress: 0.0,
                },
            );
            return;
        }
        Ok(RunnerOutcome::Cancelled(_)) | Err(_) if reason == STOP_LIMIT => Finish::Failed(
            ctl.limit
                .lock()
                .ok()
                .and_then(|m| m.clone())
                .unwrap_or_else(|| "the job exceeded a server limit".into()),
        ),
        Ok(RunnerOutcome::Cancelled(partial)) => Finish::Cancelled(partial),
        Err(_) if reason == STOP_USER => Finish::Cancelled(None),
        // The one place a job's error becomes text: the job's `error` field.
        Err(e) => Finish::Failed(e.to_string()),
    };
    let (status, progress) = match &finish {
        Finish::Succeeded(_) => (JobStatus::Succeeded, 1.0),
        Finish::Failed(_) => (JobStatus::Failed, job.progress),
        Finish::Cancelled(_) => (JobStatus::Cancelled, job.progress),
    };
    core.store_result("recording a finished job", core.store.finish(id, &finish));
    // Its artifacts count against the disk quota from now on.
    core.forget_artifact_bytes();
    if job.kind == JobKind::PgaRun {
        // The last child of a search queues the search again: a thread of this process may
        // be idle (another process hears it through the store's notification).
        core.notify_work();
    }
    let progress = core.stored_progress(id, progress);
    core.hub.publish(id, JobEvent { status, progress });
}

fn prepare_dir(dir: &Path) -> Result<(), JobError> {
    // A rerun (after a crash) starts from a clean directory so no stale artifact survives.
    if dir.exists() {
        std::fs::remove_dir_all(dir).map_err(|e| {
            tracing::error!(dir = %dir.display(), error = %e, "clearing a job directory");
            JobError::Directory {
                clear: true,
                source: e,
            }
        })?;
    }
    std::fs::create_dir_all(dir).map_err(|e| {
        tracing::error!(dir = %dir.display(), error = %e, "creating a job directory");
        JobError::Directory {
            clear: false,
            source: e,
        }
    })
}

/// Run `work` with the job's hooks (progress to the hub and the store, the stop switch),
/// turning a panic into an error for the user.
fn execute<T>(
    core: &Core,
    id: Uuid,
    dir: &Path,
    ctl: &RunControl,
    work: impl FnOnce(&RunHooks<'_>) -> Result<T, JobError>,
) -> Result<T, JobError> {
    let last_write = Mutex::new(Instant::now());
    let progress = |p: f64| {
        let p = if p.is_finite() {
            p.clamp(0.0, 1.0)
        } else {
            0.0
        };
        core.hub.publish(
            id,
            JobEvent {
                status: JobStatus::Running,
                progress: p,
            },
        );
        let due = last_write.lock().map(|mut t| {
            let due = t.elapsed() >= core.params.progress_write_interval;
            if due {
                *t = Instant::now();
            }
            due
        });
        if due.unwrap_or(false) {
            core.store_result("recording progress", core.store.set_progress(id, p));
        }
    };
    let hooks = RunHooks {
        out_dir: dir,
        cancel: &ctl.stop,
        progress: &progress,
    };
    let done = AtomicBool::new(false);
    let result = std::thread::scope(|sc| {
        // The watchdog: wall-clock and artifact-size limits, checked while the job runs.
        sc.spawn(|| watchdog(core, dir, ctl, &done));
        let r = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| work(&hooks)));
        done.store(true, Ordering::SeqCst);
        r
    });
    match result {
        Ok(r) => r,
        Err(panic) => {
            let msg = panic
                .downcast_ref::<String>()
                .cloned()
                .or_else(|| panic.downcast_ref::<&str>().map(|s| s.to_string()))
                .unwrap_or_default();
            tracing::error!(%id, panic = %msg, "the runner panicked");
            Err(JobError::Panicked)
        }
    }
}

/// Bytes of the files directly in `dir` (a job directory is flat).
pub fn dir_bytes(dir: &Path) -> u64 {
    std::fs::read_dir(dir)
        .map(|rd| {
            rd.filter_map(Result::ok)
                .filter_map(|e| e.metadata().ok())
                .filter(|m| m.is_file())
                .map(|m| m.len())
                .sum()
        })
        .unwrap_or(0)
}

/// Stop the job (reason `STOP_LIMIT`) when it runs longer than `--max-job-seconds` or its
/// directory grows beyond `--max-job-artifact-bytes`; returns when `done` is set.
fn watchdog(core: &Core, dir: &Path, ctl: &RunControl, done: &AtomicBool) {
    let start = Instant::now();
    let max_time = Duration::from_secs(core.limits.max_job_seconds);
    let mut tick = 0u64;
    while !done.load(Ordering::SeqCst) {
        std::thread::sleep(Duration::from_millis(100));
        tick += 1;
        let over = if start.elapsed() > max_time {
            Some(format!(
                "the job ran longer than the server's limit of {} s of wall-clock time (ashlar serve --max-job-seconds) and was stopped",
                core.limits.max_job_seconds
            ))
        } else if tick % 5 == 0 {
            let bytes = dir_bytes(dir);
            (bytes > core.limits.max_job_artifact_bytes).then(|| {
                format!(
                    "the job wrote {bytes} bytes of artifacts, over the server's limit of {} per job (ashlar serve --max-job-artifact-bytes), and was stopped",
                    core.limits.max_job_artifact_bytes
                )
            })
        } else {
            None
        };
        if let Some(msg) = over {
            tracing::warn!(dir = %dir.display(), "{msg}");
            if let Ok(mut m) = ctl.limit.lock() {
                m.get_or_insert(msg);
            }
            ctl.throw(STOP_LIMIT);
            return;
        }
    }
}
