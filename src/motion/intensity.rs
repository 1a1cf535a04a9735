//! Intensity measures of a ground motion (docs/format.md §3, output of `ashlar motion`): peaks,
//! Arias intensity, significant duration, CAV, mean period and the pseudo-acceleration response
//! spectrum, plus the spectrum as a hand-written SVG. Reads `GroundMotion`; nothing reads it
//! back but the CLI, the service and job reports.
//!
//! Length (over 600 lines): about a third is unit tests (closed forms, the SVG's text boxes);
//! the drawing's pieces are `crate::plot`'s.
use super::{GroundMotion, Signal, Units, STANDARD_GRAVITY};
use crate::plot::{self, Anchor};
use serde::{Deserialize, Serialize};

/// Knobs of `report_with`. The defaults reproduce the docs/format.md §3 output.
#[derive(Debug, Clone, PartialEq)]
pub struct ReportParams {
    /// Oscillator damping ratio of the spectrum; 5 % is the engineering convention.
    pub damping: f64,
    /// Shortest and longest spectral period, s (0.01–10 s: rigid to very flexible structures).
    pub period_range: (f64, f64),
    /// Number of log-spaced periods; 100 resolves spectral peaks to about 7 % in period.
    pub periods: usize,
    /// Sample interval used to evaluate analytic pulses and sines, s: 1 ms resolves any pulse
    /// slower than 10 Hz to better than 0.1 % in peak values.
    pub analytic_dt: f64,
    /// Length over which a steady sine is measured, s (it has no end of its own).
    pub steady_duration: f64,
}

impl Default for ReportParams {
    fn default() -> Self {
        Self {
            damping: 0.05,
            period_range: (0.01, 10.0),
            periods: 100,
            analytic_dt: 0.001,
            steady_duration: 10.0,
        }
    }
}

/// The pseudo-acceleration response spectrum.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Spectrum {
    /// Damping ratio (0.05 = 5 %).
    pub damping: f64,
    /// Oscillator periods, s.
    pub periods: Vec<f64>,
    /// Pseudo-spectral acceleration ω² max|u|, m/s².
    pub psa: Vec<f64>,
}

/// Intensity measures of the horizontal component after scaling, SI units (docs/format.md §3).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct IntensityMeasures {
    pub npts: usize,
    /// s.
    pub dt: f64,
    /// s.
    pub duration: f64,
    pub original_units: Units,
    /// m/s².
    pub pga: f64,
    /// PGA in the record's original units (after scaling).
    pub pga_original_units: f64,
    /// PGA in g (standard gravity, 9.80665 m/s²), whatever the record's units.
    #[serde(default)]
    pub pga_g: f64,
    /// m/s.
    pub pgv: f64,
    /// m.
    pub pgd: f64,
    /// Ia = π/(2g) ∫a² dt, m/s.
    pub arias_intensity: f64,
    /// Time between 5 % and 95 % of the Arias intensity, s.
    pub significant_duration_5_95: f64,
    /// ∫|a| dt, m/s.
    pub cav: f64,
    /// Rathje et al. (1998) mean period Σ(C²/f)/ΣC² over 0.25–20 Hz, s.
    pub mean_period: f64,
    pub spectrum: Spectrum,
    /// Where the record came from (file, format, processing).
    pub provenance: String,
    /// The unit of every numeric field, by field name (`spectrum` nested): see
    /// [`intensity_units`].
    #[serde(default)]
    pub units: serde_json::Value,
}

/// The `units` object of the intensity measures: each numeric field's unit ("1" for a ratio,
/// "count" for a number of samples); `pga_original_units` is in the record's own units.
pub fn intensity_units(original: Units) -> serde_json::Value {
    serde_json::json!({
        "npts": "count",
        "dt": "s",
        "duration": "s",
        "pga": "m/s2",
        "pga_original_units": original.name(),
        "pga_g": "g",
        "pgv": "m/s",
        "pgd": "m",
        "arias_intensity": "m/s",
        "significant_duration_5_95": "s",
        "cav": "m/s",
        "mean_period": "s",
        "spectrum": { "damping": "1", "periods": "s", "psa": "m/s2" },
    })
}

