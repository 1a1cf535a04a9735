//! Service: why a request body is refused ([`RequestError`]), one variant per cause, each naming
//! the JSON pointer of the member at fault (`/scene/blocks/1/vertices`; `""` for the whole body).
//! Raised by `request` (and its `budget`); free of HTTP types. The HTTP layer turns it into a
//! problem, choosing the problem type per cause (`impl From<RequestError> for ApiError` in
//! `http/problem.rs`); a worker re-reading a stored request shows its text as the job's error.
//! The `Display` text is the problem's `detail`: it starts with the pointer.
use super::budget::{num, GROUND_ACCELERATION};
use super::{MAX_OBSERVATIONS, MAX_RECORDS};
use crate::analysis::criteria::CriterionError;
use crate::analysis::fragility::MethodParseError;
use crate::analysis::pga::{CombineParseError, CriterionParseError, ScanParseError};
use crate::analysis::run::RunError;
use crate::motion::{AccelerationError, MotionError};
use crate::scene::SceneError;

/// Why a request body is refused; see the module's documentation.
#[derive(Debug, thiserror::Error)]
pub enum RequestError {
    // The body as a whole.
    #[error("the request body is empty; expected a JSON object")]
    EmptyBody,
    /// Not JSON (the line and column are serde_json's).
    #[error("invalid JSON at line {}, column {}: {}", .0.line(), .0.column(), .0)]
    Syntax(#[source] serde_json::Error),
    /// The body is not an object; `members` lists what it should hold.
    #[error("the body must be a JSON object {members}")]
    NotAnObject { members: &'static str },
    /// A member is missing, unknown or of the wrong type (serde's message).
    #[error("{}: {source}", shown(pointer))]
    Field {
        pointer: String,
        #[source]
        source: serde_json::Error,
    },

    // What the pre-scan refuses while reading (`budget::prescan`).
    #[error(
        "the body holds more than {limit} JSON values (ashlar serve --max-json-values); \
         send a record as text (\"format\"/\"content\") rather than as a long array"
    )]
    JsonValues { limit: usize },
    #[error("/scene/blocks: more than {limit} blocks, the server's limit (ashlar serve --max-blocks); refused while reading")]
    BlocksWhileReading { limit: usize },
    #[error("/motions: more than {MAX_RECORDS} records exceed the limit per search")]
    RecordsWhileReading,

