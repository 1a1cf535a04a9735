//! Probe (development aid): toppling of a column under a one-sine pulse at several amplitudes
//! and time steps. `cargo run --example pga_probe -- B H F A1 A2 ...`
use ashlar::analysis::pga::{evaluate, Criterion};
use ashlar::motion::{GroundMotion, Signal};
use ashlar::scene::parse_scene;

fn main() {
    let a: Vec<f64> = std::env::args()
        .skip(1)
        .map(|s| s.parse().expect("number"))
        .collect();
    let (b, h, f) = (a[0], a[1], a[2]);
    for dt in [1e-3, 5e-4, 2e-4, 1e-4] {
        let scene = serde_json::json!({
            "format": "ashlar.scene/1", "gravity": 9.81,
            "materials": { "stone": { "density": 2500.0, "young_modulus": 2.0e10, "poisson_ratio": 0.2 } },
            "joints": { "j": { "friction_angle": 85.0 } },
            "blocks": [
                { "id": "base", "material": "stone", "fixed": true, "vertices": [[-1.0, -0.5], [1.0, -0.5], [1.0, 0.0], [-1.0, 0.0]] },
                { "id": "column", "material": "stone", "block_model": "rigid", "vertices": [[-b, 0.0], [b, 0.0], [b, 2.0 * h], [-b, 2.0 * h]] },
            ],
            "control": { "duration": 1.0 / f + 3.0, "time_step": dt },
        });
        let scene = parse_scene(&scene.to_string()).expect("scene");
        let pulse = GroundMotion::horizontal(Signal::Pulse {
            amplitude: 1.0,
            period: 1.0 / f,
            cycles: 1.0,
            phase: 0.0,
        });
        let c = [Criterion::parse("toppled:column").expect("c")];
        let out: Vec<String> = a[3..]
            .iter()
            .map(|&amp| {
                format!(
                    "{amp}:{}",
                    if evaluate(&scene, &pulse, &c, amp, None).expect("run") {
                        "X"
                    } else {
                        "."
                    }
                )
            })
            .collect();
        println!("dt {dt:e}: {}", out.join(" "));
    }
}
