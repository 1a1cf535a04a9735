//! HTTP layer: a finished run's files, `GET /v1/jobs/{id}/histories` (JSON or streamed CSV,
//! selected blocks, every n-th frame) and `GET /v1/jobs/{id}/trajectory.mcap` (byte ranges),
//! streamed in chunks so that memory stays one chunk per response.
//!
//! Length (over 600 lines): both downloads share the job lookup, the history format's
//! negotiation and the chunked bodies; about 90 lines are the range parser's unit tests.
use super::problem::ApiError;
use super::state::{blocking, load, parse_id, ApiResult, AppState};
use crate::service::auth::Access;
use crate::service::histories::{Histories, HistoriesError};
use crate::service::store::{JobKind, JobRecord, JobStatus};
use crate::service::worker::Core;
use axum::body::{Body, Bytes};
use axum::extract::rejection::{PathRejection, QueryRejection};
use axum::extract::{Path, Query, State};
use axum::http::{header, HeaderMap, HeaderValue, StatusCode};
use axum::response::IntoResponse;
use uuid::Uuid;

/// Artifacts exist for finished runs; a cancelled run keeps what it wrote before stopping.
fn artifact_available(j: &JobRecord, what: &str) -> Result<(), ApiError> {
    match j.status {
        JobStatus::Succeeded | JobStatus::Cancelled => Ok(()),
        s => Err(ApiError::conflict(format!(
            "the job is {}; its {what} {}",
            s.as_str(),
            if s == JobStatus::Failed {
                "were never written"
            } else {
                "are available once it has succeeded"
            }
        ))),
    }
}

enum HistoryFormat {
    Json,
    Csv,
}

fn history_format(
    query: &[(String, String)],
    headers: &HeaderMap,
) -> Result<HistoryFormat, ApiError> {
    if let Some((_, f)) = query.iter().find(|(k, _)| k == "format") {
        return match f.as_str() {
            "json" => Ok(HistoryFormat::Json),
            "csv" => Ok(HistoryFormat::Csv),
            other => Err(ApiError::invalid_parameter(
                "format",
                format!("format {other:?} is not one of \"json\", \"csv\""),
            )),
        };
    }
    let accept = headers
        .get(header::ACCEPT)
        .and_then(|v| v.to_str().ok())
        .unwrap_or("")
        .to_ascii_lowercase();
    let types: Vec<&str> = accept
        .split(',')
        .map(|t| t.split(';').next().unwrap_or("").trim())
        .filter(|t| !t.is_empty())
        .collect();
    if types.is_empty() {
        return Ok(HistoryFormat::Json);
    }
    // The first acceptable type wins (q-values are not weighed: clients ask for one format).
    for t in types {
        match t {
            "application/json" | "application/*" | "*/*" => return Ok(HistoryFormat::Json),
            "text/csv" | "text/*" => return Ok(HistoryFormat::Csv),
            _ => {}
        }
    }
    Err(ApiError::not_acceptable(format!(
        "cannot produce {accept:?}; histories come as application/json or text/csv"
    )))
}

/// Largest history (bytes of `histories.csv`, after `every`) answered as JSON: the JSON form is
/// built in memory (~3× the text). Larger ones come as CSV, which is streamed.
pub const MAX_JSON_HISTORY_BYTES: u64 = 8 << 20;

/// Bytes per chunk of a streamed file or history.
const CHUNK: usize = 64 * 1024;

