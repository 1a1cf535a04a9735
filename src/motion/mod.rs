//! Ground motion: records and analytic signals, evaluated at any time. Feeds `assembly`
//! (inertial loads) and the driven-block excitation; independent of the engine otherwise.
//!
//! Sign convention: horizontal acceleration positive along +x, vertical positive along +y.
//! All values inside are SI (m/s², m/s, m); the original units are kept for reporting.
//!
//! Length (over 600 lines): the `GroundMotion` type, its evaluation, the loaders' dispatch and
//! their tests; each format's reader is already its own file.
use serde::{Deserialize, Serialize};
use std::path::Path;

mod at2;
mod cosmos;
mod csv;
mod esm;
mod intensity;
mod json;
pub mod options;
mod process;
mod text;
pub use intensity::{
    cumulative_arias, intensity_units, log_periods, mean_period, oscillator_peak, peak_time,
    report, report_with, response_spectrum, significant_duration, spectrum_svg, IntensityMeasures,
    ReportParams, Spectrum,
};
pub use json::{
    from_json, from_json_with, ComponentSpec, MotionSpec, PulseSpec, ScaleSpec, SineSpec,
};
pub use options::{
    parse_acceleration, AccelerationError, Amplitude, RecordArgs, RecordOptionError, UnitsArg,
};
pub use process::{
    highpass_gain, highpass_zero_phase, remove_linear_drift, Baseline, HighPass, ProcessParams,
};
pub use text::{RawRecord, RecordKind};

/// Units a record may come in.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
pub enum Units {
    /// Standard gravity, 9.80665 m/s².
    #[serde(rename = "g")]
    #[default]
    G,
    #[serde(rename = "m/s2")]
    MetresPerSecond2,
    #[serde(rename = "cm/s2", alias = "gal")]
    CentimetresPerSecond2,
}

/// Standard gravity used for records in g, m/s².
pub const STANDARD_GRAVITY: f64 = 9.80665;

impl Units {
    /// The docs/format.md name ("g", "m/s2", "cm/s2").
    pub fn name(self) -> &'static str {
        match self {
            Units::G => "g",
            Units::MetresPerSecond2 => "m/s2",
            Units::CentimetresPerSecond2 => "cm/s2",
        }
    }

    /// Parse a unit name as users and file headers write it (`g`, `m/s2`, `m/s^2`, `cm/s2`,
    /// `cm/sec2`, `gal`).
    pub fn parse(text: &str) -> Option<Units> {
        text::parse_units(text)
    }

    /// Factor converting a value in these units to m/s².
    pub fn to_si(self) -> f64 {
        match self {
            Units::G => STANDARD_GRAVITY,
            Units::MetresPerSecond2 => 1.0,
            Units::CentimetresPerSecond2 => 0.01,
        }
    }
}

/// A failure to read or interpret a ground motion. `source` names the file or field,
/// `line` the 1-based line where known.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("{origin}{}: {message}", line.map(|l| format!(", line {l}")).unwrap_or_default())]
pub struct MotionError {
    pub origin: String,
    pub line: Option<usize>,
    pub message: String,
}

impl MotionError {
    pub fn new(source: impl Into<String>, line: Option<usize>, message: impl Into<String>) -> Self {
        Self {
            origin: source.into(),
            line,
            message: message.into(),
        }
    }
}

/// A uniformly sampled acceleration record with its exact integrals under linear interpolation.
/// Between samples the acceleration is linear (this is also how the solver resamples it);
/// after the last sample it is zero and the ground keeps its final velocity.
#[derive(Debug, Clone, PartialEq)]
pub struct Sampled {
    /// s.
    pub dt: f64,
    /// m/s².
    pub accel: Vec<f64>,
    /// m/s at each sample (exact integral of the piecewise-linear acceleration, v(0) = 0
    /// unless a baseline correction shifted it).
    pub vel: Vec<f64>,
    /// m at each sample (exact integral, d(0) = 0).
    pub disp: Vec<f64>,
}

