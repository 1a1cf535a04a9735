//! Service: HTTP routes → durable queue → store → worker threads, driving `analysis`.
//! The top of the flow; nothing in the physics core imports it.
//!
//! `http` answers requests (one router per resource; async, no simulation work), `store` keeps
//! every job durably, `worker` runs jobs on std threads through a `JobRunner`, `events` streams
//! progress (docs/architecture.md, "The service").
pub mod auth;
pub mod events;
pub mod fake;
pub mod histories;
pub mod http;
pub mod jobs;
pub mod request;
pub mod retention;
pub mod serve;
pub mod server;
pub mod store;
pub mod worker;

// The paths the CLI, the tests and the store use from before the layering (service/http/,
// service/worker/, service/store/), kept so that their callers need not change.
pub use http::problem;
pub use request::budget;
pub use store::{postgres as pg_store, tls as pg_tls};
pub use worker::{artifacts, runner};

pub use http::problem::ApiError;
pub use http::{app, route_table, AppState, OPENAPI_YAML};
pub use request::Limits;
pub use serve::{isolation_for, serve_cli, IsolationFlag, ServeArgs, ServeError};
pub use store::{JobStore, SqliteStore, StoreError};
pub use worker::{analysis_runner, JobRunner, RunHooks, RunnerOutcome, WorkerParams};

use std::path::PathBuf;
use std::sync::Arc;
use std::time::Duration;

/// The fan-out width a process uses: `--fanout-width` if given (0: none), else fan out on a
/// shared (PostgreSQL) store with one interior point per core, like the in-process search.
pub fn fanout_width(flag: Option<usize>, postgres: bool) -> Option<usize> {
    match flag {
        Some(0) => None,
        Some(n) => Some(n),
        None if postgres => Some(rayon::current_num_threads().max(1)),
        None => None,
    }
}

/// How to start the service (the library form of `ServeArgs`).
#[derive(Debug, Clone)]
pub struct ServiceConfig {
    /// Artifacts go to `<data_dir>/jobs/<uuid>/`.
    pub data_dir: PathBuf,
    /// The SQLite file (default `<data_dir>/jobs.sqlite`).
    pub database: Option<PathBuf>,
    pub limits: Limits,
    pub workers: WorkerParams,
    /// A PostgreSQL URL: the cluster store instead of SQLite (`database` is then ignored).
    pub postgres: Option<String>,
    /// Shared artifact storage URL (see [`artifacts::ArtifactStore::open`]).
    pub artifacts: Option<String>,
    pub lease: store::postgres::LeaseParams,
    /// This process takes submissions (`ashlar serve`): on a PostgreSQL store it publishes its
    /// limits as the API's, which workers compare theirs with.
    pub api: bool,
}

impl ServiceConfig {
    pub fn new(data_dir: impl Into<PathBuf>) -> Self {
        Self {
            data_dir: data_dir.into(),
            database: None,
            limits: Limits::default(),
            workers: WorkerParams::default(),
            postgres: None,
            artifacts: None,
            lease: store::postgres::LeaseParams::default(),
            api: false,
        }
    }
}

