//! The CLI's one error type: every subcommand returns a [`CliError`], which `cli::main` prints
//! once, as one line on standard error (`ashlar: …`). Each variant wraps the typed error of the
//! layer that failed (`#[from]`), with the file or option it concerns; its text carries the
//! cause chain (the wrapped errors' own texts already include their causes, so the chain is not
//! walked again: each cause appears once).
use crate::analysis::criteria::CriterionError;
use crate::analysis::pga::CriterionParseError;
use crate::analysis::run::RunError;
use crate::analysis::study::StudyError;
use crate::motion::{AccelerationError, MotionError, RecordOptionError};
use crate::scene::templates::TemplateError;
use crate::scene::SceneError;
use std::path::PathBuf;

#[derive(Debug, thiserror::Error)]
pub enum CliError {
    /// A file or directory that could not be read.
    #[error("{}: {source}", path.display())]
    Read {
        path: PathBuf,
        source: std::io::Error,
    },
    /// A file or directory that could not be written.
    #[error("{}: {source}", path.display())]
    Write {
        path: PathBuf,
        source: std::io::Error,
    },
    /// A scene file that does not parse or validate.
    #[error("{}: {source}", path.display())]
    Scene { path: PathBuf, source: SceneError },
    /// A ground motion (file, JSON member or line of a record).
    #[error(transparent)]
    Motion(#[from] MotionError),
    /// `--units`, `--pga`, `--scale`.
    #[error(transparent)]
    RecordOption(#[from] RecordOptionError),
    /// An acceleration with units given to `option` (`--min 0.05g`).
    #[error("{option} {text:?}: {source}")]
    Acceleration {
        option: String,
        text: String,
        source: AccelerationError,
    },
    /// A criterion given to `option` that does not parse.
    #[error("{option}: {source}")]
    Criterion {
        option: String,
        source: CriterionParseError,
    },
    /// A damage criterion that does not apply to the scene (a block it names).
    #[error(transparent)]
    CriterionScene(#[from] CriterionError),
    /// The run or search itself (the engine's typed diagnostic, an output directory, …).
    #[error(transparent)]
    Run(#[from] RunError),
    /// A template's parameters.
    #[error(transparent)]
    Template(#[from] TemplateError),
    /// A DXF drawing or its import options (`ashlar scene import`); the error names the
    /// entity's handle and layer.
    #[error("{}: {source}", path.display())]
    Import {
        path: PathBuf,
        /// Boxed: the importer's error is large and the CLI's error is returned everywhere.
        source: Box<crate::scene::import::dxf::DxfImportError>,
    },
    /// `ashlar motion`.
    #[error(transparent)]
    MotionCommand(#[from] super::motion::MotionCommandError),
    /// JSON that does not parse (`at`: the file or line) or could not be written.
    #[error("{at}: {source}")]
    Json {
        at: String,
        source: serde_json::Error,
    },
    /// An option's value, or a combination of options, that the command does not accept; the
    /// text names the option and says what is expected.
    #[error("{0}")]
    Usage(String),
    /// Where in a file of several tasks (a sweep manifest's line) the error happened.
    #[error("{at}: {source}")]
    At { at: String, source: Box<CliError> },
    /// `ashlar study --check`: the points that missed their targets, one line each.
    #[error("study check failed ({} failure{}):\n  {}", .0.len(), if .0.len() == 1 { "" } else { "s" }, .0.join("\n  "))]
    StudyCheck(Vec<String>),
    /// `--combine` is neither `all` nor `any`.
    #[error("--{0}")]
    Combine(#[from] crate::analysis::pga::CombineParseError),
    /// `--scan` is neither `full` nor `lowest`.
    #[error("--{0}")]
    Scan(#[from] crate::analysis::pga::ScanParseError),
    /// `--fit` is neither `interval` nor `binary`.
    #[error("--fit: {0}")]
    Fit(#[from] crate::analysis::fragility::MethodParseError),
    /// `ashlar worker --database`: not a PostgreSQL URL this ashlar opens.
    #[error(transparent)]
    Database(#[from] crate::service::DatabaseError),
    /// `ashlar worker --lease`: outside 1 s … a day.
    #[error(transparent)]
    Lease(#[from] crate::service::LeaseError),
    /// `ashlar worker`: the service did not start.
    #[error(transparent)]
    ServiceStart(#[from] crate::service::StartError),
    /// An async runtime the command needs could not start (`what` it was for).
    #[error("starting {what}: {source}")]
    Runtime {
        what: &'static str,
        source: std::io::Error,
    },
    /// `ashlar study` (the sweep, the records study, their outputs).
    #[error(transparent)]
    Study(#[from] StudyError),
    /// `ashlar serve` or `ashlar internal-run-job` did not start (or stopped serving), and
    /// `--isolation process` of `ashlar worker` found no executable.
    #[error(transparent)]
    Serve(#[from] crate::service::ServeError),
}

impl CliError {
    /// `self`, said to have happened at `at`.
    pub fn at(self, at: impl Into<String>) -> Self {
        CliError::At {
            at: at.into(),
            source: Box::new(self),
        }
    }

    /// A write error on `path`.
    pub fn write(path: impl Into<PathBuf>) -> impl FnOnce(std::io::Error) -> Self {
        let path = path.into();
        move |source| CliError::Write { path, source }
    }

    /// A read error on `path`.
    pub fn read(path: impl Into<PathBuf>) -> impl FnOnce(std::io::Error) -> Self {
        let path = path.into();
        move |source| CliError::Read { path, source }
    }

    /// A criterion given to `option` that does not parse.
    pub fn criterion(option: impl Into<String>) -> impl FnOnce(CriterionParseError) -> Self {
        let option = option.into();
        move |source| CliError::Criterion { option, source }
    }

    /// JSON at `at` that does not parse or print.
    pub fn json(at: impl Into<String>) -> impl FnOnce(serde_json::Error) -> Self {
        let at = at.into();
        move |source| CliError::Json { at, source }
    }
}

/// Pretty JSON of a value the CLI prints or writes (its own result types: cannot fail in
/// practice, but a failure is an error, not a panic).
pub fn pretty(value: &impl serde::Serialize) -> Result<String, CliError> {
    serde_json::to_string_pretty(value).map_err(CliError::json("output"))
}