impl Sampled {
    pub fn new(dt: f64, accel: Vec<f64>) -> Self {
        let n = accel.len();
        let mut vel = vec![0.0; n];
        let mut disp = vec![0.0; n];
        for i in 1..n {
            let (a0, a1) = (accel[i - 1], accel[i]);
            vel[i] = vel[i - 1] + 0.5 * dt * (a0 + a1);
            disp[i] = disp[i - 1] + dt * vel[i - 1] + dt * dt * (a0 / 3.0 + a1 / 6.0);
        }
        Self {
            dt,
            accel,
            vel,
            disp,
        }
    }

    pub fn duration(&self) -> f64 {
        self.dt * (self.accel.len().saturating_sub(1)) as f64
    }

    /// Index of the step holding t and the offset into it, or `None` outside [0, duration).
    #[inline]
    fn locate(&self, t: f64) -> Option<(usize, f64)> {
        let n = self.accel.len();
        if n < 2 || t.is_nan() || t < 0.0 {
            return None;
        }
        let x = t / self.dt;
        if x >= (n - 1) as f64 {
            return None;
        }
        let i = x as usize;
        Some((i, t - i as f64 * self.dt))
    }

    /// Acceleration at t (linear between samples, zero outside the record). O(1).
    #[inline]
    pub fn accel_at(&self, t: f64) -> f64 {
        match self.locate(t) {
            Some((i, s)) => self.accel[i] + (self.accel[i + 1] - self.accel[i]) * s / self.dt,
            None if t == self.duration() => self.accel.last().copied().unwrap_or(0.0),
            None => 0.0,
        }
    }

    /// (a, v, d) at time t: linear acceleration between samples, zero acceleration after the end.
    pub fn eval(&self, t: f64) -> (f64, f64, f64) {
        let n = self.accel.len();
        if n == 0 {
            return (0.0, 0.0, 0.0);
        }
        if t.is_nan() || t <= 0.0 {
            let a0 = if t == 0.0 { self.accel[0] } else { 0.0 };
            return (a0, self.vel[0], self.disp[0]);
        }
        let Some((i, s)) = self.locate(t) else {
            let tl = t - self.duration();
            let v = self.vel[n - 1];
            let a = if tl == 0.0 { self.accel[n - 1] } else { 0.0 };
            return (a, v, self.disp[n - 1] + v * tl);
        };
        let (a0, a1) = (self.accel[i], self.accel[i + 1]);
        let slope = (a1 - a0) / self.dt;
        let a = a0 + slope * s;
        let v = self.vel[i] + a0 * s + 0.5 * slope * s * s;
        let d = self.disp[i] + self.vel[i] * s + 0.5 * a0 * s * s + slope * s * s * s / 6.0;
        (a, v, d)
    }

    /// The record resampled at a new interval by linear interpolation (what the solver sees),
    /// over the same duration.
    pub fn resampled(&self, dt: f64) -> Sampled {
        if !(dt > 0.0 && dt.is_finite()) || self.accel.is_empty() {
            return self.clone();
        }
        let n = (self.duration() / dt + 1e-9).floor() as usize + 1;
        Sampled::new(dt, (0..n).map(|k| self.accel_at(k as f64 * dt)).collect())
    }
}

/// One component of ground motion, already in m/s².
#[derive(Debug, Clone, PartialEq)]
pub enum Signal {
    Zero,
    Sampled(Sampled),
    /// a(t) = amplitude · sin(2π t / period + phase) for 0 ≤ t ≤ cycles · period, zero after.
    Pulse {
        amplitude: f64,
        period: f64,
        cycles: f64,
        phase: f64,
    },
    /// a(t) = amplitude · sin(2π f t) for all t ≥ 0.
    Sine {
        amplitude: f64,
        frequency: f64,
    },
}

