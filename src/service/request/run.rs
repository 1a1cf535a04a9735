//! Request bodies: `POST /v1/jobs`, one run (scene, motion, an optional damage criterion).
use super::RequestError;
use super::{motion_summary, parse_criteria, scene_and_motion, typed, JobInput, Limits, Parsed};
use serde::Deserialize;
use serde_json::Value;

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RunBody {
    scene: Value,
    #[serde(default)]
    motion: Option<Value>,
    /// Damage criteria to judge on the finished run (as a search's `criterion`).
    #[serde(default)]
    criterion: Option<Value>,
}

/// `POST /v1/jobs` body → run input.
pub fn parse_run(body: &Value, limits: &Limits) -> Result<Parsed, RequestError> {
    if !body.is_object() {
        return Err(RequestError::NotAnObject {
            members: "{\"scene\": …, \"motion\": …}",
        });
    }
    let b: RunBody = typed("", body)?;
    let (scene, motion) = scene_and_motion(&b.scene, b.motion.as_ref(), limits)?;
    let criteria = match b.criterion.as_ref().filter(|c| !c.is_null()) {
        None => Vec::new(),
        Some(c) => parse_criteria(c, "/criterion", &scene)?
            .into_iter()
            .map(|(_, c)| c)
            .collect(),
    };
    let motion_summary = motion_summary(&motion);
    Ok(Parsed {
        input: JobInput::Run {
            scene,
            motion,
            criteria,
        },
        motion_summary,
    })
}
