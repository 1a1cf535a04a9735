//! Integration tests of the trajectory recording (`record::mcap`): files written from a
//! synthetic run with closed-form motion are read back with the `mcap` crate's reader and
//! checked against the frames, the CSV written from the same frames, their embedded schemas
//! and a golden digest.
use ashlar::record::mcap::{log_time_ns, TOPIC_BLOCKS, TOPIC_GROUND, TOPIC_SCENE, TOPIC_TF};
use ashlar::record::messages::fill_color;
use ashlar::record::synthetic::RockingSquare;
use ashlar::record::triangulate::signed_area;
use ashlar::record::{
    BlockMotionState, Frame, FrameBlockKind, HistoryWriter, McapParams, McapRecorder, RecordError,
    RecordHeader,
};
use serde_json::Value;
use std::collections::{BTreeMap, BTreeSet};
use std::io::Cursor;
use std::path::{Path, PathBuf};

fn tmp(name: &str) -> PathBuf {
    Path::new(env!("CARGO_TARGET_TMPDIR")).join(name)
}

fn record(path: &Path, run: &RockingSquare, frames: u64, params: &McapParams) {
    let mut rec = McapRecorder::create(path, &run.header(), params).expect("create");
    for f in run.frames().take(frames as usize) {
        rec.write_frame(&f).expect("write_frame");
    }
    rec.finish().expect("finish");
}

struct Msg {
    topic: String,
    /// The message text, for [`raw_numbers`].
    raw: String,
    schema_name: String,
    log_time: u64,
    sequence: u32,
    json: Value,
}

fn read_messages(bytes: &[u8]) -> Vec<Msg> {
    mcap::MessageStream::new(bytes)
        .expect("stream")
        .map(|m| {
            let m = m.expect("message");
            let schema = m
                .channel
                .schema
                .as_ref()
                .expect("every channel has a schema");
            assert_eq!(schema.encoding, "jsonschema");
            assert_eq!(m.channel.message_encoding, "json");
            Msg {
                topic: m.channel.topic.clone(),
                schema_name: schema.name.clone(),
                log_time: m.log_time,
                sequence: m.sequence,
                json: serde_json::from_slice(&m.data).expect("message is JSON"),
                raw: String::from_utf8(m.data.to_vec()).expect("UTF-8"),
            }
        })
        .collect()
}

/// The values of `"key":` in `text`, in order, parsed with Rust's exact `str::parse`. (serde_json
/// without its `float_roundtrip` feature parses some floats one ulp off, which would blur the
/// bit-for-bit comparisons below; the writer itself is exact.)
fn raw_numbers(text: &str, key: &str) -> Vec<f64> {
    let pat = format!("\"{key}\":");
    text.match_indices(&pat)
        .map(|(i, _)| {
            let rest = &text[i + pat.len()..];
            let end = rest.find([',', '}', ']']).unwrap_or(rest.len());
            rest[..end]
                .parse()
                .unwrap_or_else(|e| panic!("{key}: {:?}: {e}", &rest[..end]))
        })
        .collect()
}

fn on<'a>(msgs: &'a [Msg], topic: &str) -> Vec<&'a Msg> {
    msgs.iter().filter(|m| m.topic == topic).collect()
}

