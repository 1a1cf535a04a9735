//! Damage criteria as users observe them in the field (docs/format.md §3): drums offset, a
//! keystone dropped, a block rotated, a column fallen, a share of a wall displaced, and their
//! combinations. Sits beside `pga` in `analysis`: a criterion reads the final state of the free
//! blocks of a run (its `Tracker` while it runs, or its `Summary` afterwards) and says whether
//! the observed damage is reproduced. JSON syntax: docs/format.md §3 "Damage criteria".
//!
//! Displacements are the blocks' centroid displacements from their start (m, x to the right,
//! y up), rotations the final rotations (rad inside, degrees in the syntax, counter-clockwise
//! positive), as in `summary.json`.
use super::run::{Summary, Tracker};
use crate::scene::{BlockKind, Scene};
use serde::{Deserialize, Serialize};

/// |final rotation| past which a block counts as fallen: the summary's `toppled` (30°).
pub const FALLEN_ROTATION_DEG: f64 = 30.0;

/// One damage criterion (the JSON form is the serde form, tagged by `kind`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case", deny_unknown_fields)]
pub enum Damage {
    /// The horizontal offset between two blocks' centroids changed by at least `metres` (a drum
    /// slid on the one below it): |Δx_A − Δx_B| ≥ metres.
    RelativeSliding { blocks: [String; 2], metres: f64 },
    /// The block's centroid went down by at least `metres` (a dropped keystone): −Δy ≥ metres.
    Drop { block: String, metres: f64 },
    /// The block's final rotation is at least `degrees` either way.
    Rotation { block: String, degrees: f64 },
    /// At least one of `blocks` fell: |final rotation| > 30° (the summary's `toppled`) or, when
    /// `drop` (m) is given, its centroid went down by at least `drop`.
    Fallen {
        blocks: Vec<String>,
        #[serde(default, skip_serializing_if = "Option::is_none")]
        drop: Option<f64>,
    },
    /// At least `fraction` (0–1] of the blocks (those listed, default every free block) ended
    /// displaced by at least `metres`.
    DisplacedFraction {
        metres: f64,
        fraction: f64,
        #[serde(default, skip_serializing_if = "Option::is_none")]
        blocks: Option<Vec<String>>,
    },
    /// Every criterion of `of` holds.
    All { of: Vec<Damage> },
    /// At least one of `of` holds.
    Any { of: Vec<Damage> },
    /// `of` does not hold (an observation that something did *not* happen).
    Not { of: Box<Damage> },
}

/// A criterion that cannot be evaluated on a scene.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum CriterionError {
    #[error("criterion: {0}")]
    Syntax(String),
    #[error("criterion {path}: {message}")]
    Invalid { path: String, message: String },
}

/// The final state of the free blocks: id, centroid displacement [x, y] (m), rotation (rad).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct FinalState {
    pub blocks: Vec<(String, [f64; 2], f64)>,
}

impl FinalState {
    pub fn from_tracker(tr: &Tracker) -> Self {
        Self {
            blocks: tr
                .ids
                .iter()
                .zip(&tr.final_displacement)
                .zip(&tr.final_rotation)
                .map(|((id, d), r)| (id.clone(), *d, *r))
                .collect(),
        }
    }

    pub fn from_summary(s: &Summary) -> Self {
        Self {
            blocks: s
                .blocks
                .iter()
                .map(|b| (b.id.clone(), b.final_displacement, b.final_rotation))
                .collect(),
        }
    }

    fn get(&self, id: &str) -> Option<([f64; 2], f64)> {
        self.blocks
            .iter()
            .find(|(i, _, _)| i == id)
            .map(|(_, d, r)| (*d, *r))
    }
}

impl Damage {
    /// Parse the JSON form.
    pub fn parse(text: &str) -> Result<Self, CriterionError> {
        let de = &mut serde_json::Deserializer::from_str(text);
        serde_path_to_error::deserialize(de).map_err(|e| {
            let path = e.path().to_string();
            CriterionError::Syntax(format!("{path}: {}", e.into_inner()))
        })
    }

    /// The compact JSON form (what `parse` reads).
    pub fn text(&self) -> String {
        serde_json::to_string(self).unwrap_or_default()
    }

    /// Every block the criterion names.
    pub fn blocks(&self) -> Vec<&str> {
        match self {
            Damage::RelativeSliding { blocks, .. } => blocks.iter().map(String::as_str).collect(),
            Damage::Drop { block, .. } | Damage::Rotation { block, .. } => vec![block],
            Damage::Fallen { blocks, .. } => blocks.iter().map(String::as_str).collect(),
            Damage::DisplacedFraction { blocks, .. } => {
                blocks.iter().flatten().map(String::as_str).collect()
            }
            Damage::All { of } | Damage::Any { of } => of.iter().flat_map(Damage::blocks).collect(),
            Damage::Not { of } => of.blocks(),
        }
    }

