//! Shared lexing for the text record formats (AT2, CSV, COSMOS, ESM): Fortran-style numbers,
//! fixed-width fields, unit names, and the checks every parsed record must pass before it
//! becomes a `Sampled` signal.
use super::{MotionError, Units};

/// Whether a record has already been corrected by its provider (which decides the processing
/// that may still be applied: see `process`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize, Default)]
#[serde(rename_all = "snake_case")]
pub enum RecordKind {
    /// Baseline-corrected and filtered by the provider (NGA-West2 AT2, COSMOS V2, ESM processed).
    Processed,
    /// As recorded (COSMOS V1, ESM unprocessed): may be high-pass filtered.
    Raw,
    /// The format does not say (CSV, JSON samples).
    #[default]
    Unknown,
    /// An analytic pulse or sine, integrated exactly.
    Analytic,
}

/// A record as read from a file, before unit conversion and processing.
#[derive(Debug, Clone, PartialEq)]
pub struct RawRecord {
    /// Sample interval, s.
    pub dt: f64,
    /// Acceleration in `units`.
    pub values: Vec<f64>,
    pub units: Units,
    pub kind: RecordKind,
    /// Format name for reports ("at2", "csv", "cosmos-v2", "esm").
    pub format: &'static str,
    /// Free description from the header (station, component), may be empty.
    pub description: String,
}

/// Parse one number the way Fortran writes them: `.1234E-02`, `1.5D+01`, `-3.`, `+2`.
/// Returns `None` for anything else, including `NaN` and infinities spelled out (the caller
/// reports those as non-finite).
pub fn parse_fortran(tok: &str) -> Option<f64> {
    let t = tok.trim();
    if t.is_empty()
        || !t
            .bytes()
            .all(|b| b.is_ascii_digit() || b"+-.eEdD".contains(&b))
    {
        return None;
    }
    if !t.bytes().any(|b| b.is_ascii_digit()) {
        return None;
    }
    t.replace(['D', 'd'], "E").parse::<f64>().ok()
}

/// The error for a token that is not a finite number.
fn bad_number(origin: &str, line: usize, tok: &str, expected: &str) -> MotionError {
    let lower = tok.to_ascii_lowercase();
    let what = if lower.contains("nan") || lower.contains("inf") {
        format!("non-finite value {tok:?}; expected {expected}")
    } else {
        format!("expected {expected}, found {tok:?}")
    };
    MotionError::new(origin, Some(line), what)
}

/// Parse a token as a finite number or explain why not.
pub fn number(origin: &str, line: usize, tok: &str, expected: &str) -> Result<f64, MotionError> {
    match parse_fortran(tok) {
        Some(v) if v.is_finite() => Ok(v),
        _ => Err(bad_number(origin, line, tok, expected)),
    }
}

/// All numbers on a free-format line. Whitespace or commas separate values; values that touch
/// (`-0.00003-0.00004`, as Fortran writes full fields) are split before a sign that does not
/// follow an exponent letter.
pub fn numbers_in_line(origin: &str, line: usize, text: &str) -> Result<Vec<f64>, MotionError> {
    let mut out = Vec::new();
    for tok in text
        .split(|c: char| c.is_whitespace() || c == ',')
        .filter(|t| !t.is_empty())
    {
        if let Some(v) = parse_fortran(tok) {
            if !v.is_finite() {
                return Err(bad_number(origin, line, tok, "a finite number"));
            }
            out.push(v);
            continue;
        }
        for part in split_touching(tok) {
            out.push(number(origin, line, part, "a number")?);
        }
    }
    Ok(out)
}

/// Split `-1.0E-02-3.0E-02` into `-1.0E-02`, `-3.0E-02`.
fn split_touching(tok: &str) -> Vec<&str> {
    let b = tok.as_bytes();
    let mut parts = Vec::new();
    let mut start = 0;
    for i in 1..b.len() {
        if (b[i] == b'-' || b[i] == b'+') && !b"eEdD".contains(&b[i - 1]) {
            parts.push(&tok[start..i]);
            start = i;
        }
    }
    parts.push(&tok[start..]);
    parts
}

/// A Fortran edit descriptor such as `(8F10.5)`, `(5E15.7)`, `(1P6E13.5)`, `(10I8)`: values per
/// line and field width.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct FixedFormat {
    pub per_line: usize,
    pub width: usize,
}

impl FixedFormat {
    /// Find and parse the descriptor after `Format=` (case-insensitive) in a header line.
    pub fn find(line: &str) -> Option<Self> {
        let lower = line.to_ascii_lowercase();
        let at = lower.find("format")?;
        let rest = &lower[at..];
        let open = rest.find('(')?;
        let close = rest[open..].find(')')? + open;
        Self::parse(&rest[open + 1..close])
    }

    /// Parse `8f10.5`, `1p6e13.5`, `10i8` (lower case, no parentheses).
    pub fn parse(spec: &str) -> Option<Self> {
        let spec = spec.trim();
        let spec = match spec.find('p') {
            Some(i) => &spec[i + 1..],
            None => spec,
        };
        let letter = spec.find(|c: char| matches!(c, 'f' | 'e' | 'i' | 'g' | 'd'))?;
        let per_line = if letter == 0 {
            1
        } else {
            spec[..letter].trim().parse().ok()?
        };
        let after = &spec[letter + 1..];
        let wend = after
            .find(|c: char| !c.is_ascii_digit())
            .unwrap_or(after.len());
        let width: usize = after[..wend].parse().ok()?;
        (per_line > 0 && width > 0 && per_line <= 100 && width <= 100)
            .then_some(Self { per_line, width })
    }

