//! PEER NGA AT2 reader (docs/format.md §2): four header lines, the fourth either
//! `NPTS=  N, DT=  dt SEC` (NGA-West2, trailing commas allowed) or `N  dt  NPTS, DT` (the older
//! NGA layout); then free-format values in g, any number a line, the last line short.
use super::text::{self, RawRecord, RecordKind};
use super::{MotionError, Units};

const HEADER_HELP: &str = "`NPTS=  N, DT=  dt SEC` or `N  dt  NPTS, DT`";

/// Parse AT2 text. `origin` names the file or JSON field in errors.
pub fn parse(origin: &str, content: &str) -> Result<RawRecord, MotionError> {
    let lines: Vec<(usize, &str)> = text::numbered_lines(content).collect();
    if lines.len() < 4 {
        return Err(MotionError::new(
            origin,
            Some(lines.len().max(1)),
            format!("truncated AT2 header: expected 4 header lines, the 4th {HEADER_HELP}"),
        ));
    }
    let units = header_units(origin, lines[2].1)?;
    let (npts, dt) = npts_dt(origin, lines[3].1)?;
    if npts == 0 {
        return Err(MotionError::new(origin, Some(4), "empty record: NPTS = 0"));
    }
    let mut values = Vec::with_capacity(npts);
    for &(no, line) in &lines[4..] {
        let vals = text::numbers_in_line(origin, no, line)?;
        if values.len() + vals.len() > npts {
            return Err(MotionError::new(
                origin,
                Some(no),
                format!("more values than the header's NPTS = {npts}"),
            ));
        }
        values.extend(vals);
    }
    if values.len() < npts {
        let last = lines.last().map(|l| l.0).unwrap_or(4);
        return Err(MotionError::new(
            origin,
            Some(last),
            format!(
                "truncated record: the header says NPTS = {npts} but the file ends after {} values",
                values.len()
            ),
        ));
    }
    let description = format!("{} {}", lines[1].1.trim(), lines[0].1.trim())
        .trim()
        .to_string();
    let rec = RawRecord {
        dt,
        values,
        units,
        kind: RecordKind::Processed,
        format: "at2",
        description,
    };
    rec.check(origin)?;
    Ok(rec)
}

/// Line 3 says what the series is; refuse velocity and displacement files (VT2, DT2), and read
/// `UNITS OF X` when present (AT2 is in g by definition).
fn header_units(origin: &str, line: &str) -> Result<Units, MotionError> {
    let upper = line.to_ascii_uppercase();
    if upper.contains("VELOCITY") || upper.contains("DISPLACEMENT") {
        return Err(MotionError::new(
            origin,
            Some(3),
            "this is a velocity or displacement series (VT2/DT2); expected an acceleration record",
        ));
    }
    match upper.find("UNITS OF") {
        None => Ok(Units::G),
        Some(i) => {
            let name = upper[i + 8..].split_whitespace().next().unwrap_or("");
            text::parse_units(name).ok_or_else(|| text::unknown_units(origin, Some(3), name))
        }
    }
}

/// Line 4 in either header style.
fn npts_dt(origin: &str, line: &str) -> Result<(usize, f64), MotionError> {
    let upper = line.to_ascii_uppercase();
    let bad = |what: String| MotionError::new(origin, Some(4), what);
    let (n_text, dt_text) =
        if let (Some(n_at), Some(dt_at)) = (upper.find("NPTS="), upper.find("DT=")) {
            (
                field_after(&upper, n_at + 5),
                field_after(&upper, dt_at + 3),
            )
        } else if upper.contains("NPTS") {
            let mut toks = upper
                .split(|c: char| c.is_whitespace() || c == ',')
                .filter(|t| !t.is_empty());
            (
                toks.next().unwrap_or("").to_string(),
                toks.next().unwrap_or("").to_string(),
            )
        } else {
            return Err(bad(format!(
                "expected {HEADER_HELP}, found {:?}",
                line.trim()
            )));
        };
    let npts: usize = n_text.parse().map_err(|_| {
        bad(format!(
            "NPTS must be a whole number, found {n_text:?} (expected {HEADER_HELP})"
        ))
    })?;
    let dt = text::number(origin, 4, &dt_text, "the time step DT in s")?;
    if dt <= 0.0 {
        return Err(bad(format!("DT must be > 0 s, got {dt}")));
    }
    Ok((npts, dt))
}

/// The token after `at`, up to a comma or whitespace.
fn field_after(s: &str, at: usize) -> String {
    s[at..]
        .trim_start()
        .split(|c: char| c.is_whitespace() || c == ',')
        .next()
        .unwrap_or("")
        .to_string()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn both_header_styles() {
        assert_eq!(
            npts_dt("t", "NPTS=   7269, DT=   0.0050 SEC,").expect("new"),
            (7269, 0.005)
        );
        assert_eq!(
            npts_dt("t", "NPTS= 12, DT= .0100 SEC").expect("new"),
            (12, 0.01)
        );
        assert_eq!(
            npts_dt("t", "   4000    0.0050    NPTS, DT").expect("old"),
            (4000, 0.005)
        );
        assert!(npts_dt("t", "4000 0.005").is_err());
        assert!(npts_dt("t", "NPTS= 10, DT= 0.0 SEC").is_err());
    }
}
