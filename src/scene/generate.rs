//! Generated scenes for examples, benchmarks and tests: a dry-stone running-bond wall and a
//! free-standing column. They return a [`SceneSpec`] so they pass through validation like a
//! user's file.
use super::spec::*;
use std::collections::BTreeMap;

/// Parameters of a running-bond wall on a fixed foundation.
#[derive(Debug, Clone, PartialEq)]
pub struct WallParams {
    pub courses: usize,
    /// Whole blocks a course (alternate courses start and end with half blocks).
    pub blocks_per_course: usize,
    /// m.
    pub block_length: f64,
    /// m.
    pub block_height: f64,
    /// degrees.
    pub friction_angle: f64,
    pub block_model: BlockModel,
}

impl Default for WallParams {
    fn default() -> Self {
        Self {
            courses: 5,
            blocks_per_course: 6,
            block_length: 0.6,
            block_height: 0.3,
            friction_angle: 35.0,
            block_model: BlockModel::Rigid,
        }
    }
}

fn rect(x0: f64, y0: f64, w: f64, h: f64) -> Vec<[f64; 2]> {
    vec![[x0, y0], [x0 + w, y0], [x0 + w, y0 + h], [x0, y0 + h]]
}

/// The stones' material, named in the scene.
#[derive(Debug, Clone, Copy)]
pub struct Stone {
    pub name: &'static str,
    /// kg/m³.
    pub density: f64,
    /// Pa.
    pub young_modulus: f64,
    pub poisson_ratio: f64,
}

/// Marble (Pentelic-like): 2700 kg/m³, E = 50 GPa, ν = 0.2, values of the order used for the
/// Parthenon's columns in the DEM literature.
pub const MARBLE: Stone = Stone {
    name: "marble",
    density: 2700.0,
    young_modulus: 5.0e10,
    poisson_ratio: 0.2,
};

/// A medium limestone: 2500 kg/m³, E = 20 GPa, ν = 0.2 (the project's examples' stone).
pub const LIMESTONE: Stone = Stone {
    name: "limestone",
    density: 2500.0,
    young_modulus: 2.0e10,
    poisson_ratio: 0.2,
};

/// An empty scene named `name`: one stone, the joint `dry` (friction `friction` degrees, no
/// cohesion or tension), gravity 9.81 m/s², no blocks yet. Every generated scene and template
/// starts from it.
pub fn stone_scene(name: impl Into<String>, stone: Stone, friction: f64) -> SceneSpec {
    let mut materials = BTreeMap::new();
    materials.insert(
        stone.name.to_string(),
        MaterialSpec {
            density: stone.density,
            young_modulus: stone.young_modulus,
            poisson_ratio: stone.poisson_ratio,
            plane: PlaneKind::Stress,
        },
    );
    let mut joints = BTreeMap::new();
    joints.insert(
        "dry".to_string(),
        JointSpec {
            friction_angle: friction,
            cohesion: 0.0,
            tensile_strength: 0.0,
        },
    );
    SceneSpec {
        format: "ashlar.scene/1".into(),
        name: Some(name.into()),
        gravity: Some(9.81),
        materials,
        joints,
        blocks: Vec::new(),
        interfaces: None,
        excitation: None,
        initial: Vec::new(),
        control: ControlSpec::default(),
    }
}

/// A running-bond wall: `courses` courses on a fixed foundation, joints offset by half a block.
pub fn running_bond_wall(p: &WallParams) -> SceneSpec {
    let mut spec = stone_scene(
        format!(
            "running-bond wall, {} courses × {} blocks",
            p.courses, p.blocks_per_course
        ),
        LIMESTONE,
        p.friction_angle,
    );
    let (l, h) = (p.block_length, p.block_height);
    let width = l * p.blocks_per_course as f64;
    spec.blocks.push(BlockSpec {
        id: "foundation".into(),
        material: "limestone".into(),
        fixed: true,
        vertices: rect(-0.5, -0.5, width + 1.0, 0.5),
        block_model: None,
    });
    for c in 0..p.courses {
        let y = c as f64 * h;
        let mut x = 0.0;
        let mut k = 0;
        let mut pieces = Vec::new();
        if c % 2 == 1 {
            pieces.push(0.5 * l);
            for _ in 1..p.blocks_per_course {
                pieces.push(l);
            }
            pieces.push(0.5 * l);
        } else {
            pieces.extend(std::iter::repeat_n(l, p.blocks_per_course));
        }
        for w in pieces {
            spec.blocks.push(BlockSpec {
                id: format!("c{c}b{k}"),
                material: "limestone".into(),
                fixed: false,
                vertices: rect(x, y, w, h),
                block_model: Some(p.block_model),
            });
            x += w;
            k += 1;
        }
    }
    spec
}

/// A free-standing rectangular column (half-width `b`, half-height `h`) on a fixed plinth.
pub fn column(b: f64, h: f64, friction: f64) -> SceneSpec {
    let mut spec = stone_scene("free-standing column on a plinth", LIMESTONE, friction);
    spec.blocks.push(BlockSpec {
        id: "plinth".into(),
        material: "limestone".into(),
        fixed: true,
        vertices: rect(-1.0, -0.5, 2.0, 0.5),
        block_model: None,
    });
    spec.blocks.push(BlockSpec {
        id: "column".into(),
        material: "limestone".into(),
        fixed: false,
        vertices: rect(-b, 0.0, 2.0 * b, 2.0 * h),
        block_model: Some(BlockModel::Rigid),
    });
    spec
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn wall_validates_and_has_expected_block_count() {
        let p = WallParams {
            courses: 4,
            blocks_per_course: 5,
            ..Default::default()
        };
        let spec = running_bond_wall(&p);
        // 2 courses of 5 + 2 courses of 6 (4 whole + 2 halves) + foundation.
        assert_eq!(spec.blocks.len(), 1 + 5 + 6 + 5 + 6);
        assert!(crate::scene::validate(&spec).is_ok());
    }
}
