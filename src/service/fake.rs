//! A deterministic stand-in for the engine, for testing the service's machinery (queue, store,
//! cancellation, progress, restart) independently of the physics. Not a model of anything: every
//! free block simply follows the ground displacement. Selected in tests, or with the hidden
//! `ashlar serve --fake-runner` flag for contract tests.
//!
//! Behaviour: it steps through the run one output frame at a time, sleeping
//! `wall_per_simulated_second × output_interval` per frame, reports progress each frame, and
//! stops at the next frame when cancelled (writing the frames done so far). A scene named
//! `fake:fail` fails with a message; `fake:panic` panics (to test the worker's guard).
use super::request::JobInput;
use super::worker::{JobError, JobRunner, RunHooks, RunnerOutcome};
use crate::analysis::pga::{PgaResult, PgaRun};
use crate::analysis::run::{summary_units, BlockSummary, Diagnostics, Summary, RUN_OUTPUTS_FORMAT};
use std::sync::atomic::Ordering;
use std::sync::Arc;
use std::time::Duration;

/// Bytes of the fake `trajectory.mcap`: `k % 251` for k = 0..N (a prime period, so any slice
/// identifies its offset; range requests are checked against it).
pub const FAKE_TRAJECTORY_LEN: usize = 10_000;

/// The fake runner; `wall_per_simulated_second` sets how slowly it runs.
pub fn fake_runner(wall_per_simulated_second: Duration) -> JobRunner {
    Arc::new(move |input: &JobInput, hooks: &RunHooks<'_>| match input {
        JobInput::Run { .. } => fake_run(input, hooks, wall_per_simulated_second),
        JobInput::SiteAnalysis {
            records,
            observations,
            request,
            ..
        } => fake_site(
            records,
            observations,
            request,
            hooks,
            wall_per_simulated_second,
        ),
        JobInput::PgaSearch {
            request, criterion, ..
        } => {
            // Pretend the criterion is met above the middle of the range; bisect to the tolerance.
            let threshold = 0.5 * (request.min + request.max);
            let (mut lo, mut hi) = (request.min, request.max);
            let mut runs = vec![
                PgaRun {
                    pga: lo,
                    failed: false,
                },
                PgaRun {
                    pga: hi,
                    failed: true,
                },
            ];
            while hi - lo > request.tolerance {
                if hooks.cancel.load(Ordering::SeqCst) {
                    return Ok(RunnerOutcome::Cancelled(None));
                }
                std::thread::sleep(wall_per_simulated_second / 10);
                let mid = 0.5 * (lo + hi);
                let failed = mid >= threshold;
                runs.push(PgaRun { pga: mid, failed });
                if failed {
                    hi = mid;
                } else {
                    lo = mid;
                }
                (hooks.progress)(
                    (request.max - request.min - (hi - lo)) / (request.max - request.min),
                );
            }
            let result = PgaResult {
                criterion: criterion.clone(),
                safe_pga: Some(lo),
                failing_pga: Some(hi),
                units: "m/s2".into(),
                monotonic: true,
                resolution: request.max - request.min,
                failing_intervals: vec![[hi, request.max]],
                scan: crate::analysis::pga::ScanOrder::Full,
                scanned_to: Some(request.max),
                runs,
            };
            let value = serde_json::to_value(&result)?;
            std::fs::write(hooks.out_dir.join("result.json"), value.to_string()).map_err(
                |source| JobError::Write {
                    file: "result.json",
                    source,
                },
            )?;
            Ok(RunnerOutcome::Completed(value))
        }
    })
}

