//! Turn a [`SceneSpec`] into a [`Scene`], rejecting anything the engine cannot run faithfully.
//!
//! Length (over 600 lines): one check per field of the format, in the order of docs/format.md
//! §1, and their tests; splitting them would scatter the one place that says what is refused.
use super::*;
use crate::geometry::{inside_depth, polygon_signed_area, segments_cross, segments_touch};
use std::collections::HashMap;

/// Joint index per block pair (lower index first).
type PairJoints = HashMap<(usize, usize), usize>;

fn err<T>(path: impl Into<String>, msg: impl Into<String>) -> Result<T, SceneError> {
    Err(SceneError::new(path, msg))
}

fn finite(path: &str, v: f64) -> Result<f64, SceneError> {
    if v.is_finite() {
        Ok(v)
    } else {
        err(path, format!("must be a finite number, got {v}"))
    }
}

fn positive(path: &str, v: f64) -> Result<f64, SceneError> {
    finite(path, v)?;
    if v > 0.0 {
        Ok(v)
    } else {
        err(path, format!("must be > 0, got {v}"))
    }
}

fn non_negative(path: &str, v: f64) -> Result<f64, SceneError> {
    finite(path, v)?;
    if v >= 0.0 {
        Ok(v)
    } else {
        err(path, format!("must be ≥ 0, got {v}"))
    }
}

/// Validate a parsed scene.
pub fn validate(spec: &SceneSpec) -> Result<Scene, SceneError> {
    if spec.format != "ashlar.scene/1" {
        return err(
            "format",
            format!("expected \"ashlar.scene/1\", got {:?}", spec.format),
        );
    }
    let gravity = match spec.gravity {
        Some(g) => non_negative("gravity", g)?,
        None => 9.81,
    };
    let (materials, mat_index) = materials(spec)?;
    let (joints, joint_index) = joints(spec)?;
    let control = control(&spec.control)?;
    let blocks = blocks(spec, &mat_index)?;
    let ids: Vec<String> = blocks.iter().map(|b| b.id.clone()).collect();
    let by_id: HashMap<&str, usize> = ids
        .iter()
        .enumerate()
        .map(|(i, b)| (b.as_str(), i))
        .collect();
    let (default_joint, pair_joints) = interfaces(spec, &joint_index, &by_id)?;
    let mut blocks = blocks;
    let excitation = match &spec.excitation {
        None | Some(ExcitationSpec::BaseAcceleration) => Excitation::BaseAcceleration,
        Some(ExcitationSpec::DrivenBlock { block }) => {
            let Some(&i) = by_id.get(block.as_str()) else {
                return err("excitation.block", format!("no block with id {block:?}"));
            };
            if blocks[i].kind == BlockKind::Fixed {
                return err(
                    "excitation.block",
                    format!("block {block:?} is fixed; a driven block must not also be fixed"),
                );
            }
            blocks[i].kind = BlockKind::Driven;
            Excitation::DrivenBlock(i)
        }
    };
    if !blocks.iter().any(|b| matches!(b.kind, BlockKind::Free(_))) {
        return err("blocks", "the scene has no free block: nothing would move");
    }
    let mut initial_velocity = vec![[0.0; 3]; blocks.len()];
    for (k, init) in spec.initial.iter().enumerate() {
        let path = format!("initial[{k}]");
        let Some(&i) = by_id.get(init.block.as_str()) else {
            return err(
                format!("{path}.block"),
                format!("no block with id {:?}", init.block),
            );
        };
        if !matches!(blocks[i].kind, BlockKind::Free(_)) {
            return err(
                format!("{path}.block"),
                format!(
                    "block {:?} is not free; only free blocks take initial velocities",
                    init.block
                ),
            );
        }
        finite(&format!("{path}.velocity[0]"), init.velocity[0])?;
        finite(&format!("{path}.velocity[1]"), init.velocity[1])?;
        finite(&format!("{path}.angular_velocity"), init.angular_velocity)?;
        initial_velocity[i] = [init.velocity[0], init.velocity[1], init.angular_velocity];
    }
    check_overlaps(&blocks)?;
    let explicit: Vec<Option<BlockModel>> = spec.blocks.iter().map(|b| b.block_model).collect();
    let block_model_reasons = super::block_model::resolve(
        &mut blocks,
        &explicit,
        &materials,
        &joints,
        gravity,
        control.block_model,
        control.restitution,
    );
    Ok(Scene {
        name: spec.name.clone().unwrap_or_else(|| "unnamed scene".into()),
        gravity,
        materials,
        joints,
        blocks,
        default_joint,
        pair_joints,
        excitation,
        initial_velocity,
        control,
        block_model_reasons,
        spec: spec.clone(),
    })
}

