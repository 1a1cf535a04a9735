//! Why the reduced rocking model's peak differs from the converged engine's at a point of the
//! hand-over study (docs/accuracy-vs-speed.md, "Reduced models on records"): three independent
//! answers for one column of `examples/handover_study.rs` under one record at one PGA, each
//! history cut into half-cycles (from a lift-off or an impact to the next impact):
//! (r) the reduced model as `auto` runs it (`analysis::reduced`, adaptive Dormand–Prince with
//! located impacts), (h) Housner's equation (`analysis::reference`, RK4 at 1e-5 s, the same
//! restitution), (e) the full engine (`"model": "dda"`) at Δt = 1e-4 s. Prints per half-cycle:
//! start time, |θ̇| at its start, peak |θ|, for the three.
//!
//! Run: `cargo run --release --example reduced_history -- SCENE RECORD PGA [T_END]`, SCENE one of
//! `column` (examples/column.json), `slender` (0.24 × 1.6 m, φ = 75°), `slender9` (the same over
//! the record's first 9 s); PGA in m/s² (handover.md's column); T_END cuts every run (s).
//! Diagnosis switches of the engine run (SLOW, HOVER, GROUP, SPLIT, AVG, DUAL, DTOL, KPEN, EDT, HAND), the
//! per-landing ratio r (LAND0, LAND1) and a sample dump (DUMP0, DUMP1): docs/accuracy-vs-speed.md,
//! "Micro-rocking: what parts the engine from Housner (session 34)".
use ashlar::analysis::reduced::{self, Modes, Phase, Reduced, ReducedParams};
use ashlar::analysis::reference::{half_cycles, housner_rocking, landings, HousnerColumn, Landing};
use ashlar::analysis::run::duration;
use ashlar::presets::{self, Column};
use ashlar::scene::{parse_scene, ModelChoice, Scene};
use ashlar::simulation::{SimParams, Simulation};
use serde_json::json;

/// Past this |θ| (rad) a run stops: the column has fallen (handover_study stops at 60°).
const FALLEN: f64 = 1.0;

