//! Service: request bodies, JSON text → validated [`JobInput`], with the server's limits
//! applied (`budget`: the pre-scan, ranges and work estimates). Beside `jobs`, below `http` and
//! `worker`, which both import it; it imports no HTTP type: its errors are [`RequestError`]s
//! (`error.rs`, one variant per cause, each naming its JSON pointer), which `http` turns into
//! problems and the worker shows as text.
//! Used twice with the same rules: by the routes when a job is submitted (errors become
//! 400/413/422 problems naming the field) and by a worker when it starts the stored job.
//! This module holds what the three kinds share (limits, the scene and motion checks, criteria);
//! `run`, `pga` and `site` parse each kind's body. Over 600 lines with its tests, which cover
//! the three parsers through their shared checks.
pub mod budget;
pub mod error;
mod pga;
pub mod pointer;
mod run;
mod site;

use crate::analysis::fragility::Method;
use crate::analysis::pga::{Criterion, PgaRequest};
use crate::motion::{GroundMotion, Signal};
use crate::scene::Scene;
pub use error::RequestError;
pub use pga::{parse_pga, DEFAULT_SCAN_POINTS, MAX_RECORDS};
use pointer::{dotted_to_pointer, point_at_named_field};
pub use run::parse_run;
use serde::Deserialize;
use serde_json::Value;
pub use site::{parse_site, MAX_OBSERVATIONS};

/// Limits that protect the server from requests that would exhaust it. Each is a flag of
/// `ashlar serve`; exceeding one is answered with 413 (body size) or 422 naming the field.
#[derive(Debug, Clone, PartialEq)]
pub struct Limits {
    /// Bytes of a request body. 16 MiB holds a 40-minute AT2 record at 200 Hz as text (~5 MB)
    /// three times over, while bounding what one request can make the server buffer.
    pub max_body_bytes: usize,
    /// Blocks in a scene. 5000 covers a large masonry façade; contact detection grows faster
    /// than linearly in the block count, so far beyond that one job would hog a worker for hours.
    pub max_blocks: usize,
    /// Samples in a ground-motion record (both components together). 1 000 000 is 83 minutes at
    /// 200 Hz: every real record fits, a runaway upload does not.
    pub max_record_samples: usize,
    /// Nominal steps of one run, duration / time_step. 2 000 000 is 2000 s at the default 1 ms
    /// step: hours of CPU for a large scene, the most a shared server should give to one run.
    /// The engine's own hard cap (`control.max_steps`) is set to ten times this, leaving room for
    /// the adaptive step's cuts. Recorded frames (duration / output_interval) are held to the
    /// same number, since each one costs memory and output.
    pub max_total_steps: u64,
    /// Vertices of one block. Validation checks every pair of edges for crossings (quadratic),
    /// so an unbounded polygon would let one request stall the server; 1000 is far more than a
    /// masonry unit or an arch voussoir needs.
    pub max_block_vertices: usize,
    /// Coarse scan points of a PGA search (each one a full run).
    pub max_scan_points: usize,
    /// Jobs waiting in the queue (submitted jobs and searches, not a search's own runs);
    /// beyond it submissions get 429 with Retry-After. Checked in the insert's transaction.
    pub max_queued_jobs: u64,
    /// Runs (`POST /v1/jobs`) one token may have waiting in the queue (`--tokens` only; 429
    /// beyond). 1000: a study's batch of runs fits, one user cannot fill the server's queue.
    pub max_queued_jobs_per_token: u64,
    /// PGA searches one token may have waiting in the queue (`--tokens` only; 429 beyond).
    /// 100: each search is tens of runs, so ten times fewer than runs.
    pub max_queued_searches_per_token: u64,
    /// Work of one run, blocks × nominal steps. 1e9 is 200 000 steps (200 s at 1 ms) of a
    /// 5000-block façade or the whole step limit for 500 blocks: minutes to hours of CPU. The
    /// bundled examples and the study scenes need less than 1e7.
    pub max_block_steps: u64,
    /// Output of one run, blocks × recorded frames: what the MCAP and histories grow with
    /// (about 100 bytes each). 2e7 is ~2 GB at most; the examples record under 1e4.
    pub max_block_frames: u64,
    /// Work of one PGA search, runs × blocks × steps (runs: records × (scan points + the
    /// bisections down to the tolerance)). 1e10 is ten single-run budgets.
    pub max_search_block_steps: u64,
    /// JSON values (numbers, strings, objects, …) in a request body, counted while reading:
    /// a parsed value costs 30–100 bytes of memory whatever its text length, so this bounds
    /// what a body can make the server allocate (~200 MB at 2e6). A 1 000 000-sample record
    /// sent as an array fits; longer records go as text (`format`/`content`).
    pub max_json_values: usize,
    /// Wall-clock seconds one job may run before it is stopped and failed (a search counts as
    /// one job). 6 h: far beyond any bundled example (seconds), short of a runaway.
    pub max_job_seconds: u64,
    /// Bytes one job may write to its artifact directory before it is stopped and failed.
    pub max_job_artifact_bytes: u64,
    /// Bytes of all jobs' artifacts under `--data`; beyond it submissions get 507 until jobs
    /// are deleted (`DELETE /v1/jobs/{id}`).
    pub max_artifact_bytes: u64,
    /// Finished jobs are deleted this long after they ended (`--retain-finished`, the
    /// retention policy of docs/service.md); `None`, the default: kept until deleted, since
    /// deleting results is the operator's choice.
    pub retain_finished: Option<std::time::Duration>,
}