/// Intensity measures with the default parameters.
pub fn report(gm: &GroundMotion) -> IntensityMeasures {
    report_with(gm, &ReportParams::default())
}

/// Intensity measures of the scaled horizontal component.
pub fn report_with(gm: &GroundMotion, p: &ReportParams) -> IntensityMeasures {
    let (dt, a, v, d) = sampled_series(&gm.horizontal, gm.scale, p);
    let peak = |x: &[f64]| x.iter().fold(0.0_f64, |m, y| m.max(y.abs()));
    let pga = peak(&a);
    let periods = log_periods(p.period_range.0, p.period_range.1, p.periods);
    let psa = response_spectrum(&a, dt, &periods, p.damping);
    let arias = cumulative_arias(&a, dt);
    IntensityMeasures {
        npts: a.len(),
        dt,
        duration: dt * a.len().saturating_sub(1) as f64,
        original_units: gm.meta.original_units,
        pga,
        pga_original_units: pga / gm.meta.original_units.to_si(),
        pga_g: pga / STANDARD_GRAVITY,
        pgv: peak(&v),
        pgd: peak(&d),
        arias_intensity: arias.last().copied().unwrap_or(0.0),
        significant_duration_5_95: significant_duration(&arias, dt, 0.05, 0.95),
        cav: a
            .windows(2)
            .map(|w| 0.5 * dt * (w[0].abs() + w[1].abs()))
            .sum(),
        mean_period: mean_period(&a, dt),
        spectrum: Spectrum {
            damping: p.damping,
            periods,
            psa,
        },
        provenance: gm.provenance.clone(),
        units: intensity_units(gm.meta.original_units),
    }
}

/// (dt, a, v, d) of a signal on a uniform grid: the record's own samples and exact integrals,
/// or the analytic signal evaluated exactly every `analytic_dt`.
fn sampled_series(
    sig: &Signal,
    scale: f64,
    p: &ReportParams,
) -> (f64, Vec<f64>, Vec<f64>, Vec<f64>) {
    let sc = |x: &[f64]| x.iter().map(|y| y * scale).collect::<Vec<_>>();
    match sig {
        Signal::Zero => (0.0, vec![], vec![], vec![]),
        Signal::Sampled(s) => (s.dt, sc(&s.accel), sc(&s.vel), sc(&s.disp)),
        _ => {
            let length = sig.duration().unwrap_or(p.steady_duration);
            let n = (length / p.analytic_dt).round().max(1.0) as usize;
            let dt = length / n as f64;
            let (mut a, mut v, mut d) = (
                Vec::with_capacity(n + 1),
                Vec::with_capacity(n + 1),
                Vec::with_capacity(n + 1),
            );
            for i in 0..=n {
                // The pulse's end sample is evaluated just inside so it keeps its value.
                let t = (i as f64 * dt).min(length * (1.0 - 1e-15));
                let (ai, vi, di) = sig.eval(t);
                a.push(ai * scale);
                v.push(vi * scale);
                d.push(di * scale);
            }
            (dt, a, v, d)
        }
    }
}

/// Time (s) of the largest horizontal ground acceleration, the motion sampled every `every`
/// seconds over its duration (0 for a motion without one): where a short window of a long
/// record is cut for tests and benchmarks.
pub fn peak_time(gm: &GroundMotion, every: f64) -> f64 {
    let (mut best, mut at, mut t) = (0.0, 0.0, 0.0);
    while t < gm.duration().unwrap_or(0.0) {
        let a = gm.acceleration(t)[0].abs();
        if a > best {
            best = a;
            at = t;
        }
        t += every;
    }
    at
}

/// `n` periods log-spaced from `lo` to `hi` inclusive.
pub fn log_periods(lo: f64, hi: f64, n: usize) -> Vec<f64> {
    if n <= 1 {
        return vec![lo];
    }
    let r = (hi / lo).ln();
    (0..n)
        .map(|i| lo * (r * i as f64 / (n - 1) as f64).exp())
        .collect()
}

