//! `arch`: a semicircular or pointed (equilateral) arch of voussoirs with radial joints, on two
//! piers or springing from the fixed foundation.
//!
//! Geometry: R is the radius of the centreline (the circle midway between intrados and
//! extrados), t = `thickness_ratio` · R the ring's thickness; the intrados and the extrados of
//! each voussoir are drawn as chords between its joints (the joints' end points lie exactly on
//! the circles R ∓ t/2, so hinges form where the statics puts them). A semicircular arch spans
//! 2R on the centreline; an equilateral pointed arch has its two centres at the opposite
//! springings, spans R on the centreline, and meets at a vertical joint at the apex.
use super::common::*;
use super::{Kind, Param, TemplateError, Values};
use crate::scene::spec::SceneSpec;
use std::f64::consts::PI;

pub fn params() -> Vec<Param> {
    vec![
        Param {
            name: "shape",
            units: "",
            description: "semicircular, or pointed (equilateral: centres at the springings)",
            kind: Kind::Choice {
                default: "semicircular",
                choices: &["semicircular", "pointed"],
            },
        },
        integer(
            "voussoirs",
            "number of voussoirs (even for a pointed arch)",
            15,
            3,
            200,
        ),
        number(
            "radius",
            "m",
            "radius R of the ring's centreline",
            2.0,
            0.2,
            30.0,
        ),
        // 0.15 stands with a margin over Heyman's minimum t/R ≈ 0.106 of the semicircle.
        number(
            "thickness_ratio",
            "1",
            "ring thickness over the centreline radius, t/R",
            0.15,
            0.02,
            0.5,
        ),
        number(
            "pier_height",
            "m",
            "height of the two piers (0: the arch springs from the fixed foundation)",
            1.5,
            0.0,
            30.0,
        ),
        number(
            "pier_width",
            "m",
            "width of each pier, its inner face flush with the intrados",
            0.8,
            0.05,
            20.0,
        ),
        friction_param(),
    ]
}

pub fn arch(v: &Values) -> Result<SceneSpec, TemplateError> {
    let pointed = v.word("shape") == "pointed";
    let n = v.count("voussoirs");
    let r = v.num("radius");
    let t = v.num("thickness_ratio") * r;
    let (ri, re) = (r - 0.5 * t, r + 0.5 * t);
    let (pier_h, pier_w) = (v.num("pier_height"), v.num("pier_width"));
    if pointed && n % 2 == 1 {
        return Err(TemplateError::geometry(
            "voussoirs",
            format!(
                "a pointed arch has a joint at its apex, so an even number of voussoirs; got {n}"
            ),
        ));
    }
    if pier_h > 0.0 && pier_w < t {
        return Err(TemplateError::geometry(
            "pier_width",
            format!(
                "a pier must carry the whole ring, t = {} m thick; got {pier_w} m",
                tidy(t)
            ),
        ));
    }
    let name = format!(
        "{} arch: {n} voussoirs, R = {r} m, t/R = {}{}",
        if pointed { "pointed" } else { "semicircular" },
        v.num("thickness_ratio"),
        if pier_h > 0.0 {
            format!(", on piers {pier_h} m")
        } else {
            String::new()
        }
    );
    let mut spec = stone_scene(name, LIMESTONE, v.num("friction_angle"));
    let ys = pier_h;
    // The left half's centre (x) and its joints: (inner, outer) points, from the springing up.
    let left_joints: Vec<([f64; 2], [f64; 2])> = if pointed {
        let c = 0.5 * r;
        let m = n / 2;
        (0..=m)
            .map(|k| {
                if k == m {
                    // Apex: where each face meets the vertical x = 0.
                    let yi = (ri * ri - c * c).max(0.0).sqrt();
                    let yo = (re * re - c * c).sqrt();
                    ([0.0, ys + yi], [0.0, ys + yo])
                } else {
                    let a = PI - k as f64 * (PI / 3.0) / m as f64;
                    let (s, co) = a.sin_cos();
                    ([c + ri * co, ys + ri * s], [c + re * co, ys + re * s])
                }
            })
            .collect()
    } else {
        (0..=n)
            .map(|k| {
                let a = PI - k as f64 * PI / n as f64;
                let (s, co) = a.sin_cos();
                ([ri * co, ys + ri * s], [re * co, ys + re * s])
            })
            .collect()
    };
    if pointed && ri <= 0.5 * r {
        return Err(TemplateError::geometry(
            "thickness_ratio",
            "an equilateral pointed arch needs t/R < 1 so that its intrados closes at the apex",
        ));
    }
    let mirror = |p: [f64; 2]| [-p[0], p[1]];
    let joints_of_voussoir = |k: usize| -> ([f64; 2], [f64; 2], [f64; 2], [f64; 2]) {
        if pointed {
            let m = n / 2;
            if k < m {
                let (i0, o0) = left_joints[k];
                let (i1, o1) = left_joints[k + 1];
                (i0, i1, o1, o0)
            } else {
                // Right half: mirror of the left, counted from the apex down; mirroring flips
                // the orientation, so the points are listed the other way round.
                let j = n - 1 - k;
                let (i0, o0) = left_joints[j];
                let (i1, o1) = left_joints[j + 1];
                (mirror(i1), mirror(i0), mirror(o0), mirror(o1))
            }
        } else {
            let (i0, o0) = left_joints[k];
            let (i1, o1) = left_joints[k + 1];
            (i0, i1, o1, o0)
        }
    };
    let half_span_out = left_joints[0].1[0].abs();
    let half_span_in = left_joints[0].0[0].abs();
    let outer_reach = if pier_h > 0.0 {
        half_span_in + pier_w
    } else {
        half_span_out
    };
    spec.blocks.push(foundation(
        LIMESTONE.name,
        -outer_reach - 1.0,
        outer_reach + 1.0,
    ));
    if pier_h > 0.0 {
        spec.blocks.push(stone(
            "pier_left",
            LIMESTONE.name,
            rect(-half_span_in - pier_w, 0.0, -half_span_in, pier_h),
        ));
        spec.blocks.push(stone(
            "pier_right",
            LIMESTONE.name,
            rect(half_span_in, 0.0, half_span_in + pier_w, pier_h),
        ));
    }
    for k in 0..n {
        let (a, b, c, d) = joints_of_voussoir(k);
        spec.blocks.push(stone(
            format!("v{}", k + 1),
            LIMESTONE.name,
            vec![a, b, c, d],
        ));
    }
    Ok(spec)
}

#[cfg(test)]
mod tests {
    use super::super::build;
    use serde_json::Value;
    use std::collections::BTreeMap;

    #[test]
    fn voussoirs_close_the_ring_and_pointed_needs_even() {
        let mut g = BTreeMap::new();
        g.insert("voussoirs".to_string(), Value::from(40));
        g.insert("pier_height".to_string(), Value::from(0.0));
        let (spec, _) = build("arch", &g).unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(spec.blocks.len(), 41);
        // The crown joint (between v20 and v21) is vertical at x = 0.
        let v20 = &spec.blocks[20].vertices;
        assert!(
            v20.iter().filter(|p| p[0].abs() < 1e-9).count() == 2,
            "{v20:?}"
        );
        g.insert("shape".to_string(), Value::from("pointed"));
        g.insert("voussoirs".to_string(), Value::from(15));
        let e = build("arch", &g).expect_err("must be refused");
        assert_eq!(e.parameter(), Some("voussoirs"));
        g.insert("voussoirs".to_string(), Value::from(16));
        build("arch", &g).unwrap_or_else(|e| panic!("{e}"));
    }
}
