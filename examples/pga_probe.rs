//! Probe (development aid): toppling of a column under a one-sine pulse at several amplitudes
//! and time steps. `cargo run --example pga_probe -- B H F A1 A2 ...`
use ashlar::analysis::pga::{evaluate, Criterion};
use ashlar::motion::{GroundMotion, Signal};
use ashlar::presets::Column;

/// The column of `presets::Column::SEED` with half-sizes b × h and φ = 85° (it rocks, never
/// slides).
fn column(b: f64, h: f64) -> Column {
    Column {
        half_width: b,
        half_height: h,
        ..Column::SEED.friction(85.0)
    }
}

fn main() {
    let a: Vec<f64> = std::env::args()
        .skip(1)
        .map(|s| s.parse().expect("number"))
        .collect();
    let (b, h, f) = (a[0], a[1], a[2]);
    for dt in [1e-3, 5e-4, 2e-4, 1e-4] {
        let scene = column(b, h)
            .scene(serde_json::json!({ "duration": 1.0 / f + 3.0, "time_step": dt }))
            .expect("scene");
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