/// Cumulative Arias intensity π/(2g) ∫₀ᵗ a² dt (trapezoidal), m/s, at each sample.
pub fn cumulative_arias(a: &[f64], dt: f64) -> Vec<f64> {
    let k = std::f64::consts::PI / (2.0 * STANDARD_GRAVITY);
    let mut out = Vec::with_capacity(a.len());
    let mut sum = 0.0;
    for i in 0..a.len() {
        if i > 0 {
            sum += k * 0.5 * dt * (a[i - 1] * a[i - 1] + a[i] * a[i]);
        }
        out.push(sum);
    }
    out
}

/// Time between the fractions `lo` and `hi` of the final cumulative value, interpolating
/// linearly inside the step where each is crossed.
pub fn significant_duration(cum: &[f64], dt: f64, lo: f64, hi: f64) -> f64 {
    let total = cum.last().copied().unwrap_or(0.0);
    if total <= 0.0 {
        return 0.0;
    }
    let crossing = |level: f64| -> f64 {
        let target = level * total;
        let i = cum.partition_point(|&c| c < target);
        if i == 0 {
            return 0.0;
        }
        let (c0, c1) = (cum[i - 1], cum[i]);
        let frac = if c1 > c0 {
            (target - c0) / (c1 - c0)
        } else {
            0.0
        };
        (i as f64 - 1.0 + frac) * dt
    };
    crossing(hi) - crossing(lo)
}

/// Mean period Tm (Rathje, Abrahamson & Bray 1998): Σ(Cᵢ²/fᵢ)/ΣCᵢ² over the Fourier amplitudes
/// with 0.25 ≤ fᵢ ≤ 20 Hz. The record is zero-padded to a power of two for the FFT; padding
/// refines the frequency grid without changing the spectrum it samples.
pub fn mean_period(a: &[f64], dt: f64) -> f64 {
    if a.is_empty() || dt <= 0.0 {
        return 0.0;
    }
    let n = a.len().next_power_of_two();
    let mut re = vec![0.0; n];
    let mut im = vec![0.0; n];
    re[..a.len()].copy_from_slice(a);
    fft(&mut re, &mut im);
    let df = 1.0 / (n as f64 * dt);
    let (mut num, mut den) = (0.0, 0.0);
    for k in 1..=n / 2 {
        let f = k as f64 * df;
        if (0.25..=20.0).contains(&f) {
            let c2 = re[k] * re[k] + im[k] * im[k];
            num += c2 / f;
            den += c2;
        }
    }
    if den > 0.0 {
        num / den
    } else {
        0.0
    }
}

/// In-place radix-2 FFT (length a power of two).
fn fft(re: &mut [f64], im: &mut [f64]) {
    let n = re.len();
    let mut j = 0;
    for i in 1..n {
        let mut bit = n >> 1;
        while j & bit != 0 {
            j ^= bit;
            bit >>= 1;
        }
        j |= bit;
        if i < j {
            re.swap(i, j);
            im.swap(i, j);
        }
    }
    let mut len = 2;
    while len <= n {
        let ang = -2.0 * std::f64::consts::PI / len as f64;
        for start in (0..n).step_by(len) {
            for k in 0..len / 2 {
                let (s, c) = (ang * k as f64).sin_cos();
                let (a, b) = (start + k, start + k + len / 2);
                let tr = re[b] * c - im[b] * s;
                let ti = re[b] * s + im[b] * c;
                re[b] = re[a] - tr;
                im[b] = im[a] - ti;
                re[a] += tr;
                im[a] += ti;
            }
        }
        len <<= 1;
    }
}