#[test]
fn recording_reads_back_with_the_mcap_crate() {
    let run = RockingSquare::default();
    let path = tmp("roundtrip.mcap");
    record(&path, &run, run.frame_count(), &McapParams::default());
    let bytes = std::fs::read(&path).expect("read");
    let n = run.frame_count();

    // Summary: channel list, schema names, counts, compression, metadata.
    let summary = mcap::Summary::read(&bytes)
        .expect("summary parses")
        .expect("summary present");
    let topics: BTreeMap<String, String> = summary
        .channels
        .values()
        .map(|c| {
            (
                c.topic.clone(),
                c.schema
                    .as_ref()
                    .map(|s| s.name.clone())
                    .unwrap_or_default(),
            )
        })
        .collect();
    let expected: BTreeMap<String, String> = [
        (TOPIC_BLOCKS, "ashlar.BlockStates"),
        (TOPIC_GROUND, "ashlar.GroundMotion"),
        (TOPIC_SCENE, "foxglove.SceneUpdate"),
        (TOPIC_TF, "foxglove.FrameTransforms"),
    ]
    .into_iter()
    .map(|(a, b)| (a.to_string(), b.to_string()))
    .collect();
    assert_eq!(topics, expected);
    let stats = summary.stats.as_ref().expect("statistics");
    let count = |topic: &str| {
        let id = summary
            .channels
            .values()
            .find(|c| c.topic == topic)
            .expect("channel")
            .id;
        stats.channel_message_counts.get(&id).copied().unwrap_or(0)
    };
    assert_eq!(
        (
            count(TOPIC_BLOCKS),
            count(TOPIC_GROUND),
            count(TOPIC_SCENE),
            count(TOPIC_TF)
        ),
        (n, n, n, 1)
    );
    assert_eq!(stats.message_count, 3 * n + 1);
    assert_eq!(
        stats.message_end_time,
        log_time_ns(run.duration).expect("ns")
    );
    assert!(!summary.chunk_indexes.is_empty());
    assert!(summary
        .chunk_indexes
        .iter()
        .all(|c| c.compression == "zstd"));
    assert_eq!(summary.metadata_indexes.len(), 1);
    let meta = mcap::read::metadata(&bytes, &summary.metadata_indexes[0]).expect("metadata");
    assert_eq!(meta.name, "ashlar.run");
    assert_eq!(meta.metadata, run.header().metadata);

    // Messages: counts seen by a linear read agree with the statistics; log times are the
    // frame times in ns (exact: the rounding is to the nearest ns), sequences the frame index.
    let msgs = read_messages(&bytes);
    assert_eq!(msgs.len() as u64, 3 * n + 1);
    for topic in [TOPIC_BLOCKS, TOPIC_GROUND, TOPIC_SCENE] {
        let ms = on(&msgs, topic);
        assert_eq!(ms.len() as u64, n, "{topic}");
        for (k, m) in ms.iter().enumerate() {
            let t = run.frame(k as u64).time;
            assert_eq!(m.log_time, (t * 1e9).round() as u64, "{topic} frame {k}");
            assert_eq!(m.sequence, k as u32);
            if topic != TOPIC_SCENE {
                assert_eq!(raw_numbers(&m.raw, "time"), [t]);
            }
        }
        assert!(
            ms.windows(2).all(|w| w[0].log_time < w[1].log_time),
            "{topic} strictly increasing"
        );
    }
    let tf = on(&msgs, TOPIC_TF);
    assert_eq!(tf[0].log_time, 0);
    assert_eq!(tf[0].json["transforms"][0]["parent_frame_id"], "world");

    // Ground: the frames' values, horizontal and vertical.
    for (k, m) in on(&msgs, TOPIC_GROUND).iter().enumerate() {
        let g = run.frame(k as u64).ground;
        assert_eq!(raw_numbers(&m.raw, "acceleration"), [g.acceleration[0]]);
        assert_eq!(raw_numbers(&m.raw, "velocity"), [g.velocity[0]]);
        assert_eq!(raw_numbers(&m.raw, "displacement"), [g.displacement[0]]);
        assert_eq!(
            raw_numbers(&m.raw, "vertical_acceleration"),
            [g.acceleration[1]]
        );
        assert_eq!(
            raw_numbers(&m.raw, "vertical_displacement"),
            [g.displacement[1]]
        );
    }
}

/// Parses `histories.csv` into (header, rows of f64).
fn parse_csv(text: &str) -> (Vec<String>, Vec<Vec<f64>>) {
    let mut lines = text.lines();
    let header: Vec<String> = lines
        .next()
        .expect("header")
        .split(',')
        .map(String::from)
        .collect();
    let rows = lines
        .map(|l| {
            l.split(',')
                .map(|c| c.parse::<f64>().expect("number"))
                .collect::<Vec<_>>()
        })
        .collect();
    (header, rows)
}

