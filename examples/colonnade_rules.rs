//! The approximate rules of the open–close loop on a rocking stack (docs/contact-solve.md §27):
//! the bundled Doric colonnade (examples/doric-colonnade.json) under the first 12 s of Friuli
//! 1976 Tolmezzo 000 at 0.3 g, run as `ashlar run` runs it (`analysis::run::run`), as the
//! colonnade checks of tests/engine (light_state_rocking, stone_settle, cycle_rule) do, with
//! each rule on or off. Prints one line per configuration: verdict, peak (largest
//! `max_displacement`, its block), steps, cuts, and the peak against the run with none of the
//! rules. `--trace NAME` steps `Simulation` with configuration NAME instead and, after every
//! step in which the cycle rule closed a contact sliding, lists the contacts that end the step
//! sliding after at least `cycle_flips` state changes (the rule's closings, or their successors):
//! block pair, interface load at the step end against the lighter stone's weight, normal, time.
//! Configurations `no-predict`, `no-stick`, `no-slip`, `no-predictions`: the default without
//! the stick–slip prediction, without one half of it, or without any prediction (§32).
//! Run: `cargo run --release --example colonnade_rules -- [NAME,…] [--trace NAME] [--record FILE]
//! [--pga G] [--duration S] [--impact-cluster on|off]`.
use ashlar::analysis::run::Summary;
use ashlar::contact::ContactState;
use ashlar::presets;
use ashlar::simulation::{SimParams, Simulation};
use ashlar::solve::open_close::OpenCloseParams;
use std::collections::BTreeMap;

/// Simulated time, s (the tests' `light_state_rocking::DURATION`).
const DURATION: f64 = 12.0;

/// The configurations by name: `none` has none of the approximate rules (the light rule, the
/// stone settle rule, the cycle rule); `light`, `stone`, `cycle` have that rule alone; the
/// `*-broken` ones have the variant each test was written against, alone; `default` has all;
/// `no-light`, `no-stone`, `no-cycle` the default without one; `default+*-broken` the default
/// with one rule's broken variant.
fn config(name: &str) -> Option<OpenCloseParams> {
    let d = OpenCloseParams::default();
    let none = OpenCloseParams {
        light_state_changes: false,
        stone_settle_friction: 0.0,
        cycle_flips: 0,
        ..d
    };
    let light_broken = |p: OpenCloseParams| OpenCloseParams {
        light_state_changes: true,
        light_state_tilt: std::f64::consts::FRAC_PI_2,
        light_state_interface: false,
        ..p
    };
    let stone_broken = |p: OpenCloseParams| OpenCloseParams {
        stone_settle_friction: 1e-3,
        stone_settle_supports: 0,
        ..p
    };
    let cycle = |p: OpenCloseParams, check: bool| OpenCloseParams {
        cycle_flips: 4,
        cycle_after: 1,
        cycle_light_interface: check,
        cycle_tilt: std::f64::consts::FRAC_PI_4,
        ..p
    };
    // Session 37's rule: any orientation.
    let any = |p: OpenCloseParams| OpenCloseParams {
        cycle_tilt: std::f64::consts::FRAC_PI_2,
        ..p
    };
    Some(match name {
        "none" => none,
        "default" => d,
        "light" => OpenCloseParams {
            light_state_changes: true,
            ..none
        },
        "stone" => OpenCloseParams {
            stone_settle_friction: 1e-3,
            ..none
        },
        "cycle" => cycle(none, true),
        "light-broken" => light_broken(none),
        "stone-broken" => stone_broken(none),
        // Session 36's trial: no interface check, any orientation.
        "cycle-broken" => any(cycle(none, false)),
        "cycle-any" => any(cycle(none, true)),
        "no-light" => OpenCloseParams {
            light_state_changes: false,
            ..d
        },
        "no-stone" => OpenCloseParams {
            stone_settle_friction: 0.0,
            ..d
        },
        "no-cycle" => OpenCloseParams {
            cycle_flips: 0,
            ..d
        },
        "light+cycle" => cycle(
            OpenCloseParams {
                light_state_changes: true,
                ..none
            },
            true,
        ),
        "stone+cycle" => cycle(
            OpenCloseParams {
                stone_settle_friction: 1e-3,
                ..none
            },
            true,
        ),
        // cycle_rule.rs's bed-joint check: the stone and cycle rules, the cycle rule of any
        // orientation.
        "stone+cycle-any" => any(cycle(
            OpenCloseParams {
                stone_settle_friction: 1e-3,
                ..none
            },
            true,
        )),
        "default+light-broken" => light_broken(d),
        "default+stone-broken" => stone_broken(d),
        "default+cycle-broken" => any(cycle(d, false)),
        "default-any" => any(d),
        "no-light-any" => any(OpenCloseParams {
            light_state_changes: false,
            ..d
        }),
        // Session 41's stick–slip prediction (docs/contact-solve.md §32): the default without
        // it, or without one of its halves, and session 40's default (no friction prediction
        // either).
        "no-predict" => OpenCloseParams {
            stick_predict: None,
            slip_predict: None,
            ..d
        },
        "no-stick" => OpenCloseParams {
            stick_predict: None,
            ..d
        },
        "no-slip" => OpenCloseParams {
            slip_predict: None,
            ..d
        },
        "no-predictions" => OpenCloseParams {
            stick_predict: None,
            slip_predict: None,
            friction_predict: None,
            ..d
        },
        _ => return None,
    })
}

