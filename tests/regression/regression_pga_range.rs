//! What broke: the PGA search's answer depended on where the user put the range. Same scene
//! (`examples/column.json`, default model) and record: `--min 0.05g` gave a lowest failing PGA
//! of 10.63 m/s², `--min 0.1g` gave 12.71–12.81 m/s², both with `monotonic: true`. The scan
//! (8 points, 2.7 m/s² apart) stepped over a failing interval ~1 m/s² wide in one range and not
//! in the other, and only the first change of outcome was refined.
//!
//! Now the search reports its scan's resolution, refines every change of outcome, and scans 40
//! points by default (0.49 m/s² over 0.05–2 g): two ranges that both contain the answer give
//! the same lowest failing PGA within the tolerance whenever the failing interval holding it is
//! wider than the resolution. Checked here on Loma Prieta 1989 Capitola and Imperial Valley
//! 1979 El Centro #6. Near their thresholds the failing set is fragmented below the resolution
//! (tests/analysis/pga_range.rs: islands ~0.05–0.25 m/s² wide), so the two ranges' answers are
//! held to 0.1 m/s² (1.5 % of the ~6 m/s² thresholds), not to the 0.01 m/s² tolerance:
//! measured 0.001 m/s² (Loma Prieta) and 0.039 m/s² (Imperial Valley: 6.653 against 6.614,
//! each range's refinement stepping over a different sub-island), against 2.1 m/s² before.
use crate::common::{example_column, record, toppled_column_search};
use ashlar::analysis::pga::search;
use ashlar::analysis::run::RunOptions;

const G: f64 = 9.80665;

#[test]
fn the_start_of_the_range_does_not_move_the_lowest_failing_pga() {
    let scene = example_column();
    for name in [
        "loma-prieta-1989-capitola-000.at2",
        "imperial-valley-1979-el-centro-6-233.csv",
    ] {
        let gm = record(name);
        let req = toppled_column_search;
        let a = search(&scene, &gm, &req(0.05), &RunOptions::default()).expect("search");
        let b = search(&scene, &gm, &req(0.1), &RunOptions::default()).expect("search");
        let (fa, fb) = (a.failing_pga.expect("fails"), b.failing_pga.expect("fails"));
        eprintln!(
            "{name}: from 0.05 g {fa:.3} m/s² (resolution {:.3}, {} intervals, monotonic {}), from 0.1 g {fb:.3} m/s² (resolution {:.3}, {} intervals, monotonic {})",
            a.resolution,
            a.failing_intervals.len(),
            a.monotonic,
            b.resolution,
            b.failing_intervals.len(),
            b.monotonic
        );
        assert!(fa > 0.1 * G, "{name}: the answer must lie in both ranges");
        assert!((fa - fb).abs() <= 0.1, "{name}: {fa} against {fb} m/s²");
        assert_eq!(a.monotonic, b.monotonic, "{name}");
        assert!(a.resolution < 0.5 && b.resolution < 0.5);
    }
}
