//! Displacement histories of a finished job: read `histories.csv` (header
//! `time_s,<id>.x_m,<id>.y_m,<id>.rotation_rad,...`, or the version-1 header
//! `time,<id>.x,<id>.y,<id>.rotation` of jobs recorded before units were added) and serve it as
//! JSON `{"time": [...], "blocks": {"id": {"x": [...], "y": [...], "rotation": [...]}},
//! "units": {...}}` or as CSV (always the current header), optionally restricted to some blocks.
use serde::Serialize;
use std::collections::BTreeMap;

/// One block's columns.
#[derive(Debug, Clone, Default, PartialEq, Serialize)]
pub struct BlockHistory {
    /// m, centroid displacement from the initial position.
    pub x: Vec<f64>,
    pub y: Vec<f64>,
    /// rad, counter-clockwise positive.
    pub rotation: Vec<f64>,
}

/// The histories of a run, blocks in file order.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Histories {
    pub time: Vec<f64>,
    pub blocks: Vec<(String, BlockHistory)>,
}

#[derive(Serialize)]
struct JsonForm<'a> {
    time: &'a [f64],
    blocks: BTreeMap<&'a str, &'a BlockHistory>,
    units: Units,
}

/// The `units` object of the JSON form.
#[derive(Serialize)]
struct Units {
    time: &'static str,
    x: &'static str,
    y: &'static str,
    rotation: &'static str,
}

const UNITS: Units = Units {
    time: "s",
    x: "m",
    y: "m",
    rotation: "rad",
};

/// Column name suffixes of the two header versions: (time, x, y, rotation).
const HEADER_V2: [&str; 4] = crate::record::histories::HEADER_COLUMNS;
const HEADER_V1: [&str; 4] = ["time", ".x", ".y", ".rotation"];

/// Why a `histories.csv` does not read (the file is ours: a bug or a damaged file), naming the
/// line (1 is the header).
#[derive(Debug, thiserror::Error)]
pub enum HistoriesError {
    #[error("histories.csv is empty")]
    Empty,
    #[error("histories.csv line 1: unexpected header {header:?}")]
    Header { header: String },
    #[error("histories.csv line 1: column {column:?}")]
    Column { column: String },
    #[error("histories.csv line 1: columns of block {id:?} out of order")]
    Order { id: String },
    #[error("histories.csv line {line}: {source}")]
    Number {
        line: usize,
        #[source]
        source: std::num::ParseFloatError,
    },
    #[error("histories.csv line {line}: {values} values, expected {expected}")]
    Count {
        line: usize,
        values: usize,
        expected: usize,
    },
    /// The file could not be read at `line`.
    #[error("histories.csv line {line}: {source}")]
    Read {
        line: usize,
        #[source]
        source: std::io::Error,
    },
    /// A kept field of `line` (its 1-based `column`) is not a number.
    #[error("histories.csv line {line}: column {column} unreadable")]
    Unreadable { line: usize, column: usize },
    /// The kept rows of a JSON answer would not fit the 32-bit offsets they are indexed by.
    #[error("the kept histories exceed 4 GiB")]
    TooLarge,
}

/// A block asked for that the histories do not have.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("no block {id:?} in the histories")]
pub struct UnknownBlock {
    pub id: String,
}

impl Histories {
    /// Parse `histories.csv`. Errors name the line (the file is ours, so an error is a bug or
    /// a damaged file, reported as an internal error).
    pub fn parse_csv(text: &str) -> Result<Self, HistoriesError> {
        let mut lines = text
            .lines()
            .enumerate()
            .filter(|(_, l)| !l.trim().is_empty());
        let (_, header) = lines.next().ok_or(HistoriesError::Empty)?;
        let cols: Vec<&str> = header.split(',').map(str::trim).collect();
        let bad_header = || HistoriesError::Header {
            header: header.to_string(),
        };
        let names = match cols.first() {
            Some(&t) if t == HEADER_V2[0] => HEADER_V2,
            Some(&t) if t == HEADER_V1[0] => HEADER_V1,
            _ => return Err(bad_header()),
        };
        if (cols.len() - 1) % 3 != 0 {
            return Err(bad_header());
        }
        let mut blocks = Vec::new();
        for triple in cols[1..].chunks(3) {
            let id = triple[0]
                .strip_suffix(names[1])
                .ok_or_else(|| HistoriesError::Column {
                    column: triple[0].to_string(),
                })?;
            if triple[1] != format!("{id}{}", names[2]) || triple[2] != format!("{id}{}", names[3])
            {
                return Err(HistoriesError::Order { id: id.to_string() });
            }
            blocks.push((id.to_string(), BlockHistory::default()));
        }
        let mut time = Vec::new();
        for (n, line) in lines {
            let vals: Result<Vec<f64>, _> =
                line.split(',').map(|v| v.trim().parse::<f64>()).collect();
            let vals = vals.map_err(|source| HistoriesError::Number {
                line: n + 1,
                source,
            })?;
            if vals.len() != cols.len() {
                return Err(HistoriesError::Count {
                    line: n + 1,
                    values: vals.len(),
                    expected: cols.len(),
                });
            }
            time.push(vals[0]);
            for (k, (_, b)) in blocks.iter_mut().enumerate() {
                b.x.push(vals[1 + 3 * k]);
                b.y.push(vals[2 + 3 * k]);
                b.rotation.push(vals[3 + 3 * k]);
            }
        }
        Ok(Self { time, blocks })
    }

