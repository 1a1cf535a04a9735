//! Paleo-PGA back-analysis: the amplitude at which a damage criterion is first met.
//!
//! Overturning is not monotonic in amplitude (rocking has safe regions above the first
//! overturning amplitude), so the search first scans a lattice of amplitudes anchored at 0 in
//! parallel (multiples of the search's `resolution` h: every failing interval wider than it
//! holds a scan point), then refines the *lowest* change of outcome between neighbouring lattice
//! points (the threshold) by k-section ([`SECTIONS`]) down to the tolerance; the other changes
//! (islands' edges) are reported at the resolution. The answer does not depend on the number of
//! cores (they only evaluate the refinement's next points ahead), and two ranges that share h
//! and the lowest failing lattice point give it to the bit.
//!
//! Length (over 600 lines): the criteria, the planner (scan, refinement of the lowest change of
//! outcome) and the single- and multi-record searches share the request and the run tracker;
//! about a quarter of the file is their unit tests.
use super::fragility::{fit_binary, fit_interval, Capacity, FitParams, Fragility, Method, Point};
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
    Toppled {
        block: String,
    },
    Displacement {
        block: String,
        metres: f64,
    },
    Rotation {
        block: String,
        degrees: f64,
    },
    Not {
        inner: Box<Criterion>,
    },
    /// A damage criterion of `criteria` (its JSON form on the command line).
    Damage {
        damage: super::criteria::Damage,
    },
}

/// A criterion that does not parse: the text as given and what is wrong with it.
/// What a PGA search, a multi-record search or a site analysis cannot do as asked, by cause
/// (`RunError::Search`, or `RunError::RecordSearch` naming the record); each message names the
/// field.
#[derive(Debug, thiserror::Error)]
pub enum SearchError {
    #[error("criterion: at least one is required")]
    NoCriterion,
    /// A damage criterion does not fit the scene (its path and what is wrong).
    #[error(transparent)]
    Damage(#[from] super::criteria::CriterionError),
    #[error("criterion {criterion:?}: no free block with id {id:?}")]
    CriterionBlock { criterion: String, id: String },
    /// The amplitude range (m/s²).
    #[error("range: need 0 ≤ min < max, got min {min} max {max}")]
    Range { min: f64, max: f64 },
    /// The refinement's tolerance (m/s²).
    #[error("tolerance: must be > 0, got {0}")]
    Tolerance(f64),
    #[error("scan_points: must lie in 2..=1000, got {0}")]
    ScanPoints(usize),
    /// The asked scan resolution (m/s²).
    #[error("resolution: must be > 0, got {0}")]
    Resolution(f64),
    /// The scan lattice over the range holds too many points (resolution h in m/s²).
    #[error("resolution: the range needs {points} scan points at a resolution of {h} m/s², more than {MAX_SCAN_POINTS}: ask for a coarser resolution or a narrower range")]
    LatticePoints { points: usize, h: f64 },
    #[error("motion: the horizontal record is zero everywhere and cannot be scaled to a PGA")]
    ZeroMotion,
    #[error("motions: give at least one record")]
    NoRecords,
    #[error("observations: at least one is required")]
    NoObservations,
    #[error("records: at least one is required")]
    NoSiteRecords,
}

#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum CriterionParseError {
    /// A JSON damage criterion (docs/format.md §3) that does not parse; names the path.
    #[error(transparent)]
    Damage(#[from] super::criteria::CriterionError),
    #[error("criterion {text:?}: {what} must be a positive number, got {got:?}")]
    NotPositive {
        text: String,
        what: &'static str,
        got: String,
    },
    #[error("criterion {text:?}: expected toppled:BLOCK, displacement:BLOCK:METRES or rotation:BLOCK:DEGREES (optionally prefixed not:)")]
    Form { text: String },
}

/// Rotation (rad) past which a toppling block is counted as fallen before the run ends: at
/// 60° every block with a width-to-height ratio below 1.7 is beyond its tipping angle.
const FALLEN_ROTATION: f64 = std::f64::consts::FRAC_PI_3;

impl Criterion {
    /// Parse the command-line / API form.
    pub fn parse(text: &str) -> Result<Self, CriterionParseError> {
        if text.trim_start().starts_with('{') {
            let damage = super::criteria::Damage::parse(text)?;
            return Ok(Criterion::Damage { damage });
        }
        if let Some(rest) = text.strip_prefix("not:") {
            return Ok(Criterion::Not {
                inner: Box::new(Criterion::parse(rest)?),
            });
        }
        let parts: Vec<&str> = text.split(':').collect();
        let num = |s: &str, what: &'static str| -> Result<f64, CriterionParseError> {
            s.parse::<f64>()
                .ok()
                .filter(|v| v.is_finite() && *v > 0.0)
                .ok_or_else(|| CriterionParseError::NotPositive {
                    text: text.to_string(),
                    what,
                    got: s.to_string(),
                })
        };
        match parts.as_slice() {
            ["toppled", b] if !b.is_empty() => Ok(Criterion::Toppled {
                block: b.to_string(),
            }),
            ["displacement", b, m] if !b.is_empty() => Ok(Criterion::Displacement {
                block: b.to_string(),
                metres: num(m, "METRES")?,
            }),
            ["rotation", b, d] if !b.is_empty() => Ok(Criterion::Rotation {
                block: b.to_string(),
                degrees: num(d, "DEGREES")?,
            }),
            _ => Err(CriterionParseError::Form {
                text: text.to_string(),
            }),
        }
    }

    /// The command-line form.
    pub fn text(&self) -> String {
        match self {
            Criterion::Toppled { block } => format!("toppled:{block}"),
            Criterion::Displacement { block, metres } => format!("displacement:{block}:{metres}"),
            Criterion::Rotation { block, degrees } => format!("rotation:{block}:{degrees}"),
            Criterion::Not { inner } => format!("not:{}", inner.text()),
            Criterion::Damage { damage } => damage.text(),
        }
    }

    /// The block the criterion observes.
    pub fn block(&self) -> &str {
        match self {
            Criterion::Toppled { block }
            | Criterion::Displacement { block, .. }
            | Criterion::Rotation { block, .. } => block,
            Criterion::Not { inner } => inner.block(),
            Criterion::Damage { damage } => damage.blocks().first().copied().unwrap_or_default(),
        }
    }

    /// Every block the criterion names (checked to be free blocks of the scene).
    pub fn blocks(&self) -> Vec<&str> {
        match self {
            Criterion::Damage { damage } => damage.blocks(),
            other => vec![other.block()],
        }
    }

    /// Is the criterion met by the run's final state?
    fn met(&self, tr: &Tracker) -> bool {
        // A damage criterion reads every block it names (or all), not one block.
        match self {
            Criterion::Damage { damage } => {
                return damage.met(&super::criteria::FinalState::from_tracker(tr))
            }
            Criterion::Not { inner } if matches!(**inner, Criterion::Damage { .. }) => {
                return !inner.met(tr)
            }
            _ => {}
        }
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
            // Answered above.
            Criterion::Damage { .. } => false,
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

/// A `combine` that is neither `all` nor `any` (the text given).
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("combine: expected \"all\" or \"any\", got {got:?}")]
pub struct CombineParseError {
    pub got: String,
}

/// How several criteria combine into one verdict "failed".
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Combine {
    /// Every criterion is met (the observations all hold at once). The default: several
    /// observations of one site constrain the same shaking together.
    #[default]
    All,
    /// At least one criterion is met (any of several damage states counts as failure).
    Any,
}

impl Combine {
    /// Parse `all` / `any`.
    pub fn parse(text: &str) -> Result<Self, CombineParseError> {
        match text {
            "all" => Ok(Combine::All),
            "any" => Ok(Combine::Any),
            other => Err(CombineParseError {
                got: other.to_string(),
            }),
        }
    }

    /// The verdict from the criteria's verdicts.
    fn verdict(self, mut met: impl Iterator<Item = bool>) -> bool {
        match self {
            Combine::All => met.all(|m| m),
            Combine::Any => met.any(|m| m),
        }
    }

    /// The combined verdict once it is known before the end of the run: `all` is decided false
    /// by one criterion decided false, `any` true by one decided true; otherwise every
    /// criterion must be decided.
    fn decided(self, each: impl Iterator<Item = Option<bool>>) -> Option<bool> {
        let short = self == Combine::Any;
        let mut all_known = true;
        for d in each {
            match d {
                Some(m) if m == short => return Some(short),
                Some(_) => {}
                None => all_known = false,
            }
        }
        all_known.then_some(!short)
    }

    /// The `criterion` text of a result: one criterion as given (docs/format.md §3); several joined
    /// by `,` for `all` (as before) and written `any(a,b)` for `any`.
    pub fn label(self, criteria: &[Criterion]) -> String {
        let joined = criteria
            .iter()
            .map(Criterion::text)
            .collect::<Vec<_>>()
            .join(",");
        match self {
            Combine::Any if criteria.len() > 1 => format!("any({joined})"),
            _ => joined,
        }
    }
}

/// A `scan` that is neither `full` nor `lowest` (the text given).
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("scan: expected \"full\" or \"lowest\", got {got:?}")]
pub struct ScanParseError {
    pub got: String,
}