fn materials(spec: &SceneSpec) -> Result<(Vec<Material>, HashMap<String, usize>), SceneError> {
    if spec.materials.is_empty() {
        return err("materials", "at least one material is required");
    }
    let mut out = Vec::new();
    let mut idx = HashMap::new();
    for (name, m) in &spec.materials {
        let p = format!("materials.{name}");
        positive(&format!("{p}.density"), m.density)?;
        positive(&format!("{p}.young_modulus"), m.young_modulus)?;
        finite(&format!("{p}.poisson_ratio"), m.poisson_ratio)?;
        if !(m.poisson_ratio > -1.0 && m.poisson_ratio < 0.5) {
            return err(
                format!("{p}.poisson_ratio"),
                format!("must lie in (−1, 0.5), got {}", m.poisson_ratio),
            );
        }
        idx.insert(name.clone(), out.len());
        out.push(Material {
            name: name.clone(),
            density: m.density,
            young_modulus: m.young_modulus,
            poisson_ratio: m.poisson_ratio,
            plane: m.plane,
        });
    }
    Ok((out, idx))
}

fn joints(spec: &SceneSpec) -> Result<(Vec<Joint>, HashMap<String, usize>), SceneError> {
    if spec.joints.is_empty() {
        return err("joints", "at least one joint is required");
    }
    let mut out = Vec::new();
    let mut idx = HashMap::new();
    for (name, j) in &spec.joints {
        let p = format!("joints.{name}");
        finite(&format!("{p}.friction_angle"), j.friction_angle)?;
        if !(0.0..90.0).contains(&j.friction_angle) {
            return err(
                format!("{p}.friction_angle"),
                format!("must lie in [0°, 90°), got {}", j.friction_angle),
            );
        }
        non_negative(&format!("{p}.cohesion"), j.cohesion)?;
        non_negative(&format!("{p}.tensile_strength"), j.tensile_strength)?;
        idx.insert(name.clone(), out.len());
        out.push(Joint {
            name: name.clone(),
            friction_angle: j.friction_angle.to_radians(),
            cohesion: j.cohesion,
            tensile_strength: j.tensile_strength,
        });
    }
    Ok((out, idx))
}

fn blocks(spec: &SceneSpec, mat_index: &HashMap<String, usize>) -> Result<Vec<Block>, SceneError> {
    if spec.blocks.is_empty() {
        return err("blocks", "at least one block is required");
    }
    let mut seen: HashMap<&str, usize> = HashMap::new();
    let mut out = Vec::with_capacity(spec.blocks.len());
    for (i, b) in spec.blocks.iter().enumerate() {
        let p = format!("blocks[{i}]");
        if b.id.is_empty() {
            return err(format!("{p}.id"), "must not be empty");
        }
        if let Some(j) = seen.insert(b.id.as_str(), i) {
            return err(
                format!("{p}.id"),
                format!("duplicate id {:?} (also blocks[{j}])", b.id),
            );
        }
        let Some(&material) = mat_index.get(&b.material) else {
            return err(
                format!("{p}.material"),
                format!("block {:?}: no material named {:?}", b.id, b.material),
            );
        };
        let vertices = polygon(&p, &b.id, &b.vertices)?;
        let kind = if b.fixed {
            BlockKind::Fixed
        } else {
            // Placeholder: resolved once the driven block is known (`block_model::resolve`).
            BlockKind::Free(b.block_model.unwrap_or(BlockModel::Rigid))
        };
        out.push(Block {
            id: b.id.clone(),
            material,
            kind,
            vertices,
        });
    }
    Ok(out)
}