impl Signal {
    /// Acceleration alone at t, m/s² (the solver's hot path: no integrals computed).
    #[inline]
    pub fn accel(&self, t: f64) -> f64 {
        match self {
            Signal::Zero => 0.0,
            Signal::Sampled(s) => s.accel_at(t),
            Signal::Pulse {
                amplitude,
                period,
                cycles,
                phase,
            } => {
                let w = 2.0 * std::f64::consts::PI / period;
                if t >= 0.0 && t <= cycles * period {
                    amplitude * (w * t + phase).sin()
                } else {
                    0.0
                }
            }
            Signal::Sine {
                amplitude,
                frequency,
            } => {
                if t >= 0.0 {
                    amplitude * (2.0 * std::f64::consts::PI * frequency * t).sin()
                } else {
                    0.0
                }
            }
        }
    }

    /// (acceleration, velocity, displacement) at t, with v(0) = d(0) = 0. Analytic signals are
    /// integrated exactly.
    pub fn eval(&self, t: f64) -> (f64, f64, f64) {
        match self {
            Signal::Zero => (0.0, 0.0, 0.0),
            Signal::Sampled(s) => s.eval(t),
            Signal::Pulse {
                amplitude,
                period,
                cycles,
                phase,
            } => {
                let w = 2.0 * std::f64::consts::PI / period;
                let end = cycles * period;
                let te = t.clamp(0.0, end);
                let a = self.accel(t);
                let v = amplitude / w * (phase.cos() - (w * te + phase).cos());
                let d = amplitude / w * te * phase.cos()
                    - amplitude / (w * w) * ((w * te + phase).sin() - phase.sin());
                let (v, d) = if t > end {
                    (v, d + v * (t - end))
                } else {
                    (v, d)
                };
                (a, v, d)
            }
            Signal::Sine {
                amplitude,
                frequency,
            } => {
                let w = 2.0 * std::f64::consts::PI * frequency;
                let t = t.max(0.0);
                (
                    self.accel(t),
                    amplitude / w * (1.0 - (w * t).cos()),
                    amplitude / w * t - amplitude / (w * w) * (w * t).sin(),
                )
            }
        }
    }

    /// The first time after `t` (s) at which the acceleration's slope (or value) may jump: the
    /// next sample of a record, the end of a record or of a pulse; `f64::INFINITY` when the
    /// signal is smooth from `t` on. Between two of them the acceleration is linear (records)
    /// or analytic (pulses, sines), so an ODE step that ends there sees a smooth load.
    pub fn next_kink(&self, t: f64) -> f64 {
        // Times within 1e-12 s of t are t itself (the run loops' time resolution).
        const SAME: f64 = 1e-12;
        match self {
            Signal::Zero | Signal::Sine { .. } => f64::INFINITY,
            Signal::Pulse { period, cycles, .. } => {
                let end = cycles * period;
                if t < end - SAME {
                    end
                } else {
                    f64::INFINITY
                }
            }
            Signal::Sampled(s) => {
                let end = s.duration();
                if s.accel.len() < 2 || t.is_nan() || t >= end - SAME {
                    return f64::INFINITY;
                }
                // Sample k is at k·dt, the same product `duration` and `locate` use. The cast
                // truncates, which is the floor of a quotient ≥ 0 (and costs no call to `floor`,
                // which this target does not inline: this runs once a step of a reduced model).
                let mut k = (t.max(0.0) / s.dt) as usize + 1;
                while (k as f64) * s.dt <= t + SAME {
                    k += 1;
                }
                ((k as f64) * s.dt).min(end)
            }
        }
    }

    /// Is the acceleration linear between the times [`Signal::next_kink`] gives? (Records and
    /// zero; pulses and sines are curved.)
    pub fn piecewise_linear(&self) -> bool {
        matches!(self, Signal::Zero | Signal::Sampled(_))
    }

    /// Length of the signal in s (`None` for steady signals and zero).
    pub fn duration(&self) -> Option<f64> {
        match self {
            Signal::Zero | Signal::Sine { .. } => None,
            Signal::Sampled(s) => Some(s.duration()),
            Signal::Pulse { period, cycles, .. } => Some(period * cycles),
        }
    }

