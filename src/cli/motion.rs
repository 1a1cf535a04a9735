//! `ashlar motion RECORD`: read a record, print its intensity measures as JSON (docs/format.md §3),
//! optionally write the response spectrum as SVG. The CLI wires `Command::Motion(MotionArgs)`
//! to `run`.
use super::{
    load_path_with, report_with, spectrum_svg, Baseline, HighPass, LoadParams, ProcessParams,
    RecordArgs, ReportParams,
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
pub fn run(args: &MotionArgs) -> Result<(), String> {
    let json = report_json(args)?;
    println!("{json}");
    Ok(())
}

/// Everything `run` does but printing; returns the JSON text.
pub fn report_json(args: &MotionArgs) -> Result<String, String> {
    let opts = &args.record_options;
    opts.validate().map_err(|e| e.to_string())?;
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
        units: opts.units.units().map_err(|e| e.to_string())?,
        process: ProcessParams { highpass, baseline },
    };
    let gm = load_path_with(&args.record, &params).map_err(|e| e.to_string())?;
    let gm = opts.apply(gm).map_err(|e| e.to_string())?;
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
