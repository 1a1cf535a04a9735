//! scene (validation) → the block model of each free block: a block's own `block_model`, else
//! `control.block_model`, and for `"auto"` (the default) the rule below, with the reason the
//! run summary reports (`block_model_reason`). The engine (simulation) only sees the result.
//!
//! **The rule** (docs/format.md, "How `"auto"` chooses the block model"). What a deformable
//! block adds to a rigid one is its elastic strain ε: it moves the block's vertices, and so the
//! lever arms and contact positions that decide rocking and toppling, by ε times the block's
//! size; friction (sliding) does not depend on it. A block is rigid when the strain the scene's
//! loads can cause, times the slenderness that turns a strain into a change of a lever arm,
//! stays within [`AutoBlockModelParams::strain_bound`] (10⁻⁴):
//!
//! - vertical stress at the block's bed: σ = ρ_max (g + a_v) H, H from the block's lowest
//!   point to the top of the free structure, ρ_max the densest free block, a_v ≤ 1 g (the
//!   vertical ground acceleration: beyond 1 g every block leaves its bed, and then nothing is
//!   strained);
//! - shear: what dry or bonded joints can pass into the block, τ ≤ c_max + σ tan φ_max, and
//!   tension ≤ the largest tensile strength. The horizontal load is bounded by the joints, not
//!   by the peak ground acceleration: a block accelerates horizontally only through its
//!   contacts (its inertial load in the moving frame is balanced by them), so the bound holds
//!   for every record and every amplitude of a PGA search, which therefore never switches
//!   model between its runs;
//! - ε = (σ + τ + t) / E of the block's own material;
//! - measure m = ε · max(1, h/w of the block, H/B of the free structure): a strain ε moves the
//!   top of a block of height h (or of the structure, H) sideways by up to ε h, against the
//!   half-width that is the lever arm of toppling.
//!
//! With the contacts' own impact response (`restitution: "contact"`) the rebound includes the
//! blocks' elastic compliance (the study fits e = 0.615 deformable against 0.84 rigid, trapezoidal),
//! so `"auto"` keeps such blocks deformable. Under an impact law (the default `"housner"`, or a
//! coefficient), the impact is the law's, whatever the block model.
use super::{Block, BlockKind, BlockModel, BlockModelChoice, Joint, Material, Restitution};

/// Knobs of the `"auto"` block model.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct AutoBlockModelParams {
    /// Largest strain measure (strain × slenderness, 1) for which a block is rigid: 1e-4, so
    /// the lever arms that decide toppling move by at most 0.01 % of themselves, and the
    /// rocking threshold (a_g = g b/h for a rectangle, a ratio of two lengths) by at most
    /// ~0.02 %. The same bound the reduced models accept a deformable block at
    /// (`analysis::reduced::ReducedParams::rigid_strain`).
    pub strain_bound: f64,
    /// Vertical load factor (1): (g + a_v)/g with a vertical ground acceleration up to 1 g.
    pub vertical_factor: f64,
}

impl Default for AutoBlockModelParams {
    fn default() -> Self {
        Self {
            strain_bound: 1.0e-4,
            vertical_factor: 2.0,
        }
    }
}

/// The strain measure of the rule for each block (0 for fixed and driven blocks), with its
/// parts for the reason text.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StrainMeasure {
    /// 1, the rule's measure ε · slenderness.
    pub measure: f64,
    /// 1, the strain bound ε.
    pub strain: f64,
    /// 1, the slenderness factor.
    pub slenderness: f64,
    /// m, the height of structure above the block's lowest point.
    pub load_height: f64,
}

fn extent(v: &[nalgebra::Vector2<f64>]) -> (f64, f64, f64, f64) {
    v.iter().fold(
        (
            f64::INFINITY,
            f64::NEG_INFINITY,
            f64::INFINITY,
            f64::NEG_INFINITY,
        ),
        |(x0, x1, y0, y1), p| (x0.min(p.x), x1.max(p.x), y0.min(p.y), y1.max(p.y)),
    )
}