    /// s, the time from which the acceleration is zero for ever (0 for a zero signal or one
    /// whose samples are all zero; `None` for a sine that never ends). A record is linear
    /// between samples, so it is still from the sample after its last non-zero one.
    pub fn still_from(&self) -> Option<f64> {
        match self {
            Signal::Zero => Some(0.0),
            Signal::Sampled(s) => Some(match s.accel.iter().rposition(|&a| a != 0.0) {
                Some(k) => ((k + 1) as f64 * s.dt).min(s.duration()),
                None => 0.0,
            }),
            Signal::Pulse {
                amplitude,
                period,
                cycles,
                ..
            } => Some(if *amplitude == 0.0 {
                0.0
            } else {
                period * cycles
            }),
            Signal::Sine { amplitude, .. } => (*amplitude == 0.0).then_some(0.0),
        }
    }

    /// Peak absolute acceleration, m/s².
    pub fn peak(&self) -> f64 {
        match self {
            Signal::Zero => 0.0,
            Signal::Sampled(s) => s.accel.iter().fold(0.0, |m, a| m.max(a.abs())),
            Signal::Pulse {
                amplitude,
                cycles,
                phase,
                ..
            } => {
                // |sin| reaches 1 inside the window if a crest (phase angle π/2 + kπ) falls in
                // [phase, phase + 2π·cycles]; otherwise the peak is at an end of the window.
                let (start, stop) = (*phase, phase + 2.0 * std::f64::consts::PI * cycles);
                let k = ((start - std::f64::consts::FRAC_PI_2) / std::f64::consts::PI).ceil();
                let crest = std::f64::consts::FRAC_PI_2 + k * std::f64::consts::PI;
                let ends = start.sin().abs().max(stop.sin().abs());
                amplitude.abs() * if crest <= stop { 1.0 } else { ends }
            }
            Signal::Sine { amplitude, .. } => amplitude.abs(),
        }
    }
}

/// What is known about where a ground motion came from, for reports.
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
pub struct RecordMeta {
    /// Units of the horizontal record as given (values inside are SI regardless).
    pub original_units: Units,
    pub kind: RecordKind,
    /// Format of the horizontal component ("at2", "csv", "cosmos-v2", "esm", "samples", "pulse", ...).
    pub format: String,
    /// Processing applied on reading.
    pub processing: ProcessParams,
}

/// Horizontal and vertical ground motion with a common scale factor.
#[derive(Debug, Clone, PartialEq)]
pub struct GroundMotion {
    pub horizontal: Signal,
    pub vertical: Signal,
    /// Multiplies both components.
    pub scale: f64,
    /// Where the record came from (file name, format), for reports.
    pub provenance: String,
    /// Original units, record kind and processing of the horizontal component.
    pub meta: RecordMeta,
}

impl GroundMotion {
    /// No shaking at all (a scene under gravity alone).
    pub fn none() -> Self {
        Self {
            horizontal: Signal::Zero,
            vertical: Signal::Zero,
            scale: 1.0,
            provenance: "none".into(),
            meta: RecordMeta::default(),
        }
    }

    pub fn horizontal(signal: Signal) -> Self {
        let analytic = matches!(signal, Signal::Pulse { .. } | Signal::Sine { .. });
        let meta = RecordMeta {
            original_units: Units::MetresPerSecond2,
            kind: if analytic {
                RecordKind::Analytic
            } else {
                RecordKind::Unknown
            },
            ..RecordMeta::default()
        };
        Self {
            horizontal: signal,
            vertical: Signal::Zero,
            scale: 1.0,
            provenance: "analytic".into(),
            meta,
        }
    }

    /// Ground acceleration [ax, ay] at t, m/s². O(1), no allocation (called every solver step).
    #[inline]
    pub fn acceleration(&self, t: f64) -> [f64; 2] {
        [
            self.scale * self.horizontal.accel(t),
            self.scale * self.vertical.accel(t),
        ]
    }

