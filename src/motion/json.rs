//! Ground motion as JSON (docs/format.md §2): embedded records (`{"format", "content", "units"}`),
//! uniform samples, analytic pulses and steady sines, and the common scale. Extension: a sampled
//! component may carry `"processing": {"highpass": {"corner_hz", "order"}, "baseline": "linear"}`.
use super::*;

/// Parse a docs/format.md §2 ground-motion object.
pub fn from_json(value: &serde_json::Value) -> Result<GroundMotion, MotionError> {
    from_json_with(value, &ProcessParams::default())
}

/// `from_json` with processing applied to sampled components that do not name their own.
pub fn from_json_with(
    value: &serde_json::Value,
    process: &ProcessParams,
) -> Result<GroundMotion, MotionError> {
    let obj = value.as_object().ok_or_else(|| {
        MotionError::new(
            "motion",
            None,
            "expected an object with \"horizontal\", \"vertical\", \"scale\"",
        )
    })?;
    for k in obj.keys() {
        if !matches!(k.as_str(), "horizontal" | "vertical" | "scale") {
            return Err(MotionError::new(
                format!("motion.{k}"),
                None,
                "unknown field",
            ));
        }
    }
    let comp = |name: &str| -> Result<(Signal, RecordMeta, String), MotionError> {
        match obj.get(name) {
            None | Some(serde_json::Value::Null) => {
                Ok((Signal::Zero, RecordMeta::default(), "none".into()))
            }
            Some(v) => component(&format!("motion.{name}"), v, process),
        }
    };
    let (horizontal, meta, provenance) = comp("horizontal")?;
    let (vertical, _, _) = comp("vertical")?;
    let mut gm = GroundMotion {
        horizontal,
        vertical,
        scale: 1.0,
        provenance,
        meta,
    };
    if let Some(s) = obj.get("scale").filter(|s| !s.is_null()) {
        let scale: ScaleSpec = serde_json::from_value(s.clone())
            .map_err(|e| MotionError::new("motion.scale", None, e.to_string()))?;
        match (scale.factor, scale.target_pga) {
            (Some(f), None) if f.is_finite() => gm.scale = f,
            (None, Some(x)) => {
                let units = scale.units.unwrap_or(Units::MetresPerSecond2);
                let target = x
                    .to_si(units)
                    .map_err(|e| MotionError::new("motion.scale.target_pga", None, e.to_string()))?;
                gm = gm.scaled_to_pga(target)
            }
            _ => {
                return Err(MotionError::new(
                    "motion.scale",
                    None,
                    "give exactly one finite \"factor\" or a non-negative \"target_pga\" (a number in \"units\", m/s2 by default, or a string with units such as \"0.4g\")",
                ))
            }
        }
    }
    let pga = gm.pga();
    if !(pga.is_finite() && pga <= MAX_PGA) {
        let field = if obj.get("scale").is_some_and(|s| !s.is_null()) {
            "motion.scale"
        } else {
            "motion.horizontal"
        };
        return Err(MotionError::new(
            field,
            None,
            format!(
                "peak acceleration {pga:e} m/s² is beyond the largest accepted, {MAX_PGA:e} m/s²"
            ),
        ));
    }
    Ok(gm)
}