#[test]
fn blocks_channel_equals_histories_csv() {
    // Both writers get the same frames; the CSV is parsed back here and every history value
    // must equal the `/ashlar/blocks` value bit for bit (both are shortest round-trip decimals
    // of the same f64, so any difference is a lossy writer).
    let run = RockingSquare {
        copies: 2,
        ..RockingSquare::default()
    };
    let header = run.header();
    let mcap_path = tmp("vs_csv.mcap");
    let csv_path = tmp("vs_csv.csv");
    let mut rec =
        McapRecorder::create(&mcap_path, &header, &McapParams::default()).expect("create");
    let mut csv = HistoryWriter::create(&csv_path, &header).expect("csv");
    for f in run.frames() {
        rec.write_frame(&f).expect("mcap frame");
        csv.write_frame(&f).expect("csv frame");
    }
    rec.finish().expect("finish");
    csv.finish().expect("finish csv");

    let (cols, rows) = parse_csv(&std::fs::read_to_string(&csv_path).expect("csv"));
    let bytes = std::fs::read(&mcap_path).expect("mcap");
    let msgs = read_messages(&bytes);
    let blocks = on(&msgs, TOPIC_BLOCKS);
    assert_eq!(rows.len(), blocks.len());
    assert_eq!(cols.len(), 1 + 3 * header.history_blocks.len());
    for (row, msg) in rows.iter().zip(&blocks) {
        // The CSV's time is the message's rounded to the nanosecond (its log-time resolution).
        let t = raw_numbers(&msg.raw, "time")[0];
        assert_eq!(
            row[0].to_bits(),
            ashlar::record::histories::round_time(t).to_bits()
        );
        for (j, col) in cols.iter().enumerate().skip(1) {
            let (id, field_unit) = col.rsplit_once('.').expect("id.field_unit");
            let (field, unit) = field_unit.rsplit_once('_').expect("field_unit");
            let want = if field == "rotation" { "rad" } else { "m" };
            assert_eq!(unit, want, "{col}");
            let index = msg.json["blocks"]
                .as_array()
                .expect("blocks")
                .iter()
                .position(|b| b["id"] == id)
                .expect("block in message");
            // One `"x":` (etc.) per block, in the order of the blocks array.
            let v = raw_numbers(&msg.raw, field)[index];
            assert_eq!(row[j].to_bits(), v.to_bits(), "{col} at t = {}", row[0]);
        }
    }
}

fn centroid(p: &[[f64; 2]]) -> [f64; 2] {
    let a = signed_area(p);
    let n = p.len();
    let (mut cx, mut cy) = (0.0, 0.0);
    for i in 0..n {
        let (u, v) = (p[i], p[(i + 1) % n]);
        let w = u[0] * v[1] - v[0] * u[1];
        cx += (u[0] + v[0]) * w;
        cy += (u[1] + v[1]) * w;
    }
    [cx / (6.0 * a), cy / (6.0 * a)]
}

fn points(v: &Value) -> Vec<[f64; 2]> {
    v.as_array()
        .expect("points")
        .iter()
        .map(|p| {
            assert_eq!(p["z"].as_f64(), Some(0.0), "the 2D scene lies in z = 0");
            [p["x"].as_f64().expect("x"), p["y"].as_f64().expect("y")]
        })
        .collect()
}