/// Which scan points a search evaluates before it refines the lowest change of outcome.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ScanOrder {
    /// Every scan point, all at once: `monotonic` and `failing_intervals` cover the whole
    /// range. The library's default (the searches the docs and tests record).
    #[default]
    Full,
    /// Ascending batches of `width` scan points, stopping after the first batch that holds a
    /// failing point; the refinement is the same. The answer needs no run above that batch,
    /// and on a many-block wall the runs far above the threshold are the slow ones
    /// (docs/pga.md). A range whose lowest point fails (a `not:` criterion) is scanned in full.
    Lowest,
}

impl ScanOrder {
    /// Parse `full` / `lowest`.
    pub fn parse(text: &str) -> Result<Self, ScanParseError> {
        match text {
            "full" => Ok(ScanOrder::Full),
            "lowest" => Ok(ScanOrder::Lowest),
            other => Err(ScanParseError {
                got: other.to_string(),
            }),
        }
    }
}

/// m/s², the refinement's tolerance of a search that asks for none (`ashlar pga` and the
/// service alike): an absolute amplitude, so that the lattice (h = tolerance × 2^K) and the
/// answer do not depend on the range; 0.01 m/s² (0.1 % of g) is below what a record's own
/// scaling tells apart, and from the default resolution it costs four trisection levels.
pub const DEFAULT_TOLERANCE: f64 = 0.01;

/// Scan points a search may hold (the lattice over its range): each is a full run.
pub const MAX_SCAN_POINTS: usize = 1000;

/// The scan resolution (m/s²) of a search that asks for none: 0.64 = 0.01 × 2⁶, a lattice
/// point of the default tolerance, puts 31 points over the default range 0.05–2 g (today's
/// 40 points were 0.49 m/s² apart) and costs about as many runs as they did (docs/pga.md,
/// "Search": 37 runs against 48 for the example column under Northridge); 0.32 (61 points)
/// cost 1.5 times as many for the same answers on the bundled records.
pub const DEFAULT_RESOLUTION: f64 = 0.64;

/// Scan points of a search over a range wider than [`DEFAULT_RESOLUTION`] × 39 (25 m/s²,
/// 2.5 g) that asks for neither a resolution nor scan points: its default resolution is
/// coarsened to span / 39 so that it never asks for more scan points than the former default.
pub const DEFAULT_SCAN_POINTS: usize = 40;

/// Relative slack when a resolution and the range's ends are matched to the lattice, so that a
/// decimal resolution (0.64 = 64 × 0.01) or range end (1.92 = 3 × 0.64) is not lost to
/// rounding: one part in 10⁹, far below any tolerance a search is given.
const LATTICE_SLACK: f64 = 1e-9;

/// The asked resolution (m/s²) of a search over [min, max] that asks for neither a resolution
/// nor scan points: [`DEFAULT_RESOLUTION`], or span / ([`DEFAULT_SCAN_POINTS`] − 1) over a
/// wider range. The CLI and the service both start from it.
pub fn default_resolution(min: f64, max: f64) -> f64 {
    DEFAULT_RESOLUTION.max((max - min) / (DEFAULT_SCAN_POINTS - 1) as f64)
}

/// A PGA search request (amplitudes in m/s²). The criteria combine by `combine` into "failed".
#[derive(Debug, Clone, PartialEq)]
pub struct PgaRequest {
    pub criteria: Vec<Criterion>,
    pub combine: Combine,
    pub min: f64,
    pub max: f64,
    pub tolerance: f64,
    /// Scan points asked for when `resolution` is `None`: the asked resolution is then
    /// (max − min)/(scan_points − 1), rounded down to the lattice as any other ([`Lattice`]).
    pub scan_points: usize,
    /// m/s², the scan resolution asked for (`None`: from `scan_points`). The scan runs on the
    /// lattice of multiples of h = tolerance × 2^K ≤ it ([`Lattice`], [`PgaResult::resolution`]).
    pub resolution: Option<f64>,
    /// Which scan points are run before the refinement ([`ScanOrder`]).
    pub scan: ScanOrder,
}

/// The scan lattice of a search: the multiples `k·h` (m/s²) of its resolution h anchored at 0,
/// for k in `first..=last`, which cover the range rounded outward to the lattice
/// (`floor(min/h)·h … ceil(max/h)·h`: at most one point beyond each end). h = tolerance × 2^K
/// with K ≥ 0 the largest such that h does not exceed the asked resolution (h = tolerance when
/// the asked resolution is finer), so that every search sharing the tolerance and the asked
/// resolution (or any two whose asked resolutions round to the same power of two) scans the
/// same amplitudes and refines the same cells the same way.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Lattice {
    /// m/s², the spacing: the search's resolution.
    pub h: f64,
    /// Levels of k-section ([`SECTIONS`]) that narrow a lattice cell to the tolerance.
    pub levels: u32,
    pub first: u64,
    pub last: u64,
}

impl Lattice {
    /// The lattice of a valid request ([`validate_search`]).
    pub fn of(req: &PgaRequest) -> Lattice {
        let asked = req
            .resolution
            .unwrap_or((req.max - req.min) / (req.scan_points.max(2) - 1) as f64);
        let mut power = 0i32;
        // 2^1000 tolerances is beyond any range (f64 holds 2^1023).
        while power < 1000 && req.tolerance * 2f64.powi(power + 1) <= asked * (1.0 + LATTICE_SLACK)
        {
            power += 1;
        }
        let h = req.tolerance * 2f64.powi(power);
        let levels = refinement_levels(h, req.tolerance);
        let first = (req.min / h + LATTICE_SLACK).floor().max(0.0) as u64;
        let last = ((req.max / h - LATTICE_SLACK).ceil() as u64).max(first + 1);
        Lattice {
            h,
            levels,
            first,
            last,
        }
    }

    /// Scan points of the lattice (`last − first + 1`).
    pub fn points(&self) -> usize {
        (self.last - self.first).saturating_add(1) as usize
    }

    /// The amplitude of multiple `k` (m/s²), computed the same way by every search.
    pub fn point(&self, k: u64) -> f64 {
        k as f64 * self.h
    }
}

impl PgaRequest {
    /// The search `ashlar pga` runs by default (`cli::load`'s range flags and `--resolution`):
    /// 0.05–2 g (standard g), resolution 0.64 m/s² ([`default_resolution`]), to 0.01 m/s²,
    /// every criterion. The examples and
    /// tests that reproduce a user's default search start from it.
    pub fn cli_default(criteria: Vec<Criterion>) -> Self {
        let g = crate::motion::STANDARD_GRAVITY;
        Self {
            criteria,
            combine: Combine::All,
            min: 0.05 * g,
            max: 2.0 * g,
            tolerance: DEFAULT_TOLERANCE,
            scan_points: DEFAULT_SCAN_POINTS,
            resolution: Some(default_resolution(0.05 * g, 2.0 * g)),
            scan: ScanOrder::Full,
        }
    }
}

#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct PgaRun {
    pub pga: f64,
    pub failed: bool,
}

/// `result.json` of docs/format.md §3.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct PgaResult {
    pub criterion: String,
    /// Largest amplitude found not to meet the criterion (below `failing_pga`).
    pub safe_pga: Option<f64>,
    /// Smallest amplitude found to meet it.
    pub failing_pga: Option<f64>,
    pub units: String,
    /// No amplitude above `failing_pga` was found safe by the scan or the refinement, and the
    /// scan ran to the top of the range (`scanned_to` ≥ max). This holds at the scan's
    /// resolution: a safe (or failing) interval narrower than `resolution` may lie between two
    /// scan points. Always false when the scan stopped at the first failure (nothing above
    /// `scanned_to` was run).
    pub monotonic: bool,
    /// m/s², spacing h of the scan lattice (multiples of h anchored at 0; [`Lattice`]): every
    /// failing interval wider than this holds a scan point and was found; narrower ones may
    /// have been missed. (0 in results written before the field existed.)
    #[serde(default)]
    pub resolution: f64,
    /// m/s², every failing interval found by the scan and the refinement, lowest first:
    /// `[lowest, highest]` failing amplitude of each run of consecutive failing amplitudes (the
    /// lowest change of outcome refined to the tolerance, every other end known to the
    /// `resolution`). Like `safe_pga`, `failing_pga` and `monotonic`, it does not depend on the
    /// number of cores; the runs evaluated ahead of the refinement are in `runs` only.
    #[serde(default)]
    pub failing_intervals: Vec<[f64; 2]>,
    /// The scan that was run: `full` (every scan point) or `lowest` (ascending, stopped at the
    /// first failing point; on several cores the rest of that point's batch was run too and
    /// is in `runs` only). A `lowest` request whose first failing point is the range's top,
    /// or whose lowest point failed, reports `full`. (`full` in results written before the
    /// field existed.)
    #[serde(default)]
    pub scan: ScanOrder,
    /// m/s², the highest scan point the answer reads: the range's max after a full scan, the
    /// first failing point after a lowest one (the same for any number of cores; points of
    /// its batch above it may be in `runs`). Above it `failing_intervals` and `monotonic` say
    /// nothing. (`null` in results written before the field existed.)
    #[serde(default)]
    pub scanned_to: Option<f64>,
    pub runs: Vec<PgaRun>,
}