/// Pseudo-spectral acceleration ω² max|u| of damped oscillators ü + 2ζωu̇ + ω²u = −a(t) at rest
/// at t = 0, by the exact recurrence for piecewise-linear excitation (Nigam & Jennings 1969;
/// Chopra, Dynamics of Structures §5.2). Each record step is split into substeps so that an
/// oscillator period spans at least 20 of them: the recurrence stays exact for the same
/// piecewise-linear input, and the peak between record samples is not missed. The free vibration
/// after the record ends is included (for long periods the peak can come after the shaking).
pub fn response_spectrum(a: &[f64], dt: f64, periods: &[f64], damping: f64) -> Vec<f64> {
    periods
        .iter()
        .map(|&t| oscillator_peak(a, dt, t, damping) * (2.0 * std::f64::consts::PI / t).powi(2))
        .collect()
}

/// max |u| of one oscillator of period `t` (s) and damping ratio `z` (< 1).
pub fn oscillator_peak(a: &[f64], dt: f64, period: f64, z: f64) -> f64 {
    if a.len() < 2
        || period.is_nan()
        || period <= 0.0
        || dt.is_nan()
        || dt <= 0.0
        || !(0.0..1.0).contains(&z)
    {
        return 0.0;
    }
    let sub = ((20.0 * dt / period).ceil() as usize).clamp(1, 10_000);
    let h = dt / sub as f64;
    let c = Recurrence::new(2.0 * std::f64::consts::PI / period, z, h);
    let (mut u, mut v, mut peak) = (0.0_f64, 0.0_f64, 0.0_f64);
    for w in a.windows(2) {
        for s in 0..sub {
            let p0 = -(w[0] + (w[1] - w[0]) * s as f64 / sub as f64);
            let p1 = -(w[0] + (w[1] - w[0]) * (s + 1) as f64 / sub as f64);
            let un = c.a * u + c.b * v + c.c * p0 + c.d * p1;
            let vn = c.a2 * u + c.b2 * v + c.c2 * p0 + c.d2 * p1;
            peak = peak.max(substep_peak(u, v, un, vn, h));
            u = un;
            v = vn;
        }
    }
    // Free vibration after the record: the envelope only decays, so one period holds its peak.
    for _ in 0..((period / h).ceil() as usize).min(1_000_000) {
        let un = c.a * u + c.b * v;
        let vn = c.a2 * u + c.b2 * v;
        peak = peak.max(substep_peak(u, v, un, vn, h));
        u = un;
        v = vn;
    }
    peak
}

/// max |u| over one substep of length `h` from the end states (u0, v0) and (u1, v1). When the
/// velocity changes sign inside, the extremum is located on the cubic Hermite interpolant of the
/// exact end states: with at least 20 substeps a period its error is below (2π/20)⁴/384 ≈ 3e-5
/// of the amplitude, where reading the peak at the substeps alone misses up to
/// 1 − cos(π/20) = 1.2 %.
fn substep_peak(u0: f64, v0: f64, u1: f64, v1: f64, h: f64) -> f64 {
    let mut peak = u1.abs();
    if v0 * v1 < 0.0 {
        let (hv0, hv1) = (h * v0, h * v1);
        // p'(s) = qa s² + qb s + qc on s ∈ [0, 1].
        let qa = 6.0 * (u0 - u1) + 3.0 * (hv0 + hv1);
        let qb = 6.0 * (u1 - u0) - 4.0 * hv0 - 2.0 * hv1;
        let qc = hv0;
        let hermite = |s: f64| {
            let s2 = s * s;
            let s3 = s2 * s;
            (2.0 * s3 - 3.0 * s2 + 1.0) * u0
                + (s3 - 2.0 * s2 + s) * hv0
                + (-2.0 * s3 + 3.0 * s2) * u1
                + (s3 - s2) * hv1
        };
        let mut consider = |s: f64| {
            if (0.0..=1.0).contains(&s) {
                peak = peak.max(hermite(s).abs());
            }
        };
        if qa.abs() < 1e-300 {
            if qb != 0.0 {
                consider(-qc / qb);
            }
        } else {
            let disc = qb * qb - 4.0 * qa * qc;
            if disc >= 0.0 {
                let r = disc.sqrt();
                consider((-qb + r) / (2.0 * qa));
                consider((-qb - r) / (2.0 * qa));
            }
        }
    }
    peak
}

