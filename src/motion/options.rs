//! Record options shared by every entry point that reads a record (`ashlar run`, `pga`,
//! `motion` and the HTTP API): the units of a record that does not name them, and amplitudes
//! written with their units (`0.4g`, `4m/s2`, `392gal`). Sits beside the record readers in
//! `motion`; the CLI flattens [`RecordArgs`], the service calls [`parse_acceleration`].
//!
//! A bare number is refused where its units would be a guess: `--pga 0.4` could be 0.4 g or
//! 0.4 m/s² (a factor of ten apart), so the user must say which.
use super::{GroundMotion, LoadParams, Units};

/// Why an amplitude text was refused. The caller prefixes the option or field it came from.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum AccelerationError {
    #[error(
        "{number} has no units: write {number}g or {number}m/s2 (cm/s2 and gal are accepted too)"
    )]
    MissingUnits { number: String },
    #[error("unknown units {units:?} in {text:?}; expected g, m/s2 (m/s², m/s^2), cm/s2 or gal")]
    UnknownUnits { text: String, units: String },
    #[error(
        "{text:?} is not an acceleration: expected a number with units, such as 0.4g or 4m/s2"
    )]
    NotANumber { text: String },
    #[error("{text:?}: must be a finite number ≥ 0")]
    OutOfRange { text: String },
}

/// Why the record options could not be applied.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum RecordOptionError {
    #[error("--units {0:?}: expected g, m/s2 or cm/s2 (gal)")]
    Units(String),
    #[error("--pga {text:?}: {source}")]
    Pga {
        text: String,
        source: AccelerationError,
    },
    #[error("--scale {0}: must be a finite number")]
    Scale(f64),
}

/// Parse an acceleration with its units into m/s²: `0.4g`, `0.4G`, `4m/s2`, `4 m/s²`,
/// `4m/s^2`, `40cm/s2`, `392gal`. A bare number is refused ([`AccelerationError::MissingUnits`]).
pub fn parse_acceleration(text: &str) -> Result<f64, AccelerationError> {
    let (value, units) = split_amplitude(text)?;
    match units {
        Some(u) => Ok(value * u.to_si()),
        None => Err(AccelerationError::MissingUnits {
            number: text.trim().to_string(),
        }),
    }
}

/// An amplitude in JSON (HTTP API, sweep manifests): a number, in the units its object names
/// (m/s² unless said otherwise, as documented before units were required), or a string that
/// carries its own units (`"0.4g"`, parsed by [`parse_acceleration`]).
#[derive(Debug, Clone, PartialEq, serde::Deserialize, serde::Serialize)]
#[serde(untagged)]
pub enum Amplitude {
    Number(f64),
    Text(String),
}

impl Amplitude {
    /// The amplitude in m/s²; `units` applies to a plain number only.
    pub fn to_si(&self, units: Units) -> Result<f64, AccelerationError> {
        match self {
            Amplitude::Number(v) if v.is_finite() && *v >= 0.0 => Ok(v * units.to_si()),
            Amplitude::Number(v) => Err(AccelerationError::OutOfRange {
                text: v.to_string(),
            }),
            Amplitude::Text(t) => parse_acceleration(t),
        }
    }
}

/// Split `text` into a non-negative finite number and its units (`None` for a bare number).
fn split_amplitude(text: &str) -> Result<(f64, Option<Units>), AccelerationError> {
    let t = text.trim();
    // The longest prefix that reads as a number is the value; the rest names the units.
    // (Longest, so that an exponent such as `2e-1g` stays with the number.)
    let split = t
        .char_indices()
        .map(|(i, _)| i)
        .chain(std::iter::once(t.len()))
        .rev()
        .find(|&i| i > 0 && t[..i].trim().parse::<f64>().is_ok());
    let Some(i) = split else {
        return Err(AccelerationError::NotANumber { text: t.into() });
    };
    let (num, rest) = (t[..i].trim(), t[i..].trim());
    // `parse::<f64>` also takes `inf` and `NaN`; neither is an amplitude.
    let value = num.parse::<f64>().unwrap_or(f64::NAN);
    if !(value.is_finite() && value >= 0.0) {
        return Err(AccelerationError::OutOfRange { text: t.into() });
    }
    if rest.is_empty() {
        return Ok((value, None));
    }
    match Units::parse(rest) {
        Some(u) => Ok((value, Some(u))),
        None => Err(AccelerationError::UnknownUnits {
            text: t.into(),
            units: rest.into(),
        }),
    }
}

/// `--units`: the units of a record file that does not name them (a CSV without a units
/// header or `# units:` comment). A file that names its units must agree.
#[derive(Debug, Clone, Default, clap::Args)]
pub struct UnitsArg {
    /// Units of a record that does not name them (CSV): g, m/s2 or cm/s2 (gal). A record that
    /// names its units must agree.
    #[arg(long)]
    pub units: Option<String>,
}

impl UnitsArg {
    /// The parsed units, if given.
    pub fn units(&self) -> Result<Option<Units>, RecordOptionError> {
        match &self.units {
            None => Ok(None),
            Some(u) => Units::parse(u)
                .map(Some)
                .ok_or_else(|| RecordOptionError::Units(u.clone())),
        }
    }

