//! Job isolation: service::worker hands a job here (a run, an in-process search, or one
//! `pga_run` child of a fanned-out search), which runs it in a child `ashlar internal-run-job`
//! process (→ analysis) under resource limits, so that a run that panics, crashes or exhausts
//! memory fails its own job only and never the server, an `ashlar worker`, or other jobs.
//!
//! Protocol: the worker writes one JSON line ([`ChildSpec`]) to the child's stdin and keeps stdin
//! open; a later line `cancel` asks the child to stop at its next step (as the in-process stop
//! switch does), and the end of stdin (the server died, or gave up on the child) makes the child
//! exit at once. The child writes its artifacts to the job directory and [`ChildMessage`] JSON
//! lines to stdout: progress, then its outcome. Its exit status tells how a run ended that could
//! not say so itself (a signal, the memory limit).
//!
//! The child sets its limits on itself before it reads the scene (RLIMIT_AS, RLIMIT_CPU,
//! RLIMIT_FSIZE), asks the kernel to kill it when the worker thread that started it dies
//! (PR_SET_PDEATHSIG, Linux), and checks its parent is still the server (else exits). Unix only;
//! elsewhere `ashlar serve` runs jobs in-process.
//!
//! Length (over 600 lines): both sides of one protocol, the parent (spawn, limits, the child's
//! lines, its exit as a failure) and the child (`child_main`), kept together so that a change to
//! the protocol is made in one place.
use super::error::{Inconsistent, JobError, ProcessEnd, ProcessError};
use super::fanout::ChildRequest;
use super::run::{RunHooks, RunnerOutcome};
use crate::service::request::{parse_pga, parse_run, parse_site, JobInput, Limits};
use crate::service::store::JobKind;
use serde::{Deserialize, Serialize};
use serde_json::Value;
use std::io::{BufRead, Read, Write};
use std::path::PathBuf;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{mpsc, Arc, Mutex};
use std::time::{Duration, Instant};

/// Where a job runs.
#[derive(Debug, Clone, PartialEq, Default)]
pub enum Isolation {
    /// On the worker thread (a panic fails only the job; a crash or exhausted memory takes the
    /// server down). The library default (tests with in-process runners).
    #[default]
    Thread,
    /// In a child process with resource limits (`ashlar serve --isolation process`).
    Process(ProcessParams),
}

/// How a job's child process is started and limited.
#[derive(Debug, Clone, PartialEq)]
pub struct ProcessParams {
    /// The `ashlar` binary (the server's own executable).
    pub exe: PathBuf,
    /// Bytes of address space of the child (RLIMIT_AS); 0: none. Address space, not resident
    /// memory: it counts reserved but untouched mappings, so it is set well above what a run
    /// touches (see [`DEFAULT_JOB_MEMORY_LIMIT`]).
    pub memory_limit: u64,
    /// Seconds of CPU time of the child (RLIMIT_CPU); 0: none.
    pub cpu_seconds: u64,
    /// How long a child asked to stop (cancel, shutdown, a watchdog limit) gets before it is
    /// killed. 10 s: a run checks its stop switch every step, a search every run's step.
    pub cancel_grace: Duration,
    /// Run the service's fake runner in the child with this slowness (`--fake-runner`).
    pub fake: Option<Duration>,
    /// Extra environment of the child (tests set the fault trigger here).
    pub env: Vec<(String, String)>,
}

/// Default `--job-memory-limit`: 8 GiB of address space. Generous on purpose (not measured
/// against the largest run the budgets admit): address space counts reservations that are never
/// touched (thread stacks, allocator arenas), so a tight default would fail legitimate runs; the
/// point is that one job cannot take the whole machine's memory from the server and the others.
pub const DEFAULT_JOB_MEMORY_LIMIT: u64 = 8 << 30;

impl ProcessParams {
    pub fn new(exe: PathBuf) -> Self {
        Self {
            exe,
            memory_limit: DEFAULT_JOB_MEMORY_LIMIT,
            cpu_seconds: 0,
            cancel_grace: Duration::from_secs(10),
            fake: None,
            env: Vec::new(),
        }
    }
}

