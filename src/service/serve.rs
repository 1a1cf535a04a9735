//! Service start-up errors: why `ashlar serve` (its options, its socket, its runtime, the
//! service's start) or `ashlar internal-run-job` (a job's child process) did not run. The
//! CLI prints one as `ashlar: …`, one line; each cause is a variant, so a caller can match on it.
use super::worker::runner::ChildError;
use super::StartError;
use std::net::SocketAddr;

/// Why `ashlar serve` or `ashlar internal-run-job` stopped before serving (or while serving).
#[derive(Debug, thiserror::Error)]
pub enum ServeError {
    /// `--database`: not a `sqlite:PATH` or PostgreSQL URL (the text names the option).
    #[error("{0}")]
    Database(String),
    /// `--lease`: out of range (the text names the option and the value).
    #[error("{0}")]
    Lease(String),
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
    /// `--tokens FILE`: unreadable or malformed (the text names the file and the line).
    #[error("{0}")]
    Tokens(String),
    /// `--signed-url-seconds` outside 1 s … a week.
    #[error("--signed-url-seconds must be between 1 and 604800 (a week), got {0}")]
    SignedUrlSeconds(u64),
    /// `--signing-key-file`: unreadable or too short (the text names the file).
    #[error("{0}")]
    SigningKey(String),
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
