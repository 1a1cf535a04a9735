//! Service: what one submission may cost, checked before it is queued. Sits between the routes
//! (which read the body) and `request` (which parses it): a streaming pre-scan of the JSON text
//! refuses oversized scenes before a `serde_json::Value` is built, physical values outside their
//! documented ranges are refused with their JSON pointer, and the work estimate of a run
//! (blocks × steps, blocks × recorded frames) or of a search (runs × blocks × steps) is held to
//! the server's limits (`ashlar serve --max-*`, reported by `GET /v1/limits`).
use super::Limits;
use super::RequestError;
use serde::de::{DeserializeSeed, Deserializer, MapAccess, SeqAccess, Visitor};
use serde_json::Value;
use std::cell::{Cell, RefCell};
use std::fmt;

/// Where the pre-scan is in the document (only the places with a limit are told apart).
#[derive(Clone, Copy, PartialEq)]
enum At {
    Root,
    Scene,
    Blocks,
    Motions,
    Other,
}

struct Scan<'a> {
    at: At,
    values: &'a Cell<usize>,
    limits: &'a Limits,
    refusal: &'a RefCell<Option<RequestError>>,
}

impl Scan<'_> {
    fn child(&self, at: At) -> Self {
        Scan {
            at,
            values: self.values,
            limits: self.limits,
            refusal: self.refusal,
        }
    }
    fn count<E: serde::de::Error>(&self) -> Result<(), E> {
        let n = self.values.get() + 1;
        self.values.set(n);
        if n > self.limits.max_json_values {
            return Err(self.refuse(RequestError::JsonValues {
                limit: self.limits.max_json_values,
            }));
        }
        Ok(())
    }
    fn refuse<E: serde::de::Error>(&self, e: RequestError) -> E {
        let msg = e.to_string();
        *self.refusal.borrow_mut() = Some(e);
        E::custom(msg)
    }
}

impl<'de> DeserializeSeed<'de> for Scan<'_> {
    type Value = ();
    fn deserialize<D: Deserializer<'de>>(self, d: D) -> Result<(), D::Error> {
        d.deserialize_any(self)
    }
}

impl<'de> Visitor<'de> for Scan<'_> {
    type Value = ();
    fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
        f.write_str("any JSON value")
    }
    fn visit_bool<E: serde::de::Error>(self, _: bool) -> Result<(), E> {
        self.count()
    }
    fn visit_i64<E: serde::de::Error>(self, _: i64) -> Result<(), E> {
        self.count()
    }
    fn visit_u64<E: serde::de::Error>(self, _: u64) -> Result<(), E> {
        self.count()
    }
    fn visit_f64<E: serde::de::Error>(self, _: f64) -> Result<(), E> {
        self.count()
    }
    fn visit_str<E: serde::de::Error>(self, _: &str) -> Result<(), E> {
        self.count()
    }
    fn visit_unit<E: serde::de::Error>(self) -> Result<(), E> {
        self.count()
    }
    fn visit_seq<A: SeqAccess<'de>>(self, mut seq: A) -> Result<(), A::Error> {
        self.count()?;
        let mut n = 0usize;
        while seq.next_element_seed(self.child(At::Other))?.is_some() {
            n += 1;
            if self.at == At::Blocks && n > self.limits.max_blocks {
                return Err(self.refuse(RequestError::BlocksWhileReading {
                    limit: self.limits.max_blocks,
                }));
            }
            if self.at == At::Motions && n > super::MAX_RECORDS {
                return Err(self.refuse(RequestError::RecordsWhileReading));
            }
        }
        Ok(())
    }
    fn visit_map<A: MapAccess<'de>>(self, mut map: A) -> Result<(), A::Error> {
        self.count()?;
        while let Some(key) = map.next_key::<std::borrow::Cow<'de, str>>()? {
            let at = match (self.at, key.as_ref()) {
                (At::Root, "scene") => At::Scene,
                (At::Root, "motions") => At::Motions,
                (At::Scene, "blocks") => At::Blocks,
                _ => At::Other,
            };
            map.next_value_seed(self.child(at))?;
        }
        Ok(())
    }
}

