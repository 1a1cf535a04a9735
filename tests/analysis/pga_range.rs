//! The PGA search does not depend on where the range starts (docs/pga.md), against an
//! independent answer: a brute-force scan of the same scene (`examples/column.json`, default
//! model) under Loma Prieta 1989 Capitola (its response is not monotonic in amplitude) every
//! 0.05 m/s², each amplitude one `evaluate` run, no bisection. Two searches over ranges that
//! both contain the answer (0.05–2 g and 0.1–2 g, the default resolution, tolerance
//! 0.01 m/s²) must
//! - agree with each other to the bit (they share the scan lattice and its lowest failing
//!   point, so they bisect the same bracket);
//! - find the lowest failing interval of the brute force that is wider than their resolution
//!   (what the search promises: its lowest failing PGA is at most that interval's first grid
//!   point + the tolerance), and report nothing below the brute force's lowest failure by more
//!   than its grid step.
//!
//! The brute force also shows what the resolution leaves out: near the threshold the failing
//! set is fragmented at the 0.1 m/s² scale (measured: failing at 5.84, then 5.99–6.14,
//! 6.24–6.49, 6.64–6.69, 6.79–6.99 m/s²), so no interval there is wider than the resolution and
//! the promise above holds vacuously; what is checked then is the observed agreement: both
//! searches within 0.2 m/s² (3.4 % of the threshold; measured 0.13) of the brute force's lowest
//! failure, and not below it.
use crate::common::{example_column, record, toppled_column_search};
use ashlar::analysis::pga::{evaluate, search};
use ashlar::analysis::run::RunOptions;
use rayon::prelude::*;

const G: f64 = 9.80665;
const STEP: f64 = 0.05;

#[test]
fn two_ranges_find_the_brute_force_lowest_failing_pga() {
    let scene = example_column();
    let gm = record("loma-prieta-1989-capitola-000.at2");
    let req = toppled_column_search;
    let criteria = req(0.05).criteria;
    let a = search(&scene, &gm, &req(0.05), &RunOptions::default()).expect("search");
    let b = search(&scene, &gm, &req(0.1), &RunOptions::default()).expect("search");
    let (fa, fb) = (a.failing_pga.expect("fails"), b.failing_pga.expect("fails"));
    // Brute force from the bottom of the wider range to 1 m/s² above the searches' answer.
    let top = fa.max(fb) + 1.0;
    let n = ((top - 0.05 * G) / STEP).ceil() as usize + 1;
    let grid: Vec<f64> = (0..n).map(|i| 0.05 * G + i as f64 * STEP).collect();
    let outcomes: Vec<bool> = grid
        .par_iter()
        .map(|&p| evaluate(&scene, &gm, &criteria, p, None).expect("run"))
        .collect();
    // Failing intervals of the brute force: [first, last] failing grid point of each run.
    let mut intervals: Vec<[f64; 2]> = Vec::new();
    for (i, &failed) in outcomes.iter().enumerate() {
        if failed {
            match intervals.last_mut() {
                Some(last) if i > 0 && outcomes[i - 1] => last[1] = grid[i],
                _ => intervals.push([grid[i], grid[i]]),
            }
        }
    }
    let resolution = a.resolution.max(b.resolution);
    let lowest = intervals.first().expect("the brute force fails")[0];
    let wide = intervals
        .iter()
        .find(|iv| iv[1] - iv[0] >= resolution)
        .map_or(f64::INFINITY, |iv| iv[0]);
    eprintln!(
        "brute force ({n} runs, every {STEP} m/s²): lowest failing {lowest:.3} m/s², lowest failing interval wider than the resolution from {wide:.3}; intervals {intervals:.3?}"
    );
    eprintln!(
        "search from 0.05 g: {fa:.4} m/s² ({} runs, resolution {:.3}, monotonic {}, intervals {:.3?}); from 0.1 g: {fb:.4} ({} runs, resolution {:.3}, monotonic {})",
        a.runs.len(),
        a.resolution,
        a.monotonic,
        a.failing_intervals,
        b.runs.len(),
        b.resolution,
        b.monotonic
    );
    assert!(lowest > 0.1 * G, "the answer lies in both ranges");
    for f in [fa, fb] {
        assert!(f <= wide + 0.01, "{f}: missed the interval from {wide}");
        assert!(
            f >= lowest - STEP - 0.01,
            "{f} below the brute force's {lowest}"
        );
        assert!(f - lowest <= 0.2, "{f} against the brute force's {lowest}");
    }
    assert_eq!(fa.to_bits(), fb.to_bits(), "{fa} against {fb}");
}
