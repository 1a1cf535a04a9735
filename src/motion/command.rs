//! `ashlar motion RECORD`: read a record, print its intensity measures as JSON (docs/format.md §3),
//! optionally write the response spectrum as SVG. The CLI wires `Command::Motion(MotionArgs)`
//! to `run`.
use super::{
    load_path_with, report_with, spectrum_svg, Baseline, HighPass, LoadParams, ProcessParams,
    ReportParams, Units, STANDARD_GRAVITY,
};
use std::path::PathBuf;

/// Arguments of `ashlar motion`.
#[derive(Debug, Clone, clap::Args)]
pub struct MotionArgs {
    /// Record file: .at2, .csv, .v1/.v2 (COSMOS), .asc (ESM) or a ground-motion .json.
    pub record: PathBuf,
    /// Also write the 5 %-damped response spectrum as SVG to this file.
    #[arg(long, value_name = "FILE")]
    pub svg: Option<PathBuf>,
    /// Units of a CSV record that does not name them: g, m/s2, cm/s2 (gal).
    #[arg(long)]
    pub units: Option<String>,
    /// High-pass the record (raw records only): zero-phase Butterworth corner in Hz.
    #[arg(long, value_name = "HZ")]
    pub highpass: Option<f64>,
    /// Order of the high-pass filter (one pass).
    #[arg(long, default_value_t = 4)]
    pub order: usize,
    /// Baseline correction of the integrated displacement: none or linear.
    #[arg(long, default_value = "none")]
    pub baseline: String,
    /// Multiply the record by this factor.
    #[arg(long, conflicts_with = "pga")]
    pub scale: Option<f64>,
    /// Scale the record to this PGA: m/s², or g with a `g` suffix (`0.3g`).
    #[arg(long)]
    pub pga: Option<String>,
    /// Damping ratio of the response spectrum.
    #[arg(long, default_value_t = 0.05)]
    pub damping: f64,
}

/// Run the subcommand: JSON on stdout, errors as one line for stderr.
pub fn run(args: &MotionArgs) -> Result<(), String> {
    let json = report_json(args)?;
    println!("{json}");
    Ok(())
}

/// Everything `run` does but printing; returns the JSON text.
pub fn report_json(args: &MotionArgs) -> Result<String, String> {
    let units = match &args.units {
        None => None,
        Some(u) => Some(
            Units::parse(u)
                .ok_or_else(|| format!("--units {u:?}: expected g, m/s2 or cm/s2 (gal)"))?,
        ),
    };
    let baseline = match args.baseline.as_str() {
        "none" => Baseline::None,
        "linear" => Baseline::Linear,
        other => return Err(format!("--baseline {other:?}: expected none or linear")),
    };
    let highpass = args.highpass.map(|corner_hz| HighPass {
        corner_hz,
        order: args.order,
    });
    let params = LoadParams {
        units,
        process: ProcessParams { highpass, baseline },
    };
    let mut gm = load_path_with(&args.record, &params).map_err(|e| e.to_string())?;
    if let Some(f) = args.scale {
        if !f.is_finite() {
            return Err(format!("--scale {f}: must be a finite number"));
        }
        gm = gm.scaled(f);
    }
    if let Some(p) = &args.pga {
        gm = gm.scaled_to_pga(parse_pga(p)?);
    }
    if !(0.0..1.0).contains(&args.damping) {
        return Err(format!("--damping {}: must be in [0, 1)", args.damping));
    }
    let im = report_with(
        &gm,
        &ReportParams {
            damping: args.damping,
            ..ReportParams::default()
        },
    );
    if let Some(path) = &args.svg {
        std::fs::write(path, spectrum_svg(&im))
            .map_err(|e| format!("{}: cannot write: {e}", path.display()))?;
    }
    serde_json::to_string_pretty(&im).map_err(|e| e.to_string())
}

/// `2.5` (m/s²) or `0.3g`.
pub fn parse_pga(text: &str) -> Result<f64, String> {
    let t = text.trim();
    let (num, k) = match t.strip_suffix(['g', 'G']) {
        Some(n) => (n, STANDARD_GRAVITY),
        None => (t.strip_suffix("m/s2").unwrap_or(t), 1.0),
    };
    match num.trim().parse::<f64>() {
        Ok(v) if v.is_finite() && v >= 0.0 => Ok(v * k),
        _ => Err(format!(
            "--pga {text:?}: expected a non-negative number in m/s² or with a g suffix (0.3g)"
        )),
    }
}