/// The first line a child reads.
#[derive(Debug, Serialize, Deserialize)]
pub struct ChildSpec {
    /// `run`, `pga_search` or `pga_run` (one amplitude of a fanned-out search).
    pub kind: String,
    /// The stored request body (of a `pga_run`: its search's).
    pub request: Value,
    /// Of a `pga_run`: which amplitude of which record it evaluates.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub pga_run: Option<ChildRequest>,
    /// The server's limits, which parsing applies (e.g. the engine's step cap).
    pub limits: Value,
    /// The job directory: artifacts go there.
    pub out_dir: PathBuf,
    pub memory_limit: u64,
    pub cpu_seconds: u64,
    /// Largest file the child may write (RLIMIT_FSIZE), the per-job artifact limit.
    pub file_size_limit: u64,
    /// Milliseconds of wall time per simulated second of the fake runner, when it is used.
    pub fake_ms: Option<u64>,
    /// The server's process id: a child whose parent is already another process exits.
    pub parent_pid: u32,
}

/// A line a child writes to stdout.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "type", rename_all = "snake_case")]
pub enum ChildMessage {
    Progress { progress: f64 },
    Completed { value: Value },
    Cancelled { partial: Option<Value> },
    Error { message: String },
}

fn limits_to_value(l: &Limits) -> Value {
    serde_json::json!({
        "max_body_bytes": l.max_body_bytes,
        "max_blocks": l.max_blocks,
        "max_record_samples": l.max_record_samples,
        "max_total_steps": l.max_total_steps,
        "max_block_vertices": l.max_block_vertices,
        "max_scan_points": l.max_scan_points,
        "max_queued_jobs": l.max_queued_jobs,
        "max_block_steps": l.max_block_steps,
        "max_block_frames": l.max_block_frames,
        "max_search_block_steps": l.max_search_block_steps,
        "max_json_values": l.max_json_values,
        "max_job_seconds": l.max_job_seconds,
        "max_job_artifact_bytes": l.max_job_artifact_bytes,
        "max_artifact_bytes": l.max_artifact_bytes,
    })
}

// `..d`: a field added to `Limits` later keeps its default here until it is sent.
#[allow(clippy::needless_update)]
fn limits_from_value(v: &Value) -> Limits {
    let d = Limits::default();
    let u = |k: &str, or: u64| v.get(k).and_then(Value::as_u64).unwrap_or(or);
    let z = |k: &str, or: usize| u(k, or as u64) as usize;
    Limits {
        max_body_bytes: z("max_body_bytes", d.max_body_bytes),
        max_blocks: z("max_blocks", d.max_blocks),
        max_record_samples: z("max_record_samples", d.max_record_samples),
        max_total_steps: u("max_total_steps", d.max_total_steps),
        max_block_vertices: z("max_block_vertices", d.max_block_vertices),
        max_scan_points: z("max_scan_points", d.max_scan_points),
        max_queued_jobs: u("max_queued_jobs", d.max_queued_jobs),
        max_block_steps: u("max_block_steps", d.max_block_steps),
        max_block_frames: u("max_block_frames", d.max_block_frames),
        max_search_block_steps: u("max_search_block_steps", d.max_search_block_steps),
        max_json_values: z("max_json_values", d.max_json_values),
        max_job_seconds: u("max_job_seconds", d.max_job_seconds),
        max_job_artifact_bytes: u("max_job_artifact_bytes", d.max_job_artifact_bytes),
        max_artifact_bytes: u("max_artifact_bytes", d.max_artifact_bytes),
        ..d
    }
}

/// Most bytes of a child's stderr kept for the log (the end of it: a panic message, the
/// allocator's "memory allocation of N bytes failed").
const STDERR_TAIL: usize = 8 << 10;

/// Run one job (`Run` or an in-process `PgaSearch`) in a child process; same contract as a
/// [`super::run::JobRunner`]: progress through `hooks`, stops when `hooks.cancel` is set.
pub fn run_in_child(
    params: &ProcessParams,
    kind: JobKind,
    request: &Value,
    limits: &Limits,
    hooks: &RunHooks<'_>,
) -> Result<RunnerOutcome, JobError> {
    run_spec_in_child(params, kind, request, None, limits, hooks)
}

/// Run one child run (`pga_run`) of a fanned-out search in a child process: `search` is the
/// search's stored request, `run` the amplitude and record. Its outcome is the
/// [`super::fanout::ChildResult`] the in-thread path stores.
pub fn run_pga_run_in_child(
    params: &ProcessParams,
    search: &Value,
    run: &ChildRequest,
    limits: &Limits,
    hooks: &RunHooks<'_>,
) -> Result<RunnerOutcome, JobError> {
    run_spec_in_child(
        params,
        JobKind::PgaRun,
        search,
        Some(run.clone()),
        limits,
        hooks,
    )
}

