//! The scan that stops at the first failure (`ScanOrder::Lowest`, docs/pga.md) against the
//! full scan, on a real scene: the example column (default model) under Northridge 1994
//! Mulholland and Loma Prieta 1989 Capitola, the CLI's default search on this machine's thread
//! pool. The planner's claim (pga::tests): the lowest change of outcome on the scan lattice lies
//! below the lowest scan's last scan point (`scanned_to`), so both scans bisect the same bracket
//! and give the same `safe_pga`/`failing_pga` to the bit, with fewer runs; under Loma Prieta the
//! column stands again above its first failures (before the lattice, the two answers differed
//! there by 0.0026 m/s²). The bracket's ends are rerun as an independent check of its verdicts.
use crate::common::{example_column, record};
use ashlar::analysis::pga::{evaluate, search, Criterion, PgaRequest, ScanOrder};
use ashlar::analysis::run::RunOptions;

#[test]
fn the_lowest_scan_gives_the_full_scans_answer_with_fewer_runs() {
    let scene = example_column();
    let full_req =
        PgaRequest::cli_default(vec![Criterion::parse("toppled:column").expect("criterion")]);
    let low_req = PgaRequest {
        scan: ScanOrder::Lowest,
        ..full_req.clone()
    };
    for name in [
        "northridge-1994-mulholland-009.at2",
        "loma-prieta-1989-capitola-000.at2",
    ] {
        let gm = record(name);
        let full = search(&scene, &gm, &full_req, &RunOptions::default()).expect("search");
        let low = search(&scene, &gm, &low_req, &RunOptions::default()).expect("search");
        let to = low.scanned_to.expect("scanned_to");
        eprintln!(
            "{name}: full [{:?}, {:?}] {} runs (monotonic {}); lowest [{:?}, {:?}] {} runs, \
             scanned to {to:.3} m/s², scan {:?}",
            full.safe_pga,
            full.failing_pga,
            full.runs.len(),
            full.monotonic,
            low.safe_pga,
            low.failing_pga,
            low.runs.len(),
            low.scan
        );
        assert_eq!(
            low.scan,
            ScanOrder::Lowest,
            "{name}: stopped before the top"
        );
        assert!(!low.monotonic, "{name}: nothing above scanned_to was run");
        assert!(low.runs.len() < full.runs.len(), "{name}: fewer runs");
        assert!(to < full_req.max);
        assert_eq!(
            (
                full.safe_pga.map(f64::to_bits),
                full.failing_pga.map(f64::to_bits)
            ),
            (
                low.safe_pga.map(f64::to_bits),
                low.failing_pga.map(f64::to_bits)
            ),
            "{name}"
        );
        // Honest: the bracket's ends give their verdicts when rerun.
        let (s, f) = (low.safe_pga.expect("safe"), low.failing_pga.expect("fails"));
        assert!(f - s <= full_req.tolerance + 1e-12 && f <= to, "{name}");
        let crit = &full_req.criteria;
        assert!(
            !evaluate(&scene, &gm, crit, s, None).expect("run"),
            "{name}"
        );
        assert!(evaluate(&scene, &gm, crit, f, None).expect("run"), "{name}");
    }
}
