//! Ground motion: records and analytic signals, evaluated at any time. Feeds `assembly`
//! (inertial loads) and the driven-block excitation; independent of the engine otherwise.
//!
//! Sign convention: horizontal acceleration positive along +x, vertical positive along +y.
//! All values inside are SI (m/s², m/s, m); the original units are kept for reporting.
use serde::{Deserialize, Serialize};

mod json;
pub use json::from_json;

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
        Self { origin: source.into(), line, message: message.into() }
    }
}

/// A uniformly sampled acceleration record with its exact integrals under linear interpolation.
#[derive(Debug, Clone, PartialEq)]
pub struct Sampled {
    /// s.
    pub dt: f64,
    /// m/s².
    pub accel: Vec<f64>,
    /// m/s at each sample (exact integral of the piecewise-linear acceleration, v(0) = 0).
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
        Self { dt, accel, vel, disp }
    }

    pub fn duration(&self) -> f64 {
        self.dt * (self.accel.len().saturating_sub(1)) as f64
    }

    /// (a, v, d) at time t: linear acceleration between samples, zero acceleration after the end.
    pub fn eval(&self, t: f64) -> (f64, f64, f64) {
        let n = self.accel.len();
        if n == 0 || t <= 0.0 {
            return (if n > 0 && t == 0.0 { self.accel[0] } else { 0.0 }, 0.0, 0.0);
        }
        let x = t / self.dt;
        let i = x.floor() as usize;
        if i + 1 >= n {
            let tl = t - self.duration();
            let v = self.vel[n - 1];
            return (0.0, v, self.disp[n - 1] + v * tl);
        }
        let s = t - i as f64 * self.dt;
        let (a0, a1) = (self.accel[i], self.accel[i + 1]);
        let slope = (a1 - a0) / self.dt;
        let a = a0 + slope * s;
        let v = self.vel[i] + a0 * s + 0.5 * slope * s * s;
        let d = self.disp[i] + self.vel[i] * s + 0.5 * a0 * s * s + slope * s * s * s / 6.0;
        (a, v, d)
    }
}

/// One component of ground motion, already in m/s².
#[derive(Debug, Clone, PartialEq)]
pub enum Signal {
    Zero,
    Sampled(Sampled),
    /// a(t) = amplitude · sin(2π t / period + phase) for 0 ≤ t ≤ cycles · period, zero after.
    Pulse { amplitude: f64, period: f64, cycles: f64, phase: f64 },
    /// a(t) = amplitude · sin(2π f t) for all t ≥ 0.
    Sine { amplitude: f64, frequency: f64 },
}

impl Signal {
    /// (acceleration, velocity, displacement) at t, with v(0) = d(0) = 0. Analytic signals are
    /// integrated exactly.
    pub fn eval(&self, t: f64) -> (f64, f64, f64) {
        match self {
            Signal::Zero => (0.0, 0.0, 0.0),
            Signal::Sampled(s) => s.eval(t),
            Signal::Pulse { amplitude, period, cycles, phase } => {
                let w = 2.0 * std::f64::consts::PI / period;
                let end = cycles * period;
                let te = t.clamp(0.0, end);
                let a = if t >= 0.0 && t <= end { amplitude * (w * t + phase).sin() } else { 0.0 };
                let v = amplitude / w * (phase.cos() - (w * te + phase).cos());
                let d = amplitude / w * te * phase.cos() - amplitude / (w * w) * ((w * te + phase).sin() - phase.sin());
                let (v, d) = if t > end { (v, d + v * (t - end)) } else { (v, d) };
                (a, v, d)
            }
            Signal::Sine { amplitude, frequency } => {
                let w = 2.0 * std::f64::consts::PI * frequency;
                let t = t.max(0.0);
                (amplitude * (w * t).sin(), amplitude / w * (1.0 - (w * t).cos()), amplitude / w * t - amplitude / (w * w) * (w * t).sin())
            }
        }
    }

    /// Length of the signal in s (`None` for steady signals and zero).
    pub fn duration(&self) -> Option<f64> {
        match self {
            Signal::Zero | Signal::Sine { .. } => None,
            Signal::Sampled(s) => Some(s.duration()),
            Signal::Pulse { period, cycles, .. } => Some(period * cycles),
        }
    }

    /// Peak absolute acceleration, m/s².
    pub fn peak(&self) -> f64 {
        match self {
            Signal::Zero => 0.0,
            Signal::Sampled(s) => s.accel.iter().fold(0.0, |m, a| m.max(a.abs())),
            Signal::Pulse { amplitude, period, cycles, phase } => {
                // Sample densely plus the analytic maxima inside the window.
                let n = 2000;
                let end = cycles * period;
                let w = 2.0 * std::f64::consts::PI / period;
                let mut m: f64 = 0.0;
                for k in 0..=n {
                    let t = end * k as f64 / n as f64;
                    m = m.max((amplitude * (w * t + phase).sin()).abs());
                }
                let mut k = ((phase - std::f64::consts::FRAC_PI_2) / std::f64::consts::PI).floor() - 1.0;
                loop {
                    let t = (std::f64::consts::FRAC_PI_2 + k * std::f64::consts::PI - phase) / w;
                    if t > end {
                        break;
                    }
                    if t >= 0.0 {
                        m = m.max(amplitude.abs());
                    }
                    k += 1.0;
                }
                m
            }
            Signal::Sine { amplitude, .. } => amplitude.abs(),
        }
    }
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
}

impl GroundMotion {
    /// No shaking at all (a scene under gravity alone).
    pub fn none() -> Self {
        Self { horizontal: Signal::Zero, vertical: Signal::Zero, scale: 1.0, provenance: "none".into() }
    }

    pub fn horizontal(signal: Signal) -> Self {
        Self { horizontal: signal, vertical: Signal::Zero, scale: 1.0, provenance: "analytic".into() }
    }

    /// Ground acceleration [ax, ay] at t, m/s².
    #[inline]
    pub fn acceleration(&self, t: f64) -> [f64; 2] {
        [self.scale * self.horizontal.eval(t).0, self.scale * self.vertical.eval(t).0]
    }

    /// Ground (acceleration, velocity, displacement), each [x, y], at t.
    pub fn state(&self, t: f64) -> [[f64; 2]; 3] {
        let h = self.horizontal.eval(t);
        let v = self.vertical.eval(t);
        let s = self.scale;
        [[s * h.0, s * v.0], [s * h.1, s * v.1], [s * h.2, s * v.2]]
    }

    /// Record length, s (the longer component), or `None` for steady or no motion.
    pub fn duration(&self) -> Option<f64> {
        match (self.horizontal.duration(), self.vertical.duration()) {
            (Some(a), Some(b)) => Some(a.max(b)),
            (a, b) => a.or(b),
        }
    }

    /// Peak horizontal acceleration after scaling, m/s².
    pub fn pga(&self) -> f64 {
        self.scale.abs() * self.horizontal.peak()
    }

    /// A copy scaled so that the horizontal PGA equals `target` (m/s²).
    pub fn scaled_to_pga(&self, target: f64) -> Self {
        let peak = self.horizontal.peak();
        let mut out = self.clone();
        out.scale = if peak > 0.0 { target / peak } else { 0.0 };
        out
    }
}
