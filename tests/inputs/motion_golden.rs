//! Intensity measures of two shared records against values from independent implementations
//! (eqsig, pyrotd, numpy, scipy), produced offline by tests/fixtures/motion/golden_reference.py
//! into golden_reference.json. Tolerance 1 % unless stated; each exception says why.
//!
//! Each scalar also has a regression bound at 5–10× the error measured today (the figures in
//! docs/motion.md, printed by `cargo test --test inputs motion_golden:: -- --nocapture`), so that a drift
//! is caught long before the tolerance. Where today's error is round-off (≤ 3.4e-16: the same
//! sums in the same order as numpy), the bound is 3e-15, about 10× the largest round-off seen:
//! a wrong constant of gravity (0.034 %) or a changed formula fails it at once.
use ashlar::motion::{self, highpass_zero_phase, report, Sampled, Signal};
use serde_json::Value;
use std::path::Path;

fn golden() -> Value {
    let text = std::fs::read_to_string(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/tests/fixtures/motion/golden_reference.json"
    ))
    .expect("golden file");
    serde_json::from_str(&text).expect("golden json")
}

fn f(v: &Value, key: &str) -> f64 {
    v[key]
        .as_f64()
        .unwrap_or_else(|| panic!("golden value {key}"))
}

fn arr(v: &Value, key: &str) -> Vec<f64> {
    v[key]
        .as_array()
        .unwrap_or_else(|| panic!("golden array {key}"))
        .iter()
        .filter_map(Value::as_f64)
        .collect()
}

fn check(name: &str, what: &str, got: f64, want: f64, tol: f64) {
    let r = (got - want).abs() / want.abs();
    assert!(
        r <= tol,
        "{name}: {what} {got} vs reference {want} (relative {r:.2e} > {tol})"
    );
}

/// Round-off bound (see the module text): 3e-15, ~10× the largest round-off measured (3.4e-16).
const ROUND_OFF: f64 = 3e-15;

/// `check` with the regression bound `regress[k]` for record `k` of [`RECORDS`] as well.
fn check2(k: usize, what: &str, got: f64, want: f64, tol: f64, regress: [f64; 2]) {
    let name = RECORDS[k];
    let r = (got - want).abs() / want.abs();
    // The figures quoted in docs/motion.md: `cargo test --test inputs motion_golden:: -- --nocapture`.
    println!(
        "{name:42} {what:16} ashlar {got:12.6} reference {want:12.6} relative {r:.1e} (tolerance {tol:.0e}, regression bound {:.1e})",
        regress[k]
    );
    check(name, what, got, want, tol);
    assert!(
        r <= regress[k],
        "{name}: {what} {got} vs reference {want}: relative {r:.2e} within the tolerance {tol} but above the regression bound {:.1e} (5–10× today's error): find what changed",
        regress[k]
    );
}

const RECORDS: [&str; 2] = [
    "northridge-1994-mulholland-009.at2",
    "imperial-valley-1979-el-centro-6-233.csv",
];

fn load(name: &str) -> motion::GroundMotion {
    let p = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("data/ground-motions")
        .join(name);
    motion::load_path(&p).expect(name)
}

/// Regression bounds (measured relative errors, Northridge / Imperial Valley): PGA, PGV,
/// Arias, CAV, mean period ≤ 3.4e-16 → round-off bound; PGD 1.6e-4 / 6.5e-6 (eqsig integrates
/// by the trapezoid without ashlar's within-sample peak search) → 1e-3 / 5e-5; D5–95
/// 7.0e-4 / 5.5e-4 (eqsig reads it at whole samples) → 5e-3 / 5e-3.
#[test]
fn scalar_measures_match_eqsig_and_numpy() {
    let g = golden();
    for (k, name) in RECORDS.iter().enumerate() {
        let r = &g["records"][name];
        let im = report(&load(name));
        assert_eq!(im.npts as f64, f(r, "npts"), "{name}: npts");
        let ro = [ROUND_OFF; 2];
        check2(k, "PGA", im.pga, f(r, "pga"), 1e-9, ro);
        check2(k, "PGV", im.pgv, f(r, "pgv"), 0.01, ro);
        check2(k, "PGD", im.pgd, f(r, "pgd"), 0.01, [1e-3, 5e-5]);
        check2(
            k,
            "Arias intensity",
            im.arias_intensity,
            f(r, "arias_intensity"),
            0.01,
            ro,
        );
        check2(k, "CAV", im.cav, f(r, "cav"), 0.01, ro);
        check2(
            k,
            "D5-95",
            im.significant_duration_5_95,
            f(r, "significant_duration_5_95"),
            0.01,
            [5e-3, 5e-3],
        );
        check2(
            k,
            "mean period",
            im.mean_period,
            f(r, "mean_period"),
            0.01,
            ro,
        );
    }
}