fn polygon(p: &str, id: &str, raw: &[[f64; 2]]) -> Result<Vec<Vector2<f64>>, SceneError> {
    let path = format!("{p}.vertices");
    if raw.len() < 3 {
        return err(
            path,
            format!(
                "block {id:?}: a polygon needs at least 3 vertices, got {}",
                raw.len()
            ),
        );
    }
    for (k, v) in raw.iter().enumerate() {
        if !v[0].is_finite() || !v[1].is_finite() {
            return err(
                format!("{path}[{k}]"),
                format!("block {id:?}: vertex coordinates must be finite"),
            );
        }
    }
    let mut v: Vec<Vector2<f64>> = raw.iter().map(|a| Vector2::new(a[0], a[1])).collect();
    let n = v.len();
    let (mut lo, mut hi) = (v[0], v[0]);
    for q in &v {
        lo = lo.inf(q);
        hi = hi.sup(q);
    }
    let size = (hi - lo).norm();
    for k in 0..n {
        if (v[(k + 1) % n] - v[k]).norm() <= 1e-12 * size.max(f64::MIN_POSITIVE) {
            return err(
                format!("{path}[{}]", (k + 1) % n),
                format!("block {id:?}: repeats the previous vertex (zero-length edge)"),
            );
        }
    }
    let area = polygon_signed_area(&v);
    if area.abs() <= 1e-12 * size * size || size == 0.0 {
        return err(path, format!("block {id:?}: polygon has zero area"));
    }
    let tol = 1e-12 * size * size;
    for a in 0..n {
        for b in (a + 1)..n {
            let adjacent = b == a + 1 || (a == 0 && b == n - 1);
            if adjacent {
                continue;
            }
            if segments_touch(v[a], v[(a + 1) % n], v[b], v[(b + 1) % n], tol) {
                return err(
                    path,
                    format!("block {id:?}: polygon self-intersects (edges {a} and {b})"),
                );
            }
        }
    }
    // Adjacent edges folding back on each other (a spike) also make the polygon non-simple.
    for k in 0..n {
        let a = v[(k + n - 1) % n];
        let b = v[k];
        let c = v[(k + 1) % n];
        if (b - a).perp(&(c - b)).abs() <= tol && (b - a).dot(&(c - b)) < 0.0 {
            return err(
                format!("{path}[{k}]"),
                format!("block {id:?}: edges fold back at this vertex"),
            );
        }
    }
    if area < 0.0 {
        v.reverse();
    }
    Ok(v)
}

fn interfaces(
    spec: &SceneSpec,
    joint_index: &HashMap<String, usize>,
    by_id: &HashMap<&str, usize>,
) -> Result<(usize, PairJoints), SceneError> {
    let mut pairs = HashMap::new();
    let default = match spec.interfaces.as_ref().and_then(|i| i.default.as_ref()) {
        Some(name) => *joint_index.get(name).ok_or_else(|| {
            SceneError::new("interfaces.default", format!("no joint named {name:?}"))
        })?,
        None if joint_index.len() == 1 => 0,
        None => {
            return err(
                "interfaces.default",
                "required when the scene has more than one joint",
            );
        }
    };
    if let Some(ifs) = &spec.interfaces {
        for (k, pr) in ifs.pairs.iter().enumerate() {
            let p = format!("interfaces.pairs[{k}]");
            let mut ix = [0usize; 2];
            for s in 0..2 {
                ix[s] = *by_id.get(pr.blocks[s].as_str()).ok_or_else(|| {
                    SceneError::new(
                        format!("{p}.blocks[{s}]"),
                        format!("no block with id {:?}", pr.blocks[s]),
                    )
                })?;
            }
            if ix[0] == ix[1] {
                return err(
                    format!("{p}.blocks"),
                    "a block cannot form an interface with itself",
                );
            }
            let j = *joint_index.get(&pr.joint).ok_or_else(|| {
                SceneError::new(
                    format!("{p}.joint"),
                    format!("no joint named {:?}", pr.joint),
                )
            })?;
            pairs.insert((ix[0].min(ix[1]), ix[0].max(ix[1])), j);
        }
    }
    Ok((default, pairs))
}

