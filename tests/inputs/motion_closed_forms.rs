//! Processing and intensity measures against closed forms: sine pulses and steady sines
//! (PGV = A/ω, Arias intensity of n full cycles, CAV, D5–95, mean period), the response spectrum
//! (rigid limit → PGA, undamped and damped resonance), exact integration, scaling, resampling,
//! and the zero-phase high-pass and baseline options on a real record.
use ashlar::motion::{
    self, oscillator_peak, report, report_with, GroundMotion, ReportParams, Sampled, Signal,
    STANDARD_GRAVITY,
};
use std::f64::consts::PI;

fn rel(a: f64, b: f64) -> f64 {
    (a - b).abs() / b.abs()
}

fn pulse(shape_phase: f64, amplitude: f64, period: f64, cycles: f64) -> GroundMotion {
    GroundMotion::horizontal(Signal::Pulse {
        amplitude,
        period,
        cycles,
        phase: shape_phase,
    })
}

/// A sampled sine a(t) = A sin(2π t / T) over n full cycles, `per` samples a period.
fn sampled_sine(amplitude: f64, period: f64, cycles: usize, per: usize) -> GroundMotion {
    let dt = period / per as f64;
    let n = cycles * per + 1;
    let a = (0..n)
        .map(|i| amplitude * (2.0 * PI * i as f64 * dt / period).sin())
        .collect();
    GroundMotion::horizontal(Signal::Sampled(Sampled::new(dt, a)))
}

/// Cosine pulse of full cycles: v = A/ω sin ωt, so PGV = A/ω; from rest a sine gives
/// v = A/ω (1 − cos ωt), PGV = 2A/ω, and d grows monotonically to PGD = A·nT/ω.
/// Tolerance 1e-4: the report samples analytic signals every 1 ms, and a sampled sine's peak
/// misses the true one by at most 1 − cos(π·1 ms/T) ≈ 2e-5 for T = 0.5 s.
#[test]
fn peak_velocity_and_displacement_of_pulses() {
    let (a, t, n) = (2.0, 0.5, 3.0);
    let w = 2.0 * PI / t;
    let im = report(&pulse(PI / 2.0, a, t, n));
    assert!(
        rel(im.pgv, a / w) < 1e-4,
        "cosine PGV {} vs A/ω {}",
        im.pgv,
        a / w
    );
    assert!(rel(im.pga, a) < 1e-12, "cosine PGA");
    let im = report(&pulse(0.0, a, t, n));
    assert!(
        rel(im.pgv, 2.0 * a / w) < 1e-4,
        "sine PGV {} vs 2A/ω",
        im.pgv
    );
    assert!(
        rel(im.pgd, a * n * t / w) < 1e-4,
        "sine PGD {} vs A nT/ω",
        im.pgd
    );
}

/// Arias intensity of n full cycles of A sin ωt: π/(2g) · A² nT/2. The trapezoidal rule is exact
/// (to rounding) for a trigonometric polynomial over whole periods, so 1e-9 for both the analytic
/// pulse and a sampled sine. CAV = 4nA/ω (tolerance 2e-4: the trapezoidal rule on each
/// half-wave of |sin| underestimates by (ω dt)²/12 = 1.3e-4 at 160 samples a period). D5–95 = 9T for 10 cycles exactly (at 0.5 and 9.5 cycles the oscillating part of
/// the cumulative integral vanishes); tolerance 1e-4 for the linear interpolation inside a step.
#[test]
fn arias_cav_and_significant_duration_of_sines() {
    let (a, t) = (3.0, 0.8);
    for n in [4usize, 10] {
        let expected = PI / (2.0 * STANDARD_GRAVITY) * a * a * n as f64 * t / 2.0;
        let im = report(&pulse(0.0, a, t, n as f64));
        assert!(
            rel(im.arias_intensity, expected) < 1e-9,
            "pulse n={n}: {} vs {expected}",
            im.arias_intensity
        );
        let im = report(&sampled_sine(a, t, n, 160));
        assert!(
            rel(im.arias_intensity, expected) < 1e-9,
            "sampled n={n}: {} vs {expected}",
            im.arias_intensity
        );
        let cav = 4.0 * n as f64 * a / (2.0 * PI / t);
        assert!(rel(im.cav, cav) < 2e-4, "CAV n={n}: {} vs {cav}", im.cav);
    }
    let im = report(&sampled_sine(a, t, 10, 160));
    assert!(
        rel(im.significant_duration_5_95, 9.0 * t) < 1e-4,
        "D5-95 {}",
        im.significant_duration_5_95
    );
}