pub(super) async fn get_histories(
    State(s): State<AppState>,
    access: Access,
    id: Result<Path<String>, PathRejection>,
    query: Result<Query<Vec<(String, String)>>, QueryRejection>,
    headers: HeaderMap,
) -> ApiResult {
    use tokio::io::AsyncBufReadExt;
    let id = parse_id(id)?;
    let Query(query) = query.map_err(|e| ApiError::invalid_parameter("query", e.body_text()))?;
    if let Some((k, _)) = query
        .iter()
        .find(|(k, _)| !matches!(k.as_str(), "format" | "block" | "every" | "expires" | "sig"))
    {
        return Err(ApiError::invalid_parameter(
            k.clone(),
            format!("unknown query parameter {k:?} (known: block, format, every)"),
        ));
    }
    let format = history_format(&query, &headers)?;
    let every = match query.iter().find(|(k, _)| k == "every") {
        None => 1u64,
        Some((_, v)) => match v.parse::<u64>() {
            Ok(n) if n >= 1 => n,
            _ => {
                return Err(ApiError::invalid_parameter(
                    "every",
                    format!(
                        "every {v:?} is not a whole number ≥ 1 (keep every n-th recorded frame)"
                    ),
                ))
            }
        },
    };
    let mut blocks: Vec<String> = Vec::new();
    for (_, v) in query.iter().filter(|(k, _)| k == "block") {
        if !blocks.contains(v) {
            blocks.push(v.clone());
        }
    }
    let (file, size, path) = open_artifact(&s, &access, id, Artifact::HISTORIES).await?;
    let mut reader = tokio::io::BufReader::with_capacity(CHUNK, file);
    let mut header = String::new();
    reader
        .read_line(&mut header)
        .await
        .map_err(|e| ApiError::internal(format!("{}: {e}", path.display())))?;
    let head = Histories::parse_csv(header.trim_end()).map_err(ApiError::internal)?;
    let ids: Vec<String> = head.block_ids().map(str::to_string).collect();
    let mut selected: Vec<usize> = Vec::new();
    for b in &blocks {
        match ids.iter().position(|i| i == b) {
            Some(k) => selected.push(k),
            None => {
                return Err(ApiError::not_found_parameter(
                    "block",
                    format!(
                        "the job has no history for block {b:?} (it has: {})",
                        ids.join(", ")
                    ),
                ))
            }
        }
    }
    if blocks.is_empty() {
        selected = (0..ids.len()).collect();
    }
    match format {
        HistoryFormat::Json => {
            if size / every > MAX_JSON_HISTORY_BYTES {
                return Err(ApiError::not_acceptable(format!(
                    "these histories are {size} bytes of CSV; JSON is offered up to {MAX_JSON_HISTORY_BYTES} bytes \
                     (after ?every=N). Ask for format=csv (streamed), a larger ?every, or fewer ?block="
                )));
            }
            // At most JSON_BUILDS at once: a JSON answer holds its kept rows as text (the
            // selected fields only, at most about 8 MiB) plus one offset a row while it is
            // written, so concurrent requests for large histories wait instead of adding up
            // (eight 31 MB histories at once took 4.7 GB when each built its text, a parsed
            // copy and a JSON tree, and 381 MB with two at once holding parsed numbers).
            // The permit goes into the body's stream: it is held until the answer is sent (or
            // the client leaves), since the kept rows live as long as the stream.
            let permit = json_builds()
                .clone()
                .acquire_owned()
                .await
                .map_err(ApiError::internal)?;
            // The rows the reader already buffered after the header, then the rest of the file.
            let buffered = reader.buffer().to_vec();
            let rest = reader.into_inner().into_std().await;
            let reader = std::io::Read::chain(std::io::Cursor::new(buffered), rest);
            // Blocks in file order: the fields of each kept row are then read left to right.
            selected.sort_unstable();
            let cols = selected.clone();
            let capacity = usize::try_from(size / every)
                .unwrap_or(usize::MAX)
                .min(MAX_JSON_HISTORY_BYTES as usize)
                + CHUNK;
            let rows = blocking(move || KeptRows::read(reader, &cols, every, capacity))
                .await?
                .map_err(ApiError::internal)?;
            let names: Vec<String> = selected.iter().map(|&k| ids[k].clone()).collect();
            let mut r = Body::from_stream(futures_util::stream::iter(
                json_chunks(names, rows).map(move |chunk| {
                    let _held = &permit;
                    Ok::<_, std::io::Error>(chunk)
                }),
            ))
            .into_response();
            r.headers_mut().insert(
                header::CONTENT_TYPE,
                HeaderValue::from_static("application/json"),
            );
            Ok(r)
        }
        HistoryFormat::Csv => {
            let mut first =
                crate::record::histories::header_line(selected.iter().map(|&k| ids[k].as_str()));
            first.push('\n');
            let all = blocks.is_empty();
            let lines = reader.lines();
            let stream = futures_util::stream::unfold(
                (lines, Some(first), 0u64, false),
                move |(mut lines, mut pending, mut row, mut done)| {
                    let selected = selected.clone();
                    async move {
                        if done {
                            return None;
                        }
                        let mut out = pending.take().unwrap_or_default();
                        while out.len() < CHUNK {
                            match lines.next_line().await {
                                Ok(Some(line)) => {
                                    if line.trim().is_empty() {
                                        continue;
                                    }
                                    let keep = row % every == 0;
                                    row += 1;
                                    if !keep {
                                        continue;
                                    }
                                    if all {
                                        out.push_str(&line);
                                    } else {
                                        let vals: Vec<&str> = line.split(',').collect();
                                        out.push_str(vals.first().copied().unwrap_or(""));
                                        for &k in &selected {
                                            for c in 1 + 3 * k..4 + 3 * k {
                                                out.push(',');
                                                out.push_str(vals.get(c).copied().unwrap_or(""));
                                            }
                                        }
                                    }
                                    out.push('\n');
                                }
                                Ok(None) => {
                                    done = true;
                                    break;
                                }
                                Err(e) => {
                                    return Some((Err(e), (lines, None, row, true)));
                                }
                            }
                        }
                        if out.is_empty() {
                            return None;
                        }
                        Some((Ok(Bytes::from(out)), (lines, None, row, done)))
                    }
                },
            );
            let mut r = Body::from_stream(stream).into_response();
            r.headers_mut().insert(
                header::CONTENT_TYPE,
                HeaderValue::from_static("text/csv; charset=utf-8"),
            );
            Ok(r)
        }
    }
}

