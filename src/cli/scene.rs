//! `ashlar scene`: build a parametric structure (`scene::templates`) and print its scene JSON, list
//! the templates, or import a DXF drawing (`ashlar scene import FILE`, `scene::import::dxf`). Thin:
//! parsing arguments and printing; the templates and the importer live in the library.
use super::error::CliError;
use crate::scene::import::dxf::{self, ImportOptions};
use crate::scene::templates;
use serde_json::Value;
use std::collections::BTreeMap;
use std::path::PathBuf;

/// The word that makes `ashlar scene` import a drawing instead of building a template (no
/// template has this name: `scene::templates::find` refuses it).
pub const IMPORT: &str = "import";

#[derive(Debug, clap::Args)]
pub struct SceneArgs {
    /// Template to build (`ashlar scene --list` names them): drum-column, colonnade, arch,
    /// wall, buttressed-wall, obelisk, pyramid; or `import` to read a DXF drawing (docs/import.md).
    #[arg(required_unless_present = "list")]
    pub name: Option<String>,
    /// With `import`: the DXF drawing (closed polylines; layer = material, layer `fixed` = fixed).
    #[arg(value_name = "DRAWING.dxf")]
    pub drawing: Option<PathBuf>,
    /// A parameter's value, `KEY=VALUE` (lengths in m, angles in degrees); repeat for several.
    #[arg(long = "set", value_name = "KEY=VALUE")]
    pub set: Vec<String>,
    /// With `import`: a JSON file of materials, joint, units and layers to skip (docs/import.md).
    #[arg(long, value_name = "FILE")]
    pub options: Option<PathBuf>,
    /// Print the templates and their parameters (name, units, default, min, max) as JSON.
    #[arg(long, conflicts_with_all = ["name", "set"])]
    pub list: bool,
}

pub fn run(args: &SceneArgs) -> Result<(), CliError> {
    let name = args.name.as_deref().unwrap_or_default();
    if name == IMPORT {
        return import(args);
    }
    if let Some(d) = &args.drawing {
        return Err(CliError::Usage(format!(
            "scene {name}: unexpected argument {}; a template takes --set KEY=VALUE (to import a \
             drawing: ashlar scene import DRAWING.dxf)",
            d.display()
        )));
    }
    if args.options.is_some() {
        return Err(CliError::Usage(
            "scene: --options applies to `ashlar scene import DRAWING.dxf`".into(),
        ));
    }
    let text = if args.list {
        serde_json::to_string_pretty(&templates::list())
    } else {
        let mut given = BTreeMap::new();
        for kv in &args.set {
            let (k, v) = kv
                .split_once('=')
                .ok_or_else(|| CliError::Usage(format!("--set {kv:?}: expected KEY=VALUE")))?;
            if given
                .insert(k.trim().to_string(), Value::String(v.trim().to_string()))
                .is_some()
            {
                return Err(CliError::Usage(format!("--set {k}: given twice")));
            }
        }
        let (spec, _) = templates::build(name, &given)
            .map_err(|e| CliError::from(e).at(format!("scene {name}")))?;
        serde_json::to_string_pretty(&spec)
    }
    .map_err(CliError::json("scene: cannot write JSON"))?;
    println!("{text}");
    Ok(())
}

/// `ashlar scene import DRAWING.dxf [--options FILE]`: the scene JSON on stdout, notes (units
/// assumed, materials defaulted, entities skipped) on stderr.
fn import(args: &SceneArgs) -> Result<(), CliError> {
    let Some(path) = &args.drawing else {
        return Err(CliError::Usage(
            "scene import: give the drawing: ashlar scene import DRAWING.dxf".into(),
        ));
    };
    if !args.set.is_empty() {
        return Err(CliError::Usage(
            "scene import: --set applies to templates; use --options FILE".into(),
        ));
    }
    let options = match &args.options {
        None => ImportOptions::default(),
        Some(p) => {
            let text = std::fs::read_to_string(p).map_err(CliError::read(p))?;
            ImportOptions::from_json(&text).map_err(|source| CliError::Import {
                path: p.clone(),
                source: Box::new(source),
            })?
        }
    };
    let bytes = std::fs::read(path).map_err(CliError::read(path))?;
    let imported = dxf::import(&bytes, &options).map_err(|source| CliError::Import {
        path: path.clone(),
        source: Box::new(source),
    })?;
    for note in &imported.notes {
        eprintln!("ashlar: {}: note: {note}", path.display());
    }
    let text = serde_json::to_string_pretty(&imported.spec)
        .map_err(CliError::json("scene: cannot write JSON"))?;
    println!("{text}");
    Ok(())
}
