//! Presets: the scenes and ground motions shared by the tests, benchmarks, examples, the study
//! and the service's tests (as box2d's shared samples), each written once. They sit beside the
//! inputs (scene, motion): a preset is a scene JSON or a [`GroundMotion`] that then goes through
//! the same parsing and validation as a user's file; where a scene generator builds the same
//! structure (`scene::generate`), the preset is built from it.
//!
//! Units: m, s, degrees for friction angles, m/s² for accelerations (along +x).
use crate::motion::{self, GroundMotion, MotionError, Signal};
use crate::scene::generate::{self, WallParams};
use crate::scene::{parse_scene, BlockModel, Scene, SceneError, SceneSpec};
use serde_json::{json, Value};
use std::path::PathBuf;

/// Gravity of the presets, m/s² (the scenes' `gravity`).
pub const G: f64 = 9.81;

/// A scene JSON with one stone (`stone`: 2500 kg/m³, E = 20 GPa, ν = 0.2) and one dry joint
/// (`j`, friction `friction_deg` degrees, no cohesion or tension); `control` is the scene's
/// `control` object (`{}` or `null` for the defaults).
pub fn scene_json(blocks: Value, friction_deg: f64, control: Value) -> Value {
    let mut v = json!({
        "format": "ashlar.scene/1",
        "gravity": G,
        "materials": { "stone": { "density": 2500.0, "young_modulus": 2.0e10, "poisson_ratio": 0.2 } },
        "joints": { "j": { "friction_angle": friction_deg } },
        "blocks": blocks,
    });
    if !control.is_null() {
        v["control"] = control;
    }
    v
}

/// Corners of the rectangle [x0, x1] × [y0, y1], counter-clockwise.
pub fn rect(x0: f64, y0: f64, x1: f64, y1: f64) -> Value {
    json!([[x0, y0], [x1, y0], [x1, y1], [x0, y1]])
}

/// A free-standing rectangular column on a fixed base 0.5 m deep (blocks `base` and `column`,
/// in the material `stone` of [`scene_json`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Column {
    /// Half-width b, m.
    pub half_width: f64,
    /// Half-height h, m.
    pub half_height: f64,
    /// Friction angle of the joint, degrees.
    pub friction_angle: f64,
    /// Half-width of the base, m (wide enough that the column never rocks off it).
    pub base_half_width: f64,
    /// The column's `block_model` (None: the scene's default).
    pub block_model: Option<BlockModel>,
}

impl Column {
    /// The rocking column of Yagoda-Biran & Hatzor 2015, §3.3: 0.4 × 1.2 m (b = 0.2, h = 0.6,
    /// the reference column of `analysis::reference::HousnerColumn::YAGODA_BIRAN_2015`), rigid, on a 2 m
    /// base; φ = 75° (tan 75° = 3.7 ≫ the friction demand of rocking: it rocks, never slides).
    pub const SEED: Column = Column {
        half_width: 0.2,
        half_height: 0.6,
        friction_angle: 75.0,
        base_half_width: 1.0,
        block_model: Some(BlockModel::Rigid),
    };

    /// The slender column of the PGA-search honesty tests and the hand-over studies: 0.24 ×
    /// 1.6 m (slenderness 0.15 rad, 8.5°), otherwise [`Column::SEED`]; near its threshold its
    /// verdict turns on the impacts, which is what those checks need.
    pub const SLENDER: Column = Column {
        half_width: 0.12,
        half_height: 0.8,
        ..Column::SEED
    };

    /// The same column with another friction angle, degrees.
    pub const fn friction(self, friction_angle: f64) -> Self {
        Column {
            friction_angle,
            ..self
        }
    }

    /// The same column with the scene's default block model (no `block_model` of its own).
    pub const fn default_model(self) -> Self {
        Column {
            block_model: None,
            ..self
        }
    }