fn peak(s: &Summary) -> (f64, String) {
    s.blocks
        .iter()
        .map(|b| (b.max_displacement, b.id.clone()))
        .fold((0.0, String::new()), |a, b| if b.0 > a.0 { b } else { a })
}

fn trace(name: &str, oc: OpenCloseParams) {
    let (scene, gm) = presets::rocking_colonnade(DURATION).expect("colonnade");
    let mut sim = Simulation::new(
        &scene,
        &gm,
        SimParams {
            open_close: oc,
            ..Default::default()
        },
    );
    let ids: Vec<String> = scene.blocks.iter().map(|b| b.id.clone()).collect();
    let mut before = sim.changes().cycle_closed;
    // Closings by block pair: count, largest interface load / lighter weight.
    let mut by_pair: BTreeMap<(String, String), (u64, f64)> = BTreeMap::new();
    // Contacts sliding after a cycle at a step end on bed joints (normal within 45° of
    // vertical) and on head joints.
    let mut bed_head = [0u64; 2];
    while sim.time() < DURATION - 1e-12 {
        sim.step(DURATION - sim.time()).expect("colonnade step");
        let now = sim.changes().cycle_closed;
        if now == before {
            continue;
        }
        let made = now[0] - before[0] + now[1] - before[1];
        before = now;
        let contacts = &sim.contacts().contacts;
        // Interface loads at the step end: the largest normal force between each block pair.
        let mut load: BTreeMap<(usize, usize), f64> = BTreeMap::new();
        for c in contacts {
            let key = (
                c.vertex_block.min(c.edge_block),
                c.vertex_block.max(c.edge_block),
            );
            let l = load.entry(key).or_insert(0.0);
            *l = l.max(c.normal_force.max(0.0));
        }
        let weight = |b: usize| {
            sim.dofs().free_index[b]
                .map(|f| sim.solved_system().weight[f])
                .unwrap_or(f64::INFINITY)
        };
        for c in contacts {
            if c.flips < oc.cycle_flips || !matches!(c.state, ContactState::Sliding { .. }) {
                continue;
            }
            let key = (
                c.vertex_block.min(c.edge_block),
                c.vertex_block.max(c.edge_block),
            );
            let lighter = weight(c.vertex_block).min(weight(c.edge_block));
            let ratio = load[&key] / lighter;
            eprintln!(
                "t={:.4} closed {made}: {}/{} n=({:+.3},{:+.3}) N={:.3e} N, interface {:.3e} of the lighter weight {:.3e} N",
                sim.time(),
                ids[c.vertex_block],
                ids[c.edge_block],
                c.n.x,
                c.n.y,
                c.normal_force,
                ratio,
                lighter
            );
            bed_head[(c.n.y.abs() < c.n.x.abs()) as usize] += 1;
            let e = by_pair
                .entry((ids[key.0].clone(), ids[key.1].clone()))
                .or_insert((0, 0.0));
            e.0 += 1;
            e.1 = e.1.max(ratio);
        }
    }
    let ch = sim.changes();
    println!(
        "{name} (Simulation::step, {DURATION} s): closed sliding light {} loaded {}, kept locked {}, steps finished in the extra iterations {}, cuts {}; sliding after a cycle: bed {} head {}; stone rule friction {} state {}; light rule {}",
        ch.cycle_closed[0],
        ch.cycle_closed[1],
        ch.cycle_kept_locked,
        ch.cycle_extra_steps,
        sim.stats().time_step_cuts,
        bed_head[0],
        bed_head[1],
        ch.stone_settled_friction,
        ch.stone_settled_state,
        ch.light
    );
    for ((a, b), (n, r)) in by_pair {
        println!("  {a}/{b}: {n} sliding after a cycle at a step end, interface ≤ {r:.3e} of the lighter weight");
    }
}

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    if let Some(i) = args.iter().position(|a| a == "--trace") {
        let name = args.get(i + 1).expect("--trace NAME");
        trace(name, config(name).expect("configuration name"));
        return;
    }
    let names: Vec<String> = match args.first() {
        Some(list) => list.split(',').map(str::to_string).collect(),
        None => [
            "none",
            "default",
            "light",
            "stone",
            "cycle",
            "light-broken",
            "stone-broken",
            "cycle-broken",
            "no-light",
            "no-stone",
            "no-cycle",
        ]
        .map(str::to_string)
        .to_vec(),
    };
    // `--record FILE --pga G --duration S`: another motion (a record of data/ground-motions
    // scaled to G g) or length; `--impact-cluster on|off`: `ImpactParams::cluster`
    // (on by default since session 40).
    let opt = |k: &str| {
        args.iter()
            .position(|a| a == k)
            .and_then(|i| args.get(i + 1).cloned())
    };
    let duration: f64 = opt("--duration").map_or(DURATION, |v| v.parse().expect("--duration"));
    let cluster = opt("--impact-cluster");
    let (mut scene, mut gm) = presets::rocking_colonnade(duration).expect("colonnade");
    if let Some(r) = opt("--record") {
        let g: f64 = opt("--pga").map_or(0.3, |v| v.parse().expect("--pga"));
        gm = presets::record(&r)
            .expect("--record: a record of data/ground-motions")
            .scaled_to_pga(g * ashlar::motion::STANDARD_GRAVITY);
    } else if let Some(g) = opt("--pga") {
        let g: f64 = g.parse().expect("--pga");
        gm = presets::record("friuli-1976-tolmezzo-000.at2")
            .expect("Friuli")
            .scaled_to_pga(g * ashlar::motion::STANDARD_GRAVITY);
    }
    scene.control.duration = Some(duration);
    let mut p_none = None;
    for name in &names {
        let oc = config(name).unwrap_or_else(|| panic!("unknown configuration {name}"));
        let t0 = std::time::Instant::now();
        let mut sim_params = SimParams {
            open_close: oc,
            ..Default::default()
        };
        match cluster.as_deref() {
            Some("on") => sim_params.impact.cluster = true,
            Some("off") => sim_params.impact.cluster = false,
            None => {}
            Some(o) => panic!("--impact-cluster {o}: on or off"),
        }
        let opts = ashlar::analysis::run::RunOptions {
            sim_params: Some(sim_params),
            no_trajectory: true,
            ..Default::default()
        };
        let s: Summary = ashlar::analysis::run::run(&scene, &gm, &opts)
            .expect("colonnade run")
            .summary;
        let (p, id) = peak(&s);
        if name == "none" {
            p_none = Some(p);
        }
        let rel = p_none
            .map(|q| format!("{:+.1} % of none", 100.0 * (p - q) / q))
            .unwrap_or_default();
        let rot = s
            .blocks
            .iter()
            .map(|b| b.max_rotation.abs())
            .fold(0.0, f64::max);
        let fin = s
            .blocks
            .iter()
            .map(|b| b.final_displacement[0].hypot(b.final_displacement[1]))
            .fold(0.0, f64::max);
        let slid = s
            .blocks
            .iter()
            .map(|b| b.sliding_distance)
            .fold(0.0, f64::max);
        println!(
            "{name}: {} peak {p:.4e} m ({id}) {rel}, {} steps, {} cuts, max rotation {rot:.4e} rad, final {fin:.4e} m, sliding {slid:.4e} m, penetration {:.3e} m, impacts {:?}, toppled {}, {:.0} s",
            s.failure_mode,
            s.steps,
            s.diagnostics.time_step_cuts,
            s.diagnostics.max_penetration,
            s.diagnostics.impacts,
            s.blocks.iter().filter(|b| b.toppled).count(),
            t0.elapsed().as_secs_f64()
        );
    }
}