/// The failing intervals of `runs` (sorted by amplitude): `[first, last]` failing amplitude of
/// each maximal run of consecutive failing amplitudes.
pub fn failing_intervals(runs: &[PgaRun]) -> Vec<[f64; 2]> {
    let mut out: Vec<[f64; 2]> = Vec::new();
    let mut open = false;
    for r in runs {
        match (r.failed, open) {
            (true, true) => {
                if let Some(last) = out.last_mut() {
                    last[1] = r.pga;
                }
            }
            (true, false) => out.push([r.pga, r.pga]),
            _ => {}
        }
        open = r.failed;
    }
    out
}

/// Largest amplitude not meeting the criterion below the lowest failing one, the lowest
/// failing one, and whether every amplitude above it fails, from `runs` sorted by amplitude.
pub fn bracket_of(runs: &[PgaRun]) -> (Option<f64>, Option<f64>, bool) {
    let failing = runs.iter().find(|r| r.failed).map(|r| r.pga);
    let safe = runs
        .iter()
        .filter(|r| !r.failed && failing.is_none_or(|f| r.pga < f))
        .map(|r| r.pga)
        .fold(None, |m: Option<f64>, p| Some(m.map_or(p, |m| m.max(p))));
    let monotonic = match failing {
        Some(f) => runs.iter().all(|r| r.failed || r.pga < f),
        None => true,
    };
    (safe, failing, monotonic)
}