fn scene_of(name: &str) -> Scene {
    let slender = || Column::SLENDER.json(json!({})).to_string();
    match name {
        "column" => parse_scene(presets::EXAMPLE_COLUMN).expect("column"),
        "slender" => parse_scene(&slender()).expect("slender"),
        "slender9" => {
            let mut s = parse_scene(&slender()).expect("slender");
            s.control.duration = Some(9.0);
            s
        }
        other => panic!("unknown scene {other}"),
    }
}

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let scene = scene_of(args.first().map_or("column", |s| s.as_str()));
    let rec = args
        .get(1)
        .map_or("loma-prieta-1989-capitola-000.at2", |s| s.as_str());
    let pga: f64 = args.get(2).and_then(|s| s.parse().ok()).unwrap_or(5.371);
    let gm = presets::record(rec).expect("record").scaled_to_pga(pga);
    let mut t_end = duration(&scene, &gm).expect("duration");
    if let Some(t) = args.get(3).and_then(|s| s.parse::<f64>().ok()) {
        t_end = t_end.min(t);
    }
    // (r) the reduced model, as `auto` runs it, sampled every 0.1 ms.
    let env = |k: &str| std::env::var(k).ok().and_then(|v| v.parse::<f64>().ok());
    let mut params = ReducedParams::default();
    if let Some(r) = env("RTOL") {
        params.tolerance.rtol = r;
        params.tolerance.atol = 1e-2 * r;
    }
    if let Some(s) = env("MAXSTEP") {
        params.max_step = s;
    }
    let block = reduced::qualify(&scene, &params).expect("one block on a base");
    let (b, h) = (0.5 * block.pivots[1], block.centroid.y);
    let mut m = Reduced::new(block.clone(), &gm, params, Modes::Auto);
    let mut hr = Vec::new();
    let mut violation = None;
    while m.time < t_end - 1e-12 {
        let next = (m.time + 1e-4).min(t_end);
        if let Err(v) = m.advance(next) {
            violation = Some(v);
            break;
        }
        let (th, w) = match m.phase {
            Phase::Rocking { theta, omega, .. } => (theta, omega),
            Phase::Fallen { theta, .. } => (theta, 0.0),
            _ => (0.0, 0.0),
        };
        hr.push((m.time, th, w));
        if th.abs() > FALLEN {
            break;
        }
    }
    // (h) Housner's equation by RK4 at 1e-5 s.
    let mut hh = Vec::new();
    housner_rocking(
        &HousnerColumn {
            b,
            h,
            g: scene.gravity,
            dt: env("HDT").unwrap_or(1e-5),
        },
        |t| gm.acceleration(t)[0],
        t_end,
        |s| {
            hh.push((s.t, s.theta, s.omega));
            s.theta.abs() > FALLEN
        },
    );
    // (e) the engine at 1e-4 s.
    let mut fine = scene.clone();
    fine.control.model = ModelChoice::Dda;
    fine.control.time_step = env("EDT").unwrap_or(1e-4);
    // Diagnosis of the engine's contact handling in micro-rocking (docs/accuracy-vs-speed.md,
    // "Micro-rocking"): SLOW = ImpactParams::slow_factor, HOVER/GROUP/SPLIT = 0 turn off
    // close_hover/group_landings/split_before, KPEN = penalty stiffness (N/m) in place of 10 E,
    // DUAL = 1 the dual (penalty-free) contact solver, AVG = 1 SimParams::average_ground_load,
    // EDT = the engine's Δt (s), HAND = 1 ImpactParams::hand_over_weight with no threshold of its
    // own (session 35), HAND = 0 no hand-over (unset: the defaults, `hand_over_below` 2), DTOL = the dual solver's
    // tolerance.
    let mut sp = SimParams::default();
    if let Some(f) = env("SLOW") {
        sp.impact.slow_factor = f;
    }
    let off = |k: &str| env(k) == Some(0.0);
    sp.impact.close_hover &= !off("HOVER");
    sp.impact.group_landings &= !off("GROUP");
    sp.impact.split_before &= !off("SPLIT");
    if env("AVG") == Some(1.0) {
        sp.average_ground_load = true;
    }
    if let Some(h) = env("HAND") {
        sp.impact.hand_over_weight = h == 1.0;
        sp.impact.hand_over_below = None;
    }
    if env("DUAL") == Some(1.0) {
        fine.control.contact_solver = ashlar::scene::ContactSolver::Dual;
    }
    if let Some(t) = env("DTOL") {
        // The dual solver's tolerance (DualParams::tolerance, fraction of the smallest block's
        // half size).
        fine.control.dual_tolerance = Some(t);
    }
    if let Some(k) = env("KPEN") {
        fine.control.penalty_stiffness = ashlar::scene::Penalty::Value(k);
    }
    let mut sim = Simulation::new(&fine, &gm, sp);
    let mut he = Vec::new();
    let free = block.free;
    let engine_end = if env("ENGINE") == Some(0.0) {
        0.0
    } else {
        t_end
    };
    while sim.time() < engine_end - 1e-12 {
        // As `analysis::run` steps (to each output frame) unless FRAMES=0.
        let limit = if env("FRAMES") == Some(0.0) {
            t_end
        } else {
            let every = fine.control.output_interval;
            (((sim.time() + 1e-9 * every) / every).floor() + 1.0) * every
        };
        sim.step(limit.min(t_end) - sim.time()).expect("step");
        let th = sim.geoms()[free].rotation;
        he.push((sim.time(), th, sim.block_velocity(free)[2]));
        if th.abs() > FALLEN {
            break;
        }
    }
    if env("COND") == Some(1.0) {
        // Conditioning: the reduced model's and Housner's peaks (and falls) at nearby PGAs.
        for f in [0.97, 0.99, 1.0, 1.01, 1.03] {
            let g2 = gm.scaled_to_pga(pga * f);
            let mut mr = Reduced::new(block.clone(), &g2, params, Modes::Rocking);
            let mut pr = 0.0f64;
            while mr.time < t_end - 1e-12 {
                let next = (mr.time + 1e-3).min(t_end);
                let _ = mr.advance(next);
                let th = match mr.phase {
                    Phase::Rocking { theta, .. } | Phase::Fallen { theta, .. } => theta,
                    _ => 0.0,
                };
                pr = pr.max(th.abs());
                if pr > FALLEN {
                    break;
                }
            }
            let mut ph = 0.0f64;
            housner_rocking(
                &HousnerColumn {
                    b,
                    h,
                    g: scene.gravity,
                    dt: env("HDT").unwrap_or(1e-5),
                },
                |t| g2.acceleration(t)[0],
                t_end,
                |s| {
                    ph = ph.max(s.theta.abs());
                    ph > FALLEN
                },
            );
            println!("{f} × PGA: reduced (forced rocking) peak {pr:.5}, Housner {ph:.5}");
        }
    }
    if let (Some(t0), Some(t1)) = (env("DUMP0"), env("DUMP1")) {
        // The three histories sample by sample over [DUMP0, DUMP1] s (engine samples; Housner's
        // nearest sample), for the landings of micro-rocking.
        for &(t, th, w) in he.iter().filter(|x| x.0 >= t0 && x.0 <= t1) {
            // Housner's samples are in time order: the nearest one by bisection.
            let k = hh
                .partition_point(|x| x.0 < t)
                .min(hh.len().saturating_sub(1));
            let j = if k > 0 && (hh[k - 1].0 - t).abs() < (hh[k].0 - t).abs() {
                k - 1
            } else {
                k
            };
            let (th_h, w_h) = hh.get(j).map_or((0.0, 0.0), |x| (x.1, x.2));
            println!(
                "dump t {t:.5} engine θ {th:+.3e} θ̇ {w:+.3e} | Housner θ {th_h:+.3e} θ̇ {w_h:+.3e} | ü_g {:+.4}",
                gm.acceleration(t)[0]
            );
        }
    }
    if let (Some(t0), Some(t1)) = (env("LAND0"), env("LAND1")) {
        // Per-landing angular-velocity ratio over [LAND0, LAND1] s, for the engine and Housner.
        // Landings split at the settling threshold of the default engine run (Δt = 1e-4 s),
        // whatever EDT, so that the classes are the same landings across Δt.
        let slow = 2.0 * scene.gravity.abs() * 1e-4 / (2.0 * b);
        for (name, v) in [("engine", &he), ("Housner", &hh)] {
            let rs = landings(v, t0, t1);
            let mean = |f: &dyn Fn(f64) -> bool| {
                let x: Vec<f64> = rs
                    .iter()
                    .filter(|l| f(l.before))
                    .map(Landing::ratio)
                    .collect();
                let m = x.iter().sum::<f64>() / x.len() as f64;
                (
                    x.len(),
                    if x.is_empty() {
                        "-".into()
                    } else {
                        format!("{m:.4}")
                    },
                )
            };
            let (ns, rs_slow) = mean(&|w| w < slow);
            let (nf, rs_fast) = mean(&|w| w >= slow);
            println!(
                "landings {name}: {ns} with |θ̇⁻| < 2g(1e-4 s)/2b = {slow:.5} rad/s, mean r {rs_slow}; {nf} faster, mean r {rs_fast}"
            );
        }
    }
    let (r, hs, e) = (half_cycles(&hr), half_cycles(&hh), half_cycles(&he));
    let peak = |v: &[(f64, f64, f64)]| v.iter().fold(0.0f64, |a, x| a.max(x.1.abs()));
    println!(
        "{rec} at {pga} m/s², b = {b} m, h = {h} m, mu = {:.3}, to {t_end} s; reduced: {} steps, {} impacts, violation {:?}; engine: {} steps, {} impacts",
        block.mu,
        m.stats.steps,
        m.stats.impacts,
        violation.map(|v| v.what),
        sim.stats().steps,
        sim.stats().impacts
    );
    println!(
        "peak |θ|: reduced {:.5}, Housner {:.5}, engine 1e-4 s {:.5}",
        peak(&hr),
        peak(&hh),
        peak(&he)
    );
    println!("| half-cycle | start, s (reduced / Housner / engine) | \\|θ̇\\| at start, rad/s | peak \\|θ\\|, rad |");
    println!("|---|---|---|---|");
    for k in 0..r.len().max(hs.len()).max(e.len()) {
        let f = |v: &[(f64, f64, f64)], i: usize| v.get(k).map(|x| [x.0, x.1, x.2][i]);
        let s = |x: Option<f64>, p: usize| x.map_or("-".into(), |x| format!("{x:.p$}"));
        println!(
            "| {k} | {} / {} / {} | {} / {} / {} | {} / {} / {} |",
            s(f(&r, 0), 4),
            s(f(&hs, 0), 4),
            s(f(&e, 0), 4),
            s(f(&r, 1), 4),
            s(f(&hs, 1), 4),
            s(f(&e, 1), 4),
            s(f(&r, 2), 5),
            s(f(&hs, 2), 5),
            s(f(&e, 2), 5),
        );
    }
}
