//! A recording's life: finished early, streamed to disk as it goes, and bad input as a clear
//! error naming the file.
use super::*;

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
