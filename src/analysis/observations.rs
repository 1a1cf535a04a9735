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
//!
//! Over a set of records (`distribution`): per observed criterion c its fragility F_c(a), the
//! fraction of records whose threshold is ≤ a and the lognormal fit of `fragility`; the site's
//! PGA a then has the likelihood Π_seen F_c(a) · Π_not_seen (1 − F_c(a)), normalised over the
//! searched range under a uniform prior. The product assumes the observations independent given
//! the PGA (not one record shared by every structure); the per-record intervals assume that.
use super::fragility::{fit_interval, probability, Capacity, FitParams, Fragility};
use super::pga::SearchError;
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
        return Err(SearchError::NoObservations.into());
    }
    let (mut lower, mut upper) = (base.min, base.max);
    let mut results = Vec::new();
    let n = observations.len() as f64;
    for (k, o) in observations.iter().enumerate() {
        let req = PgaRequest {
            criteria: vec![o.criterion.clone()],
            combine: Combine::All,
            ..base.clone()
        };
        // Each search reports 0..1 of itself: the k-th of n covers (k..k+1)/n of the whole.
        let progress = |p: f64| {
            if let Some(report) = opts.progress {
                report((k as f64 + p) / n);
            }
        };
        // `search` reads only these two of the options.
        let sub = RunOptions {
            cancel: opts.cancel,
            progress: Some(&progress),
            ..Default::default()
        };
        let r = search(scene, motion, &req, &sub)?;
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

/// One observation's thresholds over a set of records: what each record's search says of the
/// lowest PGA (m/s²) at which the criterion is met, (safe_pga, failing_pga].
#[derive(Debug, Clone, PartialEq)]
pub struct CriterionRecords {
    pub criterion: String,
    pub observed: bool,
    pub capacities: Vec<Capacity>,
}

/// Tuning of the distribution over records. Each default says why.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DistributionParams {
    /// Points of the PGA grid over the searched range, ends included. The quantiles come from
    /// the trapezoid CDF with linear interpolation: on a smooth likelihood their error is
    /// O(spacing²); on the empirical (step) likelihood it is at most one spacing, i.e. 0.25 %
    /// of the range at 401 points, below the usual search tolerance.
    pub grid_points: usize,
}

impl Default for DistributionParams {
    fn default() -> Self {
        Self { grid_points: 401 }
    }
}

/// Per observation: its fragility over the records.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct CriterionFragility {
    pub criterion: String,
    pub observed: bool,
    /// m/s², each record's threshold as the empirical fragility counts it: its `failing_pga`
    /// (the lowest amplitude found to meet the criterion, within the search tolerance of the
    /// true threshold); `null` when the criterion was not met anywhere in the range.
    pub thresholds: Vec<Option<f64>>,
    /// The lognormal fit of `pga --motion DIR` (interval-censored MLE over the records'
    /// brackets; `points` left empty here); `null` when none can be fitted.
    pub fragility: Option<Fragility>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub fragility_error: Option<String>,
}

/// A posterior distribution of the site's PGA (m/s²) on the grid.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Posterior {
    pub median: f64,
    /// [5 %, 95 %] quantiles.
    pub p05_p95: [f64; 2],
    /// [16 %, 84 %] quantiles.
    pub p16_p84: [f64; 2],
    /// The grid (m/s²) and the normalised density on it (per m/s²; it integrates to 1 over the
    /// range by the trapezoid rule).
    pub pga: Vec<f64>,
    pub density: Vec<f64>,
}

/// The distribution of the site's PGA given every observation, over a set of records.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct SiteDistribution {
    pub units: &'static str,
    /// m/s², the searched range (the prior's support).
    pub range: [f64; 2],
    pub prior: &'static str,
    pub likelihood: &'static str,
    pub assumes: &'static str,
    pub criteria: Vec<CriterionFragility>,
    /// With each criterion's lognormal fragility; `null` when some criterion has no fit.
    pub lognormal: Option<Posterior>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub lognormal_error: Option<String>,
    /// With each criterion's empirical fragility (fraction of records); `null` when the
    /// likelihood is zero over the whole range.
    pub empirical: Option<Posterior>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub empirical_error: Option<String>,
}