#[test]
fn scene_outlines_agree_with_block_states() {
    // Second method: the displacement and rotation in `/ashlar/blocks` are recomputed from the
    // outlines drawn in `/ashlar/scene` (polygon centroid, edge angle). 1e-12 m / rad: the
    // centroid formula's rounding on coordinates of order 1 m.
    let run = RockingSquare::default();
    let header = run.header();
    let path = tmp("scene.mcap");
    record(&path, &run, run.frame_count(), &McapParams::default());
    let bytes = std::fs::read(&path).expect("read");
    let msgs = read_messages(&bytes);
    let scenes = on(&msgs, TOPIC_SCENE);
    let blocks = on(&msgs, TOPIC_BLOCKS);
    let first = run.frame(0);
    let mut states_seen = BTreeSet::new();
    for (scene, bm) in scenes.iter().zip(&blocks) {
        let entities = scene.json["entities"].as_array().expect("entities");
        assert_eq!(entities.len(), header.block_ids.len(), "one entity a block");
        for (i, e) in entities.iter().enumerate() {
            assert_eq!(e["id"], header.block_ids[i].as_str());
            assert_eq!(e["frame_id"], "world");
            let line = &e["lines"][0];
            assert_eq!(line["type"], 1, "LINE_LOOP closes the outline");
            let outline = points(&line["points"]);
            let fill = &e["triangles"][0];
            assert_eq!(points(&fill["points"]), outline);
            // The triangles tile the outline: their areas add up to the polygon's.
            let idx: Vec<usize> = fill["indices"]
                .as_array()
                .expect("indices")
                .iter()
                .map(|i| i.as_u64().expect("index") as usize)
                .collect();
            assert_eq!(idx.len() % 3, 0);
            let tri_area: f64 = idx
                .chunks(3)
                .map(|t| signed_area(&[outline[t[0]], outline[t[1]], outline[t[2]]]))
                .sum();
            let area = signed_area(&outline);
            assert!(
                (tri_area - area).abs() < 1e-12 * area.abs(),
                "fill area {tri_area} vs {area}"
            );

            let b = &bm.json["blocks"][i];
            let c0 = centroid(&first.blocks[i].outline);
            let c = centroid(&outline);
            assert!((c[0] - c0[0] - b["x"].as_f64().expect("x")).abs() < 1e-12);
            assert!((c[1] - c0[1] - b["y"].as_f64().expect("y")).abs() < 1e-12);
            let o0 = &first.blocks[i].outline;
            let ang = |p: &[[f64; 2]]| (p[1][1] - p[0][1]).atan2(p[1][0] - p[0][0]);
            let rot = ang(&outline) - ang(o0);
            assert!((rot - b["rotation"].as_f64().expect("rotation")).abs() < 1e-12);

            // Colour and metadata follow the block's kind and state.
            let state: BlockMotionState = match b["state"].as_str().expect("state") {
                "at_rest" => BlockMotionState::AtRest,
                "sliding" => BlockMotionState::Sliding,
                "rocking" => BlockMotionState::Rocking,
                "toppled" => BlockMotionState::Toppled,
                other => panic!("unknown state {other}"),
            };
            let c = fill_color(header.block_kinds[i], state);
            let col = &fill["color"];
            assert_eq!(
                [
                    col["r"].as_f64(),
                    col["g"].as_f64(),
                    col["b"].as_f64(),
                    col["a"].as_f64()
                ],
                [Some(c.r), Some(c.g), Some(c.b), Some(c.a)]
            );
            assert_eq!(e["metadata"][1]["value"], b["state"]);
            if header.block_kinds[i] == FrameBlockKind::Free {
                states_seen.insert(b["state"].as_str().expect("state").to_string());
            }
        }
    }
    assert_eq!(
        states_seen.len(),
        4,
        "the run shows all four colours: {states_seen:?}"
    );
    // Four states on free blocks give four different colours.
    let colours: BTreeSet<String> = [
        BlockMotionState::AtRest,
        BlockMotionState::Sliding,
        BlockMotionState::Rocking,
        BlockMotionState::Toppled,
    ]
    .iter()
    .map(|&s| format!("{:?}", fill_color(FrameBlockKind::Free, s)))
    .collect();
    assert_eq!(colours.len(), 4);
}

/// A small JSON Schema checker (the subset the recording's schemas use): `type`, `required`,
/// `properties` (and no property the schema does not declare), `items`, `enum`, `oneOf` of
/// consts, `minimum`, `maximum`.
fn validate(schema: &Value, v: &Value, at: &str) -> Result<(), String> {
    if let Some(ty) = schema.get("type").and_then(Value::as_str) {
        let ok = match ty {
            "object" => v.is_object(),
            "array" => v.is_array(),
            "number" => v.is_number(),
            "integer" => v.is_u64() || v.is_i64(),
            "string" => v.is_string(),
            "boolean" => v.is_boolean(),
            other => return Err(format!("{at}: schema type {other} not handled")),
        };
        if !ok {
            return Err(format!("{at}: expected {ty}, got {v}"));
        }
    }
    if let Some(options) = schema.get("oneOf").and_then(Value::as_array) {
        if !options.iter().any(|o| o.get("const") == Some(v)) {
            return Err(format!("{at}: {v} is none of the enumerated values"));
        }
    }
    if let Some(options) = schema.get("enum").and_then(Value::as_array) {
        if !options.contains(v) {
            return Err(format!("{at}: {v} not in enum"));
        }
    }
    if let (Some(min), Some(x)) = (schema.get("minimum").and_then(Value::as_f64), v.as_f64()) {
        if x < min {
            return Err(format!("{at}: {x} < minimum {min}"));
        }
    }
    if let (Some(max), Some(x)) = (schema.get("maximum").and_then(Value::as_f64), v.as_f64()) {
        if x > max {
            return Err(format!("{at}: {x} > maximum {max}"));
        }
    }
    if let Some(req) = schema.get("required").and_then(Value::as_array) {
        for key in req.iter().filter_map(Value::as_str) {
            if v.get(key).is_none() {
                return Err(format!("{at}: required field {key} missing"));
            }
        }
    }
    if let (Some(props), Some(obj)) = (
        schema.get("properties").and_then(Value::as_object),
        v.as_object(),
    ) {
        for (key, val) in obj {
            let sub = props
                .get(key)
                .ok_or_else(|| format!("{at}: field {key} not in the schema"))?;
            validate(sub, val, &format!("{at}.{key}"))?;
        }
    }
    if let (Some(items), Some(arr)) = (schema.get("items"), v.as_array()) {
        for (i, x) in arr.iter().enumerate() {
            validate(items, x, &format!("{at}[{i}]"))?;
        }
    }
    Ok(())
}

