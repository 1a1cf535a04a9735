//! Workers: the fan-out of a PGA search (and of a fragility or site analysis's searches) into
//! child `pga_run` jobs that any worker claims, the replay that plans the next batch from the
//! children's verdicts, and one child run's verdict (on the worker thread or in a child
//! process through `runner`).
use super::error::{write_artifact, Inconsistent, JobError};
use super::pool::Core;
use super::run::{RunHooks, RunnerOutcome};
use crate::service::request::{parse_pga, JobInput};
use crate::service::store::{JobKind, JobRecord, JobStatus, NewJob};
use std::sync::atomic::{AtomicBool, Ordering};
use uuid::Uuid;

/// What a child run (`pga_run`) is asked: one amplitude of one record of its search. The
/// amplitude travels as its bits so that the replaying search finds exactly the value it
/// planned (a decimal round trip through JSON could move it by one ULP).
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct ChildRequest {
    pub parent: Uuid,
    /// Index of the record in the search's `motions` (0 for a single-record search).
    pub record: usize,
    /// m/s², for people reading the store; `pga_bits` is what counts.
    pub pga: f64,
    pub pga_bits: u64,
    /// Interior points per k-section round, fixed by the search's first fan-out so that every
    /// replay plans the same batches.
    pub width: usize,
    /// This run's share of the search's progress (1 / expected runs).
    pub progress_step: f64,
}

/// A child's `result`.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct ChildResult {
    pub pga: f64,
    pub failed: bool,
}

/// Does this search fan out: configured to, or fanned out already (then it must replay).
pub(super) fn fans_out(core: &Core, job: &JobRecord) -> bool {
    core.params.fanout_width.is_some_and(|w| w > 0)
        || core
            .store
            .children(job.id)
            .map(|c| !c.is_empty())
            .unwrap_or(false)
}

/// One step of a fanned-out search: replay its planner from its children's outcomes; finish
/// (`Some`) or enqueue the next batch as child jobs and park the search (`None`).
pub(super) fn fan_out_search(
    core: &Core,
    job: &JobRecord,
    input: &JobInput,
    hooks: &RunHooks<'_>,
) -> Result<Option<RunnerOutcome>, JobError> {
    use crate::analysis::pga;
    use std::collections::{HashMap, HashSet};
    let JobInput::PgaSearch {
        scene,
        motion,
        request,
        records,
        fit,
        ..
    } = input
    else {
        return Err(Inconsistent::NotASearch.into());
    };
    if records.is_empty() {
        pga::validate_search(scene, motion, request)
    } else {
        pga::validate_records(scene, records, request)
    }?;
    let mut width = None;
    let mut known: HashMap<(usize, u64), bool> = HashMap::new();
    let mut unfinished: HashSet<(usize, u64)> = HashSet::new();
    for ch in core.store.children(job.id).map_err(JobError::store)? {
        let spec: ChildRequest =
            serde_json::from_value(ch.request.clone()).map_err(|source| JobError::Corrupt {
                what: "a child run of this search is corrupt in the store",
                source,
            })?;
        width.get_or_insert(spec.width);
        let key = (spec.record, spec.pga_bits);
        match ch.status {
            JobStatus::Succeeded => {
                let r: ChildResult = serde_json::from_str(ch.result.as_deref().unwrap_or(""))
                    .map_err(|source| JobError::Corrupt {
                        what: "a child run's result is corrupt in the store",
                        source,
                    })?;
                known.insert(key, r.failed);
            }
            JobStatus::Failed | JobStatus::Cancelled => {
                return Err(JobError::ChildEnded {
                    status: ch.status.as_str(),
                    error: ch.error,
                })
            }
            _ => {
                unfinished.insert(key);
            }
        }
    }
    if hooks.cancel.load(Ordering::SeqCst) {
        return Ok(Some(RunnerOutcome::Cancelled(None)));
    }
    let width = width
        .or(core.params.fanout_width)
        .filter(|w| *w > 0)
        .unwrap_or_else(|| rayon::current_num_threads().max(1));
    let look = |i: usize, p: f64| known.get(&(i, p.to_bits())).copied();
    let step = if records.is_empty() {
        match pga::plan(request, width, &|p| look(0, p)) {
            pga::Step::Done(r) => pga::Step::Done(vec![r]),
            pga::Step::Pending { batch, done } => pga::Step::Pending { batch, done },
        }
    } else {
        pga::plan_records(records.len(), request, width, &look)
    };
    match step {
        pga::Step::Done(results) => finish_search(results, records, request, *fit, hooks).map(Some),
        pga::Step::Pending { batch, done } => {
            let expected = pga::expected_runs(request, width) * records.len().max(1) as f64;
            let children: Vec<NewJob> = batch
                .iter()
                .filter(|(i, p)| !unfinished.contains(&(*i, p.to_bits())))
                .map(|&(record, pga)| NewJob {
                    id: Uuid::new_v4(),
                    kind: JobKind::PgaRun,
                    request: serde_json::json!(ChildRequest {
                        parent: job.id,
                        record,
                        pga,
                        pga_bits: pga.to_bits(),
                        width,
                        progress_step: 1.0 / expected,
                    }),
                    motion: serde_json::json!({ "pga": pga }),
                    owner: None,
                })
                .collect();
            let progress = (done as f64 / expected).min(0.99);
            if !core
                .store
                .fan_out(job.id, &children, progress)
                .map_err(JobError::store)?
            {
                tracing::warn!(id = %job.id, "the search was no longer ours to fan out (lease lost)");
            }
            for _ in 0..children.len().min(core.params.workers) {
                core.notify_work();
            }
            Ok(None)
        }
    }
}

