//! `histories.csv` writer: one row a recorded frame, streamed as the run proceeds. Sits in
//! `record`, after `simulation`; the column layout is docs/format.md §3.
use super::error::{check_frame, check_header};
use super::{Frame, RecordError, RecordHeader};
use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};

/// The header line of `histories.csv` (no newline): `time_s`, then `<id>.x_m,<id>.y_m,
/// <id>.rotation_rad` per block. The unit suffixes are format version 2 (`summary.json`
/// `"format": "ashlar.run/2"`); version 1 wrote `time,<id>.x,<id>.y,<id>.rotation`.
pub fn header_line<'a>(ids: impl IntoIterator<Item = &'a str>) -> String {
    let [time, x, y, rotation] = HEADER_COLUMNS;
    let mut line = String::from(time);
    for id in ids {
        line.push_str(&format!(",{id}{x},{id}{y},{id}{rotation}"));
    }
    line
}

/// The time column's name and the suffixes of each block's columns (x, y, rotation) in the
/// current header: written by [`header_line`], read back by the service.
pub const HEADER_COLUMNS: [&str; 4] = ["time_s", ".x_m", ".y_m", ".rotation_rad"];

/// Time as written to outputs, s: rounded to the nanosecond (the MCAP log-time resolution), so
/// that 3000 steps of 1 ms read 3 and not 2.9999999999999925.
pub fn round_time(t: f64) -> f64 {
    if t.is_finite() && t.abs() < 1e9 {
        (t * 1e9).round() / 1e9
    } else {
        t
    }
}

/// Streams [`header_line`] for the header's `history_blocks`, in that order. Values are
/// the frame time (s, [`round_time`]), centroid displacements (m) and rotations (rad,
/// counter-clockwise positive) written with Rust's shortest round-trip formatting, so parsing
/// a cell gives back the exact `f64`. Each row is flushed to the sink, so memory stays constant and a reader sees every
/// finished frame.
pub struct HistoryWriter<W: Write> {
    sink: W,
    /// Named in errors (the file, or what the caller says the sink is).
    path: PathBuf,
    header: RecordHeader,
    rows: u64,
    last_time: Option<f64>,
    line: String,
}

impl HistoryWriter<BufWriter<File>> {
    /// Creates (or truncates) the CSV file at `path` and writes the header line.
    pub fn create(path: &Path, header: &RecordHeader) -> Result<Self, RecordError> {
        check_header(header).map_err(|m| RecordError::invalid(path, m))?;
        let file = File::create(path).map_err(|e| RecordError::io(path, e))?;
        Self::new(BufWriter::new(file), path, header)
    }
}

impl<W: Write> HistoryWriter<W> {
    /// Writes the header line to `sink`; `name` is what errors call the sink.
    pub fn new(
        sink: W,
        name: impl Into<PathBuf>,
        header: &RecordHeader,
    ) -> Result<Self, RecordError> {
        let path = name.into();
        check_header(header).map_err(|m| RecordError::invalid(&path, m))?;
        let mut line = header_line(
            header
                .history_blocks
                .iter()
                .map(|&i| header.block_ids[i].as_str()),
        );
        line.push('\n');
        let mut writer = HistoryWriter {
            sink,
            path,
            header: header.clone(),
            rows: 0,
            last_time: None,
            line,
        };
        writer.write_line()?;
        Ok(writer)
    }

    /// Appends the row of `frame` (every block of the scene, in scene order).
    pub fn write_frame(&mut self, frame: &Frame) -> Result<(), RecordError> {
        check_frame(&self.header, frame, self.rows, self.last_time, false)
            .map_err(|m| RecordError::invalid(&self.path, m))?;
        self.line.clear();
        push_f64(&mut self.line, round_time(frame.time));
        for &i in &self.header.history_blocks {
            let b = &frame.blocks[i];
            for v in [b.x, b.y, b.rotation] {
                self.line.push(',');
                push_f64(&mut self.line, v);
            }
        }
        self.line.push('\n');
        self.write_line()?;
        self.rows += 1;
        self.last_time = Some(frame.time);
        Ok(())
    }

    /// Rows written so far.
    pub fn rows(&self) -> u64 {
        self.rows
    }

    /// Flushes and hands back the sink; the CSV is complete after any number of frames
    /// (a cancelled run gives a valid, shorter file).
    pub fn finish(mut self) -> Result<W, RecordError> {
        self.sink
            .flush()
            .map_err(|e| RecordError::io(&self.path, e))?;
        Ok(self.sink)
    }

    fn write_line(&mut self) -> Result<(), RecordError> {
        self.sink
            .write_all(self.line.as_bytes())
            .and_then(|()| self.sink.flush())
            .map_err(|e| RecordError::io(&self.path, e))
    }
}

/// Shortest decimal that parses back to the same `f64` (Rust's `Display`).
fn push_f64(out: &mut String, v: f64) {
    use std::fmt::Write as _;
    // Writing to a String cannot fail.
    let _ = write!(out, "{v}");
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn display_formatting_round_trips_awkward_values() {
        // Exact equality: the whole point of the formatting is that nothing is lost.
        for v in [
            0.1 + 0.2,
            1e-300,
            -0.0,
            5e-324,
            1.0 / 3.0,
            123456.789e10,
            f64::MAX,
        ] {
            let mut s = String::new();
            push_f64(&mut s, v);
            let back: f64 = s.parse().expect("parses");
            assert_eq!(back.to_bits(), v.to_bits(), "{v} written as {s}");
        }
    }
}