    pub fn block_ids(&self) -> impl Iterator<Item = &str> {
        self.blocks.iter().map(|(id, _)| id.as_str())
    }

    /// Keep only the named blocks, in the order asked. The error names the first unknown one.
    pub fn select(self, ids: &[String]) -> Result<Self, UnknownBlock> {
        if ids.is_empty() {
            return Ok(self);
        }
        let mut by_id: BTreeMap<String, BlockHistory> = self.blocks.into_iter().collect();
        let mut blocks = Vec::new();
        for id in ids {
            if blocks.iter().any(|(b, _): &(String, BlockHistory)| b == id) {
                continue;
            }
            let h = by_id
                .remove(id)
                .ok_or_else(|| UnknownBlock { id: id.clone() })?;
            blocks.push((id.clone(), h));
        }
        Ok(Self {
            time: self.time,
            blocks,
        })
    }

    pub fn to_json(&self) -> serde_json::Value {
        let form = JsonForm {
            time: &self.time,
            blocks: self.blocks.iter().map(|(id, h)| (id.as_str(), h)).collect(),
            units: UNITS,
        };
        serde_json::to_value(form).unwrap_or_default()
    }

    /// Same columns as `histories.csv` (the current header, whatever version was read);
    /// values printed with Rust's shortest round-trip form.
    pub fn to_csv(&self) -> String {
        let mut out = crate::record::histories::header_line(self.block_ids());
        out.push('\n');
        for (i, t) in self.time.iter().enumerate() {
            out.push_str(&t.to_string());
            for (_, h) in &self.blocks {
                out.push_str(&format!(",{},{},{}", h.x[i], h.y[i], h.rotation[i]));
            }
            out.push('\n');
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const CSV: &str = "time_s,col.x_m,col.y_m,col.rotation_rad,top.block.x_m,top.block.y_m,top.block.rotation_rad\n\
                       0,0,0,0,0,0,0\n\
                       0.01,1e-3,-2e-4,0.5,3,4,-0.25\n";
    /// The same file as recorded before units were added (format version 1).
    const CSV_V1: &str =
        "time,col.x,col.y,col.rotation,top.block.x,top.block.y,top.block.rotation\n\
                          0,0,0,0,0,0,0\n\
                          0.01,1e-3,-2e-4,0.5,3,4,-0.25\n";

    #[test]
    fn version_1_files_still_read() {
        let v1 = Histories::parse_csv(CSV_V1).expect("v1");
        assert_eq!(v1, Histories::parse_csv(CSV).expect("v2"));
        assert_eq!(v1.to_csv().lines().next(), CSV.lines().next());
        let mixed = "time_s,a.x,a.y,a.rotation\n0,0,0,0\n";
        assert!(Histories::parse_csv(mixed).is_err());
    }

    #[test]
    fn parses_filters_and_round_trips() {
        let h = Histories::parse_csv(CSV).expect("parse");
        assert_eq!(h.time, vec![0.0, 0.01]);
        assert_eq!(h.block_ids().collect::<Vec<_>>(), vec!["col", "top.block"]);
        assert_eq!(h.blocks[1].1.rotation, vec![0.0, -0.25]);
        // CSV → JSON → CSV keeps every value exactly (shortest round-trip printing).
        let again = Histories::parse_csv(&h.to_csv()).expect("reparse");
        assert_eq!(again, h);
        let only = h.clone().select(&["top.block".into()]).expect("known id");
        assert_eq!(
            only.to_json()["blocks"]["top.block"]["x"],
            serde_json::json!([0.0, 3.0])
        );
        assert_eq!(only.to_json()["units"]["rotation"], "rad");
        assert!(only.to_json()["blocks"].get("col").is_none());
        assert_eq!(
            h.select(&["nope".into()]),
            Err(UnknownBlock { id: "nope".into() })
        );
    }

    #[test]
    fn damaged_files_name_the_line() {
        assert!(Histories::parse_csv("").is_err());
        let e = Histories::parse_csv("time_s,a.x_m,a.y_m,a.rotation_rad\n0,1,2\n")
            .expect_err("short row");
        assert!(e.to_string().contains("line 2"), "{e}");
        let e = Histories::parse_csv("time,a.x,a.y\n").expect_err("bad header");
        assert!(e.to_string().contains("line 1"), "{e}");
    }
}