fn run_spec_in_child(
    params: &ProcessParams,
    kind: JobKind,
    request: &Value,
    pga_run: Option<ChildRequest>,
    limits: &Limits,
    hooks: &RunHooks<'_>,
) -> Result<RunnerOutcome, JobError> {
    use std::process::{Command, Stdio};
    let spec = ChildSpec {
        kind: kind.as_str().to_string(),
        request: request.clone(),
        pga_run,
        limits: limits_to_value(limits),
        out_dir: hooks.out_dir.to_path_buf(),
        memory_limit: params.memory_limit,
        cpu_seconds: params.cpu_seconds,
        file_size_limit: limits.max_job_artifact_bytes,
        fake_ms: params.fake.map(|d| d.as_millis() as u64),
        parent_pid: std::process::id(),
    };
    let mut line = serde_json::to_vec(&spec)?;
    line.push(b'\n');
    let mut cmd = Command::new(&params.exe);
    cmd.arg("internal-run-job")
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        // glibc reserves 64 MB of address space per malloc arena (up to 8 per core): under an
        // address-space limit that reservation, not the run, would be what runs out.
        .env("MALLOC_ARENA_MAX", "2");
    for (k, v) in &params.env {
        cmd.env(k, v);
    }
    let mut child = cmd.spawn().map_err(|e| {
        tracing::error!(exe = %params.exe.display(), error = %e, "starting a job's process");
        ProcessError::Spawn(e)
    })?;
    let pid = child.id();
    let (Some(mut stdin), Some(stdout), Some(stderr)) =
        (child.stdin.take(), child.stdout.take(), child.stderr.take())
    else {
        let _ = child.kill();
        let _ = child.wait();
        return Err(ProcessError::Pipes.into());
    };
    // A 16 MB request is more than a pipe holds: write it from a thread while we read.
    let writer = std::thread::spawn(move || {
        let ok = stdin.write_all(&line).and_then(|()| stdin.flush()).is_ok();
        (stdin, ok)
    });
    let tail = Arc::new(Mutex::new(Vec::<u8>::new()));
    let tail_w = tail.clone();
    let err_reader = std::thread::spawn(move || {
        let mut r = std::io::BufReader::new(stderr);
        let mut buf = [0u8; 4096];
        while let Ok(n) = r.read(&mut buf) {
            if n == 0 {
                break;
            }
            if let Ok(mut t) = tail_w.lock() {
                t.extend_from_slice(&buf[..n]);
                let excess = t.len().saturating_sub(STDERR_TAIL);
                t.drain(..excess);
            }
        }
    });
    let (tx, rx) = mpsc::channel::<String>();
    let out_reader = std::thread::spawn(move || {
        for l in std::io::BufReader::new(stdout).lines() {
            match l {
                Ok(l) => {
                    if tx.send(l).is_err() {
                        break;
                    }
                }
                Err(_) => break,
            }
        }
    });
    let mut outcome: Option<ChildMessage> = None;
    let mut cancel_sent: Option<Instant> = None;
    let mut killed = false;
    let mut stdin = None;
    let mut writer = Some(writer);
    loop {
        match rx.recv_timeout(Duration::from_millis(50)) {
            Ok(l) => match serde_json::from_str::<ChildMessage>(&l) {
                Ok(ChildMessage::Progress { progress }) => (hooks.progress)(progress),
                Ok(m) => outcome = Some(m),
                Err(_) => tracing::debug!(pid, line = %l, "a job's process wrote a stray line"),
            },
            Err(mpsc::RecvTimeoutError::Timeout) => {}
            Err(mpsc::RecvTimeoutError::Disconnected) => break,
        }
        if writer.as_ref().is_some_and(|w| w.is_finished()) {
            if let Some(Ok((s, ok))) = writer.take().map(|w| w.join()) {
                if ok {
                    stdin = Some(s);
                }
            }
        }
        if hooks.cancel.load(Ordering::SeqCst) && !killed {
            match cancel_sent {
                None => {
                    if let Some(s) = stdin.as_mut() {
                        let _ = s.write_all(b"cancel\n").and_then(|()| s.flush());
                    }
                    cancel_sent = Some(Instant::now());
                }
                Some(t) if t.elapsed() > params.cancel_grace => {
                    tracing::warn!(pid, "a job's process did not stop when asked; killed");
                    let _ = child.kill();
                    killed = true;
                }
                Some(_) => {}
            }
        }
    }
    let status = child.wait().map_err(|e| {
        tracing::error!(pid, error = %e, "waiting for a job's process");
        ProcessError::Wait(e)
    })?;
    drop(stdin);
    if let Some(w) = writer {
        let _ = w.join();
    }
    let _ = out_reader.join();
    let _ = err_reader.join();
    let tail = tail
        .lock()
        .map(|t| String::from_utf8_lossy(&t).into_owned())
        .unwrap_or_default();
    match (outcome, status.success()) {
        (Some(ChildMessage::Completed { value }), true) => Ok(RunnerOutcome::Completed(value)),
        (Some(ChildMessage::Cancelled { partial }), true) => Ok(RunnerOutcome::Cancelled(partial)),
        (Some(ChildMessage::Error { message }), _) => {
            if !tail.trim().is_empty() {
                tracing::error!(pid, stderr = %tail.trim(), "a job's run failed");
            }
            Err(ProcessError::Reported(message).into())
        }
        _ => {
            let msg = exit_cause(params, limits, status, &tail, killed);
            tracing::error!(pid, status = %status, stderr = %tail.trim(), "a job's process ended abnormally: {msg}");
            Err(ProcessError::Ended(msg).into())
        }
    }
}