fn control(c: &ControlSpec) -> Result<Control, SceneError> {
    let mut out = Control::default();
    if let Some(d) = c.duration {
        out.duration = Some(positive("control.duration", d)?);
    }
    if let Some(dt) = c.time_step {
        out.time_step = positive("control.time_step", dt)?;
    }
    if let Some(a) = c.adaptive_time_step {
        out.adaptive_time_step = a;
    }
    if let Some(g2) = c.max_displacement_ratio {
        positive("control.max_displacement_ratio", g2)?;
        if g2 > 0.5 {
            return err(
                "control.max_displacement_ratio",
                format!("must be ≤ 0.5 (a fraction of the model's half size), got {g2}"),
            );
        }
        out.max_displacement_ratio = g2;
    }
    if let Some(p) = c.penalty_stiffness {
        out.penalty_stiffness = match p {
            PenaltySpec::Keyword(PenaltyKeyword::Auto) => Penalty::Auto,
            PenaltySpec::Value(v) => Penalty::Value(positive("control.penalty_stiffness", v)?),
        };
    }
    if let Some(f) = c.dynamic_factor {
        finite("control.dynamic_factor", f)?;
        if !(0.0..=1.0).contains(&f) {
            return err(
                "control.dynamic_factor",
                format!("must lie in [0, 1], got {f}"),
            );
        }
        out.dynamic_factor = f;
    }
    if let Some(r) = c.kinetic_damping_rate {
        out.kinetic_damping_rate = non_negative("control.kinetic_damping_rate", r)?;
    }
    if let Some(i) = c.integrator {
        out.integrator = i;
    }
    if let Some(s) = c.contact_solver {
        out.contact_solver = s;
    }
    if let Some(m) = c.block_model {
        out.block_model = m;
    }
    if out.integrator == Integrator::Trapezoidal && out.contact_solver == ContactSolver::Dual {
        // The dual contact is rigid: its one-step impulse enters the trapezoidal rule's
        // step-end acceleration, which the next step carries forward as a force, so every
        // impact injects energy (a bouncing block gained 5× its energy on its first impact).
        // The DDA rule (γ = 1) keeps no acceleration between steps.
        return err(
            "control.integrator",
            "\"trapezoidal\" cannot be used with contact_solver \"dual\": a rigid contact's impact \
             carries into the next step's acceleration and injects energy; use integrator \"dda\" \
             with the dual solver, or the penalty solver with \"trapezoidal\"",
        );
    }
    if let Some(m) = c.model {
        out.model = m;
    }
    if let Some(o) = c.output_interval {
        out.output_interval = positive("control.output_interval", o)?;
    }
    if let Some(n) = c.max_steps {
        if n == 0 {
            return err("control.max_steps", "must be ≥ 1");
        }
        out.max_steps = n;
    }
    dual_knobs(c, &mut out)?;
    if let Some(r) = c.unconverged_floor {
        finite("control.unconverged_floor", r)?;
        if !(0.0..=1.0).contains(&r) {
            return err(
                "control.unconverged_floor",
                format!(
                    "must lie in [0, 1] (a fraction of control.time_step; 0: no floor), got {r}"
                ),
            );
        }
        if r > 0.0 && out.contact_solver == ContactSolver::Dual {
            // An unconverged dual solve leaves no iterate to take (the engine ignores the
            // floor there): say so rather than run something else than asked.
            return err(
                "control.unconverged_floor",
                "applies only with contact_solver \"penalty\" (an unconverged dual solve has no \
                 iterate to take); remove it or use the penalty solver",
            );
        }
        out.unconverged_floor = Some(r);
    }
    if let Some(r) = c.restitution {
        out.restitution = match r {
            RestitutionSpec::Housner => Restitution::Housner,
            RestitutionSpec::Contact => Restitution::Contact,
            RestitutionSpec::Coefficient(e) => {
                finite("control.restitution", e)?;
                if !(0.0..=1.0).contains(&e) {
                    return err(
                        "control.restitution",
                        format!(
                            "must be a coefficient of restitution in [0, 1], \"housner\" or \"contact\", got {e}"
                        ),
                    );
                }
                Restitution::Coefficient(e)
            }
        };
    }
    Ok(out)
}

