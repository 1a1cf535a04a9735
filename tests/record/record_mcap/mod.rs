//! Integration tests of the trajectory recording (`record::mcap`): files written from a
//! synthetic run with closed-form motion are read back with the `mcap` crate's reader and
//! checked against the frames, the CSV written from the same frames, their embedded schemas
//! and a golden digest.
use ashlar::record::mcap::{log_time_ns, TOPIC_BLOCKS, TOPIC_GROUND, TOPIC_SCENE, TOPIC_TF};
use ashlar::record::synthetic::RockingSquare;
use ashlar::record::{Frame, HistoryWriter, McapParams, McapRecorder, RecordError, RecordHeader};
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

mod lifecycle;
mod outlines;
mod schemas;
