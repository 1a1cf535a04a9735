//! The scan that stops at the first failure (`ScanOrder::Lowest`, docs/pga.md) against the
//! full scan, on a real scene: the example column (default model) under Northridge 1994
//! Mulholland and Loma Prieta 1989 Capitola, the CLI's default search on this machine's thread
//! pool. The planner's claim (pga::tests): whenever every run of the full search at or above
//! the lowest scan's last scan point (`scanned_to`) has the outcome there, the two give the same
//! `safe_pga`/`failing_pga` to the bit. Northridge is such a case (the full search is
//! monotonic) and must agree to the bit with fewer runs; under Loma Prieta the column stands
//! again above its first failures, the condition is checked from the full search's own runs,
//! and when it does not hold the lowest scan must still bracket a change of outcome to the
//! tolerance at or below `scanned_to`, each end's verdict confirmed by a rerun.
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
    for (name, must_agree) in [
        ("northridge-1994-mulholland-009.at2", true),
        ("loma-prieta-1989-capitola-000.at2", false),
    ] {
        let gm = record(name);
        let full = search(&scene, &gm, &full_req, &RunOptions::default()).expect("search");
        let low = search(&scene, &gm, &low_req, &RunOptions::default()).expect("search");
        let to = low.scanned_to.expect("scanned_to");
        let at_to = full
            .runs
            .iter()
            .find(|r| r.pga == to)
            .expect("a scan point")
            .failed;
        let constant = full
            .runs
            .iter()
            .filter(|r| r.pga >= to)
            .all(|r| r.failed == at_to);
        eprintln!(
            "{name}: full [{:?}, {:?}] {} runs (monotonic {}); lowest [{:?}, {:?}] {} runs, \
             scanned to {to:.3} m/s², scan {:?}; nothing changes above it: {constant}",
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
        if must_agree {
            assert!(
                constant && full.monotonic,
                "{name}: the case the claim covers"
            );
        }
        if constant {
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
        } else {
            // Honest on its own: its bracket ends give their verdicts when rerun.
            let (s, f) = (low.safe_pga.expect("safe"), low.failing_pga.expect("fails"));
            assert!(f - s <= full_req.tolerance && f <= to, "{name}");
            let crit = &full_req.criteria;
            assert!(
                !evaluate(&scene, &gm, crit, s, None).expect("run"),
                "{name}"
            );
            assert!(evaluate(&scene, &gm, crit, f, None).expect("run"), "{name}");
        }
    }
}
