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
    MotionSpec::from_value(value)?.build(process)
}

/// The ground-motion object of docs/format.md §2 as typed data: every member known (an unknown
/// one is refused, by the command line as by the HTTP API), `null` only where the format
/// allows it (an absent component or scale). [`MotionSpec::build`] checks the values and
/// makes the [`GroundMotion`].
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MotionSpec {
    /// Acceleration along +x; absent or `null`: none.
    #[serde(default)]
    pub horizontal: Option<ComponentSpec>,
    /// Acceleration along +y; absent or `null`: none.
    #[serde(default)]
    pub vertical: Option<ComponentSpec>,
    /// Absent or `null`: the record as given.
    #[serde(default)]
    pub scale: Option<ScaleSpec>,
}

/// One component: exactly one form (`pulse`, `sine`, `samples` + `dt`, `format` + `content`),
/// with the members of that form only. Members are optional here so that a member of another
/// form is named in the error ([`ComponentSpec::form`]).
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ComponentSpec {
    #[serde(default, deserialize_with = "non_null")]
    pub pulse: Option<PulseSpec>,
    #[serde(default, deserialize_with = "non_null")]
    pub sine: Option<SineSpec>,
    /// Uniform samples from t = 0, in `units` (g by default).
    #[serde(default, deserialize_with = "non_null")]
    pub samples: Option<Vec<f64>>,
    /// s, the samples' time step.
    #[serde(default, deserialize_with = "non_null")]
    pub dt: Option<f64>,
    /// Record format name (`at2`, `csv`, `cosmos`, `esm` and their aliases).
    #[serde(default, deserialize_with = "non_null")]
    pub format: Option<String>,
    /// The text of a record file.
    #[serde(default, deserialize_with = "non_null")]
    pub content: Option<String>,
    #[serde(default, deserialize_with = "non_null")]
    pub units: Option<Units>,
    /// Command-line extension (docs/format.md §2): filtering and baseline of a sampled or
    /// embedded record. The HTTP API refuses it ([`ComponentSpec::processing_refused`]).
    #[serde(default, deserialize_with = "non_null")]
    pub processing: Option<ProcessParams>,
}

/// The forms of a component, each with the members it takes (`processing` aside).
const FORMS: [(&str, &[&str]); 4] = [
    ("pulse", &["pulse"]),
    ("sine", &["sine"]),
    ("samples", &["samples", "dt", "units"]),
    ("format", &["format", "content", "units"]),
];

/// The form that the member names `given` select (the first of [`FORMS`] present; `content`
/// selects `format`), or `None` when none does; a member outside that form (other than
/// `processing` for sampled and embedded records) is refused, naming it.
fn check_form(path: &str, given: &[&str]) -> Result<Option<&'static str>, MotionError> {
    let Some((name, allowed)) = FORMS
        .iter()
        .find(|(f, _)| given.contains(f) || (*f == "format" && given.contains(&"content")))
    else {
        return Ok(None);
    };
    let extension_ok = matches!(*name, "samples" | "format");
    match given
        .iter()
        .find(|k| !(allowed.contains(k) || (extension_ok && **k == "processing")))
    {
        Some(k) => Err(MotionError::new(
            format!("{path}.{k}"),
            None,
            format!(
                "unknown field for a {name:?} component (allowed: {})",
                allowed.join(", ")
            ),
        )),
        None => Ok(Some(name)),
    }
}

/// A member given as `null`: refused, since leaving it out says the same without ambiguity.
fn non_null<'de, D, T>(d: D) -> Result<Option<T>, D::Error>
where
    D: serde::Deserializer<'de>,
    T: Deserialize<'de>,
{
    match Option::<T>::deserialize(d)? {
        Some(v) => Ok(Some(v)),
        None => Err(serde::de::Error::custom(
            "must not be null (leave it out instead)",
        )),
    }
}

impl MotionSpec {
    /// Read the typed object; the error names the member (`motion.horizontal.pulse.period`).
    pub fn from_value(value: &serde_json::Value) -> Result<Self, MotionError> {
        if !value.is_object() {
            return Err(MotionError::new(
                "motion",
                None,
                "expected an object with \"horizontal\", \"vertical\", \"scale\"",
            ));
        }
        // Members of another form are named before their contents are read: in
        // `{"pulse": {…}, "sine": {}}` the error is the extra `sine`, not what `sine` lacks.
        for name in ["horizontal", "vertical"] {
            if let Some(c) = value.get(name).and_then(serde_json::Value::as_object) {
                let given: Vec<&str> = c.keys().map(String::as_str).collect();
                check_form(&format!("motion.{name}"), &given)?;
            }
        }
        let spec: MotionSpec = serde_path_to_error::deserialize(value).map_err(|e| {
            let path = e.path().to_string();
            let message = e.into_inner().to_string();
            let mut origin = if path.is_empty() || path == "." {
                "motion".to_string()
            } else {
                format!("motion.{path}")
            };
            // Name an unknown member in the origin too, when serde's path stops above it.
            if let Some(name) = message
                .strip_prefix("unknown field `")
                .and_then(|r| r.split('`').next())
            {
                if !origin.ends_with(&format!(".{name}")) {
                    origin = format!("{origin}.{name}");
                }
            }
            MotionError::new(origin, None, message)
        })?;
        for (name, c) in spec.components() {
            c.form(&format!("motion.{name}"))?;
        }
        Ok(spec)
    }

