//! `ashlar site`: the PGA interval consistent with several observations at one site, per record
//! and, over several records, its distribution (`analysis::observations`; docs/observations.md).
//! Thin: arguments in, JSON out.
use super::error::{pretty, CliError};
use super::load::{load_records, load_scene, record_name, RangeArgs};
use super::run::apply_duration;
use crate::analysis::observations::{site_analysis, Observation};
use crate::analysis::pga::{Combine, Criterion};
use crate::analysis::run::RunOptions;
use crate::motion::UnitsArg;
use std::path::PathBuf;

/// Scan points of a site analysis's searches when neither `--scan-points` nor `--resolution`
/// is given: each observation is a search per record, so the scan is kept coarse (8, as
/// before the lattice; docs/observations.md).
const SITE_SCAN_POINTS: usize = 8;

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
    /// `--min`, `--max`, `--tolerance`: the searched range, as for `pga`.
    #[command(flatten)]
    pub range: RangeArgs,
    /// Scan points over the range instead of `--resolution` (default 8 when neither is given),
    /// as for `pga`.
    #[arg(long)]
    pub scan_points: Option<usize>,
}

pub fn run(args: &SiteArgs) -> Result<(), CliError> {
    let mut observations = Vec::new();
    for (texts, observed) in [(&args.seen, true), (&args.not_seen, false)] {
        for t in texts {
            let criterion =
                Criterion::parse(t).map_err(CliError::criterion("--seen/--not-seen"))?;
            observations.push(Observation {
                criterion,
                observed,
            });
        }
    }
    if observations.is_empty() {
        return Err(CliError::Usage(
            "site: give at least one --seen or --not-seen observation".into(),
        ));
    }
    let base = args.range.request(
        Vec::new(),
        Combine::All,
        args.scan_points
            .or(args.range.resolution.is_none().then_some(SITE_SCAN_POINTS)),
        crate::analysis::pga::ScanOrder::Full,
    )?;
    let mut scene = load_scene(&args.scene)?;
    apply_duration(&mut scene, args.duration)?;
    let params = args.units.load_params()?;
    let mut loaded = Vec::new();
    for m in &args.motion {
        loaded.extend(load_records(m, &params)?.0);
    }
    let records: Vec<(String, crate::motion::GroundMotion)> = loaded
        .into_iter()
        .map(|(p, gm)| (record_name(&p), gm))
        .collect();
    let out = site_analysis(
        &scene,
        &records,
        &observations,
        &base,
        &RunOptions::default(),
    )
    .map_err(CliError::from)?;
    println!("{}", pretty(&out)?);
    Ok(())
}
