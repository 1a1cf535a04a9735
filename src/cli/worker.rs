//! `ashlar worker`: a process that only runs jobs, from a PostgreSQL queue shared with
//! `ashlar serve --database postgres://…` and any number of other workers. Thin: the service's
//! worker pool and cluster threads without the HTTP layer.
use crate::service::{self, Limits, ServiceConfig};
use std::time::Duration;

#[derive(Debug, clap::Args)]
pub struct WorkerArgs {
    /// The shared queue: postgres://USER@HOST:PORT/DBNAME.
    #[arg(long)]
    pub database: String,
    /// The flags `ashlar serve` has too: directories, threads, lease, fan-out, run limits.
    #[command(flatten)]
    pub process: service::serve::ProcessArgs,
    /// Seconds between looks at the queue when no notification came (NOTIFY wakes idle
    /// workers at once; this only bounds the delay if a notification is lost).
    #[arg(long, default_value_t = 5.0)]
    pub idle_poll: f64,
    /// Testing aid: the service's deterministic fake runner, N ms per simulated second.
    #[arg(long, hide = true)]
    pub fake_runner_ms: Option<u64>,
    /// The job flags `ashlar serve` has too (limits, isolation); this worker enforces them.
    #[command(flatten)]
    pub jobs: service::serve::JobRunArgs,
}

pub fn run(args: &WorkerArgs) -> Result<(), super::error::CliError> {
    use super::error::CliError;
    service::serve::init_logging(Some("info"));
    let url = match service::parse_database(&args.database)? {
        service::Database::Postgres(url) => url,
        service::Database::Sqlite(_) => {
            return Err(CliError::Usage(
                "--database: `ashlar worker` needs a PostgreSQL queue (postgres://…); with the embedded store, `ashlar serve` runs the jobs itself"
                    .into(),
            ))
        }
    };
    let mut config = ServiceConfig::new(&args.process.data);
    config.postgres = Some(url);
    config.artifacts = args.process.artifacts.clone();
    config.lease = service::lease_params(args.process.lease)?;
    config.limits = Limits {
        max_blocks: args.process.max_blocks,
        max_record_samples: args.process.max_record_samples,
        max_total_steps: args.process.max_total_steps,
        max_job_seconds: args.jobs.max_job_seconds,
        max_job_artifact_bytes: args.jobs.max_job_artifact_bytes,
        ..Limits::default()
    };
    if let Some(n) = args.process.workers {
        if n == 0 {
            return Err(CliError::Usage("--workers must be at least 1".into()));
        }
        config.workers.workers = n;
    }
    if !(args.idle_poll.is_finite() && args.idle_poll > 0.0 && args.idle_poll <= 3600.0) {
        return Err(CliError::Usage(format!(
            "--idle-poll must be a number of seconds in (0, 3600], got {}",
            args.idle_poll
        )));
    }
    config.workers.idle_poll = Duration::from_secs_f64(args.idle_poll);
    if !(args.process.shutdown_grace.is_finite() && args.process.shutdown_grace >= 0.0) {
        return Err(CliError::Usage(format!(
            "--shutdown-grace must be a number of seconds ≥ 0, got {}",
            args.process.shutdown_grace
        )));
    }
    if args.fake_runner_ms.is_none() {
        config.workers.fanout_width = service::fanout_width(args.process.fanout_width, true);
    }
    // Published artifacts are served by the API processes from shared storage: the local
    // copy is scratch, removed once the job ends (else it would fill this machine's disk).
    config.workers.discard_local_artifacts = config.artifacts.is_some();
    config.workers.isolation = service::isolation_for(
        args.jobs.isolation,
        args.jobs.job_memory_limit,
        args.jobs.job_cpu_seconds,
        &config.limits,
        args.fake_runner_ms.map(Duration::from_millis),
    )?;
    let runner = match args.fake_runner_ms {
        Some(ms) => service::fake::fake_runner(Duration::from_millis(ms)),
        None => service::analysis_runner(),
    };
    let workers = config.workers.workers;
    let svc = service::Service::start(config, runner)?;
    let runtime = tokio::runtime::Builder::new_current_thread()
        .enable_all()
        .build()
        .map_err(|source| CliError::Runtime {
            what: "the signal runtime",
            source,
        })?;
    // Caught from here on: a SIGTERM right after the line below must stop gracefully.
    let signals = runtime.block_on(async { service::ShutdownSignals::register() });
    // One line on stdout that scripts (and the tests) wait for.
    println!("ashlar worker: running {workers} job(s) at a time");
    tracing::info!(workers, "worker started");
    runtime.block_on(signals.wait());
    tracing::info!(
        "stopping: no new claims; running jobs get {} s",
        args.process.shutdown_grace
    );
    let requeued = svc.shutdown(Duration::from_secs_f64(args.process.shutdown_grace));
    tracing::info!(requeued, "stopped");
    Ok(())
}
