//! `pyramid`: the section of a stepped pyramid through its apex. Tiers of running-bond courses,
//! each tier set back from the one below on both sides. `section = corbelled` opens a corbelled
//! chamber on the axis: from the foundation up, each course's two halves project `corbel` m
//! further over the chamber than the course below, until the gap closes under a solid course.
use super::common::*;
use super::{Kind, Param, TemplateError, Values};
use crate::scene::spec::SceneSpec;

pub fn params() -> Vec<Param> {
    vec![
        Param {
            name: "section",
            units: "",
            description: "stepped (solid courses), or corbelled (a corbel-vaulted chamber on the axis)",
            kind: Kind::Choice {
                default: "stepped",
                choices: &["stepped", "corbelled"],
            },
        },
        number(
            "chamber_width",
            "m",
            "corbelled: width of the chamber at its floor",
            0.9,
            0.1,
            100.0,
        ),
        number(
            "corbel",
            "m",
            "corbelled: how far each course projects over the one below, each side (< 0.2 stone, so that the shortest stone's centre stays over its support)",
            0.15,
            0.01,
            2.0,
        ),
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
    let corbelled = v.word("section") == "corbelled";
    let (chamber, corbel) = (v.num("chamber_width"), v.num("corbel"));
    // Courses with an open chamber: its width chamber − 2·corbel·c stays > 0.
    let open = if corbelled {
        (chamber / (2.0 * corbel) - 1e-9).ceil() as usize
    } else {
        0
    };
    if corbelled {
        if corbel >= 0.2 * l {
            return Err(TemplateError::geometry(
                "corbel",
                format!("a corbel of {corbel} m is at least 0.2 of a {l} m stone: the shortest stone (0.4 of one) would tip into the chamber"),
            ));
        }
        if open >= tiers * per {
            return Err(TemplateError::geometry(
                "chamber_width",
                format!(
                    "a {chamber} m chamber corbelled {corbel} m a course needs {} courses to close, the pyramid has {}",
                    open + 1,
                    tiers * per
                ),
            ));
        }
    }
    let mut spec = skeleton(
        format!(
            "{} pyramid section: {tiers} tiers, {base} m at the base",
            if corbelled { "corbelled" } else { "stepped" }
        ),
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
            let gap = 0.5 * (chamber - 2.0 * corbel * c as f64);
            let pieces = if c < open {
                if half - gap < 0.4 * l {
                    return Err(TemplateError::geometry(
                        "chamber_width",
                        format!(
                            "course {}: the chamber leaves {} m of masonry each side, less than 0.4 stone",
                            c + 1,
                            tidy(half - gap)
                        ),
                    ));
                }
                let mut p = running_bond(-half, -gap, l, offset);
                p.extend(running_bond(gap, half, l, offset));
                p
            } else {
                running_bond(-half, half, l, offset)
            };
            for (k, [x0, x1]) in pieces.into_iter().enumerate() {
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