fn fake_run(
    input: &JobInput,
    hooks: &RunHooks<'_>,
    slowness: Duration,
) -> Result<RunnerOutcome, JobError> {
    let scene = input.scene();
    let motion = input.motion();
    match scene.name.as_str() {
        "fake:fail" => return Err(JobError::Fake),
        "fake:panic" => panic!("fake panic requested by the scene name"),
        _ => {}
    }
    let duration = crate::analysis::run::duration(scene, motion).unwrap_or(1.0);
    let dt = scene.control.output_interval;
    let frames = (duration / dt).round().max(1.0) as usize;
    let free: Vec<&str> = scene
        .free_blocks()
        .map(|i| scene.blocks[i].id.as_str())
        .collect();
    let mut csv = crate::record::histories::header_line(free.iter().copied());
    csv.push('\n');
    let mut max_d: f64 = 0.0;
    let mut last = 0.0;
    let mut cancelled = false;
    let mut done = 0;
    for k in 0..=frames {
        if hooks.cancel.load(Ordering::SeqCst) {
            cancelled = true;
            break;
        }
        let t = k as f64 * dt;
        let d = motion.state(t)[2][0];
        csv.push_str(&t.to_string());
        for _ in &free {
            csv.push_str(&format!(",{d},0,0"));
        }
        csv.push('\n');
        max_d = max_d.max(d.abs());
        last = d;
        done = k;
        (hooks.progress)(t / duration);
        if k < frames {
            std::thread::sleep(slowness.mul_f64(dt));
        }
    }
    std::fs::write(hooks.out_dir.join("histories.csv"), csv).map_err(|source| JobError::Write {
        file: "histories.csv",
        source,
    })?;
    let traj: Vec<u8> = (0..FAKE_TRAJECTORY_LEN).map(|k| (k % 251) as u8).collect();
    std::fs::write(hooks.out_dir.join("trajectory.mcap"), traj).map_err(|source| {
        JobError::Write {
            file: "trajectory.mcap",
            source,
        }
    })?;
    let summary = Summary {
        format: RUN_OUTPUTS_FORMAT.into(),
        completed: !cancelled,
        simulated_time: done as f64 * dt,
        steps: done as u64,
        wall_time_s: 0.0,
        pga: motion.pga(),
        failure_mode: "stable".into(),
        blocks: free
            .iter()
            .map(|id| BlockSummary {
                id: id.to_string(),
                max_displacement: max_d,
                final_displacement: [last, 0.0],
                max_rotation: 0.0,
                final_rotation: 0.0,
                toppled: false,
                sliding_distance: 0.0,
                block_model: None,
                block_model_reason: None,
            })
            .collect(),
        diagnostics: Diagnostics::default(),
        model: "fake".into(),
        model_reason: "service test double".into(),
        block_model_reason: String::new(),
        stopped_reason: cancelled.then(|| "cancelled".to_string()),
        control: serde_json::Value::Null,
        units: summary_units(),
        settled: !cancelled,
        events: Vec::new(),
    };
    let value = serde_json::to_value(&summary)?;
    std::fs::write(hooks.out_dir.join("summary.json"), value.to_string()).map_err(|source| {
        JobError::Write {
            file: "summary.json",
            source,
        }
    })?;
    Ok(if cancelled {
        RunnerOutcome::Cancelled(Some(value))
    } else {
        RunnerOutcome::Completed(value)
    })
}

/// A fake site analysis: every observation's threshold is pretended to lie at the middle of the
/// range under every record (bracketed to the tolerance), one sleep per record; the distribution
/// over the records is the real [`distribution`] of those thresholds.
fn fake_site(
    records: &[(String, crate::motion::GroundMotion)],
    observations: &[crate::analysis::observations::Observation],
    request: &crate::analysis::pga::PgaRequest,
    hooks: &RunHooks<'_>,
    slowness: Duration,
) -> Result<RunnerOutcome, JobError> {
    use crate::analysis::observations::{
        criterion_records, distribution, DistributionParams, ObservationResult, RecordInterval,
        SiteAnalysis, SiteInterval,
    };
    let mid = 0.5 * (request.min + request.max);
    let (safe, failing) = (mid - 0.5 * request.tolerance, mid + 0.5 * request.tolerance);
    let mut out = Vec::new();
    for (i, (name, _)) in records.iter().enumerate() {
        if hooks.cancel.load(Ordering::SeqCst) {
            return Ok(RunnerOutcome::Cancelled(None));
        }
        std::thread::sleep(slowness / 10);
        let seen = observations.iter().any(|o| o.observed);
        let unseen = observations.iter().any(|o| !o.observed);
        let (lower, upper) = (
            if seen { safe } else { request.min },
            if unseen { failing } else { request.max },
        );
        out.push(RecordInterval {
            record: name.clone(),
            interval: SiteInterval {
                lower,
                upper,
                consistent: lower < upper,
                units: "m/s2",
                observations: observations
                    .iter()
                    .map(|o| ObservationResult {
                        criterion: o.criterion.text(),
                        observed: o.observed,
                        safe_pga: Some(safe),
                        failing_pga: Some(failing),
                        monotonic: true,
                    })
                    .collect(),
            },
        });
        (hooks.progress)((i + 1) as f64 / records.len() as f64);
    }
    let plain: Vec<SiteInterval> = out.iter().map(|r| r.interval.clone()).collect();
    let result = SiteAnalysis {
        units: "m/s2",
        distribution: distribution(
            &criterion_records(observations, &plain),
            request.min,
            request.max,
            &DistributionParams::default(),
        ),
        records: out,
    };
    let value = serde_json::to_value(&result)?;
    std::fs::write(hooks.out_dir.join("result.json"), value.to_string()).map_err(|source| {
        JobError::Write {
            file: "result.json",
            source,
        }
    })?;
    Ok(RunnerOutcome::Completed(value))
}