    /// The blocks: `base` (fixed) then `column`.
    pub fn blocks(&self) -> Value {
        let (b, h, w) = (self.half_width, self.half_height, self.base_half_width);
        let mut column =
            json!({ "id": "column", "material": "stone", "vertices": rect(-b, 0.0, b, 2.0 * h) });
        if let Some(m) = self.block_model {
            column["block_model"] = serde_json::to_value(m).expect("a block model is a word");
        }
        json!([
            { "id": "base", "material": "stone", "fixed": true, "vertices": rect(-w, -0.5, w, 0.0) },
            column,
        ])
    }

    /// The scene JSON with `control` (see [`scene_json`]).
    pub fn json(&self, control: Value) -> Value {
        scene_json(self.blocks(), self.friction_angle, control)
    }

    /// The parsed scene with `control`.
    pub fn scene(&self, control: Value) -> Result<Scene, SceneError> {
        parse_scene(&self.json(control).to_string())
    }
}

/// The rocking frame of Makris & Vassiliou (2013): two equal free-standing rigid columns
/// (half-width b, half-height h) centred at x = ±`column_offset` on a fixed base 0.5 m deep,
/// carrying a free rigid cap beam that spans their outer faces, its thickness chosen so that
/// its mass is γ × both columns' (blocks `base`, `left`, `right`, `cap`, in the material
/// `stone` of [`scene_json`]). It rocks as one column of slenderness atan(b/h) with Housner's
/// p² scaled by (1 + 2γ)/(1 + 3γ) (tests/engine/multiblock_references/).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RockingFrame {
    /// Half-width b of each column, m.
    pub half_width: f64,
    /// Half-height h of each column, m.
    pub half_height: f64,
    /// Distance of each column's centre from x = 0, m.
    pub column_offset: f64,
    /// Cap mass / total mass of the columns, γ (dimensionless, ≥ 0).
    pub gamma: f64,
    /// Friction angle of every joint, degrees.
    pub friction_angle: f64,
    /// Half-width of the base, m.
    pub base_half_width: f64,
}

impl RockingFrame {
    /// Yagoda-Biran & Hatzor's column (b = 0.2, h = 0.6 m) twice, 1.6 m apart, under a cap as
    /// heavy as both (γ = 1), on a 6 m base; φ = 75° everywhere: no joint slips (the frame's
    /// model has none).
    pub const SEED: RockingFrame = RockingFrame {
        half_width: 0.2,
        half_height: 0.6,
        column_offset: 0.8,
        gamma: 1.0,
        friction_angle: 75.0,
        base_half_width: 3.0,
    };

    /// The same frame with another cap mass ratio γ.
    pub const fn gamma(self, gamma: f64) -> Self {
        RockingFrame { gamma, ..self }
    }

    /// The cap's thickness, m: mass γ × both columns' over the span of their outer faces.
    pub fn cap_thickness(&self) -> f64 {
        let (b, h, x) = (self.half_width, self.half_height, self.column_offset);
        let column_area = 2.0 * (2.0 * b) * (2.0 * h);
        self.gamma * column_area / (2.0 * (x + b))
    }

    /// The blocks: `base` (fixed), `left`, `right`, `cap`, all free blocks rigid.
    pub fn blocks(&self) -> Value {
        let (b, h, x, w) = (
            self.half_width,
            self.half_height,
            self.column_offset,
            self.base_half_width,
        );
        let t = self.cap_thickness();
        json!([
            { "id": "base", "material": "stone", "fixed": true, "vertices": rect(-w, -0.5, w, 0.0) },
            { "id": "left", "material": "stone", "block_model": "rigid", "vertices": rect(-x - b, 0.0, -x + b, 2.0 * h) },
            { "id": "right", "material": "stone", "block_model": "rigid", "vertices": rect(x - b, 0.0, x + b, 2.0 * h) },
            { "id": "cap", "material": "stone", "block_model": "rigid", "vertices": rect(-x - b, 2.0 * h, x + b, 2.0 * h + t) },
        ])
    }

