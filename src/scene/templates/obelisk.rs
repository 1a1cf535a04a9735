//! `obelisk`: a monolithic tapering shaft with its pyramidion (one stone), on a pedestal, on
//! steps. Each step is one stone, wider than the one above by a tread on each side.
use super::common::*;
use super::{Param, TemplateError, Values};
use crate::scene::spec::SceneSpec;

pub fn params() -> Vec<Param> {
    vec![
        number(
            "height",
            "m",
            "height of the monolith, pyramidion included",
            8.0,
            0.5,
            60.0,
        ),
        number(
            "base_width",
            "m",
            "width of the shaft at its foot",
            0.9,
            0.05,
            10.0,
        ),
        number(
            "top_width",
            "m",
            "width of the shaft under the pyramidion",
            0.6,
            0.05,
            10.0,
        ),
        number(
            "pyramidion_height",
            "m",
            "height of the pyramidion",
            0.6,
            0.01,
            10.0,
        ),
        number(
            "pedestal_height",
            "m",
            "height of the pedestal (0: none)",
            1.0,
            0.0,
            10.0,
        ),
        number(
            "pedestal_width",
            "m",
            "width of the pedestal",
            1.6,
            0.05,
            20.0,
        ),
        integer("steps", "number of steps under the pedestal", 2, 0, 10),
        number("step_height", "m", "height of a step", 0.3, 0.05, 2.0),
        number(
            "step_tread",
            "m",
            "how far each step reaches beyond the one above, on each side",
            0.3,
            0.05,
            3.0,
        ),
        friction_param(),
    ]
}

pub fn obelisk(v: &Values) -> Result<SceneSpec, TemplateError> {
    let (height, b, top, py) = (
        v.num("height"),
        v.num("base_width"),
        v.num("top_width"),
        v.num("pyramidion_height"),
    );
    let (ph, pw) = (v.num("pedestal_height"), v.num("pedestal_width"));
    let (steps, sh, tread) = (v.count("steps"), v.num("step_height"), v.num("step_tread"));
    if py >= height {
        return Err(TemplateError::geometry(
            "pyramidion_height",
            format!("must be less than the monolith's height {height} m, got {py} m"),
        ));
    }
    if top > b {
        return Err(TemplateError::geometry(
            "top_width",
            format!(
                "an obelisk tapers upward: top_width must not exceed base_width {b} m, got {top} m"
            ),
        ));
    }
    let seat = if ph > 0.0 { pw } else { b };
    if ph > 0.0 && pw < b {
        return Err(TemplateError::geometry(
            "pedestal_width",
            format!(
                "the pedestal must be at least as wide as the shaft's foot ({b} m), got {pw} m"
            ),
        ));
    }
    let mut spec = stone_scene(
        format!("obelisk {height} m on a pedestal and {steps} step(s)"),
        LIMESTONE,
        v.num("friction_angle"),
    );
    let widest = seat + 2.0 * tread * steps as f64;
    spec.blocks.push(foundation(
        LIMESTONE.name,
        -0.5 * widest - 0.5,
        0.5 * widest + 0.5,
    ));
    let mut y = 0.0;
    // Steps from the bottom (widest) up.
    for k in 0..steps {
        let half = 0.5 * seat + tread * (steps - k) as f64;
        spec.blocks.push(stone(
            format!("step{}", k + 1),
            LIMESTONE.name,
            rect(-half, y, half, y + sh),
        ));
        y += sh;
    }
    if ph > 0.0 {
        spec.blocks.push(stone(
            "pedestal",
            LIMESTONE.name,
            rect(-0.5 * pw, y, 0.5 * pw, y + ph),
        ));
        y += ph;
    }
    let shaft = height - py;
    spec.blocks.push(stone(
        "obelisk",
        LIMESTONE.name,
        vec![
            [-0.5 * b, y],
            [0.5 * b, y],
            [0.5 * top, y + shaft],
            [0.0, y + height],
            [-0.5 * top, y + shaft],
        ],
    ));
    Ok(spec)
}