fn validate(scene: &Scene, motion: &GroundMotion, req: &PgaRequest) -> Result<(), SearchError> {
    if req.criteria.is_empty() {
        return Err(SearchError::NoCriterion);
    }
    for c in &req.criteria {
        if let Criterion::Damage { damage } = c {
            damage.check(scene)?;
        }
        for id in c.blocks() {
            if scene
                .block_index(id)
                .is_none_or(|b| !matches!(scene.blocks[b].kind, crate::scene::BlockKind::Free(_)))
            {
                return Err(SearchError::CriterionBlock {
                    criterion: c.text(),
                    id: id.to_string(),
                });
            }
        }
    }
    if !(req.min.is_finite() && req.max.is_finite() && req.min >= 0.0 && req.max > req.min) {
        return Err(SearchError::Range {
            min: req.min,
            max: req.max,
        });
    }
    if !(req.tolerance.is_finite() && req.tolerance > 0.0) {
        return Err(SearchError::Tolerance(req.tolerance));
    }
    match req.resolution {
        Some(r) if !(r.is_finite() && r > 0.0) => return Err(SearchError::Resolution(r)),
        Some(_) => {}
        None if req.scan_points < 2 || req.scan_points > MAX_SCAN_POINTS => {
            return Err(SearchError::ScanPoints(req.scan_points))
        }
        None => {}
    }
    let lattice = Lattice::of(req);
    if lattice.last - lattice.first >= MAX_SCAN_POINTS as u64 {
        return Err(SearchError::LatticePoints {
            points: (lattice.last - lattice.first).saturating_add(1) as usize,
            h: lattice.h,
        });
    }
    if motion.horizontal.peak() <= 0.0 {
        return Err(SearchError::ZeroMotion);
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
    evaluate_combined(scene, motion, criteria, Combine::All, pga, cancel)
}

/// [`evaluate`] with an explicit combination of the criteria.
pub fn evaluate_combined(
    scene: &Scene,
    motion: &GroundMotion,
    criteria: &[Criterion],
    combine: Combine,
    pga: f64,
    cancel: Option<&std::sync::atomic::AtomicBool>,
) -> Result<bool, RunError> {
    evaluate_with_summary(scene, motion, criteria, combine, pga, cancel).map(|(failed, _)| failed)
}

/// [`evaluate_combined`] returning the run's summary too (which model ran, its steps and wall
/// time: `examples/reduced_speed.rs` profiles searches with it).
pub fn evaluate_with_summary(
    scene: &Scene,
    motion: &GroundMotion,
    criteria: &[Criterion],
    combine: Combine,
    pga: f64,
    cancel: Option<&std::sync::atomic::AtomicBool>,
) -> Result<(bool, super::run::Summary), RunError> {
    let gm = motion.scaled_to_pga(pga);
    let decided = |tr: &Tracker| {
        combine
            .decided(criteria.iter().map(|c| c.decided(tr)))
            .is_some()
    };
    // `auto`'s fallback to the engine hands over as in `ashlar run` (both take the default of
    // `RunOptions::fallback_from_zero`), so a full run at a bracket end reproduces its verdict
    // (tests/analysis/pga_honesty.rs; docs/speed.md, "Reduced models on records").
    let opts = RunOptions {
        stop_when: Some(&decided),
        cancel,
        no_trajectory: true,
        end_when_still: true,
        ..Default::default()
    };
    let out = run(scene, &gm, &opts)?;
    if out.cancelled {
        return Err(RunError::Cancelled);
    }
    let s = out.summary;
    // The verdict from the final state; a run stopped early was stopped because every
    // criterion was decided, and `decided` agrees with `met` by construction.
    let mut tr = Tracker::default();
    for b in &s.blocks {
        tr.ids.push(b.id.clone());
        tr.final_rotation.push(b.final_rotation);
        tr.final_displacement.push(b.final_displacement);
    }
    Ok((combine.verdict(criteria.iter().map(|c| c.met(&tr))), s))
}

/// One step of a search replayed from the outcomes known so far (see [`plan`]).
#[derive(Debug, Clone, PartialEq)]
pub enum Step<T> {
    /// These (record, amplitude m/s²) pairs must be evaluated before the search can go on;
    /// `done` runs were found known on the way.
    Pending {
        batch: Vec<(usize, f64)>,
        done: usize,
    },
    /// The search is over.
    Done(T),
}

/// Runs a search is expected to need: the scan, then rounds of `width` runs, each taking the
/// refinement log_k(width + 1) levels down (k = [`SECTIONS`]; a level's k − 1 points take
/// (k − 1)/width rounds on fewer cores), until the lattice's levels are done. For progress only.
pub fn expected_runs(req: &PgaRequest, width: usize) -> f64 {
    let width = width.max(1);
    let lattice = Lattice::of(req);
    let k = SECTIONS as f64;
    let per_round = if width + 1 < SECTIONS {
        width as f64 / (k - 1.0)
    } else {
        ((width + 1) as f64).log(k)
    };
    let rounds = (f64::from(lattice.levels) / per_round - 1e-9).ceil();
    lattice.points() as f64 + rounds * width as f64
}

/// Parts the refinement splits the lowest bracket into at each level (the k of k-section):
/// 3, the split the search used on two cores before the lattice (its answers in the docs'
/// tables were found so), which on two cores takes a level per round with no run wasted,
/// and whose rule (the lowest change among the bracket's ends and two inner points) found the
/// example column's threshold under Loma Prieta within 0.13 m/s² of a brute force where
/// bisection (2) landed 0.25 above it (docs/pga.md, "Search"). A constant, not a request
/// field: two searches share their answer only when they share it.
pub const SECTIONS: usize = 3;

/// The bracket of the refinement: a change of outcome between `lo` and `hi` (m/s²), the outcome
/// at `lo`, and the levels of k-section ([`SECTIONS`]) left down to the tolerance.
#[derive(Debug, Clone, Copy)]
struct Bracket {
    lo: f64,
    hi: f64,
    lo_failed: bool,
    levels: u32,
}

impl Bracket {
    /// The bracket's inner points, lowest first, or `None` once the tolerance is reached (or the
    /// bracket is too narrow for floating point to split: a tolerance below one ULP of the
    /// amplitudes). Computed from `lo` and `hi` only, the same way on every path to them.
    fn points(&self) -> Option<Vec<f64>> {
        let k = SECTIONS as f64;
        let pts: Vec<f64> = (1..SECTIONS)
            .map(|i| self.lo + (self.hi - self.lo) * i as f64 / k)
            .collect();
        let inside = pts.first().is_some_and(|&p| p > self.lo)
            && pts.last().is_some_and(|&p| p < self.hi)
            && pts.windows(2).all(|w| w[0] < w[1]);
        (self.levels > 0 && inside).then_some(pts)
    }

    /// The part the refinement keeps once the outcomes at `pts` (`self.points()`) are known: the
    /// lowest whose ends differ (failing above a safe `lo`: the lowest failure found).
    fn child(&self, pts: &[f64], failed: &[bool]) -> Bracket {
        let ends: Vec<f64> = std::iter::once(self.lo)
            .chain(pts.iter().copied())
            .chain(std::iter::once(self.hi))
            .collect();
        let outs: Vec<bool> = std::iter::once(self.lo_failed)
            .chain(failed.iter().copied())
            .chain(std::iter::once(!self.lo_failed))
            .collect();
        // The ends differ, so some part's ends do.
        let i = (0..ends.len() - 1)
            .find(|&i| outs[i] != outs[i + 1])
            .unwrap_or(ends.len() - 2);
        Bracket {
            lo: ends[i],
            hi: ends[i + 1],
            lo_failed: outs[i],
            levels: self.levels - 1,
        }
    }

    /// The next `width` points of the refinement's tree under this bracket not in `seen`,
    /// breadth first and lowest part first: this bracket's inner points, then those of each of
    /// its parts, ... Each is computed as the refinement computes it once it gets there, so the
    /// outcomes evaluated ahead are found again to the bit.
    fn ahead(&self, width: usize, seen: &std::collections::HashMap<u64, bool>) -> Vec<f64> {
        let mut queue = std::collections::VecDeque::from([*self]);
        let mut out = Vec::with_capacity(width);
        while out.len() < width {
            let Some(b) = queue.pop_front() else { break };
            let Some(pts) = b.points() else { continue };
            out.extend(
                pts.iter()
                    .filter(|p| !seen.contains_key(&p.to_bits()))
                    .take(width - out.len()),
            );
            // Every part, whatever the outcomes (which do not move the points).
            let ends: Vec<f64> = std::iter::once(b.lo)
                .chain(pts.iter().copied())
                .chain(std::iter::once(b.hi))
                .collect();
            queue.extend(ends.windows(2).map(|w| Bracket {
                lo: w[0],
                hi: w[1],
                levels: b.levels - 1,
                ..b
            }));
        }
        out
    }
}

/// Levels of k-section ([`SECTIONS`]) that narrow a lattice cell `h` wide (m/s²) to the
/// tolerance or below.
fn refinement_levels(h: f64, tolerance: f64) -> u32 {
    let mut levels = 0;
    let mut width = h;
    // h ≤ tolerance × 2^1000 ([`Lattice::of`]) takes fewer than 1000 levels.
    while width > tolerance * (1.0 + LATTICE_SLACK) && levels < 1000 {
        width /= SECTIONS as f64;
        levels += 1;
    }
    levels
}

/// The search as a pure, deterministic planner: replays the scan of the lattice ([`Lattice`])
/// and the k-section of its lowest change of outcome from the outcomes `known` returns (`None`:
/// not evaluated yet) and stops at the first batch with unknown amplitudes. Each round of the
/// refinement evaluates the next `width` points of its tree ahead ([`Bracket::ahead`]), but the
/// bracket is chosen by the k-section rule only, so the result (apart from its `runs`) is the
/// same for any `width`. Replaying with more outcomes known gives the same batches again, so
/// the outcomes may come from anywhere (this process's threads, or child jobs on other
/// machines) in any order. `req` must be valid.
pub fn plan(
    req: &PgaRequest,
    width: usize,
    known: &dyn Fn(f64) -> Option<bool>,
) -> Step<PgaResult> {
    let width = width.max(1);
    let mut done = 0;
    // A batch's runs, or the amplitudes of it still unknown.
    let mut batch = |pgas: &[f64]| -> Result<Vec<PgaRun>, Vec<(usize, f64)>> {
        let got: Vec<Option<bool>> = pgas.iter().map(|&p| known(p)).collect();
        done += got.iter().filter(|g| g.is_some()).count();
        if got.iter().all(Option::is_some) {
            Ok(pgas
                .iter()
                .zip(got)
                .map(|(&pga, g)| PgaRun {
                    pga,
                    failed: g == Some(true),
                })
                .collect())
        } else {
            Err(pgas
                .iter()
                .zip(got)
                .filter(|(_, g)| g.is_none())
                .map(|(&p, _)| (0, p))
                .collect())
        }
    };
    let lattice = Lattice::of(req);
    let grid: Vec<f64> = (lattice.first..=lattice.last)
        .map(|k| lattice.point(k))
        .collect();
    let n = grid.len();
    // The scan: every lattice point at once, or ascending batches of `width` up to the first
    // batch holding a failing point. The lowest change of outcome lies below that point, so
    // both scans refine the same bracket and give the same answer.
    let mut scanned = 0;
    let mut runs = Vec::with_capacity(n);
    while scanned < n {
        let end = match req.scan {
            ScanOrder::Full => n,
            // The first batch failing at its lowest point (a range that starts failing: the
            // change asked for is where failure ends) takes the rest of the scan at once.
            ScanOrder::Lowest if runs.first().is_some_and(|r: &PgaRun| r.failed) => n,
            ScanOrder::Lowest => (scanned + width).min(n),
        };
        match batch(&grid[scanned..end]) {
            Ok(r) => runs.extend(r),
            Err(pending) => {
                return Step::Pending {
                    batch: pending,
                    done,
                }
            }
        }
        scanned = end;
        if runs.iter().any(|r| r.failed) && !runs[0].failed {
            break;
        }
    }
    // Where the scan would have stopped on one core: a lowest scan at its first failing point
    // (the rest of its last batch was run only because `width` points go at once, so it stays
    // in `runs` and out of the answer); a full scan, or one whose lowest point failed, at the
    // top. `scanned_to`, `monotonic` and `failing_intervals` read this, not `scanned`.
    let scan_end = match req.scan {
        ScanOrder::Lowest if !runs.first().is_some_and(|r| r.failed) => runs
            .iter()
            .position(|r| r.failed)
            .map_or(scanned, |k| k + 1),
        _ => scanned,
    };
    // The scan and the refinement's own points: what the result's answer, `monotonic` and
    // `failing_intervals` are read from, the same for any width.
    let mut path = runs[..scan_end].to_vec();
    // Bisect the lowest change of outcome between neighbouring lattice points (the threshold
    // the search answers: the lowest failing amplitude, or for a range that starts failing,
    // e.g. a `not:` criterion, the highest amplitude that still fails) down to the tolerance.
    // Every other change stays at the resolution: refining them does not move
    // `safe_pga`/`failing_pga`, and it took 44 % of the drum column's search (docs/speed.md).
    let lowest = runs
        .windows(2)
        .find(|w| w[0].failed != w[1].failed)
        .map(|w| Bracket {
            lo: w[0].pga,
            hi: w[1].pga,
            lo_failed: w[0].failed,
            levels: lattice.levels,
        });
    if let Some(mut bracket) = lowest {
        // The refinement's outcomes replayed so far (this replay's batches only).
        let mut seen = std::collections::HashMap::new();
        loop {
            // Down the refinement as far as the outcomes go; the others were evaluated ahead
            // on a branch it did not take.
            while let Some(pts) = bracket.points() {
                let Some(failed) = pts
                    .iter()
                    .map(|p| seen.get(&p.to_bits()).copied())
                    .collect::<Option<Vec<bool>>>()
                else {
                    break;
                };
                path.extend(
                    pts.iter()
                        .zip(&failed)
                        .map(|(&pga, &failed)| PgaRun { pga, failed }),
                );
                bracket = bracket.child(&pts, &failed);
            }
            let ahead = bracket.ahead(width, &seen);
            if ahead.is_empty() {
                break;
            }
            match batch(&ahead) {
                Ok(round) => {
                    seen.extend(round.iter().map(|r| (r.pga.to_bits(), r.failed)));
                    runs.extend(round);
                }
                Err(pending) => {
                    return Step::Pending {
                        batch: pending,
                        done,
                    }
                }
            }
        }
    }
    runs.sort_by(|a, b| a.pga.total_cmp(&b.pga));
    path.sort_by(|a, b| a.pga.total_cmp(&b.pga));
    let (safe, fail, monotonic) = bracket_of(&path);
    let full = scan_end == n;
    Step::Done(PgaResult {
        criterion: req.combine.label(&req.criteria),
        safe_pga: safe,
        failing_pga: fail,
        units: "m/s2".into(),
        monotonic: monotonic && full,
        resolution: lattice.h,
        failing_intervals: failing_intervals(&path),
        scan: if full {
            ScanOrder::Full
        } else {
            ScanOrder::Lowest
        },
        scanned_to: Some(grid[scan_end - 1]),
        runs,
    })
}

/// [`plan`] for several records searched together: one planner per record, replayed side by
/// side; the pending batches of every record come out at once. `known(record, pga)`.
pub fn plan_records(
    records: usize,
    req: &PgaRequest,
    width: usize,
    known: &dyn Fn(usize, f64) -> Option<bool>,
) -> Step<Vec<PgaResult>> {
    let mut results = Vec::with_capacity(records);
    let mut pending = Vec::new();
    let mut done = 0;
    for i in 0..records {
        match plan(req, width, &|p| known(i, p)) {
            Step::Done(r) => {
                done += r.runs.len();
                results.push(r);
            }
            Step::Pending { batch, done: d } => {
                done += d;
                pending.extend(batch.into_iter().map(|(_, p)| (i, p)));
            }
        }
    }
    if pending.is_empty() {
        Step::Done(results)
    } else {
        Step::Pending {
            batch: pending,
            done,
        }
    }
}

/// Search for the threshold amplitude: [`plan`] driven in this process, each batch evaluated
/// on the rayon pool (one interior point per thread and round).
pub fn search(
    scene: &Scene,
    motion: &GroundMotion,
    req: &PgaRequest,
    opts: &RunOptions,
) -> Result<PgaResult, RunError> {
    validate(scene, motion, req)?;
    let cancel = opts.cancel;
    let workers = rayon::current_num_threads().max(1);
    let expected = expected_runs(req, workers);
    let report = |done: usize| {
        if let Some(p) = opts.progress {
            p((done as f64 / expected).min(0.99));
        }
    };
    let mut known: std::collections::HashMap<u64, bool> = std::collections::HashMap::new();
    let mut done = 0;
    loop {
        let step = plan(req, workers, &|p| known.get(&p.to_bits()).copied());
        let batch = match step {
            Step::Done(r) => return Ok(r),
            Step::Pending { batch, .. } => batch,
        };
        if done > 0 && cancel.is_some_and(|c| c.load(std::sync::atomic::Ordering::Relaxed)) {
            return Err(RunError::Cancelled);
        }
        let outcomes: Vec<bool> = batch
            .par_iter()
            .map(|&(_, pga)| {
                let start = std::time::Instant::now();
                let (failed, s) =
                    evaluate_with_summary(scene, motion, &req.criteria, req.combine, pga, cancel)?;
                // A long search's progress, run by run (`RUST_LOG=ashlar::analysis::pga=info`
                // with `ashlar pga`): amplitude m/s², verdict, wall seconds, simulated seconds
                // and steps, and why the run ended early (if it did).
                tracing::info!(
                    pga,
                    failed,
                    seconds = start.elapsed().as_secs_f64(),
                    simulated = s.simulated_time,
                    steps = s.steps,
                    stopped = s.stopped_reason.as_deref().unwrap_or("-"),
                    "run"
                );
                Ok(failed)
            })
            .collect::<Result<_, RunError>>()?;
        for (&(_, pga), failed) in batch.iter().zip(outcomes) {
            known.insert(pga.to_bits(), failed);
        }
        done += batch.len();
        report(done);
    }
}

/// One record's search in a multi-record study: the single-record result plus the record's name.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct RecordResult {
    pub motion: String,
    #[serde(flatten)]
    pub result: PgaResult,
}

