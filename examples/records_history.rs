//! Where the full engine's Δt error on a record arises (docs/accuracy-vs-speed.md, "Records",
//! "Where the 1 ms error comes from"): one column of `analysis::study_records` under one record
//! at one PGA, the engine at the default Δt and at 1e-4 s and Housner's equation (RK4 at 1e-5 s),
//! each history cut into half-cycles (from a lift-off or an impact to the next impact). Prints
//! per half-cycle: start time, |θ̇| at its start (after the impact), peak |θ|, for the three;
//! the growth of the difference between the two engine runs tells the phase that makes it:
//! the impact (ω after it differs with ω before equal), the free rocking (the peak differs with
//! the start equal) or the lift-off (the first half-cycle).
//! Run: `cargo run --example records_history -- [column 0|1] [record] [PGA g] [variant]`
//! (default: 0, Friuli, 0.6; variant: `new` (the defaults) or modifiers joined by `+`: `trap`
//! (trapezoidal rule), `stale` (`restart_after_impact` off: the trapezoidal rule as it was before
//! the restart), `avg` (`average_ground_load`), `rigid` (block model), `rock:C`, `err:R`, `nm:G` (Newmark γ = G,
//! β = (G + ½)²/4), `slow:F` (`impact.slow_factor`), `dt:S` (the coarse run's step), `fine:S` (the reference run's
//! step, 1e-4 s unless given), `hand` (`impact.hand_over_weight`), `hslow:F` (the hand-over with its own
//! threshold, `impact.hand_over_below` = F), `vsnew` (the second run is the defaults at the default step
//! instead of the 1e-4 s one); the reference run takes the same modifiers except `rock`, `err`, `dt`).
use ashlar::analysis::reference::{half_cycles, housner_rocking, HousnerColumn};
use ashlar::analysis::study_records::{self as sr, COLUMNS};
use ashlar::assembly::Newmark;
use ashlar::scene::scene_from_value;
use ashlar::simulation::{SimParams, Simulation};
use serde_json::json;
use std::path::Path;

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let col = &COLUMNS[args.first().and_then(|s| s.parse().ok()).unwrap_or(0)];
    let rec = args.get(1).map_or(sr::RECORDS[0], |s| s.as_str());
    let pga: f64 = args.get(2).and_then(|s| s.parse().ok()).unwrap_or(0.6);
    let variant = args.get(3).map_or("new", |s| s.as_str());
    let m = sr::load_record(Path::new("data/ground-motions"), rec, pga).expect("record");
    let t_end = sr::run_length(&m);
    let run = |control: serde_json::Value, params: SimParams| {
        let scene = scene_from_value(&sr::column_scene(col, &control)).expect("scene");
        let mut sim = Simulation::new(&scene, &m, params);
        let mut h = Vec::new();
        while sim.time() < t_end - 1e-12 {
            sim.step(t_end - sim.time()).expect("step");
            let th = sim.geoms()[1].rotation;
            h.push((sim.time(), th, sim.block_velocity(1)[2]));
            if th.abs() > sr::FALLEN {
                break;
            }
        }
        (h, sim.stats().steps, sim.stats().impacts)
    };
    // The variant: modifiers joined by '+', each applied to the defaults in turn; the 1e-4 s
    // run takes the same ones except the step ones (`rock:`, `dt:`).
    let mut coarse_c = json!({});
    let mut coarse_p = SimParams::default();
    let mut fine_p = SimParams::default();
    let mut fine_c = json!({ "time_step": 1e-4 });
    let mut vs_new = false;
    for v in variant.split('+') {
        match v {
            "new" | "old" => {}
            "trap" => {
                coarse_c["integrator"] = json!("trapezoidal");
                fine_c["integrator"] = json!("trapezoidal");
            }
            "avg" => {
                coarse_p.average_ground_load = true;
                fine_p.average_ground_load = true;
            }
            "stale" => {
                coarse_p.restart_after_impact = false;
                fine_p.restart_after_impact = false;
            }
            "rigid" => {
                coarse_c["block_model"] = json!("rigid");
                fine_c["block_model"] = json!("rigid");
            }
            v if v.starts_with("rock:") => {
                coarse_p.rocking_velocity_change = Some(v[5..].parse().expect("ratio"))
            }
            v if v.starts_with("nm:") => {
                // Newmark γ with β = (γ + ½)²/4 (second order at γ = ½, damped above).
                let gamma: f64 = v[3..].parse().expect("gamma");
                let nm = Newmark {
                    beta: 0.25 * (gamma + 0.5).powi(2),
                    gamma,
                };
                coarse_p.newmark = Some(nm);
                fine_p.newmark = Some(nm);
            }
            v if v.starts_with("slow:") => {
                let f = v[5..].parse().expect("factor");
                coarse_p.impact.slow_factor = f;
                fine_p.impact.slow_factor = f;
            }
            v if v.starts_with("err:") => {
                coarse_p.local_error_ratio = Some(v[4..].parse().expect("ratio"))
            }
            v if v.starts_with("dt:") => {
                coarse_c["time_step"] = json!(v[3..].parse::<f64>().expect("dt"))
            }
            v if v.starts_with("fine:") => {
                fine_c["time_step"] = json!(v[5..].parse::<f64>().expect("dt"))
            }
            // ImpactParams::hand_over_weight (with `slow:0`: session 35's `hand`).
            "hand" => {
                for p in [&mut coarse_p, &mut fine_p] {
                    p.impact.hand_over_weight = true;
                    p.impact.hand_over_below = None;
                }
            }
            // The hand-over with its own threshold F (ImpactParams::hand_over_below).
            v if v.starts_with("hslow:") => {
                let f = v[6..].parse().expect("factor");
                for p in [&mut coarse_p, &mut fine_p] {
                    p.impact.hand_over_weight = true;
                    p.impact.hand_over_below = Some(f);
                }
            }
            // The second run is the defaults at the default step instead (a variant against
            // the defaults, landing by landing).
            "vsnew" => vs_new = true,
            v => panic!("unknown variant {v}"),
        }
    }
    if vs_new {
        fine_c = json!({});
        fine_p = SimParams::default();
    }
    let (coarse, n_coarse, i_coarse) = run(coarse_c, coarse_p);
    let (fine, n_fine, i_fine) = run(fine_c, fine_p);
    let mut hh = Vec::new();
    housner_rocking(
        &HousnerColumn {
            b: col.b,
            h: col.h,
            g: sr::G,
            dt: sr::HOUSNER_DT,
        },
        |t| m.acceleration(t)[0],
        t_end,
        |s| {
            hh.push((s.t, s.theta, s.omega));
            s.theta.abs() > sr::FALLEN
        },
    );
    let (a, b, c) = (half_cycles(&coarse), half_cycles(&fine), half_cycles(&hh));
    println!(
        "{} {rec} {pga} g, {variant}: {n_coarse} steps {i_coarse} impacts, fine: {n_fine} steps {i_fine} impacts",
        col.name
    );
    let peak = |h: &[(f64, f64, f64)]| h.iter().fold(0.0f64, |m, x| m.max(x.1.abs()));
    let (pc, pf, ph) = (peak(&coarse), peak(&fine), peak(&hh));
    println!(
        "peak {variant} {pc:.5} ({:+.2} % vs Housner, {:+.2} % vs fine) | fine {pf:.5} ({:+.2} % vs Housner) | Housner {ph:.5}",
        100.0 * (pc / ph - 1.0),
        100.0 * (pc / pf - 1.0),
        100.0 * (pf / ph - 1.0)
    );
    println!("k | start s: {variant} / 1e-4 / Housner | |ω| at start rad/s | peak |θ| rad | peak {variant} vs 1e-4");
    for k in 0..a.len().max(b.len()).max(c.len()) {
        let f = |v: &[(f64, f64, f64)], i: usize| v.get(k).map(|x| [x.0, x.1, x.2][i]);
        let s = |x: Option<f64>, p: usize| x.map_or("-".into(), |x| format!("{x:.p$}"));
        let rel = match (f(&a, 2), f(&b, 2)) {
            (Some(x), Some(y)) => format!("{:+.2} %", 100.0 * (x / y - 1.0)),
            _ => "-".into(),
        };
        println!(
            "{k} | {} / {} / {} | {} / {} / {} | {} / {} / {} | {rel}",
            s(f(&a, 0), 4),
            s(f(&b, 0), 4),
            s(f(&c, 0), 4),
            s(f(&a, 1), 4),
            s(f(&b, 1), 4),
            s(f(&c, 1), 4),
            s(f(&a, 2), 5),
            s(f(&b, 2), 5),
            s(f(&c, 2), 5),
        );
    }
}
