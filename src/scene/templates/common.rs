//! Pieces shared by the templates: the scene skeleton (material, joint, foundation), rectangles
//! and polygons as block specs, and the running-bond filler that cuts a course into stones.
use super::{Kind, Param};
use crate::scene::spec::*;
use std::collections::BTreeMap;

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

/// The dry joint's friction angle, shared by every template. 37° (tan φ ≈ 0.75) is the middle
/// of the 30–45° measured on dressed limestone and marble joints.
pub fn friction_param() -> Param {
    Param {
        name: "friction_angle",
        units: "deg",
        description: "friction angle of the dry joints between stones and on the foundation",
        kind: Kind::Number {
            default: 37.0,
            min: 5.0,
            max: 85.0,
        },
    }
}

pub fn number(
    name: &'static str,
    units: &'static str,
    description: &'static str,
    default: f64,
    min: f64,
    max: f64,
) -> Param {
    Param {
        name,
        units,
        description,
        kind: Kind::Number { default, min, max },
    }
}

pub fn integer(
    name: &'static str,
    description: &'static str,
    default: u32,
    min: u32,
    max: u32,
) -> Param {
    Param {
        name,
        units: "count",
        description,
        kind: Kind::Integer { default, min, max },
    }
}

/// An empty scene named `name`: one stone, the joint `dry` (friction `friction` degrees, no
/// cohesion or tension), no blocks yet.
pub fn skeleton(name: String, stone: Stone, friction: f64) -> SceneSpec {
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
        name: Some(name),
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

/// The most blocks a template may build: 5000 stones is hours of engine time a second of
/// shaking, far beyond an interactive question (and the check keeps a wild parameter, a 300 m
/// pyramid of 5 cm stones, from allocating millions of blocks).
pub const MAX_BLOCKS: usize = 5000;

/// Called after each course: refuse to go on past [`MAX_BLOCKS`], naming `param`, the
/// parameter that most directly sets the count.
pub fn within_budget(spec: &SceneSpec, param: &str) -> Result<(), super::TemplateError> {
    if spec.blocks.len() > MAX_BLOCKS {
        return Err(super::TemplateError::geometry(
            param,
            format!("these parameters make more than {MAX_BLOCKS} stones; use larger stones or a smaller structure"),
        ));
    }
    Ok(())
}

/// Round to a nanometre so that generated coordinates print short and compare exactly where two
/// blocks share an edge computed twice.
pub fn tidy(x: f64) -> f64 {
    let r = (x * 1e9).round() / 1e9;
    if r == 0.0 {
        0.0
    } else {
        r
    }
}

/// A free rigid stone with the given outline (counter-clockwise).
pub fn stone(id: impl Into<String>, material: &str, vertices: Vec<[f64; 2]>) -> BlockSpec {
    BlockSpec {
        id: id.into(),
        material: material.into(),
        fixed: false,
        vertices: vertices
            .into_iter()
            .map(|[x, y]| [tidy(x), tidy(y)])
            .collect(),
        block_model: Some(BlockModel::Rigid),
    }
}

/// The rectangle [x0, x1] × [y0, y1], counter-clockwise.
pub fn rect(x0: f64, y0: f64, x1: f64, y1: f64) -> Vec<[f64; 2]> {
    vec![[x0, y0], [x1, y0], [x1, y1], [x0, y1]]
}

/// The fixed foundation under [x0, x1] at y = 0, 0.5 m deep.
pub fn foundation(material: &str, x0: f64, x1: f64) -> BlockSpec {
    BlockSpec {
        id: "foundation".into(),
        material: material.into(),
        fixed: true,
        vertices: rect(x0, -0.5, x1, 0.0)
            .into_iter()
            .map(|[x, y]| [tidy(x), tidy(y)])
            .collect(),
        block_model: None,
    }
}

/// Cut the course segment [a, b] into stones of length `length` in running bond: vertical joints
/// at `offset + k·length`; a piece shorter than 0.4·`length` at either end is merged into its
/// neighbour (no slivers). Returns the pieces' [x0, x1].
pub fn running_bond(a: f64, b: f64, length: f64, offset: f64) -> Vec<[f64; 2]> {
    let mut cuts = vec![a];
    let first = ((a - offset) / length).floor() as i64 + 1;
    let mut k = first;
    loop {
        let x = offset + k as f64 * length;
        if x >= b - 1e-9 {
            break;
        }
        if x > a + 1e-9 {
            cuts.push(x);
        }
        k += 1;
    }
    cuts.push(b);
    let min_piece = 0.4 * length;
    if cuts.len() > 2 && cuts[1] - cuts[0] < min_piece {
        cuts.remove(1);
    }
    let n = cuts.len();
    if n > 2 && cuts[n - 1] - cuts[n - 2] < min_piece {
        cuts.remove(n - 2);
    }
    cuts.windows(2).map(|w| [w[0], w[1]]).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn running_bond_cuts_whole_stones_and_merges_slivers() {
        let p = running_bond(0.0, 2.0, 0.6, 0.0);
        assert_eq!(p.len(), 3, "{p:?}"); // 0.6, 0.6, 0.8 (the 0.2 sliver merged)
        assert!((p[2][1] - p[2][0] - 0.8).abs() < 1e-12);
        let q = running_bond(0.0, 2.0, 0.6, 0.3);
        assert_eq!(q.len(), 4, "{q:?}"); // 0.3, 0.6, 0.6, 0.5 (0.3 > 0.24 is kept)
        assert!((q[0][1] - 0.3).abs() < 1e-12, "{q:?}");
        let r = running_bond(0.0, 0.3, 0.6, 0.0);
        assert_eq!(r, vec![[0.0, 0.3]]);
    }
}
