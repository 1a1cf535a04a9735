//! Record processing between parsing and the engine: an optional zero-phase Butterworth
//! high-pass for raw records, then exact integration (in `Sampled::new`), then an optional
//! linear baseline removal of the displacement drift. Processed records (NGA-West2 AT2,
//! COSMOS V2, ESM processed) are only integrated: filtering them again is refused.
use super::text::RecordKind;
use super::{MotionError, Sampled};
use serde::{Deserialize, Serialize};

/// How a sampled record is processed before it drives the model. Off by default: a record is
/// used as given, which is what users of corrected database records expect.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize, Default)]
#[serde(deny_unknown_fields, default)]
pub struct ProcessParams {
    /// Zero-phase Butterworth high-pass (raw records only).
    pub highpass: Option<HighPass>,
    /// Remove the linear drift of the integrated displacement.
    pub baseline: Baseline,
}

/// Zero-phase (forward-backward) Butterworth high-pass filter.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct HighPass {
    /// Corner frequency, Hz (−6 dB after the two passes: the gain there is 1/2).
    pub corner_hz: f64,
    /// Order of the one-way filter (the two passes square its magnitude response). Default 4,
    /// the order most strong-motion processing uses (Boore & Bommer 2005).
    #[serde(default = "default_order")]
    pub order: usize,
}

fn default_order() -> usize {
    4
}

/// Baseline correction applied after integration.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "snake_case")]
pub enum Baseline {
    /// Integrate as given.
    #[default]
    None,
    /// Subtract the straight line d(T)·t/T from the displacement so the record ends where it
    /// began. Acceleration is unchanged (a line has no curvature), velocity shifts by the
    /// constant −d(T)/T: the ground starts with that small velocity instead of rest.
    Linear,
}

impl ProcessParams {
    /// Check the knobs themselves (before any record is read).
    pub fn validate(&self, origin: &str) -> Result<(), MotionError> {
        if let Some(hp) = self.highpass {
            if !(hp.corner_hz.is_finite() && hp.corner_hz > 0.0) {
                return Err(MotionError::new(
                    origin,
                    None,
                    format!("high-pass corner must be > 0 Hz, got {}", hp.corner_hz),
                ));
            }
            if !(1..=12).contains(&hp.order) {
                return Err(MotionError::new(
                    origin,
                    None,
                    format!("high-pass order must be 1..=12, got {}", hp.order),
                ));
            }
        }
        Ok(())
    }

    /// Turn an acceleration series (m/s²) into a `Sampled` signal.
    pub fn apply(
        &self,
        origin: &str,
        kind: RecordKind,
        dt: f64,
        accel: Vec<f64>,
    ) -> Result<Sampled, MotionError> {
        self.validate(origin)?;
        let accel = match self.highpass {
            None => accel,
            Some(_) if kind == RecordKind::Processed => {
                return Err(MotionError::new(
                    origin,
                    None,
                    "this record is already processed (filtered and baseline-corrected by its provider); high-pass filtering is for raw records, use the linear baseline option instead",
                ))
            }
            Some(hp) => {
                let nyquist = 0.5 / dt;
                if hp.corner_hz >= nyquist {
                    return Err(MotionError::new(
                        origin,
                        None,
                        format!("high-pass corner {} Hz must be below the Nyquist frequency {} Hz", hp.corner_hz, crate::quantity::sig(nyquist)),
                    ));
                }
                highpass_zero_phase(&accel, dt, hp.corner_hz, hp.order)
            }
        };
        let mut s = Sampled::new(dt, accel);
        if self.baseline == Baseline::Linear {
            remove_linear_drift(&mut s);
        }
        Ok(s)
    }
}

/// Subtract d(T)·t/T from the displacement and d(T)/T from the velocity (see `Baseline`).
pub fn remove_linear_drift(s: &mut Sampled) {
    let n = s.disp.len();
    let duration = s.duration();
    if n < 2 || duration <= 0.0 {
        return;
    }
    let rate = s.disp[n - 1] / duration;
    for i in 0..n {
        s.vel[i] -= rate;
        s.disp[i] -= rate * i as f64 * s.dt;
    }
}

/// One second-order (or first-order, b2 = a2 = 0) section, a0 normalised to 1.
#[derive(Debug, Clone, Copy)]
struct Biquad {
    b: [f64; 3],
    a: [f64; 2],
}

