//! Effective restitution of the engine's rocking impact: a rigid column (half-sizes b × h)
//! released from rest at a tilt θ0 about its right corner rocks back onto its base; the ratio
//! of the angular velocity just after the first impact to just before it is the engine's
//! coefficient of restitution r, compared with Housner's r = 1 − 1.5 sin²α. Prints a table.
//! Run: `cargo run --release --example rocking_restitution`
use ashlar::motion::GroundMotion;
use ashlar::presets::{scene_json, Column};
use ashlar::scene::parse_scene;
use ashlar::simulation::{SimParams, Simulation};

fn measure(b: f64, h: f64, theta0: f64, dt: Option<f64>) -> (f64, f64) {
    let alpha = (b / h).atan();
    // Rectangle rotated clockwise by θ0 about its bottom-right corner (b, 0).
    let (c, s) = (theta0.cos(), theta0.sin());
    let rot = |x: f64, y: f64| {
        let (dx, dy) = (x - b, y);
        [b + c * dx + s * dy, -s * dx + c * dy]
    };
    let v = [rot(-b, 0.0), rot(b, 0.0), rot(b, 2.0 * h), rot(-b, 2.0 * h)];
    let mut control = serde_json::json!({ "duration": 3.0 });
    if let Some(dt) = dt {
        control["time_step"] = serde_json::json!(dt);
    }
    // The column of `presets::Column::SEED` with half-sizes b × h and φ = 85° (it rocks, never
    // slides), tilted.
    let column = Column {
        half_width: b,
        half_height: h,
        ..Column::SEED.friction(85.0)
    };
    let mut blocks = column.blocks();
    blocks[1]["vertices"] = serde_json::json!(v);
    let scene = scene_json(blocks, column.friction_angle, control);
    let scene = parse_scene(&scene.to_string()).expect("scene");
    let mut sim = Simulation::new(&scene, &GroundMotion::none(), SimParams::default());
    // Upright when the accumulated rotation is +θ0 (counter-clockwise back); after the impact
    // the column tilts the other way to its peak θ1 = max rotation − θ0, where ω changes sign.
    // Energy on either side of the impact gives r² = (cos(α − θ1) − cos α)/(cos(α − θ0) − cos α),
    // free of the gravity torque that acts while ω is sampled.
    let mut hit = false;
    let mut peak = f64::NEG_INFINITY;
    while sim.time() < 3.0 {
        sim.step(f64::INFINITY).expect("step");
        let th = sim.geoms()[1].rotation;
        let w = sim.block_velocity(1)[2];
        if !hit {
            hit = th >= theta0;
        } else {
            peak = peak.max(th);
            if w < 0.0 {
                break;
            }
        }
    }
    let theta1 = peak - theta0;
    let r = ((alpha - theta1).cos() - alpha.cos()) / ((alpha - theta0).cos() - alpha.cos());
    (r.sqrt(), 1.0 - 1.5 * alpha.sin().powi(2))
}

fn main() {
    println!("| column b × h (m) | θ0/α | Δt | engine r | Housner r |");
    println!("|---|---|---|---|---|");
    for (b, h) in [(0.2f64, 0.6f64), (0.1, 0.8)] {
        let alpha: f64 = (b / h).atan();
        for f in [0.5, 0.9] {
            for dt in [None, Some(1e-4)] {
                let (r, hr) = measure(b, h, f * alpha, dt);
                println!(
                    "| {b} × {h} | {f} | {} | {r:.4} | {hr:.4} |",
                    dt.map_or("default".into(), |d| format!("{d:e}"))
                );
            }
        }
    }
}
