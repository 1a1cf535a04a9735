//! Paleo-PGA back-analysis: the amplitude at which a damage criterion is first met.
//!
//! Overturning is not monotonic in amplitude (rocking has safe regions above the first
//! overturning amplitude), so the search first scans a coarse grid of amplitudes in parallel,
//! then narrows the lowest safe/failing bracket, evaluating as many interior points per round
//! as there are cores.
use super::run::{run, RunError, RunOptions, Tracker};
use crate::motion::GroundMotion;
use crate::scene::Scene;
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

/// One observation: `toppled:BLOCK`, `displacement:BLOCK:METRES`, `rotation:BLOCK:DEGREES`,
/// each optionally prefixed `not:` (the block was observed *not* to fail, which bounds the PGA
/// from above).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum Criterion {
    Toppled { block: String },
    Displacement { block: String, metres: f64 },
    Rotation { block: String, degrees: f64 },
    Not { inner: Box<Criterion> },
}

/// Rotation (rad) past which a toppling block is counted as fallen before the run ends: at
/// 60° every block with a width-to-height ratio below 1.7 is beyond its tipping angle.
const FALLEN_ROTATION: f64 = std::f64::consts::FRAC_PI_3;

impl Criterion {
    /// Parse the command-line / API form.
    pub fn parse(text: &str) -> Result<Self, String> {
        if let Some(rest) = text.strip_prefix("not:") {
            return Ok(Criterion::Not {
                inner: Box::new(Criterion::parse(rest)?),
            });
        }
        let parts: Vec<&str> = text.split(':').collect();
        let num = |s: &str, what: &str| -> Result<f64, String> {
            s.parse::<f64>()
                .ok()
                .filter(|v| v.is_finite() && *v > 0.0)
                .ok_or_else(|| {
                    format!("criterion {text:?}: {what} must be a positive number, got {s:?}")
                })
        };
        match parts.as_slice() {
            ["toppled", b] if !b.is_empty() => Ok(Criterion::Toppled { block: b.to_string() }),
            ["displacement", b, m] if !b.is_empty() => Ok(Criterion::Displacement { block: b.to_string(), metres: num(m, "METRES")? }),
            ["rotation", b, d] if !b.is_empty() => Ok(Criterion::Rotation { block: b.to_string(), degrees: num(d, "DEGREES")? }),
            _ => Err(format!("criterion {text:?}: expected toppled:BLOCK, displacement:BLOCK:METRES or rotation:BLOCK:DEGREES (optionally prefixed not:)")),
        }
    }

    /// The command-line form.
    pub fn text(&self) -> String {
        match self {
            Criterion::Toppled { block } => format!("toppled:{block}"),
            Criterion::Displacement { block, metres } => format!("displacement:{block}:{metres}"),
            Criterion::Rotation { block, degrees } => format!("rotation:{block}:{degrees}"),
            Criterion::Not { inner } => format!("not:{}", inner.text()),
        }
    }

    /// The block the criterion observes.
    pub fn block(&self) -> &str {
        match self {
            Criterion::Toppled { block }
            | Criterion::Displacement { block, .. }
            | Criterion::Rotation { block, .. } => block,
            Criterion::Not { inner } => inner.block(),
        }
    }

    /// Is the criterion met by the run's final state?
    fn met(&self, tr: &Tracker) -> bool {
        let Some(k) = tr.index_of(self.block()) else {
            return false;
        };
        match self {
            Criterion::Toppled { .. } => tr.final_rotation[k].abs() > 30f64.to_radians(),
            Criterion::Displacement { metres, .. } => {
                let d = tr.final_displacement[k];
                (d[0] * d[0] + d[1] * d[1]).sqrt() >= *metres
            }
            Criterion::Rotation { degrees, .. } => {
                tr.final_rotation[k].abs() >= degrees.to_radians()
            }
            Criterion::Not { inner } => !inner.met(tr),
        }
    }

    /// Decided before the end of the run: `Some(met)` once a block has fallen.
    fn decided(&self, tr: &Tracker) -> Option<bool> {
        let k = tr.index_of(self.block())?;
        match self {
            Criterion::Toppled { .. } if tr.final_rotation[k].abs() > FALLEN_ROTATION => Some(true),
            Criterion::Not { inner } => inner.decided(tr).map(|m| !m),
            _ => None,
        }
    }
}

/// A PGA search request (amplitudes in m/s²). All criteria must hold for "failed".
#[derive(Debug, Clone, PartialEq)]
pub struct PgaRequest {
    pub criteria: Vec<Criterion>,
    pub min: f64,
    pub max: f64,
    pub tolerance: f64,
    /// Coarse scan points before bisection.
    pub scan_points: usize,
}

#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct PgaRun {
    pub pga: f64,
    pub failed: bool,
}

/// `result.json` of FORMAT.md §3.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct PgaResult {
    pub criterion: String,
    /// Largest amplitude found not to meet the criterion (below `failing_pga`).
    pub safe_pga: Option<f64>,
    /// Smallest amplitude found to meet it.
    pub failing_pga: Option<f64>,
    pub units: String,
    pub monotonic: bool,
    pub runs: Vec<PgaRun>,
}

fn all_met(criteria: &[Criterion], tr: &Tracker) -> bool {
    criteria.iter().all(|c| c.met(tr))
}

