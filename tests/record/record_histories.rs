//! Integration tests of `histories.csv` (`record::histories`): layout of docs/format.md §3, exact
//! round trip of every value, streaming, early finish and clear errors.
use ashlar::record::synthetic::RockingSquare;
use ashlar::record::{HistoryWriter, RecordError};
use std::path::Path;

fn csv_of(run: &RockingSquare, history_blocks: Option<Vec<usize>>, frames: usize) -> String {
    let mut header = run.header();
    if let Some(h) = history_blocks {
        header.history_blocks = h;
    }
    let mut w = HistoryWriter::new(Vec::new(), "<memory>", &header).expect("writer");
    for f in run.frames().take(frames) {
        w.write_frame(&f).expect("frame");
    }
    assert_eq!(w.rows(), frames.min(run.frame_count() as usize) as u64);
    String::from_utf8(w.finish().expect("finish")).expect("UTF-8")
}

#[test]
fn header_and_rows_follow_format_md() {
    let run = RockingSquare::default();
    let text = csv_of(&run, None, usize::MAX);
    let mut lines = text.lines();
    assert_eq!(
        lines.next(),
        Some("time_s,column.x_m,column.y_m,column.rotation_rad,slider.x_m,slider.y_m,slider.rotation_rad")
    );
    let rows: Vec<&str> = lines.collect();
    assert_eq!(rows.len() as u64, run.frame_count());
    assert!(text.ends_with('\n'));
    // Every value parses back to the frame's f64 bit for bit (exact: shortest round-trip
    // formatting loses nothing); the time is the frame's rounded to the nanosecond.
    for (k, row) in rows.iter().enumerate() {
        let f = run.frame(k as u64);
        let cells: Vec<f64> = row.split(',').map(|c| c.parse().expect("number")).collect();
        let want = [
            ashlar::record::histories::round_time(f.time),
            f.blocks[1].x,
            f.blocks[1].y,
            f.blocks[1].rotation,
            f.blocks[2].x,
            f.blocks[2].y,
            f.blocks[2].rotation,
        ];
        assert_eq!(cells.len(), want.len());
        for (c, w) in cells.iter().zip(want) {
            assert_eq!(c.to_bits(), w.to_bits(), "row {k}: {row}");
        }
    }
}

#[test]
fn history_blocks_choose_the_columns_and_their_order() {
    let run = RockingSquare {
        copies: 2,
        ..RockingSquare::default()
    };
    let text = csv_of(&run, Some(vec![4, 1]), 3);
    let header = text.lines().next().expect("header");
    assert_eq!(
        header,
        "time_s,slider_2.x_m,slider_2.y_m,slider_2.rotation_rad,column.x_m,column.y_m,column.rotation_rad"
    );
    let text = csv_of(&run, Some(vec![]), 2);
    assert_eq!(text, "time_s\n0\n0.01\n");
}

#[test]
fn finishing_early_gives_complete_rows() {
    let run = RockingSquare::default();
    let text = csv_of(&run, None, 5);
    let lines: Vec<&str> = text.lines().collect();
    assert_eq!(lines.len(), 6);
    assert!(lines.iter().all(|l| l.split(',').count() == 7));
}

#[test]
fn rows_reach_the_file_as_they_are_written() {
    let run = RockingSquare::default();
    let path = Path::new(env!("CARGO_TARGET_TMPDIR")).join("streamed.csv");
    let mut w = HistoryWriter::create(&path, &run.header()).expect("create");
    for f in run.frames().take(3) {
        w.write_frame(&f).expect("frame");
    }
    // Not finished yet: the rows are on disk already.
    let text = std::fs::read_to_string(&path).expect("read");
    assert_eq!(text.lines().count(), 4);
    drop(w);
}

#[test]
fn bad_input_is_a_clear_error() {
    let run = RockingSquare::default();
    let missing = Path::new(env!("CARGO_TARGET_TMPDIR")).join("nowhere/histories.csv");
    let err = HistoryWriter::create(&missing, &run.header())
        .err()
        .expect("error");
    assert!(matches!(err, RecordError::Io { .. }));
    assert!(err.to_string().contains("nowhere/histories.csv"), "{err}");

    let mut h = run.header();
    h.block_ids[1] = "col,umn".into();
    let err = HistoryWriter::new(Vec::new(), "h.csv", &h)
        .err()
        .expect("comma");
    assert!(
        err.to_string().contains("h.csv") && err.to_string().contains("comma"),
        "{err}"
    );

    let mut w = HistoryWriter::new(Vec::new(), "h.csv", &run.header()).expect("writer");
    let mut f = run.frame(0);
    f.blocks[2].y = f64::NEG_INFINITY;
    let err = w.write_frame(&f).expect_err("infinite");
    assert!(
        err.to_string().contains("\"slider\": y is not finite"),
        "{err}"
    );
    // The failed frame wrote nothing.
    assert_eq!(w.rows(), 0);
    let text = String::from_utf8(w.finish().expect("finish")).expect("UTF-8");
    assert_eq!(text.lines().count(), 1);
}
