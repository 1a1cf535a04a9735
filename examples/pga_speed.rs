//! Speed of the PGA search (docs/pga.md): the rocking column (0.2 × 0.6 m half-sizes, half-sine pulse
//! of period 1 s, 3 s simulated) searched over 2–10 m/s² to a tolerance of 0.01 m/s² with the
//! default 8 scan points. Prints, from one run of this program:
//! - the wall time of one full run (no early stop, at 5.6 m/s², just below the threshold);
//! - the search's wall time on a 2-thread pool (target < 1 s);
//! - the search's wall time on a 1-thread pool, i.e. its total work, divided by the full run's
//!   time: the cost in single-run equivalents (target ≤ 15).
//!
//! Each figure is the median of 7 repetitions. Run:
//! `cargo run --release --example pga_speed`
use ashlar::analysis::pga::{search, Combine, Criterion, PgaRequest};
use ashlar::analysis::run::{run, RunOptions};
use ashlar::presets::{rocking_pulse, Column};
use std::time::Instant;

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

fn main() {
    let scene = Column::SEED
        .scene(serde_json::json!({ "duration": 3.0 }))
        .expect("scene");
    let pulse = rocking_pulse(1.0);
    let req = PgaRequest {
        criteria: vec![Criterion::parse("toppled:column").expect("criterion")],
        combine: Combine::All,
        min: 2.0,
        max: 10.0,
        tolerance: 0.01,
        scan_points: 8,
        resolution: None,
        scan: ashlar::analysis::pga::ScanOrder::Full,
    };
    let reps = 7;
    let single = median(
        (0..reps)
            .map(|_| {
                let t = Instant::now();
                let out =
                    run(&scene, &pulse.scaled_to_pga(5.6), &RunOptions::default()).expect("run");
                assert!(out.summary.completed);
                t.elapsed().as_secs_f64()
            })
            .collect(),
    );
    let timed = |threads: usize| {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .expect("pool");
        let mut runs = 0;
        let mut bracket = (0.0, 0.0);
        let wall = median(
            (0..reps)
                .map(|_| {
                    let t = Instant::now();
                    let r = pool
                        .install(|| search(&scene, &pulse, &req, &RunOptions::default()))
                        .expect("search");
                    let dt = t.elapsed().as_secs_f64();
                    runs = r.runs.len();
                    bracket = (
                        r.safe_pga.unwrap_or(f64::NAN),
                        r.failing_pga.unwrap_or(f64::NAN),
                    );
                    dt
                })
                .collect(),
        );
        (wall, runs, bracket)
    };
    let (w2, runs2, b2) = timed(2);
    let (w1, runs1, _) = timed(1);
    println!("| figure | measured | target |");
    println!("|---|---|---|");
    println!(
        "| one full run (3 s simulated) | {:.2} ms | |",
        1e3 * single
    );
    println!(
        "| search, 2 threads: wall time ({runs2} runs, bracket [{:.3}, {:.3}] m/s²) | {:.1} ms | < 1 s |",
        b2.0,
        b2.1,
        1e3 * w2
    );
    println!(
        "| search, 1 thread: total work ({runs1} runs) | {:.1} ms = {:.1} single-run equivalents | ≤ 15 |",
        1e3 * w1,
        w1 / single
    );
    println!("| speed-up of 2 threads over 1 | {:.2} | |", w1 / w2);
}