/// Coefficients of u_{i+1} = A u_i + B u̇_i + C p_i + D p_{i+1} and its velocity counterpart
/// for unit mass, stiffness ω² and a load p varying linearly over the step h.
struct Recurrence {
    a: f64,
    b: f64,
    c: f64,
    d: f64,
    a2: f64,
    b2: f64,
    c2: f64,
    d2: f64,
}

impl Recurrence {
    fn new(w: f64, z: f64, h: f64) -> Self {
        let k = w * w;
        let sq = (1.0 - z * z).sqrt();
        let wd = w * sq;
        let e = (-z * w * h).exp();
        let (s, c) = (wd * h).sin_cos();
        Self {
            a: e * (z / sq * s + c),
            b: e * s / wd,
            c: (2.0 * z / (w * h)
                + e * (((1.0 - 2.0 * z * z) / (wd * h) - z / sq) * s
                    - (1.0 + 2.0 * z / (w * h)) * c))
                / k,
            d: (1.0 - 2.0 * z / (w * h)
                + e * ((2.0 * z * z - 1.0) / (wd * h) * s + 2.0 * z / (w * h) * c))
                / k,
            a2: -e * w / sq * s,
            b2: e * (c - z / sq * s),
            c2: (-1.0 / h + e * ((w / sq + z / (h * sq)) * s + c / h)) / k,
            d2: (1.0 - e * (z / sq * s + c)) / (k * h),
        }
    }
}

/// Estimated width of one character, in em, when laying out SVG text without a font at hand:
/// DejaVu Sans, the widest common sans-serif, averages 0.68 em over capitals and less over
/// lower case, digits and spaces, so 0.7 em over-estimates any realistic line (a title that
/// fits by this estimate fits in the browser).
const SVG_CHAR_EM: f64 = 0.7;

/// `text` broken into lines of at most `max_chars` characters, at spaces (or at `/` in paths)
/// where possible, hard-broken otherwise; at most `max_lines` lines, the last one ending in `…`
/// when text was left out.
fn wrap_text(text: &str, max_chars: usize, max_lines: usize) -> Vec<String> {
    let max_chars = max_chars.max(2);
    let mut lines: Vec<String> = Vec::new();
    let mut rest: Vec<char> = text
        .split_whitespace()
        .collect::<Vec<_>>()
        .join(" ")
        .chars()
        .collect();
    while !rest.is_empty() {
        if rest.len() <= max_chars {
            lines.push(rest.iter().collect());
            break;
        }
        // The last space (dropped) or slash (kept) within the line; else a hard break.
        let window = &rest[..=max_chars];
        let cut = match window.iter().rposition(|c| *c == ' ' || *c == '/') {
            Some(i) if i > 0 && window[i] == ' ' => (i, i + 1),
            Some(i) if i > 0 && i < max_chars => (i + 1, i + 1),
            _ => (max_chars, max_chars),
        };
        lines.push(rest[..cut.0].iter().collect());
        rest.drain(..cut.1);
    }
    if lines.len() > max_lines {
        lines.truncate(max_lines);
        let last = &mut lines[max_lines - 1];
        let mut chars: Vec<char> = last.chars().collect();
        chars.truncate(max_chars - 1);
        *last = chars.into_iter().collect::<String>() + "…";
    }
    lines
}

