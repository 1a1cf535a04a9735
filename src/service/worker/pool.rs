//! Workers: a fixed pool of std threads that claim jobs from the store and run them through a
//! [`JobRunner`] (the physics never runs on the async runtime). Also the shared core the routes
//! see ([`Core`]): store, limits, progress hub, the stop switches of running jobs.
use crate::service::events::{Hub, JobEvent};
use crate::service::http::request::{parse_pga, parse_run, parse_site, JobInput, Limits};
use crate::service::store::{Finish, JobKind, JobRecord, JobStatus, JobStore, NewJob};
use serde_json::Value;
use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, AtomicU8, AtomicUsize, Ordering};
use std::sync::{Arc, Condvar, Mutex};
use std::time::{Duration, Instant};
use uuid::Uuid;

/// What a runner is handed besides the input.
pub struct RunHooks<'a> {
    /// The job's artifact directory, `<data>/jobs/<uuid>/` (exists, empty on a fresh start).
    pub out_dir: &'a Path,
    /// Becomes true when the run must stop (user cancel or server shutdown); checked every step.
    pub cancel: &'a AtomicBool,
    /// Simulated time / duration, 0..1.
    pub progress: &'a (dyn Fn(f64) + Sync),
}

/// How a runner finished (errors are `Err(message for the user)`).
#[derive(Debug, Clone, PartialEq)]
pub enum RunnerOutcome {
    /// `summary.json` of a run or `result.json` of a PGA search.
    Completed(Value),
    /// Stopped through `cancel`; the partial summary where there is one.
    Cancelled(Option<Value>),
}

