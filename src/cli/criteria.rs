//! `ashlar run --criterion`: evaluate damage criteria (`analysis::criteria`, or the `pga`
//! forms) on a finished run's summary; verdicts to OUT/criteria.json and one line each on
//! standard error (standard output keeps the summary alone).
use super::error::{pretty, CliError};
use crate::analysis::pga::Criterion;
use crate::analysis::run::Summary;
use crate::scene::{BlockKind, Scene};
use std::path::Path;

/// Parse the criteria and check them against the scene before anything runs.
pub fn parse_for(scene: &Scene, texts: &[String]) -> Result<Vec<Criterion>, CliError> {
    let mut out = Vec::new();
    for t in texts {
        let c = Criterion::parse(t).map_err(CliError::criterion("--criterion"))?;
        if let Criterion::Damage { damage } = &c {
            damage
                .check(scene)
                .map_err(|e| CliError::from(e).at("--criterion"))?;
        }
        for id in c.blocks() {
            let free = scene
                .block_index(id)
                .is_some_and(|b| matches!(scene.blocks[b].kind, BlockKind::Free(_)));
            if !free {
                return Err(CliError::Usage(format!(
                    "--criterion {t:?}: no free block with id {id:?}"
                )));
            }
        }
        out.push(c);
    }
    Ok(out)
}

/// Evaluate and report; nothing when no criterion was given.
pub fn report(criteria: &[Criterion], summary: &Summary, out: &Path) -> Result<(), CliError> {
    if criteria.is_empty() {
        return Ok(());
    }
    let verdicts = crate::analysis::pga::verdicts(criteria, summary);
    for v in &verdicts {
        eprintln!(
            "criterion {}: {}",
            v.criterion,
            if v.met { "met" } else { "not met" }
        );
    }
    let text = pretty(&verdicts)?;
    std::fs::create_dir_all(out).map_err(CliError::write(out))?;
    let path = out.join("criteria.json");
    std::fs::write(&path, text).map_err(CliError::write(&path))
}
