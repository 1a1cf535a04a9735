//! `ashlar sweep`: studies on batch systems with no server. `--index N` runs line N of a JSONL
//! manifest (one scene × record × amplitude per line) into `OUT/NNNNNN/`; `--collect OUT`
//! gathers the lines into `report.json`: per scene, record and criterion, the runs and the
//! threshold bracket in the shape of the PGA search's `result.json` (docs/format.md §3).
//! Thin: parsing and files here, the runs in `analysis`.
use super::error::{pretty, CliError};
use crate::analysis::pga::{met_by_summary, Criterion, PgaResult, PgaRun};
use crate::analysis::run::{run as run_scene, RunOptions, Summary};
use crate::motion::{self, parse_acceleration, GroundMotion};
use crate::scene::parse_scene;
use serde::{Deserialize, Serialize};
use serde_json::Value;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

#[derive(Debug, clap::Args)]
#[command(group(clap::ArgGroup::new("mode").required(true).args(["manifest", "collect"])))]
pub struct SweepArgs {
    /// The manifest: JSON lines `{"scene": PATH, "record": PATH, "amplitude": "0.3g",
    /// "criterion": "toppled:BLOCK"}` (paths relative to the manifest; record, amplitude and
    /// criterion optional). The amplitude is a PGA with units ("0.3g", "2.5m/s2", "250gal"),
    /// or a bare JSON number in m/s².
    pub manifest: Option<PathBuf>,
    /// Line to run, from 0. Default: $SLURM_ARRAY_TASK_ID, else $JOB_COMPLETION_INDEX
    /// (Kubernetes indexed jobs), else $ASHLAR_SWEEP_INDEX.
    #[arg(long, requires = "manifest")]
    pub index: Option<usize>,
    /// Results directory (each line writes OUT/NNNNNN/).
    #[arg(long, default_value = "sweep-results")]
    pub out: PathBuf,
    /// Gather the results in DIR into DIR/report.json (and print it).
    #[arg(long, value_name = "DIR")]
    pub collect: Option<PathBuf>,
    /// With --collect: the manifest the results came from, to name missing lines.
    #[arg(long = "with-manifest", requires = "collect")]
    pub with_manifest: Option<PathBuf>,
    /// With --collect: write the report even if lines of --with-manifest are missing.
    #[arg(long, requires = "collect")]
    pub allow_missing: bool,
    /// Do not write trajectory.mcap for each line.
    #[arg(long)]
    pub no_trajectory: bool,
}

/// One manifest line as written.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
struct Line {
    scene: String,
    #[serde(default)]
    record: Option<String>,
    #[serde(default)]
    amplitude: Option<Value>,
    #[serde(default)]
    criterion: Option<Value>,
    /// Free label carried into the report.
    #[serde(default)]
    label: Option<String>,
}

/// `line.json`: what one line ran and its verdict (written next to summary.json).
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct LineResult {
    pub index: usize,
    pub scene: String,
    pub record: Option<String>,
    /// m/s² applied (the record's own PGA when the line has no amplitude).
    pub pga: f64,
    pub criterion: Option<String>,
    /// Whether the criterion was met (None without a criterion).
    pub failed: Option<bool>,
    pub failure_mode: String,
    pub label: Option<String>,
    /// Unit of each numeric field: `{"pga": "m/s2"}`.
    #[serde(default)]
    pub units: Value,
}

pub fn run(args: &SweepArgs) -> Result<(), CliError> {
    match (&args.manifest, &args.collect) {
        (Some(m), None) => run_line(args, m),
        (None, Some(dir)) => collect(args, dir),
        _ => Err(CliError::Usage(
            "give either MANIFEST (with --index) or --collect DIR".into(),
        )),
    }
}

fn index_from_env() -> Result<usize, CliError> {
    for var in [
        "SLURM_ARRAY_TASK_ID",
        "JOB_COMPLETION_INDEX",
        "ASHLAR_SWEEP_INDEX",
    ] {
        if let Ok(v) = std::env::var(var) {
            return v.trim().parse().map_err(|_| {
                CliError::Usage(format!("${var} = {v:?} is not a line index (0, 1, 2…)"))
            });
        }
    }
    Err(CliError::Usage(
        "--index N is required (or $SLURM_ARRAY_TASK_ID / $JOB_COMPLETION_INDEX)".into(),
    ))
}

