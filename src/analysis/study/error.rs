//! Analysis › study › errors: why a study (`run_study`, `write_outputs`) or the records study
//! (`study_records`) stopped, typed by cause; the CLI wraps it as `CliError::Study`.
use crate::analysis::run::RunError;
use crate::motion::MotionError;
use crate::scene::SceneError;
use std::path::PathBuf;

#[derive(Debug, thiserror::Error)]
pub enum StudyError {
    /// A benchmark scene the study builds did not parse (a defect of the study itself).
    #[error("study scene: {0}")]
    Scene(#[from] SceneError),
    /// A run of the sweep failed outside the points it measures (the restitution fit, the
    /// records study).
    #[error(transparent)]
    Run(#[from] RunError),
    /// A record the study reads (from `--ground-motions`).
    #[error("{path}: {source}{hint}")]
    Motion {
        path: PathBuf,
        source: MotionError,
        /// Where the record is, when it is one the repository bundles.
        hint: String,
    },
    /// An output file or folder.
    #[error("{path}: {source}")]
    Io {
        path: PathBuf,
        source: std::io::Error,
    },
    /// The results as JSON (a defect: every field serializes).
    #[error("study results as JSON: {0}")]
    Json(#[from] serde_json::Error),
    /// A search of the sweep ran no point it could use (over its time budget, or every run
    /// failed: the first failure).
    #[error("{0}")]
    NoRun(String),
}

impl StudyError {
    pub(crate) fn io(path: &std::path::Path, source: std::io::Error) -> Self {
        StudyError::Io {
            path: path.to_path_buf(),
            source,
        }
    }
}
