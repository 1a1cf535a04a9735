//! Errors of the recording writers (histories CSV, trajectory MCAP), and the checks of the
//! header and frames both writers share. Sits in `record`, after `simulation` in the flow.
use super::{Frame, RecordHeader};
use std::path::{Path, PathBuf};

/// What went wrong while recording; every variant names the file being written.
#[derive(Debug, thiserror::Error)]
pub enum RecordError {
    /// The file could not be created or written.
    #[error("{}: {source}", path.display())]
    Io {
        path: PathBuf,
        #[source]
        source: std::io::Error,
    },
    /// The MCAP library refused a record (the message says which).
    #[error("{}: MCAP: {message}", path.display())]
    Mcap { path: PathBuf, message: String },
    /// The header, a frame or the parameters do not describe a recordable run (a caller's bug
    /// or a diverged simulation); the reason names the frame, block and field.
    #[error("{}: {reason}", path.display())]
    Invalid {
        path: PathBuf,
        #[source]
        reason: InvalidRecord,
    },
}

impl RecordError {
    pub(crate) fn io(path: &Path, source: std::io::Error) -> Self {
        RecordError::Io {
            path: path.to_path_buf(),
            source,
        }
    }

    pub(crate) fn invalid(path: &Path, reason: impl Into<InvalidRecord>) -> Self {
        RecordError::Invalid {
            path: path.to_path_buf(),
            reason: reason.into(),
        }
    }

    /// The file this error is about.
    pub fn path(&self) -> &Path {
        match self {
            RecordError::Io { path, .. }
            | RecordError::Mcap { path, .. }
            | RecordError::Invalid { path, .. } => path,
        }
    }
}