    /// The scene JSON with `control` (see [`scene_json`]).
    pub fn json(&self, control: Value) -> Value {
        scene_json(self.blocks(), self.friction_angle, control)
    }
}

/// A pier: `courses` equal rigid blocks stacked into a column of half-width b and half-height h
/// on a fixed base 0.5 m deep (blocks `base`, `course0` … bottom up, material `stone` of
/// [`scene_json`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Pier {
    /// Half-width b, m.
    pub half_width: f64,
    /// Half-height h of the whole pier, m.
    pub half_height: f64,
    /// Number of blocks.
    pub courses: usize,
    /// Friction angle of every joint, degrees.
    pub friction_angle: f64,
    /// Half-width of the base, m.
    pub base_half_width: f64,
}

impl Pier {
    /// Yagoda-Biran & Hatzor's column (b = 0.2, h = 0.6 m) cut into three 0.4 × 0.4 m blocks,
    /// on a 4 m base; φ = 75° (μ = 3.7): the joints neither slip nor, below tipping, open, so it
    /// moves as the monolithic column (tests/engine/multiblock_references/ checks that).
    pub const SEED: Pier = Pier {
        half_width: 0.2,
        half_height: 0.6,
        courses: 3,
        friction_angle: 75.0,
        base_half_width: 2.0,
    };

    /// The blocks: `base` (fixed), then `course0` … `course{n−1}` bottom up.
    pub fn blocks(&self) -> Value {
        let (b, w) = (self.half_width, self.base_half_width);
        let course = 2.0 * self.half_height / self.courses as f64;
        let mut blocks = vec![
            json!({ "id": "base", "material": "stone", "fixed": true, "vertices": rect(-w, -0.5, w, 0.0) }),
        ];
        for k in 0..self.courses {
            let y = k as f64 * course;
            blocks.push(
                json!({ "id": format!("course{k}"), "material": "stone", "block_model": "rigid",
                                "vertices": rect(-b, y, b, y + course) }),
            );
        }
        Value::Array(blocks)
    }

    /// The scene JSON with `control` (see [`scene_json`]).
    pub fn json(&self, control: Value) -> Value {
        scene_json(self.blocks(), self.friction_angle, control)
    }
}

/// Two blocks stacked on a fixed base: `base` (fixed, [−`base_half_width`, `base_half_width`] ×
/// [−`base_depth`, 0]), `lower` ([−b, b] × [0, `lower_height`]) and `upper` ([−b, b] ×
/// [`lower_height`, `lower_height` + `upper_height`]). The material and the block model are
/// the caller's (the scenes that use it differ there): the two-block rocking stack of
/// tests/engine/stacked_column.rs, the sliding stack of tests/engine/multiblock_references/,
/// the standard case of tests/engine/extremes/.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Stack {
    /// Half-width b of both blocks, m.
    pub half_width: f64,
    /// Height of the lower block, m.
    pub lower_height: f64,
    /// Height of the upper block, m.
    pub upper_height: f64,
    /// Half-width of the base, m.
    pub base_half_width: f64,
    /// Depth of the base below y = 0, m.
    pub base_depth: f64,
}

impl Stack {
    /// The blocks `base`, `lower`, `upper`, all in `material`, the free ones with
    /// `block_model` (`"rigid"`, `"deformable"` or `"auto"`).
    pub fn blocks(&self, material: &str, block_model: &str) -> Value {
        let (b, w, d) = (self.half_width, self.base_half_width, self.base_depth);
        let (y1, y2) = (self.lower_height, self.lower_height + self.upper_height);
        json!([
            { "id": "base", "material": material, "fixed": true, "vertices": rect(-w, -d, w, 0.0) },
            { "id": "lower", "material": material, "block_model": block_model, "vertices": rect(-b, 0.0, b, y1) },
            { "id": "upper", "material": material, "block_model": block_model, "vertices": rect(-b, y1, b, y2) },
        ])
    }
}

