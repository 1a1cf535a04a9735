//! `drum-column` and `colonnade`: Doric-like columns of drums with an echinus and an abacus,
//! alone or in a row carrying architrave blocks.
use super::common::*;
use super::{Param, TemplateError, Values};
use crate::scene::spec::{BlockSpec, SceneSpec};

/// The column's parameters (shared by `colonnade`). Defaults: a seven-drum Doric column 6.2 m
/// tall (shaft 5.6 m, lower diameter 1.0 m tapering to 0.8 m, echinus 0.4 m, abacus 0.2 m),
/// proportions of a small Greek temple's peristyle.
fn shaft_params() -> Vec<Param> {
    vec![
        integer("drums", "number of drums in the shaft", 7, 1, 30),
        number(
            "shaft_height",
            "m",
            "height of the shaft (all drums)",
            5.6,
            0.5,
            30.0,
        ),
        number(
            "lower_diameter",
            "m",
            "shaft diameter at its foot",
            1.0,
            0.1,
            5.0,
        ),
        number(
            "upper_diameter",
            "m",
            "shaft diameter at its top (taper)",
            0.8,
            0.1,
            5.0,
        ),
        number(
            "capital_height",
            "m",
            "height of the echinus (0: none)",
            0.4,
            0.0,
            3.0,
        ),
        number(
            "abacus_height",
            "m",
            "height of the abacus (0: none)",
            0.2,
            0.0,
            2.0,
        ),
        number(
            "abacus_width",
            "m",
            "width of the abacus; the echinus widens from the shaft's top to it",
            1.2,
            0.1,
            6.0,
        ),
        number(
            "base_height",
            "m",
            "height of a base under the shaft (0: none, as Doric)",
            0.0,
            0.0,
            2.0,
        ),
        number("base_width", "m", "width of the base", 1.3, 0.1, 6.0),
    ]
}

pub fn column_params() -> Vec<Param> {
    let mut p = shaft_params();
    p.push(friction_param());
    p
}

pub fn colonnade_params() -> Vec<Param> {
    let mut p = vec![
        integer("columns", "number of columns", 3, 2, 12),
        number(
            "spacing",
            "m",
            "axis-to-axis distance of the columns",
            2.5,
            0.5,
            20.0,
        ),
        number(
            "architrave_height",
            "m",
            "height of the architrave blocks",
            0.8,
            0.1,
            4.0,
        ),
    ];
    p.extend(shaft_params());
    p.push(friction_param());
    p
}

/// The column's dimensions, m.
#[derive(Debug, Clone, Copy)]
struct Column {
    drums: usize,
    shaft_height: f64,
    lower: f64,
    upper: f64,
    capital: f64,
    abacus: f64,
    abacus_width: f64,
    base: f64,
    base_width: f64,
}

impl Column {
    fn read(v: &Values) -> Result<Self, TemplateError> {
        let c = Column {
            drums: v.count("drums"),
            shaft_height: v.num("shaft_height"),
            lower: v.num("lower_diameter"),
            upper: v.num("upper_diameter"),
            capital: v.num("capital_height"),
            abacus: v.num("abacus_height"),
            abacus_width: v.num("abacus_width"),
            base: v.num("base_height"),
            base_width: v.num("base_width"),
        };
        if c.capital > 0.0 && c.abacus_width < c.upper {
            return Err(TemplateError::geometry(
                "abacus_width",
                format!(
                    "the echinus widens from the shaft's top ({} m) to the abacus, which must not be narrower, got {} m",
                    c.upper, c.abacus_width
                ),
            ));
        }
        Ok(c)
    }

    /// Height from the foot (base included) to the top of the abacus, m.
    fn height(&self) -> f64 {
        self.base + self.shaft_height + self.capital + self.abacus
    }

    /// Width at the top, m: what an architrave rests on.
    fn top_width(&self) -> f64 {
        if self.abacus > 0.0 || self.capital > 0.0 {
            self.abacus_width
        } else {
            self.upper
        }
    }

