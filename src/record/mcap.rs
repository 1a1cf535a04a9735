//! `trajectory.mcap` writer: streams a run to an MCAP file (docs/format.md §5) that Foxglove opens
//! as is. Sits in `record`, after `simulation`; `analysis` calls it once per output frame.
//!
//! Layout: channels `/ashlar/blocks` (`ashlar.BlockStates`), `/ashlar/ground`
//! (`ashlar.GroundMotion`), `/ashlar/scene` (`foxglove.SceneUpdate`) with one message each per
//! frame, `/tf` (`foxglove.FrameTransforms`) with one static message at t = 0, and the metadata
//! record `ashlar.run`. JSON messages, JSON Schemas embedded; log time = simulation time in ns.
use super::error::{check_frame, check_header};
use super::messages::{self, SceneStyle};
use super::{foxglove, Frame, RecordError, RecordHeader};
use ::mcap::records::{MessageHeader, Metadata};
use ::mcap::{Compression, WriteOptions, Writer};
use std::collections::BTreeMap;
use std::fs::File;
use std::io::{BufWriter, Seek, Write};
use std::path::{Path, PathBuf};

/// Topics of the recording.
pub const TOPIC_BLOCKS: &str = "/ashlar/blocks";
pub const TOPIC_GROUND: &str = "/ashlar/ground";
pub const TOPIC_SCENE: &str = "/ashlar/scene";
pub const TOPIC_TF: &str = "/tf";
/// Name of the metadata record holding the header's `metadata`.
pub const METADATA_NAME: &str = "ashlar.run";
/// Written as the MCAP profile (empty would also do; this tells tools who wrote the file).
pub const PROFILE: &str = "ashlar";

/// Tuning knobs of the MCAP writer.
#[derive(Debug, Clone, PartialEq)]
pub struct McapParams {
    /// zstd worker threads per recording. Default 0: compression runs on the thread that calls
    /// `write_frame` (the run's own worker), so N concurrent jobs use N threads, not N × (1 +
    /// cores) as the `mcap` crate's default (one zstd worker per physical core) would; on the
    /// 2-core machines the service targets that oversubscribes as soon as two jobs run. zstd's
    /// workers would only help on chunks of several MiB anyway, and compressing costs little
    /// next to solving (see docs/foxglove.md for the measured rate).
    pub compression_threads: u32,
    /// zstd level. Default 3, zstd's own default: most of the size gain of higher levels at
    /// several times their speed (JSON of floating-point numbers compresses ~4-6× at 3).
    pub compression_level: u32,
    /// Uncompressed bytes a chunk holds before it is compressed and written. Default 1 MiB (the
    /// `mcap` crate's default): bounds the writer's memory and what a killed process loses,
    /// while keeping chunks large enough to compress well.
    pub chunk_size: u64,
    /// Outline width in the 3D view, screen pixels. Default 2: visible at any zoom without
    /// hiding small blocks.
    pub outline_px: f64,
}

impl Default for McapParams {
    fn default() -> Self {
        McapParams {
            compression_threads: 0,
            compression_level: 3,
            chunk_size: 1 << 20,
            outline_px: 2.0,
        }
    }
}

/// What a finished recording holds.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct McapStats {
    pub frames: u64,
    /// Messages on all channels (3 a frame, plus the static transform).
    pub messages: u64,
    pub bytes: u64,
}

/// Streams frames to an MCAP file. Memory stays bounded by one chunk whatever the run's length.
/// Call [`McapRecorder::finish`] at the end (also after a cancellation) to write the summary
/// and the index; a recorder dropped unfinished still completes the file (the `mcap` writer
/// finishes itself on drop) but cannot report an error.
pub struct McapRecorder<W: Write + Seek = BufWriter<File>> {
    writer: Writer<W>,
    path: PathBuf,
    header: RecordHeader,
    style: SceneStyle,
    channels: Channels,
    frames: u64,
    last_time: Option<f64>,
    buf: Vec<u8>,
}

#[derive(Debug, Clone, Copy)]
struct Channels {
    blocks: u16,
    ground: u16,
    scene: u16,
}