/// The computation behind a job. The default is [`analysis_runner`]; tests use
/// [`crate::service::fake::fake_runner`].
pub type JobRunner =
    Arc<dyn Fn(&JobInput, &RunHooks<'_>) -> Result<RunnerOutcome, String> + Send + Sync>;

/// The real computation: `analysis::run::run` or `analysis::pga::search`.
pub fn analysis_runner() -> JobRunner {
    Arc::new(|input: &JobInput, hooks: &RunHooks<'_>| {
        let opts = crate::analysis::run::RunOptions {
            out_dir: Some(hooks.out_dir),
            cancel: Some(hooks.cancel),
            progress: Some(hooks.progress),
            ..Default::default()
        };
        match input {
            JobInput::Run {
                scene,
                motion,
                criteria,
            } => {
                let out =
                    crate::analysis::run::run(scene, motion, &opts).map_err(|e| e.to_string())?;
                let mut summary = serde_json::to_value(&out.summary).map_err(|e| e.to_string())?;
                // The request's damage criteria, judged on the finished run (`run --criterion`).
                if !criteria.is_empty() && !out.cancelled {
                    let v = crate::analysis::pga::verdicts(criteria, &out.summary);
                    summary["criteria"] = serde_json::to_value(v).map_err(|e| e.to_string())?;
                }
                Ok(if out.cancelled {
                    RunnerOutcome::Cancelled(Some(summary))
                } else {
                    RunnerOutcome::Completed(summary)
                })
            }
            JobInput::PgaSearch {
                scene,
                request,
                records,
                fit,
                ..
            } if !records.is_empty() => {
                // Several records: per-record searches and the fragility curve; the plot is
                // written beside result.json for `GET .../fragility.svg`.
                let res =
                    crate::analysis::pga::search_records(scene, records, request, *fit, &opts);
                if hooks.cancel.load(Ordering::Relaxed) {
                    return Ok(RunnerOutcome::Cancelled(None));
                }
                let res = res.map_err(|e| e.to_string())?;
                let value = serde_json::to_value(&res).map_err(|e| e.to_string())?;
                if let Some(svg) = crate::analysis::pga::fragility_svg(&res) {
                    std::fs::write(hooks.out_dir.join("fragility.svg"), svg)
                        .map_err(|e| format!("writing fragility.svg: {e}"))?;
                }
                let text = serde_json::to_string_pretty(&value).map_err(|e| e.to_string())?;
                std::fs::write(hooks.out_dir.join("result.json"), text)
                    .map_err(|e| format!("writing result.json: {e}"))?;
                Ok(RunnerOutcome::Completed(value))
            }
            JobInput::SiteAnalysis {
                scene,
                records,
                observations,
                request,
                ..
            } => {
                // Per record the interval, over them the distribution (docs/observations.md).
                let res = crate::analysis::observations::site_analysis(
                    scene,
                    records,
                    observations,
                    request,
                    &opts,
                );
                if hooks.cancel.load(Ordering::Relaxed) {
                    return Ok(RunnerOutcome::Cancelled(None));
                }
                let res = res.map_err(|e| e.to_string())?;
                let value = serde_json::to_value(&res).map_err(|e| e.to_string())?;
                let text = serde_json::to_string_pretty(&value).map_err(|e| e.to_string())?;
                std::fs::write(hooks.out_dir.join("result.json"), text)
                    .map_err(|e| format!("writing result.json: {e}"))?;
                Ok(RunnerOutcome::Completed(value))
            }
            JobInput::PgaSearch {
                scene,
                motion,
                request,
                ..
            } => {
                let res = crate::analysis::pga::search(scene, motion, request, &opts);
                if hooks.cancel.load(Ordering::Relaxed) {
                    return Ok(RunnerOutcome::Cancelled(None));
                }
                let res = res.map_err(|e| e.to_string())?;
                let value = serde_json::to_value(&res).map_err(|e| e.to_string())?;
                let path = hooks.out_dir.join("result.json");
                if !path.exists() {
                    let text = serde_json::to_string_pretty(&value).map_err(|e| e.to_string())?;
                    std::fs::write(&path, text).map_err(|e| format!("writing result.json: {e}"))?;
                }
                Ok(RunnerOutcome::Completed(value))
            }
        }
    })
}

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
    pub fn start(core: Arc<Core>) -> Result<Self, String> {
        let mut handles = Vec::new();
        for k in 0..core.params.workers {
            let c = core.clone();
            // Counted before the thread starts, so /healthz never sees a pool still spinning up.
            core.workers_alive.fetch_add(1, Ordering::SeqCst);
            let h = std::thread::Builder::new()
                .name(format!("ashlar-worker-{k}"))
                .spawn(move || worker_loop(&c))
                .map_err(|e| {
                    core.workers_alive.fetch_sub(1, Ordering::SeqCst);
                    format!("starting worker thread: {e}")
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

fn parse_stored(core: &Core, job: &JobRecord) -> Result<JobInput, String> {
    let parsed = match job.kind {
        JobKind::Run => parse_run(&job.request, &core.limits),
        JobKind::PgaSearch => parse_pga(&job.request, &core.limits),
        JobKind::SiteAnalysis => parse_site(&job.request, &core.limits),
        JobKind::PgaRun => return Err("a child run has no request of its own".into()),
    };
    parsed
        .map(|p| p.input)
        .map_err(|e| format!("the stored request is no longer accepted: {}", e.detail))
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
            a.publish_dir(id, &dir).map(|()| o)
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
        Err(msg) => Finish::Failed(msg),
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

fn prepare_dir(dir: &Path) -> Result<(), String> {
    // A rerun (after a crash) starts from a clean directory so no stale artifact survives.
    if dir.exists() {
        std::fs::remove_dir_all(dir).map_err(|e| {
            tracing::error!(dir = %dir.display(), error = %e, "clearing a job directory");
            "the server could not prepare the job's output directory".to_string()
        })?;
    }
    std::fs::create_dir_all(dir).map_err(|e| {
        tracing::error!(dir = %dir.display(), error = %e, "creating a job directory");
        "the server could not create the job's output directory".to_string()
    })
}

/// Run `work` with the job's hooks (progress to the hub and the store, the stop switch),
/// turning a panic into an error for the user.
fn execute<T>(
    core: &Core,
    id: Uuid,
    dir: &Path,
    ctl: &RunControl,
    work: impl FnOnce(&RunHooks<'_>) -> Result<T, String>,
) -> Result<T, String> {
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
            Err(
                "the computation crashed (an internal error in ashlar; the cause has been logged)"
                    .into(),
            )
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

/// What a child run (`pga_run`) is asked: one amplitude of one record of its search. The
/// amplitude travels as its bits so that the replaying search finds exactly the value it
/// planned (a decimal round trip through JSON could move it by one ULP).
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct ChildRequest {
    pub parent: Uuid,
    /// Index of the record in the search's `motions` (0 for a single-record search).
    pub record: usize,
    /// m/s², for people reading the store; `pga_bits` is what counts.
    pub pga: f64,
    pub pga_bits: u64,
    /// Interior points per k-section round, fixed by the search's first fan-out so that every
    /// replay plans the same batches.
    pub width: usize,
    /// This run's share of the search's progress (1 / expected runs).
    pub progress_step: f64,
}

/// A child's `result`.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct ChildResult {
    pub pga: f64,
    pub failed: bool,
}

/// Does this search fan out: configured to, or fanned out already (then it must replay).
fn fans_out(core: &Core, job: &JobRecord) -> bool {
    core.params.fanout_width.is_some_and(|w| w > 0)
        || core
            .store
            .children(job.id)
            .map(|c| !c.is_empty())
            .unwrap_or(false)
}

fn store_msg(e: crate::service::store::StoreError) -> String {
    tracing::error!(error = %e, "job store");
    "the job store failed while running the search; see the server log".into()
}

/// One step of a fanned-out search: replay its planner from its children's outcomes; finish
/// (`Some`) or enqueue the next batch as child jobs and park the search (`None`).
fn fan_out_search(
    core: &Core,
    job: &JobRecord,
    input: &JobInput,
    hooks: &RunHooks<'_>,
) -> Result<Option<RunnerOutcome>, String> {
    use crate::analysis::pga;
    use std::collections::{HashMap, HashSet};
    let JobInput::PgaSearch {
        scene,
        motion,
        request,
        records,
        fit,
        ..
    } = input
    else {
        return Err("not a PGA search".into());
    };
    if records.is_empty() {
        pga::validate_search(scene, motion, request)
    } else {
        pga::validate_records(scene, records, request)
    }
    .map_err(|e| e.to_string())?;
    let mut width = None;
    let mut known: HashMap<(usize, u64), bool> = HashMap::new();
    let mut unfinished: HashSet<(usize, u64)> = HashSet::new();
    for ch in core.store.children(job.id).map_err(store_msg)? {
        let spec: ChildRequest = serde_json::from_value(ch.request.clone())
            .map_err(|e| format!("a child run of this search is corrupt in the store: {e}"))?;
        width.get_or_insert(spec.width);
        let key = (spec.record, spec.pga_bits);
        match ch.status {
            JobStatus::Succeeded => {
                let r: ChildResult = serde_json::from_str(ch.result.as_deref().unwrap_or(""))
                    .map_err(|e| format!("a child run's result is corrupt in the store: {e}"))?;
                known.insert(key, r.failed);
            }
            JobStatus::Failed | JobStatus::Cancelled => {
                return Err(crate::service::store::child_error(
                    ch.status.as_str(),
                    ch.error,
                ))
            }
            _ => {
                unfinished.insert(key);
            }
        }
    }
    if hooks.cancel.load(Ordering::SeqCst) {
        return Ok(Some(RunnerOutcome::Cancelled(None)));
    }
    let width = width
        .or(core.params.fanout_width)
        .filter(|w| *w > 0)
        .unwrap_or_else(|| rayon::current_num_threads().max(1));
    let look = |i: usize, p: f64| known.get(&(i, p.to_bits())).copied();
    let step = if records.is_empty() {
        match pga::plan(request, width, &|p| look(0, p)) {
            pga::Step::Done(r) => pga::Step::Done(vec![r]),
            pga::Step::Pending { batch, done } => pga::Step::Pending { batch, done },
        }
    } else {
        pga::plan_records(records.len(), request, width, &look)
    };
    match step {
        pga::Step::Done(results) => finish_search(results, records, request, *fit, hooks).map(Some),
        pga::Step::Pending { batch, done } => {
            let expected = pga::expected_runs(request, width) * records.len().max(1) as f64;
            let children: Vec<NewJob> = batch
                .iter()
                .filter(|(i, p)| !unfinished.contains(&(*i, p.to_bits())))
                .map(|&(record, pga)| NewJob {
                    id: Uuid::new_v4(),
                    kind: JobKind::PgaRun,
                    request: serde_json::json!(ChildRequest {
                        parent: job.id,
                        record,
                        pga,
                        pga_bits: pga.to_bits(),
                        width,
                        progress_step: 1.0 / expected,
                    }),
                    motion: serde_json::json!({ "pga": pga }),
                    owner: None,
                })
                .collect();
            let progress = (done as f64 / expected).min(0.99);
            if !core
                .store
                .fan_out(job.id, &children, progress)
                .map_err(store_msg)?
            {
                tracing::warn!(id = %job.id, "the search was no longer ours to fan out (lease lost)");
            }
            for _ in 0..children.len().min(core.params.workers) {
                core.notify_work();
            }
            Ok(None)
        }
    }
}

/// The finished search's result (and its files), as the in-process runner writes them.
fn finish_search(
    mut results: Vec<crate::analysis::pga::PgaResult>,
    records: &[(String, crate::motion::GroundMotion)],
    request: &crate::analysis::pga::PgaRequest,
    fit: crate::analysis::fragility::Method,
    hooks: &RunHooks<'_>,
) -> Result<RunnerOutcome, String> {
    use crate::analysis::pga;
    let value = if records.is_empty() {
        let r = results.pop().ok_or("the search has no result")?;
        serde_json::to_value(&r).map_err(|e| e.to_string())?
    } else {
        let recs = records
            .iter()
            .zip(results)
            .map(|((name, _), result)| pga::RecordResult {
                motion: name.clone(),
                result,
            })
            .collect();
        let res = pga::multi_result(recs, request, fit);
        if let Some(svg) = pga::fragility_svg(&res) {
            std::fs::write(hooks.out_dir.join("fragility.svg"), svg)
                .map_err(|e| format!("writing fragility.svg: {e}"))?;
        }
        serde_json::to_value(&res).map_err(|e| e.to_string())?
    };
    let text = serde_json::to_string_pretty(&value).map_err(|e| e.to_string())?;
    std::fs::write(hooks.out_dir.join("result.json"), text)
        .map_err(|e| format!("writing result.json: {e}"))?;
    Ok(RunnerOutcome::Completed(value))
}

/// A child run: one amplitude of one record of its search, whose request (scene, records,
/// criteria) is read from the search's row. With process isolation it runs in a child process
/// like any job ([`super::runner::run_pga_run_in_child`]), so that a run that crashes or
/// exhausts memory fails this child (and through it its search, with the amplitude named), never
/// the worker.
fn run_child(core: &Core, job: &JobRecord, hooks: &RunHooks<'_>) -> Result<RunnerOutcome, String> {
    let spec: ChildRequest = serde_json::from_value(job.request.clone())
        .map_err(|e| format!("the stored child run is corrupt: {e}"))?;
    let parent = core
        .store
        .get(spec.parent)
        .map_err(store_msg)?
        .ok_or("the search of this run no longer exists")?;
    match &core.params.isolation {
        super::runner::Isolation::Process(p) => {
            super::runner::run_pga_run_in_child(p, &parent.request, &spec, &core.limits, hooks)
                .map_err(|msg| {
                    format!(
                        "the search's run at {} m/s² (record {}) failed: {msg}",
                        f64::from_bits(spec.pga_bits),
                        spec.record
                    )
                })
        }
        super::runner::Isolation::Thread => {
            let input = parse_pga(&parent.request, &core.limits)
                .map_err(|e| format!("the stored request is no longer accepted: {}", e.detail))?
                .input;
            evaluate_child(&input, &spec, hooks.cancel)
        }
    }
}

/// The verdict of one child run (`pga_run`) of the search `input`: on the worker thread, or in
/// the child process of [`super::runner`].
pub(crate) fn evaluate_child(
    input: &JobInput,
    spec: &ChildRequest,
    cancel: &AtomicBool,
) -> Result<RunnerOutcome, String> {
    use crate::analysis::pga;
    let JobInput::PgaSearch {
        scene,
        motion,
        request,
        records,
        ..
    } = input
    else {
        return Err("the parent of a child run is not a PGA search".into());
    };
    let pga = f64::from_bits(spec.pga_bits);
    let (name, gm) = if records.is_empty() {
        (None, motion)
    } else {
        let (n, g) = records
            .get(spec.record)
            .ok_or_else(|| format!("the search has no record {}", spec.record))?;
        (Some(n), g)
    };
    let failed = pga::evaluate_combined(
        scene,
        gm,
        &request.criteria,
        request.combine,
        pga,
        Some(cancel),
    )
    .map_err(|e| match name {
        Some(n) => pga::record_error(n, e).to_string(),
        None => e.to_string(),
    })?;
    let value = serde_json::to_value(ChildResult { pga, failed }).map_err(|e| e.to_string())?;
    Ok(RunnerOutcome::Completed(value))
}
