//! `pyramid`: the section of a stepped pyramid through its apex. Tiers of running-bond courses,
//! each tier set back from the one below on both sides.
use super::common::*;
use super::{Param, TemplateError, Values};
use crate::scene::spec::SceneSpec;

pub fn params() -> Vec<Param> {
    vec![
        integer("tiers", "number of tiers (steps)", 4, 1, 40),
        integer("courses_per_tier", "courses in each tier", 1, 1, 20),
        number(
            "base_width",
            "m",
            "width of the lowest tier",
            6.0,
            0.5,
            300.0,
        ),
        number(
            "setback",
            "m",
            "how far each tier is set back from the one below, on each side",
            0.6,
            0.05,
            30.0,
        ),
        number("course_height", "m", "height of a course", 0.5, 0.05, 5.0),
        number("block_length", "m", "length of a stone", 1.0, 0.05, 10.0),
        friction_param(),
    ]
}

pub fn pyramid(v: &Values) -> Result<SceneSpec, TemplateError> {
    let (tiers, per) = (v.count("tiers"), v.count("courses_per_tier"));
    let (base, setback, h, l) = (
        v.num("base_width"),
        v.num("setback"),
        v.num("course_height"),
        v.num("block_length"),
    );
    let top = base - 2.0 * setback * (tiers - 1) as f64;
    if top < 0.4 * l {
        return Err(TemplateError::geometry(
            "setback",
            format!(
                "{tiers} tiers set back {setback} m from a {base} m base leave a top tier {} m wide, less than 0.4 stone",
                tidy(top)
            ),
        ));
    }
    let mut spec = skeleton(
        format!("stepped pyramid section: {tiers} tiers, {base} m at the base"),
        LIMESTONE,
        v.num("friction_angle"),
    );
    spec.blocks.push(foundation(
        LIMESTONE.name,
        -0.5 * base - 0.5,
        0.5 * base + 0.5,
    ));
    for tier in 0..tiers {
        let half = 0.5 * base - setback * tier as f64;
        for j in 0..per {
            let c = tier * per + j;
            let (y0, y1) = (c as f64 * h, (c + 1) as f64 * h);
            let offset = if c % 2 == 1 { 0.5 * l } else { 0.0 };
            for (k, [x0, x1]) in running_bond(-half, half, l, offset).into_iter().enumerate() {
                spec.blocks.push(stone(
                    format!("c{}b{}", c + 1, k + 1),
                    LIMESTONE.name,
                    rect(x0, y0, x1, y1),
                ));
            }
            within_budget(&spec, "block_length")?;
        }
    }
    Ok(spec)
}
