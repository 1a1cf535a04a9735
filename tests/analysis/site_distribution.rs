//! The distribution of a site's PGA over a set of records (docs/observations.md;
//! `analysis::observations::distribution`), checked against independent computations:
//!
//! - Empirical fragilities with known thresholds (records' thresholds 3 and 5 m/s² for the
//!   damage seen, 6 and 8 for the damage not seen, range [0, 10]): the likelihood is piecewise
//!   constant and its quantiles are worked out by hand below. Tolerance: one grid spacing, since
//!   the trapezoid rule smears each step of the likelihood over the grid cell that holds it.
//! - One observation with a lognormal fragility reduces to the fragility curve itself: the
//!   posterior is F(a) (seen) or 1 − F(a) (not seen) normalised over the range, whose CDF has a
//!   closed form, ∫F = a Φ(d) − θ e^{β²/2} Φ(d − β) with d = ln(a/θ)/β; quantiles solved by
//!   bisection on it. The fit must give back the θ, β of exact capacities θ e^{±β} (the
//!   closed form of the interval fit: mean and population standard deviation of ln c), and the
//!   fit is the one `pga --motion DIR` reports (`pga::multi_result`).
use ashlar::analysis::fragility::{normal_cdf, Capacity, Method};
use ashlar::analysis::observations::{distribution, CriterionRecords, DistributionParams};
use ashlar::analysis::pga::{
    multi_result, Combine, Criterion, PgaRequest, PgaResult, RecordResult,
};

fn exact(thresholds: &[f64]) -> Vec<Capacity> {
    thresholds
        .iter()
        .map(|&t| Capacity {
            above: Some(t),
            at_most: Some(t),
        })
        .collect()
}

fn obs(name: &str, observed: bool, thresholds: &[f64]) -> CriterionRecords {
    CriterionRecords {
        criterion: name.into(),
        observed,
        capacities: exact(thresholds),
    }
}

fn close(what: &str, got: f64, want: f64, tol: f64) {
    assert!(
        (got - want).abs() <= tol,
        "{what}: got {got}, want {want} (tolerance {tol})"
    );
}

#[test]
fn site_distribution_with_empirical_fragilities_matches_the_hand_computed_quantiles() {
    let params = DistributionParams { grid_points: 401 };
    let h = 10.0 / 400.0;
    // Seen only: L = F1 = 0 below 3, 1/2 on [3, 5), 1 from 5; mass 1 + 5 = 6. Quantile q:
    // below 5 the CDF is (a − 3)/2/6, above it 1/6 + (a − 5)/6.
    let d = distribution(&[obs("c1", true, &[3.0, 5.0])], 0.0, 10.0, &params);
    let p = d.empirical.expect("empirical posterior");
    close("seen median", p.median, 7.0, h);
    close("seen 5 %", p.p05_p95[0], 3.6, h);
    close("seen 16 %", p.p16_p84[0], 4.92, h);
    close("seen 84 %", p.p16_p84[1], 9.04, h);
    close("seen 95 %", p.p05_p95[1], 9.7, h);
    // Not seen only: L = 1 − F2 = 1 below 6, 1/2 on [6, 8), 0 from 8; mass 6 + 1 = 7.
    let d = distribution(&[obs("c2", false, &[6.0, 8.0])], 0.0, 10.0, &params);
    let p = d.empirical.expect("empirical posterior");
    close("not seen median", p.median, 3.5, h);
    close(
        "not seen 95 %",
        p.p05_p95[1],
        6.0 + 2.0 * (0.95 * 7.0 - 6.0),
        h,
    );
    // Both: L = F1 (1 − F2) = 1/2 on [3, 5), 1 on [5, 6), 1/2 on [6, 8), 0 elsewhere; mass 3.
    let d = distribution(
        &[obs("c1", true, &[3.0, 5.0]), obs("c2", false, &[6.0, 8.0])],
        0.0,
        10.0,
        &params,
    );
    let p = d.empirical.expect("empirical posterior");
    close("joint median", p.median, 5.5, h);
    close("joint 5 %", p.p05_p95[0], 3.0 + 2.0 * 0.15, h);
    close("joint 16 %", p.p16_p84[0], 3.96, h);
    close("joint 84 %", p.p16_p84[1], 7.04, h);
    close(
        "joint 95 %",
        p.p05_p95[1],
        6.0 + 2.0 * (0.95 * 3.0 - 2.0),
        h,
    );
    // The density integrates to 1 (trapezoid) and vanishes where a record set rules a out.
    let mass: f64 = p
        .density
        .windows(2)
        .zip(p.pga.windows(2))
        .map(|(d, a)| 0.5 * (d[0] + d[1]) * (a[1] - a[0]))
        .sum();
    close("mass", mass, 1.0, 1e-12);
    assert_eq!(p.density[(2.9 / h) as usize], 0.0);
    assert_eq!(p.density[(8.1 / h) as usize + 1], 0.0);
    // Two records cannot rule out that a stood everywhere: the lognormal fit exists too.
    assert!(d.lognormal.is_some(), "{:?}", d.lognormal_error);
    assert!(d.assumes.contains("independent given the PGA"));

    // Observations no record reproduces at any PGA of the range: an error, not a curve.
    let d = distribution(
        &[obs("c1", true, &[7.0, 9.0]), obs("c2", false, &[2.0, 4.0])],
        0.0,
        10.0,
        &params,
    );
    assert!(d.empirical.is_none() && d.empirical_error.is_some());
}

