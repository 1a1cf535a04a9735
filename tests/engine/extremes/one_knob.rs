//! Extremes, one knob at a time: penalty, time step, friction, cohesion and tension, aspect
//! ratio, block size, density, Young's modulus, PGA, a quiet scene for 1e4 s.
use super::*;

// ---------------------------------------------------------------------------------------------
// One knob at a time

#[test]
fn penalty_stiffness_sweep() {
    run_cases(vec![
        (
            "penalty 1e4 N/m",
            Knobs {
                penalty: Some(1e4),
                ..k()
            },
            Diagnostic,
        ),
        (
            "penalty 1e6 N/m",
            Knobs {
                penalty: Some(1e6),
                ..k()
            },
            Diagnostic,
        ),
        (
            "penalty 1e8 N/m",
            Knobs {
                penalty: Some(1e8),
                ..k()
            },
            Complete,
        ),
        (
            "penalty 1e10 N/m",
            Knobs {
                penalty: Some(1e10),
                ..k()
            },
            Complete,
        ),
        (
            "penalty 1e12 N/m",
            Knobs {
                penalty: Some(1e12),
                ..k()
            },
            Complete,
        ),
        (
            "penalty 1e15 N/m",
            Knobs {
                penalty: Some(1e15),
                ..k()
            },
            Complete,
        ),
    ]);
}

#[test]
fn time_step_sweep() {
    run_cases(vec![
        ("Δt 1e-7 s", Knobs { dt: 1e-7, ..k() }, Complete),
        ("Δt 1e-5 s", Knobs { dt: 1e-5, ..k() }, Complete),
        ("Δt 1e-3 s", Knobs { dt: 1e-3, ..k() }, Complete),
        ("Δt 1e-2 s", Knobs { dt: 1e-2, ..k() }, Complete),
        (
            "Δt 0.1 s (adaptive)",
            Knobs {
                dt: 0.1,
                duration: 2.0,
                ..k()
            },
            Complete,
        ),
        (
            "Δt 0.1 s (fixed)",
            Knobs {
                dt: 0.1,
                adaptive: false,
                duration: 2.0,
                ..k()
            },
            Complete,
        ),
    ]);
}

#[test]
fn friction_sweep() {
    run_cases(vec![
        (
            "friction 0°",
            Knobs {
                friction_deg: 0.0,
                ..k()
            },
            Complete,
        ),
        (
            "friction 10°",
            Knobs {
                friction_deg: 10.0,
                ..k()
            },
            Complete,
        ),
        (
            "friction 45°",
            Knobs {
                friction_deg: 45.0,
                ..k()
            },
            Complete,
        ),
        (
            "friction 80°",
            Knobs {
                friction_deg: 80.0,
                ..k()
            },
            Complete,
        ),
        (
            "friction 89°",
            Knobs {
                friction_deg: 89.0,
                ..k()
            },
            Complete,
        ),
    ]);
}

#[test]
fn cohesion_and_tension_sweep() {
    run_cases(vec![
        (
            "cohesion 1e4 Pa",
            Knobs {
                cohesion: 1e4,
                ..k()
            },
            Complete,
        ),
        (
            "cohesion 1e8 Pa",
            Knobs {
                cohesion: 1e8,
                ..k()
            },
            Complete,
        ),
        (
            "tensile 1e4 Pa",
            Knobs {
                tensile: 1e4,
                ..k()
            },
            Complete,
        ),
        (
            "tensile 1e8 Pa",
            Knobs {
                tensile: 1e8,
                ..k()
            },
            Complete,
        ),
        (
            "cohesion + tensile 1e8 Pa, 5 g",
            Knobs {
                cohesion: 1e8,
                tensile: 1e8,
                pga_g: 5.0,
                ..k()
            },
            Complete,
        ),
    ]);
}

#[test]
fn aspect_ratio_sweep() {
    run_cases(vec![
        (
            "slab 1:50",
            Knobs {
                width: 5.0,
                height: 0.1,
                ..k()
            },
            Complete,
        ),
        (
            "slab 1:500",
            Knobs {
                width: 5.0,
                height: 0.01,
                ..k()
            },
            Complete,
        ),
        (
            "needle 1:50",
            Knobs {
                width: 0.1,
                height: 5.0,
                ..k()
            },
            Complete,
        ),
        (
            "needle 1:500",
            Knobs {
                width: 0.01,
                height: 5.0,
                ..k()
            },
            // Completes since the narrow phase stopped taking phantom penetrations of
            // vertices outside the edge block (contact/vertex_edge.rs): before, a vertex was
            // "found" 1.1 cm deep and the run stopped with `PenaltyTooSoft` after the energy
            // had grown by 2.8 × the scale. Energy and penetration are checked as for every
            // completed case.
            Complete,
        ),
    ]);
}

#[test]
fn block_size_sweep() {
    run_cases(vec![
        (
            "size 1 mm",
            Knobs {
                width: 1e-3,
                height: 1e-3,
                ..k()
            },
            Complete,
        ),
        (
            "size 1 cm",
            Knobs {
                width: 1e-2,
                height: 1e-2,
                ..k()
            },
            Complete,
        ),
        (
            "size 10 m",
            Knobs {
                width: 10.0,
                height: 10.0,
                ..k()
            },
            Complete,
        ),
        (
            "size 100 m",
            Knobs {
                width: 100.0,
                height: 100.0,
                ..k()
            },
            Complete,
        ),
    ]);
}

#[test]
fn density_sweep() {
    run_cases(vec![
        (
            "density 1 kg/m³",
            Knobs {
                density: 1.0,
                ..k()
            },
            Complete,
        ),
        (
            "density 1e5 kg/m³",
            Knobs {
                density: 1e5,
                ..k()
            },
            Complete,
        ),
    ]);
}

#[test]
fn young_modulus_sweep() {
    run_cases(vec![
        (
            "E 1e5 Pa (deformable, auto penalty)",
            Knobs {
                young: 1e5,
                model: "deformable",
                ..k()
            },
            Diagnostic,
        ),
        (
            "E 1e7 Pa (deformable)",
            Knobs {
                young: 1e7,
                model: "deformable",
                ..k()
            },
            Complete,
        ),
        (
            "E 1e13 Pa (deformable)",
            Knobs {
                young: 1e13,
                model: "deformable",
                ..k()
            },
            Complete,
        ),
        ("E 1e13 Pa (rigid)", Knobs { young: 1e13, ..k() }, Complete),
    ]);
}

#[test]
fn pga_sweep() {
    run_cases(vec![
        ("PGA 0", Knobs { pga_g: 0.0, ..k() }, Complete),
        ("PGA 1 g", Knobs { pga_g: 1.0, ..k() }, Complete),
        ("PGA 5 g", Knobs { pga_g: 5.0, ..k() }, Complete),
        ("PGA 20 g", Knobs { pga_g: 20.0, ..k() }, Complete),
        ("PGA 50 g", Knobs { pga_g: 50.0, ..k() }, Complete),
    ]);
}

#[test]
fn quiet_scene_for_1e4_s() {
    run_cases(vec![(
        "quiet stack, 1e4 s at Δt ≤ 1 s",
        Knobs {
            pga_g: 0.0,
            dt: 1.0,
            duration: 1e4,
            budget: 20_000,
            ..k()
        },
        Complete,
    )]);
}