impl McapRecorder<BufWriter<File>> {
    /// Creates (or truncates) the MCAP file at `path`, writes the schemas, channels, the static
    /// transform and the `ashlar.run` metadata.
    pub fn create(
        path: &Path,
        header: &RecordHeader,
        params: &McapParams,
    ) -> Result<Self, RecordError> {
        check_header(header).map_err(|m| RecordError::invalid(path, m))?;
        check_params(params).map_err(|m| RecordError::invalid(path, m))?;
        let file = File::create(path).map_err(|e| RecordError::io(path, e))?;
        Self::new(BufWriter::new(file), path, header, params)
    }
}

impl<W: Write + Seek> McapRecorder<W> {
    /// Like [`McapRecorder::create`] on any seekable sink; `name` is what errors call it.
    pub fn new(
        sink: W,
        name: impl Into<PathBuf>,
        header: &RecordHeader,
        params: &McapParams,
    ) -> Result<Self, RecordError> {
        let path = name.into();
        check_header(header).map_err(|m| RecordError::invalid(&path, m))?;
        check_params(params).map_err(|m| RecordError::invalid(&path, m))?;
        let options = WriteOptions::new()
            .profile(PROFILE)
            .compression(Some(Compression::Zstd))
            .compression_level(params.compression_level)
            .compression_threads(params.compression_threads)
            .chunk_size(Some(params.chunk_size));
        let mcap_err = |e: ::mcap::McapError| RecordError::Mcap {
            path: path.clone(),
            message: e.to_string(),
        };
        let mut writer = options.create(sink).map_err(mcap_err)?;
        let no_meta = BTreeMap::new();
        let mut channel = |topic: &str, schema: serde_json::Value| -> Result<u16, RecordError> {
            let name = schema["title"].as_str().unwrap_or_default().to_string();
            let data = serde_json::to_vec(&schema).map_err(|e| RecordError::invalid(&path, e))?;
            let schema_id = writer
                .add_schema(&name, "jsonschema", &data)
                .map_err(mcap_err)?;
            writer
                .add_channel(schema_id, topic, "json", &no_meta)
                .map_err(mcap_err)
        };
        let channels = Channels {
            blocks: channel(TOPIC_BLOCKS, messages::block_states_schema())?,
            ground: channel(TOPIC_GROUND, messages::ground_motion_schema())?,
            scene: channel(TOPIC_SCENE, foxglove::scene_update_schema())?,
        };
        let tf = channel(TOPIC_TF, foxglove::frame_transforms_schema())?;
        let mut rec = McapRecorder {
            writer,
            path,
            header: header.clone(),
            style: SceneStyle {
                outline_px: params.outline_px,
            },
            channels,
            frames: 0,
            last_time: None,
            buf: Vec::new(),
        };
        write_json(
            &mut rec.writer,
            &mut rec.buf,
            &rec.path,
            tf,
            0,
            0,
            &messages::static_transforms(),
        )?;
        let metadata = Metadata {
            name: METADATA_NAME.to_string(),
            metadata: header.metadata.clone(),
        };
        rec.writer
            .write_metadata(&metadata)
            .map_err(|e| rec.mcap_error(e))?;
        Ok(rec)
    }

    /// Records one frame: a message on each of `/ashlar/blocks`, `/ashlar/ground` and
    /// `/ashlar/scene`, logged at the frame's simulation time. Frames must come in time order.
    pub fn write_frame(&mut self, frame: &Frame) -> Result<(), RecordError> {
        check_frame(&self.header, frame, self.frames, self.last_time, true)
            .map_err(|m| RecordError::invalid(&self.path, m))?;
        let ns = log_time_ns(frame.time).map_err(|m| RecordError::invalid(&self.path, m))?;
        let seq = u32::try_from(self.frames).unwrap_or(u32::MAX);
        let c = self.channels;
        let (w, buf, path) = (&mut self.writer, &mut self.buf, &self.path);
        write_json(
            w,
            buf,
            path,
            c.blocks,
            seq,
            ns,
            &messages::block_states(&self.header, frame),
        )?;
        write_json(
            w,
            buf,
            path,
            c.ground,
            seq,
            ns,
            &messages::ground_motion(frame),
        )?;
        let scene = messages::scene_update(&self.header, frame, ns, self.style);
        write_json(w, buf, path, c.scene, seq, ns, &scene)?;
        self.frames += 1;
        self.last_time = Some(frame.time);
        Ok(())
    }

    /// Frames written so far.
    pub fn frames(&self) -> u64 {
        self.frames
    }