/// Largest `control.dual_tolerance`: 1 % of the smallest block's half size. Beyond it the
/// accepted overlaps and gaps are visible in any drawing of the blocks, and the vertex–edge
/// linearisation the solver relies on degrades (the same bound as the penalty runs'
/// `max_penetration_ratio` of 5 % of the block's thickness, with a margin).
const MAX_DUAL_TOLERANCE: f64 = 1e-2;

/// The dual solver's knobs: meaningful only with `contact_solver: "dual"`, so a scene that sets
/// them for the penalty solver is refused rather than silently ignored.
fn dual_knobs(c: &ControlSpec, out: &mut Control) -> Result<(), SceneError> {
    for (field, set) in [
        ("control.dual_tolerance", c.dual_tolerance.is_some()),
        (
            "control.dual_stall_acceptance",
            c.dual_stall_acceptance.is_some(),
        ),
    ] {
        if set && out.contact_solver != ContactSolver::Dual {
            return err(
                field,
                "applies only with contact_solver \"dual\" (the penalty solver has no such \
                 iteration); remove it or set control.contact_solver to \"dual\"",
            );
        }
    }
    if let Some(t) = c.dual_tolerance {
        positive("control.dual_tolerance", t)?;
        if t > MAX_DUAL_TOLERANCE {
            return err(
                "control.dual_tolerance",
                format!(
                    "must be ≤ {MAX_DUAL_TOLERANCE} (a fraction of the smallest block's half \
                     size; larger overlaps are visible), got {t}"
                ),
            );
        }
        out.dual_tolerance = Some(t);
    }
    if let Some(a) = c.dual_stall_acceptance {
        finite("control.dual_stall_acceptance", a)?;
        if a < 1.0 {
            return err(
                "control.dual_stall_acceptance",
                format!(
                    "must be ≥ 1 (a multiple of control.dual_tolerance; 1 accepts no stalled \
                     solve), got {a}"
                ),
            );
        }
        out.dual_stall_acceptance = Some(a);
    }
    Ok(())
}

/// Blocks must not overlap at the start (touching along edges or at vertices is fine). A sweep
/// over x-sorted bounding boxes keeps this near-linear for large walls.
fn check_overlaps(blocks: &[Block]) -> Result<(), SceneError> {
    let boxes: Vec<(f64, f64, f64, f64)> = blocks
        .iter()
        .map(|b| {
            let mut lo = b.vertices[0];
            let mut hi = b.vertices[0];
            for v in &b.vertices {
                lo = lo.inf(v);
                hi = hi.sup(v);
            }
            (lo.x, hi.x, lo.y, hi.y)
        })
        .collect();
    let mut order: Vec<usize> = (0..blocks.len()).collect();
    order.sort_by(|&a, &b| boxes[a].0.total_cmp(&boxes[b].0));
    for (k, &a) in order.iter().enumerate() {
        for &b in &order[k + 1..] {
            if boxes[b].0 > boxes[a].1 {
                break;
            }
            if boxes[b].2 > boxes[a].3 || boxes[a].2 > boxes[b].3 {
                continue;
            }
            if let Some(depth) = overlap_depth(&blocks[a], &blocks[b]) {
                let (i, j) = (a.min(b), a.max(b));
                return err(
                    format!("blocks[{j}].vertices"),
                    format!(
                        "block {:?} overlaps block {:?} at the start (by about {depth:.3e} m); blocks may touch but not overlap",
                        blocks[j].id, blocks[i].id
                    ),
                );
            }
        }
    }
    Ok(())
}