#[test]
fn every_message_validates_against_its_embedded_schema() {
    let run = RockingSquare {
        copies: 2,
        ..RockingSquare::default()
    };
    let path = tmp("schemas.mcap");
    record(&path, &run, 120, &McapParams::default());
    let bytes = std::fs::read(&path).expect("read");
    let summary = mcap::Summary::read(&bytes)
        .expect("summary")
        .expect("present");
    let schemas: BTreeMap<String, Value> = summary
        .schemas
        .values()
        .map(|s| {
            let v: Value = serde_json::from_slice(&s.data).expect("schema is JSON");
            assert_eq!(
                v["title"].as_str(),
                Some(s.name.as_str()),
                "schema title = schema name"
            );
            (s.name.clone(), v)
        })
        .collect();
    let msgs = read_messages(&bytes);
    for m in &msgs {
        validate(&schemas[&m.schema_name], &m.json, &m.topic).unwrap_or_else(|e| panic!("{e}"));
    }
    // The checker does reject: a scene entity without `cubes`, and an unknown line type.
    let scene = &on(&msgs, TOPIC_SCENE)[0].json;
    let mut broken = scene.clone();
    broken["entities"][0]
        .as_object_mut()
        .expect("entity")
        .remove("cubes");
    assert!(validate(&schemas["foxglove.SceneUpdate"], &broken, "x").is_err());
    let mut broken = scene.clone();
    broken["entities"][0]["lines"][0]["type"] = 7.into();
    assert!(validate(&schemas["foxglove.SceneUpdate"], &broken, "x").is_err());
}

#[test]
fn foxglove_schemas_have_the_published_fields() {
    // Reference: tests/fixtures/record/foxglove_fields.json, the field lists of Foxglove's
    // published JSON Schemas. Every titled object in the embedded schemas must have exactly
    // those properties, required in that order; every listed type must appear.
    let fixture =
        Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures/record/foxglove_fields.json");
    let expected: BTreeMap<String, Value> =
        serde_json::from_str(&std::fs::read_to_string(fixture).expect("fixture")).expect("JSON");
    let run = RockingSquare::default();
    let path = tmp("fields.mcap");
    record(&path, &run, 2, &McapParams::default());
    let bytes = std::fs::read(&path).expect("read");
    let summary = mcap::Summary::read(&bytes)
        .expect("summary")
        .expect("present");
    let mut seen = BTreeSet::new();
    fn walk(v: &Value, expected: &BTreeMap<String, Value>, seen: &mut BTreeSet<String>) {
        if let (Some(title), Some(props)) = (
            v.get("title").and_then(Value::as_str),
            v.get("properties").and_then(Value::as_object),
        ) {
            if let Some(fields) = expected.get(title).and_then(Value::as_array) {
                let want: Vec<&str> = fields.iter().filter_map(Value::as_str).collect();
                let mut have: Vec<&str> = props.keys().map(String::as_str).collect();
                let mut sorted_want = want.clone();
                sorted_want.sort();
                have.sort();
                assert_eq!(have, sorted_want, "{title}: properties");
                if title != "time" && title != "duration" {
                    let req: Vec<&str> = v["required"]
                        .as_array()
                        .expect("required")
                        .iter()
                        .filter_map(Value::as_str)
                        .collect();
                    assert_eq!(req, want, "{title}: required");
                }
                seen.insert(title.to_string());
            }
        }
        if let Some(obj) = v.as_object() {
            obj.values().for_each(|x| walk(x, expected, seen));
        }
        if let Some(arr) = v.as_array() {
            arr.iter().for_each(|x| walk(x, expected, seen));
        }
    }
    for s in summary
        .schemas
        .values()
        .filter(|s| s.name.starts_with("foxglove."))
    {
        walk(
            &serde_json::from_slice(&s.data).expect("JSON"),
            &expected,
            &mut seen,
        );
    }
    let listed: BTreeSet<String> = expected
        .keys()
        .filter(|k| !k.starts_with('_'))
        .cloned()
        .collect();
    assert_eq!(seen, listed);
}

