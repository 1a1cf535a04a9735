//! `ashlar motion RECORD` (cli, thin): read a record with `motion`, print its intensity
//! measures as JSON (docs/format.md §3), optionally write the response spectrum as SVG.
use crate::motion::{
    load_path_with, report_with, spectrum_svg, Baseline, HighPass, LoadParams, MotionError,
    ProcessParams, RecordArgs, RecordOptionError, ReportParams,
};
use std::path::PathBuf;

/// Why `ashlar motion` failed; each message names the option or the file (and its line).
#[derive(Debug, thiserror::Error)]
pub enum MotionCommandError {
    /// `--units`, `--pga` or `--scale` refused.
    #[error(transparent)]
    Options(#[from] RecordOptionError),
    /// The record could not be read or processed.
    #[error(transparent)]
    Record(#[from] MotionError),
    #[error("--baseline {0:?}: expected none or linear")]
    Baseline(String),
    #[error("--damping {0}: must be in [0, 1)")]
    Damping(f64),
    #[error("{}: cannot write: {source}", path.display())]
    WriteSvg {
        path: PathBuf,
        source: std::io::Error,
    },
    /// Serializing the report (never expected: it holds numbers and strings only).
    #[error("intensity report: {0}")]
    Json(#[from] serde_json::Error),
}

/// Arguments of `ashlar motion`.
#[derive(Debug, Clone, clap::Args)]
pub struct MotionArgs {
    /// Record file: .at2, .csv, .v1/.v2 (COSMOS), .asc (ESM) or a ground-motion .json.
    pub record: PathBuf,
    /// Also write the 5 %-damped response spectrum as SVG to this file.
    #[arg(long, value_name = "FILE")]
    pub svg: Option<PathBuf>,
    /// `--units`, `--pga`, `--scale`: the record options shared with `run` and `pga`.
    #[command(flatten)]
    pub record_options: RecordArgs,
    /// High-pass the record (raw records only): zero-phase Butterworth corner in Hz.
    #[arg(long, value_name = "HZ")]
    pub highpass: Option<f64>,
    /// Order of the high-pass filter (one pass).
    #[arg(long, default_value_t = 4)]
    pub order: usize,
    /// Baseline correction of the integrated displacement: none or linear.
    #[arg(long, default_value = "none")]
    pub baseline: String,
    /// Damping ratio of the response spectrum.
    #[arg(long, default_value_t = 0.05)]
    pub damping: f64,
}

/// Run the subcommand: JSON on stdout, errors as one line for stderr.
pub fn run(args: &MotionArgs) -> Result<(), MotionCommandError> {
    let json = report_json(args)?;
    println!("{json}");
    Ok(())
}

/// Everything `run` does but printing; returns the JSON text.
pub fn report_json(args: &MotionArgs) -> Result<String, MotionCommandError> {
    let opts = &args.record_options;
    opts.validate()?;
    let baseline = match args.baseline.as_str() {
        "none" => Baseline::None,
        "linear" => Baseline::Linear,
        other => return Err(MotionCommandError::Baseline(other.into())),
    };
    let highpass = args.highpass.map(|corner_hz| HighPass {
        corner_hz,
        order: args.order,
    });
    let params = LoadParams {
        units: opts.units.units()?,
        process: ProcessParams { highpass, baseline },
    };
    let gm = load_path_with(&args.record, &params)?;
    let gm = opts.apply(gm)?;
    if !(0.0..1.0).contains(&args.damping) {
        return Err(MotionCommandError::Damping(args.damping));
    }
    let im = report_with(
        &gm,
        &ReportParams {
            damping: args.damping,
            ..ReportParams::default()
        },
    );
    if let Some(path) = &args.svg {
        std::fs::write(path, spectrum_svg(&im)).map_err(|source| MotionCommandError::WriteSvg {
            path: path.clone(),
            source,
        })?;
    }
    Ok(serde_json::to_string_pretty(&im)?)
}