/// The rule's measure for every block (see the module text).
pub fn strain_measures(
    blocks: &[Block],
    materials: &[Material],
    joints: &[Joint],
    gravity: f64,
    params: &AutoBlockModelParams,
) -> Vec<StrainMeasure> {
    let free: Vec<&Block> = blocks
        .iter()
        .filter(|b| matches!(b.kind, BlockKind::Free(_)))
        .collect();
    let (mut sx0, mut sx1, mut sy0, mut sy1) = (
        f64::INFINITY,
        f64::NEG_INFINITY,
        f64::INFINITY,
        f64::NEG_INFINITY,
    );
    let mut rho_max: f64 = 0.0;
    for b in &free {
        let (x0, x1, y0, y1) = extent(&b.vertices);
        sx0 = sx0.min(x0);
        sx1 = sx1.max(x1);
        sy0 = sy0.min(y0);
        sy1 = sy1.max(y1);
        rho_max = rho_max.max(materials[b.material].density);
    }
    let structure_slenderness = if sx1 > sx0 {
        (sy1 - sy0) / (sx1 - sx0)
    } else {
        1.0
    };
    let tan_phi = joints
        .iter()
        .map(|j| j.friction_angle.tan().abs())
        .fold(0.0, f64::max);
    let cohesion = joints.iter().map(|j| j.cohesion).fold(0.0, f64::max);
    let tension = joints
        .iter()
        .map(|j| j.tensile_strength)
        .fold(0.0, f64::max);
    blocks
        .iter()
        .map(|b| {
            if !matches!(b.kind, BlockKind::Free(_)) {
                return StrainMeasure {
                    measure: 0.0,
                    strain: 0.0,
                    slenderness: 0.0,
                    load_height: 0.0,
                };
            }
            let (x0, x1, y0, y1) = extent(&b.vertices);
            let load_height = (sy1 - y0).max(0.0);
            let sigma = rho_max * gravity * params.vertical_factor * load_height;
            let tau = cohesion + sigma * tan_phi;
            let strain = (sigma + tau + tension) / materials[b.material].young_modulus;
            let own = if x1 > x0 { (y1 - y0) / (x1 - x0) } else { 1.0 };
            let slenderness = 1.0_f64.max(own).max(structure_slenderness);
            StrainMeasure {
                measure: strain * slenderness,
                strain,
                slenderness,
                load_height,
            }
        })
        .collect()
}

/// Resolve every free block's model: `explicit[i]` (the block's own `block_model`) first, then
/// `control.block_model`, and for `"auto"` the rule. Sets `blocks[i].kind` and returns the
/// reason of each block (empty for fixed and driven blocks).
pub fn resolve(
    blocks: &mut [Block],
    explicit: &[Option<BlockModel>],
    materials: &[Material],
    joints: &[Joint],
    gravity: f64,
    choice: BlockModelChoice,
    restitution: Restitution,
) -> Vec<String> {
    let params = AutoBlockModelParams::default();
    let measures = strain_measures(blocks, materials, joints, gravity, &params);
    let mut reasons = Vec::with_capacity(blocks.len());
    let mut auto = Vec::new();
    for (i, b) in blocks.iter_mut().enumerate() {
        if !matches!(b.kind, BlockKind::Free(_)) {
            reasons.push(String::new());
            continue;
        }
        let (model, reason) = match (explicit.get(i).copied().flatten(), choice) {
            (Some(m), _) => (m, format!("the block's own block_model ({})", name(m))),
            (None, BlockModelChoice::Rigid) => (BlockModel::Rigid, "control.block_model".into()),
            (None, BlockModelChoice::Deformable) => {
                (BlockModel::Deformable, "control.block_model".into())
            }
            (None, BlockModelChoice::Auto) if restitution == Restitution::Contact => (
                BlockModel::Deformable,
                "auto: restitution \"contact\" makes the impact the contacts' own response, \
                 which includes the blocks' elastic compliance"
                    .into(),
            ),
            (None, BlockModelChoice::Auto) => {
                let m = measures[i];
                let rigid = m.measure <= params.strain_bound;
                auto.push(i);
                let model = if rigid {
                    BlockModel::Rigid
                } else {
                    BlockModel::Deformable
                };
                (model, auto_reason(&b.id, &m, params.strain_bound, false))
            }
        };
        b.kind = BlockKind::Free(model);
        reasons.push(reason);
    }
    // Every block the rule chose got the same model: one reason for the scene, that of the
    // block that decides it (the most strained when rigid, the least when deformable).
    let model_of = |i: usize| match blocks[i].kind {
        BlockKind::Free(m) => Some(m),
        _ => None,
    };
    if let Some(&first) = auto.first() {
        let m0 = model_of(first);
        if auto.iter().all(|&i| model_of(i) == m0) && auto.len() > 1 {
            let rigid = m0 == Some(BlockModel::Rigid);
            let key = |i: &usize| measures[*i].measure;
            let governing = if rigid {
                auto.iter()
                    .copied()
                    .max_by(|a, b| key(a).total_cmp(&key(b)))
            } else {
                auto.iter()
                    .copied()
                    .min_by(|a, b| key(a).total_cmp(&key(b)))
            };
            if let Some(g) = governing {
                let r = auto_reason(&blocks[g].id, &measures[g], params.strain_bound, true);
                for &i in &auto {
                    reasons[i] = r.clone();
                }
            }
        }
    }
    reasons
}

