//! Several observations at one site (docs/observations.md): column A fell, column B stands, a drum
//! slid by 3 cm. Each observation is a damage criterion and whether it was seen; under one
//! record, an observed failure bounds the site's PGA from below (the shaking reached at least
//! that criterion's threshold), an observed survival from above (it stayed below that one's).
//! The interval consistent with all of them is the intersection. Sits above `pga` in
//! `analysis`: one threshold search a criterion (docs/observations.md).
//!
//! Conservative ends: a threshold is known only within its search bracket (safe, failing], so
//! the lower bound is the largest `safe_pga` of the observed failures and the upper bound the
//! smallest `failing_pga` of the observed survivals: the interval certainly contains every
//! consistent PGA within the searched range. It assumes each criterion's outcome is monotonic
//! in amplitude over the range (the search says when it found otherwise: `monotonic`).
use super::pga::{search, Combine, Criterion, PgaRequest};
use super::run::{RunError, RunOptions};
use crate::motion::GroundMotion;
use crate::scene::Scene;
use serde::Serialize;

/// One field observation: the criterion and whether the damage it describes was seen.
#[derive(Debug, Clone, PartialEq)]
pub struct Observation {
    pub criterion: Criterion,
    /// `true`: the damage is there (a lower bound); `false`: it is not (an upper bound).
    pub observed: bool,
}

/// One observation's threshold search, m/s².
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ObservationResult {
    pub criterion: String,
    pub observed: bool,
    pub safe_pga: Option<f64>,
    pub failing_pga: Option<f64>,
    pub monotonic: bool,
}

/// The PGA interval (m/s²) consistent with every observation under one record.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct SiteInterval {
    /// Largest `safe_pga` over the observed failures; the range's `min` when there are none.
    pub lower: f64,
    /// Smallest `failing_pga` over the observed survivals; the range's `max` when none failed
    /// within the range (the survival bounds nothing inside it).
    pub upper: f64,
    /// `lower < upper`: some PGA in the range reproduces every observation at once.
    pub consistent: bool,
    pub units: &'static str,
    pub observations: Vec<ObservationResult>,
}

/// Search each observation's threshold over `base`'s range and intersect the bounds. An
/// observed failure that does not occur anywhere in the range makes the interval empty at
/// `lower = max` (the shaking must have exceeded the range).
pub fn site_interval(
    scene: &Scene,
    motion: &GroundMotion,
    observations: &[Observation],
    base: &PgaRequest,
    opts: &RunOptions,
) -> Result<SiteInterval, RunError> {
    if observations.is_empty() {
        return Err(RunError::Invalid(
            "observations: at least one is required".into(),
        ));
    }
    let (mut lower, mut upper) = (base.min, base.max);
    let mut results = Vec::new();
    for o in observations {
        let req = PgaRequest {
            criteria: vec![o.criterion.clone()],
            combine: Combine::All,
            ..base.clone()
        };
        let r = search(scene, motion, &req, opts)?;
        if o.observed {
            // Failed at the site: the PGA reached this threshold, above safe_pga (or the whole
            // range, when even max is safe).
            let bound = match (r.safe_pga, r.failing_pga) {
                (_, None) => base.max,
                (Some(s), Some(_)) => s,
                (None, Some(_)) => base.min,
            };
            lower = lower.max(bound);
        } else if let Some(f) = r.failing_pga {
            upper = upper.min(f);
        }
        results.push(ObservationResult {
            criterion: r.criterion.clone(),
            observed: o.observed,
            safe_pga: r.safe_pga,
            failing_pga: r.failing_pga,
            monotonic: r.monotonic,
        });
    }
    Ok(SiteInterval {
        lower,
        upper,
        consistent: lower < upper,
        units: "m/s2",
        observations: results,
    })
}