#[test]
fn a_recording_finished_early_is_valid_and_shorter() {
    // A cancelled run calls finish() after fewer frames.
    let run = RockingSquare::default();
    let path = tmp("cancelled.mcap");
    let mut rec =
        McapRecorder::create(&path, &run.header(), &McapParams::default()).expect("create");
    for f in run.frames().take(37) {
        rec.write_frame(&f).expect("frame");
    }
    let (stats, _) = rec.finish().expect("finish");
    assert_eq!((stats.frames, stats.messages), (37, 3 * 37 + 1));
    let bytes = std::fs::read(&path).expect("read");
    assert_eq!(stats.bytes, bytes.len() as u64);
    let summary = mcap::Summary::read(&bytes)
        .expect("summary")
        .expect("present");
    assert_eq!(summary.stats.expect("stats").message_count, 3 * 37 + 1);
    assert_eq!(on(&read_messages(&bytes), TOPIC_BLOCKS).len(), 37);

    // A recorder dropped without finish() (an early return on another error) still leaves a
    // complete file: the mcap writer finishes itself on drop.
    let path = tmp("dropped.mcap");
    {
        let mut rec =
            McapRecorder::create(&path, &run.header(), &McapParams::default()).expect("create");
        for f in run.frames().take(10) {
            rec.write_frame(&f).expect("frame");
        }
    }
    let bytes = std::fs::read(&path).expect("read");
    let summary = mcap::Summary::read(&bytes)
        .expect("summary")
        .expect("present");
    assert_eq!(summary.stats.expect("stats").message_count, 3 * 10 + 1);

    // No frame at all: still a valid file with the static transform and the metadata.
    let path = tmp("empty.mcap");
    record(&path, &run, 0, &McapParams::default());
    let bytes = std::fs::read(&path).expect("read");
    assert_eq!(read_messages(&bytes).len(), 1);
}

#[test]
fn recording_streams_to_disk_as_it_goes() {
    // With 64 KiB chunks, the file on disk grows while frames are written (nothing waits for
    // finish), and the writer's memory is bounded by a chunk, not the run.
    let run = RockingSquare {
        copies: 10,
        duration: 20.0,
        ..RockingSquare::default()
    };
    let path = tmp("streaming.mcap");
    let params = McapParams {
        chunk_size: 64 * 1024,
        ..McapParams::default()
    };
    let mut rec = McapRecorder::create(&path, &run.header(), &params).expect("create");
    let mut sizes = Vec::new();
    for (k, f) in run.frames().enumerate() {
        rec.write_frame(&f).expect("frame");
        if k % 500 == 499 {
            sizes.push(std::fs::metadata(&path).expect("stat").len());
        }
    }
    rec.finish().expect("finish");
    assert!(sizes.len() >= 3);
    assert!(
        sizes.windows(2).all(|w| w[1] > w[0]),
        "file grows during the run: {sizes:?}"
    );
}

fn frame0() -> (RecordHeader, Frame) {
    let run = RockingSquare::default();
    (run.header(), run.frame(1))
}

fn write_one(header: &RecordHeader, frame: &Frame, name: &str) -> Result<(), RecordError> {
    let path = tmp(name);
    let mut rec = McapRecorder::create(&path, header, &McapParams::default())?;
    rec.write_frame(frame)
}