/// JSON histories built at once (see `get_histories`).
const JSON_BUILDS: usize = 2;

fn json_builds() -> &'static std::sync::Arc<tokio::sync::Semaphore> {
    static S: std::sync::OnceLock<std::sync::Arc<tokio::sync::Semaphore>> =
        std::sync::OnceLock::new();
    S.get_or_init(|| std::sync::Arc::new(tokio::sync::Semaphore::new(JSON_BUILDS)))
}

/// The kept rows of a history, for its JSON form: each row's time and the `x, y, rotation`
/// fields of the selected blocks, as the CSV's text (`t,x,y,r,…\n`), and where each row's next
/// unread field starts. Columns are then written one after the other, each row's offset moving
/// one field right per column: memory is the kept text plus 4 bytes a row.
struct KeptRows {
    text: String,
    next: Vec<u32>,
}

impl KeptRows {
    /// Read every `every`-th row of `reader` (positioned after the header line), keeping the
    /// fields of the blocks at `selected` (header indices, increasing). Every kept field must be
    /// a number (the file is ours: an error names the line, as an internal error).
    fn read(
        reader: impl std::io::Read,
        selected: &[usize],
        every: u64,
        capacity: usize,
    ) -> Result<Self, HistoriesError> {
        use std::io::BufRead;
        let wanted: Vec<usize> = std::iter::once(0)
            .chain(selected.iter().flat_map(|&k| 1 + 3 * k..4 + 3 * k))
            .collect();
        let mut text = String::with_capacity(capacity);
        let mut next = Vec::new();
        let mut row = 0u64;
        for (n, line) in std::io::BufReader::with_capacity(CHUNK, reader)
            .lines()
            .enumerate()
        {
            let line = line.map_err(|source| HistoriesError::Read {
                line: n + 2,
                source,
            })?;
            if line.trim().is_empty() {
                continue;
            }
            let keep = row % every == 0;
            row += 1;
            if !keep {
                continue;
            }
            let start = u32::try_from(text.len()).map_err(|_| HistoriesError::TooLarge)?;
            next.push(start);
            let mut fields = line.split(',').enumerate();
            for (i, &k) in wanted.iter().enumerate() {
                let v = fields
                    .find(|(j, _)| *j == k)
                    .map(|(_, v)| v.trim())
                    .filter(|v| v.parse::<f64>().is_ok())
                    .ok_or(HistoriesError::Unreadable {
                        line: n + 2,
                        column: k + 1,
                    })?;
                if i > 0 {
                    text.push(',');
                }
                text.push_str(v);
            }
            text.push('\n');
        }
        Ok(Self { text, next })
    }

    /// The next field of row `r` as a number, moving the row's offset past it.
    fn take(&mut self, r: usize) -> f64 {
        let start = self.next[r] as usize;
        let rest = &self.text[start..];
        let len = rest.find([',', '\n']).unwrap_or(rest.len());
        // +1: past the separator.
        self.next[r] = u32::try_from(start + len + 1).unwrap_or(u32::MAX);
        rest[..len].parse().unwrap_or(f64::NAN)
    }
}