fn validate(scene: &Scene, motion: &GroundMotion, req: &PgaRequest) -> Result<(), RunError> {
    if req.criteria.is_empty() {
        return Err(RunError::Invalid(
            "criterion: at least one is required".into(),
        ));
    }
    for c in &req.criteria {
        let id = c.block();
        if scene
            .block_index(id)
            .is_none_or(|b| !matches!(scene.blocks[b].kind, crate::scene::BlockKind::Free(_)))
        {
            return Err(RunError::Invalid(format!(
                "criterion {:?}: no free block with id {id:?}",
                c.text()
            )));
        }
    }
    if !(req.min.is_finite() && req.max.is_finite() && req.min >= 0.0 && req.max > req.min) {
        return Err(RunError::Invalid(format!(
            "range: need 0 ≤ min < max, got min {} max {}",
            req.min, req.max
        )));
    }
    if !(req.tolerance.is_finite() && req.tolerance > 0.0) {
        return Err(RunError::Invalid(format!(
            "tolerance: must be > 0, got {}",
            req.tolerance
        )));
    }
    if req.scan_points < 2 || req.scan_points > 1000 {
        return Err(RunError::Invalid(format!(
            "scan_points: must lie in 2..=1000, got {}",
            req.scan_points
        )));
    }
    if motion.horizontal.peak() <= 0.0 {
        return Err(RunError::Invalid(
            "motion: the horizontal record is zero everywhere and cannot be scaled to a PGA".into(),
        ));
    }
    Ok(())
}

/// Evaluate the criteria at one amplitude (m/s²), stopping the run as soon as they are decided.
pub fn evaluate(
    scene: &Scene,
    motion: &GroundMotion,
    criteria: &[Criterion],
    pga: f64,
    cancel: Option<&std::sync::atomic::AtomicBool>,
) -> Result<bool, RunError> {
    let gm = motion.scaled_to_pga(pga);
    let decided = |tr: &Tracker| criteria.iter().all(|c| c.decided(tr).is_some());
    let opts = RunOptions {
        stop_when: Some(&decided),
        cancel,
        no_trajectory: true,
        ..Default::default()
    };
    let s = run(scene, &gm, &opts)?.summary;
    // The verdict from the final state; a run stopped early was stopped because every
    // criterion was decided, and `decided` agrees with `met` by construction.
    let mut tr = Tracker::default();
    for b in &s.blocks {
        tr.ids.push(b.id.clone());
        tr.final_rotation.push(b.final_rotation);
        tr.final_displacement.push(b.final_displacement);
    }
    Ok(all_met(criteria, &tr))
}

/// Search for the threshold amplitude.
pub fn search(
    scene: &Scene,
    motion: &GroundMotion,
    req: &PgaRequest,
    opts: &RunOptions,
) -> Result<PgaResult, RunError> {
    validate(scene, motion, req)?;
    let cancel = opts.cancel;
    let eval_many = |pgas: &[f64]| -> Result<Vec<PgaRun>, RunError> {
        pgas.par_iter()
            .map(|&pga| {
                evaluate(scene, motion, &req.criteria, pga, cancel)
                    .map(|failed| PgaRun { pga, failed })
            })
            .collect()
    };
    let n = req.scan_points;
    let grid: Vec<f64> = (0..n)
        .map(|k| req.min + (req.max - req.min) * k as f64 / (n - 1) as f64)
        .collect();
    let mut runs = eval_many(&grid)?;
    if let Some(p) = opts.progress {
        p(0.5);
    }
    let first_fail = runs.iter().position(|r| r.failed);
    let monotonic_scan = match first_fail {
        Some(k) => runs[k..].iter().all(|r| r.failed),
        None => true,
    };
    let (mut safe, mut fail) = match first_fail {
        None => (Some(req.max), None),
        Some(0) => (None, Some(req.min)),
        Some(k) => (Some(runs[k - 1].pga), Some(runs[k].pga)),
    };
    let workers = rayon::current_num_threads().max(1);
    while let (Some(s), Some(f)) = (safe, fail) {
        if f - s <= req.tolerance {
            break;
        }
        if cancel.is_some_and(|c| c.load(std::sync::atomic::Ordering::Relaxed)) {
            return Err(RunError::Invalid("cancelled".into()));
        }
        // Split the bracket into workers + 1 parts and evaluate the interior points together.
        let pts: Vec<f64> = (1..=workers)
            .map(|k| s + (f - s) * k as f64 / (workers + 1) as f64)
            .collect();
        let round = eval_many(&pts)?;
        match round.iter().position(|r| r.failed) {
            Some(0) => fail = Some(round[0].pga),
            Some(k) => {
                safe = Some(round[k - 1].pga);
                fail = Some(round[k].pga);
            }
            None => safe = Some(round[round.len() - 1].pga),
        }
        runs.extend(round);
    }
    let monotonic = monotonic_scan && {
        let lowest_fail = runs
            .iter()
            .filter(|r| r.failed)
            .map(|r| r.pga)
            .fold(f64::INFINITY, f64::min);
        runs.iter().all(|r| r.failed || r.pga < lowest_fail)
    };
    runs.sort_by(|a, b| a.pga.total_cmp(&b.pga));
    Ok(PgaResult {
        criterion: req
            .criteria
            .iter()
            .map(Criterion::text)
            .collect::<Vec<_>>()
            .join(","),
        safe_pga: safe,
        failing_pga: fail,
        units: "m/s2".into(),
        monotonic,
        runs,
    })
}

/// The verdict of `criteria` (all must hold) on a finished run's summary: the same test
/// [`evaluate`] applies, for callers that ran the scene themselves (batch sweeps).
pub fn met_by_summary(criteria: &[Criterion], summary: &super::run::Summary) -> bool {
    let mut tr = Tracker::default();
    for b in &summary.blocks {
        tr.ids.push(b.id.clone());
        tr.final_rotation.push(b.final_rotation);
        tr.final_displacement.push(b.final_displacement);
    }
    all_met(criteria, &tr)
}