/// Walk the body's JSON text without building it, refusing (422, with the pointer) a document
/// with more values than `--max-json-values` or more blocks than `--max-blocks` as soon as the
/// reader gets there: memory stays proportional to the limits, not to what was sent. Syntax
/// errors are left to the parser proper, which names line and column.
pub fn prescan(bytes: &[u8], limits: &Limits) -> Result<(), RequestError> {
    let values = Cell::new(0);
    let refusal = RefCell::new(None);
    let mut de = serde_json::Deserializer::from_slice(bytes);
    let scan = Scan {
        at: At::Root,
        values: &values,
        limits,
        refusal: &refusal,
    };
    let r = scan.deserialize(&mut de);
    match (r, refusal.into_inner()) {
        (_, Some(e)) => Err(e),
        _ => Ok(()),
    }
}

/// A number for a message: significant digits, in exponent form when very large or small
/// (`1e308`, not the 309 digits `quantity::sig` would print).
pub fn num(x: f64) -> String {
    if x != 0.0 && x.is_finite() && !(1e-4..1e7).contains(&x.abs()) {
        let t = format!("{x:.3e}");
        // 1.000e308 → 1e308, 2.500e10 → 2.5e10
        match t.split_once('e') {
            Some((m, e)) => {
                let m = m.trim_end_matches('0').trim_end_matches('.');
                format!("{m}e{e}")
            }
            None => t,
        }
    } else {
        crate::quantity::sig(x)
    }
}

/// A documented range of a physical value (inclusive), with its units.
struct Range {
    min: f64,
    max: f64,
    units: &'static str,
}

const fn range(min: f64, max: f64, units: &'static str) -> Range {
    Range { min, max, units }
}

/// Physical ranges a scene's values must lie in (docs/format.md "Ranges", openapi.yaml
/// `minimum`/`maximum`). Wide enough for any material or motion of a real structure, narrow
/// enough that no product of them overflows a double in the engine: 1e308 used to pass
/// submission and fail the run with "linear solve failed … non-finite".
pub const DENSITY: (f64, f64) = (1.0, 1.0e5); // kg/m³: lighter than any solid … beyond osmium
pub const YOUNG_MODULUS: (f64, f64) = (1.0e3, 1.0e13); // Pa: soft rubber … beyond diamond
pub const GRAVITY: (f64, f64) = (0.0, 100.0); // m/s²: none … 10 g
pub const PENALTY: (f64, f64) = (1.0, 1.0e16); // N/m
pub const VELOCITY: (f64, f64) = (-1.0e3, 1.0e3); // m/s, each component
pub const ANGULAR_VELOCITY: (f64, f64) = (-1.0e3, 1.0e3); // rad/s
pub const DURATION: (f64, f64) = (1.0e-6, 1.0e6); // s (11.6 days)
pub const TIME_STEP: (f64, f64) = (1.0e-9, 10.0); // s
pub const OUTPUT_INTERVAL: (f64, f64) = (1.0e-9, 1.0e6); // s
pub const COORDINATE: (f64, f64) = (-1.0e6, 1.0e6); // m, each vertex coordinate
pub const COHESION: (f64, f64) = (0.0, 1.0e10); // Pa, cohesion and tensile strength
/// Ground acceleration, m/s², each record sample and a pulse's or sine's amplitude (in its own
/// units, converted): the motion reader's largest accepted peak (`motion::json::MAX_PGA`,
/// ~10⁵ g), so that a value refused later is refused here with its pointer instead.
pub const GROUND_ACCELERATION: (f64, f64) = (-1.0e6, 1.0e6);
/// A record's sample interval, s: > 0; 1 µs … 10 s spans every instrument (100–1000 Hz) and
/// any decimated record, and keeps the samples per second of a run bounded.
pub const RECORD_DT: (f64, f64) = (1.0e-6, 10.0);
/// A sine's frequency, Hz: 1 mHz … 1 kHz (ground shaking that moves a structure is 0.1–30 Hz).
pub const FREQUENCY: (f64, f64) = (1.0e-3, 1.0e3);
/// A pulse's period, s: the reciprocal of [`FREQUENCY`].
pub const PERIOD: (f64, f64) = (1.0e-3, 1.0e3);
/// A pulse's phase, rad: finite and a few hundred turns at most.
pub const PHASE: (f64, f64) = (-1.0e3, 1.0e3);