/// The engine's test wall: `scene::generate::running_bond_wall` of `courses` courses of
/// `blocks_per_course` stones of [`WallParams::default`] (0.6 × 0.3 m, rigid, 35° dry joints),
/// Δt = 1 ms. The wall of tests/engine/solver_reuse.rs (5 × 8), shaken_wall_settle.rs and
/// examples/shaken_walls.rs (10 × 10, 105 stones), benches/engine.rs and examples/wall_probe.rs
/// (20 × 20), examples/engine_scaling.rs (10 … 80 square).
pub fn wall(courses: usize, blocks_per_course: usize) -> SceneSpec {
    wall_of(&WallParams {
        courses,
        blocks_per_course,
        ..Default::default()
    })
}

/// [`wall`] of any [`WallParams`] (another block model, block size or friction), Δt = 1 ms.
pub fn wall_of(p: &WallParams) -> SceneSpec {
    let mut spec = generate::running_bond_wall(p);
    spec.control.time_step = Some(1e-3);
    spec
}

/// `columns × rows` aligned 0.4 × 0.2 m blocks (`b{row}_{column}`, bottom row 0) in a fixed U
/// (`floor`, `left`, `right`, 1 m thick), frictionless, under `contact_solver: "dual"` at
/// Δt = 1 ms, with the top middle block thrown down at 1 m/s: four corners meet at every
/// interior node (the redundant vertex–vertex contacts of Zheng et al.'s pile).
pub fn aligned_stack(columns: usize, rows: usize) -> Value {
    let (w, h) = (0.4, 0.2);
    let (width, height) = (columns as f64 * w, rows as f64 * h);
    let mut blocks = vec![
        json!({ "id": "floor", "material": "stone", "fixed": true, "vertices": rect(-1.0, -1.0, width + 1.0, 0.0) }),
        json!({ "id": "left", "material": "stone", "fixed": true, "vertices": rect(-1.0, 0.0, 0.0, height + 1.0) }),
        json!({ "id": "right", "material": "stone", "fixed": true, "vertices": rect(width, 0.0, width + 1.0, height + 1.0) }),
    ];
    for r in 0..rows {
        for c in 0..columns {
            let (x0, y0) = (c as f64 * w, r as f64 * h);
            blocks.push(json!({ "id": format!("b{r}_{c}"), "material": "stone",
                                "vertices": rect(x0, y0, x0 + w, y0 + h) }));
        }
    }
    let mut v = scene_json(
        json!(blocks),
        0.0,
        json!({ "time_step": 1e-3, "contact_solver": "dual", "duration": 1.0 }),
    );
    v["initial"] =
        json!([{ "block": format!("b{}_{}", rows - 1, columns / 2), "velocity": [0.0, -1.0] }]);
    v
}

/// [`aligned_stack`]'s U, control and thrown block with its courses in running bond: every
/// odd course (`r` = 1, 3, …) starts and ends with a half block (0.2 × 0.2 m), so that its
/// head joints fall on the middle of the blocks below (`b{row}_{column}`, columns counted
/// from the left in each course). A stack whose contacts are not all vertex–vertex: the
/// impulse solve's joined landings of tests/regression/regression_impact_cluster_size.rs and
/// examples/impact_landing.rs (`--bond`).
pub fn running_bond_stack(columns: usize, rows: usize) -> Value {
    let (w, h) = (0.4, 0.2);
    let width = columns as f64 * w;
    let mut v = aligned_stack(columns, rows);
    let blocks = v["blocks"]
        .as_array_mut()
        .expect("aligned_stack has blocks");
    blocks.retain(|b| b.get("fixed").is_some());
    for r in 0..rows {
        let y0 = r as f64 * h;
        let mut edges = vec![0.0];
        let mut x = if r % 2 == 1 { 0.5 * w } else { w };
        while x < width - 1e-9 {
            edges.push(x);
            x += w;
        }
        edges.push(width);
        for (c, e) in edges.windows(2).enumerate() {
            blocks.push(json!({ "id": format!("b{r}_{c}"), "material": "stone",
                                "vertices": rect(e[0], y0, e[1], y0 + h) }));
        }
    }
    v
}