/// Mean period of a pure 2 Hz sine of 40 cycles: the Fourier energy sits at 2 Hz with leakage of
/// width ~1/(40 cycles), so Tm = 0.5 s to 1 %.
#[test]
fn mean_period_of_a_sine() {
    let im = report(&sampled_sine(1.0, 0.5, 40, 100));
    assert!(rel(im.mean_period, 0.5) < 0.01, "Tm {}", im.mean_period);
}

/// A steady sine is measured over `steady_duration`: its Arias intensity grows linearly.
#[test]
fn steady_sine_uses_the_report_duration() {
    let gm = GroundMotion::horizontal(Signal::Sine {
        amplitude: 1.0,
        frequency: 2.0,
    });
    let im = report_with(
        &gm,
        &ReportParams {
            steady_duration: 5.0,
            ..ReportParams::default()
        },
    );
    let expected = PI / (2.0 * STANDARD_GRAVITY) * 5.0 / 2.0;
    assert!(rel(im.arias_intensity, expected) < 1e-9 && rel(im.duration, 5.0) < 1e-12);
}

/// Rigid limit: an oscillator of T = 0.01 s follows a 1 Hz ground motion, its pseudo-acceleration
/// tends to the PGA (static amplification 1/(1 − (T/1 s)²) = 1.0001). Tolerance 0.5 %.
#[test]
fn spectrum_tends_to_pga_at_short_periods() {
    let gm = sampled_sine(2.0, 1.0, 5, 200);
    let im = report(&gm);
    assert_eq!(im.spectrum.periods[0], 0.01);
    assert!(
        rel(im.spectrum.psa[0], im.pga) < 0.005,
        "PSA(0.01) {} vs PGA {}",
        im.spectrum.psa[0],
        im.pga
    );
    assert!((im.spectrum.periods[99] - 10.0).abs() < 1e-9);
}

/// Undamped oscillator driven at resonance from rest: u = A/(2ω²)(sin ωt − ωt cos ωt), whose
/// peak over n cycles is A/(2ω²)·2πn, so PSA = πnA. Damped (5 %), the amplitude tends to
/// A/(2ζω²): PSA → A/(2ζ) = 10 A after 40 cycles (transient e^{−ζω t} < 4e-6).
/// Tolerances 1e-3 and 5e-3: linear interpolation of a sine at 200 samples a period.
#[test]
fn resonance_amplification() {
    let (a, t, n) = (1.5, 0.4, 5usize);
    let gm = sampled_sine(a, t, n, 200);
    let Signal::Sampled(s) = &gm.horizontal else {
        unreachable!()
    };
    let w = 2.0 * PI / t;
    let psa = oscillator_peak(&s.accel, s.dt, t, 0.0) * w * w;
    assert!(
        rel(psa, PI * n as f64 * a) < 1e-3,
        "undamped PSA {psa} vs {}",
        PI * n as f64 * a
    );
    let gm = sampled_sine(a, t, 40, 200);
    let Signal::Sampled(s) = &gm.horizontal else {
        unreachable!()
    };
    let psa = oscillator_peak(&s.accel, s.dt, t, 0.05) * w * w;
    assert!(
        rel(psa, a / 0.1) < 5e-3,
        "damped PSA {psa} vs A/(2ζ) {}",
        a / 0.1
    );
}

/// Sampled integration is exact for piecewise-linear acceleration: a ramp a = c·t gives
/// v = c t²/2 and d = c t³/6 at any t, between samples too (tolerance 1e-12, rounding).
/// After the record the acceleration is zero and the ground coasts at its final velocity.
#[test]
fn sampled_integration_is_exact() {
    let (c, dt) = (0.7, 0.013);
    let s = Sampled::new(dt, (0..101).map(|i| c * i as f64 * dt).collect());
    for &t in &[0.0, 0.0051, 0.4, 0.777, 1.3] {
        let (a, v, d) = s.eval(t);
        assert!(
            (a - c * t).abs() < 1e-12
                && (v - c * t * t / 2.0).abs() < 1e-12
                && (d - c * t.powi(3) / 6.0).abs() < 1e-12,
            "t={t}"
        );
    }
    let end = s.duration();
    let (a, v, d) = s.eval(end + 0.5);
    let v_end = c * end * end / 2.0;
    assert!(
        a == 0.0
            && (v - v_end).abs() < 1e-12
            && (d - (c * end.powi(3) / 6.0 + v_end * 0.5)).abs() < 1e-12
    );
}