/// The JSON form of the histories (`{"time": […], "blocks": {"id": {"x": […], "y": […],
/// "rotation": […]}}, "units": {…}}`, the same object as `Histories::to_json`, blocks in file
/// order) as a sequence of chunks of about [`CHUNK`] bytes, written from the kept rows as the
/// body is sent. `names`: the kept blocks, in the order of their fields.
fn json_chunks(names: Vec<String>, mut rows: KeptRows) -> impl Iterator<Item = Bytes> {
    // The text before each column; the columns follow the rows' fields left to right.
    let mut prefixes: Vec<String> = vec!["{\"time\":[".to_string()];
    for (i, name) in names.iter().enumerate() {
        let key = serde_json::to_string(name).unwrap_or_default();
        let open = if i == 0 { "],\"blocks\":{" } else { "]}," };
        prefixes.push(format!("{open}{key}:{{\"x\":["));
        prefixes.push("],\"y\":[".to_string());
        prefixes.push("],\"rotation\":[".to_string());
    }
    let tail = if names.is_empty() {
        "],\"blocks\":{},\"units\":"
    } else {
        "]}},\"units\":"
    };
    let tail = format!("{tail}{{\"time\":\"s\",\"x\":\"m\",\"y\":\"m\",\"rotation\":\"rad\"}}}}");
    let n_rows = rows.next.len();
    let mut prefixes = prefixes.into_iter();
    // Inside a column: the next row to write.
    let mut at: Option<usize> = None;
    let mut finished = false;
    std::iter::from_fn(move || {
        if finished {
            return None;
        }
        let mut out: Vec<u8> = Vec::with_capacity(CHUNK + 64);
        while out.len() < CHUNK {
            match at {
                Some(r) if r < n_rows => {
                    if r > 0 {
                        out.push(b',');
                    }
                    // Printed as `Histories::to_json` prints it (serde_json's shortest form).
                    if serde_json::to_writer(&mut out, &rows.take(r)).is_err() {
                        out.extend_from_slice(b"null");
                    }
                    at = Some(r + 1);
                }
                _ => match prefixes.next() {
                    Some(prefix) => {
                        out.extend_from_slice(prefix.as_bytes());
                        at = Some(0);
                    }
                    None => {
                        out.extend_from_slice(tail.as_bytes());
                        finished = true;
                        break;
                    }
                },
            }
        }
        Some(Bytes::from(out))
    })
}

/// `len` bytes of `file` from `start`, read and sent in chunks of [`CHUNK`]: memory stays
/// one chunk per response whatever the file's size.
fn file_body(file: tokio::fs::File, start: u64, len: u64) -> Body {
    use tokio::io::{AsyncReadExt, AsyncSeekExt};
    let stream = futures_util::stream::unfold(
        (file, start, len, false),
        |(mut f, pos, left, seeked)| async move {
            if left == 0 {
                return None;
            }
            if !seeked {
                if let Err(e) = f.seek(std::io::SeekFrom::Start(pos)).await {
                    return Some((Err(e), (f, pos, 0, true)));
                }
            }
            let mut buf = vec![0u8; usize::try_from(left).unwrap_or(CHUNK).min(CHUNK)];
            match f.read(&mut buf).await {
                Ok(0) => None,
                Ok(n) => {
                    buf.truncate(n);
                    Some((
                        Ok(Bytes::from(buf)),
                        (f, pos + n as u64, left - n as u64, true),
                    ))
                }
                Err(e) => Some((Err(e), (f, pos, 0, true))),
            }
        },
    );
    Body::from_stream(stream)
}

/// A single byte range, resolved against the file length (RFC 9110 §14.1.2).
#[derive(Debug, PartialEq)]
enum RangeAsk {
    Whole,
    Part(u64, u64),
    Unsatisfiable,
}

