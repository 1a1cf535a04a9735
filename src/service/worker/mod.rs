//! Service workers: run the queued jobs that `http` accepted and `store` keeps, driving
//! `analysis`. `pool` holds the shared state (`Core`), the threads and their claims; `run` is
//! the `JobRunner` over `analysis`; `fanout` splits PGA searches, fragility and site analyses
//! into child runs; `runner` runs a job in a child process; `artifacts` publishes and fetches
//! job files on shared storage; `error` is how a job's computation fails (`JobError`).
pub mod artifacts;
pub mod cluster;
pub mod error;
pub mod fanout;
pub mod pool;
pub mod run;
pub mod runner;

pub use error::{Inconsistent, JobError, ProcessEnd, ProcessError, ThreadStartError};
pub use fanout::{ChildRequest, ChildResult};
pub use pool::*;
pub use run::{analysis_runner, JobRunner, RunHooks, RunnerOutcome};