    // Values outside docs/format.md "Ranges" (`budget::check_ranges`, `check_motion_ranges`).
    /// A physical value outside its range (`min`, `max` in `units`).
    #[error(
        "{pointer}: {} {units} is outside the accepted range {} … {} {units} (docs/format.md, \"Ranges\")",
        num(*.value),
        num(*.min),
        num(*.max)
    )]
    OutOfRange {
        pointer: String,
        value: f64,
        min: f64,
        max: f64,
        units: &'static str,
    },
    /// A ground acceleration `value` given in `units`, outside [`GROUND_ACCELERATION`] (m/s²).
    #[error(
        "{pointer}: {} {units} is outside the accepted range {} … {} m/s² (docs/format.md, \"Ranges\")",
        num(*.value),
        num(GROUND_ACCELERATION.0),
        num(GROUND_ACCELERATION.1)
    )]
    AccelerationOutOfRange {
        pointer: String,
        value: f64,
        units: &'static str,
    },

    // The scene and the motion.
    /// A `base_acceleration` excitation's member, or a `driven_block`'s other than `block`.
    #[error("{pointer}: unknown field for this excitation type")]
    ExcitationField { pointer: String },
    /// The scene reader refused the scene.
    #[error("{pointer}: {}", .source.message)]
    Scene {
        pointer: String,
        #[source]
        source: SceneError,
    },
    /// The motion reader refused the motion (`pointer` is `""` for a motion that is the body).
    #[error(
        "{}{}: {}",
        shown(pointer),
        .source.line.map(|l| format!(" (line {l} of the record)")).unwrap_or_default(),
        .source.message
    )]
    Motion {
        pointer: String,
        #[source]
        source: MotionError,
    },
    /// `choose_model` refused the scene ([`RunError::ModelNotApplicable`]: a forced reduced
    /// model that cannot represent it; any other cause is a bug of the caller).
    #[error("{}", model_detail(.0))]
    Model(#[source] RunError),
    #[error("/scene/control/duration: required when the motion has no length (no record, or a steady sine)")]
    NoDuration,

    // The server's limits (`ashlar serve --max-*`).
    /// Vertices of the block `block` (its index).
    #[error("/scene/blocks/{block}/vertices: {count} vertices exceed the server's limit of {limit} per block")]
    Vertices {
        block: usize,
        count: usize,
        limit: usize,
    },
    /// A pulse of `component` (`horizontal`/`vertical`) longer than the record limit allows
    /// (`limit` cycles, 20 samples a cycle).
    #[error("/motion/{component}/pulse/cycles: {cycles} cycles is longer than the server's record limit allows ({limit} cycles; ashlar serve --max-record-samples)")]
    PulseCycles {
        component: &'static str,
        cycles: f64,
        limit: usize,
    },
    #[error("/scene/blocks: {count} blocks exceed the server's limit of {limit} (ashlar serve --max-blocks)")]
    Blocks { count: usize, limit: usize },
    #[error("/motion: the record has {samples} samples, over the server's limit of {limit} (ashlar serve --max-record-samples)")]
    RecordSamples { samples: usize, limit: usize },
    /// Nominal steps of one run (`duration` and `time_step` in s).
    #[error(
        "/scene/control/duration: {} s at a time step of {} s is {} steps, over the server's limit of {limit} \
         (ashlar serve --max-total-steps); shorten the duration or lengthen control.time_step",
        num(*.duration),
        num(*.time_step),
        num(*.steps)
    )]
    Steps {
        duration: f64,
        time_step: f64,
        steps: f64,
        limit: u64,
    },
    /// Recorded frames of one run (`duration` and `output_interval` in s).
    #[error(
        "/scene/control/output_interval: {} s recorded every {} s is {} frames, over the server's \
         limit of {limit} (ashlar serve --max-total-steps)",
        num(*.duration),
        num(*.output_interval),
        num(*.frames)
    )]
    Frames {
        duration: f64,
        output_interval: f64,
        frames: f64,
        limit: u64,
    },
    /// Blocks × steps of one run.
    #[error(
        "/scene: {blocks} blocks × {steps:.0} steps = {} block-steps, {:.1} times the server's limit of {limit} \
         (ashlar serve --max-block-steps); shorten control.duration, lengthen control.time_step or use fewer blocks",
        num(*.blocks as f64 * *.steps),
        *.blocks as f64 * *.steps / *.limit as f64
    )]
    RunWork {
        blocks: usize,
        steps: f64,
        limit: u64,
    },
    /// Blocks × recorded frames of one run.
    #[error(
        "/scene/control/output_interval: {blocks} blocks × {frames:.0} recorded frames = {} block-frames, {:.1} times \
         the server's limit of {limit} (ashlar serve --max-block-frames); lengthen control.output_interval",
        num(*.blocks as f64 * *.frames),
        *.blocks as f64 * *.frames / *.limit as f64
    )]
    RunOutput {
        blocks: usize,
        frames: f64,
        limit: u64,
    },
    /// Runs × blocks × steps of a search.
    #[error(
        "/scan_points: up to {runs:.0} runs × {blocks} blocks × {steps:.0} steps = {} block-steps, {:.1} times the \
         server's limit of {limit} for a search (ashlar serve --max-search-block-steps); use fewer records or scan \
         points, a coarser tolerance, or a shorter run",
        num(*.runs * *.blocks as f64 * *.steps),
        *.runs * *.blocks as f64 * *.steps / *.limit as f64
    )]
    SearchWork {
        runs: f64,
        blocks: usize,
        steps: f64,
        limit: u64,
    },

    // Criteria.
    #[error("{pointer}: give at least one criterion")]
    NoCriterion { pointer: String },
    /// A criterion's text does not parse.
    #[error("{pointer}: {source}")]
    Criterion {
        pointer: String,
        #[source]
        source: CriterionParseError,
    },
    #[error("{pointer}: a criterion is a string (\"toppled:BLOCK\") or a damage object ({{\"kind\": …}})")]
    CriterionType { pointer: String },
    /// Blocks named by criteria that are not free blocks of the scene: (pointer, block) each,
    /// all of them at once; the problem points at the first.
    #[error(
        "{}: not a free block of the scene ({} in all): {}",
        .missing[0].0,
        .missing.len(),
        .missing.iter().map(|(p, b)| format!("{p}: {b:?}")).collect::<Vec<_>>().join(", ")
    )]
    NotFreeBlocks { missing: Vec<(String, String)> },
    /// A damage criterion that cannot be evaluated on the scene.
    #[error("{pointer}: {source}")]
    Damage {
        pointer: String,
        #[source]
        source: CriterionError,
    },

    // PGA searches and site analyses.
    #[error("/motions: give at least one record")]
    NoRecords,
    #[error("/motions: {count} records exceed the limit of {MAX_RECORDS} per search")]
    TooManyRecords { count: usize },
    /// The `name` of record `index` is not a non-empty string.
    #[error("/motions/{index}/name: must be a non-empty string")]
    RecordName { index: usize },
    #[error("/motions/{index}: a record is required")]
    RecordMissing { index: usize },
    #[error("/motions/{index}/name: {name:?} names an earlier record too")]
    DuplicateRecord { index: usize, name: String },
    /// An error of record `index` of `"motions"`, read by the single-motion parser: its
    /// pointer and text re-pointed from `/motion` to `/motions/{index}`.
    #[error("{}", at_record(&.source.to_string(), *.index))]
    InRecord {
        index: usize,
        #[source]
        source: Box<RequestError>,
    },
    /// A searched motion whose horizontal component (at `pointer`) is missing or zero.
    #[error("{pointer}: a PGA search scales the horizontal component, which is missing or zero")]
    ZeroHorizontal { pointer: String },
    #[error("/motions: give either \"motion\" (one record) or \"motions\" (several), not both")]
    MotionAndMotions,
    #[error(
        "/motion: a PGA search needs a ground motion to scale (or \"motions\": several records)"
    )]
    NoMotion,
    #[error("/{0}")]
    Combine(#[source] CombineParseError),
    #[error("/fit: {0}")]
    Fit(#[source] MethodParseError),
    #[error("/{0}")]
    Scan(#[source] ScanParseError),
    #[error("/fit: a fragility fit needs several records (\"motions\")")]
    FitNeedsRecords,
    /// An amplitude of the searched range (`/range/min`, `/range/max`, `/tolerance`).
    #[error("{pointer}: {source}")]
    Amplitude {
        pointer: String,
        #[source]
        source: AccelerationError,
    },
    /// `range.max` not above `range.min` (both m/s²).
    #[error(
        "/range/max: must be finite and > range.min, got {} m/s² ≤ {} m/s²",
        crate::quantity::sig(*.max),
        crate::quantity::sig(*.min)
    )]
    RangeOrder { min: f64, max: f64 },
    #[error("/tolerance: must be a finite amplitude > 0")]
    Tolerance,
    #[error("/scan_points: must lie in 2..={limit}, got {got}")]
    ScanPoints { got: usize, limit: usize },
    #[error("/resolution: must be a finite amplitude > 0")]
    Resolution,
    /// The scan points a resolution asks for over the range (span / resolution + 1).
    #[error("/resolution: the range needs {got} scan points at this resolution, more than the server's limit of {limit} (max_scan_points): ask for a coarser resolution or a narrower range")]
    ResolutionPoints { got: usize, limit: usize },
    #[error("/resolution: give resolution or scan_points, not both")]
    ResolutionAndScanPoints,
    #[error(
        "/observations: give a non-empty array of {{\"criterion\": …, \"observed\": true|false}}"
    )]
    NoObservations,
    #[error(
        "/observations: {count} observations exceed the limit of {MAX_OBSERVATIONS} per analysis"
    )]
    TooManyObservations { count: usize },
    /// An observation's criterion given as an array (`index` of the observation).
    #[error(
        "/observations/{index}/criterion: an observation is one criterion; combine several with a damage object \
         ({{\"kind\": \"all\" | \"any\", \"of\": […]}}, docs/format.md §3)"
    )]
    ObservationArray { index: usize },
}