impl Default for Limits {
    fn default() -> Self {
        Self {
            max_body_bytes: 16 * 1024 * 1024,
            max_blocks: 5000,
            max_record_samples: 1_000_000,
            max_total_steps: 2_000_000,
            max_block_vertices: 1000,
            max_scan_points: 64,
            max_queued_jobs: 100_000,
            max_queued_jobs_per_token: 1000,
            max_queued_searches_per_token: 100,
            max_block_steps: 1_000_000_000,
            max_block_frames: 20_000_000,
            max_search_block_steps: 10_000_000_000,
            max_json_values: 2_000_000,
            max_job_seconds: 6 * 3600,
            max_job_artifact_bytes: 4 << 30,
            max_artifact_bytes: 50 << 30,
            retain_finished: None,
        }
    }
}

/// A validated job, ready for a runner.
#[derive(Debug, Clone)]
pub enum JobInput {
    Run {
        scene: Scene,
        motion: GroundMotion,
        /// Damage criteria judged on the finished run's summary (`"criterion"`, optional).
        criteria: Vec<Criterion>,
    },
    PgaSearch {
        scene: Scene,
        motion: GroundMotion,
        request: PgaRequest,
        criterion: String,
        /// A multi-record search (`"motions"`): each record's name and motion, and the
        /// fragility fit. Empty for a single-record search (then `motion` is the record; with
        /// several, `motion` is the first).
        records: Vec<(String, GroundMotion)>,
        fit: Method,
    },
    /// Several observations at one site over a set of records (`POST /v1/site-analyses`,
    /// `analysis::observations`).
    SiteAnalysis {
        scene: Scene,
        /// The first record (what `motion()` answers).
        motion: GroundMotion,
        records: Vec<(String, GroundMotion)>,
        observations: Vec<crate::analysis::observations::Observation>,
        /// The searched range, tolerance and scan points (its criteria are empty: each
        /// observation's search takes its own).
        request: PgaRequest,
    },
}

impl JobInput {
    pub fn scene(&self) -> &Scene {
        match self {
            JobInput::Run { scene, .. }
            | JobInput::PgaSearch { scene, .. }
            | JobInput::SiteAnalysis { scene, .. } => scene,
        }
    }
    pub fn motion(&self) -> &GroundMotion {
        match self {
            JobInput::Run { motion, .. }
            | JobInput::PgaSearch { motion, .. }
            | JobInput::SiteAnalysis { motion, .. } => motion,
        }
    }
}

/// A parsed submission: the input, and the motion's intensity summary reported with the job.
#[derive(Debug, Clone)]
pub struct Parsed {
    pub input: JobInput,
    pub motion_summary: Value,
}

/// Parse body bytes as JSON (syntax errors name line and column).
pub fn json_body(bytes: &[u8]) -> Result<Value, RequestError> {
    if bytes.iter().all(|b| b.is_ascii_whitespace()) {
        return Err(RequestError::EmptyBody);
    }
    serde_json::from_slice(bytes).map_err(RequestError::Syntax)
}

/// Deserialize a typed body part, turning serde's message into a problem naming the field.
pub(super) fn typed<T: for<'de> Deserialize<'de>>(
    prefix: &str,
    value: &Value,
) -> Result<T, RequestError> {
    serde_path_to_error::deserialize(value).map_err(|e| {
        let path = e.path().to_string();
        let source = e.into_inner();
        let pointer = point_at_named_field(dotted_to_pointer(prefix, &path), &source.to_string());
        RequestError::Field { pointer, source }
    })
}