/// The spectrum as a standalone SVG: log period axis, linear PSA axis in m/s² (and g on the
/// right), title from the provenance. The title wraps to the drawing's width (a record's
/// provenance, file path and header included, is often wider than the plot), and the top margin
/// grows with its lines, so that no text leaves the viewBox.
pub fn spectrum_svg(im: &IntensityMeasures) -> String {
    let sp = &im.spectrum;
    let w = 720.0;
    // Title: the heading at 14 px, then the provenance at 12 px on up to 4 lines, both centred
    // with a 10 px margin on each side.
    let heading = format!(
        "{} % damped pseudo-acceleration spectrum",
        fmt(100.0 * sp.damping)
    );
    let usable = w - 20.0;
    let mut title: Vec<(String, f64)> =
        wrap_text(&heading, (usable / (14.0 * SVG_CHAR_EM)) as usize, 2)
            .into_iter()
            .map(|line| (line, 14.0))
            .collect();
    title.extend(
        wrap_text(&im.provenance, (usable / (12.0 * SVG_CHAR_EM)) as usize, 4)
            .into_iter()
            .map(|line| (line, 12.0)),
    );
    // Baselines: each line a font size and a third below the previous one.
    let mut baselines = Vec::with_capacity(title.len());
    let mut y_text = 4.0;
    for (_, size) in &title {
        y_text += size * 1.3;
        baselines.push(y_text);
    }
    let (l, r, b) = (70.0, 60.0, 50.0);
    let t = y_text + 14.0;
    let ph = 350.0;
    let h = t + ph + b;
    let pw = w - l - r;
    let (lo, hi) = (
        sp.periods.first().copied().unwrap_or(0.01).max(1e-6),
        sp.periods.last().copied().unwrap_or(10.0).max(1e-5),
    );
    let ymax = plot::nice_ceiling(sp.psa.iter().fold(0.0_f64, |m, y| m.max(*y)).max(1e-9));
    let x = |p: f64| l + pw * ((p / lo).ln() / (hi / lo).ln().max(1e-12));
    let y = |a: f64| t + ph * (1.0 - a / ymax);
    let mut s = plot::document(w, h, 12.0, true);
    for ((line, size), y_line) in title.iter().zip(&baselines) {
        s += &plot::title_line(w / 2.0, plot::tenth(*y_line), *size, line);
    }
    // Decade grid on the period axis.
    let mut dec = 10f64.powf(lo.log10().floor());
    while dec <= hi * 1.0001 {
        if dec >= lo * 0.9999 {
            let xd = x(dec);
            s += &plot::grid_line(xd, t, xd, t + ph);
            s += &plot::text(
                plot::tenth(xd),
                t + ph + 16.0,
                Anchor::Middle,
                "",
                &fmt(dec),
            );
        }
        dec *= 10.0;
    }
    for i in 0..=5 {
        let a = ymax * i as f64 / 5.0;
        let yy = y(a);
        s += &plot::grid_line(l, yy, l + pw, yy);
        let label_y = plot::tenth(yy + 4.0);
        s += &plot::text(l - 6.0, label_y, Anchor::End, "", &fmt(a));
        s += &plot::text(
            l + pw + 6.0,
            label_y,
            Anchor::Start,
            "",
            &fmt(a / STANDARD_GRAVITY),
        );
    }
    s += &plot::frame(l, t, pw, ph);
    let pts: Vec<(f64, f64)> = sp
        .periods
        .iter()
        .zip(&sp.psa)
        .map(|(p, a)| (x(*p), y(*a)))
        .collect();
    s += &plot::polyline(&pts, "#c0392b", 2.0, "");
    s += &plot::text(l + pw / 2.0, h - 10.0, Anchor::Middle, "", "period (s)");
    s += &plot::axis_title(18.0, t + ph / 2.0, -90.0, "PSA (m/s²)");
    s += &plot::axis_title(w - 14.0, t + ph / 2.0, 90.0, "PSA (g)");
    s += plot::END;
    s
}