/// A landing on a stack: [`aligned_stack`] (or, with `bond`, [`running_bond_stack`]) of
/// `columns × rows` rigid blocks, φ = 30°, `contact_solver: "penalty"`, its blocks at rest,
/// and a rigid 0.4 × 0.2 m `lander` (last in `blocks`) with its bottom `drop` m above the top
/// middle block, thrown down at 1 m/s: the scene of `examples/impact_landing.rs` and of the
/// impact cluster's regression test.
pub fn stack_with_lander(columns: usize, rows: usize, bond: bool, drop: f64) -> Value {
    let (w, h) = (0.4, 0.2);
    let mut v = if bond {
        running_bond_stack(columns, rows)
    } else {
        aligned_stack(columns, rows)
    };
    let blocks = v["blocks"]
        .as_array_mut()
        .expect("aligned_stack has blocks");
    for b in blocks.iter_mut().filter(|b| b.get("fixed").is_none()) {
        b["block_model"] = json!("rigid");
    }
    let (x0, top) = ((columns / 2) as f64 * w, rows as f64 * h);
    blocks.push(
        json!({ "id": "lander", "material": "stone", "block_model": "rigid",
                        "vertices": rect(x0, top + drop, x0 + w, top + drop + h) }),
    );
    v["joints"]["j"]["friction_angle"] = json!(30.0);
    v["control"]["contact_solver"] = json!("penalty");
    v["initial"] = json!([{ "block": "lander", "velocity": [0.0, -1.0] }]);
    v
}

/// `examples/column.json`, the repository's example column (0.4 × 1.2 m, rigid, φ = 40°, on a
/// 2 m plinth, Δt = 1 ms), as the file's text: the file is the preset, so the golden digests
/// (tests/record) and every test that runs "the example column" read the same bytes.
pub const EXAMPLE_COLUMN: &str = include_str!("../examples/column.json");

/// [`EXAMPLE_COLUMN`] as JSON.
pub fn example_column() -> Value {
    serde_json::from_str(EXAMPLE_COLUMN).expect("examples/column.json is JSON")
}

/// The column of `scene::generate::column` (plinth, limestone, joint `dry`), with the service's
/// examples' φ = 40° and `duration` s of simulation: the job the service's tests and the load
/// test submit. Its column has the default block model.
pub fn plinth_column_json(duration: f64) -> Value {
    let mut spec = generate::column(0.2, 0.6, 40.0);
    spec.blocks[1].block_model = None;
    spec.name = Some("column on a plinth".into());
    let mut v = without_nulls(serde_json::to_value(&spec).expect("a scene spec is JSON"));
    v["control"] = json!({ "duration": duration });
    v
}

/// A block (1 × 0.5 m) resting on an incline of `alpha_deg` that descends towards +x, its
/// bottom-left corner at the origin, on a fixed 400 m base: the blocks `base` and `block`, and
/// the unit down-slope direction.
pub fn incline_blocks(alpha_deg: f64) -> (Value, [f64; 2]) {
    let a = alpha_deg.to_radians();
    let d = [a.cos(), -a.sin()];
    let n = [a.sin(), a.cos()];
    let (w, h, l) = (1.0, 0.5, 200.0);
    let base = json!([
        [-l * d[0], -l * d[1]],
        [l * d[0], l * d[1]],
        [l * d[0], l * d[1] - 20.0],
        [-l * d[0], -l * d[1] - 20.0]
    ]);
    let block = json!([
        [0.0, 0.0],
        [w * d[0], w * d[1]],
        [w * d[0] + h * n[0], w * d[1] + h * n[1]],
        [h * n[0], h * n[1]]
    ]);
    let blocks = json!([
        { "id": "base", "material": "stone", "fixed": true, "vertices": base },
        { "id": "block", "material": "stone", "vertices": block },
    ]);
    (blocks, d)
}

