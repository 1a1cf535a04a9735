//! Service › `ashlar serve`: its arguments (`ServeArgs`), its entry point (`serve_cli`), the
//! isolation its flags ask for, and its start-up errors (`ServeError`): why `ashlar serve` (its
//! options, its socket, its runtime, the service's start) or `ashlar internal-run-job` (a job's
//! child process) did not run. The CLI prints one as `ashlar: …`, one line; each cause is a
//! variant, so a caller can match on it.
use super::worker::runner::{self, ChildError};
use super::{
    analysis_runner, app, auth, fake, fanout_width, lease_params, parse_database, retention,
    server, Database, Limits, Service, ServiceConfig, ShutdownSignals, StartError,
};
use std::net::SocketAddr;
use std::path::PathBuf;
use std::sync::Arc;
use std::time::Duration;

/// Why `ashlar serve` or `ashlar internal-run-job` stopped before serving (or while serving).
#[derive(Debug, thiserror::Error)]
pub enum ServeError {
    /// `--database`: not a `sqlite:PATH` or PostgreSQL URL.
    #[error(transparent)]
    Database(#[from] super::DatabaseError),
    /// `--lease`: out of range.
    #[error(transparent)]
    Lease(#[from] super::LeaseError),
    /// A duration option (`--header-timeout`, `--body-timeout`, `--idle-timeout`) out of range.
    #[error("--{option} must be a number of seconds between 0.1 and 86400, got {value}")]
    Seconds { option: &'static str, value: f64 },
    /// `--max-connections 0`.
    #[error("--max-connections must be at least 1")]
    NoConnections,
    /// `--cors-origin` that is not `scheme://host[:port]`.
    #[error(
        "--cors-origin {origin:?}: expected an origin, scheme://host[:port], e.g. https://app.foxglove.dev"
    )]
    CorsOrigin { origin: String },
    /// `--tokens FILE`: unreadable or malformed (the file and the line).
    #[error(transparent)]
    Tokens(#[from] auth::TokensFileError),
    /// `--signed-url-seconds` outside 1 s … a week.
    #[error("--signed-url-seconds must be between 1 and 604800 (a week), got {0}")]
    SignedUrlSeconds(u64),
    /// `--signing-key-file`: unreadable or too short (the file).
    #[error(transparent)]
    SigningKey(#[from] auth::SigningKeyFileError),
    /// `--workers 0` without a PostgreSQL database (nothing would run the jobs).
    #[error("--workers must be at least 1 (0 only with a PostgreSQL --database, whose `ashlar worker` processes run the jobs)")]
    NoWorkers,
    /// `--shutdown-grace` negative or not a number.
    #[error("--shutdown-grace must be a number of seconds ≥ 0, got {0}")]
    ShutdownGrace(f64),
    /// `--isolation process`: the executable to start for each job was not found.
    #[error("--isolation process: cannot find the ashlar executable: {0}")]
    Executable(#[source] std::io::Error),
    /// The async runtime could not start.
    #[error("starting the async runtime: {0}")]
    Runtime(#[source] std::io::Error),
    /// `--addr`: cannot bind (in use, not an address of this machine) or read the bound address.
    #[error("--addr {addr}: {source}")]
    Bind {
        addr: String,
        source: std::io::Error,
    },
    /// `--addr` reachable from other machines without `--tokens` or `--allow-insecure`.
    #[error(
        "--addr {addr} is reachable from other machines, and without --tokens anyone who reaches \
         the port could submit, read and delete jobs. Give --tokens FILE, or pass --allow-insecure \
         on a network you trust"
    )]
    Insecure { addr: SocketAddr },
    /// The service (store, workers, artifact store, sweeper) did not start.
    #[error(transparent)]
    Start(#[from] StartError),
    /// Accepting connections failed while serving.
    #[error("serving: {0}")]
    Serve(#[source] std::io::Error),
    /// `ashlar internal-run-job` (a job's child process) could not start its job.
    #[error(transparent)]
    Child(#[from] ChildError),
}

/// `ashlar serve` arguments.
#[derive(Debug, Clone, clap::Args)]
pub struct ServeArgs {
    /// Address to listen on (port 0 picks a free port; the chosen address is printed).
    #[arg(long, default_value = "127.0.0.1:8080")]
    pub addr: String,
    /// Job store URL instead of the embedded default: `sqlite:PATH` (artifacts go to --data),
    /// or `postgres://USER@HOST:PORT/DBNAME` to share one queue with `ashlar worker` processes
    /// (TLS: libpq's `?sslmode=verify-full&sslrootcert=CA.pem`, see docs/cluster.md).
    #[arg(long)]
    pub database: Option<String>,
    /// The flags `ashlar worker` has too: directories, threads, lease, fan-out, run limits.
    #[command(flatten)]
    pub process: ProcessArgs,
    /// Largest request body, bytes (413 beyond).
    #[arg(long, default_value_t = Limits::default().max_body_bytes)]
    pub max_body_bytes: usize,
    /// Most jobs waiting in the queue (429 with Retry-After beyond).
    #[arg(long, default_value_t = Limits::default().max_queued_jobs)]
    pub max_queued_jobs: u64,
    /// With --tokens: most runs one token may have waiting in the queue (429 beyond).
    #[arg(long, default_value_t = Limits::default().max_queued_jobs_per_token)]
    pub max_queued_jobs_per_token: u64,
    /// With --tokens: most PGA searches one token may have waiting in the queue (429 beyond).
    #[arg(long, default_value_t = Limits::default().max_queued_searches_per_token)]
    pub max_queued_searches_per_token: u64,
    /// Most blocks × steps of one run (422 beyond; see `GET /v1/limits`).
    #[arg(long, default_value_t = Limits::default().max_block_steps)]
    pub max_block_steps: u64,
    /// Most blocks × recorded frames of one run (422 beyond).
    #[arg(long, default_value_t = Limits::default().max_block_frames)]
    pub max_block_frames: u64,
    /// Most runs × blocks × steps of one PGA search (422 beyond).
    #[arg(long, default_value_t = Limits::default().max_search_block_steps)]
    pub max_search_block_steps: u64,
    /// Most JSON values in a request body, counted while reading (422 beyond).
    #[arg(long, default_value_t = Limits::default().max_json_values)]
    pub max_json_values: usize,
    /// Bytes of all jobs' artifacts under --data; submissions get 507 beyond.
    #[arg(long, default_value_t = Limits::default().max_artifact_bytes)]
    pub max_artifact_bytes: u64,
    /// Open connections at once; more are closed on accept.
    #[arg(long, default_value_t = server::ServerParams::default().max_connections)]
    pub max_connections: usize,
    /// Seconds a client has to send a request's headers.
    #[arg(long, default_value_t = server::ServerParams::default().header_read_timeout.as_secs_f64())]
    pub header_timeout: f64,
    /// Seconds a client has to send a submission's body (408 beyond).
    #[arg(long, default_value_t = server::ServerParams::default().body_read_timeout.as_secs_f64())]
    pub body_timeout: f64,
    /// Seconds a connection may stay with nothing read or written before it is closed.
    #[arg(long, default_value_t = server::ServerParams::default().idle_timeout.as_secs_f64())]
    pub idle_timeout: f64,
    /// Require `Authorization: Bearer TOKEN` on every /v1/ request (401 without): a file of
    /// lines `ROLE TOKEN` (ROLE user or admin; TOKEN the token, or `sha256:HEX` its digest).
    #[arg(long, value_name = "FILE")]
    pub tokens: Option<PathBuf>,
    /// With --tokens: the key (a file of at least 32 bytes) that signs the short-lived URLs of
    /// artifact and event links a browser or Foxglove opens without headers. Default: a random
    /// key per start (links then stop working when the server restarts).
    #[arg(long, value_name = "FILE")]
    pub signing_key_file: Option<PathBuf>,
    /// Seconds a signed URL stays valid.
    #[arg(long, default_value_t = auth::SIGNED_URL_SECONDS)]
    pub signed_url_seconds: u64,
    /// Delete finished jobs and searches (and their artifacts) this long after they ended,
    /// e.g. `7d`, `12h`, `30m`, `90s`. Default: keep them until deleted.
    #[arg(long, value_name = "DURATION", value_parser = retention::parse_duration)]
    pub retain_finished: Option<Duration>,
    /// An origin whose web pages may call the API from a browser (CORS), repeatable; e.g.
    /// `--cors-origin https://app.foxglove.dev` for the "open in Foxglove" link. None by default.
    #[arg(long = "cors-origin", value_name = "ORIGIN")]
    pub cors_origins: Vec<String>,
    /// Listen on a non-loopback address although the service has no access control (anyone
    /// who reaches the port can submit, read and delete jobs). Without it such an --addr is
    /// refused.
    #[arg(long)]
    pub allow_insecure: bool,
    /// Testing aid: run jobs with the service's deterministic fake runner instead of the engine.
    #[arg(long, hide = true)]
    pub fake_runner: bool,
    #[command(flatten)]
    pub jobs: JobRunArgs,
}

/// The flags of a process that runs jobs, shared by `ashlar serve` and `ashlar worker`
/// (`#[command(flatten)]` in both; `--database` is not among them: optional for `serve`,
/// required for `worker`).
#[derive(Debug, Clone, clap::Args)]
pub struct ProcessArgs {
    /// Directory for the embedded job store (`jobs.sqlite`, `ashlar serve` without a
    /// PostgreSQL --database) and the artifacts of the jobs this process runs
    /// (`jobs/<uuid>/`; a scratch copy with --artifacts, else give every process of a cluster
    /// the same shared directory).
    #[arg(long, default_value = "./ashlar-data")]
    pub data: PathBuf,
    /// Shared artifact storage (`file:///DIR`, or `s3://BUCKET/PREFIX` with the `s3` feature):
    /// workers publish finished jobs' files there and the API serves them from there.
    #[arg(long)]
    pub artifacts: Option<String>,
    /// Jobs run at once, one per worker thread (default: the number of cores; `ashlar serve`
    /// with a PostgreSQL --database may take 0: an API-only process, `ashlar worker`
    /// processes run the jobs).
    #[arg(long)]
    pub workers: Option<usize>,
    /// PostgreSQL store: seconds a claimed job stays leased without a heartbeat (heartbeat: a
    /// third of it).
    #[arg(long, default_value_t = 30.0)]
    pub lease: f64,
    /// Seconds running jobs get to finish on SIGINT/SIGTERM before they are stopped and requeued.
    #[arg(long, default_value_t = 20.0)]
    pub shutdown_grace: f64,
    /// PGA searches fan out their runs as child jobs shared by every worker process, with N
    /// interior amplitudes per k-section round (default with a PostgreSQL --database: the
    /// number of cores; 0: each search runs on the cores of the worker that claims it, the
    /// embedded store's default).
    #[arg(long)]
    pub fanout_width: Option<usize>,
    /// Most blocks in a scene (the API answers 422 beyond; give workers the API's value).
    #[arg(long, default_value_t = Limits::default().max_blocks)]
    pub max_blocks: usize,
    /// Most samples in a ground-motion record, both components together (the API answers 422
    /// beyond; give workers the API's value).
    #[arg(long, default_value_t = Limits::default().max_record_samples)]
    pub max_record_samples: usize,
    /// Most steps of one run, duration / time_step (the API answers 422 beyond; give workers
    /// the API's value).
    #[arg(long, default_value_t = Limits::default().max_total_steps)]
    pub max_total_steps: u64,
}

/// The flags of how one job runs, shared by `ashlar serve` and `ashlar worker`
/// (`#[command(flatten)]` in both): its time and artifact limits, where it runs, and its
/// process's resource limits.
#[derive(Debug, Clone, clap::Args)]
pub struct JobRunArgs {
    /// Wall-clock seconds one job (or one run of a fanned-out search) may run before it is
    /// stopped and failed (the process that runs it enforces it).
    #[arg(long, default_value_t = Limits::default().max_job_seconds)]
    pub max_job_seconds: u64,
    /// Bytes of artifacts one job may write before it is stopped and failed.
    #[arg(long, default_value_t = Limits::default().max_job_artifact_bytes)]
    pub max_job_artifact_bytes: u64,
    /// Where jobs run: `process` (a child process per job and per run of a fanned-out search,
    /// with the limits below: a crash or exhausted memory fails that job only, never the
    /// process that runs it) or `thread` (on the worker threads).
    #[arg(long, value_enum, default_value_t = IsolationFlag::default())]
    pub isolation: IsolationFlag,
    /// Address space of a job's process (RLIMIT_AS), bytes or with K/M/G; 0: no limit.
    /// With --isolation process.
    #[arg(long, default_value = "8G", value_parser = runner::parse_bytes)]
    pub job_memory_limit: u64,
    /// CPU seconds of a job's process (RLIMIT_CPU; default: --max-job-seconds × cores).
    #[arg(long)]
    pub job_cpu_seconds: Option<u64>,
}

/// `--isolation`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum IsolationFlag {
    Process,
    Thread,
}

impl Default for IsolationFlag {
    /// Child processes where they exist (Unix); threads elsewhere.
    fn default() -> Self {
        if cfg!(unix) {
            IsolationFlag::Process
        } else {
            IsolationFlag::Thread
        }
    }
}

/// The commands' log on standard error: `RUST_LOG`'s filter, else `default` (`None`: no log
/// unless `RUST_LOG` is set). A second call keeps the first subscriber.
pub fn init_logging(default: Option<&str>) {
    let filter = match (
        tracing_subscriber::EnvFilter::try_from_default_env(),
        default,
    ) {
        (Ok(filter), _) => filter,
        (Err(_), Some(d)) => tracing_subscriber::EnvFilter::new(d),
        (Err(_), None) => return,
    };
    let _ = tracing_subscriber::fmt()
        .with_env_filter(filter)
        .with_writer(std::io::stderr)
        // Colour codes only for a terminal: a log written to a file or a pipe stays plain text.
        .with_ansi(std::io::IsTerminal::is_terminal(&std::io::stderr()))
        .try_init();
}

/// Entry point of `ashlar serve`: blocks until SIGINT/SIGTERM, then shuts down gracefully.
pub fn serve_cli(args: ServeArgs) -> Result<(), ServeError> {
    init_logging(Some("info"));
    let mut config = ServiceConfig::new(&args.process.data);
    match args
        .database
        .as_deref()
        .map(parse_database)
        .transpose()
        .map_err(ServeError::Database)?
    {
        Some(Database::Sqlite(p)) => config.database = Some(p),
        Some(Database::Postgres(url)) => config.postgres = Some(url),
        None => {}
    }
    config.artifacts = args.process.artifacts.clone();
    config.api = true;
    config.lease = lease_params(args.process.lease).map_err(ServeError::Lease)?;
    config.limits = Limits {
        max_body_bytes: args.max_body_bytes,
        max_blocks: args.process.max_blocks,
        max_record_samples: args.process.max_record_samples,
        max_total_steps: args.process.max_total_steps,
        max_queued_jobs: args.max_queued_jobs,
        max_queued_jobs_per_token: args.max_queued_jobs_per_token,
        max_queued_searches_per_token: args.max_queued_searches_per_token,
        max_block_steps: args.max_block_steps,
        max_block_frames: args.max_block_frames,
        max_search_block_steps: args.max_search_block_steps,
        max_json_values: args.max_json_values,
        max_job_seconds: args.jobs.max_job_seconds,
        max_job_artifact_bytes: args.jobs.max_job_artifact_bytes,
        max_artifact_bytes: args.max_artifact_bytes,
        retain_finished: args.retain_finished,
        ..Limits::default()
    };
    let secs = |option: &'static str, value: f64| {
        if value.is_finite() && (0.1..=86_400.0).contains(&value) {
            Ok(Duration::from_secs_f64(value))
        } else {
            Err(ServeError::Seconds { option, value })
        }
    };
    if args.max_connections == 0 {
        return Err(ServeError::NoConnections);
    }
    for o in &args.cors_origins {
        let ok = (o.starts_with("https://") || o.starts_with("http://"))
            && !o
                .trim_end_matches('/')
                .split("://")
                .nth(1)
                .unwrap_or("")
                .contains('/')
            && axum::http::HeaderValue::from_str(o).is_ok();
        if !ok {
            return Err(ServeError::CorsOrigin { origin: o.clone() });
        }
    }
    let tokens = args
        .tokens
        .as_deref()
        .map(auth::Tokens::load)
        .transpose()
        .map_err(ServeError::Tokens)?
        .map(Arc::new);
    if !(1..=7 * 86_400).contains(&args.signed_url_seconds) {
        return Err(ServeError::SignedUrlSeconds(args.signed_url_seconds));
    }
    let validity = Duration::from_secs(args.signed_url_seconds);
    let signing = match (&tokens, &args.signing_key_file) {
        (_, Some(path)) => {
            Some(auth::SigningKey::load(path, validity).map_err(ServeError::SigningKey)?)
        }
        (Some(_), None) => Some(auth::SigningKey::random(validity)),
        (None, None) => None,
    };
    let server_params = server::ServerParams {
        signing: tokens.as_ref().and(signing),
        tokens,
        cors_origins: args
            .cors_origins
            .iter()
            .map(|o| o.trim_end_matches('/').to_string())
            .collect(),
        max_connections: args.max_connections,
        header_read_timeout: secs("header-timeout", args.header_timeout)?,
        body_read_timeout: secs("body-timeout", args.body_timeout)?,
        idle_timeout: secs("idle-timeout", args.idle_timeout)?,
        ..server::ServerParams::default()
    };
    if let Some(n) = args.process.workers {
        if n == 0 && config.postgres.is_none() {
            return Err(ServeError::NoWorkers);
        }
        config.workers.workers = n;
    }
    if !(args.process.shutdown_grace.is_finite() && args.process.shutdown_grace >= 0.0) {
        return Err(ServeError::ShutdownGrace(args.process.shutdown_grace));
    }
    if !args.fake_runner {
        config.workers.fanout_width =
            fanout_width(args.process.fanout_width, config.postgres.is_some());
    }
    config.workers.isolation = isolation(&args, &config.limits)?;
    let runner = if args.fake_runner {
        fake::fake_runner(Duration::from_millis(200))
    } else {
        analysis_runner()
    };
    let runtime = tokio::runtime::Builder::new_multi_thread()
        .enable_all()
        .build()
        .map_err(ServeError::Runtime)?;
    // Bind before starting workers: a port clash must not start running recovered jobs.
    let listener = runtime
        .block_on(tokio::net::TcpListener::bind(&args.addr))
        .map_err(|source| ServeError::Bind {
            addr: args.addr.clone(),
            source,
        })?;
    let local = listener.local_addr().map_err(|source| ServeError::Bind {
        addr: args.addr.clone(),
        source,
    })?;
    if !local.ip().is_loopback() && server_params.tokens.is_none() && !args.allow_insecure {
        return Err(ServeError::Insecure { addr: local });
    }
    let service = Service::start_with(config, runner, server_params.clone())?;
    let state = service.state();
    let signals = runtime.block_on(async { ShutdownSignals::register() });
    // One line on stdout that scripts (and the tests) read to find the port.
    println!("ashlar serve: listening on http://{local}");
    tracing::info!(%local, workers = state.core.params.workers, data = %args.process.data.display(), "listening");
    let served = runtime.block_on(async {
        let shutdown_state = state.clone();
        server::serve(listener, app(state), server_params, async move {
            signals.wait().await;
            tracing::info!(
                "shutting down: no new jobs; running jobs get {} s",
                args.process.shutdown_grace
            );
            shutdown_state.core.begin_shutdown();
        })
        .await
    });
    let requeued = service.shutdown(Duration::from_secs_f64(args.process.shutdown_grace));
    runtime.shutdown_timeout(Duration::from_secs(1));
    tracing::info!(requeued, "stopped");
    served.map_err(ServeError::Serve)
}

/// The isolation a `serve` command line asks for.
fn isolation(args: &ServeArgs, limits: &Limits) -> Result<runner::Isolation, ServeError> {
    isolation_for(
        args.jobs.isolation,
        args.jobs.job_memory_limit,
        args.jobs.job_cpu_seconds,
        limits,
        args.fake_runner.then(|| Duration::from_millis(200)),
    )
}

/// The isolation of `--isolation FLAG --job-memory-limit BYTES --job-cpu-seconds S` (`ashlar
/// serve` and `ashlar worker` alike); `fake`: the fake runner's slowness, for tests.
pub fn isolation_for(
    flag: IsolationFlag,
    memory_limit: u64,
    cpu_seconds: Option<u64>,
    limits: &Limits,
    fake: Option<Duration>,
) -> Result<runner::Isolation, ServeError> {
    if flag == IsolationFlag::Thread || !cfg!(unix) {
        return Ok(runner::Isolation::Thread);
    }
    let exe = std::env::current_exe().map_err(ServeError::Executable)?;
    let cores = std::thread::available_parallelism().map_or(1, |n| n.get()) as u64;
    let mut p = runner::ProcessParams::new(exe);
    p.memory_limit = memory_limit;
    p.cpu_seconds = cpu_seconds.unwrap_or_else(|| limits.max_job_seconds.saturating_mul(cores));
    p.fake = fake;
    Ok(runner::Isolation::Process(p))
}