fn read_manifest(path: &Path) -> Result<Vec<(usize, String)>, CliError> {
    let text = std::fs::read_to_string(path).map_err(CliError::read(path))?;
    // Line numbers of non-blank lines: index k is the k-th non-blank line (from 0).
    Ok(text
        .lines()
        .enumerate()
        .filter(|(_, l)| !l.trim().is_empty())
        .map(|(n, l)| (n + 1, l.to_string()))
        .collect())
}

fn parse_criteria(v: &Option<Value>, at: &str) -> Result<Vec<Criterion>, CliError> {
    let texts: Vec<String> = match v {
        None | Some(Value::Null) => vec![],
        Some(Value::String(s)) => vec![s.clone()],
        Some(Value::Array(a)) => a
            .iter()
            .map(|x| {
                x.as_str()
                    .map(str::to_string)
                    .ok_or_else(|| CliError::Usage(format!("{at}: criterion: expected strings")))
            })
            .collect::<Result<_, _>>()?,
        Some(_) => {
            return Err(CliError::Usage(format!(
                "{at}: criterion: expected a string or a list"
            )))
        }
    };
    texts
        .iter()
        .map(|t| Criterion::parse(t).map_err(CliError::criterion(at)))
        .collect()
}

fn run_line(args: &SweepArgs, manifest: &Path) -> Result<(), CliError> {
    let index = match args.index {
        Some(i) => i,
        None => index_from_env()?,
    };
    let lines = read_manifest(manifest)?;
    let Some((line_no, text)) = lines.get(index) else {
        return Err(CliError::Usage(format!(
            "--index {index}: {} has {} lines (indices 0..{})",
            manifest.display(),
            lines.len(),
            lines.len().saturating_sub(1)
        )));
    };
    let at = format!("{} line {line_no}", manifest.display());
    let line: Line = serde_json::from_str(text).map_err(CliError::json(&at))?;
    let base = manifest.parent().unwrap_or(Path::new("."));
    let scene_path = base.join(&line.scene);
    let scene_text = std::fs::read_to_string(&scene_path)
        .map_err(|e| CliError::read(&scene_path)(e).at(format!("{at}: scene")))?;
    let scene = parse_scene(&scene_text).map_err(|source| {
        CliError::Scene {
            path: line.scene.clone().into(),
            source,
        }
        .at(format!("{at}: scene"))
    })?;
    let mut gm = match &line.record {
        Some(r) => motion::load_path(&base.join(r))
            .map_err(|e| CliError::from(e).at(format!("{at}: record {r}")))?,
        None => GroundMotion::none(),
    };
    match &line.amplitude {
        None | Some(Value::Null) => {}
        Some(Value::Number(n)) => {
            let a = n
                .as_f64()
                .filter(|a| a.is_finite() && *a >= 0.0)
                .ok_or_else(|| {
                    CliError::Usage(format!("{at}: amplitude must be a number ≥ 0 (m/s²) or a string with units like \"0.3g\""))
                })?;
            gm = gm.scaled_to_pga(a);
        }
        Some(Value::String(s)) => {
            let a = parse_acceleration(s).map_err(|source| {
                CliError::Acceleration {
                    option: "amplitude".into(),
                    text: s.clone(),
                    source,
                }
                .at(at.clone())
            })?;
            gm = gm.scaled_to_pga(a)
        }
        Some(_) => {
            return Err(CliError::Usage(format!(
                "{at}: amplitude must be a number (m/s²) or a string with units like \"0.3g\""
            )))
        }
    }
    let criteria = parse_criteria(&line.criterion, &at)?;
    for c in &criteria {
        if !scene.blocks.iter().any(|b| b.id == c.block()) {
            return Err(CliError::Usage(format!(
                "{at}: criterion {}: the scene has no block {:?}",
                c.text(),
                c.block()
            )));
        }
    }
    // Written into a scratch directory, renamed into place when complete: --collect never
    // sees half a line, and a rerun (a retried array task) replaces the old result whole.
    std::fs::create_dir_all(&args.out).map_err(CliError::write(&args.out))?;
    let final_dir = args.out.join(format!("{index:06}"));
    let tmp = args
        .out
        .join(format!(".{index:06}.{}", uuid::Uuid::new_v4().simple()));
    let opts = RunOptions {
        out_dir: Some(&tmp),
        no_trajectory: args.no_trajectory,
        ..Default::default()
    };
    let outcome = run_scene(&scene, &gm, &opts).map_err(|e| CliError::from(e).at(at.clone()))?;
    let result = LineResult {
        index,
        scene: line.scene.clone(),
        record: line.record.clone(),
        pga: gm.pga(),
        criterion: (!criteria.is_empty()).then(|| {
            criteria
                .iter()
                .map(Criterion::text)
                .collect::<Vec<_>>()
                .join(",")
        }),
        failed: (!criteria.is_empty()).then(|| met_by_summary(&criteria, &outcome.summary)),
        failure_mode: outcome.summary.failure_mode.clone(),
        label: line.label.clone(),
        units: serde_json::json!({ "pga": "m/s2" }),
    };
    let json = pretty(&result)?;
    std::fs::write(tmp.join("line.json"), format!("{json}\n")).map_err(CliError::write(&tmp))?;
    if final_dir.exists() {
        std::fs::remove_dir_all(&final_dir).map_err(CliError::write(&final_dir))?;
    }
    std::fs::rename(&tmp, &final_dir).map_err(CliError::write(&final_dir))?;
    println!("{json}");
    Ok(())
}

