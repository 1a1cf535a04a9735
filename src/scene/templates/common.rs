//! Pieces shared by the templates: the scene skeleton (`generate::stone_scene`: material, joint;
//! and the foundation), rectangles and polygons as block specs, the running-bond filler that
//! cuts a course into stones and the course builder that lays them.
use super::{Kind, Param, TemplateError};
/// The old name of [`stone_scene`], kept while `pyramid.rs` is being changed on another branch
/// (rename it there after the merge).
pub use crate::scene::generate::stone_scene as skeleton;
pub use crate::scene::generate::{stone_scene, LIMESTONE, MARBLE};
use crate::scene::spec::*;

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

/// The `height` of a wall, m, rounded to whole courses by the template.
pub fn wall_height(default: f64, min: f64, max: f64) -> Param {
    number(
        "height",
        "m",
        "height of the wall (rounded to whole courses)",
        default,
        min,
        max,
    )
}

/// The `course_height` of a coursed template, m (at least 5 cm).
pub fn course_height(default: f64, max: f64) -> Param {
    number(
        "course_height",
        "m",
        "height of a course",
        default,
        0.05,
        max,
    )
}

/// How many whole courses of height `course` make `height` (at least one).
pub fn whole_courses(height: f64, course: f64) -> usize {
    (height / course).round().max(1.0) as usize
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

/// The most blocks a template may build: 5000 stones is hours of engine time a second of
/// shaking, far beyond an interactive question (and the check keeps a wild parameter, a 300 m
/// pyramid of 5 cm stones, from allocating millions of blocks).
pub const MAX_BLOCKS: usize = 5000;

/// Called after each course: refuse to go on past [`MAX_BLOCKS`], naming `param`, the
/// parameter that most directly sets the count.
pub fn within_budget(spec: &SceneSpec, param: &str) -> Result<(), TemplateError> {
    if spec.blocks.len() > MAX_BLOCKS {
        return Err(TemplateError::geometry(
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

/// Lay course `c` of stones of `material` (0 at the foot, `h` high) in running bond: stones `l` long over each of
/// `segments` (left to right), alternate courses offset by half a stone, plus the `named` whole
/// pieces (lintels) where they fall; the stones are numbered `c{c+1}b{k}` from the left, the
/// named pieces keep their names. Then refuses to go past [`MAX_BLOCKS`] (naming
/// `block_length`, the parameter that most directly sets the count).
pub fn lay_course(
    spec: &mut SceneSpec,
    material: &str,
    c: usize,
    h: f64,
    l: f64,
    segments: &[[f64; 2]],
    named: Vec<([f64; 2], String)>,
) -> Result<(), TemplateError> {
    let (y0, y1) = (c as f64 * h, (c + 1) as f64 * h);
    let offset = if c % 2 == 1 { 0.5 * l } else { 0.0 };
    let mut pieces: Vec<([f64; 2], Option<String>)> = segments
        .iter()
        .flat_map(|&[a, b]| running_bond(a, b, l, offset))
        .map(|p| (p, None))
        .collect();
    pieces.extend(named.into_iter().map(|(p, name)| (p, Some(name))));
    // Stable: the running-bond pieces are already in order, so only the named ones move.
    pieces.sort_by(|a, b| a.0[0].total_cmp(&b.0[0]));
    let mut k = 0;
    for ([x0, x1], name) in pieces {
        let id = name.unwrap_or_else(|| {
            k += 1;
            format!("c{}b{k}", c + 1)
        });
        spec.blocks.push(stone(id, material, rect(x0, y0, x1, y1)));
    }
    within_budget(spec, "block_length")
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