/// The ranges as `GET /v1/limits` reports them: `{"<field>": {"min", "max", "units"}}`.
pub fn ranges_json() -> Value {
    let r = |(min, max): (f64, f64), units: &str| serde_json::json!({"min": min, "max": max, "units": units});
    serde_json::json!({
        "materials.density": r(DENSITY, "kg/m3"),
        "materials.young_modulus": r(YOUNG_MODULUS, "Pa"),
        "gravity": r(GRAVITY, "m/s2"),
        "control.penalty_stiffness": r(PENALTY, "N/m"),
        "initial.velocity": r(VELOCITY, "m/s"),
        "initial.angular_velocity": r(ANGULAR_VELOCITY, "rad/s"),
        "control.duration": r(DURATION, "s"),
        "control.time_step": r(TIME_STEP, "s"),
        "control.output_interval": r(OUTPUT_INTERVAL, "s"),
        "blocks.vertices": r(COORDINATE, "m"),
        "joints.cohesion": r(COHESION, "Pa"),
        "joints.tensile_strength": r(COHESION, "Pa"),
        "motion.samples": r(GROUND_ACCELERATION, "m/s2"),
        "motion.dt": r(RECORD_DT, "s"),
        "motion.pulse.amplitude": r(GROUND_ACCELERATION, "m/s2"),
        "motion.pulse.period": r(PERIOD, "s"),
        "motion.pulse.phase": r(PHASE, "rad"),
        "motion.sine.amplitude": r(GROUND_ACCELERATION, "m/s2"),
        "motion.sine.frequency": r(FREQUENCY, "Hz"),
    })
}

/// m/s² per unit of a motion component's `units` (default g); `None` for an unknown name (the
/// motion reader names that error).
fn accel_units(v: Option<&Value>) -> Option<(f64, &'static str)> {
    match v.and_then(Value::as_str) {
        None | Some("g") => Some((crate::motion::STANDARD_GRAVITY, "g")),
        Some("m/s2") => Some((1.0, "m/s²")),
        Some("cm/s2") | Some("gal") => Some((0.01, "cm/s²")),
        Some(_) => None,
    }
}

/// An acceleration `x` given in `units`, against [`GROUND_ACCELERATION`] (in m/s²).
fn check_accel(pointer: String, v: &Value, units: Option<&Value>) -> Result<(), RequestError> {
    let (Some(x), Some((k, name))) = (v.as_f64(), accel_units(units)) else {
        return Ok(());
    };
    let (lo, hi) = GROUND_ACCELERATION;
    if x.is_finite() && (lo..=hi).contains(&(x * k)) {
        return Ok(());
    }
    Err(RequestError::AccelerationOutOfRange {
        pointer,
        value: x,
        units: name,
    })
}

/// Refuse motion values outside their documented ranges, before the motion is read: a sample
/// list's samples (the pointer names the sample's index) and `dt`, a pulse's amplitude, period
/// and phase, a sine's amplitude and frequency. `base` is the motion's pointer (`/motion`).
pub fn check_motion_ranges(base: &str, motion: &Value) -> Result<(), RequestError> {
    let r = |(min, max): (f64, f64), units| range(min, max, units);
    for name in ["horizontal", "vertical"] {
        let Some(c) = motion.get(name).filter(|c| c.is_object()) else {
            continue;
        };
        let p = format!("{base}/{name}");
        if let Some(samples) = c.get("samples").and_then(Value::as_array) {
            let k = accel_units(c.get("units")).map_or(1.0, |(k, _)| k);
            let (lo, hi) = GROUND_ACCELERATION;
            // The pointer is only built for the sample refused (a record has up to 10⁶).
            if let Some(i) = samples.iter().position(|x| {
                x.as_f64()
                    .is_some_and(|x| !(x.is_finite() && (lo..=hi).contains(&(x * k))))
            }) {
                check_accel(format!("{p}/samples/{i}"), &samples[i], c.get("units"))?;
            }
        }
        if let Some(dt) = c.get("dt") {
            check(format!("{p}/dt"), dt, r(RECORD_DT, "s"))?;
        }
        if let Some(pulse) = c.get("pulse").filter(|v| v.is_object()) {
            if let Some(a) = pulse.get("amplitude") {
                check_accel(format!("{p}/pulse/amplitude"), a, pulse.get("units"))?;
            }
            if let Some(t) = pulse.get("period") {
                check(format!("{p}/pulse/period"), t, r(PERIOD, "s"))?;
            }
            if let Some(f) = pulse.get("phase") {
                check(format!("{p}/pulse/phase"), f, r(PHASE, "rad"))?;
            }
        }
        if let Some(sine) = c.get("sine").filter(|v| v.is_object()) {
            if let Some(a) = sine.get("amplitude") {
                check_accel(format!("{p}/sine/amplitude"), a, sine.get("units"))?;
            }
            if let Some(f) = sine.get("frequency") {
                check(format!("{p}/sine/frequency"), f, r(FREQUENCY, "Hz"))?;
            }
        }
    }
    Ok(())
}