/// PSA against three independent references, all including the free vibration after the record:
/// - scipy's exact state-space discretisation for linearly interpolated input ("foh", matrix
///   exponential) on a grid of ≥ 64 points per period: the same model as ashlar by other means,
///   so every one of the 100 periods, 0.01–10 s, is compared at 1 % (its own peak reading is
///   at most 0.12 % low; ashlar locates the peak between substeps on the Hermite interpolant);
/// - pyrotd's frequency-domain oscillators (Fourier interpolation of the record);
/// - eqsig's Nigam–Jennings recurrence (peaks read at the samples only).
///
/// Tolerances against the last two, from the known differences between the methods:
/// - pyrotd, T ≥ 10 dt: 1 % + (π dt/T)²/3. Linear interpolation between samples (ashlar's and the
///   solver's convention) low-passes the record by sinc²(f dt) ≈ 1 − (π f dt)²/3 against
///   Fourier interpolation, which is 3.3 % at T = 10 dt and below 0.4 % beyond 30 dt. Below 10 dt
///   the samples do not determine the signal between them and the methods differ by up to 10 %
///   (documented in docs/motion.md), so that band is not compared.
/// - eqsig, T ≥ 30 dt: 1 %. Its peaks are read at the samples, which misses the true peak by up to
///   1 − cos(π dt/T) ≤ 0.55 % there.
#[test]
fn response_spectrum_matches_pyrotd_and_eqsig() {
    let g = golden();
    for name in RECORDS {
        let r = &g["records"][name];
        let im = report(&load(name));
        let periods = arr(r, "periods");
        assert_eq!(periods.len(), im.spectrum.periods.len());
        for (p, q) in periods.iter().zip(&im.spectrum.periods) {
            assert!((p - q).abs() < 1e-9 * p, "period grid {p} vs {q}");
        }
        let rotd = arr(r, "psa_pyrotd");
        let nj = arr(r, "psa_nigam_jennings");
        let foh = arr(r, "psa_state_space_foh");
        let dt = f(r, "dt");
        let mut compared = 0;
        for i in 0..periods.len() {
            let t = periods[i];
            check(
                name,
                &format!("PSA({t:.4} s) vs state-space foh"),
                im.spectrum.psa[i],
                foh[i],
                0.01,
            );
            // Regression bound against the same model by other means: 5e-3, ~6.5× the largest
            // difference measured over the 100 periods (7.7e-4 / 7.4e-4). The other two
            // references differ by method (1.2e-2 at 10–30 dt, 4.1e-3 beyond): 5× those would
            // exceed their tolerances, which therefore stay the only bound.
            let rel = (im.spectrum.psa[i] - foh[i]).abs() / foh[i];
            assert!(
                rel <= 5e-3,
                "{name}: PSA({t:.4} s) vs state-space foh: {rel:.2e} within 1 % but above the regression bound 5e-3"
            );
            if t >= 10.0 * dt {
                let tol = 0.01 + (std::f64::consts::PI * dt / t).powi(2) / 3.0;
                check(
                    name,
                    &format!("PSA({t:.4} s) vs pyrotd"),
                    im.spectrum.psa[i],
                    rotd[i],
                    tol,
                );
                compared += 1;
            }
            if t >= 30.0 * dt {
                check(
                    name,
                    &format!("PSA({t:.4} s) vs eqsig"),
                    im.spectrum.psa[i],
                    nj[i],
                    0.01,
                );
            }
        }
        assert!(compared >= 66, "{name}: only {compared} periods compared");
        // Largest relative differences by band, quoted in docs/motion.md.
        for (lo, hi) in [(0.0, 10.0), (10.0, 30.0), (30.0, f64::INFINITY)] {
            let band = |refv: &[f64]| {
                (0..periods.len())
                    .filter(|&i| periods[i] >= lo * dt && periods[i] < hi * dt)
                    .map(|i| (im.spectrum.psa[i] - refv[i]).abs() / refv[i])
                    .fold(0.0_f64, f64::max)
            };
            println!(
                "{name:42} PSA, T/dt in [{lo}, {hi}): max relative difference state-space {:.1e}, pyrotd {:.1e}, eqsig {:.1e}",
                band(&foh),
                band(&rotd),
                band(&nj)
            );
        }
    }
}

/// The zero-phase Butterworth high-pass (0.1 Hz, order 4) against scipy's butter/sosfilt run
/// forward and backward over the same zero pads. Same filter definition, independent code:
/// samples agree to 1e-6 of the PGA, PGA/PGV/PGD of the filtered record to 1 %.
#[test]
fn highpass_matches_scipy() {
    let g = golden();
    for name in RECORDS {
        let r = &g["records"][name]["highpass_0.1hz_order4"];
        let gm = load(name);
        let Signal::Sampled(s) = &gm.horizontal else {
            unreachable!()
        };
        let y = highpass_zero_phase(&s.accel, s.dt, 0.1, 4);
        let pga_ref = f(r, "pga");
        for (k, want) in arr(r, "samples_every_500").iter().enumerate() {
            let got = y[500 * k];
            assert!(
                (got - want).abs() < 1e-6 * pga_ref,
                "{name}: sample {}: {got} vs {want}",
                500 * k
            );
        }
        let fs = Sampled::new(s.dt, y);
        let peak = |x: &[f64]| x.iter().fold(0.0_f64, |m, v| m.max(v.abs()));
        // Regression bounds: measured PGA 1.4e-13 / 9.5e-13, PGV 7.9e-13 / 7.4e-13 (the
        // filters' sums in another order) → 5e-12; PGD 1.5e-4 / 2.4e-7 → 1e-3 / 2e-6.
        let k = RECORDS.iter().position(|n| *n == name).expect("record");
        check2(
            k,
            "filtered PGA",
            peak(&fs.accel),
            pga_ref,
            0.01,
            [5e-12; 2],
        );
        check2(
            k,
            "filtered PGV",
            peak(&fs.vel),
            f(r, "pgv"),
            0.01,
            [5e-12; 2],
        );
        check2(
            k,
            "filtered PGD",
            peak(&fs.disp),
            f(r, "pgd"),
            0.01,
            [1e-3, 2e-6],
        );
    }
}