/// One group of the report: every line of one scene × record × criterion.
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
pub struct Group {
    pub scene: String,
    pub record: Option<String>,
    pub criterion: Option<String>,
    /// Lines of the group, by amplitude.
    pub lines: Vec<usize>,
    /// The PGA search's `result.json` for this grid (with a criterion).
    pub result: Option<PgaResult>,
    /// Failure mode per amplitude, same order as `lines`.
    pub failure_modes: Vec<String>,
}

/// `report.json` of `--collect`.
#[derive(Debug, Clone, Serialize, Deserialize, PartialEq)]
pub struct Report {
    pub format: String,
    pub lines: usize,
    pub missing: Vec<usize>,
    pub groups: Vec<Group>,
}

/// The threshold bracket of a grid of verdicts, by the PGA search's rules: `failing_pga` is the
/// lowest failing amplitude, `safe_pga` the highest safe one below it; `monotonic` is false when
/// a safe amplitude lies above a failing one.
pub fn bracket(criterion: &str, runs: &[PgaRun]) -> PgaResult {
    let mut runs = runs.to_vec();
    runs.sort_by(|a, b| a.pga.total_cmp(&b.pga));
    let (safe, failing, monotonic) = crate::analysis::pga::bracket_of(&runs);
    PgaResult {
        criterion: criterion.to_string(),
        safe_pga: safe,
        failing_pga: failing,
        units: "m/s2".into(),
        monotonic,
        // The grid's widest gap: a failing interval narrower than it may lie between two of
        // the manifest's amplitudes.
        resolution: runs
            .windows(2)
            .map(|w| w[1].pga - w[0].pga)
            .fold(0.0, f64::max),
        failing_intervals: crate::analysis::pga::failing_intervals(&runs),
        scan: crate::analysis::pga::ScanOrder::Full,
        scanned_to: runs.last().map(|r| r.pga),
        runs,
    }
}

/// Scene, record, criterion.
type GroupKey = (String, Option<String>, Option<String>);