/// Criteria of a request at JSON pointer `pointer`: a string (`toppled:B`, …), a damage object
/// (docs/format.md §3), or a non-empty array of them. Each comes back with its text form (the
/// compact JSON for an object). Every block named by any criterion that is not a free block of
/// the scene is reported at once, in one 422, so a user fixes them in one go.
pub fn parse_criteria(
    spec: &Value,
    pointer: &str,
    scene: &Scene,
) -> Result<Vec<(String, Criterion)>, RequestError> {
    let items: Vec<(String, &Value)> = match spec {
        Value::Array(v) => v
            .iter()
            .enumerate()
            .map(|(i, x)| (format!("{pointer}/{i}"), x))
            .collect(),
        other => vec![(pointer.to_string(), other)],
    };
    if items.is_empty() {
        return Err(RequestError::NoCriterion {
            pointer: pointer.to_string(),
        });
    }
    let mut out = Vec::new();
    for (p, item) in &items {
        let c = match item {
            Value::String(t) => Criterion::parse(t)
                .map_err(|source| RequestError::Criterion {
                    pointer: p.clone(),
                    source,
                })
                .map(|c| (t.clone(), c))?,
            Value::Object(_) => {
                let damage: crate::analysis::criteria::Damage = typed(p, item)?;
                let c = Criterion::Damage { damage };
                (c.text(), c)
            }
            _ => return Err(RequestError::CriterionType { pointer: p.clone() }),
        };
        out.push((p.clone(), c));
    }
    let mut missing = Vec::new();
    for (p, (_, c)) in &out {
        for id in c.blocks() {
            let free = scene
                .block_index(id)
                .is_some_and(|i| matches!(scene.blocks[i].kind, crate::scene::BlockKind::Free(_)));
            if !free
                && !missing
                    .iter()
                    .any(|(q, b): &(String, String)| q == p && b == id)
            {
                missing.push((p.clone(), id.to_string()));
            }
        }
    }
    if !missing.is_empty() {
        return Err(RequestError::NotFreeBlocks { missing });
    }
    for (p, (_, c)) in &out {
        if let Criterion::Damage { damage } = c {
            damage.check(scene).map_err(|source| RequestError::Damage {
                pointer: p.clone(),
                source,
            })?;
        }
    }
    Ok(out.into_iter().map(|(_, tc)| tc).collect())
}

/// Shape checks before any work: a `base_acceleration` excitation takes no other field (the
/// scene reader leaves that out), and the motion reads as a [`crate::motion::MotionSpec`],
/// which is returned (`None`: no motion) so that it is built without being parsed again.
pub(super) fn check_shapes(
    scene: &Value,
    motion: Option<&Value>,
) -> Result<Option<crate::motion::MotionSpec>, RequestError> {
    if let Some(ex) = scene.get("excitation").and_then(Value::as_object) {
        let allowed: &[&str] = match ex.get("type").and_then(Value::as_str) {
            Some("driven_block") => &["type", "block"],
            _ => &["type"],
        };
        if let Some(k) = ex.keys().find(|k| !allowed.contains(&k.as_str())) {
            return Err(RequestError::ExcitationField {
                pointer: format!("/scene/excitation/{k}"),
            });
        }
    }
    // The motion's shape is its type: members of another form, nulls and `processing` (a
    // command-line extension) are refused by reading it as a `MotionSpec`.
    if let Some(m) = motion.filter(|m| !m.is_null()) {
        let spec = crate::motion::MotionSpec::from_value(m).map_err(motion_error)?;
        for (name, c) in spec.components() {
            if let Some(e) = c.processing_refused(&format!("motion.{name}")) {
                return Err(motion_error(e));
            }
        }
        return Ok(Some(spec));
    }
    Ok(None)
}

