//! ESM / ITACA ASCII reader: a `KEY: value` header (EVENT_NAME, STATION_CODE, STREAM, NDATA,
//! SAMPLING_INTERVAL_S, UNITS, PROCESSING, LOW_CUT_FREQUENCY_HZ, USER1..5, ...) then the values,
//! one or more a line. The header ends at the first line that is not `KEY: value`.
use super::text::{self, RawRecord, RecordKind};
use super::MotionError;
use std::collections::HashMap;

/// Parse ESM text.
pub fn parse(origin: &str, content: &str) -> Result<RawRecord, MotionError> {
    let lines: Vec<(usize, &str)> = text::numbered_lines(content).collect();
    let mut header: HashMap<String, (String, usize)> = HashMap::new();
    let mut at = 0;
    while let Some(&(no, line)) = lines.get(at) {
        match header_field(line) {
            Some((k, v)) => {
                header.entry(k).or_insert((v, no));
                at += 1;
            }
            None => break,
        }
    }
    let last_header_line = at.max(1);
    let get = |key: &str| -> Result<&(String, usize), MotionError> {
        header.get(key).ok_or_else(|| {
            MotionError::new(
                origin,
                Some(last_header_line),
                format!("missing header field {key}"),
            )
        })
    };
    if let Some((ty, no)) = header.get("DATA_TYPE") {
        if !ty.to_ascii_uppercase().contains("ACCELERATION") {
            return Err(MotionError::new(
                origin,
                Some(*no),
                format!("DATA_TYPE is {ty:?}; expected ACCELERATION"),
            ));
        }
    }
    let (n_text, n_line) = get("NDATA")?;
    let ndata: usize = n_text.trim().parse().map_err(|_| {
        MotionError::new(
            origin,
            Some(*n_line),
            format!("NDATA must be a whole number, found {n_text:?}"),
        )
    })?;
    let (dt_text, dt_line) = get("SAMPLING_INTERVAL_S")?;
    let dt = text::number(origin, *dt_line, dt_text, "SAMPLING_INTERVAL_S in s")?;
    if dt <= 0.0 {
        return Err(MotionError::new(
            origin,
            Some(*dt_line),
            format!("SAMPLING_INTERVAL_S must be > 0 s, got {dt}"),
        ));
    }
    let (u_text, u_line) = get("UNITS")?;
    let units = text::parse_units(u_text)
        .ok_or_else(|| text::unknown_units(origin, Some(*u_line), u_text))?;
    if ndata == 0 {
        return Err(MotionError::new(
            origin,
            Some(*n_line),
            "empty record: NDATA = 0",
        ));
    }
    let mut values = Vec::with_capacity(ndata);
    for &(no, line) in &lines[at..] {
        let vals = text::numbers_in_line(origin, no, line)?;
        if values.len() + vals.len() > ndata {
            return Err(MotionError::new(
                origin,
                Some(no),
                format!("more values than NDATA = {ndata}"),
            ));
        }
        values.extend(vals);
    }
    if values.len() < ndata {
        let last = lines.last().map(|l| l.0).unwrap_or(1);
        return Err(MotionError::new(
            origin,
            Some(last),
            format!(
                "truncated record: NDATA = {ndata} but the file ends after {} values",
                values.len()
            ),
        ));
    }
    let field = |k: &str| header.get(k).map(|v| v.0.trim()).unwrap_or("");
    let description = [field("EVENT_NAME"), field("STATION_CODE"), field("STREAM")]
        .into_iter()
        .filter(|s| !s.is_empty())
        .collect::<Vec<_>>()
        .join(" ");
    let rec = RawRecord {
        dt,
        values,
        units,
        kind: kind(field("PROCESSING"), field("LOW_CUT_FREQUENCY_HZ")),
        format: "esm",
        description,
    };
    rec.check(origin)?;
    Ok(rec)
}

/// `KEY: value` where KEY is upper case letters, digits and `_/^.-`.
fn header_field(line: &str) -> Option<(String, String)> {
    let (k, v) = line.split_once(':')?;
    let k = k.trim();
    let ok = !k.is_empty()
        && k.chars().any(|c| c.is_ascii_uppercase())
        && k.chars()
            .all(|c| c.is_ascii_uppercase() || c.is_ascii_digit() || "_/^.-".contains(c));
    ok.then(|| (k.to_string(), v.trim().to_string()))
}

/// Processed when PROCESSING names a procedure or a low-cut filter was applied.
fn kind(processing: &str, low_cut: &str) -> RecordKind {
    let p = processing.to_ascii_lowercase();
    let named = !p.is_empty()
        && !["none", "unprocessed", "raw", "not processed"]
            .iter()
            .any(|w| p.contains(w));
    if named || text::parse_fortran(low_cut).is_some_and(|f| f > 0.0) {
        RecordKind::Processed
    } else {
        RecordKind::Raw
    }
}