fn overlap_depth(a: &Block, b: &Block) -> Option<f64> {
    let size = |blk: &Block| {
        let mut lo = blk.vertices[0];
        let mut hi = blk.vertices[0];
        for v in &blk.vertices {
            lo = lo.inf(v);
            hi = hi.sup(v);
        }
        (hi - lo).norm()
    };
    let s = size(a).min(size(b));
    // Overlaps shallower than a millionth of the smaller block are rounding in the input
    // coordinates; the contact springs resolve them in the first step.
    let tol = 1e-6 * s;
    let mut worst: f64 = 0.0;
    for p in &a.vertices {
        worst = worst.max(inside_depth(*p, &b.vertices));
    }
    for p in &b.vertices {
        worst = worst.max(inside_depth(*p, &a.vertices));
    }
    if worst > tol {
        return Some(worst);
    }
    let (na, nb) = (a.vertices.len(), b.vertices.len());
    for i in 0..na {
        for j in 0..nb {
            let t = 1e-9 * s * s;
            if segments_cross(
                a.vertices[i],
                a.vertices[(i + 1) % na],
                b.vertices[j],
                b.vertices[(j + 1) % nb],
                t,
            ) {
                // Crossing edges with no vertex inside deeper than tol: e.g. two squares forming a
                // cross. Measure depth from the crossing geometry.
                let mid = 0.5 * (a.vertices[i] + a.vertices[(i + 1) % na]);
                let d = inside_depth(mid, &b.vertices).max(inside_depth(
                    0.5 * (b.vertices[j] + b.vertices[(j + 1) % nb]),
                    &a.vertices,
                ));
                if d > tol {
                    return Some(d);
                }
            }
        }
    }
    // Neither test sees two convex blocks laid over each other with every vertex on the other's
    // boundary and no edge crossing properly: two stones of one course 0.1 m into each other
    // (edges collinear along the bed joints), or two identical blocks on top of each other.
    // Their common part is measured by clipping one with the other; its area over its diameter
    // is the depth of a strip overlap.
    if convex(&a.vertices) && convex(&b.vertices) {
        let common = clip_convex(&a.vertices, &b.vertices);
        if common.len() >= 3 {
            // About the common part's own first vertex: the shoelace sum in scene coordinates
            // carries a rounding error of ~eps·|x|² (5e-15 m² at 5 m), which over the diameter
            // of a corner sliver (1e-15 m) read as metres of overlap for stones of a pile
            // touching diagonally.
            let origin = common[0];
            let local: Vec<Vector2<f64>> = common.iter().map(|p| p - origin).collect();
            let area = polygon_signed_area(&local).abs();
            let mut diameter: f64 = 0.0;
            for p in &common {
                for q in &common {
                    diameter = diameter.max((p - q).norm());
                }
            }
            if diameter > 0.0 && area / diameter > tol {
                return Some(area / diameter);
            }
        }
    }
    None
}

/// Whether a counter-clockwise polygon is convex (collinear vertices allowed, to rounding).
fn convex(v: &[Vector2<f64>]) -> bool {
    let n = v.len();
    let mut lo = v[0];
    let mut hi = v[0];
    for p in v {
        lo = lo.inf(p);
        hi = hi.sup(p);
    }
    let size = (hi - lo).norm();
    (0..n).all(|k| {
        let (a, b, c) = (v[k], v[(k + 1) % n], v[(k + 2) % n]);
        (b - a).perp(&(c - b)) >= -1e-12 * size * size
    })
}