/// Sizes checked on the raw JSON, before any work proportional to them: vertices per block,
/// and the length of analytic pulses (counted as 20 samples a cycle against the record limit,
/// since evaluating a pulse's peak walks its cycles).
pub(super) fn check_sizes(
    scene: &Value,
    motion: Option<&Value>,
    limits: &Limits,
) -> Result<(), RequestError> {
    let blocks = scene
        .get("blocks")
        .and_then(Value::as_array)
        .map(Vec::as_slice)
        .unwrap_or_default();
    for (i, b) in blocks.iter().enumerate() {
        let n = b
            .get("vertices")
            .and_then(Value::as_array)
            .map(Vec::len)
            .unwrap_or(0);
        if n > limits.max_block_vertices {
            return Err(RequestError::Vertices {
                block: i,
                count: n,
                limit: limits.max_block_vertices,
            });
        }
    }
    for name in ["horizontal", "vertical"] {
        let cycles = motion
            .and_then(|m| m.get(name))
            .and_then(|c| c.get("pulse"))
            .and_then(|p| p.get("cycles"))
            .and_then(Value::as_f64)
            .unwrap_or(0.0);
        if cycles * 20.0 > limits.max_record_samples as f64 {
            return Err(RequestError::PulseCycles {
                component: name,
                cycles,
                limit: limits.max_record_samples / 20,
            });
        }
    }
    Ok(())
}

/// A motion error pointing into the body (`motion.horizontal.dt` → `/motion/horizontal/dt`).
pub(super) fn motion_error(source: crate::motion::MotionError) -> RequestError {
    RequestError::Motion {
        pointer: point_at_named_field(dotted_to_pointer("", &source.origin), &source.message),
        source,
    }
}

pub(super) fn scene_and_motion(
    scene: &Value,
    motion: Option<&Value>,
    limits: &Limits,
) -> Result<(Scene, GroundMotion), RequestError> {
    let spec = check_shapes(scene, motion)?;
    check_sizes(scene, motion, limits)?;
    super::budget::check_ranges(scene)?;
    if let Some(m) = motion {
        super::budget::check_motion_ranges("/motion", m)?;
    }
    if let Some(n) = scene.get("blocks").and_then(Value::as_array).map(Vec::len) {
        if n > limits.max_blocks {
            return Err(RequestError::Blocks {
                count: n,
                limit: limits.max_blocks,
            });
        }
    }
    let mut scene = crate::scene::scene_from_value(scene).map_err(|source| {
        let pointer =
            point_at_named_field(dotted_to_pointer("/scene", &source.path), &source.message);
        RequestError::Scene { pointer, source }
    })?;
    // A forced reduced model the scene cannot take is refused now, not failed later by a worker.
    crate::analysis::run::choose_model(&scene, &Default::default()).map_err(RequestError::Model)?;
    let motion = match spec {
        None => GroundMotion::none(),
        Some(spec) => spec
            .build(&crate::motion::ProcessParams::default())
            .map_err(motion_error)?,
    };
    let samples = signal_samples(&motion.horizontal) + signal_samples(&motion.vertical);
    if samples > limits.max_record_samples {
        return Err(RequestError::RecordSamples {
            samples,
            limit: limits.max_record_samples,
        });
    }
    let duration =
        crate::analysis::run::duration(&scene, &motion).map_err(|_| RequestError::NoDuration)?;
    let steps = (duration / scene.control.time_step).ceil();
    if steps.is_nan() || steps > limits.max_total_steps as f64 {
        return Err(RequestError::Steps {
            duration,
            time_step: scene.control.time_step,
            steps,
            limit: limits.max_total_steps,
        });
    }
    let frames = (duration / scene.control.output_interval).ceil();
    if frames.is_nan() || frames > limits.max_total_steps as f64 {
        return Err(RequestError::Frames {
            duration,
            output_interval: scene.control.output_interval,
            frames,
            limit: limits.max_total_steps,
        });
    }
    super::budget::check_run_work(scene.blocks.len(), steps, frames, limits)?;
    scene.control.max_steps = scene
        .control
        .max_steps
        .min(limits.max_total_steps.saturating_mul(10));
    Ok((scene, motion))
}

pub(super) fn signal_samples(s: &Signal) -> usize {
    match s {
        Signal::Sampled(x) => x.accel.len(),
        _ => 0,
    }
}