    /// Reading options for a record with these units and no processing.
    pub fn load_params(&self) -> Result<LoadParams, RecordOptionError> {
        Ok(LoadParams {
            units: self.units()?,
            ..LoadParams::default()
        })
    }
}

/// The record options of `ashlar run` and `ashlar motion`: `--units`, and one of `--pga`
/// (with units) or `--scale`. (`ashlar pga` takes only `--units`: it sets amplitudes itself.)
#[derive(Debug, Clone, Default, clap::Args)]
pub struct RecordArgs {
    #[command(flatten)]
    pub units: UnitsArg,
    /// Scale the record so its peak horizontal acceleration is this, with units: 0.4g, 4m/s2,
    /// 392gal. A bare number is refused (0.4 g and 0.4 m/s² differ tenfold).
    #[arg(long, conflicts_with = "scale", allow_hyphen_values = true)]
    pub pga: Option<String>,
    /// Multiply the record by this factor (dimensionless).
    #[arg(long, allow_hyphen_values = true)]
    pub scale: Option<f64>,
}

impl RecordArgs {
    /// The target PGA in m/s², if `--pga` was given.
    pub fn target_pga(&self) -> Result<Option<f64>, RecordOptionError> {
        self.pga
            .as_deref()
            .map(|p| {
                parse_acceleration(p).map_err(|source| RecordOptionError::Pga {
                    text: p.to_string(),
                    source,
                })
            })
            .transpose()
    }

    /// Check every option before any file is read (a bad `--pga` is reported even when the
    /// record is also bad).
    pub fn validate(&self) -> Result<(), RecordOptionError> {
        self.units.units()?;
        self.target_pga()?;
        if let Some(f) = self.scale {
            if !f.is_finite() {
                return Err(RecordOptionError::Scale(f));
            }
        }
        Ok(())
    }

    /// `gm` scaled by `--pga` or `--scale` (unchanged without either).
    pub fn apply(&self, gm: GroundMotion) -> Result<GroundMotion, RecordOptionError> {
        self.validate()?;
        Ok(match (self.target_pga()?, self.scale) {
            (Some(p), _) => gm.scaled_to_pga(p),
            (None, Some(f)) => gm.scaled(f),
            (None, None) => gm,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::motion::STANDARD_GRAVITY;

    #[test]
    fn amplitudes_with_units() {
        // Exact products: the factor is applied once to the parsed number.
        for (text, expect) in [
            ("0.4g", 0.4 * STANDARD_GRAVITY),
            ("0.4G", 0.4 * STANDARD_GRAVITY),
            (" 0.4 g ", 0.4 * STANDARD_GRAVITY),
            ("2e-1g", 0.2 * STANDARD_GRAVITY),
            ("4m/s2", 4.0),
            ("4 m/s²", 4.0),
            ("4m/s^2", 4.0),
            ("392gal", 392.0 * 0.01),
            ("392 Gal", 392.0 * 0.01),
            ("40cm/s2", 40.0 * 0.01),
            ("0g", 0.0),
        ] {
            assert_eq!(parse_acceleration(text), Ok(expect), "{text}");
        }
    }

    #[test]
    fn json_amplitudes_take_units_from_the_object_or_the_string() {
        let n: Amplitude = serde_json::from_str("0.5").expect("number");
        assert_eq!(n.to_si(Units::G), Ok(0.5 * STANDARD_GRAVITY));
        assert_eq!(n.to_si(Units::MetresPerSecond2), Ok(0.5));
        let t: Amplitude = serde_json::from_str("\"0.5g\"").expect("text");
        assert_eq!(t.to_si(Units::MetresPerSecond2), Ok(0.5 * STANDARD_GRAVITY));
        let bare: Amplitude = serde_json::from_str("\"0.5\"").expect("text");
        assert!(matches!(
            bare.to_si(Units::G),
            Err(AccelerationError::MissingUnits { .. })
        ));
        assert!(Amplitude::Number(-1.0).to_si(Units::G).is_err());
    }

    #[test]
    fn bare_numbers_and_nonsense_are_refused() {
        let e = parse_acceleration("0.4").expect_err("bare");
        assert_eq!(
            e.to_string(),
            "0.4 has no units: write 0.4g or 0.4m/s2 (cm/s2 and gal are accepted too)"
        );
        assert!(matches!(
            parse_acceleration("0.4 furlongs"),
            Err(AccelerationError::UnknownUnits { .. })
        ));
        assert!(matches!(
            parse_acceleration("fast"),
            Err(AccelerationError::NotANumber { .. })
        ));
        assert!(matches!(
            parse_acceleration("g"),
            Err(AccelerationError::NotANumber { .. })
        ));
        for bad in ["-1g", "infg", "NaN m/s2"] {
            assert!(
                matches!(
                    parse_acceleration(bad),
                    Err(AccelerationError::OutOfRange { .. })
                ),
                "{bad}"
            );
        }
    }
}
