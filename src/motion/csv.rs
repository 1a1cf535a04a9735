//! Two-column CSV reader (time, acceleration): `#` comment lines and one header line allowed;
//! comma, semicolon, tab or space separated. Units come from the caller, the header's column
//! name (`accel_g`, `acc (cm/s2)`, `a [m/s^2]`) or a `# units: g` comment, and must agree.
use super::text::{self, RawRecord, RecordKind};
use super::{MotionError, Units};

/// Relative deviation from the uniform grid tolerated in the time column: times are often
/// printed with few decimals (0.0024 s steps to 4 decimals are exact, 1/300 s steps are not),
/// while a missing or duplicated sample is a whole step off.
const GRID_TOLERANCE: f64 = 0.05;

/// Parse CSV text. `units` (from JSON or the command line) may be `None` when the file names
/// its units.
pub fn parse(origin: &str, content: &str, units: Option<Units>) -> Result<RawRecord, MotionError> {
    let mut header_units: Option<(Units, usize)> = None;
    let mut header_seen = false;
    let mut sep: Option<char> = None;
    let mut times: Vec<(f64, usize)> = Vec::new();
    let mut values = Vec::new();
    let mut comments = Vec::new();
    for (no, line) in text::numbered_lines(content) {
        let trimmed = line.trim();
        if trimmed.is_empty() {
            continue;
        }
        if let Some(c) = trimmed.strip_prefix('#') {
            if let Some(u) = comment_units(origin, no, c)? {
                header_units = Some((u, no));
            }
            comments.push(c.trim().to_string());
            continue;
        }
        let s = *sep.get_or_insert_with(|| detect_separator(trimmed));
        let fields: Vec<&str> = split(trimmed, s);
        if times.is_empty() && !header_seen && text::parse_fortran(fields[0]).is_none() {
            header_seen = true;
            if let Some(name) = fields.get(1) {
                if let Some(u) = column_units(name) {
                    header_units = Some((u, no));
                }
            }
            continue;
        }
        if fields.len() != 2 {
            return Err(MotionError::new(
                origin,
                Some(no),
                format!(
                    "expected 2 columns (time, acceleration), found {}",
                    fields.len()
                ),
            ));
        }
        times.push((text::number(origin, no, fields[0], "a time in s")?, no));
        values.push(text::number(origin, no, fields[1], "an acceleration")?);
    }
    let units = match (units, header_units) {
        (Some(a), Some((b, no))) if a != b => {
            return Err(MotionError::new(
                origin,
                Some(no),
                format!("units conflict: the file says {} but {} was given", b.name(), a.name()),
            ))
        }
        (Some(a), _) => a,
        (None, Some((b, _))) => b,
        (None, None) => {
            return Err(MotionError::new(
                origin,
                None,
                "unknown units: name them in the header (e.g. `time_s,accel_g`), a `# units: g` comment, or pass them (`--units g|m/s2|cm/s2` on the command line, `\"units\"` in JSON)",
            ))
        }
    };
    let dt = uniform_step(origin, &times)?;
    let t0 = times.first().map(|t| t.0).unwrap_or(0.0);
    let mut description = comments.first().cloned().unwrap_or_default();
    if t0 != 0.0 {
        description.push_str(&format!(" (first sample at t = {t0} s taken as t = 0)"));
    }
    let rec = RawRecord {
        dt,
        values,
        units,
        kind: RecordKind::Unknown,
        format: "csv",
        description,
    };
    rec.check(origin)?;
    Ok(rec)
}

fn detect_separator(line: &str) -> char {
    [',', ';', '\t']
        .into_iter()
        .find(|c| line.contains(*c))
        .unwrap_or(' ')
}

fn split(line: &str, sep: char) -> Vec<&str> {
    if sep == ' ' {
        line.split_whitespace().collect()
    } else {
        line.split(sep).map(str::trim).collect()
    }
}

/// `# units: g` or `# units = cm/s2`.
fn comment_units(origin: &str, no: usize, comment: &str) -> Result<Option<Units>, MotionError> {
    let lower = comment.trim().to_ascii_lowercase();
    let Some(rest) = lower.strip_prefix("units") else {
        return Ok(None);
    };
    let rest = rest.trim_start();
    let Some(name) = rest.strip_prefix(':').or_else(|| rest.strip_prefix('=')) else {
        return Ok(None);
    };
    text::parse_units(name)
        .map(Some)
        .ok_or_else(|| text::unknown_units(origin, Some(no), name))
}

/// Units named in a column header: inside brackets, after the last `_`, or the whole name.
fn column_units(name: &str) -> Option<Units> {
    let inner = name.find(['(', '[']).and_then(|i| {
        name[i + 1..]
            .find([')', ']'])
            .map(|j| &name[i + 1..i + 1 + j])
    });
    let suffix = name.rfind('_').map(|i| &name[i + 1..]);
    [inner, suffix, Some(name)]
        .into_iter()
        .flatten()
        .find_map(text::parse_units)
}

/// The time step of a uniform time column, or an error naming the first line off the grid.
fn uniform_step(origin: &str, times: &[(f64, usize)]) -> Result<f64, MotionError> {
    match times {
        [] => return Err(MotionError::new(origin, None, "empty record: no data rows")),
        [(_, no)] => {
            return Err(MotionError::new(
                origin,
                Some(*no),
                "a single sample: the time step cannot be inferred",
            ))
        }
        _ => {}
    }
    for w in times.windows(2) {
        if w[1].0 <= w[0].0 {
            return Err(MotionError::new(
                origin,
                Some(w[1].1),
                format!(
                    "time must increase: {} s follows {} s (time step ≤ 0)",
                    w[1].0, w[0].0
                ),
            ));
        }
    }
    // Judge each step against the median step (robust to the one gap being looked for), then
    // take the mean step, which averages out the rounding of printed times.
    let mut steps: Vec<f64> = times.windows(2).map(|w| w[1].0 - w[0].0).collect();
    steps.sort_by(f64::total_cmp);
    let median = steps[steps.len() / 2];
    for w in times.windows(2) {
        let step = w[1].0 - w[0].0;
        if (step - median).abs() > GRID_TOLERANCE * median {
            return Err(MotionError::new(
                origin,
                Some(w[1].1),
                format!(
                    "non-uniform time column: expected t = {:.6} s (the step is {} s elsewhere), found {} s",
                    w[0].0 + median,
                    crate::quantity::sig(median),
                    w[1].0
                ),
            ));
        }
    }
    let dt = (times[times.len() - 1].0 - times[0].0) / (times.len() - 1) as f64;
    Ok(dt)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn units_from_column_names() {
        assert_eq!(column_units("accel_g"), Some(Units::G));
        assert_eq!(
            column_units("acc (cm/s2)"),
            Some(Units::CentimetresPerSecond2)
        );
        assert_eq!(column_units("a [m/s^2]"), Some(Units::MetresPerSecond2));
        assert_eq!(column_units("acceleration"), None);
    }
}
