//! HTTP layer: a finished run's files, `GET /v1/jobs/{id}/histories` (JSON or streamed CSV,
//! selected blocks, every n-th frame) and `GET /v1/jobs/{id}/trajectory.mcap` (byte ranges),
//! streamed in chunks so that memory stays one chunk per response.
use super::problem::ApiError;
use super::state::{blocking, load, parse_id, ApiResult, AppState};
use crate::service::auth::Access;
use crate::service::histories::Histories;
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
pub const MAX_JSON_HISTORY_BYTES: u64 = 32 << 20;

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
    let j = load(&s, &access, id, JobKind::Run).await?;
    artifact_available(&j, "histories")?;
    ensure_local(&s.core, id, "histories.csv").await;
    let path = s.core.job_dir(id).join("histories.csv");
    let file = match tokio::fs::File::open(&path).await {
        Ok(f) => f,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => {
            return Err(ApiError::conflict(
                "the job finished without recording histories",
            ));
        }
        Err(e) => return Err(ApiError::internal(format!("{}: {e}", path.display()))),
    };
    let size = file
        .metadata()
        .await
        .map_err(|e| ApiError::internal(format!("{}: {e}", path.display())))?
        .len();
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
            let mut text = header.clone();
            let mut lines = reader.lines();
            let mut row = 0u64;
            while let Some(line) = lines
                .next_line()
                .await
                .map_err(|e| ApiError::internal(format!("{}: {e}", path.display())))?
            {
                if line.trim().is_empty() {
                    continue;
                }
                if row % every == 0 {
                    text.push_str(&line);
                    text.push('\n');
                }
                row += 1;
            }
            let json = blocking(move || {
                let h = Histories::parse_csv(&text)?;
                let h = h
                    .select(&blocks)
                    .map_err(|b| format!("block {b:?} vanished"))?;
                Ok::<_, String>(h.to_json())
            })
            .await?
            .map_err(ApiError::internal)?;
            Ok(axum::Json(json).into_response())
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
    let j = load(&s, &access, id, JobKind::Run).await?;
    artifact_available(&j, "trajectory")?;
    ensure_local(&s.core, id, "trajectory.mcap").await;
    let path = s.core.job_dir(id).join("trajectory.mcap");
    let file = match tokio::fs::File::open(&path).await {
        Ok(f) => f,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => {
            return Err(ApiError::conflict(
                "the job finished without recording a trajectory",
            ));
        }
        Err(e) => return Err(ApiError::internal(format!("{}: {e}", path.display()))),
    };
    let len = file
        .metadata()
        .await
        .map_err(|e| ApiError::internal(format!("{}: {e}", path.display())))?
        .len();
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
