//! Records a synthetic run (closed-form rocking and sliding, `record::synthetic`) to
//! `trajectory.mcap` and `histories.csv`, and prints what it measured as one JSON line: size,
//! speed and the process's peak memory. Used by CI to produce a file for the independent
//! Python check (scripts/check_mcap.py), and to measure the recorder (docs/foxglove.md).
//!
//! cargo run --release --example record_demo -- --out DIR [--copies N] [--duration S]
//!     [--interval S] [--threads N]
use ashlar::record::synthetic::RockingSquare;
use ashlar::record::{HistoryWriter, McapParams, McapRecorder};
use std::path::PathBuf;
use std::process::ExitCode;
use std::time::Instant;

struct Args {
    out: PathBuf,
    run: RockingSquare,
    threads: u32,
}

fn parse() -> Result<Args, String> {
    let mut out = None;
    let mut run = RockingSquare::default();
    let mut threads = McapParams::default().compression_threads;
    let mut it = std::env::args().skip(1);
    while let Some(flag) = it.next() {
        let mut value = |name: &str| it.next().ok_or_else(|| format!("{name} needs a value"));
        let number =
            |name: &str, v: String| v.parse::<f64>().map_err(|e| format!("{name} {v:?}: {e}"));
        match flag.as_str() {
            "--out" => out = Some(PathBuf::from(value("--out")?)),
            "--copies" => {
                let v = value("--copies")?;
                run.copies = v.parse().map_err(|e| format!("--copies {v:?}: {e}"))?;
            }
            "--duration" => run.duration = number("--duration", value("--duration")?)?,
            "--interval" => run.output_interval = number("--interval", value("--interval")?)?,
            "--threads" => {
                let v = value("--threads")?;
                threads = v.parse().map_err(|e| format!("--threads {v:?}: {e}"))?;
            }
            other => return Err(format!("unknown argument {other:?}")),
        }
    }
    if !(run.duration > 0.0 && run.output_interval > 0.0 && run.duration.is_finite()) {
        return Err("--duration and --interval must be positive".into());
    }
    let out = out.ok_or("--out DIR is required")?;
    Ok(Args { out, run, threads })
}

/// Peak resident memory of this process, KiB (Linux), from /proc/self/status.
fn peak_rss_kib() -> Option<u64> {
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = status.lines().find(|l| l.starts_with("VmHWM:"))?;
    line.split_whitespace().nth(1)?.parse().ok()
}

fn run(args: Args) -> Result<(), String> {
    std::fs::create_dir_all(&args.out).map_err(|e| format!("{}: {e}", args.out.display()))?;
    let header = args.run.header();
    let params = McapParams {
        compression_threads: args.threads,
        ..McapParams::default()
    };
    let mcap_path = args.out.join("trajectory.mcap");
    let csv_path = args.out.join("histories.csv");
    let rss_before = peak_rss_kib();
    let start = Instant::now();
    let mut rec = McapRecorder::create(&mcap_path, &header, &params).map_err(|e| e.to_string())?;
    let mut csv = HistoryWriter::create(&csv_path, &header).map_err(|e| e.to_string())?;
    let mut frame_time = std::time::Duration::ZERO;
    for frame in args.run.frames() {
        // Only the writers are timed, not the synthetic frames' computation.
        let t = Instant::now();
        rec.write_frame(&frame).map_err(|e| e.to_string())?;
        csv.write_frame(&frame).map_err(|e| e.to_string())?;
        frame_time += t.elapsed();
    }
    let (stats, _) = rec.finish().map_err(|e| e.to_string())?;
    csv.finish().map_err(|e| e.to_string())?;
    let wall = start.elapsed().as_secs_f64();
    let blocks = header.block_ids.len() as f64;
    let frames = stats.frames as f64;
    let report = serde_json::json!({
        "mcap": mcap_path,
        "csv": csv_path,
        "frames": stats.frames,
        "blocks": header.block_ids.len(),
        "messages": stats.messages,
        "bytes": stats.bytes,
        "bytes_per_block_frame": stats.bytes as f64 / (frames * blocks),
        "writer_us_per_frame": frame_time.as_secs_f64() * 1e6 / frames,
        "writer_us_per_block_frame": frame_time.as_secs_f64() * 1e6 / (frames * blocks),
        "wall_s": wall,
        "compression_threads": args.threads,
        "peak_rss_kib_before": rss_before,
        "peak_rss_kib": peak_rss_kib(),
    });
    println!("{report}");
    Ok(())
}

fn main() -> ExitCode {
    match parse().and_then(run) {
        Ok(()) => ExitCode::SUCCESS,
        Err(msg) => {
            eprintln!("record_demo: {msg}");
            ExitCode::FAILURE
        }
    }
}