/// The finished search's result (and its files), as the in-process runner writes them.
fn finish_search(
    mut results: Vec<crate::analysis::pga::PgaResult>,
    records: &[(String, crate::motion::GroundMotion)],
    request: &crate::analysis::pga::PgaRequest,
    fit: crate::analysis::fragility::Method,
    hooks: &RunHooks<'_>,
) -> Result<RunnerOutcome, JobError> {
    use crate::analysis::pga;
    let value = if records.is_empty() {
        let r = results.pop().ok_or(Inconsistent::NoResult)?;
        serde_json::to_value(&r)?
    } else {
        let recs = records
            .iter()
            .zip(results)
            .map(|((name, _), result)| pga::RecordResult {
                motion: name.clone(),
                result,
            })
            .collect();
        let res = pga::multi_result(recs, request, fit);
        if let Some(svg) = pga::fragility_svg(&res) {
            write_artifact(hooks.out_dir, "fragility.svg", svg)?;
        }
        serde_json::to_value(&res)?
    };
    let text = serde_json::to_string_pretty(&value)?;
    write_artifact(hooks.out_dir, "result.json", text)?;
    Ok(RunnerOutcome::Completed(value))
}

/// A child run: one amplitude of one record of its search, whose request (scene, records,
/// criteria) is read from the search's row. With process isolation it runs in a child process
/// like any job ([`super::runner::run_pga_run_in_child`]), so that a run that crashes or
/// exhausts memory fails this child (and through it its search, with the amplitude named), never
/// the worker.
pub(super) fn run_child(
    core: &Core,
    job: &JobRecord,
    hooks: &RunHooks<'_>,
) -> Result<RunnerOutcome, JobError> {
    let spec: ChildRequest =
        serde_json::from_value(job.request.clone()).map_err(|source| JobError::Corrupt {
            what: "the stored child run is corrupt",
            source,
        })?;
    let parent = core
        .store
        .get(spec.parent)
        .map_err(JobError::store)?
        .ok_or(Inconsistent::ParentGone)?;
    match &core.params.isolation {
        super::runner::Isolation::Process(p) => {
            super::runner::run_pga_run_in_child(p, &parent.request, &spec, &core.limits, hooks)
                .map_err(|e| JobError::ChildRun {
                    pga: f64::from_bits(spec.pga_bits),
                    record: spec.record,
                    source: Box::new(e),
                })
        }
        super::runner::Isolation::Thread => {
            let input = parse_pga(&parent.request, &core.limits)
                .map_err(JobError::rejected)?
                .input;
            evaluate_child(&input, &spec, hooks.cancel)
        }
    }
}

/// The verdict of one child run (`pga_run`) of the search `input`: on the worker thread, or in
/// the child process of [`super::runner`].
pub(crate) fn evaluate_child(
    input: &JobInput,
    spec: &ChildRequest,
    cancel: &AtomicBool,
) -> Result<RunnerOutcome, JobError> {
    use crate::analysis::pga;
    let JobInput::PgaSearch {
        scene,
        motion,
        request,
        records,
        ..
    } = input
    else {
        return Err(Inconsistent::ParentNotASearch.into());
    };
    let pga = f64::from_bits(spec.pga_bits);
    let (name, gm) = if records.is_empty() {
        (None, motion)
    } else {
        let (n, g) = records
            .get(spec.record)
            .ok_or(Inconsistent::NoRecord(spec.record))?;
        (Some(n), g)
    };
    let failed = pga::evaluate_combined(
        scene,
        gm,
        &request.criteria,
        request.combine,
        pga,
        Some(cancel),
    )
    .map_err(|e| match name {
        Some(n) => pga::record_error(n, e),
        None => e,
    })?;
    let value = serde_json::to_value(ChildResult { pga, failed })?;
    Ok(RunnerOutcome::Completed(value))
}