    /// Split a data line into its fields (fields may touch; a short last line is allowed).
    pub fn fields<'a>(
        &self,
        origin: &str,
        line: usize,
        text: &'a str,
    ) -> Result<Vec<&'a str>, MotionError> {
        if !text.is_ascii() {
            return Err(MotionError::new(
                origin,
                Some(line),
                "non-ASCII character in a fixed-width data line",
            ));
        }
        let text = text.trim_end();
        let mut out = Vec::new();
        let mut at = 0;
        while at < text.len() && out.len() < self.per_line {
            let end = (at + self.width).min(text.len());
            let field = text[at..end].trim();
            if !field.is_empty() {
                out.push(field);
            }
            at = end;
        }
        if at < text.len() {
            return Err(MotionError::new(
                origin,
                Some(line),
                format!(
                    "more than {} fields of width {} on a data line",
                    self.per_line, self.width
                ),
            ));
        }
        Ok(out)
    }
}

/// Interpret a unit name as written in file headers: `g`, `m/s^2`, `m/s2`, `cm/s^2`,
/// `cm/sec2`, `cm/s/s`, `gal`. `None` when unknown.
pub fn parse_units(text: &str) -> Option<Units> {
    let mut s: String = text
        .to_ascii_lowercase()
        .chars()
        .filter(|c| !c.is_whitespace())
        .collect();
    for (from, to) in [
        ("**2", "2"),
        ("^2", "2"),
        ("²", "2"),
        ("/sec", "/s"),
        ("/s/s", "/s2"),
    ] {
        s = s.replace(from, to);
    }
    match s.as_str() {
        "g" | "gs" | "g's" | "(g)" | "[g]" => Some(Units::G),
        "m/s2" | "(m/s2)" | "[m/s2]" | "ms-2" | "mps2" => Some(Units::MetresPerSecond2),
        "cm/s2" | "(cm/s2)" | "[cm/s2]" | "cms-2" | "gal" | "gals" | "(gal)" | "[gal]" => {
            Some(Units::CentimetresPerSecond2)
        }
        _ => None,
    }
}

/// The error for a unit name nobody recognises.
pub fn unknown_units(origin: &str, line: Option<usize>, text: &str) -> MotionError {
    MotionError::new(
        origin,
        line,
        format!(
            "unknown units {:?}; expected g, m/s2 or cm/s2 (gal)",
            text.trim()
        ),
    )
}

impl RawRecord {
    /// Checks shared by every format: a positive finite time step and at least one sample.
    /// (Finite values and the sample count are checked while parsing, where the line is known.)
    pub fn check(&self, origin: &str) -> Result<(), MotionError> {
        if !(self.dt.is_finite() && self.dt > 0.0) {
            return Err(MotionError::new(
                origin,
                None,
                format!("time step must be > 0 s, got {}", self.dt),
            ));
        }
        if self.values.is_empty() {
            return Err(MotionError::new(
                origin,
                None,
                "empty record: no acceleration samples",
            ));
        }
        if let Some(i) = self.values.iter().position(|v| !v.is_finite()) {
            return Err(MotionError::new(
                origin,
                None,
                format!("sample {i} is not a finite number"),
            ));
        }
        Ok(())
    }
}

/// The lines of a text with 1-based numbers, tolerant of `\r\n`.
pub fn numbered_lines(text: &str) -> impl Iterator<Item = (usize, &str)> {
    text.lines()
        .enumerate()
        .map(|(i, l)| (i + 1, l.trim_end_matches('\r')))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fortran_numbers() {
        assert_eq!(parse_fortran(".1234E-02"), Some(0.1234e-2));
        assert_eq!(parse_fortran("-1.5D+01"), Some(-15.0));
        assert_eq!(parse_fortran("3."), Some(3.0));
        assert_eq!(parse_fortran("NaN"), None);
        assert_eq!(parse_fortran("inf"), None);
        assert_eq!(parse_fortran("E"), None);
    }

    #[test]
    fn touching_values_split_at_signs() {
        let v = numbers_in_line("t", 1, "-0.00003-0.00004 1.0E-02-3.0E-02").expect("parses");
        assert_eq!(v, vec![-0.00003, -0.00004, 1.0e-2, -3.0e-2]);
        let e = numbers_in_line("t", 7, "1.0 NaN").expect_err("NaN rejected");
        assert!(
            e.to_string().contains("line 7") && e.to_string().contains("non-finite"),
            "{e}"
        );
    }

    #[test]
    fn fixed_width_fields_may_touch() {
        let f = FixedFormat::find("  12 acceleration pts, units=cm/s^2 (4),Format=(10F8.5)")
            .expect("format");
        assert_eq!(
            f,
            FixedFormat {
                per_line: 10,
                width: 8
            }
        );
        let fields = f
            .fields("t", 1, "-0.00003-0.00004 0.00001")
            .expect("fields");
        assert_eq!(fields, vec!["-0.00003", "-0.00004", "0.00001"]);
        assert_eq!(
            FixedFormat::parse("1p6e13.5"),
            Some(FixedFormat {
                per_line: 6,
                width: 13
            })
        );
    }

    #[test]
    fn unit_names() {
        assert_eq!(parse_units("cm/s^2"), Some(Units::CentimetresPerSecond2));
        assert_eq!(parse_units("cm/sec2"), Some(Units::CentimetresPerSecond2));
        assert_eq!(parse_units("M/S**2"), Some(Units::MetresPerSecond2));
        assert_eq!(parse_units("G"), Some(Units::G));
        assert_eq!(parse_units("counts"), None);
    }
}
