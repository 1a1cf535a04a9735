//! `ashlar study`: the speed/accuracy sweep of `analysis::study`, written as data, plots and
//! (optionally) the Markdown report.
use crate::analysis::study::{
    check, report, run_study, write_outputs, StudyOptions, GROUND_MOTIONS_DIR,
};
use std::path::PathBuf;

#[derive(Debug, clap::Args)]
pub struct StudyArgs {
    /// The reduced sweep (CI: under 2 minutes in a release build on 2 cores).
    #[arg(long)]
    pub quick: bool,
    /// Output directory for points.json, points.csv and the SVG plots.
    #[arg(long, default_value = "ashlar-study")]
    pub out: PathBuf,
    /// Also write the Markdown report here (its plots are linked relative to it).
    #[arg(long)]
    pub report: Option<PathBuf>,
    /// Directory of the recorded ground motions (the wall benchmark's record): the repository's
    /// data/ground-motions, relative to the working directory (run from the repository root).
    #[arg(long, default_value = GROUND_MOTIONS_DIR)]
    pub ground_motions: PathBuf,
    /// Wall-clock budget of one point, s (a point over budget is reported as such; default 60 s
    /// with --quick, 120 s otherwise).
    #[arg(long)]
    pub budget: Option<f64>,
    /// Assert the study (CI): every point has an error value, the defaults are within the 1 %
    /// target on every scene, and the default reduced model is not less accurate than the full
    /// engine (`analysis::study::check`); exits non-zero naming each failure.
    #[arg(long)]
    pub check: bool,
    /// Print each point as it is measured.
    #[arg(long, short)]
    pub verbose: bool,
    /// Run the records study instead (docs/accuracy-vs-speed.md, Records: two columns under every record in
    /// --ground-motions at 0.3–1.0 g, the engine at its defaults against Housner and against
    /// the engine at Δt = 1e-4 s) and write its Markdown table to this file.
    #[arg(long)]
    pub records: Option<PathBuf>,
}

pub fn run(args: &StudyArgs) -> Result<(), super::error::CliError> {
    use super::error::CliError;
    // Quick: 60 s a point. CI runs the quick study in a debug build and `--check` fails a point
    // without an error value, so the budget only guards against a hang: the slowest quick point
    // (the wall with the trapezoidal integrator at Δt = 1e-3 s, thousands of Δt cuts) took over
    // 10 s in a debug build on the shared 2-core machine (2.5 of its 3 s simulated in 10 s).
    let budget = args.budget.unwrap_or(if args.quick { 60.0 } else { 120.0 });
    if !(budget.is_finite() && budget > 0.0) {
        return Err(CliError::Usage(format!(
            "--budget {budget}: must be a positive number of seconds"
        )));
    }
    if !args.ground_motions.is_dir() {
        return Err(CliError::Usage(format!(
            "--ground-motions {}: not a directory (the records are in the repository's \
             {GROUND_MOTIONS_DIR}/: run from the repository root or pass \
             --ground-motions PATH/TO/ashlar/{GROUND_MOTIONS_DIR})",
            args.ground_motions.display()
        )));
    }
    if let Some(path) = &args.records {
        return crate::analysis::study_records::run_cli(
            &args.ground_motions,
            path,
            args.quick,
            args.verbose,
        )
        .map_err(CliError::from);
    }
    let opts = StudyOptions {
        quick: args.quick,
        ground_motions: args.ground_motions.clone(),
        point_budget_s: budget,
        verbose: args.verbose,
    };
    let result = run_study(&opts)?;
    let written = write_outputs(&result, &args.out)?;
    if let Some(path) = &args.report {
        let base = path.parent().unwrap_or(std::path::Path::new("."));
        let rel = pathdiff(&args.out, base);
        let command = format!(
            "ashlar study{} --out {} --report {}",
            if args.quick { " --quick" } else { "" },
            args.out.display(),
            path.display()
        );
        std::fs::write(path, report(&result, &rel, &command)).map_err(CliError::write(path))?;
    }
    let failed = result.points.iter().filter(|p| p.error.is_none()).count();
    println!(
        "{} points over {} scenes ({} without an error value); wrote {}",
        result.points.len(),
        result.scenes.len(),
        failed,
        written
            .iter()
            .map(|p| p.display().to_string())
            .collect::<Vec<_>>()
            .join(", ")
    );
    if args.check {
        match check(&result) {
            Ok(lines) => {
                for l in lines {
                    println!("check: {l}");
                }
                println!("check: passed");
            }
            Err(failures) => return Err(CliError::StudyCheck(failures)),
        }
    }
    Ok(())
}

/// `out` relative to `base` when it lies under it, else `out` as given.
fn pathdiff(out: &std::path::Path, base: &std::path::Path) -> String {
    out.strip_prefix(base)
        .map(|p| p.display().to_string())
        .unwrap_or_else(|_| out.display().to_string())
}