#[test]
fn bad_input_is_a_clear_error_naming_the_file() {
    let (header, frame) = frame0();
    let missing = Path::new(env!("CARGO_TARGET_TMPDIR")).join("no/such/dir/t.mcap");
    let err = McapRecorder::create(&missing, &header, &McapParams::default())
        .err()
        .expect("error");
    assert!(matches!(err, RecordError::Io { .. }));
    assert!(err.to_string().contains("no/such/dir/t.mcap"), "{err}");

    let mut f = frame.clone();
    f.blocks.pop();
    let err = write_one(&header, &f, "bad1.mcap").expect_err("block count");
    let msg = err.to_string();
    assert!(
        msg.contains("bad1.mcap") && msg.contains("frame 0") && msg.contains("blocks"),
        "{msg}"
    );

    let mut f = frame.clone();
    f.blocks[1].rotation = f64::NAN;
    let msg = write_one(&header, &f, "bad2.mcap")
        .expect_err("NaN")
        .to_string();
    assert!(
        msg.contains("\"column\"") && msg.contains("rotation"),
        "{msg}"
    );

    let mut f = frame.clone();
    f.blocks[2].outline.truncate(2);
    let msg = write_one(&header, &f, "bad3.mcap")
        .expect_err("outline")
        .to_string();
    assert!(
        msg.contains("\"slider\"") && msg.contains("outline"),
        "{msg}"
    );

    let mut f = frame.clone();
    f.ground.acceleration[0] = f64::INFINITY;
    let msg = write_one(&header, &f, "bad4.mcap")
        .expect_err("ground")
        .to_string();
    assert!(msg.contains("ground.acceleration"), "{msg}");

    let path = tmp("bad5.mcap");
    let mut rec = McapRecorder::create(&path, &header, &McapParams::default()).expect("create");
    rec.write_frame(&frame).expect("first");
    let mut earlier = frame.clone();
    earlier.time -= 0.005;
    let msg = rec
        .write_frame(&earlier)
        .expect_err("backwards")
        .to_string();
    assert!(msg.contains("backwards"), "{msg}");

    let mut h = header.clone();
    h.block_ids[2] = "column".into();
    let msg = write_one(&h, &frame, "bad6.mcap")
        .expect_err("duplicate id")
        .to_string();
    assert!(msg.contains("appears twice"), "{msg}");

    let mut h = header.clone();
    h.history_blocks.push(99);
    let msg = write_one(&h, &frame, "bad7.mcap")
        .expect_err("index")
        .to_string();
    assert!(msg.contains("out of range"), "{msg}");

    let bad = McapParams {
        chunk_size: 0,
        ..McapParams::default()
    };
    let msg = McapRecorder::create(&tmp("bad8.mcap"), &header, &bad)
        .err()
        .expect("params")
        .to_string();
    assert!(msg.contains("chunk_size"), "{msg}");
}

fn hex(bytes: &[u8]) -> String {
    bytes.iter().map(|b| format!("{b:02x}")).collect()
}

#[test]
fn golden_digest_of_the_synthetic_recording() {
    // The synthetic run's frames are bit-identical everywhere (IEEE arithmetic only) and zstd
    // runs single-threaded, so the file is too. A change of the digest means the recording's
    // bytes changed: a schema, a message layout, the `mcap`/zstd/serde_json versions. If that
    // is intended, regenerate with
    //   ASHLAR_BLESS=1 cargo test --test record record_mcap::golden_digest
    // and commit tests/fixtures/record/synthetic_recording.digest.
    use sha2::Digest;
    let run = RockingSquare::default();
    let mut rec = McapRecorder::new(
        Cursor::new(Vec::new()),
        "<memory>",
        &run.header(),
        &McapParams::default(),
    )
    .expect("recorder");
    for f in run.frames() {
        rec.write_frame(&f).expect("frame");
    }
    let (_, sink) = rec.finish().expect("finish");
    let bytes = sink.into_inner();
    let actual = format!(
        "size {}\nsha256 {}\n",
        bytes.len(),
        hex(&sha2::Sha256::digest(&bytes))
    );
    let fixture = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/fixtures/record/synthetic_recording.digest");
    if std::env::var("ASHLAR_BLESS").is_ok_and(|v| v == "1") {
        std::fs::write(&fixture, &actual).expect("write digest");
        eprintln!("blessed {}:\n{actual}", fixture.display());
        return;
    }
    let expected = std::fs::read_to_string(&fixture).unwrap_or_else(|e| {
        panic!(
            "{}: {e} (generate it with ASHLAR_BLESS=1)",
            fixture.display()
        )
    });
    assert_eq!(
        actual, expected,
        "recording bytes changed; see this test's comment"
    );
}