fn check(pointer: String, v: &Value, r: Range) -> Result<(), RequestError> {
    let Some(x) = v.as_f64() else {
        return Ok(()); // not a number: the scene reader names the type error
    };
    if x.is_finite() && x >= r.min && x <= r.max {
        return Ok(());
    }
    Err(RequestError::OutOfRange {
        pointer,
        value: x,
        min: r.min,
        max: r.max,
        units: r.units,
    })
}

fn esc(key: &str) -> String {
    key.replace('~', "~0").replace('/', "~1")
}

/// Refuse physical values outside their documented ranges, naming the first one by pointer.
pub fn check_ranges(scene: &Value) -> Result<(), RequestError> {
    let r = |(min, max): (f64, f64), units| range(min, max, units);
    if let Some(g) = scene.get("gravity") {
        check("/scene/gravity".into(), g, r(GRAVITY, "m/s²"))?;
    }
    if let Some(ms) = scene.get("materials").and_then(Value::as_object) {
        for (name, m) in ms {
            let p = format!("/scene/materials/{}", esc(name));
            if let Some(v) = m.get("density") {
                check(format!("{p}/density"), v, r(DENSITY, "kg/m³"))?;
            }
            if let Some(v) = m.get("young_modulus") {
                check(format!("{p}/young_modulus"), v, r(YOUNG_MODULUS, "Pa"))?;
            }
        }
    }
    if let Some(js) = scene.get("joints").and_then(Value::as_object) {
        for (name, j) in js {
            let p = format!("/scene/joints/{}", esc(name));
            for k in ["cohesion", "tensile_strength"] {
                if let Some(v) = j.get(k) {
                    check(format!("{p}/{k}"), v, r(COHESION, "Pa"))?;
                }
            }
        }
    }
    if let Some(bs) = scene.get("blocks").and_then(Value::as_array) {
        for (i, b) in bs.iter().enumerate() {
            let Some(vs) = b.get("vertices").and_then(Value::as_array) else {
                continue;
            };
            for (k, v) in vs.iter().enumerate() {
                for (c, x) in v.as_array().into_iter().flatten().enumerate() {
                    check(
                        format!("/scene/blocks/{i}/vertices/{k}/{c}"),
                        x,
                        r(COORDINATE, "m"),
                    )?;
                }
            }
        }
    }
    if let Some(is) = scene.get("initial").and_then(Value::as_array) {
        for (i, s) in is.iter().enumerate() {
            for (c, x) in s
                .get("velocity")
                .and_then(Value::as_array)
                .into_iter()
                .flatten()
                .enumerate()
            {
                check(
                    format!("/scene/initial/{i}/velocity/{c}"),
                    x,
                    r(VELOCITY, "m/s"),
                )?;
            }
            if let Some(w) = s.get("angular_velocity") {
                check(
                    format!("/scene/initial/{i}/angular_velocity"),
                    w,
                    r(ANGULAR_VELOCITY, "rad/s"),
                )?;
            }
        }
    }
    if let Some(c) = scene.get("control") {
        for (k, rg, u) in [
            ("duration", DURATION, "s"),
            ("time_step", TIME_STEP, "s"),
            ("output_interval", OUTPUT_INTERVAL, "s"),
            ("penalty_stiffness", PENALTY, "N/m"),
        ] {
            if let Some(v) = c.get(k) {
                check(format!("/scene/control/{k}"), v, r(rg, u))?;
            }
        }
    }
    Ok(())
}

/// The work of one run: blocks × nominal steps must stay within `--max-block-steps`, and
/// blocks × recorded frames (what the artifacts grow with) within `--max-block-frames`.
pub fn check_run_work(
    blocks: usize,
    steps: f64,
    frames: f64,
    limits: &Limits,
) -> Result<(), RequestError> {
    if blocks as f64 * steps > limits.max_block_steps as f64 {
        return Err(RequestError::RunWork {
            blocks,
            steps,
            limit: limits.max_block_steps,
        });
    }
    if blocks as f64 * frames > limits.max_block_frames as f64 {
        return Err(RequestError::RunOutput {
            blocks,
            frames,
            limit: limits.max_block_frames,
        });
    }
    Ok(())
}