    /// Check the criterion against the scene: blocks exist and are free, numbers in range.
    pub fn check(&self, scene: &Scene) -> Result<(), CriterionError> {
        self.check_at(scene, "")
    }

    fn check_at(&self, scene: &Scene, path: &str) -> Result<(), CriterionError> {
        let bad = |field: &str, message: String| CriterionError::Invalid {
            path: format!("{path}{}{field}", if path.is_empty() { "" } else { "." }),
            message,
        };
        let positive = |field: &str, x: f64| {
            if x.is_finite() && x > 0.0 {
                Ok(())
            } else {
                Err(bad(field, format!("must be a positive number, got {x}")))
            }
        };
        let free = |field: &str, id: &str| {
            let ok = scene
                .block_index(id)
                .is_some_and(|b| matches!(scene.blocks[b].kind, BlockKind::Free(_)));
            if ok {
                Ok(())
            } else {
                Err(bad(field, format!("no free block with id {id:?}")))
            }
        };
        match self {
            Damage::RelativeSliding { blocks, metres } => {
                free("blocks[0]", &blocks[0])?;
                free("blocks[1]", &blocks[1])?;
                if blocks[0] == blocks[1] {
                    return Err(bad("blocks", "two different blocks are needed".into()));
                }
                positive("metres", *metres)
            }
            Damage::Drop { block, metres } => {
                free("block", block)?;
                positive("metres", *metres)
            }
            Damage::Rotation { block, degrees } => {
                free("block", block)?;
                positive("degrees", *degrees)
            }
            Damage::Fallen { blocks, drop } => {
                if blocks.is_empty() {
                    return Err(bad("blocks", "at least one block is needed".into()));
                }
                for (i, b) in blocks.iter().enumerate() {
                    free(&format!("blocks[{i}]"), b)?;
                }
                drop.map_or(Ok(()), |d| positive("drop", d))
            }
            Damage::DisplacedFraction {
                metres,
                fraction,
                blocks,
            } => {
                positive("metres", *metres)?;
                if !(*fraction > 0.0 && *fraction <= 1.0) {
                    return Err(bad(
                        "fraction",
                        format!("must be in (0, 1], got {fraction}"),
                    ));
                }
                if let Some(bs) = blocks {
                    if bs.is_empty() {
                        return Err(bad("blocks", "an empty list selects nothing".into()));
                    }
                    for (i, b) in bs.iter().enumerate() {
                        free(&format!("blocks[{i}]"), b)?;
                    }
                }
                Ok(())
            }
            Damage::All { of } | Damage::Any { of } => {
                if of.is_empty() {
                    return Err(bad("of", "at least one criterion is needed".into()));
                }
                for (i, d) in of.iter().enumerate() {
                    d.check_at(
                        scene,
                        &format!("{path}{}of[{i}]", if path.is_empty() { "" } else { "." }),
                    )?;
                }
                Ok(())
            }
            Damage::Not { of } => of.check_at(
                scene,
                &format!("{path}{}of", if path.is_empty() { "" } else { "." }),
            ),
        }
    }