const PRIOR: &str = "uniform in PGA over the searched range";
const LIKELIHOOD: &str =
    "L(a) = product over damage seen of F_c(a) times product over damage not seen of (1 - F_c(a))";
const ASSUMES: &str = "the observations are independent given the PGA: each F_c(a) is the \
fraction (or lognormal probability) of records under which criterion c is met at PGA a, and the \
product treats every observation as if its structure had met its own record drawn at random from \
the set. It does NOT assume that one record shook every structure of the site; the per-record \
intervals (`records[]`) do assume that, record by record.";

/// Empirical fragility: the fraction of records whose threshold is ≤ `a`.
fn empirical_fraction(thresholds: &[Option<f64>], a: f64) -> f64 {
    if thresholds.is_empty() {
        return 0.0;
    }
    let met = thresholds
        .iter()
        .filter(|t| t.is_some_and(|t| t <= a))
        .count();
    met as f64 / thresholds.len() as f64
}

/// Normalise a likelihood sampled on `grid` and read its quantiles (trapezoid CDF, linear
/// interpolation inside a cell). `None` when it is zero (or not finite) everywhere.
fn posterior(grid: &[f64], likelihood: &[f64]) -> Option<Posterior> {
    let mut cdf = vec![0.0; grid.len()];
    for i in 1..grid.len() {
        cdf[i] = cdf[i - 1] + 0.5 * (likelihood[i] + likelihood[i - 1]) * (grid[i] - grid[i - 1]);
    }
    let total = *cdf.last()?;
    if !(total.is_finite() && total > 0.0) {
        return None;
    }
    let quantile = |q: f64| {
        let target = q * total;
        let i = cdf
            .partition_point(|&c| c < target)
            .clamp(1, grid.len() - 1);
        let (c0, c1) = (cdf[i - 1], cdf[i]);
        let (a0, a1) = (grid[i - 1], grid[i]);
        let (l0, l1) = (likelihood[i - 1], likelihood[i]);
        if c1 <= c0 {
            return a0;
        }
        // Inside the cell the density is linear, so the CDF is quadratic in a: solve it.
        let h = a1 - a0;
        let slope = (l1 - l0) / h;
        let need = target - c0;
        let t = if slope.abs() * h < 1e-12 * (l0 + l1).max(f64::MIN_POSITIVE) {
            need / l0.max(f64::MIN_POSITIVE)
        } else {
            // l0·t + slope·t²/2 = need, the root in [0, h].
            let disc = (l0 * l0 + 2.0 * slope * need).max(0.0);
            2.0 * need / (l0 + disc.sqrt())
        };
        a0 + t.clamp(0.0, h)
    };
    Some(Posterior {
        median: quantile(0.5),
        p05_p95: [quantile(0.05), quantile(0.95)],
        p16_p84: [quantile(0.16), quantile(0.84)],
        pga: grid.to_vec(),
        density: likelihood.iter().map(|l| l / total).collect(),
    })
}