/// What the user reads when a child ended without saying how its run went.
fn exit_cause(
    params: &ProcessParams,
    limits: &Limits,
    status: std::process::ExitStatus,
    stderr: &str,
    killed: bool,
) -> ProcessEnd {
    let out_of_memory = stderr.contains("memory allocation of")
        || stderr.contains("Cannot allocate memory")
        || stderr.contains("out of memory");
    let sig = signal_of(status);
    if out_of_memory {
        return if params.memory_limit > 0 {
            ProcessEnd::MemoryLimit {
                bytes: params.memory_limit,
                human: human_bytes(params.memory_limit),
            }
        } else {
            ProcessEnd::OutOfMemory
        };
    }
    match sig {
        Some(9) if killed => ProcessEnd::KilledAfterCancel,
        Some(9) => ProcessEnd::Killed,
        Some(24) => ProcessEnd::CpuLimit {
            seconds: params.cpu_seconds,
        },
        Some(25) => ProcessEnd::FileLimit {
            bytes: limits.max_job_artifact_bytes,
        },
        Some(s) => ProcessEnd::Crashed {
            signal: s,
            name: signal_name(s),
        },
        None => ProcessEnd::Exited {
            code: status.code().unwrap_or(-1),
        },
    }
}

#[cfg(unix)]
fn signal_of(status: std::process::ExitStatus) -> Option<i32> {
    std::os::unix::process::ExitStatusExt::signal(&status)
}

#[cfg(not(unix))]
fn signal_of(_: std::process::ExitStatus) -> Option<i32> {
    None
}

fn signal_name(s: i32) -> &'static str {
    match s {
        4 => "SIGILL",
        6 => "SIGABRT",
        7 => "SIGBUS",
        8 => "SIGFPE",
        9 => "SIGKILL",
        11 => "SIGSEGV",
        15 => "SIGTERM",
        24 => "SIGXCPU",
        25 => "SIGXFSZ",
        _ => "a signal",
    }
}

fn human_bytes(b: u64) -> String {
    if b >= 1 << 30 {
        format!("{:.1} GiB", b as f64 / (1u64 << 30) as f64)
    } else {
        format!("{:.0} MiB", b as f64 / (1u64 << 20) as f64)
    }
}

/// A byte count (`--job-memory-limit`) that does not read: not a whole number with an optional
/// K, M or G suffix, or over 2^64 (the text given).
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("{text:?}: expected bytes, or a number with K, M or G")]
pub struct BytesError {
    pub text: String,
}

/// Parse `--job-memory-limit`: bytes, or with a K/M/G suffix (powers of 1024); 0 is no limit.
pub fn parse_bytes(s: &str) -> Result<u64, BytesError> {
    let bad = || BytesError {
        text: s.to_string(),
    };
    let t = s.trim();
    let (num, mult) = match t.char_indices().next_back() {
        Some((i, c)) if c.is_ascii_alphabetic() => {
            let m = match c.to_ascii_uppercase() {
                'K' => 1u64 << 10,
                'M' => 1 << 20,
                'G' => 1 << 30,
                _ => return Err(bad()),
            };
            (&t[..i], m)
        }
        _ => (t, 1),
    };
    num.trim()
        .parse::<u64>()
        .ok()
        .and_then(|n| n.checked_mul(mult))
        .ok_or_else(bad)
}

