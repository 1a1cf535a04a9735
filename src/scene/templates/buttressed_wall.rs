//! `buttressed-wall`: the cross-section of a wall with a stepped buttress bonded to its +x face.
//! Shaking in the section's plane is the wall's out-of-plane motion, which governs its collapse.
//!
//! Each course spans the wall's thickness plus the buttress's depth at that height; the
//! buttress steps back `buttress_steps` times, evenly, up to `buttress_height`. Courses are cut
//! into stones `block_length` long in running bond across the section (alternate courses offset
//! by half a stone), so that wall and buttress are bonded.
use super::common::*;
use super::{Param, TemplateError, Values};
use crate::scene::spec::SceneSpec;

pub fn params() -> Vec<Param> {
    vec![
        wall_height(4.8, 0.5, 40.0),
        number("thickness", "m", "thickness of the wall", 0.8, 0.1, 5.0),
        course_height(0.4, 3.0),
        number(
            "block_length",
            "m",
            "length of a stone across the section",
            0.6,
            0.05,
            5.0,
        ),
        number(
            "buttress_depth",
            "m",
            "depth of the buttress at its foot, beyond the wall's face",
            1.2,
            0.1,
            20.0,
        ),
        number(
            "buttress_height",
            "m",
            "height of the buttress (rounded to whole courses)",
            3.6,
            0.1,
            40.0,
        ),
        integer(
            "buttress_steps",
            "number of set-backs of the buttress (each an equal part of its depth and height)",
            3,
            1,
            20,
        ),
        friction_param(),
    ]
}

pub fn buttressed_wall(v: &Values) -> Result<SceneSpec, TemplateError> {
    let (t, h, l) = (
        v.num("thickness"),
        v.num("course_height"),
        v.num("block_length"),
    );
    let courses = whole_courses(v.num("height"), h);
    let b_courses = whole_courses(v.num("buttress_height"), h);
    let steps = v.count("buttress_steps");
    let depth = v.num("buttress_depth");
    if b_courses > courses {
        return Err(TemplateError::geometry(
            "buttress_height",
            format!(
                "the buttress ({b_courses} courses) is taller than the wall ({courses} courses)"
            ),
        ));
    }
    if steps > b_courses {
        return Err(TemplateError::geometry(
            "buttress_steps",
            format!("{steps} steps do not fit in the buttress's {b_courses} courses"),
        ));
    }
    let mut spec = stone_scene(
        format!(
            "buttressed wall section: {} m high, {t} m thick, buttress {depth} m deep in {steps} steps",
            tidy(courses as f64 * h)
        ),
        LIMESTONE,
        v.num("friction_angle"),
    );
    spec.blocks
        .push(foundation(LIMESTONE.name, -0.5, t + depth + 0.5));
    for c in 0..courses {
        // Step k (0 at the foot) of the buttress holds this course; its depth falls linearly.
        let d = if c < b_courses {
            let k = c * steps / b_courses;
            depth * (steps - k) as f64 / steps as f64
        } else {
            0.0
        };
        lay_course(
            &mut spec,
            LIMESTONE.name,
            c,
            h,
            l,
            &[[0.0, t + d]],
            Vec::new(),
        )?;
    }
    Ok(spec)
}
