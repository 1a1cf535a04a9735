//! `ashlar run` and `ashlar pga`: load the scene and the record, call `analysis`, print.
use crate::analysis::pga::{search, Criterion, PgaRequest};
use crate::analysis::run::{run as run_scene, RunOptions};
use crate::motion::{self, GroundMotion, STANDARD_GRAVITY};
use crate::scene::{parse_scene, Scene};
use std::path::{Path, PathBuf};

#[derive(Debug, clap::Args)]
pub struct RunArgs {
    /// Scene file (ashlar.scene/1 JSON).
    pub scene: PathBuf,
    /// Horizontal record: .at2, .csv, COSMOS .v1/.v2, ESM .asc, or a ground-motion JSON.
    #[arg(long)]
    pub motion: Option<PathBuf>,
    /// Vertical record (same formats; its first component is used).
    #[arg(long)]
    pub vertical: Option<PathBuf>,
    /// Scale the record to this PGA: m/s², or with a g suffix (0.3g).
    #[arg(long, conflicts_with = "scale")]
    pub pga: Option<String>,
    /// Multiply the record by this factor.
    #[arg(long)]
    pub scale: Option<f64>,
    /// Output directory.
    #[arg(long, default_value = "ashlar-out")]
    pub out: PathBuf,
    /// Do not write trajectory.mcap.
    #[arg(long)]
    pub no_trajectory: bool,
    /// Write histories only for these free blocks (comma-separated ids; default: all).
    #[arg(long, value_delimiter = ',')]
    pub blocks: Option<Vec<String>>,
    /// Seconds between recorded frames (overrides the scene's control.output_interval).
    #[arg(long)]
    pub output_interval: Option<f64>,
}

#[derive(Debug, clap::Args)]
pub struct PgaArgs {
    /// Scene file (ashlar.scene/1 JSON).
    pub scene: PathBuf,
    /// Record (same formats as `run`).
    #[arg(long)]
    pub motion: PathBuf,
    /// toppled:BLOCK, displacement:BLOCK:METRES or rotation:BLOCK:DEGREES; repeat for several
    /// (all must hold); prefix with `not:` for an observation that a block did not fail.
    #[arg(long, required = true)]
    pub criterion: Vec<String>,
    /// Lower end of the amplitude range (m/s² or 0.1g).
    #[arg(long, default_value = "0.05g")]
    pub min: String,
    /// Upper end of the amplitude range (m/s² or 2g).
    #[arg(long, default_value = "2g")]
    pub max: String,
    /// Bracket width to stop at, m/s².
    #[arg(long, default_value_t = 0.01)]
    pub tolerance: f64,
    /// Coarse scan points before bisection.
    #[arg(long, default_value_t = 8)]
    pub scan_points: usize,
    /// Output directory for result.json.
    #[arg(long, default_value = "ashlar-out")]
    pub out: PathBuf,
}

/// Parse an acceleration given in m/s² or with a `g` suffix.
pub fn parse_acceleration(text: &str) -> Result<f64, String> {
    let t = text.trim();
    let (num, k) = match t.strip_suffix('g') {
        Some(n) => (n, STANDARD_GRAVITY),
        None => (t, 1.0),
    };
    num.trim()
        .parse::<f64>()
        .ok()
        .filter(|v| v.is_finite() && *v >= 0.0)
        .map(|v| v * k)
        .ok_or_else(|| {
            format!("{text:?} is not an acceleration (m/s², or with a g suffix such as 0.3g)")
        })
}

fn load_scene(path: &Path) -> Result<Scene, String> {
    let text = std::fs::read_to_string(path).map_err(|e| format!("{}: {e}", path.display()))?;
    parse_scene(&text).map_err(|e| format!("{}: {e}", path.display()))
}

fn load_motion(args: &RunArgs) -> Result<GroundMotion, String> {
    let mut gm = match &args.motion {
        Some(p) => motion::load_path(p).map_err(|e| e.to_string())?,
        None => GroundMotion::none(),
    };
    if let Some(v) = &args.vertical {
        let vm = motion::load_path(v).map_err(|e| e.to_string())?;
        gm.vertical = vm.horizontal;
    }
    if let Some(p) = &args.pga {
        gm = gm.scaled_to_pga(parse_acceleration(p)?);
    } else if let Some(f) = args.scale {
        if !f.is_finite() {
            return Err(format!("--scale {f}: must be a finite number"));
        }
        gm = gm.scaled(f);
    }
    Ok(gm)
}

pub fn run(args: &RunArgs) -> Result<(), String> {
    let mut scene = load_scene(&args.scene)?;
    if let Some(i) = args.output_interval {
        if !(i.is_finite() && i > 0.0) {
            return Err(format!(
                "--output-interval {i}: must be a positive number of seconds"
            ));
        }
        scene.control.output_interval = i;
    }
    let gm = load_motion(args)?;
    let opts = RunOptions {
        out_dir: Some(&args.out),
        no_trajectory: args.no_trajectory,
        history_blocks: args.blocks.clone(),
        ..Default::default()
    };
    let outcome = run_scene(&scene, &gm, &opts).map_err(|e| e.to_string())?;
    println!(
        "{}",
        serde_json::to_string_pretty(&outcome.summary).map_err(|e| e.to_string())?
    );
    Ok(())
}

pub fn pga(args: &PgaArgs) -> Result<(), String> {
    let scene = load_scene(&args.scene)?;
    let gm = motion::load_path(&args.motion).map_err(|e| e.to_string())?;
    let criteria = args
        .criterion
        .iter()
        .map(|c| Criterion::parse(c))
        .collect::<Result<Vec<_>, _>>()?;
    let req = PgaRequest {
        criteria,
        min: parse_acceleration(&args.min)?,
        max: parse_acceleration(&args.max)?,
        tolerance: args.tolerance,
        scan_points: args.scan_points,
    };
    let result = search(&scene, &gm, &req, &RunOptions::default()).map_err(|e| e.to_string())?;
    let text = serde_json::to_string_pretty(&result).map_err(|e| e.to_string())?;
    std::fs::create_dir_all(&args.out).map_err(|e| format!("{}: {e}", args.out.display()))?;
    std::fs::write(args.out.join("result.json"), format!("{text}\n"))
        .map_err(|e| format!("{}: {e}", args.out.display()))?;
    println!("{text}");
    Ok(())
}