/// The incline of [`incline_blocks`] as a scene JSON (friction `friction_deg`, `control`), and
/// the down-slope direction.
pub fn incline(alpha_deg: f64, friction_deg: f64, control: Value) -> (Value, [f64; 2]) {
    let (blocks, d) = incline_blocks(alpha_deg);
    (scene_json(blocks, friction_deg, control), d)
}

/// The study's masonry wall: 3 courses of two 0.6 × 0.3 m deformable blocks, φ = 35° (also the
/// scene of `tests/engine/dual_stiff_limit.rs` and `examples/wall_stiff_limit.rs`).
pub fn study_wall() -> WallParams {
    WallParams {
        courses: 3,
        blocks_per_course: 2,
        block_length: 0.6,
        block_height: 0.3,
        friction_angle: 35.0,
        block_model: BlockModel::Deformable,
    }
}

/// The study's masonry wall ([`study_wall`]) as scene JSON, without `control` of its own
/// beyond the generator's (callers set it): the scene of the study's wall bench,
/// tests/engine/dual_stiff_limit.rs and examples/wall_stiff_limit.rs.
pub fn study_wall_json() -> Value {
    serde_json::to_value(generate::running_bond_wall(&study_wall())).expect("a scene spec is JSON")
}

/// A half-sine pulse: a(t) = `amplitude` sin(2πt/`period`) for 0 ≤ t ≤ `period`/2, m/s².
pub fn half_sine(amplitude: f64, period: f64) -> GroundMotion {
    GroundMotion::horizontal(Signal::Pulse {
        amplitude,
        period,
        cycles: 0.5,
        phase: 0.0,
    })
}

/// Yagoda-Biran & Hatzor's half-sine pulse (2015, §3.3): a(t) = A sin(2πt) for 0 ≤ t ≤ 0.5 s.
pub fn rocking_pulse(amplitude: f64) -> GroundMotion {
    half_sine(amplitude, 1.0)
}

/// A half-sine pulse as the motion JSON of a request (`units` m/s²).
pub fn half_sine_json(amplitude: f64, period: f64) -> Value {
    json!({"horizontal": {"pulse": {"shape": "sine", "amplitude": amplitude, "period": period, "cycles": 0.5, "units": "m/s2"}}})
}

/// A sine of `amplitude` m/s² at `frequency` Hz, from t = 0.
pub fn sine(amplitude: f64, frequency: f64) -> GroundMotion {
    GroundMotion::horizontal(Signal::Sine {
        amplitude,
        frequency,
    })
}

/// The repository's recorded ground motions (`data/ground-motions`, with their source and
/// licence), found from the crate's own folder: for tests, benchmarks and examples run inside
/// the repository (`ashlar study` takes the folder as an argument instead).
pub fn records_dir() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("data/ground-motions")
}

/// One of the repository's records by file name (e.g. `northridge-1994-mulholland-009.at2`).
pub fn record(name: &str) -> Result<GroundMotion, MotionError> {
    motion::load_path(&records_dir().join(name))
}

/// The record of the shaken walls (examples/shaken_walls.rs, tests/engine/shaken_wall_settle.rs):
/// Northridge 1994, Mulholland 009, scaled to a PGA of 0.3 g.
pub fn shaken_wall_record() -> Result<GroundMotion, MotionError> {
    Ok(record("northridge-1994-mulholland-009.at2")?.scaled_to_pga(0.3 * motion::STANDARD_GRAVITY))
}

