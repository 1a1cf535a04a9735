//! `ashlar site`: the PGA interval consistent with several observations at one site, per record
//! and, over several records, its distribution (`analysis::observations`; docs/observations.md).
//! Thin: arguments in, JSON out.
use super::run::{acceleration_option, apply_duration, load_scene, record_name, record_paths};
use crate::analysis::observations::{
    criterion_records, distribution, site_interval, DistributionParams, Observation,
};
use crate::analysis::pga::{Combine, Criterion, PgaRequest};
use crate::analysis::run::RunOptions;
use crate::motion::{self, UnitsArg};
use std::path::PathBuf;

#[derive(Debug, clap::Args)]
pub struct SiteArgs {
    /// Scene file (ashlar.scene/1 JSON).
    pub scene: PathBuf,
    /// Record(s), as for `pga`: a file, a directory, a comma-separated list or a `.list` file.
    /// Repeat for several; over several records the PGA distribution is printed too.
    #[arg(long, required = true)]
    pub motion: Vec<String>,
    /// Damage seen at the site (a `pga` criterion or the JSON of docs/format.md §3): a lower
    /// bound. Repeat for several.
    #[arg(long)]
    pub seen: Vec<String>,
    /// Damage NOT seen (e.g. the neighbouring column stands): an upper bound. Repeat.
    #[arg(long = "not-seen")]
    pub not_seen: Vec<String>,
    #[command(flatten)]
    pub units: UnitsArg,
    /// Run duration in seconds (overrides the scene's control.duration), as for `pga`.
    #[arg(long)]
    pub duration: Option<f64>,
    /// Lower end of the searched range, with units.
    #[arg(long, default_value = "0.05g")]
    pub min: String,
    /// Upper end of the searched range, with units.
    #[arg(long, default_value = "2g")]
    pub max: String,
    /// Bracket width to stop at, with units.
    #[arg(long, default_value = "0.01m/s2")]
    pub tolerance: String,
    /// Coarse scan points before bisection.
    #[arg(long, default_value_t = 8)]
    pub scan_points: usize,
}

pub fn run(args: &SiteArgs) -> Result<(), String> {
    let mut observations = Vec::new();
    for (texts, observed) in [(&args.seen, true), (&args.not_seen, false)] {
        for t in texts {
            let criterion = Criterion::parse(t).map_err(|e| format!("--seen/--not-seen: {e}"))?;
            observations.push(Observation {
                criterion,
                observed,
            });
        }
    }
    if observations.is_empty() {
        return Err("site: give at least one --seen or --not-seen observation".into());
    }
    let base = PgaRequest {
        criteria: Vec::new(),
        combine: Combine::All,
        min: acceleration_option("min", &args.min)?,
        max: acceleration_option("max", &args.max)?,
        tolerance: acceleration_option("tolerance", &args.tolerance)?,
        scan_points: args.scan_points,
    };
    let mut scene = load_scene(&args.scene)?;
    apply_duration(&mut scene, args.duration)?;
    let params = args.units.load_params().map_err(|e| e.to_string())?;
    let mut paths = Vec::new();
    for m in &args.motion {
        paths.extend(record_paths(m)?.0);
    }
    let mut records = Vec::new();
    let mut intervals = Vec::new();
    for p in &paths {
        let gm = motion::load_path_with(p, &params).map_err(|e| e.to_string())?;
        let interval = site_interval(&scene, &gm, &observations, &base, &RunOptions::default())
            .map_err(|e| format!("{}: {e}", p.display()))?;
        let mut v = serde_json::to_value(&interval).map_err(|e| e.to_string())?;
        v["record"] = serde_json::Value::from(record_name(p));
        records.push(v);
        intervals.push(interval);
    }
    let dist = distribution(
        &criterion_records(&observations, &intervals),
        base.min,
        base.max,
        &DistributionParams::default(),
    );
    let out = serde_json::json!({ "units": "m/s2", "records": records, "distribution": dist });
    println!(
        "{}",
        serde_json::to_string_pretty(&out).map_err(|e| e.to_string())?
    );
    Ok(())
}