fn parse_range(value: Option<&str>, len: u64) -> RangeAsk {
    let Some(spec) = value.and_then(|v| v.trim().strip_prefix("bytes=")) else {
        return RangeAsk::Whole;
    };
    // Several ranges (multipart answers) are not supported: serve the whole file, as allowed.
    if spec.contains(',') {
        return RangeAsk::Whole;
    }
    let Some((a, b)) = spec.split_once('-') else {
        return RangeAsk::Whole;
    };
    let (a, b) = (a.trim(), b.trim());
    let parsed = match (a.parse::<u64>().ok(), b.parse::<u64>().ok()) {
        (Some(start), Some(end)) if a.len() + b.len() > 0 && end >= start => {
            Some((start, end.min(len.saturating_sub(1))))
        }
        (Some(_), Some(_)) => return RangeAsk::Whole, // end < start: invalid, ignored
        (Some(start), None) if b.is_empty() => Some((start, len.saturating_sub(1))),
        (None, Some(n)) if a.is_empty() => {
            if n == 0 {
                return RangeAsk::Unsatisfiable;
            }
            Some((len.saturating_sub(n), len.saturating_sub(1)))
        }
        _ => return RangeAsk::Whole,
    };
    match parsed {
        Some((start, end)) if start < len && start <= end => RangeAsk::Part(start, end),
        _ => RangeAsk::Unsatisfiable,
    }
}

pub(super) async fn get_trajectory(
    State(s): State<AppState>,
    access: Access,
    id: Result<Path<String>, PathRejection>,
    headers: HeaderMap,
) -> ApiResult {
    let id = parse_id(id)?;
    let (file, len, _) = open_artifact(&s, &access, id, Artifact::TRAJECTORY).await?;
    let range = parse_range(
        headers.get(header::RANGE).and_then(|v| v.to_str().ok()),
        len,
    );
    let mut resp = match range {
        RangeAsk::Whole => {
            let mut r = (StatusCode::OK, file_body(file, 0, len)).into_response();
            r.headers_mut()
                .insert(header::CONTENT_LENGTH, HeaderValue::from(len));
            r
        }
        RangeAsk::Part(a, b) => {
            let mut r =
                (StatusCode::PARTIAL_CONTENT, file_body(file, a, b - a + 1)).into_response();
            if let Ok(v) = HeaderValue::from_str(&format!("bytes {a}-{b}/{len}")) {
                r.headers_mut().insert(header::CONTENT_RANGE, v);
            }
            r.headers_mut()
                .insert(header::CONTENT_LENGTH, HeaderValue::from(b - a + 1));
            r
        }
        RangeAsk::Unsatisfiable => {
            let mut r = ApiError::range_not_satisfiable(format!("the trajectory has {len} bytes"))
                .into_response();
            if let Ok(v) = HeaderValue::from_str(&format!("bytes */{len}")) {
                r.headers_mut().insert(header::CONTENT_RANGE, v);
            }
            return Ok(r);
        }
    };
    let h = resp.headers_mut();
    h.insert(
        header::CONTENT_TYPE,
        HeaderValue::from_static("application/octet-stream"),
    );
    h.insert(header::ACCEPT_RANGES, HeaderValue::from_static("bytes"));
    h.insert(
        header::CONTENT_DISPOSITION,
        HeaderValue::from_static("attachment; filename=\"trajectory.mcap\""),
    );
    Ok(resp)
}

/// A run's downloadable file: its name in the job's folder, the word `artifact_available`
/// uses, and the 409 detail when the job finished without it.
struct Artifact {
    file: &'static str,
    what: &'static str,
    missing: &'static str,
}

impl Artifact {
    const HISTORIES: Artifact = Artifact {
        file: "histories.csv",
        what: "histories",
        missing: "the job finished without recording histories",
    };
    const TRAJECTORY: Artifact = Artifact {
        file: "trajectory.mcap",
        what: "trajectory",
        missing: "the job finished without recording a trajectory",
    };
}

/// The run `id`'s file `a`, open, with its length and path: checked against the caller's access and the
/// job's status, fetched from the shared artifact store first when another process ran it.
async fn open_artifact(
    s: &AppState,
    access: &Access,
    id: Uuid,
    a: Artifact,
) -> Result<(tokio::fs::File, u64, std::path::PathBuf), ApiError> {
    let j = load(s, access, id, JobKind::Run).await?;
    artifact_available(&j, a.what)?;
    ensure_local(&s.core, id, a.file).await;
    let path = s.core.job_dir(id).join(a.file);
    let file = match tokio::fs::File::open(&path).await {
        Ok(f) => f,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => {
            return Err(ApiError::conflict(a.missing));
        }
        Err(e) => return Err(ApiError::internal(format!("{}: {e}", path.display()))),
    };
    let len = file
        .metadata()
        .await
        .map_err(|e| ApiError::internal(format!("{}: {e}", path.display())))?
        .len();
    Ok((file, len, path))
}