    /// The components given, with their member names.
    pub fn components(&self) -> impl Iterator<Item = (&'static str, &ComponentSpec)> {
        [
            ("horizontal", &self.horizontal),
            ("vertical", &self.vertical),
        ]
        .into_iter()
        .filter_map(|(n, c)| c.as_ref().map(|c| (n, c)))
    }

    /// The ground motion: values checked (finite, in range, representable), records parsed,
    /// `process` applied to sampled components that do not name their own processing.
    pub fn build(self, process: &ProcessParams) -> Result<GroundMotion, MotionError> {
        let comp = |name: &str, c: Option<ComponentSpec>| match c {
            None => Ok((Signal::Zero, RecordMeta::default(), "none".into())),
            Some(c) => {
                let form = if c.samples.is_some() {
                    "samples"
                } else {
                    "content"
                };
                let path = format!("motion.{name}");
                let built = component(&path, c, process)?;
                check_samples(&format!("{path}.{form}"), &built.0)?;
                Ok(built)
            }
        };
        let (horizontal, meta, provenance) = comp("horizontal", self.horizontal)?;
        let (vertical, _, _) = comp("vertical", self.vertical)?;
        let mut gm = GroundMotion {
            horizontal,
            vertical,
            scale: 1.0,
            provenance,
            meta,
        };
        let scaled = self.scale.is_some();
        if let Some(scale) = &self.scale {
            match (scale.factor, &scale.target_pga) {
                (Some(f), None) if f.is_finite() => gm.scale = f,
                (None, Some(x)) => {
                    let units = scale.units.unwrap_or(Units::MetresPerSecond2);
                    let target = x.to_si(units).map_err(|e| {
                        MotionError::new("motion.scale.target_pga", None, e.to_string())
                    })?;
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
            let field = if scaled {
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
}

/// Every sample of a recorded component finite and within ±[`MAX_PGA`] m/s² as read (before
/// any `scale`), else an error naming the member and the sample's index (from 0): a garbage
/// sample is refused where it is, not reported later as a peak or a non-finite solve.
fn check_samples(path: &str, signal: &Signal) -> Result<(), MotionError> {
    let Signal::Sampled(x) = signal else {
        return Ok(());
    };
    match x
        .accel
        .iter()
        .position(|a| !(a.is_finite() && a.abs() <= MAX_PGA))
    {
        None => Ok(()),
        Some(i) => Err(MotionError::new(
            path,
            None,
            format!(
                "sample {i} (from 0) is {:e} m/s², outside the accepted ±{MAX_PGA:e} m/s²",
                x.accel[i]
            ),
        )),
    }
}

impl ComponentSpec {
    /// The members given, by name.
    fn members(&self) -> impl Iterator<Item = &'static str> + '_ {
        [
            ("pulse", self.pulse.is_some()),
            ("sine", self.sine.is_some()),
            ("samples", self.samples.is_some()),
            ("dt", self.dt.is_some()),
            ("format", self.format.is_some()),
            ("content", self.content.is_some()),
            ("units", self.units.is_some()),
            ("processing", self.processing.is_some()),
        ]
        .into_iter()
        .filter_map(|(k, given)| given.then_some(k))
    }

    /// The component's form (`"pulse"`, `"sine"`, `"samples"`, `"format"`); a member that
    /// belongs to another form is refused, naming it (`path` is the component's).
    pub fn form(&self, path: &str) -> Result<&'static str, MotionError> {
        let given: Vec<&str> = self.members().collect();
        check_form(path, &given)?.ok_or_else(|| {
            MotionError::new(
                path,
                None,
                "expected one of {\"format\",\"content\"}, {\"samples\",\"dt\"}, {\"pulse\"}, {\"sine\"}",
            )
        })
    }

    /// The HTTP API takes no `processing` (a command-line extension): the error the service
    /// gives for it, at `path` (the component's), when it is there.
    pub fn processing_refused(&self, path: &str) -> Option<MotionError> {
        self.processing.as_ref()?;
        let (name, allowed) = FORMS
            .iter()
            .find(|(f, _)| self.members().any(|k| k == *f))?;
        Some(MotionError::new(
            format!("{path}.processing"),
            None,
            format!(
                "unknown field for a {name:?} component (allowed: {})",
                allowed.join(", ")
            ),
        ))
    }
}

/// Largest peak ground acceleration accepted, m/s² (≈ 10⁵ g): far above any recorded motion
/// (a few g) and the 50 g the engine is tested at, and low enough that the velocities and
/// displacements of long records stay finite.
pub const MAX_PGA: f64 = 1e6;

/// `scale`: exactly one of `factor` and `target_pga`.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ScaleSpec {
    /// Multiplies both components (dimensionless).
    #[serde(default, deserialize_with = "non_null")]
    pub factor: Option<f64>,
    /// A number in `units` (m/s² by default) or a string with its own units ("0.4g").
    #[serde(default, deserialize_with = "non_null")]
    pub target_pga: Option<super::Amplitude>,
    /// Units of a numeric `target_pga`.
    #[serde(default, deserialize_with = "non_null")]
    pub units: Option<Units>,
}

/// `pulse`: a(t) = A · sin(2π t / T + φ) for 0 ≤ t ≤ n·T.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PulseSpec {
    /// `"sine"` (default) or `"cosine"` (adds π/2 to the phase).
    #[serde(default = "sine_shape")]
    pub shape: String,
    /// A, in `units` (g by default).
    pub amplitude: f64,
    /// T, s.
    pub period: f64,
    /// n (default 1).
    #[serde(default = "one")]
    pub cycles: f64,
    /// φ, rad.
    #[serde(default)]
    pub phase: f64,
    #[serde(default)]
    pub units: Units,
}

/// `sine`: steady a(t) = A · sin(2π f t).
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SineSpec {
    /// A, in `units` (g by default).
    pub amplitude: f64,
    /// f, Hz.
    pub frequency: f64,
    #[serde(default)]
    pub units: Units,
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
    c: ComponentSpec,
    process: &ProcessParams,
) -> Result<(Signal, RecordMeta, String), MotionError> {
    let analytic = |units: Units, format: &str| RecordMeta {
        original_units: units,
        kind: RecordKind::Analytic,
        format: format.into(),
        processing: ProcessParams::default(),
    };
    let missing = |k: &str| MotionError::new(path, None, format!("missing field `{k}`"));
    match c.form(path)? {
        "pulse" => {
            let Some(p) = &c.pulse else {
                return Err(missing("pulse"));
            };
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
            Ok((sig, analytic(p.units, "pulse"), prov))
        }
        "sine" => {
            let Some(s) = &c.sine else {
                return Err(missing("sine"));
            };
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
            Ok((
                Signal::Sine {
                    amplitude: s.amplitude * s.units.to_si(),
                    frequency: s.frequency,
                },
                analytic(s.units, "sine"),
                prov,
            ))
        }
        "samples" => {
            let Some(samples) = c.samples else {
                return Err(missing("samples"));
            };
            let Some(dt) = c.dt else {
                return Err(missing("dt"));
            };
            if !(dt > 0.0 && dt.is_finite()) {
                return Err(MotionError::new(format!("{path}.dt"), None, "must be > 0"));
            }
            if samples.is_empty() {
                return Err(MotionError::new(
                    format!("{path}.samples"),
                    None,
                    "empty record",
                ));
            }
            let raw = RawRecord {
                dt,
                values: samples,
                units: c.units.unwrap_or_default(),
                kind: RecordKind::Unknown,
                format: "samples",
                description: String::new(),
            };
            let gm = from_raw(path, raw, c.processing.as_ref().unwrap_or(process))?;
            Ok((gm.horizontal, gm.meta, gm.provenance))
        }
        _ => {
            let (Some(name), Some(content)) = (&c.format, &c.content) else {
                return Err(missing(if c.format.is_none() {
                    "format"
                } else {
                    "content"
                }));
            };
            let format = Format::from_name(name).ok_or_else(|| {
                MotionError::new(
                    format!("{path}.format"),
                    None,
                    format!("unknown format {name:?} (at2, csv, cosmos, esm)"),
                )
            })?;
            let origin = format!("{path}.content");
            let raw = format.parse(&origin, content, c.units)?;
            let gm = from_raw(&origin, raw, c.processing.as_ref().unwrap_or(process))?;
            Ok((gm.horizontal, gm.meta, gm.provenance))
        }
    }
}
