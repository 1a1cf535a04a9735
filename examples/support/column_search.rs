//! Shared by the column-search profiles (`reduced_profile`, `fallback_profile`): the bundled
//! records, the default search's request over the column, and one run of it replayed alone on
//! this thread (its CPU time from `thread_cpu`, which the example declares beside this module).
use crate::thread_cpu::cpu;
use ashlar::analysis::pga::{evaluate_with_summary, Criterion, PgaRequest};
use ashlar::analysis::run::Summary;
use ashlar::motion::GroundMotion;
use ashlar::scene::Scene;
use std::path::PathBuf;

/// The repository's records (`.at2`, `.csv`), sorted; those whose path contains `only` when
/// it is given.
pub fn records(only: Option<&str>) -> Vec<PathBuf> {
    let mut records: Vec<_> = std::fs::read_dir(ashlar::presets::records_dir())
        .expect("records")
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| matches!(p.extension().and_then(|e| e.to_str()), Some("at2" | "csv")))
        .filter(|p| only.is_none_or(|o| p.to_string_lossy().contains(o)))
        .collect();
    records.sort();
    records
}

/// The default column search: `toppled:column` with the CLI's range, scan and tolerance.
pub fn request() -> PgaRequest {
    PgaRequest::cli_default(vec![Criterion::parse("toppled:column").expect("criterion")])
}

/// One run of the search at `pga` (m/s²) replayed alone on this thread as the search ran it
/// (early stop once the criterion is decided): (failed, its summary, the thread's CPU s).
pub fn replay(
    scene: &Scene,
    gm: &GroundMotion,
    req: &PgaRequest,
    pga: f64,
) -> (bool, Summary, f64) {
    let c0 = cpu();
    let (failed, s) =
        evaluate_with_summary(scene, gm, &req.criteria, req.combine, pga, None).expect("run");
    (failed, s, cpu() - c0)
}
