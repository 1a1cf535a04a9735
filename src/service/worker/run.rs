//! Workers: the computation behind a job, a [`JobRunner`] over `analysis` (`analysis::run::run`,
//! `pga::search*`, `site::analyse`), with the hooks a worker hands it (output directory, stop
//! switch, progress).
use super::error::{write_artifact, JobError};
use crate::service::request::JobInput;
use serde_json::Value;
use std::path::Path;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;

/// What a runner is handed besides the input.
pub struct RunHooks<'a> {
    /// The job's artifact directory, `<data>/jobs/<uuid>/` (exists, empty on a fresh start).
    pub out_dir: &'a Path,
    /// Becomes true when the run must stop (user cancel or server shutdown); checked every step.
    pub cancel: &'a AtomicBool,
    /// Simulated time / duration, 0..1.
    pub progress: &'a (dyn Fn(f64) + Sync),
}

/// How a runner finished (a failure is a [`JobError`], whose text the job shows).
#[derive(Debug, Clone, PartialEq)]
pub enum RunnerOutcome {
    /// `summary.json` of a run or `result.json` of a PGA search.
    Completed(Value),
    /// Stopped through `cancel`; the partial summary where there is one.
    Cancelled(Option<Value>),
}

/// The computation behind a job. The default is [`analysis_runner`]; tests use
/// [`crate::service::fake::fake_runner`].
pub type JobRunner =
    Arc<dyn Fn(&JobInput, &RunHooks<'_>) -> Result<RunnerOutcome, JobError> + Send + Sync>;

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
            JobInput::Run {
                scene,
                motion,
                criteria,
            } => {
                let out = crate::analysis::run::run(scene, motion, &opts)?;
                let mut summary = serde_json::to_value(&out.summary)?;
                // The request's damage criteria, judged on the finished run (`run --criterion`).
                if !criteria.is_empty() && !out.cancelled {
                    let v = crate::analysis::pga::verdicts(criteria, &out.summary);
                    summary["criteria"] = serde_json::to_value(v)?;
                }
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
                let res = res?;
                let value = serde_json::to_value(&res)?;
                if let Some(svg) = crate::analysis::pga::fragility_svg(&res) {
                    write_artifact(hooks.out_dir, "fragility.svg", svg)?;
                }
                let text = serde_json::to_string_pretty(&value)?;
                write_artifact(hooks.out_dir, "result.json", text)?;
                Ok(RunnerOutcome::Completed(value))
            }
            JobInput::SiteAnalysis {
                scene,
                records,
                observations,
                request,
                ..
            } => {
                // Per record the interval, over them the distribution (docs/observations.md).
                let res = crate::analysis::observations::site_analysis(
                    scene,
                    records,
                    observations,
                    request,
                    &opts,
                );
                if hooks.cancel.load(Ordering::Relaxed) {
                    return Ok(RunnerOutcome::Cancelled(None));
                }
                let res = res?;
                let value = serde_json::to_value(&res)?;
                let text = serde_json::to_string_pretty(&value)?;
                write_artifact(hooks.out_dir, "result.json", text)?;
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
                let res = res?;
                let value = serde_json::to_value(&res)?;
                if !hooks.out_dir.join("result.json").exists() {
                    let text = serde_json::to_string_pretty(&value)?;
                    write_artifact(hooks.out_dir, "result.json", text)?;
                }
                Ok(RunnerOutcome::Completed(value))
            }
        }
    })
}