/// Largest peak ground acceleration accepted, m/s² (≈ 10⁵ g): far above any recorded motion
/// (a few g) and the 50 g the engine is tested at, and low enough that the velocities and
/// displacements of long records stay finite.
pub const MAX_PGA: f64 = 1e6;

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct ScaleSpec {
    factor: Option<f64>,
    /// A number in `units` (m/s² by default) or a string with its own units ("0.4g").
    target_pga: Option<super::Amplitude>,
    /// Units of a numeric `target_pga`.
    units: Option<Units>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct SamplesSpec {
    samples: Vec<f64>,
    dt: f64,
    #[serde(default)]
    units: Units,
    processing: Option<ProcessParams>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RecordSpec {
    format: String,
    content: String,
    units: Option<Units>,
    processing: Option<ProcessParams>,
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

/// An analytic signal of amplitude `a` (m/s²) and circular frequency `w` (rad/s) has velocity
/// and displacement amplitudes a/w and a/w²: all must be finite numbers, or the engine would
/// meet inf or NaN ground states (1e308 g, 1e308 Hz, a period of 1e-300 s).
fn representable(path: &str, a: f64, w: f64) -> Result<(), MotionError> {
    let ok = a.is_finite()
        && w.is_finite()
        && w > 0.0
        && (a / w).is_finite()
        && (a / (w * w)).is_finite();
    if ok {
        Ok(())
    } else {
        Err(MotionError::new(
            path,
            None,
            format!(
                "amplitude {a:e} m/s² at {w:e} rad/s is not representable: the acceleration, \
                 velocity (a/ω) and displacement (a/ω²) amplitudes must be finite"
            ),
        ))
    }
}

fn component(
    path: &str,
    v: &serde_json::Value,
    process: &ProcessParams,
) -> Result<(Signal, RecordMeta, String), MotionError> {
    let bad = |e: serde_json::Error| MotionError::new(path, None, e.to_string());
    let analytic = |units: Units, format: &str| RecordMeta {
        original_units: units,
        kind: RecordKind::Analytic,
        format: format.into(),
        processing: ProcessParams::default(),
    };
    if let Some(p) = v.get("pulse") {
        let p: PulseSpec = serde_json::from_value(p.clone()).map_err(bad)?;
        if !(p.period > 0.0
            && p.period.is_finite()
            && p.cycles > 0.0
            && p.cycles.is_finite()
            && p.amplitude.is_finite()
            && p.phase.is_finite())
        {
            return Err(MotionError::new(
                format!("{path}.pulse"),
                None,
                "amplitude and phase must be finite, period and cycles > 0",
            ));
        }
        let phase = match p.shape.as_str() {
            "sine" => p.phase,
            "cosine" => p.phase + std::f64::consts::FRAC_PI_2,
            other => {
                return Err(MotionError::new(
                    format!("{path}.pulse.shape"),
                    None,
                    format!("unknown shape {other:?} (sine, cosine)"),
                ))
            }
        };
        representable(
            &format!("{path}.pulse"),
            p.amplitude * p.units.to_si(),
            std::f64::consts::TAU / p.period,
        )?;
        if !(p.period * p.cycles).is_finite() {
            return Err(MotionError::new(
                format!("{path}.pulse"),
                None,
                "period × cycles overflows",
            ));
        }
        let sig = Signal::Pulse {
            amplitude: p.amplitude * p.units.to_si(),
            period: p.period,
            cycles: p.cycles,
            phase,
        };
        let prov = format!(
            "{} pulse, {} {} over {} s x {} cycles",
            p.shape,
            p.amplitude,
            p.units.name(),
            p.period,
            p.cycles
        );
        return Ok((sig, analytic(p.units, "pulse"), prov));
    }
    if let Some(s) = v.get("sine") {
        let s: SineSpec = serde_json::from_value(s.clone()).map_err(bad)?;
        if !(s.amplitude.is_finite() && s.frequency > 0.0 && s.frequency.is_finite()) {
            return Err(MotionError::new(
                format!("{path}.sine"),
                None,
                "amplitude must be finite and frequency > 0",
            ));
        }
        representable(
            &format!("{path}.sine"),
            s.amplitude * s.units.to_si(),
            std::f64::consts::TAU * s.frequency,
        )?;
        let prov = format!(
            "steady sine, {} {} at {} Hz",
            s.amplitude,
            s.units.name(),
            s.frequency
        );
        return Ok((
            Signal::Sine {
                amplitude: s.amplitude * s.units.to_si(),
                frequency: s.frequency,
            },
            analytic(s.units, "sine"),
            prov,
        ));
    }
    if v.get("samples").is_some() {
        let s: SamplesSpec = serde_json::from_value(v.clone()).map_err(bad)?;
        if !(s.dt > 0.0 && s.dt.is_finite()) {
            return Err(MotionError::new(format!("{path}.dt"), None, "must be > 0"));
        }
        if s.samples.is_empty() {
            return Err(MotionError::new(
                format!("{path}.samples"),
                None,
                "empty record",
            ));
        }
        let raw = RawRecord {
            dt: s.dt,
            values: s.samples,
            units: s.units,
            kind: RecordKind::Unknown,
            format: "samples",
            description: String::new(),
        };
        let gm = from_raw(path, raw, s.processing.as_ref().unwrap_or(process))?;
        return Ok((gm.horizontal, gm.meta, gm.provenance));
    }
    if v.get("format").is_some() || v.get("content").is_some() {
        let r: RecordSpec = serde_json::from_value(v.clone()).map_err(bad)?;
        let format = Format::from_name(&r.format).ok_or_else(|| {
            MotionError::new(
                format!("{path}.format"),
                None,
                format!("unknown format {:?} (at2, csv, cosmos, esm)", r.format),
            )
        })?;
        let origin = format!("{path}.content");
        let raw = format.parse(&origin, &r.content, r.units)?;
        let gm = from_raw(&origin, raw, r.processing.as_ref().unwrap_or(process))?;
        return Ok((gm.horizontal, gm.meta, gm.provenance));
    }
    Err(MotionError::new(
        path,
        None,
        "expected one of {\"format\",\"content\"}, {\"samples\",\"dt\"}, {\"pulse\"}, {\"sine\"}",
    ))
}