fn fmt(v: f64) -> String {
    plot::short(v, 3)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Constant excitation from rest: u(t) = −a/ω² (1 − e^{−ζωt}(cos ω_D t + ζ/√(1−ζ²) sin ω_D t)),
    /// which the recurrence must reproduce to rounding (the input is exactly piecewise linear).
    #[test]
    fn recurrence_is_exact_for_a_step_load() {
        let (w, z, h) = (2.0 * std::f64::consts::PI / 0.7, 0.05, 0.013);
        let c = Recurrence::new(w, z, h);
        let (mut u, mut v) = (0.0, 0.0);
        let a = 1.3;
        for i in 1..=500 {
            let un = c.a * u + c.b * v + c.c * -a + c.d * -a;
            v = c.a2 * u + c.b2 * v + c.c2 * -a + c.d2 * -a;
            u = un;
            let t = i as f64 * h;
            let wd = w * (1.0 - z * z).sqrt();
            let exact = -a / (w * w)
                * (1.0
                    - (-z * w * t).exp()
                        * ((wd * t).cos() + z / (1.0 - z * z).sqrt() * (wd * t).sin()));
            assert!((u - exact).abs() < 1e-12, "step {i}: {u} vs {exact}");
        }
    }

    #[test]
    fn fft_matches_a_direct_dft() {
        let x: Vec<f64> = (0..16).map(|i| ((i * i) % 7) as f64 - 3.0).collect();
        let (mut re, mut im) = (x.clone(), vec![0.0; 16]);
        fft(&mut re, &mut im);
        for k in 0..16 {
            let (mut r, mut i) = (0.0, 0.0);
            for (n, xn) in x.iter().enumerate() {
                let ang = -2.0 * std::f64::consts::PI * (k * n) as f64 / 16.0;
                r += xn * ang.cos();
                i += xn * ang.sin();
            }
            assert!((re[k] - r).abs() < 1e-9 && (im[k] - i).abs() < 1e-9);
        }
    }

    #[test]
    fn svg_is_well_formed_enough() {
        let gm = GroundMotion::horizontal(Signal::Pulse {
            amplitude: 3.0,
            period: 0.5,
            cycles: 2.0,
            phase: 0.0,
        });
        let im = report(&gm);
        let svg = spectrum_svg(&im);
        assert!(svg.starts_with("<svg") && svg.trim_end().ends_with("</svg>"));
        assert_eq!(plot::read::count(&svg, "polyline"), 1);
        assert!(svg.matches(',').count() >= im.spectrum.periods.len());
    }

    /// The title of `ashlar motion --svg` was one line of 14 px text centred on a 720 px wide
    /// drawing; a record's provenance (path, format and header) made it some 1,400 px wide, so
    /// both ends were cut off. Every text of the drawing, the title's lines above all, must lie
    /// inside the viewBox, for a short provenance and for a long one.
    #[test]
    fn svg_text_lies_inside_the_viewbox() {
        let gm = GroundMotion::horizontal(Signal::Pulse {
            amplitude: 3.0,
            period: 0.5,
            cycles: 2.0,
            phase: 0.0,
        });
        let long = "data/ground-motions/friuli-1976-tolmezzo-000.at2 (at2: Friuli, \
                    Italy, Tolmezzo, FRIULI/A-TMZ000 PEER NGA STRONG MOTION DATABASE RECORD)";
        let unbroken = "W".repeat(400);
        for provenance in ["pulse", long, &unbroken] {
            let mut im = report(&gm);
            im.provenance = provenance.to_string();
            let svg = spectrum_svg(&im);
            let (boxes, [vx0, vy0, vx1, vy1]) = plot::read::text_boxes(&svg);
            let titles = svg.matches("class=\"title\"").count();
            assert!(titles >= 2, "{provenance}: {titles} title lines");
            for (text, x0, y0, x1, y1) in &boxes {
                assert!(
                    *x0 >= vx0 && *y0 >= vy0 && *x1 <= vx1 && *y1 <= vy1,
                    "{provenance}: {text:?} spans ({x0:.1}, {y0:.1})–({x1:.1}, {y1:.1}), \
                     outside the viewBox ({vx0}, {vy0})–({vx1}, {vy1})"
                );
            }
            // The title is all there: every word of a provenance that fits in 4 lines.
            if provenance != unbroken {
                let shown: String = boxes
                    .iter()
                    .map(|b| b.0.as_str())
                    .collect::<Vec<_>>()
                    .join(" ");
                for word in provenance.split_whitespace() {
                    for part in word.split('/') {
                        assert!(shown.contains(part), "{part:?} missing from the title");
                    }
                }
            } else {
                assert!(
                    boxes.iter().any(|b| b.0.ends_with('…')),
                    "an overlong title is not marked as cut"
                );
            }
        }
    }
}