/// Sutherland–Hodgman: the part of convex polygon `subject` inside convex counter-clockwise
/// polygon `clip`.
fn clip_convex(subject: &[Vector2<f64>], clip: &[Vector2<f64>]) -> Vec<Vector2<f64>> {
    let mut out: Vec<Vector2<f64>> = subject.to_vec();
    let m = clip.len();
    for k in 0..m {
        if out.is_empty() {
            break;
        }
        let (e0, e1) = (clip[k], clip[(k + 1) % m]);
        let side = |p: Vector2<f64>| (e1 - e0).perp(&(p - e0));
        let input = std::mem::take(&mut out);
        let n = input.len();
        for i in 0..n {
            let (p, q) = (input[i], input[(i + 1) % n]);
            let (sp, sq) = (side(p), side(q));
            if sp >= 0.0 {
                out.push(p);
            }
            if (sp >= 0.0) != (sq >= 0.0) {
                let t = sp / (sp - sq);
                out.push(p + (q - p) * t);
            }
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use crate::scene::parse_scene;
    use serde_json::json;

    /// Two stones of one course drawn 0.1 m into each other: every vertex lies on the other's
    /// bed-joint edge and no edge crosses another properly, so neither the vertex-depth nor the
    /// crossing test saw it (a DXF drawing like this imported as a valid scene); a stone exactly on
    /// top of another likewise. Stones side by side (touching) stay valid.
    #[test]
    fn overlapping_stones_with_collinear_edges_are_refused() {
        let two = |b: [[f64; 2]; 4]| {
            json!({
                "format": "ashlar.scene/1",
                "materials": { "stone": { "density": 2500.0, "young_modulus": 2.0e10, "poisson_ratio": 0.2 } },
                "joints": { "j": { "friction_angle": 30.0 } },
                "blocks": [
                    { "id": "a", "material": "stone",
                      "vertices": [[-0.2, 0.0], [0.2, 0.0], [0.2, 1.2], [-0.2, 1.2]] },
                    { "id": "b", "material": "stone", "vertices": b }
                ]
            })
            .to_string()
        };
        let e = parse_scene(&two([[0.1, 0.0], [0.5, 0.0], [0.5, 1.2], [0.1, 1.2]]))
            .expect_err("0.1 m into each other");
        assert!(e.message.contains("overlaps"), "{e}");
        let e = parse_scene(&two([[-0.2, 0.0], [0.2, 0.0], [0.2, 1.2], [-0.2, 1.2]]))
            .expect_err("one on the other");
        assert!(e.message.contains("overlaps"), "{e}");
        parse_scene(&two([[0.2, 0.0], [0.6, 0.0], [0.6, 1.2], [0.2, 1.2]])).expect("touching");
    }

    /// Regression (examples/pile.rs refused as "b24_12 overlaps b25_13 by about 2.828 m"): two
    /// stones of a stacked pile meeting at one corner, 5 m from the origin, whose corners
    /// overlap by one rounding unit (13 × 0.4 against 12 × 0.4 + 0.4). The clipped corner sliver's
    /// area was taken in scene coordinates, all rounding error.
    #[test]
    fn stones_meeting_at_a_corner_far_from_the_origin_are_valid() {
        let (w, h) = (0.4_f64, 0.2_f64);
        let rect = |c: f64, r: f64| {
            let (x0, y0) = (c * w, r * h);
            json!([[x0, y0], [x0 + w, y0], [x0 + w, y0 + h], [x0, y0 + h]])
        };
        let text = json!({
            "format": "ashlar.scene/1",
            "materials": { "stone": { "density": 2500.0, "young_modulus": 1.0e10, "poisson_ratio": 0.2 } },
            "joints": { "j": { "friction_angle": 30.0 } },
            "blocks": [
                { "id": "upper", "material": "stone", "vertices": rect(13.0, 25.0) },
                { "id": "lower", "material": "stone", "vertices": rect(12.0, 24.0) }
            ]
        })
        .to_string();
        parse_scene(&text).expect("diagonal neighbours touch at a corner");
    }

    fn scene(control: serde_json::Value) -> String {
        json!({
            "format": "ashlar.scene/1",
            "materials": { "stone": { "density": 2500.0, "young_modulus": 2.0e10, "poisson_ratio": 0.2 } },
            "joints": { "j": { "friction_angle": 30.0 } },
            "blocks": [
                { "id": "base", "material": "stone", "fixed": true,
                  "vertices": [[-1.0, -1.0], [1.0, -1.0], [1.0, 0.0], [-1.0, 0.0]] },
                { "id": "b", "material": "stone",
                  "vertices": [[0.0, 0.0], [0.2, 0.0], [0.2, 0.2], [0.0, 0.2]] }
            ],
            "control": control
        })
        .to_string()
    }

    #[test]
    fn trapezoidal_rule_with_the_dual_solver_is_refused_by_name() {
        let e = parse_scene(&scene(
            json!({ "integrator": "trapezoidal", "contact_solver": "dual" }),
        ))
        .expect_err("refused");
        let text = e.to_string();
        assert!(text.contains("control.integrator"), "{text}");
        assert!(text.contains("dual"), "{text}");
        // Each alone, and the DDA rule with dual, are fine.
        for ok in [
            json!({ "integrator": "trapezoidal" }),
            json!({ "contact_solver": "dual" }),
            json!({ "integrator": "dda", "contact_solver": "dual" }),
        ] {
            assert!(parse_scene(&scene(ok.clone())).is_ok(), "{ok}");
        }
    }

    /// The dual solver's knobs: taken with the dual solver, refused by name otherwise and out of
    /// range (each message checked for the field and the reason).
    #[test]
    fn dual_knobs_are_checked_by_name() {
        let ok = parse_scene(&scene(json!({
            "contact_solver": "dual", "dual_tolerance": 1e-4, "dual_stall_acceptance": 10.0
        })))
        .expect("valid");
        assert_eq!(ok.control.dual_tolerance, Some(1e-4));
        assert_eq!(ok.control.dual_stall_acceptance, Some(10.0));
        let unset = parse_scene(&scene(json!({ "contact_solver": "dual" }))).expect("valid");
        assert_eq!(
            (
                unset.control.dual_tolerance,
                unset.control.dual_stall_acceptance
            ),
            (None, None)
        );
        for (control, field, reason) in [
            (
                json!({ "dual_tolerance": 1e-4 }),
                "control.dual_tolerance",
                "contact_solver \"dual\"",
            ),
            (
                json!({ "contact_solver": "penalty", "dual_stall_acceptance": 2.0 }),
                "control.dual_stall_acceptance",
                "contact_solver \"dual\"",
            ),
            (
                json!({ "contact_solver": "dual", "dual_tolerance": 0.0 }),
                "control.dual_tolerance",
                "> 0",
            ),
            (
                json!({ "contact_solver": "dual", "dual_tolerance": 0.05 }),
                "control.dual_tolerance",
                "≤ 0.01",
            ),
            (
                json!({ "contact_solver": "dual", "dual_stall_acceptance": 0.5 }),
                "control.dual_stall_acceptance",
                "≥ 1",
            ),
        ] {
            let text = parse_scene(&scene(control.clone()))
                .expect_err("refused")
                .to_string();
            assert!(
                text.contains(field) && text.contains(reason),
                "{control}: {text}"
            );
        }
    }

    /// `control.unconverged_floor`: a fraction of `time_step` in [0, 1] (0: no floor), with
    /// the penalty solver only; unset stays unset (the engine's default).
    #[test]
    fn unconverged_floor_is_checked_by_name() {
        for r in [0.0, 0.1, 1.0] {
            let ok = parse_scene(&scene(json!({ "unconverged_floor": r }))).expect("valid");
            assert_eq!(ok.control.unconverged_floor, Some(r));
        }
        let unset = parse_scene(&scene(json!({}))).expect("valid");
        assert_eq!(unset.control.unconverged_floor, None);
        for bad in [-0.1, 1.5] {
            let text = parse_scene(&scene(json!({ "unconverged_floor": bad })))
                .expect_err("refused")
                .to_string();
            assert!(
                text.contains("control.unconverged_floor") && text.contains("[0, 1]"),
                "{bad}: {text}"
            );
        }
        let dual = parse_scene(&scene(
            json!({ "unconverged_floor": 0.1, "contact_solver": "dual" }),
        ))
        .expect_err("refused")
        .to_string();
        assert!(
            dual.contains("control.unconverged_floor") && dual.contains("penalty"),
            "{dual}"
        );
        // 0 is "no floor", meaningful with either solver.
        parse_scene(&scene(
            json!({ "unconverged_floor": 0.0, "contact_solver": "dual" }),
        ))
        .expect("valid");
    }
}
