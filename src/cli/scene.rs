//! `ashlar scene`: build a parametric structure (`scene::templates`) and print its scene JSON, or
//! list the templates. Thin: parsing `--set` and printing; the templates live in the library.
use super::error::CliError;
use crate::scene::templates;
use serde_json::Value;
use std::collections::BTreeMap;

#[derive(Debug, clap::Args)]
pub struct SceneArgs {
    /// Template to build (`ashlar scene --list` names them): drum-column, colonnade, arch,
    /// wall, buttressed-wall, obelisk, pyramid.
    #[arg(required_unless_present = "list")]
    pub name: Option<String>,
    /// A parameter's value, `KEY=VALUE` (lengths in m, angles in degrees); repeat for several.
    #[arg(long = "set", value_name = "KEY=VALUE")]
    pub set: Vec<String>,
    /// Print the templates and their parameters (name, units, default, min, max) as JSON.
    #[arg(long, conflicts_with_all = ["name", "set"])]
    pub list: bool,
}

pub fn run(args: &SceneArgs) -> Result<(), CliError> {
    let text = if args.list {
        serde_json::to_string_pretty(&templates::list())
    } else {
        let name = args.name.as_deref().unwrap_or_default();
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