/// Digital Butterworth high-pass sections by the bilinear transform with the corner pre-warped,
/// so the digital magnitude is exactly 1 / sqrt(1 + (tan(π fc dt) / tan(π f dt))^(2n)).
fn butterworth_highpass(corner_hz: f64, dt: f64, order: usize) -> Vec<Biquad> {
    let k = (std::f64::consts::PI * corner_hz * dt).tan();
    let mut sections = Vec::new();
    for j in 0..order / 2 {
        // Pole pair of the normalised prototype: s² + 2 sin(θ) s + 1.
        let theta = std::f64::consts::PI * (2 * j + 1) as f64 / (2 * order) as f64;
        let c = 2.0 * theta.sin();
        // High-pass s → K/s' after bilinear s' = (1 − z⁻¹)/(1 + z⁻¹).
        let a0 = 1.0 + c * k + k * k;
        sections.push(Biquad {
            b: [1.0 / a0, -2.0 / a0, 1.0 / a0],
            a: [2.0 * (k * k - 1.0) / a0, (1.0 - c * k + k * k) / a0],
        });
    }
    if order % 2 == 1 {
        let a0 = 1.0 + k;
        sections.push(Biquad {
            b: [1.0 / a0, -1.0 / a0, 0.0],
            a: [(k - 1.0) / a0, 0.0],
        });
    }
    sections
}

fn run_sections(sections: &[Biquad], x: &mut [f64]) {
    for s in sections {
        let (mut z1, mut z2) = (0.0, 0.0);
        for v in x.iter_mut() {
            // Transposed direct form II.
            let y = s.b[0] * *v + z1;
            z1 = s.b[1] * *v - s.a[0] * y + z2;
            z2 = s.b[2] * *v - s.a[1] * y;
            *v = y;
        }
    }
}

/// Zero-phase Butterworth high-pass: zero pads of 1.5·order/fc seconds on both ends (Converse &
/// Brady 1992) absorb the filter transients, the filter runs forward then backward, and the
/// pads are cut off again so the record keeps its length and time origin.
pub fn highpass_zero_phase(accel: &[f64], dt: f64, corner_hz: f64, order: usize) -> Vec<f64> {
    let pad = ((1.5 * order as f64 / corner_hz) / dt).ceil() as usize;
    let pad = pad.min(4 * accel.len() + 1000);
    let mut x = vec![0.0; accel.len() + 2 * pad];
    x[pad..pad + accel.len()].copy_from_slice(accel);
    let sections = butterworth_highpass(corner_hz, dt, order);
    run_sections(&sections, &mut x);
    x.reverse();
    run_sections(&sections, &mut x);
    x.reverse();
    x[pad..pad + accel.len()].to_vec()
}

/// Gain of the zero-phase filter at frequency f (the square of the one-way magnitude).
pub fn highpass_gain(f: f64, dt: f64, corner_hz: f64, order: usize) -> f64 {
    let r = (std::f64::consts::PI * corner_hz * dt).tan() / (std::f64::consts::PI * f * dt).tan();
    1.0 / (1.0 + r.powi(2 * order as i32))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A long sine through the zero-phase filter keeps its phase and is scaled by the closed-form
    /// gain |H(f)|². Tolerance 1e-3 relative: the middle of a 400-cycle record is far from the
    /// pads' transients, which decay as exp(−2π fc t) over many corner periods.
    #[test]
    fn steady_sine_gain_and_zero_phase() {
        let dt = 0.005;
        for (f, order) in [(0.2, 4), (0.5, 4), (1.0, 3), (4.0, 4)] {
            let fc = 0.5;
            let n = (400.0 / f / dt) as usize;
            let x: Vec<f64> = (0..n)
                .map(|i| (2.0 * std::f64::consts::PI * f * i as f64 * dt).sin())
                .collect();
            let y = highpass_zero_phase(&x, dt, fc, order);
            let g = highpass_gain(f, dt, fc, order);
            let mid = n / 2;
            let span = (2.0 / f / dt) as usize;
            // Least-squares amplitude and phase over two cycles in the middle.
            let (mut s, mut c) = (0.0, 0.0);
            for i in mid..mid + span {
                let w = 2.0 * std::f64::consts::PI * f * i as f64 * dt;
                s += y[i] * w.sin();
                c += y[i] * w.cos();
            }
            let amp = 2.0 * (s * s + c * c).sqrt() / span as f64;
            assert!(
                (amp - g).abs() < 1e-3 * g.max(1e-3) + 1e-6,
                "f={f}: amplitude {amp} vs gain {g}"
            );
            assert!(
                c.abs() < 1e-3 * s.abs().max(1e-9) + 1e-9,
                "f={f}: phase shift (cos part {c})"
            );
        }
    }

    #[test]
    fn linear_baseline_zeroes_final_displacement_and_keeps_acceleration() {
        let s0 = Sampled::new(
            0.01,
            (0..500).map(|i| 0.1 + (i as f64 * 0.05).sin()).collect(),
        );
        let mut s = s0.clone();
        remove_linear_drift(&mut s);
        assert!(s.disp[s.disp.len() - 1].abs() < 1e-12);
        assert_eq!(s.accel, s0.accel);
        // Exactness of the corrected pair under eval: d' = v, v' = a still hold (central differences).
        let (t, h) = (2.345, 1e-5);
        let (_, v, _) = s.eval(t);
        let (_, _, dp) = s.eval(t + h);
        let (_, _, dm) = s.eval(t - h);
        assert!(((dp - dm) / (2.0 * h) - v).abs() < 1e-6);
    }
}
