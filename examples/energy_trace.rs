//! Mechanical energy of a scene's free blocks over a window, step by step, as `ashlar run` steps
//! it (frames every `control.output_interval`, the run-end extension after the record): kinetic,
//! gravitational (m g y of the centroids, from the start), springs, strain and their sum every
//! `--every` s, with the steps, Δt cuts, impacts and located steps in that interval, and the
//! energy each kind of step added (docs/energy-after-record.md).
//! Run: `cargo run --release --example energy_trace -- SCENE RECORD PGA_G [--from S] [--to S]
//! [--every S] [--no-hand-over] [--no-close-hover] [--no-group] [--cluster] [--blocks]
//! [--detail-from S --detail-to S] [--dump-at S --focus ID,…]`.
use ashlar::analysis::run_end::{self, RunEndParams};
use ashlar::motion::{self, LoadParams};
use ashlar::scene::parse_scene;
use ashlar::simulation::{SimParams, Simulation};
use std::path::Path;

/// Per-step energy changes summed by what the step did, J per m of thickness.
#[derive(Default, Clone, Copy)]
struct Split {
    /// Steps with an impact (the impact counter moved).
    impact: f64,
    /// Steps located before a predicted impact (no impact).
    located: f64,
    /// Other steps that followed a Δt cut (the cut counter moved during the attempt).
    cut: f64,
    /// All other steps.
    plain: f64,
    /// Largest single-step gain and its time.
    max_gain: f64,
    max_gain_t: f64,
}

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let flag = |name: &str| args.iter().any(|a| a == name);
    let value = |name: &str, d: f64| {
        args.iter()
            .position(|a| a == name)
            .and_then(|i| args.get(i + 1))
            .map_or(d, |v| v.parse().expect("number"))
    };
    let scene_path = args.first().expect("SCENE");
    let record = args.get(1).expect("RECORD");
    let pga_g: f64 = args.get(2).expect("PGA_G").parse().expect("PGA in g");
    let from = value("--from", 29.0);
    let to = value("--to", 37.5);
    let every = value("--every", 0.1);
    // Steps in this window are printed one by one (`#step` lines).
    // Before and after the step that starts at `--dump-at` (within 5e-8 s): the contacts of the
    // `--focus` blocks (comma-separated ids) and their velocities.
    let dump_at = value("--dump-at", f64::NAN);
    let focus: Vec<String> = args
        .iter()
        .position(|a| a == "--focus")
        .and_then(|i| args.get(i + 1))
        .map(|v| v.split(',').map(String::from).collect())
        .unwrap_or_default();
    let detail = (
        value("--detail-from", f64::INFINITY),
        value("--detail-to", f64::NEG_INFINITY),
    );
    let text = std::fs::read_to_string(scene_path).expect("scene file");
    let scene = parse_scene(&text).expect("scene");
    let gm = motion::load_path_with(Path::new(record), &LoadParams::default())
        .expect("record")
        .scaled_to_pga(pga_g * motion::STANDARD_GRAVITY);
    let mut params = SimParams::default();
    if flag("--no-hand-over") {
        params.impact = params.impact.without_hand_over();
    }
    if flag("--no-close-hover") {
        params.impact.close_hover = false;
    }
    if flag("--cluster") {
        params.impact.cluster = true;
    }
    if flag("--no-group") {
        params.impact.group_landings = false;
    }
    let duration = ashlar::analysis::run::duration(&scene, &gm).expect("duration");
    let cap = run_end::cap(duration, &gm, &RunEndParams::default());
    let floor = run_end::retirement_floor(&scene);
    let mut sim = Simulation::new(&scene, &gm, params);
    let interval = scene.control.output_interval;
    let free: Vec<usize> = (0..sim.geoms().len())
        .filter(|&b| sim.dofs().free_index[b].is_some())
        .collect();
    let weight = |sim: &Simulation, b: usize| {
        let g = &sim.geoms()[b];
        let rho = sim.scene().materials[sim.scene().blocks[b].material].density;
        rho * g.moments.area * sim.scene().gravity
    };
    let y0: Vec<f64> = sim.geoms().iter().map(|g| g.centroid.y).collect();
    let e0 = sim.energy();
    println!(
        "# duration {duration} s, cap {cap} s; energies J/m relative to t = 0 (gravity from the start)"
    );
    println!("t_s,kinetic,gravity,springs,strain,total,steps,cuts,impacts,located,dE_impact,dE_located,dE_cut,dE_plain,max_gain,max_gain_t,min_dt,top_block,top_block_E");
    let mut frame_index: u64 = 0;
    let mut next_report = from;
    let mut last = sim.stats();
    let mut split = Split::default();
    let mut min_dt = f64::INFINITY;
    while sim.time() < cap.min(to) - 1e-12 {
        let next_frame =
            ((frame_index + 1) as f64 * interval).min(run_end::horizon(sim.time(), duration, cap));
        let before = sim.stats();
        let e_full = sim.energy();
        let e_before = e_full.total();
        let block_e = |sim: &Simulation| -> Vec<f64> {
            free.iter()
                .map(|&b| {
                    run_end::kinetic_energy(sim, b)
                        + weight(sim, b) * (sim.geoms()[b].centroid.y - y0[b])
                })
                .collect()
        };
        let dump = (sim.time() - dump_at).abs() < 5e-8;
        if dump {
            dump_contacts(&sim, &focus);
        }
        let in_detail = sim.time() >= detail.0 && sim.time() <= detail.1;
        let blocks_before = if in_detail { block_e(&sim) } else { Vec::new() };
        let dt = sim.step(next_frame - sim.time()).expect("step");
        run_end::retire_fallen(&mut sim, floor);
        if sim.time() >= next_frame - 1e-9 * interval {
            frame_index += 1;
        }
        if sim.time() < from {
            continue;
        }
        if dump {
            println!("#dump after the step (t = {:.7})", sim.time());
            dump_contacts(&sim, &focus);
        }
        let after = sim.stats();
        let e_after = sim.energy();
        let de = e_after.total() - e_before;
        if in_detail {
            let mut changes: Vec<(f64, usize)> = block_e(&sim)
                .iter()
                .zip(&blocks_before)
                .enumerate()
                .map(|(i, (a, b))| (a - b, i))
                .collect();
            changes.sort_by(|a, b| b.0.abs().total_cmp(&a.0.abs()));
            let top: Vec<String> = changes
                .iter()
                .take(5)
                .map(|(d, i)| format!("{}:{:+.2}", sim.scene().blocks[free[*i]].id, d))
                .collect();
            println!(
                "#step t={:.7} dt={:.3e} dE={:+.3} dK={:+.3} dG={:+.3} dS={:+.3} impacts+{} located+{} cuts+{} oc_it+{} {}",
                sim.time(),
                dt,
                de,
                e_after.kinetic - e_full.kinetic,
                e_after.gravity - e_full.gravity,
                e_after.springs - e_full.springs,
                after.impacts - before.impacts,
                after.located_steps - before.located_steps,
                after.time_step_cuts - before.time_step_cuts,
                after.open_close_iterations - before.open_close_iterations,
                top.join(" ")
            );
        }
        min_dt = min_dt.min(dt);
        if after.impacts > before.impacts {
            split.impact += de;
        } else if after.located_steps > before.located_steps {
            split.located += de;
        } else if after.time_step_cuts > before.time_step_cuts {
            split.cut += de;
        } else {
            split.plain += de;
        }
        if de > split.max_gain {
            split.max_gain = de;
            split.max_gain_t = sim.time();
        }
        if sim.time() >= next_report - 1e-9 {
            let e = sim.energy();
            let s = sim.stats();
            // The free block with the most mechanical energy (kinetic + m g Δy from the start).
            let (top, top_e) = free
                .iter()
                .map(|&b| {
                    let k = run_end::kinetic_energy(&sim, b);
                    let p = weight(&sim, b) * (sim.geoms()[b].centroid.y - y0[b]);
                    (b, k + p)
                })
                .fold((0, f64::NEG_INFINITY), |a, x| if x.1 > a.1 { x } else { a });
            println!(
                "{:.3},{:.4},{:.4},{:.4},{:.4},{:.4},{},{},{},{},{:.4},{:.4},{:.4},{:.4},{:.4},{:.5},{:.2e},{},{:.4}",
                sim.time(),
                e.kinetic,
                e.gravity - e0.gravity,
                e.springs,
                e.strain,
                e.total() - e0.total(),
                s.steps - last.steps,
                s.time_step_cuts - last.time_step_cuts,
                s.impacts - last.impacts,
                s.located_steps - last.located_steps,
                split.impact,
                split.located,
                split.cut,
                split.plain,
                split.max_gain,
                split.max_gain_t,
                min_dt,
                sim.scene().blocks[top].id,
                top_e,
            );
            if flag("--blocks") {
                let line: Vec<String> = free
                    .iter()
                    .map(|&b| {
                        let k = run_end::kinetic_energy(&sim, b);
                        let p = weight(&sim, b) * (sim.geoms()[b].centroid.y - y0[b]);
                        format!("{}={:.3}", sim.scene().blocks[b].id, k + p)
                    })
                    .collect();
                println!("#blocks {:.3} {}", sim.time(), line.join(" "));
            }
            last = s;
            split = Split::default();
            min_dt = f64::INFINITY;
            next_report += every;
        }
    }
    let s = sim.stats();
    println!(
        "# end t = {:.4} s, steps {}, cuts {}, impacts {}, max penetration {:.3e} m",
        sim.time(),
        s.steps,
        s.time_step_cuts,
        s.impacts,
        s.max_penetration
    );
}