    /// Ground (acceleration, velocity, displacement), each [x, y], at t.
    pub fn state(&self, t: f64) -> [[f64; 2]; 3] {
        let h = self.horizontal.eval(t);
        let v = self.vertical.eval(t);
        let s = self.scale;
        [[s * h.0, s * v.0], [s * h.1, s * v.1], [s * h.2, s * v.2]]
    }

    /// The first time after `t` (s) at which either component's slope may jump
    /// ([`Signal::next_kink`]).
    pub fn next_kink(&self, t: f64) -> f64 {
        self.horizontal.next_kink(t).min(self.vertical.next_kink(t))
    }

    /// Are both components linear between kinks ([`Signal::piecewise_linear`])?
    pub fn piecewise_linear(&self) -> bool {
        self.horizontal.piecewise_linear() && self.vertical.piecewise_linear()
    }

    /// Record length, s (the longer component), or `None` for steady or no motion.
    pub fn duration(&self) -> Option<f64> {
        match (self.horizontal.duration(), self.vertical.duration()) {
            (Some(a), Some(b)) => Some(a.max(b)),
            (a, b) => a.or(b),
        }
    }

    /// s, the time from which the ground acceleration is zero for ever, both components after
    /// scaling (0 when the scale is 0; `None` under a sine that never ends).
    pub fn still_from(&self) -> Option<f64> {
        if self.scale == 0.0 {
            return Some(0.0);
        }
        Some(
            self.horizontal
                .still_from()?
                .max(self.vertical.still_from()?),
        )
    }

    /// Peak horizontal acceleration after scaling, m/s².
    pub fn pga(&self) -> f64 {
        self.scale.abs() * self.horizontal.peak()
    }

    /// A copy with both components multiplied by `factor` (on top of any existing scale).
    pub fn scaled(&self, factor: f64) -> Self {
        let mut out = self.clone();
        out.scale *= factor;
        out
    }

    /// A copy scaled so that the horizontal PGA equals `target` (m/s²).
    pub fn scaled_to_pga(&self, target: f64) -> Self {
        let peak = self.horizontal.peak();
        let mut out = self.clone();
        out.scale = if peak > 0.0 { target / peak } else { 0.0 };
        out
    }

    /// The motion from `t0` (s) on, as a motion starting at 0: a(t) of the copy is a(t0 + t)
    /// of this one. Only for records whose components are sampled with a sample at `t0`
    /// (within 1e-9 of a sample interval) or zero: the copy is then the samples from there,
    /// exact; `None` otherwise (curved signals, or `t0` between samples). The copy's ground
    /// velocity and displacement start again at zero: it is meant for a base-acceleration
    /// scene, where only the acceleration loads the blocks (a run restarted from a state at
    /// rest relative to the base, `analysis::run`'s fallback).
    pub fn from_sample_at(&self, t0: f64) -> Option<Self> {
        let shift = |s: &Signal| -> Option<Signal> {
            match s {
                Signal::Zero => Some(Signal::Zero),
                Signal::Sampled(r) => {
                    let x = t0 / r.dt;
                    let k = x.round();
                    if !(k >= 0.0 && (x - k).abs() <= 1e-9 && (k as usize) + 1 < r.accel.len()) {
                        return None;
                    }
                    Some(Signal::Sampled(Sampled::new(
                        r.dt,
                        r.accel[k as usize..].to_vec(),
                    )))
                }
                Signal::Pulse { .. } | Signal::Sine { .. } => None,
            }
        };
        let mut out = self.clone();
        out.horizontal = shift(&self.horizontal)?;
        out.vertical = shift(&self.vertical)?;
        Some(out)
    }
}

/// Options for reading a record file.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct LoadParams {
    /// Units for formats that may not name them (CSV); must agree with the file when it does.
    pub units: Option<Units>,
    pub process: ProcessParams,
}