// ---------------------------------------------------------------------------------------------
// The child side: `ashlar internal-run-job`.

/// The child's stop switch, thrown by a `cancel` line on stdin.
static CANCEL: AtomicBool = AtomicBool::new(false);

fn emit(out: &Mutex<std::io::Stdout>, m: &ChildMessage) {
    if let (Ok(mut o), Ok(text)) = (out.lock(), serde_json::to_string(m)) {
        let _ = writeln!(o, "{text}").and_then(|()| o.flush());
    }
}

/// Why `ashlar internal-run-job` could not start the job it was given.
#[derive(Debug, thiserror::Error)]
pub enum ChildError {
    /// Standard input (the job's first line) could not be read.
    #[error("internal-run-job: reading the job: {0}")]
    ReadJob(#[source] std::io::Error),
    /// The first line is not a job spec: the command was not started by a server.
    #[error("internal-run-job is started by `ashlar serve` only ({0})")]
    NotFromServer(#[source] serde_json::Error),
    /// The server that started this process exited before the child could tie itself to it.
    #[error("internal-run-job: the server that started this run is gone")]
    ParentGone,
    /// A resource limit (`memory`, `CPU`, `file size`) could not be set.
    #[error("internal-run-job: setting the {what} limit: {source}")]
    Limit {
        what: &'static str,
        source: std::io::Error,
    },
}

/// Entry point of the hidden `ashlar internal-run-job` (started by the server, never by users).
pub fn child_main() -> Result<(), ChildError> {
    let mut input = std::io::BufReader::new(std::io::stdin());
    let mut first = String::new();
    input.read_line(&mut first).map_err(ChildError::ReadJob)?;
    let spec: ChildSpec = serde_json::from_str(&first).map_err(ChildError::NotFromServer)?;
    guard_parent(&spec)?;
    set_limits(&spec)?;
    // Further lines: `cancel`; the end of stdin means the server is gone or gave up on us.
    std::thread::spawn(move || {
        let mut l = String::new();
        loop {
            l.clear();
            match input.read_line(&mut l) {
                Ok(0) | Err(_) => std::process::exit(3),
                Ok(_) if l.trim() == "cancel" => CANCEL.store(true, Ordering::SeqCst),
                Ok(_) => {}
            }
        }
    });
    let out = Mutex::new(std::io::stdout());
    let msg = match std::panic::catch_unwind(|| run_spec(&spec, &out)) {
        Ok(Ok(m)) => m,
        Ok(Err(e)) => ChildMessage::Error {
            message: e.to_string(),
        },
        Err(_) => ChildMessage::Error {
            message:
                "the computation crashed (an internal error in ashlar; the cause has been logged)"
                    .into(),
        },
    };
    emit(&out, &msg);
    Ok(())
}

fn run_spec(spec: &ChildSpec, out: &Mutex<std::io::Stdout>) -> Result<ChildMessage, JobError> {
    let limits = limits_from_value(&spec.limits);
    if spec.kind == "pga_run" {
        let run = spec.pga_run.as_ref().ok_or(Inconsistent::ChildNotTold)?;
        let input = parse_pga(&spec.request, &limits)
            .map_err(JobError::rejected)?
            .input;
        test_fault(&input.scene().name);
        return Ok(match super::fanout::evaluate_child(&input, run, &CANCEL)? {
            RunnerOutcome::Completed(value) => ChildMessage::Completed { value },
            RunnerOutcome::Cancelled(partial) => ChildMessage::Cancelled { partial },
        });
    }
    let parsed = match spec.kind.as_str() {
        "run" => parse_run(&spec.request, &limits),
        "pga_search" => parse_pga(&spec.request, &limits),
        "site_analysis" => parse_site(&spec.request, &limits),
        k => return Err(Inconsistent::NotInChild(k.to_string()).into()),
    }
    .map_err(JobError::rejected)?;
    let input: JobInput = parsed.input;
    test_fault(&input.scene().name);
    let runner = match spec.fake_ms {
        Some(ms) => crate::service::fake::fake_runner(Duration::from_millis(ms)),
        None => super::run::analysis_runner(),
    };
    // Progress at most every 50 ms (a run reports every output frame): the server forwards
    // each line to the job's event stream.
    let last = Mutex::new(None::<Instant>);
    let progress = |p: f64| {
        let due = last.lock().map(|mut t| {
            let due = t.is_none_or(|t| t.elapsed() >= Duration::from_millis(50)) || p >= 1.0;
            if due {
                *t = Some(Instant::now());
            }
            due
        });
        if due.unwrap_or(false) {
            emit(out, &ChildMessage::Progress { progress: p });
        }
    };
    let hooks = RunHooks {
        out_dir: &spec.out_dir,
        cancel: &CANCEL,
        progress: &progress,
    };
    Ok(match runner(&input, &hooks)? {
        RunnerOutcome::Completed(value) => ChildMessage::Completed { value },
        RunnerOutcome::Cancelled(partial) => ChildMessage::Cancelled { partial },
    })
}

/// Die with the server: PR_SET_PDEATHSIG (Linux), then make sure the server did not die before
/// that took effect (our parent would already be another process).
fn guard_parent(spec: &ChildSpec) -> Result<(), ChildError> {
    #[cfg(target_os = "linux")]
    {
        let _ = nix::sys::prctl::set_pdeathsig(nix::sys::signal::Signal::SIGKILL);
    }
    #[cfg(unix)]
    {
        if nix::unistd::getppid().as_raw() as u32 != spec.parent_pid {
            return Err(ChildError::ParentGone);
        }
    }
    let _ = spec;
    Ok(())
}

fn set_limits(spec: &ChildSpec) -> Result<(), ChildError> {
    #[cfg(unix)]
    {
        use nix::sys::resource::{setrlimit, Resource};
        let set = |r: Resource, v: u64, what: &'static str| -> Result<(), ChildError> {
            if v == 0 {
                return Ok(());
            }
            setrlimit(r, v as _, v as _).map_err(|e| ChildError::Limit {
                what,
                source: e.into(),
            })
        };
        set(Resource::RLIMIT_AS, spec.memory_limit, "memory")?;
        // The soft CPU limit sends SIGXCPU (the cause the server reports); the hard one, a
        // second later, SIGKILL.
        if spec.cpu_seconds > 0 {
            setrlimit(
                Resource::RLIMIT_CPU,
                spec.cpu_seconds as _,
                spec.cpu_seconds.saturating_add(1) as _,
            )
            .map_err(|e| ChildError::Limit {
                what: "CPU",
                source: e.into(),
            })?;
        }
        set(Resource::RLIMIT_FSIZE, spec.file_size_limit, "file size")?;
    }
    let _ = spec;
    Ok(())
}

/// Test-only faults, for the isolation tests: in a debug build, with `ASHLAR_TEST_FAULTS=1` in
/// the child's environment, a scene named `fault:abort`, `fault:segv`, `fault:alloc` (allocate
/// and touch memory until the limit), `fault:spin` (burn CPU) or `fault:panic` misbehaves.
/// Release builds never do.
fn test_fault(scene_name: &str) {
    if !cfg!(debug_assertions) || std::env::var_os("ASHLAR_TEST_FAULTS").is_none() {
        return;
    }
    match scene_name.strip_prefix("fault:") {
        Some("abort") => std::process::abort(),
        #[cfg(unix)]
        Some("segv") => {
            // The first SIGSEGV goes to std's stack-overflow handler, which restores the
            // default action and returns (no fault address); the second one kills.
            for _ in 0..2 {
                let _ = nix::sys::signal::raise(nix::sys::signal::Signal::SIGSEGV);
            }
        }
        Some("alloc") => {
            let mut hog: Vec<Vec<u8>> = Vec::new();
            loop {
                hog.push(vec![1u8; 16 << 20]);
                std::hint::black_box(&hog);
            }
        }
        Some("spin") => {
            let mut x = 0u64;
            loop {
                x = std::hint::black_box(x.wrapping_mul(6364136223846793005).wrapping_add(1));
            }
        }
        Some("panic") => panic!("test fault: a panic in the job's process"),
        _ => {}
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn limits_round_trip_through_the_spec() {
        let l = Limits {
            max_total_steps: 1234,
            max_job_artifact_bytes: 99,
            ..Limits::default()
        };
        assert_eq!(limits_from_value(&limits_to_value(&l)), l);
    }

    #[test]
    fn byte_sizes_parse() {
        assert_eq!(parse_bytes("512M"), Ok(512 << 20));
        assert_eq!(parse_bytes("8G"), Ok(8 << 30));
        assert_eq!(parse_bytes("1000"), Ok(1000));
        assert!(parse_bytes("lots").is_err());
        assert!(parse_bytes("9999999999999G").is_err());
    }
}