fn auto_reason(id: &str, m: &StrainMeasure, bound: f64, every: bool) -> String {
    let rigid = m.measure <= bound;
    format!(
        "auto: {}strain {:.2e} (loads of {:.3} m of structure above its bed, shear bounded by the joints, vertical ground acceleration up to 1 g) × slenderness {:.3} = {:.2e} {} {:.0e}: {}",
        match (every, rigid) {
            (true, true) => format!("every block within the bound; the most strained, {id:?}: "),
            (true, false) => format!("every block beyond the bound; the least strained, {id:?}: "),
            (false, _) => String::new(),
        },
        m.strain,
        m.load_height,
        m.slenderness,
        m.measure,
        if rigid { "≤" } else { ">" },
        bound,
        if rigid {
            "elastic strain moves the lever arms that decide toppling by less than 0.01 % of themselves, so rigid"
        } else {
            "elastic strain can move the lever arms that decide toppling by more than 0.01 %, so deformable"
        }
    )
}

fn name(m: BlockModel) -> &'static str {
    match m {
        BlockModel::Rigid => "rigid",
        BlockModel::Deformable => "deformable",
    }
}

/// The scene-wide model and reason: the free blocks' common model and reason, or `"mixed"`
/// with `None` (each block then reports its own).
pub fn scene_summary(blocks: &[Block], reasons: &[String]) -> Option<(BlockModel, String)> {
    let mut it = blocks
        .iter()
        .zip(reasons)
        .filter_map(|(b, r)| match b.kind {
            BlockKind::Free(m) => Some((m, r)),
            _ => None,
        });
    let (m0, r0) = it.next()?;
    it.all(|(m, r)| m == m0 && r == r0)
        .then(|| (m0, r0.clone()))
}

#[cfg(test)]
mod tests {
    use crate::scene::{parse_scene, BlockKind, BlockModel};

    fn scene(e: f64, w: f64, h: f64, extra: &str) -> String {
        format!(
            r#"{{"format":"ashlar.scene/1",
            "materials":{{"m":{{"density":2600,"young_modulus":{e},"poisson_ratio":0.2}}}},
            "joints":{{"dry":{{"friction_angle":37}}}},
            "blocks":[{{"id":"base","material":"m","fixed":true,"vertices":[[-5,-1],[5,-1],[5,0],[-5,0]]}},
                      {{"id":"b","material":"m","vertices":[[0,0],[{w},0],[{w},{h}],[0,{h}]]{extra}}}],
            "control":{{"duration":0.1}}}}"#
        )
    }

    fn model(text: &str) -> BlockModel {
        let s = parse_scene(text).expect("valid scene");
        match s.blocks[1].kind {
            BlockKind::Free(m) => m,
            _ => panic!("free block expected"),
        }
    }

    #[test]
    fn stone_block_is_rigid_and_soft_block_deformable() {
        // Stone, 0.4 × 1.2 m: 2 ρ g H (1 + tan 37°) / E = 5.4e-6, × h/w 3 = 1.6e-5 ≤ 1e-4.
        assert_eq!(model(&scene(2.0e10, 0.4, 1.2, "")), BlockModel::Rigid);
        // E = 1e7 Pa (a rubber bearing, raw earth): 1.1e-2 × 3: deformable.
        assert_eq!(model(&scene(1.0e7, 0.4, 1.2, "")), BlockModel::Deformable);
        // A block's own block_model is honoured against the rule.
        assert_eq!(
            model(&scene(1.0e7, 0.4, 1.2, r#","block_model":"rigid""#)),
            BlockModel::Rigid
        );
    }
}
