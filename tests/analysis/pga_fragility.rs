//! Fragility fitting (docs/pga.md): the maximum-likelihood lognormal fit checked against
//! (a) the closed form for exact capacities: θ = exp(mean ln c), β = population standard
//!     deviation of ln c (tolerance 1e-6 relative: the optimiser stops at a 1e-10 simplex);
//! (b) synthetic capacities drawn (seeded) from a known lognormal, bracketed as a search would
//!     bracket them, some right-censored: the estimate lies within 4 standard errors of the
//!     truth (SE of ln θ ≈ β/√n, of β ≈ β/√(2n); 4 SE is exceeded with probability < 1e-4);
//! (c) binary outcomes (Baker 2015) drawn from a known curve: same 4-SE bound.
//! And the multi-record search end to end on the engine (rocking column, three pulses).
use crate::common;
use ashlar::analysis::fragility::{
    fit_binary, fit_interval, normal_cdf, svg, Capacity, FitParams, Point,
};
use ashlar::analysis::pga::{search_records, Combine, Criterion, PgaRequest};
use ashlar::analysis::run::RunOptions;
use ashlar::motion::GroundMotion;
use common::*;
use serde_json::json;

/// splitmix64: a small, well-mixed seeded generator (no dependency needed for a test).
struct Rng(u64);
impl Rng {
    fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }
    fn uniform(&mut self) -> f64 {
        ((self.next_u64() >> 11) as f64 + 0.5) / (1u64 << 53) as f64
    }
    fn normal(&mut self) -> f64 {
        let (u, v) = (self.uniform(), self.uniform());
        (-2.0 * u.ln()).sqrt() * (2.0 * std::f64::consts::PI * v).cos()
    }
}

fn closed_form(c: &[f64]) -> (f64, f64) {
    let logs: Vec<f64> = c.iter().map(|x| x.ln()).collect();
    let n = logs.len() as f64;
    let m = logs.iter().sum::<f64>() / n;
    let s = (logs.iter().map(|l| (l - m).powi(2)).sum::<f64>() / n).sqrt();
    (m.exp(), s)
}

#[test]
fn exact_capacities_give_the_closed_form() {
    let caps = [2.1, 3.4, 2.8, 5.0, 4.1, 3.0, 2.5];
    let exact: Vec<Capacity> = caps
        .iter()
        .map(|&c| Capacity {
            above: Some(c),
            at_most: Some(c),
        })
        .collect();
    let f = fit_interval(&exact, vec![], &FitParams::default()).expect("fit");
    let (theta, beta) = closed_form(&caps);
    eprintln!(
        "MLE θ {} β {} vs closed form θ {theta} β {beta}",
        f.median, f.beta
    );
    assert!((f.median / theta - 1.0).abs() < 1e-6);
    assert!((f.beta / beta - 1.0).abs() < 1e-6);
}

#[test]
fn interval_censored_mle_recovers_a_known_lognormal() {
    let (theta, beta, n) = (3.0f64, 0.4f64, 2000usize);
    let mut rng = Rng(20261122);
    let caps: Vec<f64> = (0..n)
        .map(|_| (theta.ln() + beta * rng.normal()).exp())
        .collect();
    // Bracketed as a search to 0.01 m/s² would: (c − u·0.01, c + (1−u)·0.01].
    let tol = 0.01;
    let bracket = |c: f64, rng: &mut Rng| {
        let u = rng.uniform();
        (c - u * tol, c + (1.0 - u) * tol)
    };
    let bracketed: Vec<Capacity> = caps
        .iter()
        .map(|&c| {
            let (a, b) = bracket(c, &mut rng);
            Capacity {
                above: Some(a),
                at_most: Some(b),
            }
        })
        .collect();
    let p = FitParams::default();
    let f = fit_interval(&bracketed, vec![], &p).expect("fit");
    let (t_exact, b_exact) = closed_form(&caps);
    let se_mu = beta / (n as f64).sqrt();
    let se_beta = beta / (2.0 * n as f64).sqrt();
    eprintln!(
        "bracketed: θ {:.4} β {:.4}; exact sample θ {t_exact:.4} β {b_exact:.4}; truth θ {theta} β {beta}",
        f.median, f.beta
    );
    assert!((f.median.ln() - theta.ln()).abs() < 4.0 * se_mu);
    assert!((f.beta - beta).abs() < 4.0 * se_beta);
    // The 0.01 m/s² brackets (0.3 % of θ) move the estimate far less than sampling does.
    assert!((f.median / t_exact - 1.0).abs() < 1e-3);
    assert!((f.beta - b_exact).abs() < 1e-3);

    // Right-censoring at the top of a search range (4.5 m/s²: ~16 % of records never fail).
    let top = 4.5;
    let censored: Vec<Capacity> = caps
        .iter()
        .zip(&bracketed)
        .map(|(&c, b)| {
            if c > top {
                Capacity {
                    above: Some(top),
                    at_most: None,
                }
            } else {
                *b
            }
        })
        .collect();
    let nc = caps.iter().filter(|&&c| c > top).count();
    let g = fit_interval(&censored, vec![], &p).expect("fit");
    let kept: Vec<f64> = caps.iter().copied().filter(|&c| c <= top).collect();
    let (t_naive, _) = closed_form(&kept);
    eprintln!(
        "{nc} right-censored: θ {:.4} β {:.4}; ignoring them would give θ {t_naive:.4}",
        g.median, g.beta
    );
    let se_mu_c = beta / ((n - nc) as f64).sqrt();
    let se_beta_c = beta / (2.0 * (n - nc) as f64).sqrt();
    assert!((g.median.ln() - theta.ln()).abs() < 4.0 * se_mu_c);
    assert!((g.beta - beta).abs() < 4.0 * se_beta_c);
    // The censoring matters: dropping the censored records is biased beyond that bound.
    assert!((t_naive.ln() - theta.ln()).abs() > 4.0 * se_mu_c);
}