/// Why the rocking colonnade could not be built (`rocking_colonnade`).
#[derive(Debug, thiserror::Error)]
pub enum ColonnadeError {
    #[error("examples/doric-colonnade.json: {0}")]
    Read(#[from] std::io::Error),
    #[error("examples/doric-colonnade.json: {0}")]
    Scene(#[from] SceneError),
    #[error("Friuli record: {0}")]
    Motion(#[from] MotionError),
}

/// The rocking stack of the open–close loop's rule checks (tests/engine/light_state_rocking.rs,
/// examples/colonnade_rules.rs, docs/contact-solve.md §12, §27): the bundled Doric colonnade
/// (examples/doric-colonnade.json: three columns of seven marble drums with capitals and
/// abaci, two architraves jointed over the middle column) run for `duration` s, and Friuli 1976
/// Tolmezzo 000 scaled to a PGA of 0.3 g.
pub fn rocking_colonnade(duration: f64) -> Result<(Scene, GroundMotion), ColonnadeError> {
    let path = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("examples/doric-colonnade.json");
    let mut scene = parse_scene(&std::fs::read_to_string(path)?)?;
    scene.control.duration = Some(duration);
    let gm = record("friuli-1976-tolmezzo-000.at2")?.scaled_to_pga(0.3 * motion::STANDARD_GRAVITY);
    Ok((scene, gm))
}

/// Drop the `null` members of every object (a serialized spec's unset options), so that the
/// JSON reads as a user would write it.
fn without_nulls(v: Value) -> Value {
    match v {
        Value::Object(m) => Value::Object(
            m.into_iter()
                .filter(|(_, x)| !x.is_null())
                .map(|(k, x)| (k, without_nulls(x)))
                .collect(),
        ),
        Value::Array(a) => Value::Array(a.into_iter().map(without_nulls).collect()),
        x => x,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn presets_parse() {
        Column::SEED.scene(json!({})).expect("seed column");
        Column::SEED
            .default_model()
            .friction(60.0)
            .scene(Value::Null)
            .expect("variant");
        parse_scene(EXAMPLE_COLUMN).expect("example column");
        parse_scene(&plinth_column_json(2.0).to_string()).expect("plinth column");
        parse_scene(&incline(20.0, 30.0, json!({})).0.to_string()).expect("incline");
    }

    /// The running-bond stack fills the aligned stack's U: its stones' areas sum to the U's
    /// width × height (to round-off), every odd course has one block more, with a half block
    /// at each end, and the thrown block exists. Checked to fail with the odd courses starting
    /// on a whole block (the count fails first).
    #[test]
    fn the_running_bond_stack_fills_the_aligned_stacks_u() {
        let (columns, rows) = (5, 3);
        let v = running_bond_stack(columns, rows);
        parse_scene(&v.to_string()).expect("running-bond stack");
        let blocks = v["blocks"].as_array().expect("blocks");
        let stones: Vec<&Value> = blocks.iter().filter(|b| b.get("fixed").is_none()).collect();
        assert_eq!(stones.len(), 5 + 6 + 5);
        let width = |b: &Value| {
            let x = |k: usize| b["vertices"][k][0].as_f64().expect("x");
            x(1) - x(0)
        };
        let area: f64 = stones.iter().map(|b| width(b) * 0.2).sum();
        assert!((area - columns as f64 * 0.4 * rows as f64 * 0.2).abs() < 1e-12);
        let find = |id: &str| stones.iter().find(|b| b["id"] == id).expect(id);
        assert!((width(find("b1_0")) - 0.2).abs() < 1e-12);
        assert!((width(find("b1_5")) - 0.2).abs() < 1e-12);
        assert!(find(v["initial"][0]["block"].as_str().expect("thrown block"))["id"] == "b2_2");
    }

    #[test]
    fn the_plinth_column_is_the_service_tests_scene() {
        let v = plinth_column_json(3.0);
        assert_eq!(v["blocks"][0]["id"], "plinth");
        assert_eq!(
            v["blocks"][1]["vertices"],
            json!([[-0.2, 0.0], [0.2, 0.0], [0.2, 1.2], [-0.2, 1.2]])
        );
        assert!(v["blocks"][1].get("block_model").is_none());
        assert_eq!(v["joints"]["dry"]["friction_angle"], 40.0);
        assert_eq!(v["control"], json!({ "duration": 3.0 }));
    }
}
