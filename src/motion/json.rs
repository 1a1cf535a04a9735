//! Ground motion as JSON (FORMAT.md §2). Provisional minimal reader: samples, pulses and sines;
//! file formats embedded as `{"format": ..., "content": ...}` are added by the records work.
use super::*;

/// Parse a FORMAT.md §2 ground-motion object.
pub fn from_json(value: &serde_json::Value) -> Result<GroundMotion, MotionError> {
    let obj = value
        .as_object()
        .ok_or_else(|| MotionError::new("motion", None, "expected an object with \"horizontal\", \"vertical\", \"scale\""))?;
    for k in obj.keys() {
        if !matches!(k.as_str(), "horizontal" | "vertical" | "scale") {
            return Err(MotionError::new(format!("motion.{k}"), None, "unknown field"));
        }
    }
    let comp = |name: &str| -> Result<Signal, MotionError> {
        match obj.get(name) {
            None | Some(serde_json::Value::Null) => Ok(Signal::Zero),
            Some(v) => component(&format!("motion.{name}"), v),
        }
    };
    let mut gm = GroundMotion { horizontal: comp("horizontal")?, vertical: comp("vertical")?, scale: 1.0, provenance: "json".into() };
    if let Some(s) = obj.get("scale").filter(|s| !s.is_null()) {
        let scale: ScaleSpec = serde_json::from_value(s.clone()).map_err(|e| MotionError::new("motion.scale", None, e.to_string()))?;
        match (scale.factor, scale.target_pga) {
            (Some(f), None) if f.is_finite() => gm.scale = f,
            (None, Some(x)) if x.is_finite() && x >= 0.0 => gm = gm.scaled_to_pga(x * scale.units.unwrap_or(Units::MetresPerSecond2).to_si()),
            _ => return Err(MotionError::new("motion.scale", None, "give exactly one finite \"factor\" or a non-negative \"target_pga\"")),
        }
    }
    Ok(gm)
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct ScaleSpec {
    factor: Option<f64>,
    target_pga: Option<f64>,
    units: Option<Units>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct SamplesSpec {
    samples: Vec<f64>,
    dt: f64,
    #[serde(default)]
    units: Units,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct PulseSpec {
    #[serde(default = "sine_shape")]
    shape: String,
    amplitude: f64,
    period: f64,
    #[serde(default = "one")]
    cycles: f64,
    #[serde(default)]
    phase: f64,
    #[serde(default)]
    units: Units,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct SineSpec {
    amplitude: f64,
    frequency: f64,
    #[serde(default)]
    units: Units,
}

fn sine_shape() -> String {
    "sine".into()
}
fn one() -> f64 {
    1.0
}

fn component(path: &str, v: &serde_json::Value) -> Result<Signal, MotionError> {
    let bad = |e: serde_json::Error| MotionError::new(path, None, e.to_string());
    if let Some(p) = v.get("pulse") {
        let p: PulseSpec = serde_json::from_value(p.clone()).map_err(bad)?;
        if !(p.period > 0.0 && p.period.is_finite() && p.cycles > 0.0 && p.cycles.is_finite() && p.amplitude.is_finite() && p.phase.is_finite()) {
            return Err(MotionError::new(format!("{path}.pulse"), None, "amplitude and phase must be finite, period and cycles > 0"));
        }
        let phase = match p.shape.as_str() {
            "sine" => p.phase,
            "cosine" => p.phase + std::f64::consts::FRAC_PI_2,
            other => return Err(MotionError::new(format!("{path}.pulse.shape"), None, format!("unknown shape {other:?} (sine, cosine)"))),
        };
        return Ok(Signal::Pulse { amplitude: p.amplitude * p.units.to_si(), period: p.period, cycles: p.cycles, phase });
    }
    if let Some(s) = v.get("sine") {
        let s: SineSpec = serde_json::from_value(s.clone()).map_err(bad)?;
        if !(s.amplitude.is_finite() && s.frequency > 0.0 && s.frequency.is_finite()) {
            return Err(MotionError::new(format!("{path}.sine"), None, "amplitude must be finite and frequency > 0"));
        }
        return Ok(Signal::Sine { amplitude: s.amplitude * s.units.to_si(), frequency: s.frequency });
    }
    if v.get("samples").is_some() {
        let s: SamplesSpec = serde_json::from_value(v.clone()).map_err(bad)?;
        if !(s.dt > 0.0 && s.dt.is_finite()) {
            return Err(MotionError::new(format!("{path}.dt"), None, "must be > 0"));
        }
        if s.samples.is_empty() {
            return Err(MotionError::new(format!("{path}.samples"), None, "empty record"));
        }
        let k = s.units.to_si();
        return Ok(Signal::Sampled(Sampled::new(s.dt, s.samples.iter().map(|a| a * k).collect())));
    }
    Err(MotionError::new(path, None, "expected one of {\"format\",\"content\"}, {\"samples\",\"dt\"}, {\"pulse\"}, {\"sine\"}"))
}