/// Why a header, a frame or the MCAP parameters do not describe a recordable run (a caller's
/// bug or a diverged simulation), naming the frame, block and field.
#[derive(Debug, thiserror::Error)]
pub enum InvalidRecord {
    #[error(transparent)]
    Header(#[from] HeaderError),
    #[error(transparent)]
    Frame(#[from] FrameError),
    #[error(transparent)]
    Params(#[from] super::mcap::McapParamsError),
    #[error(transparent)]
    LogTime(#[from] super::mcap::LogTimeError),
    /// A message could not be encoded as JSON.
    #[error(transparent)]
    Json(#[from] serde_json::Error),
}

/// Why a [`RecordHeader`] cannot be recorded.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum HeaderError {
    #[error("header: {ids} block ids but {kinds} block kinds")]
    KindCount { ids: usize, kinds: usize },
    #[error("header: block {index} has an empty id")]
    EmptyId { index: usize },
    /// A comma, quote or line break would shift the CSV columns (ids are written unquoted,
    /// as docs/format.md's `<id>.x` header shows).
    #[error(
        "header: block id {id:?} contains a comma, quote or line break (not allowed in \
         a histories.csv column name)"
    )]
    IdCharacters { id: String },
    #[error("header: block id {id:?} appears twice")]
    DuplicateId { id: String },
    #[error("header: history block index {index} is out of range (the scene has {blocks} blocks)")]
    HistoryIndex { index: usize, blocks: usize },
    #[error("header: history block {id:?} is listed twice")]
    HistoryTwice { id: String },
}

/// Why a [`Frame`] cannot be recorded: the frame's index and time (s), and what is wrong.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("frame {index} (t = {time} s): {problem}")]
pub struct FrameError {
    pub index: u64,
    pub time: f64,
    pub problem: FrameProblem,
}

/// What is wrong in a frame (see [`FrameError`]).
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum FrameProblem {
    #[error("time must be finite and >= 0")]
    Time,
    /// The previous frame's time (s) is later.
    #[error("time goes backwards (previous frame at t = {previous} s)")]
    Backwards { previous: f64 },
    #[error("{blocks} blocks, but the header lists {listed}")]
    BlockCount { blocks: usize, listed: usize },
    /// A ground value (`ground.acceleration`, …) is not finite.
    #[error("{field} is not finite ({value:?})")]
    Ground {
        field: &'static str,
        value: [f64; 2],
    },
    /// A block's value (`x`, `rotation`, …) is not finite.
    #[error("block {id:?}: {field} is not finite ({value})")]
    Block {
        id: String,
        field: &'static str,
        value: f64,
    },
    #[error("block {id:?}: outline has {points} points (at least 3 needed)")]
    OutlinePoints { id: String, points: usize },
    #[error("block {id:?}: outline has a non-finite point")]
    OutlineNonFinite { id: String },
}

/// Checks a header before anything is written: ids unique, non-empty and usable as CSV column
/// prefixes, kinds given for every block, history indices in range and not repeated.
pub(crate) fn check_header(header: &RecordHeader) -> Result<(), HeaderError> {
    if header.block_ids.len() != header.block_kinds.len() {
        return Err(HeaderError::KindCount {
            ids: header.block_ids.len(),
            kinds: header.block_kinds.len(),
        });
    }
    let mut seen = std::collections::HashSet::new();
    for (i, id) in header.block_ids.iter().enumerate() {
        if id.is_empty() {
            return Err(HeaderError::EmptyId { index: i });
        }
        if id.contains([',', '"', '\n', '\r']) {
            return Err(HeaderError::IdCharacters { id: id.clone() });
        }
        if !seen.insert(id.as_str()) {
            return Err(HeaderError::DuplicateId { id: id.clone() });
        }
    }
    let mut used = vec![false; header.block_ids.len()];
    for &i in &header.history_blocks {
        match used.get_mut(i) {
            None => {
                return Err(HeaderError::HistoryIndex {
                    index: i,
                    blocks: header.block_ids.len(),
                })
            }
            Some(true) => {
                return Err(HeaderError::HistoryTwice {
                    id: header.block_ids[i].clone(),
                })
            }
            Some(flag) => *flag = true,
        }
    }
    Ok(())
}

/// Checks a frame against the header and the previous frame's time (s): a time that is finite,
/// non-negative and not decreasing, one entry a block, finite numbers (serde_json would write
/// NaN as `null` and the CSV `NaN`: silent garbage), and outlines of at least 3 finite points
/// when `need_outline`.
pub(crate) fn check_frame(
    header: &RecordHeader,
    frame: &Frame,
    index: u64,
    previous_time: Option<f64>,
    need_outline: bool,
) -> Result<(), FrameError> {
    let fail = |problem| FrameError {
        index,
        time: frame.time,
        problem,
    };
    if !frame.time.is_finite() || frame.time < 0.0 {
        return Err(fail(FrameProblem::Time));
    }
    if let Some(previous) = previous_time {
        if frame.time < previous {
            return Err(fail(FrameProblem::Backwards { previous }));
        }
    }
    if frame.blocks.len() != header.block_ids.len() {
        return Err(fail(FrameProblem::BlockCount {
            blocks: frame.blocks.len(),
            listed: header.block_ids.len(),
        }));
    }
    let g = &frame.ground;
    for (field, value) in [
        ("ground.acceleration", g.acceleration),
        ("ground.velocity", g.velocity),
        ("ground.displacement", g.displacement),
    ] {
        if !(value[0].is_finite() && value[1].is_finite()) {
            return Err(fail(FrameProblem::Ground { field, value }));
        }
    }
    for (b, id) in frame.blocks.iter().zip(&header.block_ids) {
        for (field, value) in [
            ("x", b.x),
            ("y", b.y),
            ("rotation", b.rotation),
            ("vx", b.vx),
            ("vy", b.vy),
            ("angular_velocity", b.angular_velocity),
        ] {
            if !value.is_finite() {
                return Err(fail(FrameProblem::Block {
                    id: id.clone(),
                    field,
                    value,
                }));
            }
        }
        if need_outline {
            if b.outline.len() < 3 {
                return Err(fail(FrameProblem::OutlinePoints {
                    id: id.clone(),
                    points: b.outline.len(),
                }));
            }
            if b.outline
                .iter()
                .any(|p| !(p[0].is_finite() && p[1].is_finite()))
            {
                return Err(fail(FrameProblem::OutlineNonFinite { id: id.clone() }));
            }
        }
    }
    Ok(())
}