/// The distribution of the site's PGA over `[min, max]` (m/s²) from each observation's
/// thresholds over the records: per criterion the empirical and the lognormal fragility
/// (`fragility::fit_interval`, as `pga --motion DIR` fits it), then the likelihood
/// Π_seen F_c · Π_not_seen (1 − F_c) under a uniform prior, normalised over the range.
pub fn distribution(
    observations: &[CriterionRecords],
    min: f64,
    max: f64,
    params: &DistributionParams,
) -> SiteDistribution {
    let n = params.grid_points.max(2);
    let grid: Vec<f64> = (0..n)
        .map(|i| min + (max - min) * i as f64 / (n - 1) as f64)
        .collect();
    let mut criteria = Vec::new();
    for o in observations {
        let thresholds: Vec<Option<f64>> = o.capacities.iter().map(|c| c.at_most).collect();
        let (fragility, fragility_error) =
            match fit_interval(&o.capacities, Vec::new(), &FitParams::default()) {
                Ok(f) => (Some(f), None),
                Err(e) => (None, Some(e.to_string())),
            };
        criteria.push(CriterionFragility {
            criterion: o.criterion.clone(),
            observed: o.observed,
            thresholds,
            fragility,
            fragility_error,
        });
    }
    let factor = |observed: bool, f: f64| if observed { f } else { 1.0 - f };
    let empirical_l: Vec<f64> = grid
        .iter()
        .map(|&a| {
            criteria
                .iter()
                .map(|c| factor(c.observed, empirical_fraction(&c.thresholds, a)))
                .product()
        })
        .collect();
    let empirical = posterior(&grid, &empirical_l);
    let empirical_error = empirical.is_none().then(|| {
        "the empirical likelihood is zero over the whole range: no record reproduces the \
         observations at any PGA in it (widen the range, or see records[])"
            .to_string()
    });
    let (lognormal, lognormal_error) = match criteria
        .iter()
        .map(|c| c.fragility.as_ref().ok_or(c))
        .collect::<Result<Vec<_>, _>>()
    {
        Err(c) => (
            None,
            Some(format!(
                "criterion {}: {}",
                c.criterion,
                c.fragility_error.as_deref().unwrap_or("no fragility fit")
            )),
        ),
        Ok(fits) => {
            let l: Vec<f64> = grid
                .iter()
                .map(|&a| {
                    fits.iter()
                        .zip(&criteria)
                        .map(|(f, c)| factor(c.observed, probability(f, a)))
                        .product()
                })
                .collect();
            match posterior(&grid, &l) {
                Some(p) => (Some(p), None),
                None => (
                    None,
                    Some("the lognormal likelihood underflows to zero over the whole range".into()),
                ),
            }
        }
    };
    SiteDistribution {
        units: "m/s2",
        range: [min, max],
        prior: PRIOR,
        likelihood: LIKELIHOOD,
        assumes: ASSUMES,
        criteria,
        lognormal,
        lognormal_error,
        empirical,
        empirical_error,
    }
}

/// The thresholds of every observation over the records, from each record's site interval
/// (its searches): the brackets as `pga::capacity` reads them.
pub fn criterion_records(
    observations: &[Observation],
    intervals: &[SiteInterval],
) -> Vec<CriterionRecords> {
    observations
        .iter()
        .enumerate()
        .map(|(k, o)| CriterionRecords {
            criterion: o.criterion.text(),
            observed: o.observed,
            capacities: intervals
                .iter()
                .filter_map(|s| s.observations.get(k))
                .map(|r| Capacity {
                    above: r.safe_pga.filter(|s| *s > 0.0),
                    at_most: r.failing_pga,
                })
                .collect(),
        })
        .collect()
}

/// One record's interval, named.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct RecordInterval {
    pub record: String,
    #[serde(flatten)]
    pub interval: SiteInterval,
}

/// The whole site analysis over a set of records (`ashlar site`, `POST /v1/site-analyses`):
/// each record's interval and the distribution over the records.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct SiteAnalysis {
    pub units: &'static str,
    pub records: Vec<RecordInterval>,
    pub distribution: SiteDistribution,
}

/// Every record's [`site_interval`] (records in parallel, as `pga::search_records` runs them),
/// then the [`distribution`] over them. Progress is the mean of the records' progress; a
/// record's error names the record.
pub fn site_analysis(
    scene: &Scene,
    records: &[(String, GroundMotion)],
    observations: &[Observation],
    base: &PgaRequest,
    opts: &RunOptions,
) -> Result<SiteAnalysis, RunError> {
    if records.is_empty() {
        return Err(SearchError::NoSiteRecords.into());
    }
    let intervals = super::pga::for_each_record(records, opts, |name, gm, sub| {
        site_interval(scene, gm, observations, base, sub).map(|interval| RecordInterval {
            record: name.to_string(),
            interval,
        })
    })?;
    let plain: Vec<SiteInterval> = intervals.iter().map(|r| r.interval.clone()).collect();
    let distribution = distribution(
        &criterion_records(observations, &plain),
        base.min,
        base.max,
        &DistributionParams::default(),
    );
    Ok(SiteAnalysis {
        units: "m/s2",
        records: intervals,
        distribution,
    })
}
