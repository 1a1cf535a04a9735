//! Command line: a thin layer that parses arguments and calls `analysis` / `service`.
mod criteria;
mod error;
mod load;
pub mod motion;
mod run;
mod scene;
mod site;
mod study;
mod sweep;
mod worker;

pub use error::CliError;

use clap::{Parser, Subcommand};
use std::process::ExitCode;

#[derive(Debug, Parser)]
#[command(
    name = "ashlar",
    version,
    about = "Seismic analysis of historical structures (2D DDA)"
)]
pub struct Cli {
    #[command(subcommand)]
    pub command: Command,
}

#[derive(Debug, Subcommand)]
pub enum Command {
    /// Run a scene under a ground motion; writes summary.json, histories.csv, trajectory.mcap.
    Run(run::RunArgs),
    /// Search the PGA threshold at which a damage criterion is met.
    Pga(run::PgaArgs),
    /// Print a record's intensity measures as JSON.
    Motion(motion::MotionArgs),
    /// Serve the HTTP API.
    Serve(crate::service::ServeArgs),
    /// Measure accuracy against speed over the benchmark scenes (docs/accuracy-vs-speed.md).
    Study(study::StudyArgs),
    /// Run jobs from a PostgreSQL queue shared with `ashlar serve --database postgres://…`.
    Worker(worker::WorkerArgs),
    /// Batch systems: run line N of a manifest (`--index N`), or gather results (`--collect DIR`).
    Sweep(sweep::SweepArgs),
    /// Print a parametric structure's scene JSON (`ashlar scene NAME --set KEY=VALUE`, `--list`).
    Scene(scene::SceneArgs),
    /// The PGA interval consistent with several observations at one site (docs/observations.md).
    Site(site::SiteArgs),
    /// Internal: one job of `ashlar serve` in its own process (job isolation).
    #[command(hide = true, name = "internal-run-job")]
    InternalRunJob,
}

/// Run the CLI; an error goes to stderr once, as one clear line (its text carries the cause
/// chain, see [`CliError`]).
pub fn main() -> ExitCode {
    let cli = Cli::parse();
    let result = match cli.command {
        Command::Run(args) => run::run(&args),
        Command::Pga(args) => run::pga(&args),
        Command::Motion(args) => motion::run(&args).map_err(CliError::from),
        Command::Serve(args) => crate::service::serve_cli(args).map_err(CliError::from),
        Command::Study(args) => study::run(&args),
        Command::Worker(args) => worker::run(&args),
        Command::Sweep(args) => sweep::run(&args),
        Command::Scene(args) => scene::run(&args),
        Command::Site(args) => site::run(&args),
        Command::InternalRunJob => crate::service::runner::child_main()
            .map_err(|e| CliError::from(crate::service::ServeError::from(e))),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("ashlar: {e}");
            ExitCode::FAILURE
        }
    }
}