/// Runs a PGA search makes on one core: per record, the scan of its lattice and the k-section
/// of one lattice cell down to the tolerance (k − 1 runs a level; the runs evaluated ahead on
/// more cores are not counted, as before).
pub fn search_runs(records: usize, request: &crate::analysis::pga::PgaRequest) -> f64 {
    use crate::analysis::pga::{Lattice, SECTIONS};
    let lattice = Lattice::of(request);
    let refinement = f64::from(lattice.levels) * (SECTIONS - 1) as f64;
    records.max(1) as f64 * (lattice.points() as f64 + refinement)
}

/// The work of a search: runs × blocks × steps within `--max-search-block-steps`.
pub fn check_search_work(
    runs: f64,
    blocks: usize,
    steps: f64,
    limits: &Limits,
) -> Result<(), RequestError> {
    if runs * blocks as f64 * steps > limits.max_search_block_steps as f64 {
        return Err(RequestError::SearchWork {
            runs,
            blocks,
            steps,
            limit: limits.max_search_block_steps,
        });
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use serde_json::json;

    #[test]
    fn prescan_refuses_too_many_blocks_and_values_while_reading() {
        let l = Limits {
            max_blocks: 3,
            max_json_values: 100,
            ..Limits::default()
        };
        let ok = br#"{"scene": {"blocks": [1, 2, 3]}, "motion": {"blocks": [1,2,3,4]}}"#;
        assert!(prescan(ok, &l).is_ok());
        let four = br#"{"scene": {"blocks": [1, 2, 3, 4]}}"#;
        let e = prescan(four, &l).expect_err("4 blocks > 3");
        assert_eq!(e.pointer().as_deref(), Some("/scene/blocks"));
        let many = format!("[{}0]", "0,".repeat(100));
        let e = prescan(many.as_bytes(), &l).expect_err("101 values > 100");
        assert!(matches!(e, RequestError::JsonValues { limit: 100 }), "{e}");
        // Syntax errors are left to the parser (which names line and column).
        assert!(prescan(b"{\"scene\": [", &l).is_ok());
    }

    #[test]
    fn ranges_name_the_value() {
        let mut s = json!({"materials": {"stone": {"density": 2500, "young_modulus": 2e10}},
                           "control": {"duration": 10, "time_step": 1e-3}});
        assert!(check_ranges(&s).is_ok());
        s["materials"]["stone"]["density"] = json!(1e308);
        let e = check_ranges(&s).expect_err("density 1e308");
        assert_eq!(
            e.pointer().as_deref(),
            Some("/scene/materials/stone/density")
        );
        assert!(e.to_string().len() < 200, "{e}");
        s["materials"]["stone"]["density"] = json!(2500);
        s["control"]["duration"] = json!(1e308);
        let e = check_ranges(&s).expect_err("duration 1e308");
        assert_eq!(e.pointer().as_deref(), Some("/scene/control/duration"));
        assert!(!e.to_string().contains("000000000000"), "{e}");
        s["control"]["duration"] = json!(10);
        s["initial"] = json!([{"block": "b", "velocity": [0, 1e308]}]);
        let e = check_ranges(&s).expect_err("velocity");
        assert_eq!(e.pointer().as_deref(), Some("/scene/initial/0/velocity/1"));
    }

    #[test]
    fn numbers_in_messages_stay_short() {
        assert_eq!(num(1e308), "1e308");
        assert_eq!(num(2.5e10), "2.5e10");
        assert_eq!(num(2500.0), crate::quantity::sig(2500.0));
    }

    #[test]
    fn search_runs_count_scan_and_bisection() {
        use crate::analysis::pga::PgaRequest;
        let req = |max: f64, tolerance: f64, scan_points: usize| PgaRequest {
            min: 0.0,
            max,
            tolerance,
            scan_points,
            resolution: None,
            ..PgaRequest::cli_default(Vec::new())
        };
        // 8 points over 0..7 → a lattice of 1 = 0.125 × 2³: 8 points, then 2 trisections (1/9 ≤
        // 0.125) of 2 runs each.
        assert_eq!(search_runs(1, &req(7.0, 0.125, 8)), 12.0);
        // 64 points over 0..10 ask for 0.159; the lattice rounds down to the tolerance 0.1
        // (no refinement) and holds 101 points: the budget counts the lattice, not the asked.
        assert_eq!(search_runs(100, &req(10.0, 0.1, 64)), 100.0 * 101.0);
    }
}