/// Record formats by name (the JSON `format` field) or file extension.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Format {
    At2,
    Csv,
    Cosmos,
    Esm,
}

impl Format {
    /// From a JSON `format` value.
    pub fn from_name(name: &str) -> Option<Format> {
        match name.to_ascii_lowercase().as_str() {
            "at2" | "peer" => Some(Format::At2),
            "csv" => Some(Format::Csv),
            "cosmos" | "v1" | "v2" => Some(Format::Cosmos),
            "esm" | "itaca" => Some(Format::Esm),
            _ => None,
        }
    }

    /// Parse text in this format.
    pub fn parse(
        self,
        origin: &str,
        content: &str,
        units: Option<Units>,
    ) -> Result<RawRecord, MotionError> {
        let rec = match self {
            Format::At2 => at2::parse(origin, content)?,
            Format::Csv => csv::parse(origin, content, units)?,
            Format::Cosmos => cosmos::parse(origin, content)?,
            Format::Esm => esm::parse(origin, content)?,
        };
        if let (Some(u), false) = (units, self == Format::Csv) {
            if u != rec.units {
                return Err(MotionError::new(
                    origin,
                    None,
                    format!(
                        "units conflict: the file says {} but {} was given",
                        rec.units.name(),
                        u.name()
                    ),
                ));
            }
        }
        Ok(rec)
    }
}

/// Turn a parsed record into a processed horizontal ground motion.
pub fn from_raw(
    origin: &str,
    rec: RawRecord,
    process: &ProcessParams,
) -> Result<GroundMotion, MotionError> {
    rec.check(origin)?;
    let k = rec.units.to_si();
    let sampled = process.apply(
        origin,
        rec.kind,
        rec.dt,
        rec.values.iter().map(|v| v * k).collect(),
    )?;
    let mut gm = GroundMotion::horizontal(Signal::Sampled(sampled));
    gm.meta = RecordMeta {
        original_units: rec.units,
        kind: rec.kind,
        format: rec.format.into(),
        processing: *process,
    };
    gm.provenance = format!(
        "{origin} ({}{})",
        rec.format,
        describe(&rec.description, process)
    );
    Ok(gm)
}

fn describe(description: &str, p: &ProcessParams) -> String {
    let mut s = String::new();
    if !description.is_empty() {
        s += &format!(": {description}");
    }
    if let Some(hp) = p.highpass {
        s += &format!("; high-pass {} Hz order {}", hp.corner_hz, hp.order);
    }
    if p.baseline == Baseline::Linear {
        s += "; linear baseline";
    }
    s
}

/// Read a record file by extension: `.at2`, `.csv`, `.v1`/`.v2` (COSMOS), `.asc` (ESM), `.json`
/// (a docs/format.md §2 object). Errors name the file and line.
pub fn load_path(path: &Path) -> Result<GroundMotion, MotionError> {
    load_path_with(path, &LoadParams::default())
}

/// `load_path` with units for unit-less CSV files and processing options.
pub fn load_path_with(path: &Path, params: &LoadParams) -> Result<GroundMotion, MotionError> {
    let origin = path.display().to_string();
    params.process.validate(&origin)?;
    let ext = path
        .extension()
        .and_then(|e| e.to_str())
        .unwrap_or("")
        .to_ascii_lowercase();
    let format = match ext.as_str() {
        "at2" => Some(Format::At2),
        "csv" | "txt" => Some(Format::Csv),
        "v1" | "v2" | "v1c" | "v2c" => Some(Format::Cosmos),
        "asc" => Some(Format::Esm),
        "json" => None,
        _ => {
            return Err(MotionError::new(
                origin,
                None,
                format!("unknown record extension {ext:?}; expected .at2, .csv, .v1, .v2 (COSMOS), .asc (ESM) or .json"),
            ))
        }
    };
    let bytes = std::fs::read(path)
        .map_err(|e| MotionError::new(&origin, None, format!("cannot read: {e}")))?;
    // Lossy: header text in Latin-1 (station names) must not stop a read; a replaced byte inside
    // a numeric field still fails with its line.
    let content = String::from_utf8_lossy(&bytes);
    let mut gm = match format {
        Some(f) => from_raw(
            &origin,
            f.parse(&origin, &content, params.units)?,
            &params.process,
        )?,
        None => {
            let value: serde_json::Value = serde_json::from_str(&content).map_err(|e| {
                MotionError::new(&origin, Some(e.line()), format!("invalid JSON: {e}"))
            })?;
            from_json_with(&value, &params.process).map_err(|e| MotionError {
                origin: format!("{origin}: {}", e.origin),
                ..e
            })?
        }
    };
    if format.is_none() {
        gm.provenance = format!("{origin} ({})", gm.provenance);
    }
    Ok(gm)
}

