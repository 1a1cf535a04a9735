//! `wall`: a running-bond wall in elevation (in-plane shaking), with openings under lintels.
//!
//! Courses of `course_height`; stones `block_length` long, alternate courses offset by half a
//! stone; slivers shorter than 0.4 stone merged into their neighbour. Each opening's sill and
//! head are rounded to whole courses; the course above it is a lintel stone reaching
//! `lintel_bearing` into the masonry on each side. Several openings are spaced evenly (their
//! centres at (i + ½)·length / openings).
use super::common::*;
use super::{Param, TemplateError, Values};
use crate::scene::spec::SceneSpec;

pub fn params() -> Vec<Param> {
    vec![
        number("length", "m", "length of the wall", 4.2, 0.5, 60.0),
        wall_height(2.4, 0.1, 30.0),
        number("block_length", "m", "length of a stone", 0.6, 0.05, 5.0),
        course_height(0.3, 3.0),
        integer(
            "openings",
            "number of openings (windows or doors), evenly spaced",
            1,
            0,
            20,
        ),
        number(
            "opening_width",
            "m",
            "clear width of each opening",
            0.9,
            0.1,
            20.0,
        ),
        number(
            "opening_height",
            "m",
            "clear height of each opening (rounded to whole courses)",
            0.9,
            0.05,
            30.0,
        ),
        number(
            "sill_height",
            "m",
            "height of the sill above the foundation (0: a door; rounded to whole courses)",
            0.6,
            0.0,
            30.0,
        ),
        number(
            "lintel_bearing",
            "m",
            "length each lintel rests on the masonry beside the opening",
            0.3,
            0.05,
            5.0,
        ),
        friction_param(),
    ]
}

pub fn wall(v: &Values) -> Result<SceneSpec, TemplateError> {
    let (length, l, h) = (
        v.num("length"),
        v.num("block_length"),
        v.num("course_height"),
    );
    let courses = whole_courses(v.num("height"), h);
    let n_open = v.count("openings");
    let (w, bearing) = (v.num("opening_width"), v.num("lintel_bearing"));
    let sill = (v.num("sill_height") / h).round() as usize;
    let tall = whole_courses(v.num("opening_height"), h);
    let mut spec = stone_scene(
        format!(
            "running-bond wall {length} m × {} m, {n_open} opening(s)",
            tidy(courses as f64 * h)
        ),
        LIMESTONE,
        v.num("friction_angle"),
    );
    // Each opening's [x0, x1].
    let openings: Vec<[f64; 2]> = (0..n_open)
        .map(|i| {
            let c = (i as f64 + 0.5) * length / n_open as f64;
            [c - 0.5 * w, c + 0.5 * w]
        })
        .collect();
    if n_open > 0 {
        // Room for the lintels' bearings and a stone's worth of pier between openings.
        let pier = length / n_open as f64 - w;
        if pier <= 0.0 {
            // Not "piers of −0.4 m": the openings overlap.
            return Err(TemplateError::geometry(
                "opening_width",
                format!(
                    "{n_open} opening(s) {w} m wide do not fit side by side in a wall {length} m long"
                ),
            ));
        }
        if pier < 2.0 * bearing + 0.4 * l {
            return Err(TemplateError::geometry(
                "opening_width",
                format!(
                    "{n_open} opening(s) {w} m wide leave piers of {} m, too narrow for two lintel bearings of {bearing} m and a stone",
                    tidy(pier)
                ),
            ));
        }
        if sill + tall + 1 > courses {
            return Err(TemplateError::geometry(
                "opening_height",
                format!(
                    "sill ({sill} courses) + opening ({tall} courses) + lintel (1 course) exceed the wall's {courses} courses"
                ),
            ));
        }
    }
    spec.blocks
        .push(foundation(LIMESTONE.name, -0.5, length + 0.5));
    let lintel_course = sill + tall;
    for c in 0..courses {
        // The segments of this course to fill with stones, and its lintels.
        let mut segments = vec![[0.0, length]];
        let mut lintels = Vec::new();
        for o in &openings {
            let gap = if n_open > 0 && (sill..lintel_course).contains(&c) {
                Some(*o)
            } else if n_open > 0 && c == lintel_course {
                let g = [o[0] - bearing, o[1] + bearing];
                lintels.push(g);
                Some(g)
            } else {
                None
            };
            if let Some([g0, g1]) = gap {
                segments = segments
                    .into_iter()
                    .flat_map(|[a, b]| {
                        let mut out = Vec::new();
                        if g0 > a {
                            out.push([a, g0.min(b)]);
                        }
                        if g1 < b {
                            out.push([g1.max(a), b]);
                        }
                        out
                    })
                    .collect();
            }
        }
        let lintels = lintels
            .into_iter()
            .enumerate()
            .map(|(i, g)| (g, format!("lintel{}", i + 1)))
            .collect();
        lay_course(&mut spec, LIMESTONE.name, c, h, l, &segments, lintels)?;
    }
    Ok(spec)
}