    /// The column's stones, bottom up, centred on `x`, foot at y = 0, ids prefixed `prefix`.
    fn blocks(&self, x: f64, prefix: &str, material: &str) -> Vec<BlockSpec> {
        let mut out = Vec::new();
        let mut y = 0.0;
        if self.base > 0.0 {
            let h = 0.5 * self.base_width;
            out.push(stone(
                format!("{prefix}base"),
                material,
                rect(x - h, y, x + h, y + self.base),
            ));
            y += self.base;
        }
        let dh = self.shaft_height / self.drums as f64;
        // Linear taper: the half-width at height s above the shaft's foot.
        let half = |s: f64| 0.5 * (self.lower + (self.upper - self.lower) * s / self.shaft_height);
        for k in 0..self.drums {
            let (s0, s1) = (k as f64 * dh, (k + 1) as f64 * dh);
            let (h0, h1) = (half(s0), half(s1));
            out.push(stone(
                format!("{prefix}drum{}", k + 1),
                material,
                vec![
                    [x - h0, y + s0],
                    [x + h0, y + s0],
                    [x + h1, y + s1],
                    [x - h1, y + s1],
                ],
            ));
        }
        y += self.shaft_height;
        if self.capital > 0.0 {
            let (h0, h1) = (0.5 * self.upper, 0.5 * self.abacus_width);
            out.push(stone(
                format!("{prefix}capital"),
                material,
                vec![
                    [x - h0, y],
                    [x + h0, y],
                    [x + h1, y + self.capital],
                    [x - h1, y + self.capital],
                ],
            ));
            y += self.capital;
        }
        if self.abacus > 0.0 {
            let h = 0.5 * self.abacus_width;
            out.push(stone(
                format!("{prefix}abacus"),
                material,
                rect(x - h, y, x + h, y + self.abacus),
            ));
        }
        out
    }
}

pub fn drum_column(v: &Values) -> Result<SceneSpec, TemplateError> {
    let c = Column::read(v)?;
    let mut spec = stone_scene(
        format!(
            "drum column: {} drums, {} m tall",
            c.drums,
            tidy(c.height())
        ),
        MARBLE,
        v.num("friction_angle"),
    );
    let reach = c.lower.max(c.base_width).max(c.abacus_width);
    spec.blocks
        .push(foundation(MARBLE.name, -reach - 0.5, reach + 0.5));
    spec.blocks.extend(c.blocks(0.0, "", MARBLE.name));
    Ok(spec)
}

pub fn colonnade(v: &Values) -> Result<SceneSpec, TemplateError> {
    let c = Column::read(v)?;
    let n = v.count("columns");
    let spacing = v.num("spacing");
    let foot = c.lower.max(if c.base > 0.0 { c.base_width } else { 0.0 });
    let top = c.top_width();
    if spacing <= foot.max(top) {
        return Err(TemplateError::geometry(
            "spacing",
            format!(
                "columns {} m wide at the foot and {} m at the top need an axis spacing above {} m, got {spacing} m",
                foot,
                top,
                foot.max(top)
            ),
        ));
    }
    let mut spec = stone_scene(
        format!(
            "colonnade: {n} columns of {} drums, {} m on centres",
            c.drums, spacing
        ),
        MARBLE,
        v.num("friction_angle"),
    );
    let last = (n - 1) as f64 * spacing;
    let reach = 0.5 * foot.max(top) + 0.5;
    spec.blocks
        .push(foundation(MARBLE.name, -reach, last + reach));
    for i in 0..n {
        spec.blocks
            .extend(c.blocks(i as f64 * spacing, &format!("c{}_", i + 1), MARBLE.name));
    }
    // Architrave blocks jointed over the column axes; the end blocks reach the outer edges of
    // the end abaci.
    let (y0, y1) = (c.height(), c.height() + v.num("architrave_height"));
    for i in 0..n - 1 {
        let x0 = if i == 0 {
            -0.5 * top
        } else {
            i as f64 * spacing
        };
        let x1 = if i == n - 2 {
            last + 0.5 * top
        } else {
            (i + 1) as f64 * spacing
        };
        spec.blocks.push(stone(
            format!("architrave{}", i + 1),
            MARBLE.name,
            rect(x0, y0, x1, y1),
        ));
    }
    Ok(spec)
}

#[cfg(test)]
mod tests {
    use super::super::build;
    use std::collections::BTreeMap;

    #[test]
    fn default_column_is_seven_drums_6_2_m() {
        let (spec, _) = build("drum-column", &BTreeMap::new()).unwrap_or_else(|e| panic!("{e}"));
        let ids: Vec<_> = spec.blocks.iter().map(|b| b.id.as_str()).collect();
        assert_eq!(
            ids,
            [
                "foundation",
                "drum1",
                "drum2",
                "drum3",
                "drum4",
                "drum5",
                "drum6",
                "drum7",
                "capital",
                "abacus"
            ]
        );
        let top = spec
            .blocks
            .iter()
            .flat_map(|b| b.vertices.iter().map(|v| v[1]))
            .fold(0.0, f64::max);
        assert!((top - 6.2).abs() < 1e-9, "{top}");
    }
}