/// The result of a search over several records with its fragility curve.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct MultiResult {
    pub criterion: String,
    pub units: String,
    pub records: Vec<RecordResult>,
    /// `null` when no curve can be fitted (then `fragility_error` says why).
    pub fragility: Option<Fragility>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub fragility_error: Option<String>,
}

/// What a record's search says of its capacity (the lowest PGA that meets the criterion):
/// it lies in (safe_pga, failing_pga]; a side the search did not bound is open.
pub fn capacity(r: &PgaResult) -> Capacity {
    Capacity {
        above: r.safe_pga.filter(|s| *s > 0.0),
        at_most: r.failing_pga,
    }
}

/// Search every record (each scaled to the amplitudes of `req`), then fit a lognormal fragility
/// curve by `method`. Records run in parallel, and so do the runs of each record's scan.
/// Progress is the mean of the records' progress.
pub fn search_records(
    scene: &Scene,
    records: &[(String, GroundMotion)],
    req: &PgaRequest,
    method: Method,
    opts: &RunOptions,
) -> Result<MultiResult, RunError> {
    validate_records(scene, records, req)?;
    let results = for_each_record(records, opts, |name, gm, sub| {
        search(scene, gm, req, sub).map(|result| RecordResult {
            motion: name.to_string(),
            result,
        })
    })?;
    Ok(multi_result(results, req, method))
}

/// `f` over every record in parallel, each with its own [`RunOptions`] whose progress feeds the
/// caller's as the mean of the records' progress (the caller's cancel flag is shared); a record's
/// error names the record ([`record_error`]). Results keep the records' order.
pub fn for_each_record<T: Send>(
    records: &[(String, GroundMotion)],
    opts: &RunOptions,
    f: impl Fn(&str, &GroundMotion, &RunOptions) -> Result<T, RunError> + Sync,
) -> Result<Vec<T>, RunError> {
    let parts = std::sync::Mutex::new(vec![0.0f64; records.len()]);
    records
        .par_iter()
        .enumerate()
        .map(|(i, (name, gm))| {
            let progress = |p: f64| {
                if let (Some(report), Ok(mut parts)) = (opts.progress, parts.lock()) {
                    parts[i] = p;
                    report(parts.iter().sum::<f64>() / parts.len() as f64);
                }
            };
            let sub = RunOptions {
                cancel: opts.cancel,
                progress: Some(&progress),
                ..Default::default()
            };
            f(name, gm, &sub).map_err(|e| record_error(name, e))
        })
        .collect()
}

/// A record's error in a multi-record search names the record (a cancel stays a cancel).
pub fn record_error(name: &str, e: RunError) -> RunError {
    match e {
        RunError::Cancelled => RunError::Cancelled,
        RunError::Search(source) => RunError::RecordSearch {
            record: name.into(),
            source,
        },
        RunError::Simulation(source) => RunError::RecordSimulation {
            record: name.into(),
            source,
        },
        other => other,
    }
}

/// The runs of a search's result whose choice does not depend on the number of cores: the
/// scan (a `lowest` scan up to its first failing point) and the refinement points the k-section
/// rule chose, found by replaying [`plan`] at width 1 on `r.runs` (at width 1 the planner
/// evaluates nothing ahead and scans one point a batch). Left out: the runs evaluated ahead on
/// branches the refinement did not take, and a `lowest` scan's points above its first failure
/// in the same batch, both of which come with the width. Every point the replay needs is in
/// `r.runs` when `r` is [`plan`]'s result for `req` at any width; otherwise (a result of another
/// request) all of `r.runs`.
pub fn width_free_runs(r: &PgaResult, req: &PgaRequest) -> Vec<PgaRun> {
    let known: std::collections::HashMap<u64, bool> = r
        .runs
        .iter()
        .map(|run| (run.pga.to_bits(), run.failed))
        .collect();
    match plan(req, 1, &|p| known.get(&p.to_bits()).copied()) {
        Step::Done(replayed) => replayed.runs,
        Step::Pending { .. } => r.runs.clone(),
    }
}

/// The multi-record result from the records' searches: the fragility curve fitted by `method`
/// to each record's [`width_free_runs`] (so that the curve does not depend on the number of
/// cores).
pub fn multi_result(results: Vec<RecordResult>, req: &PgaRequest, method: Method) -> MultiResult {
    let points: Vec<Point> = results
        .iter()
        .flat_map(|r| width_free_runs(&r.result, req))
        .filter(|r| r.pga > 0.0)
        .map(|r| Point {
            pga: r.pga,
            failed: r.failed,
        })
        .collect();
    let params = FitParams::default();
    let fit = match method {
        Method::Interval => {
            let caps: Vec<Capacity> = results.iter().map(|r| capacity(&r.result)).collect();
            fit_interval(&caps, points, &params)
        }
        Method::Binary => fit_binary(points, &params),
    };
    let (fragility, fragility_error) = match fit {
        Ok(f) => (Some(f), None),
        Err(e) => (None, Some(e.to_string())),
    };
    MultiResult {
        criterion: req.combine.label(&req.criteria),
        units: "m/s2".into(),
        records: results,
        fragility,
        fragility_error,
    }
}

/// Check a multi-record search's request against every record (the errors name the record).
pub fn validate_records(
    scene: &Scene,
    records: &[(String, GroundMotion)],
    req: &PgaRequest,
) -> Result<(), RunError> {
    if records.is_empty() {
        return Err(SearchError::NoRecords.into());
    }
    for (name, gm) in records {
        validate(scene, gm, req).map_err(|source| RunError::RecordSearch {
            record: name.clone(),
            source,
        })?;
    }
    Ok(())
}

/// Check a single-record search's request.
pub fn validate_search(
    scene: &Scene,
    motion: &GroundMotion,
    req: &PgaRequest,
) -> Result<(), RunError> {
    Ok(validate(scene, motion, req)?)
}

/// The fragility plot of a multi-record result (`None` when no curve was fitted).
pub fn fragility_svg(r: &MultiResult) -> Option<String> {
    let f = r.fragility.as_ref()?;
    let caps: Vec<(String, Capacity)> = r
        .records
        .iter()
        .map(|x| (x.motion.clone(), capacity(&x.result)))
        .collect();
    Some(super::fragility::svg(
        f,
        &caps,
        &format!("Fragility: {} ({} records)", r.criterion, r.records.len()),
    ))
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
    Combine::All.verdict(criteria.iter().map(|c| c.met(&tr)))
}

/// One criterion's verdict on a finished run (`run --criterion`, a job's `criterion`).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Verdict {
    pub criterion: String,
    pub met: bool,
}