#[cfg(test)]
mod kink_tests {
    use super::*;

    #[test]
    fn the_motion_from_a_sample_on_is_the_same_acceleration_shifted() {
        // Reference: a(t0 + t) of the whole record, piecewise linear between the samples.
        let s = Sampled::new(0.1, vec![0.0, 1.0, -1.0, 0.5, 2.0, 0.0]);
        let gm = GroundMotion::horizontal(Signal::Sampled(s)).scaled(2.0);
        let from = gm.from_sample_at(0.2).expect("0.2 s is a sample");
        assert_eq!(from.duration(), Some(0.30000000000000004));
        for k in 0..=40 {
            let t = 0.3 * k as f64 / 40.0;
            let (a, b) = (from.acceleration(t)[0], gm.acceleration(0.2 + t)[0]);
            assert!((a - b).abs() <= 1e-12, "t = {t}: {a} against {b}");
        }
        assert_eq!(from.pga(), 4.0, "the scale is kept");
        // Between samples, at or past the last sample, or a curved signal: no exact copy.
        assert!(gm.from_sample_at(0.25).is_none());
        assert!(gm.from_sample_at(0.5).is_none());
        let pulse = GroundMotion::horizontal(Signal::Pulse {
            amplitude: 1.0,
            period: 1.0,
            cycles: 1.0,
            phase: 0.0,
        });
        assert!(pulse.from_sample_at(0.2).is_none());
    }

    #[test]
    fn kinks_are_the_samples_then_the_end_of_the_record() {
        // dt = 0.1 s, 4 samples: kinks at 0.1, 0.2, 0.3 (the end), then none. 0.3 / 0.1 rounds
        // below 3 in floating point: the kink after 0.2 must still be 0.3, not 0.2 again.
        let s = Signal::Sampled(Sampled::new(0.1, vec![0.0, 1.0, -1.0, 0.5]));
        assert_eq!(s.next_kink(0.0), 0.1);
        assert_eq!(s.next_kink(0.05), 0.1);
        let k2 = s.next_kink(0.1);
        assert_eq!(k2, 2.0 * 0.1);
        let k3 = s.next_kink(k2);
        assert_eq!(k3, 3.0 * 0.1);
        assert_eq!(
            k3,
            match &s {
                Signal::Sampled(x) => x.duration(),
                _ => unreachable!(),
            }
        );
        assert_eq!(s.next_kink(k3), f64::INFINITY);
        assert!(s.piecewise_linear());
        // A pulse kinks where it ends; a sine never.
        let p = Signal::Pulse {
            amplitude: 1.0,
            period: 1.0,
            cycles: 0.5,
            phase: 0.0,
        };
        assert_eq!((p.next_kink(0.2), p.next_kink(0.5)), (0.5, f64::INFINITY));
        assert!(!p.piecewise_linear());
        let mut gm = GroundMotion::horizontal(s);
        gm.vertical = p;
        assert_eq!(gm.next_kink(0.0), 0.1);
        assert_eq!(gm.next_kink(0.45), 0.5);
        assert!(!gm.piecewise_linear());
    }
}