/// The contacts of the `focus` blocks and the velocities of the blocks they touch.
fn dump_contacts(sim: &Simulation, focus: &[String]) {
    let ids: Vec<&str> = sim.scene().blocks.iter().map(|b| b.id.as_str()).collect();
    let wanted: Vec<usize> = focus
        .iter()
        .filter_map(|f| ids.iter().position(|i| i == f))
        .collect();
    let vel = |b: usize| match sim.dofs().free_index[b] {
        Some(f) => {
            let v = sim.states()[f].vel;
            [v[0], v[1], v[2]]
        }
        None => [0.0; 3],
    };
    let mut seen = std::collections::BTreeSet::new();
    for c in &sim.contacts().contacts {
        if !(wanted.contains(&c.vertex_block) || wanted.contains(&c.edge_block)) {
            continue;
        }
        let rate = {
            let (vi, vj) = (c.vertex_block, c.edge_block);
            let vel6 = |b: usize| match sim.dofs().free_index[b] {
                Some(f) => sim.states()[f].vel,
                None => Default::default(),
            };
            c.e_i.dot(&vel6(vi)) - c.e_j.dot(&vel6(vj))
        };
        println!(
            "#contact {} v{} -> {} e{}: {:?} gap {:.3e} g0 {:.3e} rate {:+.4e} closed_within_last {} N {:.3e}",
            ids[c.vertex_block],
            c.vertex,
            ids[c.edge_block],
            c.edge,
            c.state,
            c.gap,
            c.g0,
            rate,
            c.closed_within_last_step,
            c.normal_force
        );
        seen.insert(c.vertex_block);
        seen.insert(c.edge_block);
    }
    for b in seen {
        let v = vel(b);
        println!(
            "#vel {} vx {:+.5} vy {:+.5} w {:+.5} y {:.5}",
            ids[b],
            v[0],
            v[1],
            v[2],
            sim.geoms()[b].centroid.y
        );
    }
}
