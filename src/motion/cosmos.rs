//! COSMOS strong-motion format (V1 uncorrected, V2 corrected) reader, first channel's
//! acceleration. Layout (COSMOS Strong-Motion Data Format v1.20):
//! line 1 `Corrected acceleration (Format v01.20 with 13 text lines) ...` gives the number of text
//! header lines; then `N Integer-header values follow on L lines, Format= (10I8)` and its lines;
//! `N Real-header values follow on L lines, Format= (5F15.6)` and its lines; `N Comment line(s)
//! follow`; then `N acceleration pts, approx S secs, units=cm/sec2(04), Format=(8F10.5)` and the
//! values in fixed-width fields that may touch. The sample interval is real-header value 61
//! (0-based), in milliseconds. Anything after the acceleration block (velocity, displacement,
//! further channels) is ignored.
use super::text::{self, FixedFormat, RawRecord, RecordKind};
use super::{MotionError, Units};

/// Real-header index (0-based) of the sample interval in ms.
const DT_MS_INDEX: usize = 61;
/// Integer-header index (0-based) of the units code (4 = cm/s², 2 = g), used only when the
/// data line does not name its units.
const UNITS_CODE_INDEX: usize = 2;

struct Cursor<'a> {
    origin: &'a str,
    lines: Vec<(usize, &'a str)>,
    at: usize,
}

impl<'a> Cursor<'a> {
    fn next(&mut self, expected: &str) -> Result<(usize, &'a str), MotionError> {
        let l = self.lines.get(self.at).copied().ok_or_else(|| {
            MotionError::new(
                self.origin,
                Some(self.lines.last().map(|l| l.0).unwrap_or(1)),
                format!("truncated file: it ends where {expected} was expected"),
            )
        })?;
        self.at += 1;
        Ok(l)
    }
}

/// Parse COSMOS V1/V2 text.
pub fn parse(origin: &str, content: &str) -> Result<RawRecord, MotionError> {
    let mut cur = Cursor {
        origin,
        lines: text::numbered_lines(content).collect(),
        at: 0,
    };
    let (_, first) = cur.next("the first text-header line")?;
    let kind = volume_kind(origin, first)?;
    let ntext = text_line_count(origin, first)?;
    for _ in 1..ntext {
        cur.next("a text-header line")?;
    }
    let ints = block(&mut cur, "integer-header", "Integer-header values follow")?;
    let reals = block(&mut cur, "real-header", "Real-header values follow")?;
    let (cno, cline) = cur.next("the `N Comment line(s) follow` line")?;
    let ncomments = leading_count(origin, cno, cline, "Comment line(s) follow")?;
    for _ in 0..ncomments {
        cur.next("a comment line")?;
    }
    let (dno, dline) = cur.next("the `N acceleration pts, ... units=..., Format=(...)` line")?;
    if !dline.to_ascii_lowercase().contains("acceleration") {
        return Err(MotionError::new(
            origin,
            Some(dno),
            format!(
                "expected the acceleration data line `N acceleration pts, ...`, found {:?}",
                dline.trim()
            ),
        ));
    }
    let npts = leading_count(origin, dno, dline, "acceleration pts")?;
    if npts == 0 {
        return Err(MotionError::new(
            origin,
            Some(dno),
            "empty record: 0 acceleration points",
        ));
    }
    let units = data_units(origin, dno, dline, &ints)?;
    let dt = sample_interval(origin, &reals)?;
    let format = FixedFormat::find(dline);
    let mut values = Vec::with_capacity(npts);
    while values.len() < npts {
        let (no, line) = cur.next(&format!(
            "acceleration value {} of {npts}",
            values.len() + 1
        ))?;
        let before = values.len();
        match format {
            Some(f) => {
                for field in f.fields(origin, no, line)? {
                    values.push(text::number(origin, no, field, "an acceleration value")?);
                }
            }
            None => values.extend(text::numbers_in_line(origin, no, line)?),
        }
        if values.len() == before && !line.trim().is_empty() {
            return Err(MotionError::new(
                origin,
                Some(no),
                "expected acceleration values",
            ));
        }
        if values.len() > npts {
            return Err(MotionError::new(
                origin,
                Some(no),
                format!("more values than the {npts} points announced"),
            ));
        }
    }
    let description = cur
        .lines
        .get(4)
        .map(|l| l.1.trim().to_string())
        .unwrap_or_default();
    let format_name = if kind == RecordKind::Processed {
        "cosmos-v2"
    } else {
        "cosmos-v1"
    };
    let rec = RawRecord {
        dt,
        values,
        units,
        kind,
        format: format_name,
        description,
    };
    rec.check(origin)?;
    Ok(rec)
}

/// V2 (corrected) or V1 (uncorrected) from line 1.
fn volume_kind(origin: &str, first: &str) -> Result<RecordKind, MotionError> {
    let lower = first.to_ascii_lowercase();
    if !lower.contains("acceleration") {
        return Err(MotionError::new(
            origin,
            Some(1),
            format!("expected a COSMOS acceleration volume (`Corrected acceleration ...` or `Uncorrected acceleration ...`), found {:?}", first.trim()),
        ));
    }
    if lower.contains("raw acceleration counts") {
        return Err(MotionError::new(
            origin,
            Some(1),
            "a V0 file of raw counts: convert it to a V1 or V2 volume first",
        ));
    }
    Ok(if lower.contains("uncorrected") || lower.contains("raw") {
        RecordKind::Raw
    } else {
        RecordKind::Processed
    })
}