    /// Writes the summary section and flushes: the file is a complete MCAP after any number of
    /// frames (a cancelled run gives a valid, shorter recording).
    pub fn finish(mut self) -> Result<(McapStats, W), RecordError> {
        let summary = self.writer.finish().map_err(|e| self.mcap_error(e))?;
        let messages = summary.stats.map(|s| s.message_count).unwrap_or(0);
        let frames = self.frames;
        let path = self.path.clone();
        let mut sink = self.writer.into_inner();
        sink.flush().map_err(|e| RecordError::io(&path, e))?;
        let bytes = sink
            .stream_position()
            .map_err(|e| RecordError::io(&path, e))?;
        Ok((
            McapStats {
                frames,
                messages,
                bytes,
            },
            sink,
        ))
    }

    fn mcap_error(&self, e: ::mcap::McapError) -> RecordError {
        RecordError::Mcap {
            path: self.path.clone(),
            message: e.to_string(),
        }
    }
}

/// Serializes `msg` into `buf` (reused, so a frame allocates no new buffer) and logs it.
fn write_json<W: Write + Seek, T: serde::Serialize>(
    writer: &mut Writer<W>,
    buf: &mut Vec<u8>,
    path: &Path,
    channel: u16,
    seq: u32,
    ns: u64,
    msg: &T,
) -> Result<(), RecordError> {
    buf.clear();
    serde_json::to_writer(&mut *buf, msg).map_err(|e| RecordError::invalid(path, e))?;
    let header = MessageHeader {
        channel_id: channel,
        sequence: seq,
        log_time: ns,
        publish_time: ns,
    };
    writer
        .write_to_known_channel(&header, buf)
        .map_err(|e| RecordError::Mcap {
            path: path.to_path_buf(),
            message: e.to_string(),
        })
}

/// Why [`McapParams`] cannot be used.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum McapParamsError {
    #[error("McapParams.outline_px must be finite and >= 0 (got {0})")]
    OutlinePx(f64),
    #[error("McapParams.chunk_size must be > 0")]
    ChunkSize,
    #[error("McapParams.compression_level must be 1..=22 or 0 (got {0})")]
    CompressionLevel(u32),
}

fn check_params(p: &McapParams) -> Result<(), McapParamsError> {
    if !(p.outline_px.is_finite() && p.outline_px >= 0.0) {
        return Err(McapParamsError::OutlinePx(p.outline_px));
    }
    if p.chunk_size == 0 {
        return Err(McapParamsError::ChunkSize);
    }
    if p.compression_level > 22 {
        return Err(McapParamsError::CompressionLevel(p.compression_level));
    }
    Ok(())
}

/// A time (s) that is no MCAP log time: not finite, negative, or 584 years or more.
#[derive(Debug, Clone, Copy, PartialEq, thiserror::Error)]
#[error("time {time} s cannot be a log time (must be finite, >= 0, < 584 years)")]
pub struct LogTimeError {
    pub time: f64,
}

/// Simulation time (s) to MCAP log time (ns), rounded to the nearest ns so that frames at
/// `k · output_interval` land on exact ns ticks despite the f64 sum.
pub fn log_time_ns(t: f64) -> Result<u64, LogTimeError> {
    let ns = (t * 1e9).round();
    // u64::MAX as f64 rounds up to 2^64, so `<` keeps the cast in range (584 years of run).
    if t.is_finite() && ns >= 0.0 && ns < u64::MAX as f64 {
        Ok(ns as u64)
    } else {
        Err(LogTimeError { time: t })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn log_times_round_to_the_nearest_nanosecond() {
        assert_eq!(log_time_ns(0.0), Ok(0));
        // 0.1 + 0.2 = 0.30000000000000004 s: still 300 ms exactly.
        assert_eq!(log_time_ns(0.1 + 0.2), Ok(300_000_000));
        assert_eq!(log_time_ns(3.0), Ok(3_000_000_000));
        assert!(log_time_ns(-1.0).is_err());
        assert!(log_time_ns(f64::NAN).is_err());
        assert!(log_time_ns(1e12).is_err());
    }

    #[test]
    fn default_params_are_valid() {
        assert_eq!(check_params(&McapParams::default()), Ok(()));
        let bad = McapParams {
            outline_px: f64::NAN,
            ..McapParams::default()
        };
        assert!(check_params(&bad).is_err());
    }
}