impl RequestError {
    /// The JSON pointer of the member at fault (`""`: the whole body). `None` only for a
    /// [`RequestError::Model`] that is not `ModelNotApplicable` (a bug, not the request's).
    pub fn pointer(&self) -> Option<String> {
        use RequestError as E;
        let p = |s: &str| Some(s.to_string());
        match self {
            E::EmptyBody | E::Syntax(_) | E::NotAnObject { .. } | E::JsonValues { .. } => p(""),
            E::Field { pointer, .. }
            | E::OutOfRange { pointer, .. }
            | E::AccelerationOutOfRange { pointer, .. }
            | E::ExcitationField { pointer }
            | E::Scene { pointer, .. }
            | E::Motion { pointer, .. }
            | E::NoCriterion { pointer }
            | E::Criterion { pointer, .. }
            | E::CriterionType { pointer }
            | E::Damage { pointer, .. }
            | E::ZeroHorizontal { pointer }
            | E::Amplitude { pointer, .. } => Some(pointer.clone()),
            E::BlocksWhileReading { .. } | E::Blocks { .. } => p("/scene/blocks"),
            E::RecordsWhileReading
            | E::NoRecords
            | E::TooManyRecords { .. }
            | E::MotionAndMotions => p("/motions"),
            E::Model(RunError::ModelNotApplicable { .. }) => p("/scene/control/model"),
            E::Model(_) => None,
            E::NoDuration | E::Steps { .. } => p("/scene/control/duration"),
            E::Vertices { block, .. } => Some(format!("/scene/blocks/{block}/vertices")),
            E::PulseCycles { component, .. } => Some(format!("/motion/{component}/pulse/cycles")),
            E::RecordSamples { .. } => p("/motion"),
            E::Frames { .. } | E::RunOutput { .. } => p("/scene/control/output_interval"),
            E::RunWork { .. } => p("/scene"),
            E::SearchWork { .. } | E::ScanPoints { .. } => p("/scan_points"),
            E::Resolution | E::ResolutionPoints { .. } | E::ResolutionAndScanPoints => {
                p("/resolution")
            }
            E::NotFreeBlocks { missing } => missing.first().map(|(p, _)| p.clone()),
            E::RecordName { index } | E::DuplicateRecord { index, .. } => {
                Some(format!("/motions/{index}/name"))
            }
            E::RecordMissing { index } => Some(format!("/motions/{index}")),
            E::InRecord { index, source } => source.pointer().map(|p| at_record(&p, *index)),
            E::NoMotion => p("/motion"),
            E::Combine(_) => p("/combine"),
            E::Scan(_) => p("/scan"),
            E::Fit(_) | E::FitNeedsRecords => p("/fit"),
            E::RangeOrder { .. } => p("/range/max"),
            E::Tolerance => p("/tolerance"),
            E::NoObservations | E::TooManyObservations { .. } => p("/observations"),
            E::ObservationArray { index } => Some(format!("/observations/{index}/criterion")),
        }
    }

    /// The cause behind an [`RequestError::InRecord`] (itself otherwise).
    pub fn cause(&self) -> &RequestError {
        match self {
            RequestError::InRecord { source, .. } => source.cause(),
            other => other,
        }
    }
}

/// A pointer as a message shows it: the whole body is `(body)`.
fn shown(pointer: &str) -> &str {
    if pointer.is_empty() {
        "(body)"
    } else {
        pointer
    }
}

/// Text of the single-motion parser re-pointed at record `index` of `"motions"`.
fn at_record(text: &str, index: usize) -> String {
    text.replacen("/motion", &format!("/motions/{index}"), 1)
}

/// The detail of a refused model: `/scene/control/model: <why>` for a model that cannot
/// represent the scene, the run error's text otherwise.
fn model_detail(e: &RunError) -> String {
    let text = e.to_string();
    if !matches!(e, RunError::ModelNotApplicable { .. }) {
        return text;
    }
    let why = text.strip_prefix("control.model: ").unwrap_or(&text);
    format!("/scene/control/model: {why}")
}
