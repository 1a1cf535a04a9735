//! `ashlar run` and `ashlar pga`: load the scene and the record, call `analysis`, print.
use super::error::{pretty, CliError};
use super::load::{load_records, load_scene, record_name, RangeArgs};
use crate::analysis::fragility::Method;
use crate::analysis::pga::{fragility_svg, search, search_records, Combine, Criterion, ScanOrder};
use crate::analysis::run::{run as run_scene, RunOptions};
use crate::motion::{self, GroundMotion, RecordArgs, UnitsArg};
use crate::scene::Scene;
use std::path::PathBuf;

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
    /// `--units`, `--pga`, `--scale`: the record options shared with `pga` and `motion`
    /// (`--units` applies to the vertical record too).
    #[command(flatten)]
    pub record_options: RecordArgs,
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
    /// Override the scene's control.model: `auto` (default), `dda` (force the full engine),
    /// `rocking` or `sliding`.
    #[arg(long)]
    pub model: Option<String>,
    /// Run duration in seconds (overrides the scene's control.duration; default: the record's
    /// length + 2 s). The run then goes on while the structure moves (docs/run-end.md).
    #[arg(long)]
    pub duration: Option<f64>,
    /// Damage criteria to evaluate on the run's final state (the `pga` forms, or the JSON of
    /// docs/format.md §3 "Damage criteria"); verdicts go to OUT/criteria.json and stderr.
    #[arg(long)]
    pub criterion: Vec<String>,
    /// s, the longest the run goes on after its duration while the structure still moves
    /// (default 10 s; 0 ends the run at its duration, unsettled or not: docs/run-end.md).
    #[arg(long)]
    pub max_extension: Option<f64>,
}

#[derive(Debug, clap::Args)]
pub struct PgaArgs {
    /// Scene file (ashlar.scene/1 JSON).
    pub scene: PathBuf,
    /// Record (same formats as `run`); or several, for a fragility curve: a directory (every
    /// record file in it), a comma-separated list of paths, or a `.list` file naming one path a
    /// line (`#` comments; relative paths from the list's directory).
    #[arg(long)]
    pub motion: String,
    /// toppled:BLOCK, displacement:BLOCK:METRES or rotation:BLOCK:DEGREES; repeat for several
    /// (combined by --combine); prefix with `not:` for an observation that a block did not fail.
    #[arg(long, required = true)]
    pub criterion: Vec<String>,
    /// How several criteria combine: `all` must be met, or `any` one of them.
    #[arg(long, default_value = "all")]
    pub combine: String,
    /// `--units` of the records (those that do not name them), shared with `run` and `motion`.
    /// (No `--pga`/`--scale`: the search sets the amplitude itself.)
    #[command(flatten)]
    pub units: UnitsArg,
    /// `--min`, `--max`, `--tolerance`: the amplitude range, shared with `site`.
    #[command(flatten)]
    pub range: RangeArgs,
    /// Scan points over [min, max] instead of `--resolution`: the resolution asked is then
    /// their spacing (max − min)/(N − 1), rounded down to the lattice (docs/pga.md); two
    /// searches share their answer only when they share the lattice.
    #[arg(long)]
    pub scan_points: Option<usize>,
    /// `full`: run every scan point (`monotonic` and `failing_intervals` cover the range);
    /// `lowest`: ascending batches of the pool's threads, stopping at the first batch with a
    /// failure (same answer when nothing changes above it; far fewer slow strong-motion runs on
    /// a many-block wall; docs/pga.md).
    #[arg(long, default_value = "full")]
    pub scan: String,
    /// Fragility fit over several records: `interval` (each record's capacity censored in
    /// its bracket) or `binary` (every run a pass/fail outcome, Baker 2015).
    #[arg(long, default_value = "interval")]
    pub fit: String,
    /// Output directory for result.json (and fragility.json, fragility.svg over several records).
    #[arg(long, default_value = "ashlar-out")]
    pub out: PathBuf,
    /// Override the scene's control.model: `auto` (default), `dda` (force the full engine),
    /// `rocking` or `sliding`.
    #[arg(long)]
    pub model: Option<String>,
    /// Run duration in seconds (overrides the scene's control.duration; default: the record's
    /// length + 2 s). The run then goes on while the structure moves (docs/run-end.md).
    #[arg(long)]
    pub duration: Option<f64>,
}

/// `--model NAME` as the scene's `control.model`.
fn apply_model(scene: &mut Scene, model: Option<&str>) -> Result<(), CliError> {
    if let Some(m) = model {
        scene.control.model = serde_json::from_value(serde_json::Value::from(m)).map_err(|_| {
            CliError::Usage(format!(
                "--model {m:?}: expected one of auto, dda, rocking, sliding"
            ))
        })?;
    }
    Ok(())
}

/// `--duration SECONDS` as the scene's `control.duration`.
pub(super) fn apply_duration(scene: &mut Scene, duration: Option<f64>) -> Result<(), CliError> {
    if let Some(d) = duration {
        if !(d.is_finite() && d > 0.0) {
            return Err(CliError::Usage(format!(
                "--duration {d}: must be a positive number of seconds"
            )));
        }
        scene.control.duration = Some(d);
    }
    Ok(())
}