/// `with 13 text lines` on line 1.
fn text_line_count(origin: &str, first: &str) -> Result<usize, MotionError> {
    let lower = first.to_ascii_lowercase();
    let bad = || {
        MotionError::new(
            origin,
            Some(1),
            "expected `(Format v01.20 with N text lines)` on line 1",
        )
    };
    let end = lower.find("text line").ok_or_else(bad)?;
    let before = lower[..end].trim_end();
    let start = before
        .rfind(|c: char| !c.is_ascii_digit())
        .map(|i| i + 1)
        .unwrap_or(0);
    let n: usize = before[start..].parse().map_err(|_| bad())?;
    if n == 0 || n > 1000 {
        return Err(bad());
    }
    Ok(n)
}

/// The integer at the start of a block line (`100 Integer-header values ...`).
fn leading_count(origin: &str, no: usize, line: &str, what: &str) -> Result<usize, MotionError> {
    let bad = || {
        MotionError::new(
            origin,
            Some(no),
            format!("expected `N {what} ...`, found {:?}", line.trim()),
        )
    };
    if !line
        .to_ascii_lowercase()
        .contains(&what.to_ascii_lowercase()[..what.len().min(12)])
    {
        return Err(bad());
    }
    let n: usize = line
        .split_whitespace()
        .next()
        .ok_or_else(bad)?
        .parse()
        .map_err(|_| bad())?;
    if n > 100_000_000 {
        return Err(bad());
    }
    Ok(n)
}

/// A header block: its announcement line and values, each with its line number.
fn block(cur: &mut Cursor<'_>, name: &str, marker: &str) -> Result<Vec<(f64, usize)>, MotionError> {
    let origin = cur.origin;
    let (no, line) = cur.next(&format!("the {name} line `N {marker} on L lines`"))?;
    let count = leading_count(origin, no, line, marker)?;
    let lower = line.to_ascii_lowercase();
    let nlines: usize = lower
        .find(" on ")
        .and_then(|i| lower[i + 4..].split_whitespace().next())
        .and_then(|t| t.parse().ok())
        .ok_or_else(|| {
            MotionError::new(origin, Some(no), format!("expected `{marker} on L lines`"))
        })?;
    let format = FixedFormat::find(line);
    let mut values = Vec::with_capacity(count);
    for _ in 0..nlines {
        let (vno, vline) = cur.next(&format!("a {name} line"))?;
        let parsed = match format {
            Some(f) => f
                .fields(origin, vno, vline)?
                .into_iter()
                .map(|t| text::number(origin, vno, t, &format!("a {name} value")))
                .collect::<Result<Vec<_>, _>>()?,
            None => text::numbers_in_line(origin, vno, vline)?,
        };
        values.extend(parsed.into_iter().map(|v| (v, vno)));
    }
    if values.len() != count {
        return Err(MotionError::new(
            origin,
            Some(no),
            format!(
                "the {name} announces {count} values on {nlines} lines but holds {}",
                values.len()
            ),
        ));
    }
    Ok(values)
}

/// Units from `units=cm/sec2(04)` on the data line, else the integer-header code.
fn data_units(
    origin: &str,
    no: usize,
    line: &str,
    ints: &[(f64, usize)],
) -> Result<Units, MotionError> {
    let lower = line.to_ascii_lowercase();
    if let Some(i) = lower.find("units=") {
        let rest = &line[i + 6..];
        let name = rest.split(['(', ',']).next().unwrap_or("").trim();
        return text::parse_units(name).ok_or_else(|| text::unknown_units(origin, Some(no), name));
    }
    match ints.get(UNITS_CODE_INDEX) {
        Some(&(c, _)) if c == 4.0 => Ok(Units::CentimetresPerSecond2),
        Some(&(c, _)) if c == 2.0 => Ok(Units::G),
        Some(&(c, l)) => Err(text::unknown_units(origin, Some(l), &format!("code {c}"))),
        None => Err(MotionError::new(
            origin,
            Some(no),
            "unknown units: no `units=` on the data line",
        )),
    }
}

/// Real-header value 61, ms → s.
fn sample_interval(origin: &str, reals: &[(f64, usize)]) -> Result<f64, MotionError> {
    let &(ms, line) = reals.get(DT_MS_INDEX).ok_or_else(|| {
        MotionError::new(
            origin,
            None,
            format!("the real header has no value {DT_MS_INDEX} (sample interval, ms)"),
        )
    })?;
    if !(ms > 0.0) {
        return Err(MotionError::new(
            origin,
            Some(line),
            format!("real-header value {DT_MS_INDEX} (sample interval) must be > 0 ms, got {ms}"),
        ));
    }
    Ok(ms / 1000.0)
}