/// Pulses are integrated exactly: d' = v and v' = a by central differences (h = 1e-5 s, error
/// O(h²) ≈ 1e-9), and v, d continuous at the end of the pulse.
#[test]
fn pulse_integrals_are_consistent() {
    for phase in [0.0, 0.3, PI / 2.0] {
        let sig = Signal::Pulse {
            amplitude: 4.0,
            period: 0.7,
            cycles: 1.5,
            phase,
        };
        let h = 1e-5;
        for &t in &[0.1, 0.5, 0.9, 1.2, 2.0] {
            let (a, v, _) = sig.eval(t);
            let (_, vp, dp) = sig.eval(t + h);
            let (_, vm, dm) = sig.eval(t - h);
            assert!(
                ((vp - vm) / (2.0 * h) - a).abs() < 1e-5,
                "v' = a at {t}, phase {phase}"
            );
            assert!(
                ((dp - dm) / (2.0 * h) - v).abs() < 1e-6,
                "d' = v at {t}, phase {phase}"
            );
        }
        let end = 0.7 * 1.5;
        let (_, v0, d0) = sig.eval(end - 1e-9);
        let (_, v1, d1) = sig.eval(end + 1e-9);
        assert!((v0 - v1).abs() < 1e-7 && (d0 - d1).abs() < 1e-7);
    }
}

/// Scaling by a factor multiplies PGA, PGV, PGD linearly and Arias intensity quadratically;
/// scaling to a target PGA hits it exactly; `acceleration` agrees with `state`.
#[test]
fn scaling() {
    let gm = motion::load_path(std::path::Path::new(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/data/ground-motions/northridge-1994-mulholland-009.at2"
    )))
    .expect("record");
    let base = report(&gm);
    let im = report(&gm.scaled(2.5));
    assert!(rel(im.pga, 2.5 * base.pga) < 1e-12 && rel(im.pgv, 2.5 * base.pgv) < 1e-12);
    assert!(rel(im.arias_intensity, 6.25 * base.arias_intensity) < 1e-12);
    assert!(rel(im.spectrum.psa[50], 2.5 * base.spectrum.psa[50]) < 1e-12);
    assert!((im.significant_duration_5_95 - base.significant_duration_5_95).abs() < 1e-12);
    let target = gm.scaled_to_pga(3.0);
    assert!((target.pga() - 3.0).abs() < 1e-12 && (report(&target).pga - 3.0).abs() < 1e-12);
    for &t in &[0.0, 1.234, 15.0, 40.0] {
        let [ax, ay] = target.acceleration(t);
        let st = target.state(t);
        assert!((ax - st[0][0]).abs() < 1e-12 && ay == 0.0 && st[0][1] == 0.0);
    }
}

/// Linear resampling: the original samples are reproduced, midpoints are averages.
#[test]
fn resampling_is_linear_interpolation() {
    let s = Sampled::new(0.02, vec![0.0, 1.0, -2.0, 4.0, 3.0]);
    let r = s.resampled(0.01);
    assert_eq!(r.accel.len(), 9);
    for i in 0..5 {
        assert!((r.accel[2 * i] - s.accel[i]).abs() < 1e-12);
    }
    for i in 0..4 {
        assert!((r.accel[2 * i + 1] - 0.5 * (s.accel[i] + s.accel[i + 1])).abs() < 1e-12);
    }
    // The exact integrals of the same piecewise-linear signal agree at the shared samples.
    assert!((r.disp[8] - s.disp[4]).abs() < 1e-12 && (r.vel[8] - s.vel[4]).abs() < 1e-12);
}

/// Linear baseline on a real record with a typical raw-record offset (0.01 m/s² added to the
/// Kobe record, which drifts 8 m over its 41 s): the final displacement is zero, acceleration
/// unchanged, and what `Signal::eval` returns (the driven block's input) is the corrected
/// displacement.
#[test]
fn linear_baseline_on_a_record() {
    use motion::{Baseline, ProcessParams, RecordKind};
    let path = std::path::Path::new(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/data/ground-motions/kobe-1995-nishi-akashi-000.csv"
    ));
    let raw = motion::load_path(path).expect("record");
    let Signal::Sampled(s) = &raw.horizontal else {
        unreachable!()
    };
    let offset: Vec<f64> = s.accel.iter().map(|a| a + 0.01).collect();
    let drifting = ProcessParams::default()
        .apply("kobe+offset", RecordKind::Raw, s.dt, offset.clone())
        .expect("raw");
    let end = drifting.duration();
    assert!(
        drifting.eval(end).2 > 1.0,
        "the offset record drifts, so the test means something"
    );
    let p = ProcessParams {
        baseline: Baseline::Linear,
        ..Default::default()
    };
    let fixed = Signal::Sampled(
        p.apply("kobe+offset", RecordKind::Raw, s.dt, offset.clone())
            .expect("raw"),
    );
    let (_, _, d_end) = fixed.eval(end);
    assert!(d_end.abs() < 1e-9, "final displacement {d_end}");
    let Signal::Sampled(f) = &fixed else {
        unreachable!()
    };
    assert_eq!(f.accel, offset);
}