/// Warn on stderr when the run's duration cuts the record short (the summary says it too).
fn warn_truncation(scene: &Scene, gm: &GroundMotion) {
    if let Some(d) = scene.control.duration {
        if let Some(t) = crate::analysis::run_end::truncation(d, gm) {
            eprintln!(
                "ashlar: warning: the run's duration ({:.3} s, control.duration) stops before the end of the record ({:.3} s): the rest of the record is not applied; remove control.duration or pass --duration",
                t.run_duration, t.record_duration
            );
        }
    }
}

fn load_motion(args: &RunArgs) -> Result<GroundMotion, CliError> {
    let opts = &args.record_options;
    opts.validate()?;
    let params = opts.units.load_params()?;
    let mut gm = match &args.motion {
        Some(p) => motion::load_path_with(p, &params)?,
        None => GroundMotion::none(),
    };
    if let Some(v) = &args.vertical {
        let vm = motion::load_path_with(v, &params)?;
        gm.vertical = vm.horizontal;
    }
    Ok(opts.apply(gm)?)
}

pub fn run(args: &RunArgs) -> Result<(), CliError> {
    let mut scene = load_scene(&args.scene)?;
    apply_model(&mut scene, args.model.as_deref())?;
    apply_duration(&mut scene, args.duration)?;
    if let Some(i) = args.output_interval {
        if !(i.is_finite() && i > 0.0) {
            return Err(CliError::Usage(format!(
                "--output-interval {i}: must be a positive number of seconds"
            )));
        }
        scene.control.output_interval = i;
    }
    let gm = load_motion(args)?;
    warn_truncation(&scene, &gm);
    let opts = RunOptions {
        out_dir: Some(&args.out),
        no_trajectory: args.no_trajectory,
        history_blocks: args.blocks.clone(),
        run_end: run_end_params(args.max_extension)?,
        ..Default::default()
    };
    let criteria = super::criteria::parse_for(&scene, &args.criterion)?;
    let outcome = run_scene(&scene, &gm, &opts)?;
    super::criteria::report(&criteria, &outcome.summary, &args.out)?;
    println!("{}", pretty(&outcome.summary)?);
    Ok(())
}

/// The end-of-run knobs with `--max-extension` applied (defaults when it is absent).
fn run_end_params(
    max_extension: Option<f64>,
) -> Result<Option<crate::analysis::run_end::RunEndParams>, CliError> {
    let Some(s) = max_extension else {
        return Ok(None);
    };
    if !(s.is_finite() && s >= 0.0) {
        return Err(CliError::Usage(format!(
            "--max-extension must be a finite number of seconds ≥ 0, got {s}"
        )));
    }
    Ok(Some(crate::analysis::run_end::RunEndParams {
        max_extension: s,
        ..Default::default()
    }))
}

pub fn pga(args: &PgaArgs) -> Result<(), CliError> {
    // With RUST_LOG set (`ashlar::analysis::pga=info`), each run of the search is logged to
    // standard error as it ends: the progress of a search that takes hours.
    crate::service::serve::init_logging(None);
    let criteria = args
        .criterion
        .iter()
        .map(|c| Criterion::parse(c).map_err(CliError::criterion("--criterion")))
        .collect::<Result<Vec<_>, _>>()?;
    let combine = Combine::parse(&args.combine)?;
    let scan = ScanOrder::parse(&args.scan)?;
    let req = args
        .range
        .request(criteria, combine, args.scan_points, scan)?;
    let method = Method::parse(&args.fit)?;
    let mut scene = load_scene(&args.scene)?;
    apply_model(&mut scene, args.model.as_deref())?;
    apply_duration(&mut scene, args.duration)?;
    let params = args.units.load_params()?;
    let (loaded, several) = load_records(&args.motion, &params)?;
    let mut records = Vec::new();
    for (p, gm) in loaded {
        warn_truncation(&scene, &gm);
        records.push((record_name(&p), gm));
    }
    std::fs::create_dir_all(&args.out).map_err(CliError::write(&args.out))?;
    let write = |name: &str, text: &str| {
        std::fs::write(args.out.join(name), text).map_err(CliError::write(args.out.join(name)))
    };
    let text = if several {
        let result = search_records(&scene, &records, &req, method, &RunOptions::default())?;
        let text = pretty(&result)?;
        let frag = serde_json::json!({
            "criterion": result.criterion,
            "units": result.units,
            "fragility": result.fragility,
            "fragility_error": result.fragility_error,
        });
        write("fragility.json", &format!("{}\n", pretty(&frag)?))?;
        match fragility_svg(&result) {
            Some(svg) => write("fragility.svg", &svg)?,
            None => eprintln!(
                "ashlar: no fragility curve: {}",
                result
                    .fragility_error
                    .as_deref()
                    .unwrap_or("unknown reason")
            ),
        }
        text
    } else {
        let (_, gm) = &records[0];
        let result = search(&scene, gm, &req, &RunOptions::default())?;
        pretty(&result)?
    };
    write("result.json", &format!("{text}\n"))?;
    println!("{text}");
    Ok(())
}