/// The intensity summary reported with a job: peak horizontal acceleration after scaling (m/s²),
/// record length (s, null for steady or no motion), samples, provenance.
pub fn motion_summary(m: &GroundMotion) -> Value {
    let npts = signal_samples(&m.horizontal);
    let dt = match &m.horizontal {
        Signal::Sampled(s) => Some(s.dt),
        _ => None,
    };
    serde_json::json!({
        "pga": m.pga(),
        "pga_units": "m/s2",
        "duration": m.duration(),
        "npts": if npts > 0 { Some(npts) } else { None },
        "dt": dt,
        "scale": m.scale,
        "has_vertical": !matches!(m.vertical, Signal::Zero),
        "provenance": m.provenance,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use serde_json::json;

    fn scene() -> Value {
        json!({
            "format": "ashlar.scene/1",
            "materials": {"stone": {"density": 2500, "young_modulus": 2e10, "poisson_ratio": 0.2}},
            "joints": {"dry": {"friction_angle": 40}},
            "blocks": [
                {"id": "base", "material": "stone", "fixed": true, "vertices": [[-1,-0.5],[1,-0.5],[1,0],[-1,0]]},
                {"id": "col", "material": "stone", "vertices": [[-0.2,0],[0.2,0],[0.2,1.2],[-0.2,1.2]]}
            ],
            "control": {"duration": 1.0}
        })
    }

    fn pointer_of(r: Result<Parsed, RequestError>) -> String {
        match r {
            Ok(_) => panic!("expected an error"),
            Err(e) => e.pointer().unwrap_or_else(|| "<none>".into()),
        }
    }

    #[test]
    fn errors_point_at_the_field() {
        let l = Limits::default();
        assert_eq!(
            pointer_of(parse_run(&json!({"motion": null}), &l)),
            "/scene"
        );
        assert_eq!(
            pointer_of(parse_run(&json!({"scene": scene(), "extra": 1}), &l)),
            "/extra"
        );
        let mut s = scene();
        s["blocks"][1]["vertices"] = json!([[0, 0], [1, 0]]);
        assert_eq!(
            pointer_of(parse_run(&json!({"scene": s}), &l)),
            "/scene/blocks/1/vertices"
        );
        let mut s = scene();
        s["materials"]["stone"]["density"] = json!("heavy");
        assert_eq!(
            pointer_of(parse_run(&json!({"scene": s}), &l)),
            "/scene/materials/stone/density"
        );
        // The range check (docs/format.md "Ranges") names the member itself.
        let m = json!({"horizontal": {"pulse": {"amplitude": 1, "period": -1}}});
        assert_eq!(
            pointer_of(parse_run(&json!({"scene": scene(), "motion": m}), &l)),
            "/motion/horizontal/pulse/period"
        );
    }

    #[test]
    fn a_pga_search_takes_its_scan_and_a_wrong_one_names_the_field() {
        let l = Limits::default();
        let body = |scan: Value| {
            json!({"scene": scene(), "motion": {"horizontal": {"pulse": {"amplitude": 1, "period": 1}}},
                   "criterion": "toppled:col", "range": {"min": 1, "max": 9}, "scan": scan})
        };
        let scan_of = |b: Value| match parse_pga(&b, &l).expect("parses").input {
            JobInput::PgaSearch { request, .. } => request.scan,
            _ => panic!("a search"),
        };
        use crate::analysis::pga::ScanOrder;
        assert_eq!(scan_of(body(Value::Null)), ScanOrder::Full);
        assert_eq!(scan_of(body(json!("full"))), ScanOrder::Full);
        assert_eq!(scan_of(body(json!("lowest"))), ScanOrder::Lowest);
        assert_eq!(pointer_of(parse_pga(&body(json!("upward")), &l)), "/scan");
    }

    #[test]
    fn limits_name_the_field() {
        let l = Limits {
            max_total_steps: 999,
            ..Limits::default()
        };
        // 1 s at 1 ms = 1000 steps > 999.
        let e = parse_run(&json!({"scene": scene()}), &l).expect_err("over the step limit");
        assert!(matches!(e, RequestError::Steps { .. }), "{e}");
        assert_eq!(e.pointer().as_deref(), Some("/scene/control/duration"));
        assert!(parse_run(
            &json!({"scene": scene()}),
            &Limits {
                max_total_steps: 1000,
                ..l.clone()
            }
        )
        .is_ok());
        let l = Limits {
            max_blocks: 1,
            ..Limits::default()
        };
        assert_eq!(
            pointer_of(parse_run(&json!({"scene": scene()}), &l)),
            "/scene/blocks"
        );
        let l = Limits {
            max_block_vertices: 3,
            ..Limits::default()
        };
        assert_eq!(
            pointer_of(parse_run(&json!({"scene": scene()}), &l)),
            "/scene/blocks/0/vertices"
        );
        let m = json!({"horizontal": {"pulse": {"amplitude": 1, "period": 0.1, "cycles": 1.0e12}}});
        let e = parse_run(&json!({"scene": scene(), "motion": m}), &Limits::default())
            .expect_err("a 1e12-cycle pulse");
        assert_eq!(
            e.pointer().as_deref(),
            Some("/motion/horizontal/pulse/cycles")
        );
        let l = Limits {
            max_record_samples: 3,
            ..Limits::default()
        };
        let m = json!({"horizontal": {"samples": [0, 1, 0, 1], "dt": 0.01}});
        assert_eq!(
            pointer_of(parse_run(&json!({"scene": scene(), "motion": m}), &l)),
            "/motion"
        );
    }

    #[test]
    fn pga_search_converts_units_and_checks_the_criterion() {
        let l = Limits::default();
        let m = json!({"horizontal": {"pulse": {"amplitude": 1, "period": 0.5, "units": "m/s2"}}});
        let body = json!({"scene": scene(), "motion": m, "criterion": "toppled:col",
                          "range": {"min": 0.1, "max": 1.0, "units": "g"}, "tolerance": 0.01});
        let p = parse_pga(&body, &l).expect("valid");
        let JobInput::PgaSearch { request, .. } = p.input else {
            panic!("kind")
        };
        // g → m/s² with the standard gravity, exactly.
        assert_eq!(request.max, 9.80665);
        assert_eq!(request.tolerance, 0.0980665);
        let mut bad = body.clone();
        bad["criterion"] = json!("toppled:base");
        assert_eq!(pointer_of(parse_pga(&bad, &l)), "/criterion");
        let mut bad = body.clone();
        bad["range"]["max"] = json!(0.05);
        assert_eq!(pointer_of(parse_pga(&bad, &l)), "/range/max");
        // Strings carry their own units (the range's `units` applies to numbers only): the same
        // request written as strings gives the same amplitudes, exactly.
        let mut text = body.clone();
        text["range"] = json!({"min": "0.1g", "max": "9.80665m/s2"});
        text["tolerance"] = json!("0.01 G");
        let JobInput::PgaSearch { request: r2, .. } = parse_pga(&text, &l).expect("valid").input
        else {
            panic!("kind")
        };
        assert_eq!(
            (r2.min, r2.max, r2.tolerance),
            (request.min, request.max, request.tolerance)
        );
        // A string without units is refused, naming the field and both readings.
        for (field, pointer) in [("min", "/range/min"), ("max", "/range/max")] {
            let mut bad = text.clone();
            bad["range"][field] = json!("0.5");
            let e = parse_pga(&bad, &l).expect_err("bare string").to_string();
            assert!(e.starts_with(pointer), "{e}");
            assert!(e.contains("0.5g") && e.contains("0.5m/s2"), "{e}");
        }
        let mut bad = text.clone();
        bad["tolerance"] = json!("0.01");
        assert_eq!(pointer_of(parse_pga(&bad, &l)), "/tolerance");
        let mut bad = text.clone();
        bad["range"]["min"] = json!("1 furlong");
        assert_eq!(pointer_of(parse_pga(&bad, &l)), "/range/min");
        // The motion's target PGA takes the same forms; a bare string is refused there too.
        let scaled = |t: Value| {
            json!({"scene": scene(), "motion": {"horizontal": {"pulse": {"amplitude": 1, "period": 0.5, "units": "m/s2"}},
                   "scale": {"target_pga": t}}})
        };
        let p = parse_run(&scaled(json!("0.5g")), &l).expect("valid");
        assert_eq!(p.motion_summary["pga"].as_f64(), Some(0.5 * 9.80665));
        let p = parse_run(&scaled(json!(2.5)), &l).expect("valid, m/s2 by default");
        assert_eq!(p.motion_summary["pga"].as_f64(), Some(2.5));
        let e = parse_run(&scaled(json!("0.5")), &l).expect_err("bare string");
        assert!(e.to_string().contains("has no units"), "{e}");
        assert_eq!(e.pointer().as_deref(), Some("/motion/scale/target_pga"));
        let mut bad = body;
        bad["criterion"] = json!(["toppled:col", "rotation:col:x"]);
        assert_eq!(pointer_of(parse_pga(&bad, &l)), "/criterion/1");
    }

    #[test]
    fn duration_is_required_without_a_record() {
        let mut s = scene();
        s["control"] = json!({});
        assert_eq!(
            pointer_of(parse_run(&json!({"scene": s}), &Limits::default())),
            "/scene/control/duration"
        );
    }
}
