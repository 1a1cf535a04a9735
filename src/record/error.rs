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
    /// The header or a frame does not describe a recordable run (a caller's bug or a diverged
    /// simulation); the message names the frame, block and field.
    #[error("{}: {message}", path.display())]
    Invalid { path: PathBuf, message: String },
}

impl RecordError {
    pub(crate) fn io(path: &Path, source: std::io::Error) -> Self {
        RecordError::Io {
            path: path.to_path_buf(),
            source,
        }
    }

    pub(crate) fn invalid(path: &Path, message: impl Into<String>) -> Self {
        RecordError::Invalid {
            path: path.to_path_buf(),
            message: message.into(),
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

/// Checks a header before anything is written: ids unique, non-empty and usable as CSV column
/// prefixes, kinds given for every block, history indices in range and not repeated.
pub(crate) fn check_header(header: &RecordHeader) -> Result<(), String> {
    if header.block_ids.len() != header.block_kinds.len() {
        return Err(format!(
            "header: {} block ids but {} block kinds",
            header.block_ids.len(),
            header.block_kinds.len()
        ));
    }
    let mut seen = std::collections::HashSet::new();
    for (i, id) in header.block_ids.iter().enumerate() {
        if id.is_empty() {
            return Err(format!("header: block {i} has an empty id"));
        }
        // A comma, quote or line break would shift the CSV columns (ids are written unquoted,
        // as docs/format.md's `<id>.x` header shows).
        if id.contains([',', '"', '\n', '\r']) {
            return Err(format!(
                "header: block id {id:?} contains a comma, quote or line break (not allowed in \
                 a histories.csv column name)"
            ));
        }
        if !seen.insert(id.as_str()) {
            return Err(format!("header: block id {id:?} appears twice"));
        }
    }
    let mut used = vec![false; header.block_ids.len()];
    for &i in &header.history_blocks {
        match used.get_mut(i) {
            None => {
                return Err(format!(
                    "header: history block index {i} is out of range (the scene has {} blocks)",
                    header.block_ids.len()
                ))
            }
            Some(true) => {
                return Err(format!(
                    "header: history block {:?} is listed twice",
                    header.block_ids[i]
                ))
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
) -> Result<(), String> {
    let at = format!("frame {index} (t = {} s)", frame.time);
    if !frame.time.is_finite() || frame.time < 0.0 {
        return Err(format!("{at}: time must be finite and >= 0"));
    }
    if let Some(prev) = previous_time {
        if frame.time < prev {
            return Err(format!(
                "{at}: time goes backwards (previous frame at t = {prev} s)"
            ));
        }
    }
    if frame.blocks.len() != header.block_ids.len() {
        return Err(format!(
            "{at}: {} blocks, but the header lists {}",
            frame.blocks.len(),
            header.block_ids.len()
        ));
    }
    let g = &frame.ground;
    for (name, v) in [
        ("ground.acceleration", g.acceleration),
        ("ground.velocity", g.velocity),
        ("ground.displacement", g.displacement),
    ] {
        if !(v[0].is_finite() && v[1].is_finite()) {
            return Err(format!("{at}: {name} is not finite ({v:?})"));
        }
    }
    for (b, id) in frame.blocks.iter().zip(&header.block_ids) {
        for (name, v) in [
            ("x", b.x),
            ("y", b.y),
            ("rotation", b.rotation),
            ("vx", b.vx),
            ("vy", b.vy),
            ("angular_velocity", b.angular_velocity),
        ] {
            if !v.is_finite() {
                return Err(format!("{at}: block {id:?}: {name} is not finite ({v})"));
            }
        }
        if need_outline {
            if b.outline.len() < 3 {
                return Err(format!(
                    "{at}: block {id:?}: outline has {} points (at least 3 needed)",
                    b.outline.len()
                ));
            }
            if b.outline
                .iter()
                .any(|p| !(p[0].is_finite() && p[1].is_finite()))
            {
                return Err(format!(
                    "{at}: block {id:?}: outline has a non-finite point"
                ));
            }
        }
    }
    Ok(())
}
