//! Displacement histories of a finished job: read `histories.csv` (header
//! `time,<id>.x,<id>.y,<id>.rotation,...`, m and rad) and serve it as JSON
//! `{"time": [...], "blocks": {"id": {"x": [...], "y": [...], "rotation": [...]}}}` or as CSV,
//! optionally restricted to some blocks.
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
}

impl Histories {
    /// Parse `histories.csv`. Errors name the line (the file is ours, so an error is a bug or
    /// a damaged file, reported as an internal error).
    pub fn parse_csv(text: &str) -> Result<Self, String> {
        let mut lines = text
            .lines()
            .enumerate()
            .filter(|(_, l)| !l.trim().is_empty());
        let (_, header) = lines.next().ok_or("histories.csv is empty")?;
        let cols: Vec<&str> = header.split(',').map(str::trim).collect();
        if cols.first() != Some(&"time") || (cols.len() - 1) % 3 != 0 {
            return Err(format!(
                "histories.csv line 1: unexpected header {header:?}"
            ));
        }
        let mut blocks = Vec::new();
        for triple in cols[1..].chunks(3) {
            let id = triple[0]
                .strip_suffix(".x")
                .ok_or_else(|| format!("histories.csv line 1: column {:?}", triple[0]))?;
            if triple[1] != format!("{id}.y") || triple[2] != format!("{id}.rotation") {
                return Err(format!(
                    "histories.csv line 1: columns of block {id:?} out of order"
                ));
            }
            blocks.push((id.to_string(), BlockHistory::default()));
        }
        let mut time = Vec::new();
        for (n, line) in lines {
            let vals: Result<Vec<f64>, _> =
                line.split(',').map(|v| v.trim().parse::<f64>()).collect();
            let vals = vals.map_err(|e| format!("histories.csv line {}: {e}", n + 1))?;
            if vals.len() != cols.len() {
                return Err(format!(
                    "histories.csv line {}: {} values, expected {}",
                    n + 1,
                    vals.len(),
                    cols.len()
                ));
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

    /// Keep only the named blocks, in the order asked. `Err(id)` names the first unknown one.
    pub fn select(self, ids: &[String]) -> Result<Self, String> {
        if ids.is_empty() {
            return Ok(self);
        }
        let mut by_id: BTreeMap<String, BlockHistory> = self.blocks.into_iter().collect();
        let mut blocks = Vec::new();
        for id in ids {
            if blocks.iter().any(|(b, _): &(String, BlockHistory)| b == id) {
                continue;
            }
            let h = by_id.remove(id).ok_or_else(|| id.clone())?;
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
        };
        serde_json::to_value(form).unwrap_or_default()
    }

    /// Same columns as `histories.csv`; values printed with Rust's shortest round-trip form.
    pub fn to_csv(&self) -> String {
        let mut out = String::from("time");
        for (id, _) in &self.blocks {
            out.push_str(&format!(",{id}.x,{id}.y,{id}.rotation"));
        }
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

    const CSV: &str = "time,col.x,col.y,col.rotation,top.block.x,top.block.y,top.block.rotation\n\
                       0,0,0,0,0,0,0\n\
                       0.01,1e-3,-2e-4,0.5,3,4,-0.25\n";

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
        assert!(only.to_json()["blocks"].get("col").is_none());
        assert_eq!(h.select(&["nope".into()]), Err("nope".to_string()));
    }

    #[test]
    fn damaged_files_name_the_line() {
        assert!(Histories::parse_csv("").is_err());
        let e = Histories::parse_csv("time,a.x,a.y,a.rotation\n0,1,2\n").expect_err("short row");
        assert!(e.contains("line 2"), "{e}");
        let e = Histories::parse_csv("time,a.x,a.y\n").expect_err("bad header");
        assert!(e.contains("line 1"), "{e}");
    }
}