#[test]
fn binary_mle_recovers_a_known_curve() {
    let (theta, beta) = (4.0f64, 0.5f64);
    let mut rng = Rng(7);
    let mut points = Vec::new();
    for k in 1..=12 {
        let x = 0.75 * k as f64;
        let p = normal_cdf((x / theta).ln() / beta);
        for _ in 0..200 {
            points.push(Point {
                pga: x,
                failed: rng.uniform() < p,
            });
        }
    }
    let n = points.len();
    let f = fit_binary(points, &FitParams::default()).expect("fit");
    eprintln!(
        "binary: θ {:.4} β {:.4} from {n} runs (truth {theta}, {beta})",
        f.median, f.beta
    );
    // The information per run is below that of an exact capacity; with runs spread over
    // 0.75–9 m/s² about a third of them are informative, hence √(n/3) in the SE.
    let eff = n as f64 / 3.0;
    assert!((f.median.ln() - theta.ln()).abs() < 4.0 * beta / eff.sqrt());
    assert!((f.beta - beta).abs() < 4.0 * beta / (2.0 * eff).sqrt());
}

#[test]
fn unfittable_sets_are_named_and_the_plot_is_labelled() {
    let never = [Capacity {
        above: Some(9.0),
        at_most: None,
    }; 3];
    let e = fit_interval(&never, vec![], &FitParams::default()).expect_err("no failure");
    assert!(e.to_string().contains("widen the range"), "{e}");
    let all_failed = vec![
        Point {
            pga: 1.0,
            failed: true
        };
        4
    ];
    assert!(fit_binary(all_failed, &FitParams::default()).is_err());

    let caps = vec![
        Capacity {
            above: Some(2.0),
            at_most: Some(2.5),
        },
        Capacity {
            above: Some(3.0),
            at_most: Some(3.2),
        },
        Capacity {
            above: None,
            at_most: Some(1.0),
        },
    ];
    let points = vec![
        Point {
            pga: 2.0,
            failed: false,
        },
        Point {
            pga: 2.5,
            failed: true,
        },
    ];
    let f = fit_interval(&caps, points, &FitParams::default()).expect("fit");
    let named: Vec<(String, Capacity)> = caps
        .iter()
        .enumerate()
        .map(|(i, c)| (format!("r{i}"), *c))
        .collect();
    let s = svg(&f, &named, "test <plot>");
    assert!(s.starts_with("<svg") && s.trim_end().ends_with("</svg>"));
    assert!(s.contains("PGA (m/s²)") && s.contains("Probability of failure"));
    assert!(s.contains("test &lt;plot&gt;"));
    assert_eq!(s.matches("<circle").count(), 2);
    assert_eq!(s.matches("capacity").count(), 3);
}

fn column() -> ashlar::scene::Scene {
    parse(&Column::SEED.json(json!({ "duration": 3.0, "model": "dda" })))
}

/// End to end: three pulses of different periods give three capacities; the fit passes
/// through them (interval MLE with three brackets of 0.05 m/s²: the median is their geometric
/// mean within the bracket widths, 2 %), and each record's bracket is that record's own search.
#[test]
fn multi_record_search_fits_the_records_capacities() {
    let scene = column();
    let records: Vec<(String, GroundMotion)> = [0.8, 1.0, 1.25]
        .iter()
        .map(|&t| (format!("half-sine {t} s"), half_sine(1.0, t)))
        .collect();
    let req = PgaRequest {
        criteria: vec![Criterion::parse("toppled:column").expect("criterion")],
        combine: Combine::All,
        min: 2.0,
        max: 10.0,
        tolerance: 0.05,
        scan_points: 6,
        resolution: None,
        scan: ashlar::analysis::pga::ScanOrder::Full,
    };
    let r = search_records(
        &scene,
        &records,
        &req,
        ashlar::analysis::fragility::Method::Interval,
        &RunOptions::default(),
    )
    .expect("search");
    let f = r.fragility.as_ref().expect("a curve");
    let mids: Vec<f64> = r
        .records
        .iter()
        .map(|x| {
            let (s, fl) = (
                x.result.safe_pga.expect("safe"),
                x.result.failing_pga.expect("failing"),
            );
            assert!(fl - s <= 0.05 + 1e-12);
            0.5 * (s + fl)
        })
        .collect();
    let (theta, beta) = closed_form(&mids);
    eprintln!(
        "capacities {mids:?}: θ {:.3} β {:.3} (closed form on midpoints {theta:.3}, {beta:.3})",
        f.median, f.beta
    );
    assert!((f.median / theta - 1.0).abs() < 0.02);
    assert_eq!(r.records[1].motion, "half-sine 1 s");
    assert_eq!(
        f.points.len(),
        r.records.iter().map(|x| x.result.runs.len()).sum::<usize>()
    );
    let v = serde_json::to_value(&r).expect("json");
    for k in ["criterion", "units", "records", "fragility"] {
        assert!(v.get(k).is_some(), "{k}");
    }
    assert!(v["records"][0]["motion"].is_string() && v["records"][0]["safe_pga"].is_number());
    for k in ["median", "beta", "method", "points"] {
        assert!(v["fragility"].get(k).is_some(), "{k}");
    }
}
