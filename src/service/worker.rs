//! Workers: a fixed pool of std threads that claim jobs from the store and run them through a
//! [`JobRunner`] (the physics never runs on the async runtime). Also the shared core the routes
//! see ([`Core`]): store, limits, progress hub, the stop switches of running jobs.
use super::events::{Hub, JobEvent};
use super::request::{parse_pga, parse_run, JobInput, Limits};
use super::store::{Finish, JobKind, JobRecord, JobStatus, JobStore};
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
/// [`super::fake::fake_runner`].
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
            JobInput::Run { scene, motion } => {
                let out =
                    crate::analysis::run::run(scene, motion, &opts).map_err(|e| e.to_string())?;
                let summary = serde_json::to_value(&out.summary).map_err(|e| e.to_string())?;
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

/// The stop switch of one running job.
#[derive(Default)]
pub struct RunControl {
    pub stop: AtomicBool,
    reason: AtomicU8,
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
        }
    }
}

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
}

impl Core {
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

    fn store_result<T>(&self, what: &str, r: Result<T, super::store::StoreError>) -> Option<T> {
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
    core.hub.publish(
        id,
        JobEvent {
            status: JobStatus::Running,
            progress: 0.0,
        },
    );
    let dir = core.job_dir(id);
    let outcome = prepare_dir(&dir).and_then(|()| {
        let input = parse_stored(core, &job)?;
        execute(core, id, &input, &dir, &ctl)
    });
    let outcome = match (outcome, &core.artifacts) {
        (Ok(o), Some(a)) if ctl.reason.load(Ordering::SeqCst) != STOP_SHUTDOWN => {
            a.publish_dir(id, &dir).map(|()| o)
        }
        (o, _) => o,
    };
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
    let progress = core
        .store
        .get(id)
        .ok()
        .flatten()
        .map(|j| j.progress)
        .unwrap_or(progress);
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

fn execute(
    core: &Core,
    id: Uuid,
    input: &JobInput,
    dir: &Path,
    ctl: &RunControl,
) -> Result<RunnerOutcome, String> {
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
    let runner = core.runner.clone();
    match std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| runner(input, &hooks))) {
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