/// ∫₀ˣ Φ(ln(a/θ)/β) da.
fn integral_f(x: f64, theta: f64, beta: f64) -> f64 {
    if x <= 0.0 {
        return 0.0;
    }
    let d = (x / theta).ln() / beta;
    x * normal_cdf(d) - theta * (0.5 * beta * beta).exp() * normal_cdf(d - beta)
}

fn bisect(f: impl Fn(f64) -> f64, target: f64, mut lo: f64, mut hi: f64) -> f64 {
    for _ in 0..200 {
        let mid = 0.5 * (lo + hi);
        if f(mid) < target {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    0.5 * (lo + hi)
}

#[test]
fn site_distribution_of_one_observation_reduces_to_its_lognormal_fragility() {
    let (theta, beta): (f64, f64) = (5.0, 0.3);
    let caps = [theta * (-beta).exp(), theta * beta.exp()];
    let (min, max) = (1.0, 12.0);
    let params = DistributionParams { grid_points: 2001 };
    for observed in [true, false] {
        let d = distribution(&[obs("c", observed, &caps)], min, max, &params);
        let fit = d.criteria[0].fragility.clone().expect("fit");
        // Nelder–Mead stops at a 1e-10 simplex: θ and β to 1e-7 relative.
        close("θ", fit.median, theta, 1e-7 * theta);
        close("β", fit.beta, beta, 1e-7 * beta);
        let p = d.lognormal.expect("lognormal posterior");
        let cdf = |x: f64| {
            let g = |x: f64| {
                if observed {
                    integral_f(x, theta, beta)
                } else {
                    x - integral_f(x, theta, beta)
                }
            };
            (g(x) - g(min)) / (g(max) - g(min))
        };
        // Trapezoid on a smooth density with spacing 0.0055 m/s²: the quantiles' error is
        // O(h²·f'/f) ≈ 1e-5 m/s²; 1e-4 m/s² leaves room and is 1e-4 of the range.
        for (q, got) in [
            (0.05, p.p05_p95[0]),
            (0.16, p.p16_p84[0]),
            (0.5, p.median),
            (0.84, p.p16_p84[1]),
            (0.95, p.p05_p95[1]),
        ] {
            let want = bisect(cdf, q, min, max);
            eprintln!(
                "observed {observed}: q {q}: {got} vs closed form {want} ({:.1e})",
                got - want
            );
            close(
                &format!("observed {observed}: quantile {q}"),
                got,
                want,
                1e-4,
            );
        }
    }

    // The fit is the one a multi-record PGA search reports for the same brackets.
    let req = PgaRequest {
        criteria: vec![Criterion::parse("toppled:c").unwrap_or_else(|e| panic!("{e}"))],
        combine: Combine::All,
        min,
        max,
        tolerance: 0.01,
        scan_points: 8,
        resolution: None,
        scan: ashlar::analysis::pga::ScanOrder::Full,
    };
    let records: Vec<RecordResult> = caps
        .iter()
        .enumerate()
        .map(|(i, &c)| RecordResult {
            motion: format!("r{i}"),
            result: PgaResult {
                criterion: "toppled:c".into(),
                safe_pga: Some(c),
                failing_pga: Some(c),
                units: "m/s2".into(),
                monotonic: true,
                resolution: 0.0,
                failing_intervals: Vec::new(),
                scan: ashlar::analysis::pga::ScanOrder::Full,
                scanned_to: None,
                runs: Vec::new(),
            },
        })
        .collect();
    let m = multi_result(records, &req, Method::Interval);
    let f = m.fragility.expect("multi-record fit");
    let d = distribution(&[obs("c", true, &caps)], min, max, &params);
    let g = d.criteria[0].fragility.clone().expect("fit");
    assert_eq!((f.median, f.beta), (g.median, g.beta));
}