/// A started service: the state for the router, and the worker pool behind it.
/// Why [`Service::start`] failed.
#[derive(Debug, thiserror::Error)]
pub enum StartError {
    /// The `--data` folder could not be created.
    #[error("--data {}: {source}", path.display())]
    Data {
        path: PathBuf,
        source: std::io::Error,
    },
    /// The job store could not be opened or recovered.
    #[error(transparent)]
    Store(#[from] StoreError),
    /// The shared artifact storage (`--artifacts`) could not be opened.
    #[error(transparent)]
    Artifacts(#[from] worker::artifacts::ArtifactError),
    /// A thread of the service (a worker, the cluster's listener or lease keeper, a sweeper)
    /// could not be started.
    #[error(transparent)]
    Thread(#[from] worker::ThreadStartError),
}

pub struct Service {
    state: AppState,
    pool: worker::Pool,
    cluster: Option<worker::cluster::ClusterThreads>,
    sweeper: Option<retention::Sweeper>,
    cache_sweeper: Option<retention::CacheSweeper>,
}

impl Service {
    /// Open the store (recovering jobs a dead server left running) and start the workers.
    pub fn start(config: ServiceConfig, runner: JobRunner) -> Result<Self, StartError> {
        Self::start_with(config, runner, server::ServerParams::default())
    }

    /// [`Service::start`] with the HTTP server's limits (the routes read the body timeout).
    pub fn start_with(
        config: ServiceConfig,
        runner: JobRunner,
        server_params: server::ServerParams,
    ) -> Result<Self, StartError> {
        let jobs_dir = config.data_dir.join("jobs");
        std::fs::create_dir_all(&jobs_dir).map_err(|source| StartError::Data {
            path: config.data_dir.clone(),
            source,
        })?;
        let (store, pg): (Arc<dyn JobStore>, Option<Arc<store::postgres::PgStore>>) =
            match &config.postgres {
                Some(url) => {
                    let pg = Arc::new(store::postgres::PgStore::open(url, config.lease.clone())?);
                    (pg.clone(), Some(pg))
                }
                None => {
                    let db = config
                        .database
                        .clone()
                        .unwrap_or_else(|| config.data_dir.join("jobs.sqlite"));
                    (Arc::new(SqliteStore::open(&db)?), None)
                }
            };
        // Embedded store: every job left running belongs to a dead server. Cluster store:
        // only those whose lease expired (the reaper keeps doing this while we run).
        let (requeued, failed) = store.recover(config.workers.max_attempts)?;
        if requeued + failed > 0 {
            tracing::info!(
                requeued,
                failed,
                "recovered jobs left running by a previous server"
            );
        }
        let api = config.api;
        let mut core = worker::Core::new(
            store,
            config.data_dir,
            config.limits,
            config.workers,
            runner,
        );
        core.server = server_params;
        if let Some(url) = &config.artifacts {
            core.artifacts = Some(Arc::new(artifacts::ArtifactStore::open(url)?));
        }
        core.remote_workers
            .store(pg.is_some(), std::sync::atomic::Ordering::SeqCst);
        let core = Arc::new(core);
        let cluster = match pg {
            Some(pg) => Some(worker::cluster::ClusterThreads::start(
                core.clone(),
                pg,
                api,
            )?),
            None => None,
        };
        let pool = worker::Pool::start(core.clone())?;
        let sweeper = core
            .limits
            .retain_finished
            .map(|keep| retention::Sweeper::start(core.clone(), keep))
            .transpose()?;
        // With shared artifact storage, cached copies of jobs deleted elsewhere are removed.
        let cache_sweeper = core
            .artifacts
            .is_some()
            .then(|| retention::CacheSweeper::start(core.clone(), retention::CACHE_SWEEP_EVERY))
            .transpose()?;
        Ok(Self {
            state: AppState { core },
            pool,
            cluster,
            sweeper,
            cache_sweeper,
        })
    }

    pub fn state(&self) -> AppState {
        self.state.clone()
    }

    /// Stop gracefully (see [`worker::Pool::shutdown`]); returns how many jobs were requeued.
    pub fn shutdown(self, grace: Duration) -> usize {
        if let Some(s) = self.sweeper {
            s.stop();
        }
        if let Some(s) = self.cache_sweeper {
            s.stop();
        }
        let n = self.pool.shutdown(grace);
        if let Some(c) = self.cluster {
            c.stop();
        }
        n
    }
}

/// Which store a `--database` URL names.
#[derive(Debug, Clone, PartialEq)]
pub enum Database {
    Sqlite(PathBuf),
    Postgres(String),
}

/// A `--database` URL that names no store this ashlar opens.
#[derive(Debug, thiserror::Error)]
pub enum DatabaseError {
    #[error("--database sqlite:PATH: the path is empty")]
    EmptyPath,
    #[error("--database {url:?}: expected sqlite:PATH or postgres://USER@HOST:PORT/DBNAME")]
    Scheme { url: String },
    /// A PostgreSQL URL or its TLS parameters do not parse (`store::postgres::parse_url`;
    /// the cause names the parameter, never the credentials).
    #[error(transparent)]
    Postgres(#[from] store::tls::PgUrlError),
}

/// `--lease` outside 1 s … a day.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("--lease must be a number of seconds between 1 and 86400, got {seconds}")]
pub struct LeaseError {
    pub seconds: f64,
}

/// Parse a `--database` URL.
pub fn parse_database(url: &str) -> Result<Database, DatabaseError> {
    if url.starts_with("postgres://") || url.starts_with("postgresql://") {
        store::postgres::parse_url(url)?;
        return Ok(Database::Postgres(url.to_string()));
    }
    database_path(url).map(Database::Sqlite)
}

fn database_path(url: &str) -> Result<PathBuf, DatabaseError> {
    if let Some(p) = url
        .strip_prefix("sqlite://")
        .or_else(|| url.strip_prefix("sqlite:"))
    {
        if p.is_empty() {
            return Err(DatabaseError::EmptyPath);
        }
        return Ok(PathBuf::from(p));
    }
    Err(DatabaseError::Scheme {
        url: url.to_string(),
    })
}

/// `--lease SECONDS` as lease parameters.
pub fn lease_params(secs: f64) -> Result<store::postgres::LeaseParams, LeaseError> {
    if !(secs.is_finite() && (1.0..=86_400.0).contains(&secs)) {
        return Err(LeaseError { seconds: secs });
    }
    Ok(store::postgres::LeaseParams::with_lease(
        Duration::from_secs_f64(secs),
    ))
}

/// SIGINT and SIGTERM, caught from the moment they are registered. Register them before telling
/// anyone the server is up: a supervisor (or a test) that sends SIGTERM right after the
/// "listening" line would otherwise kill the process with the default action, skipping the
/// graceful shutdown that requeues running jobs.
#[derive(Debug)]
pub struct ShutdownSignals {
    #[cfg(unix)]
    signals: Vec<tokio::signal::unix::Signal>,
}

impl ShutdownSignals {
    /// Installs the handlers now; must run inside a Tokio runtime (e.g. in `block_on`).
    pub fn register() -> Self {
        #[cfg(unix)]
        {
            use tokio::signal::unix::{signal, SignalKind};
            let signals = [SignalKind::interrupt(), SignalKind::terminate()]
                .into_iter()
                .filter_map(|kind| match signal(kind) {
                    Ok(s) => Some(s),
                    Err(e) => {
                        tracing::warn!("cannot catch signal {kind:?}: {e}");
                        None
                    }
                })
                .collect();
            ShutdownSignals { signals }
        }
        #[cfg(not(unix))]
        ShutdownSignals {}
    }

    /// Resolves on the first of the registered signals.
    pub async fn wait(self) {
        #[cfg(unix)]
        {
            let waits = self.signals.into_iter().map(|mut s| {
                Box::pin(async move {
                    s.recv().await;
                })
            });
            let waits: Vec<_> = waits.collect();
            if waits.is_empty() {
                std::future::pending::<()>().await;
            }
            futures_util::future::select_all(waits).await;
        }
        #[cfg(not(unix))]
        {
            if tokio::signal::ctrl_c().await.is_err() {
                std::future::pending::<()>().await;
            }
        }
    }
}