/// Make sure the job's artifact `name` is in its local directory, fetched from the shared
/// artifact store (`--artifacts`) when another process ran the job.
pub(super) async fn ensure_local(core: &Core, id: Uuid, name: &str) {
    if let Some(a) = &core.artifacts {
        a.ensure_local(id, &core.job_dir(id), name).await;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The streamed JSON equals `Histories::to_json` of the same selection (several blocks,
    /// not in id order, over many chunks), also with `every`.
    #[test]
    fn json_histories_are_written_as_to_json_builds_them() {
        let mut csv = String::from(
            "time_s,zeta.x_m,zeta.y_m,zeta.rotation_rad,alpha.x_m,alpha.y_m,alpha.rotation_rad,m.id.x_m,m.id.y_m,m.id.rotation_rad\n",
        );
        for i in 0..5000 {
            let t = f64::from(i) * 0.01;
            csv.push_str(&format!(
                "{t},{},{},{},{},{},{},0,0,{}\n",
                t.sin() * 1e-3,
                -t / 7.0,
                1e-9 * t,
                t.cos(),
                3.0,
                -0.25 * t,
                0.1 / (1.0 + t)
            ));
        }
        let rows = csv.split_once('\n').expect("header").1.to_string();
        for (ask, every) in [
            (vec!["m.id", "zeta"], 1u64),
            (vec![], 3),
            (vec!["alpha"], 7),
        ] {
            let ask: Vec<String> = ask.into_iter().map(String::from).collect();
            let all = Histories::parse_csv(&csv).expect("parse");
            let ids: Vec<String> = all.block_ids().map(String::from).collect();
            let selected: Vec<usize> = if ask.is_empty() {
                (0..ids.len()).collect()
            } else {
                ask.iter()
                    .map(|a| ids.iter().position(|i| i == a).expect("id"))
                    .collect()
            };
            let kept: String = csv
                .lines()
                .skip(1)
                .step_by(usize::try_from(every).expect("small"))
                .map(|l| format!("{l}\n"))
                .collect();
            let header = csv.lines().next().expect("header");
            let want = Histories::parse_csv(&format!("{header}\n{kept}"))
                .expect("parse")
                .select(&ask)
                .expect("select")
                .to_json();
            let mut selected = selected;
            selected.sort_unstable();
            let kept = KeptRows::read(std::io::Cursor::new(rows.clone()), &selected, every, 0)
                .expect("read");
            let names = selected.iter().map(|&k| ids[k].clone()).collect();
            let chunks: Vec<Bytes> = json_chunks(names, kept).collect();
            if every == 1 {
                assert!(chunks.len() > 3, "{} chunks", chunks.len());
            }
            let got: Vec<u8> = chunks.concat();
            let got: serde_json::Value = serde_json::from_slice(&got).expect("valid JSON");
            // Both read back by the same parser from their text: serde_json's default float
            // parser may be one ULP off, the same way for the same digits.
            let want: serde_json::Value =
                serde_json::from_slice(&serde_json::to_vec(&want).expect("text")).expect("JSON");
            assert_eq!(got, want, "blocks {ask:?}, every {every}");
        }
    }

    #[test]
    fn byte_ranges() {
        assert_eq!(parse_range(None, 100), RangeAsk::Whole);
        assert_eq!(parse_range(Some("bytes=0-9"), 100), RangeAsk::Part(0, 9));
        assert_eq!(parse_range(Some("bytes=90-"), 100), RangeAsk::Part(90, 99));
        assert_eq!(parse_range(Some("bytes=-10"), 100), RangeAsk::Part(90, 99));
        assert_eq!(
            parse_range(Some("bytes=50-1000"), 100),
            RangeAsk::Part(50, 99)
        );
        assert_eq!(parse_range(Some("bytes=-1000"), 100), RangeAsk::Part(0, 99));
        assert_eq!(
            parse_range(Some("bytes=100-"), 100),
            RangeAsk::Unsatisfiable
        );
        assert_eq!(parse_range(Some("bytes=-0"), 100), RangeAsk::Unsatisfiable);
        assert_eq!(parse_range(Some("bytes=5-2"), 100), RangeAsk::Whole);
        assert_eq!(parse_range(Some("bytes=0-1,5-6"), 100), RangeAsk::Whole);
        assert_eq!(parse_range(Some("items=0-1"), 100), RangeAsk::Whole);
    }
}