    /// Does the final state show the damage? (A block the state does not hold, e.g. one left
    /// out of a summary, shows none; [`Damage::check`] refuses such criteria beforehand.)
    pub fn met(&self, s: &FinalState) -> bool {
        match self {
            Damage::RelativeSliding { blocks, metres } => {
                match (s.get(&blocks[0]), s.get(&blocks[1])) {
                    (Some((a, _)), Some((b, _))) => (a[0] - b[0]).abs() >= *metres,
                    _ => false,
                }
            }
            Damage::Drop { block, metres } => s.get(block).is_some_and(|(d, _)| -d[1] >= *metres),
            Damage::Rotation { block, degrees } => s
                .get(block)
                .is_some_and(|(_, r)| r.abs() >= degrees.to_radians()),
            Damage::Fallen { blocks, drop } => blocks.iter().any(|b| {
                s.get(b).is_some_and(|(d, r)| {
                    r.abs() > FALLEN_ROTATION_DEG.to_radians() || drop.is_some_and(|m| -d[1] >= m)
                })
            }),
            Damage::DisplacedFraction {
                metres,
                fraction,
                blocks,
            } => {
                let selected: Vec<[f64; 2]> = match blocks {
                    Some(bs) => bs.iter().filter_map(|b| s.get(b)).map(|(d, _)| d).collect(),
                    None => s.blocks.iter().map(|(_, d, _)| *d).collect(),
                };
                if selected.is_empty() {
                    return false;
                }
                let moved = selected
                    .iter()
                    .filter(|d| d[0].hypot(d[1]) >= *metres)
                    .count();
                moved as f64 >= fraction * selected.len() as f64
            }
            Damage::All { of } => of.iter().all(|d| d.met(s)),
            Damage::Any { of } => of.iter().any(|d| d.met(s)),
            Damage::Not { of } => !of.met(s),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn state() -> FinalState {
        FinalState {
            blocks: vec![
                ("drum1".into(), [0.01, 0.0], 0.0),
                ("drum2".into(), [0.05, -0.001], 0.02),
                ("key".into(), [0.0, -0.04], 0.0),
                ("top".into(), [0.3, -0.2], 1.2),
            ],
        }
    }

    fn parse(t: &str) -> Damage {
        Damage::parse(t).unwrap_or_else(|e| panic!("{t}: {e}"))
    }

    #[test]
    fn each_criterion_reads_the_final_state() {
        let s = state();
        // Offset 0.04 m between drum2 and drum1.
        assert!(
            parse(r#"{"kind":"relative_sliding","blocks":["drum2","drum1"],"metres":0.03}"#)
                .met(&s)
        );
        assert!(
            !parse(r#"{"kind":"relative_sliding","blocks":["drum2","drum1"],"metres":0.05}"#)
                .met(&s)
        );
        assert!(parse(r#"{"kind":"drop","block":"key","metres":0.04}"#).met(&s));
        assert!(!parse(r#"{"kind":"drop","block":"key","metres":0.041}"#).met(&s));
        // 0.02 rad = 1.146°.
        assert!(parse(r#"{"kind":"rotation","block":"drum2","degrees":1.1}"#).met(&s));
        assert!(!parse(r#"{"kind":"rotation","block":"drum2","degrees":1.2}"#).met(&s));
        assert!(parse(r#"{"kind":"fallen","blocks":["drum1","top"]}"#).met(&s));
        assert!(!parse(r#"{"kind":"fallen","blocks":["drum1","key"]}"#).met(&s));
        assert!(parse(r#"{"kind":"fallen","blocks":["key"],"drop":0.03}"#).met(&s));
        // Displaced ≥ 0.04 m: drum2 (0.05), key (0.04), top: 3 of 4.
        assert!(parse(r#"{"kind":"displaced_fraction","metres":0.04,"fraction":0.75}"#).met(&s));
        assert!(!parse(r#"{"kind":"displaced_fraction","metres":0.04,"fraction":0.8}"#).met(&s));
        assert!(parse(
            r#"{"kind":"displaced_fraction","metres":0.04,"fraction":1,"blocks":["key","top"]}"#
        )
        .met(&s));
    }

    #[test]
    fn combinations() {
        let s = state();
        let fell = r#"{"kind":"fallen","blocks":["top"]}"#;
        let stood = r#"{"kind":"not","of":{"kind":"fallen","blocks":["drum1"]}}"#;
        let no = r#"{"kind":"drop","block":"key","metres":1}"#;
        assert!(parse(&format!(r#"{{"kind":"all","of":[{fell},{stood}]}}"#)).met(&s));
        assert!(!parse(&format!(r#"{{"kind":"all","of":[{fell},{no}]}}"#)).met(&s));
        assert!(parse(&format!(r#"{{"kind":"any","of":[{no},{fell}]}}"#)).met(&s));
        let d = parse(&format!(r#"{{"kind":"any","of":[{no},{stood}]}}"#));
        assert_eq!(Damage::parse(&d.text()), Ok(d));
    }

    #[test]
    fn bad_criteria_name_the_field() {
        let e = Damage::parse(r#"{"kind":"drop","block":"key","meters":1}"#)
            .expect_err("must be refused");
        assert!(e.to_string().contains("meters"), "{e}");
        let e = Damage::parse(r#"{"kind":"tilted","block":"key"}"#).expect_err("must be refused");
        assert!(e.to_string().contains("tilted"), "{e}");
        let (_, scene) = crate::scene::templates::build("drum-column", &Default::default())
            .unwrap_or_else(|e| panic!("{e}"));
        let d = parse(
            r#"{"kind":"any","of":[{"kind":"drop","block":"drum1","metres":0.1},{"kind":"fallen","blocks":["abacus","foundation"]}]}"#,
        );
        let e = d.check(&scene).expect_err("must be refused");
        assert_eq!(
            e.to_string(),
            "criterion of[1].blocks[1]: no free block with id \"foundation\""
        );
        let d = parse(r#"{"kind":"displaced_fraction","metres":0.01,"fraction":1.5}"#);
        assert!(d
            .check(&scene)
            .expect_err("must be refused")
            .to_string()
            .contains("fraction"));
        parse(r#"{"kind":"relative_sliding","blocks":["drum2","drum1"],"metres":0.03}"#)
            .check(&scene)
            .unwrap_or_else(|e| panic!("{e}"));
    }
}
