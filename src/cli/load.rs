//! The CLI's loaders, shared by its subcommands (`run`, `pga`, `site`): the scene file, the
//! records `--motion` names, the amplitude range of a search. Thin: files and arguments in,
//! `scene` / `motion` / `analysis` values out.
use super::error::CliError;
use crate::analysis::pga::{
    default_resolution, Combine, Criterion, PgaRequest, ScanOrder, DEFAULT_SCAN_POINTS,
};
use crate::motion::{self, parse_acceleration, GroundMotion, LoadParams};
use crate::scene::{parse_scene, Scene};
use std::path::{Path, PathBuf};

/// The amplitude range of a search (`pga`, `site`), with units.
#[derive(Debug, clap::Args)]
pub struct RangeArgs {
    /// Lower end of the amplitude range, with units (0.05g, 0.5m/s2, 50gal).
    #[arg(long, default_value = "0.05g")]
    pub min: String,
    /// Upper end of the amplitude range, with units (2g, 20m/s2).
    #[arg(long, default_value = "2g")]
    pub max: String,
    /// Bracket width to stop at, with units (0.01m/s2, 0.001g, 1gal).
    #[arg(long, default_value = "0.01m/s2")]
    pub tolerance: String,
    /// Scan resolution asked for, with units (0.64m/s2, 0.05g): the scan runs on the multiples
    /// of h = tolerance × 2^K ≤ it, anchored at 0, so that searches sharing it share their
    /// answer whatever their range (docs/pga.md). Default 0.64 m/s² (coarser over ranges wider
    /// than 25 m/s²: at most 40 points asked).
    #[arg(long, conflicts_with = "scan_points")]
    pub resolution: Option<String>,
}

impl RangeArgs {
    /// The search request over this range. The resolution asked for: `--resolution`, else
    /// that of `scan_points` when given, else [`default_resolution`].
    pub fn request(
        &self,
        criteria: Vec<Criterion>,
        combine: Combine,
        scan_points: Option<usize>,
        scan: ScanOrder,
    ) -> Result<PgaRequest, CliError> {
        let min = acceleration_option("min", &self.min)?;
        let max = acceleration_option("max", &self.max)?;
        let resolution = match (&self.resolution, scan_points) {
            (Some(text), _) => Some(acceleration_option("resolution", text)?),
            (None, Some(_)) => None,
            (None, None) => Some(default_resolution(min, max)),
        };
        Ok(PgaRequest {
            criteria,
            combine,
            min,
            max,
            tolerance: acceleration_option("tolerance", &self.tolerance)?,
            scan_points: scan_points.unwrap_or(DEFAULT_SCAN_POINTS),
            resolution,
            scan,
        })
    }
}

/// Record file extensions picked from a directory.
const RECORD_EXTENSIONS: [&str; 8] = ["at2", "csv", "v1", "v2", "v1c", "v2c", "asc", "json"];

/// The record paths `--motion` names: one file, a directory, a comma-separated list or a
/// `.list` file. Returns whether several were meant (a directory or list, even of one).
pub fn record_paths(spec: &str) -> Result<(Vec<PathBuf>, bool), CliError> {
    if spec.contains(',') {
        let paths: Vec<PathBuf> = spec
            .split(',')
            .map(str::trim)
            .filter(|s| !s.is_empty())
            .map(PathBuf::from)
            .collect();
        if paths.is_empty() {
            return Err(CliError::Usage(format!(
                "--motion {spec:?}: the list names no record"
            )));
        }
        return Ok((paths, true));
    }
    let path = PathBuf::from(spec);
    if path.is_dir() {
        let mut paths: Vec<PathBuf> = std::fs::read_dir(&path)
            .map_err(|e| CliError::read(&path)(e).at("--motion"))?
            .filter_map(|e| e.ok().map(|e| e.path()))
            .filter(|p| {
                p.is_file()
                    && p.extension().and_then(|e| e.to_str()).is_some_and(|e| {
                        RECORD_EXTENSIONS.contains(&e.to_ascii_lowercase().as_str())
                    })
            })
            .collect();
        paths.sort();
        if paths.is_empty() {
            return Err(CliError::Usage(format!(
                "--motion {}: the directory holds no record file (.{})",
                path.display(),
                RECORD_EXTENSIONS.join(", .")
            )));
        }
        return Ok((paths, true));
    }
    if path.extension().and_then(|e| e.to_str()) == Some("list") {
        let text =
            std::fs::read_to_string(&path).map_err(|e| CliError::read(&path)(e).at("--motion"))?;
        let dir = path.parent().unwrap_or(Path::new("."));
        let paths: Vec<PathBuf> = text
            .lines()
            .map(str::trim)
            .filter(|l| !l.is_empty() && !l.starts_with('#'))
            .map(|l| dir.join(l))
            .collect();
        if paths.is_empty() {
            return Err(CliError::Usage(format!(
                "--motion {}: the list names no record",
                path.display()
            )));
        }
        return Ok((paths, true));
    }
    Ok((vec![path], false))
}

/// A record's name in results: its file name.
pub fn record_name(p: &Path) -> String {
    p.file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_else(|| p.display().to_string())
}

/// `--NAME TEXT` as an acceleration with units, in m/s².
pub fn acceleration_option(name: &str, text: &str) -> Result<f64, CliError> {
    parse_acceleration(text).map_err(|source| CliError::Acceleration {
        option: format!("--{name}"),
        text: text.to_string(),
        source,
    })
}

/// The scene file at `path`, parsed and validated.
pub fn load_scene(path: &Path) -> Result<Scene, CliError> {
    let text = std::fs::read_to_string(path).map_err(CliError::read(path))?;
    parse_scene(&text).map_err(|source| CliError::Scene {
        path: path.to_path_buf(),
        source,
    })
}

/// The records `--motion` names (see [`record_paths`]), loaded with `params`: each with its
/// path, and whether several were meant.
pub fn load_records(
    spec: &str,
    params: &LoadParams,
) -> Result<(Vec<(PathBuf, GroundMotion)>, bool), CliError> {
    let (paths, several) = record_paths(spec)?;
    let mut records = Vec::new();
    for p in paths {
        let gm = motion::load_path_with(&p, params)?;
        records.push((p, gm));
    }
    Ok((records, several))
}