/// Each criterion's verdict on a finished run's summary, one by one: a damage criterion on the
/// final state (`criteria::FinalState`), the `pga` forms as [`met_by_summary`] tests them.
pub fn verdicts(criteria: &[Criterion], summary: &super::run::Summary) -> Vec<Verdict> {
    let state = super::criteria::FinalState::from_summary(summary);
    criteria
        .iter()
        .map(|c| Verdict {
            criterion: c.text(),
            met: match c {
                Criterion::Damage { damage } => damage.met(&state),
                other => met_by_summary(std::slice::from_ref(other), summary),
            },
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn combinations_decide_as_early_as_logic_allows() {
        let (t, f, u) = (Some(true), Some(false), None);
        // all: one known failure decides false; true needs every criterion known.
        assert_eq!(Combine::All.decided([f, u].into_iter()), Some(false));
        assert_eq!(Combine::All.decided([t, u].into_iter()), None);
        assert_eq!(Combine::All.decided([t, t].into_iter()), Some(true));
        // any: one known success decides true; false needs every criterion known.
        assert_eq!(Combine::Any.decided([u, t].into_iter()), Some(true));
        assert_eq!(Combine::Any.decided([f, u].into_iter()), None);
        assert_eq!(Combine::Any.decided([f, f].into_iter()), Some(false));
        assert!(Combine::Any.verdict([false, true].into_iter()));
        assert!(!Combine::All.verdict([false, true].into_iter()));
        assert!(Combine::parse("most").is_err());
        let c = [
            Criterion::parse("toppled:a").expect("c"),
            Criterion::parse("not:rotation:b:5").expect("c"),
        ];
        assert_eq!(Combine::All.label(&c), "toppled:a,not:rotation:b:5");
        assert_eq!(Combine::Any.label(&c), "any(toppled:a,not:rotation:b:5)");
        assert_eq!(Combine::Any.label(&c[..1]), "toppled:a");
    }

    fn request(min: f64, max: f64, tolerance: f64, scan_points: usize) -> PgaRequest {
        PgaRequest {
            criteria: vec![Criterion::parse("toppled:a").expect("c")],
            combine: Combine::All,
            min,
            max,
            tolerance,
            scan_points,
            resolution: None,
            scan: ScanOrder::Full,
        }
    }

    /// Drive the planner to the end with a scripted evaluator, recording every batch.
    fn drive(
        req: &PgaRequest,
        width: usize,
        fails: impl Fn(f64) -> bool,
    ) -> (PgaResult, Vec<Vec<f64>>) {
        let mut known = std::collections::HashMap::new();
        let mut batches = Vec::new();
        loop {
            match plan(req, width, &|p| known.get(&p.to_bits()).copied()) {
                Step::Done(r) => return (r, batches),
                Step::Pending { batch, done } => {
                    assert_eq!(done, known.len(), "every known run is replayed");
                    let pts: Vec<f64> = batch
                        .iter()
                        .map(|&(i, p)| {
                            assert_eq!(i, 0);
                            p
                        })
                        .collect();
                    for &p in &pts {
                        known.insert(p.to_bits(), fails(p));
                    }
                    batches.push(pts);
                }
            }
        }
    }

    /// The k-section ([`SECTIONS`]) of the bracket (lo, hi) over `levels` levels, written out
    /// independently of the planner: the lowest part whose ends differ is kept.
    fn ksect(mut lo: f64, mut hi: f64, levels: u32, fails: impl Fn(f64) -> bool) -> (f64, f64) {
        let lo_failed = fails(lo);
        let k = SECTIONS as f64;
        for _ in 0..levels {
            let (a, b) = (lo, hi);
            let mut prev = (a, lo_failed);
            for i in 1..=SECTIONS {
                let p = if i == SECTIONS {
                    b
                } else {
                    a + (b - a) * i as f64 / k
                };
                let f = if i == SECTIONS { !lo_failed } else { fails(p) };
                if f != prev.1 {
                    (lo, hi) = (prev.0, p);
                    break;
                }
                prev = (p, f);
            }
        }
        (lo, hi)
    }

    #[test]
    fn planner_scans_the_lattice_then_k_sections_the_lowest_bracket() {
        // Threshold 2.37 m/s² on [0, 4], 5 scan points asked (resolution 1) to 0.05: the
        // lattice is 0.05 × 2⁴ = 0.8 (the largest power-of-two multiple of the tolerance not
        // above 1), so the scan is 0, 0.8, ..., 4.0 and the bracket (1.6, 2.4) takes 3
        // trisections (0.8/27 ≤ 0.05). Width 2: a round is a level's two inner points.
        assert_eq!(SECTIONS, 3, "the numbers below are for trisection");
        let req = request(0.0, 4.0, 0.05, 5);
        let fails = |p: f64| p >= 2.37;
        let (r, batches) = drive(&req, 2, fails);
        let lattice = Lattice::of(&req);
        assert_eq!((lattice.h, lattice.levels), (0.8, 3));
        assert_eq!(
            batches[0],
            (0..=5).map(|k| k as f64 * 0.8).collect::<Vec<_>>()
        );
        let (lo, hi) = (2.0 * 0.8, 3.0 * 0.8);
        assert_eq!(
            batches[1],
            vec![lo + (hi - lo) / 3.0, lo + (hi - lo) * 2.0 / 3.0]
        );
        assert!(batches[1..].iter().all(|b| b.len() == 2), "{batches:?}");
        let (s, f) = ksect(lo, hi, 3, fails);
        assert_eq!((r.safe_pga, r.failing_pga), (Some(s), Some(f)));
        assert!(f - s <= 0.05 && s < 2.37 && 2.37 <= f);
        // 3 rounds of 2 after the scan; with width 2 nothing is evaluated ahead.
        assert_eq!(batches.len(), 4);
        assert_eq!(r.runs.len(), 6 + 3 * 2);
        assert_eq!(r.failing_intervals, vec![[f, 4.0]]);
        assert!(r.monotonic);
        assert_eq!(r.resolution, 0.8);
        assert!(r.runs.windows(2).all(|w| w[0].pga <= w[1].pga), "sorted");
        assert!((expected_runs(&req, 2) - 12.0).abs() < 1e-12);
        // One core: a point a round, the same answer; 8 cores: two levels a round (2 + 6).
        let (one, b1) = drive(&req, 1, fails);
        let (eight, b8) = drive(&req, 8, fails);
        assert_eq!((bits(&one), bits(&eight)), (bits(&r), bits(&r)));
        assert_eq!((b1.len(), b8.len()), (1 + 6, 1 + 2));
        assert_eq!(one.runs.len(), 12);
    }

    #[test]
    fn replay_after_partial_results_asks_for_the_rest_of_the_same_batch() {
        let req = request(0.0, 4.0, 0.05, 5);
        let fails = |p: f64| p >= 2.37;
        let (_, batches) = drive(&req, 3, fails);
        // Any subset of the outcomes known: the planner asks for exactly the missing part of
        // the first incomplete batch, and reports how many it found.
        let all: Vec<f64> = batches.iter().flatten().copied().collect();
        for cut in 0..all.len() {
            for skip in 0..=cut {
                // Known: the first `cut` runs except the `skip`-th (when skip < cut).
                let known: std::collections::HashMap<u64, bool> = all[..cut]
                    .iter()
                    .enumerate()
                    .filter(|(k, _)| *k != skip)
                    .map(|(_, &p)| (p.to_bits(), fails(p)))
                    .collect();
                let step = plan(&req, 3, &|p| known.get(&p.to_bits()).copied());
                // The batch holding the first missing run.
                let first_missing = if skip < cut { skip } else { cut };
                let (mut start, mut b) = (0, 0);
                while start + batches[b].len() <= first_missing {
                    start += batches[b].len();
                    b += 1;
                }
                let want: Vec<(usize, f64)> = batches[b]
                    .iter()
                    .filter(|p| !known.contains_key(&p.to_bits()))
                    .map(|&p| (0, p))
                    .collect();
                match step {
                    Step::Pending { batch, done } => {
                        assert_eq!(batch, want, "cut {cut} skip {skip}");
                        assert_eq!(done, start + batches[b].len() - want.len());
                    }
                    Step::Done(_) => panic!("cut {cut} skip {skip}: done too early"),
                }
            }
        }
        // Outcomes of amplitudes the search never asks for change nothing.
        let mut known: std::collections::HashMap<u64, bool> =
            all.iter().map(|&p| (p.to_bits(), fails(p))).collect();
        let Step::Done(a) = plan(&req, 3, &|p| known.get(&p.to_bits()).copied()) else {
            panic!("all known")
        };
        known.insert(0.123f64.to_bits(), true);
        let Step::Done(b) = plan(&req, 3, &|p| known.get(&p.to_bits()).copied()) else {
            panic!("all known")
        };
        assert_eq!(a, b);
    }

    #[test]
    fn planner_reports_non_monotonic_outcomes_and_unbounded_sides() {
        // Fails in [1, 1.6) and above 3: the lowest bracket is (0.5, 1], the later safe scan
        // points above it make the result non-monotonic.
        // Lattice 0.4 (0.1 × 2², 9 points asked over 4 m/s²): the bracket (0.8, 1.2).
        let req = request(0.0, 4.0, 0.1, 9);
        let fails = |p: f64| (1.0..1.6).contains(&p) || p >= 3.0;
        let (r, _) = drive(&req, 2, fails);
        assert!(!r.monotonic);
        let (s, f) = ksect(2.0 * 0.4, 3.0 * 0.4, Lattice::of(&req).levels, fails);
        assert_eq!((r.safe_pga, r.failing_pga), (Some(s), Some(f)));
        assert!(s < 1.0 && 1.0 <= f && f - s <= 0.1, "{r:?}");
        // Never failing: safe at the top, no bracket, only the scan.
        let (r, b) = drive(&req, 2, |_| false);
        assert_eq!((r.safe_pga, r.failing_pga, b.len()), (Some(4.0), None, 1));
        // Failing at the bottom already.
        let (r, _) = drive(&req, 2, |_| true);
        assert_eq!((r.safe_pga, r.failing_pga), (None, Some(0.0)));
    }

    #[test]
    fn the_lowest_change_is_refined_and_the_start_of_the_range_does_not_move_the_answer() {
        // Fails on [3.1, 3.9) (an island 0.8 m/s² wide) and from 6.2 on. Two ranges asking for
        // a resolution of 0.5 (< 0.8) from different starts share the lattice 0.32 = 0.01 × 2⁵:
        // both hold the scan point 3.2 in the island, refine the same bracket (2.88, 3.2) to the
        // tolerance, report the island's top and the main region's start at the resolution,
        // and agree to the bit.
        let fails = |p: f64| (3.1..3.9).contains(&p) || p >= 6.2;
        let (a, _) = drive(&request(0.5, 10.0, 0.01, 20), 2, fails);
        let (b, _) = drive(&request(1.0, 10.0, 0.01, 19), 3, fails);
        let levels = Lattice::of(&request(0.5, 10.0, 0.01, 20)).levels;
        assert_eq!(levels, 4, "0.32 / 3⁴ ≤ 0.01");
        let (s, f) = ksect(9.0 * 0.32, 10.0 * 0.32, levels, fails);
        for r in [&a, &b] {
            assert_eq!(r.resolution, 0.32);
            assert!(!r.monotonic);
            assert_eq!((r.safe_pga, r.failing_pga), (Some(s), Some(f)));
            assert!((3.1..=3.11).contains(&f) && s < 3.1, "{s} {f}");
            assert_eq!(r.failing_intervals.len(), 2, "{:?}", r.failing_intervals);
            let island_top = r.failing_intervals[0][1];
            assert!((3.9 - 0.32..3.9).contains(&island_top), "{island_top}");
            let main = r.failing_intervals[1][0];
            assert!((6.2..6.2 + 0.32).contains(&main), "{main}");
        }
        assert_eq!(bits(&a), bits(&b));
        assert_eq!(a.failing_intervals, b.failing_intervals);
        // A resolution coarser than the island (2.0 asked, lattice 1.28) still holds a point in
        // it (3.84) from both starts; 3.0 asked (lattice 2.56: 2.56, 5.12, 7.68) steps over it
        // from both and finds the main region's start instead. The answer depends on the
        // lattice, which is reported, not on the range.
        let (c, _) = drive(&request(1.0, 9.0, 0.01, 5), 2, fails);
        let (d, _) = drive(&request(1.5, 9.5, 0.01, 5), 2, fails);
        assert_eq!((c.resolution, d.resolution), (1.28, 1.28));
        assert_eq!(bits(&c), bits(&d));
        assert!(c.failing_pga.expect("c") < 3.2);
        let coarse = |min: f64| PgaRequest {
            resolution: Some(3.0),
            ..request(min, 9.0, 0.01, 5)
        };
        let (e, _) = drive(&coarse(1.0), 2, fails);
        let (g, _) = drive(&coarse(0.2), 4, fails);
        assert_eq!(e.resolution, 2.56);
        assert_eq!(bits(&e), bits(&g));
        assert!((6.2..6.21).contains(&e.failing_pga.expect("e")));
    }

    #[test]
    fn a_range_that_starts_failing_refines_where_failure_ends() {
        // A `not:` observation fails (the block stood) from the bottom of the range up to
        // 4.37: the search's lowest change is that upper bound, refined to the tolerance; the
        // failing island above it (7.0–8.0) is reported at the resolution.
        let fails = |p: f64| p < 4.37 || (7.0..8.0).contains(&p);
        let (r, _) = drive(&request(0.0, 10.0, 0.01, 21), 2, fails);
        assert_eq!(r.failing_pga, Some(0.0));
        let first = r.failing_intervals[0][1];
        assert!((4.36..4.37).contains(&first), "{:?}", r.failing_intervals);
        assert_eq!(r.failing_intervals.len(), 2, "{:?}", r.failing_intervals);
        assert!((7.0..7.5).contains(&r.failing_intervals[1][0]));
    }

    /// A result's answer to the bit.
    fn bits(r: &PgaResult) -> (Option<u64>, Option<u64>) {
        (
            r.safe_pga.map(f64::to_bits),
            r.failing_pga.map(f64::to_bits),
        )
    }

    fn lowest(mut req: PgaRequest) -> PgaRequest {
        req.scan = ScanOrder::Lowest;
        req
    }

    #[test]
    fn a_lowest_scan_stops_at_the_first_failing_batch_with_the_full_scans_answer() {
        // Threshold 2.37 on [0, 10] with 11 scan points asked: the lattice is 0.64 (0.01 × 2⁶),
        // 17 points 0..=10.24; the full scan runs all 17; the lowest scan runs 0..=4 · 0.64 in
        // batches of `width` up to the first holding a failing point, then the same refinement.
        let req = request(0.0, 10.0, 0.01, 11);
        let at = |k: usize| k as f64 * 0.64;
        let clean = |p: f64| p >= 2.37;
        // Fragmented below the resolution next to the threshold, and failing for good above.
        let fragmented = |p: f64| {
            (2.37..2.41).contains(&p)
                || (2.45..2.47).contains(&p)
                || (2.6..2.9).contains(&p)
                || p >= 2.95
        };
        let cases: [(&str, &dyn Fn(f64) -> bool); 2] =
            [("clean", &clean), ("fragmented", &fragmented)];
        for (name, fails) in cases {
            for width in [1, 2, 3, 4, 8] {
                let (full, _) = drive(&req, width, fails);
                let (low, batches) = drive(&lowest(req.clone()), width, fails);
                let why = format!("{name}, width {width}");
                assert_eq!(bits(&full), bits(&low), "{why}: {full:?} {low:?}");
                // Ascending batches of `width` up to the first holding a failing point (2.56,
                // the 5th, for the clean threshold; 3.2 for the fragmented one, whose islands
                // all lie between lattice points): points 0..stop, then the refinement.
                let first = (0..17).position(|k| fails(at(k))).expect("fails");
                assert_eq!(first, if name == "clean" { 4 } else { 5 });
                let stop = ((first / width + 1) * width).min(17);
                let scan: Vec<f64> = batches[..stop.div_ceil(width)]
                    .iter()
                    .flatten()
                    .copied()
                    .collect();
                assert_eq!(scan, (0..stop).map(at).collect::<Vec<_>>(), "{why}");
                // What the answer reads stops at the first failing point whatever the width:
                // the rest of its batch is in `runs` only.
                assert_eq!(low.scanned_to, Some(at(first)), "{why}");
                assert_eq!(full.scanned_to, Some(at(16)));
                assert_eq!(
                    full.runs.len() - low.runs.len(),
                    17 - stop,
                    "{why}: the refinement is shared"
                );
                assert_eq!(low.scan, ScanOrder::Lowest, "{why}");
                assert!(
                    !low.monotonic,
                    "{why}: nothing above the first failure was read"
                );
                let (one, _) = drive(&lowest(req.clone()), 1, fails);
                assert_eq!(
                    (
                        &low.failing_intervals,
                        low.scanned_to,
                        low.monotonic,
                        low.scan
                    ),
                    (
                        &one.failing_intervals,
                        one.scanned_to,
                        one.monotonic,
                        one.scan
                    ),
                    "{why}: the lowest scan's result against one core's"
                );
                assert_eq!(full.scan, ScanOrder::Full);
            }
        }
        // A range that starts failing (a `not:` criterion) is scanned in full: the same search.
        let not = |p: f64| p < 4.37;
        let (full, _) = drive(&req, 2, not);
        let (low, _) = drive(&lowest(req.clone()), 2, not);
        assert_eq!(full, low);
        // Never failing: every point run, reported as a full scan.
        let (full, _) = drive(&req, 2, |_| false);
        let (low, _) = drive(&lowest(req.clone()), 2, |_| false);
        assert_eq!(full, low);
        // The lowest scan is a pure planner too: any subset of its outcomes known replays to
        // the missing part of the same batch (as `replay_after_partial_results...` shows for
        // the full scan), and the records' planner gives each record's own search.
        let (_, batches) = drive(&lowest(req.clone()), 2, clean);
        let all: Vec<f64> = batches.iter().flatten().copied().collect();
        for cut in 0..all.len() {
            let known: std::collections::HashMap<u64, bool> = all[..cut]
                .iter()
                .map(|&p| (p.to_bits(), clean(p)))
                .collect();
            let Step::Pending { batch, done } = plan(&lowest(req.clone()), 2, &|p| {
                known.get(&p.to_bits()).copied()
            }) else {
                panic!("cut {cut}: done too early")
            };
            assert_eq!(done, cut);
            assert_eq!(batch[0].1, all[cut], "cut {cut}");
        }
        let thresholds = [2.37, 6.1];
        let mut known = std::collections::HashMap::new();
        let results = loop {
            match plan_records(2, &lowest(req.clone()), 2, &|i, p| {
                known.get(&(i, p.to_bits())).copied()
            }) {
                Step::Done(r) => break r,
                Step::Pending { batch, .. } => {
                    for (i, p) in batch {
                        known.insert((i, p.to_bits()), p >= thresholds[i]);
                    }
                }
            }
        };
        for (i, r) in results.iter().enumerate() {
            let (single, _) = drive(&lowest(req.clone()), 2, |p| p >= thresholds[i]);
            assert_eq!(r, &single, "record {i} as searched alone");
        }
    }

    /// Seeded random outcome functions fragmented below and above the resolution: 1–6 failing
    /// intervals over [0.3, 11.3], each 0.002–0.05 or up to 11 m/s² wide, and maybe failing
    /// for good above the last.
    fn fragmented(seed: u64) -> impl Fn(f64) -> bool {
        let mut state = seed | 1;
        let mut next = move || {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            (state >> 11) as f64 / (1u64 << 53) as f64
        };
        let k = 1 + (next() * 6.0) as usize;
        let mut edges: Vec<f64> = (0..2 * k).map(|_| 0.3 + next() * 11.0).collect();
        edges.sort_by(f64::total_cmp);
        for pair in edges.chunks_mut(2) {
            if next() < 0.5 {
                pair[1] = pair[0] + 0.002 + next() * 0.05;
            }
        }
        let tail = next() < 0.5;
        let top = edges[2 * k - 1];
        move |p: f64| edges.chunks(2).any(|w| (w[0]..w[1]).contains(&p)) || (tail && p >= top)
    }

    #[test]
    fn a_lowest_scan_gives_the_full_scans_answer() {
        // The lowest change of outcome lies below the lowest scan's stop, so both scans refine
        // the same bracket: the same answer to the bit, for any outcome function and width
        // (before the lattice this held only when nothing changed above the stop).
        for case in 0..400u64 {
            let fails = fragmented(0x2545_f491_4f6c_dd1d ^ (case << 20));
            let width = 1 + (case % 4) as usize;
            let req = request(0.0, 10.0, 0.01, 21);
            let (full, _) = drive(&req, width, &fails);
            let (low, _) = drive(&lowest(req.clone()), width, &fails);
            assert_eq!(bits(&full), bits(&low), "case {case}, width {width}");
            assert!(low.runs.len() <= full.runs.len(), "case {case}");
        }
    }

    /// The property of the search's answer: for outcome functions fragmented below the
    /// resolution, the same `safe_pga`/`failing_pga` to the bit for widths 1, 2, 3, 4, 8, 16
    /// and for ranges that start anywhere below the lowest failing lattice point (and end
    /// anywhere above it), from the full and the lowest scan; `monotonic`, `failing_intervals`,
    /// `scanned_to` and `scan` too, for both scans of the same range. (The planner before the lattice,
    /// given the same resolution as evenly spaced points, failed it: docs/pga.md.)
    fn same_answer_for_any_width_and_range(
        seed: u64,
        resolution: f64,
        starts: [f64; 2],
        top: f64,
    ) -> Result<(), String> {
        let fails = fragmented(seed);
        let req = |min: f64, max: f64| PgaRequest {
            resolution: Some(resolution),
            ..request(min, max, 0.01, 2)
        };
        let run = |req: &PgaRequest, width: usize| {
            let mut known = std::collections::HashMap::new();
            loop {
                match plan(req, width, &|p| known.get(&p.to_bits()).copied()) {
                    Step::Done(r) => return r,
                    Step::Pending { batch, .. } => {
                        for (_, p) in batch {
                            known.insert(p.to_bits(), fails(p));
                        }
                    }
                }
            }
        };
        // The reference: the whole of [0, 12] on one core.
        let reference = run(&req(0.0, 12.0), 1);
        // The lowest failing scan point of the reference: the lowest failing lattice point
        // (the refinement's points lie strictly between lattice points).
        let h = reference.resolution;
        let Some(first) = reference
            .runs
            .iter()
            .filter(|r| r.failed)
            .map(|r| r.pga)
            .find(|p| (p / h - (p / h).round()).abs() < 1e-9)
        else {
            return Ok(()); // never fails on the lattice: nothing to compare
        };
        let widths = [1, 2, 3, 4, 8, 16];
        for (i, &start) in starts.iter().enumerate() {
            let min = start * first;
            let max = first + top * (12.0 - first) + 1e-6;
            for &width in &widths {
                for scan in [ScanOrder::Full, ScanOrder::Lowest] {
                    let r = run(
                        &PgaRequest {
                            scan,
                            ..req(min, max)
                        },
                        width,
                    );
                    if bits(&r) != bits(&reference) {
                        return Err(format!(
                            "range {i} [{min}, {max}], width {width}, {scan:?}: {:?} {:?} against {:?} {:?}",
                            r.safe_pga, r.failing_pga, reference.safe_pga, reference.failing_pga
                        ));
                    }
                }
            }
            for scan in [ScanOrder::Full, ScanOrder::Lowest] {
                let req = PgaRequest {
                    scan,
                    ..req(min, max)
                };
                let one = run(&req, 1);
                for &width in &widths[1..] {
                    let r = run(&req, width);
                    let read = |r: &PgaResult| {
                        (
                            r.monotonic,
                            r.failing_intervals.clone(),
                            r.scanned_to,
                            r.scan,
                        )
                    };
                    if read(&r) != read(&one) {
                        return Err(format!(
                            "range {i}, width {width}, {scan:?}: monotonic, intervals or scan moved"
                        ));
                    }
                }
            }
        }
        Ok(())
    }

    proptest::proptest! {
        #![proptest_config(proptest::prelude::ProptestConfig::with_cases(200))]
        #[test]
        fn the_answer_does_not_depend_on_the_width_or_the_range(
            seed in proptest::prelude::any::<u64>(),
            resolution in 0.05f64..1.5,
            a in 0.0f64..0.999,
            b in 0.0f64..0.999,
            top in 0.0f64..1.0,
        ) {
            let checked = same_answer_for_any_width_and_range(seed, resolution, [a, b], top);
            proptest::prop_assert!(checked.is_ok(), "{}", checked.err().unwrap_or_default());
        }
    }

    #[test]
    fn records_are_planned_side_by_side() {
        let req = request(0.0, 4.0, 0.05, 5);
        let thresholds = [2.37, 0.61];
        let mut known = std::collections::HashMap::new();
        let mut rounds = 0;
        let results = loop {
            match plan_records(2, &req, 2, &|i, p| known.get(&(i, p.to_bits())).copied()) {
                Step::Done(r) => break r,
                Step::Pending { batch, .. } => {
                    rounds += 1;
                    if rounds == 1 {
                        // Both records' scans at once (the lattice 0.8: 6 points each).
                        assert_eq!(batch.len(), 12);
                        assert_eq!(batch.iter().filter(|(i, _)| *i == 1).count(), 6);
                    }
                    for (i, p) in batch {
                        known.insert((i, p.to_bits()), p >= thresholds[i]);
                    }
                }
            }
        };
        // The records' rounds overlap: as many as the longer search alone.
        let mut longest = 0;
        for (i, r) in results.iter().enumerate() {
            let (single, batches) = drive(&req, 2, |p| p >= thresholds[i]);
            assert_eq!(r, &single, "record {i} as searched alone");
            longest = longest.max(batches.len());
        }
        assert_eq!(rounds, longest);
        assert_eq!(rounds, 4, "1 scan + 3 rounds of trisection");
    }

    /// `--fit binary` reads the runs, and the runs evaluated ahead (and a lowest scan's last
    /// batch) come with the number of cores: the fit must read only [`width_free_runs`]. Six
    /// records with fragmented outcome functions, full and lowest scans, widths 1 to 8: the
    /// same curve (median, β, log-likelihood, points) to the bit, both methods. The test also
    /// checks that the raw `runs` do differ between widths 1 and 4, so that it can fail.
    #[test]
    fn the_fragility_fit_does_not_depend_on_the_width() {
        let fit_bits = |f: &Fragility| {
            let pts: Vec<(u64, bool)> = f
                .points
                .iter()
                .map(|p| (p.pga.to_bits(), p.failed))
                .collect();
            (
                f.median.to_bits(),
                f.beta.to_bits(),
                f.log_likelihood.to_bits(),
                f.observations,
                pts,
            )
        };
        for scan in [ScanOrder::Full, ScanOrder::Lowest] {
            let req = PgaRequest {
                scan,
                ..request(0.0, 10.0, 0.01, 21)
            };
            let searched = |width: usize| -> Vec<RecordResult> {
                (0..6u64)
                    .map(|i| RecordResult {
                        motion: format!("record {i}"),
                        result: drive(&req, width, fragmented(0x9e37_79b9_7f4a_7c15 ^ (i << 24))).0,
                    })
                    .collect()
            };
            let one = searched(1);
            let raw = |rs: &[RecordResult]| -> Vec<Vec<PgaRun>> {
                rs.iter().map(|r| r.result.runs.clone()).collect()
            };
            assert_ne!(
                raw(&one),
                raw(&searched(4)),
                "{scan:?}: widths 1 and 4 run the same points"
            );
            for method in [Method::Binary, Method::Interval] {
                let base = multi_result(one.clone(), &req, method);
                let base = base.fragility.as_ref().map(fit_bits);
                assert!(base.is_some(), "{scan:?} {method:?}: no curve");
                for width in [2, 3, 4, 8] {
                    let other = multi_result(searched(width), &req, method);
                    assert_eq!(
                        other.fragility.as_ref().map(fit_bits),
                        base,
                        "{scan:?} {method:?}, width {width} against 1"
                    );
                }
            }
        }
    }

    #[test]
    fn capacity_bounds_come_from_the_bracket() {
        let r = |s: Option<f64>, f: Option<f64>| PgaResult {
            criterion: "toppled:a".into(),
            safe_pga: s,
            failing_pga: f,
            units: "m/s2".into(),
            monotonic: true,
            resolution: 1.0,
            failing_intervals: vec![],
            scan: ScanOrder::Full,
            scanned_to: None,
            runs: vec![],
        };
        assert_eq!(
            capacity(&r(Some(2.0), Some(2.1))),
            Capacity {
                above: Some(2.0),
                at_most: Some(2.1)
            }
        );
        // A safe amplitude of 0 bounds nothing on a log scale; never failing is right-censored.
        assert_eq!(capacity(&r(Some(0.0), Some(0.5))).above, None);
        assert_eq!(capacity(&r(Some(9.0), None)).at_most, None);
    }
}