fn collect(args: &SweepArgs, dir: &Path) -> Result<(), CliError> {
    let entries = std::fs::read_dir(dir).map_err(|e| CliError::read(dir)(e).at("--collect"))?;
    let mut results: Vec<(LineResult, Summary)> = Vec::new();
    for e in entries {
        let e = e.map_err(|e| CliError::read(dir)(e).at("--collect"))?;
        let name = e.file_name().to_string_lossy().to_string();
        if name.starts_with('.') || !e.path().is_dir() {
            continue;
        }
        let read = |f: &str| -> Result<String, CliError> {
            let p = e.path().join(f);
            std::fs::read_to_string(&p).map_err(CliError::read(&p))
        };
        let line: LineResult = serde_json::from_str(&read("line.json")?)
            .map_err(CliError::json(format!("{}/line.json", e.path().display())))?;
        let summary: Summary = serde_json::from_str(&read("summary.json")?).map_err(
            CliError::json(format!("{}/summary.json", e.path().display())),
        )?;
        results.push((line, summary));
    }
    results.sort_by_key(|(l, _)| l.index);
    let mut missing = Vec::new();
    if let Some(m) = &args.with_manifest {
        let n = read_manifest(m)?.len();
        let have: std::collections::BTreeSet<usize> =
            results.iter().map(|(l, _)| l.index).collect();
        missing = (0..n).filter(|k| !have.contains(k)).collect();
        if !missing.is_empty() && !args.allow_missing {
            return Err(CliError::Usage(format!(
                "{} of {n} lines have no result in {} (first: {:?}); rerun them, or pass --allow-missing",
                missing.len(),
                dir.display(),
                &missing[..missing.len().min(10)]
            )));
        }
    }
    let mut groups: BTreeMap<GroupKey, Vec<&LineResult>> = BTreeMap::new();
    for (l, _) in &results {
        groups
            .entry((l.scene.clone(), l.record.clone(), l.criterion.clone()))
            .or_default()
            .push(l);
    }
    let groups = groups
        .into_iter()
        .map(|((scene, record, criterion), mut ls)| {
            ls.sort_by(|a, b| a.pga.total_cmp(&b.pga));
            let result = criterion.as_ref().map(|c| {
                let runs: Vec<PgaRun> = ls
                    .iter()
                    .map(|l| PgaRun {
                        pga: l.pga,
                        failed: l.failed.unwrap_or(false),
                    })
                    .collect();
                bracket(c, &runs)
            });
            Group {
                scene,
                record,
                criterion,
                lines: ls.iter().map(|l| l.index).collect(),
                failure_modes: ls.iter().map(|l| l.failure_mode.clone()).collect(),
                result,
            }
        })
        .collect();
    let report = Report {
        format: "ashlar.sweep-report/1".into(),
        lines: results.len(),
        missing,
        groups,
    };
    let text = pretty(&report)?;
    let path = dir.join("report.json");
    std::fs::write(&path, format!("{text}\n")).map_err(CliError::write(&path))?;
    println!("{text}");
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn r(pga: f64, failed: bool) -> PgaRun {
        PgaRun { pga, failed }
    }

    #[test]
    fn bracket_follows_the_search_rules() {
        // Hand-worked: lowest failure at 3, highest safe below it 2; 4 safe above 3 → not monotonic.
        let b = bracket(
            "toppled:c",
            &[
                r(4.0, false),
                r(1.0, false),
                r(3.0, true),
                r(2.0, false),
                r(5.0, true),
            ],
        );
        assert_eq!(
            (b.safe_pga, b.failing_pga, b.monotonic),
            (Some(2.0), Some(3.0), false)
        );
        assert_eq!(
            b.runs.iter().map(|r| r.pga).collect::<Vec<_>>(),
            vec![1.0, 2.0, 3.0, 4.0, 5.0]
        );
        let all_safe = bracket("c", &[r(1.0, false), r(2.0, false)]);
        assert_eq!(
            (all_safe.safe_pga, all_safe.failing_pga, all_safe.monotonic),
            (Some(2.0), None, true)
        );
        let all_fail = bracket("c", &[r(1.0, true), r(2.0, true)]);
        assert_eq!(
            (all_fail.safe_pga, all_fail.failing_pga, all_fail.monotonic),
            (None, Some(1.0), true)
        );
    }
}
