//! S3 artifacts (docs/cluster.md), built only with `--features s3`. Needs the S3-compatible server
//! `tests/s3/run.sh` starts (moto, from the Python package index) and the variables it sets:
//! `ASHLAR_TEST_S3_ENDPOINT`, `ASHLAR_TEST_S3_BUCKET` (created), `ASHLAR_TEST_S3_PYTHON` (a
//! Python with boto3, the independent S3 client) and `AWS_ACCESS_KEY_ID`/`AWS_SECRET_ACCESS_KEY`/
//! `AWS_REGION`. Without them each test prints SKIPPED and passes; `run.sh` fails if they skip.
//!
//! - an `ashlar serve` with `--artifacts s3://BUCKET/PREFIX?endpoint=…&allow_http=true` runs a
//!   job; boto3 finds exactly its artifacts in the bucket, byte for byte the files the run
//!   wrote locally (what the local backend serves);
//! - a second `ashlar serve` on the same job store but its own empty `--data`, configured by
//!   `AWS_ENDPOINT`/`AWS_ALLOW_HTTP` instead of URL options, serves the job's trajectory with
//!   the same SHA-256 and the same histories as the process that ran it; deleting the job there
//!   leaves no object of it in the bucket;
//! - a missing bucket and an unknown URL option stop start-up with a message naming them.
mod service_support;

use ashlar::service::artifacts::ArtifactStore;
use serde_json::{json, Value};
use service_support::*;
use sha2::{Digest, Sha256};
use std::collections::BTreeMap;
use std::io::{BufRead, Read, Write};
use std::path::Path;
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};
use uuid::Uuid;

struct S3 {
    endpoint: String,
    bucket: String,
    python: String,
}

fn s3(test: &str) -> Option<S3> {
    let get = |k: &str| std::env::var(k).ok().filter(|v| !v.is_empty());
    match (
        get("ASHLAR_TEST_S3_ENDPOINT"),
        get("ASHLAR_TEST_S3_BUCKET"),
        get("ASHLAR_TEST_S3_PYTHON"),
    ) {
        (Some(endpoint), Some(bucket), Some(python)) => Some(S3 {
            endpoint,
            bucket,
            python,
        }),
        _ => {
            // Straight to the process's stderr, not through `eprintln!`, which the test harness
            // captures: a plain `cargo test` shows the skip beside the test's "ok".
            let _ = writeln!(
                std::io::stderr(),
                "SKIPPED {test}: no S3 server (run tests/s3/run.sh)"
            );
            None
        }
    }
}

fn sha256(b: &[u8]) -> String {
    Sha256::digest(b)
        .iter()
        .map(|x| format!("{x:02x}"))
        .collect()
}

/// Every object under `prefix/` as boto3 sees it: key (relative) → (size, SHA-256).
fn bucket_listing(s3: &S3, prefix: &str) -> BTreeMap<String, (u64, String)> {
    let script = r#"
import boto3, hashlib, json, os, sys
s3 = boto3.client("s3", endpoint_url=os.environ["ASHLAR_TEST_S3_ENDPOINT"])
bucket, prefix = sys.argv[1], sys.argv[2]
out = {}
for page in s3.get_paginator("list_objects_v2").paginate(Bucket=bucket, Prefix=prefix + "/"):
    for o in page.get("Contents", []):
        body = s3.get_object(Bucket=bucket, Key=o["Key"])["Body"].read()
        out[o["Key"][len(prefix) + 1:]] = [len(body), hashlib.sha256(body).hexdigest()]
print(json.dumps(out))
"#;
    let out = Command::new(&s3.python)
        .args(["-c", script, &s3.bucket, prefix])
        .output()
        .expect("run boto3");
    assert!(
        out.status.success(),
        "boto3 listing failed: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    let v: BTreeMap<String, (u64, String)> =
        serde_json::from_slice(&out.stdout).expect("listing JSON");
    v
}

/// `ashlar serve` with extra arguments and environment; returns the child and its address.
fn serve(data: &Path, args: &[&str], envs: &[(&str, &str)]) -> (Child, String) {
    let mut cmd = Command::new(env!("CARGO_BIN_EXE_ashlar"));
    cmd.args(["serve", "--addr", "127.0.0.1:0", "--data"])
        .arg(data)
        .args(args)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped());
    for (k, v) in envs {
        cmd.env(k, v);
    }
    let mut child = cmd.spawn().expect("spawn ashlar serve");
    let mut line = String::new();
    std::io::BufReader::new(child.stdout.take().expect("stdout"))
        .read_line(&mut line)
        .expect("read the listening line");
    if !line.contains("http://") {
        let _ = child.kill();
        let mut err = String::new();
        if let Some(mut e) = child.stderr.take() {
            let _ = e.read_to_string(&mut err);
        }
        panic!("ashlar serve did not start: {line:?}\n{err}");
    }
    let addr = line
        .trim()
        .rsplit("http://")
        .next()
        .unwrap_or("")
        .to_string();
    (child, addr)
}

fn stop(mut child: Child) {
    let _ = Command::new("kill")
        .args(["-TERM", &child.id().to_string()])
        .status();
    let _ = child.wait();
}

/// GET returning the raw body bytes (MCAP is binary; `service_support::http` is for text).
fn get_bytes(addr: &str, path: &str) -> (u16, Vec<u8>) {
    let mut s = std::net::TcpStream::connect(addr).expect("connect");
    s.set_read_timeout(Some(Duration::from_secs(30))).ok();
    write!(
        s,
        "GET {path} HTTP/1.1\r\nHost: {addr}\r\nConnection: close\r\n\r\n"
    )
    .expect("write");
    let mut raw = Vec::new();
    s.read_to_end(&mut raw).expect("read");
    let split = raw
        .windows(4)
        .position(|w| w == b"\r\n\r\n")
        .expect("end of headers");
    let head = String::from_utf8_lossy(&raw[..split]).to_ascii_lowercase();
    let status = head
        .split_whitespace()
        .nth(1)
        .and_then(|c| c.parse().ok())
        .unwrap_or(0);
    let body = &raw[split + 4..];
    // Streamed artifacts (histories CSV) come chunked: decode, so the bytes compare as sent.
    if head.contains("transfer-encoding: chunked") {
        return (status, dechunk(body, path));
    }
    (status, body.to_vec())
}

/// The payload of a `Transfer-Encoding: chunked` body (RFC 9112 §7.1; no trailers expected).
fn dechunk(mut body: &[u8], path: &str) -> Vec<u8> {
    let mut out = Vec::new();
    loop {
        let line_end = body
            .windows(2)
            .position(|w| w == b"\r\n")
            .unwrap_or_else(|| panic!("chunk size line of {path}"));
        let size_text = String::from_utf8_lossy(&body[..line_end]);
        let size = usize::from_str_radix(size_text.split(';').next().unwrap_or("").trim(), 16)
            .unwrap_or_else(|_| panic!("chunk size {size_text:?} of {path}"));
        body = &body[line_end + 2..];
        if size == 0 {
            return out;
        }
        assert!(body.len() >= size + 2, "truncated chunk of {path}");
        out.extend_from_slice(&body[..size]);
        body = &body[size + 2..];
    }
}

fn wait_succeeded(addr: &str, id: &str) -> Value {
    let start = Instant::now();
    loop {
        let (_, t) = http(addr, "GET", &format!("/v1/jobs/{id}"), None).expect("GET job");
        let j: Value = serde_json::from_str(&t).unwrap_or(Value::Null);
        if is_terminal(&j) {
            assert_eq!(j["status"], "succeeded", "{j}");
            return j;
        }
        assert!(
            start.elapsed() < Duration::from_secs(120),
            "job {id} did not finish: {j}"
        );
        std::thread::sleep(Duration::from_millis(100));
    }
}

#[test]
fn artifacts_round_trip_through_s3() {
    let Some(s3) = s3("artifacts_round_trip_through_s3") else {
        return;
    };
    let root = temp_dir("s3-artifacts");
    let prefix = format!("run-{}", &Uuid::new_v4().simple().to_string()[..8]);
    let url = format!(
        "s3://{}/{prefix}?endpoint={}&allow_http=true",
        s3.bucket, s3.endpoint
    );

    // Process A runs the job and publishes its artifacts to the bucket.
    let (a, a_addr) = serve(
        &root.join("a"),
        &["--workers", "1", "--artifacts", &url],
        &[],
    );
    let body = json!({"scene": column_scene(2.0), "motion": pulse(3.0)});
    let (status, text) = http(&a_addr, "POST", "/v1/jobs", Some(&body.to_string())).expect("POST");
    assert_eq!(status, 202, "{text}");
    let id = serde_json::from_str::<Value>(&text).expect("JSON")["id"]
        .as_str()
        .expect("id")
        .to_string();
    wait_succeeded(&a_addr, &id);
    let (st, a_mcap) = get_bytes(&a_addr, &format!("/v1/jobs/{id}/trajectory.mcap"));
    assert_eq!(st, 200);
    let (st, a_csv) = get_bytes(&a_addr, &format!("/v1/jobs/{id}/histories?format=csv"));
    assert_eq!(st, 200);
    stop(a);

    // The bucket holds exactly the artifacts A wrote, byte for byte (read by boto3).
    let local_dir = root.join("a/jobs").join(&id);
    let mut want = BTreeMap::new();
    for name in ashlar::service::artifacts::ARTIFACT_NAMES {
        if let Ok(b) = std::fs::read(local_dir.join(name)) {
            want.insert(format!("jobs/{id}/{name}"), (b.len() as u64, sha256(&b)));
        }
    }
    for name in ["histories.csv", "trajectory.mcap", "summary.json"] {
        assert!(
            want.contains_key(&format!("jobs/{id}/{name}")),
            "the run left no local {name}"
        );
    }
    let got = bucket_listing(&s3, &prefix);
    assert_eq!(got, want, "bucket content differs from the run's files");
    assert_eq!(
        sha256(&a_mcap),
        want[&format!("jobs/{id}/trajectory.mcap")].1,
        "A serves its local trajectory"
    );

    // Process B: same job store (A's SQLite file), its own empty --data, S3 configured through
    // the environment only. It never ran the job: whatever it serves came from the bucket.
    let db = format!("sqlite:{}", root.join("a/jobs.sqlite").display());
    let plain = format!("s3://{}/{prefix}", s3.bucket);
    let (b, b_addr) = serve(
        &root.join("b"),
        &["--database", &db, "--workers", "1", "--artifacts", &plain],
        &[("AWS_ENDPOINT", &s3.endpoint), ("AWS_ALLOW_HTTP", "true")],
    );
    assert!(
        !root
            .join("b/jobs")
            .join(&id)
            .join("trajectory.mcap")
            .exists(),
        "B must start without the job's files"
    );
    let (st, b_mcap) = get_bytes(&b_addr, &format!("/v1/jobs/{id}/trajectory.mcap"));
    assert_eq!(st, 200);
    let (st, b_csv) = get_bytes(&b_addr, &format!("/v1/jobs/{id}/histories?format=csv"));
    assert_eq!(st, 200);
    // Deleting the job (on B, which never ran it) removes its objects from the bucket.
    let (st, text) = http(&b_addr, "DELETE", &format!("/v1/jobs/{id}"), None).expect("DELETE");
    assert_eq!(st, 204, "{text}");
    let left = bucket_listing(&s3, &prefix);
    assert!(left.is_empty(), "objects outlive DELETE: {left:?}");
    stop(b);
    assert_eq!(
        sha256(&b_mcap),
        sha256(&a_mcap),
        "trajectory served from S3 differs from the local one"
    );
    assert_eq!(
        b_csv, a_csv,
        "histories served from S3 differ from the local ones"
    );
    assert!(
        b_csv.starts_with(b"time_s,column.x_m"),
        "{}",
        String::from_utf8_lossy(&b_csv[..b_csv.len().min(200)])
    );
    std::fs::remove_dir_all(root).ok();
}

#[test]
fn bad_s3_settings_stop_start_up() {
    let Some(s3) = s3("bad_s3_settings_stop_start_up") else {
        return;
    };
    let e = ArtifactStore::open(&format!(
        "s3://no-such-bucket-{}/p?endpoint={}&allow_http=true",
        &Uuid::new_v4().simple().to_string()[..8],
        s3.endpoint
    ))
    .expect_err("a missing bucket is refused at start-up")
    .to_string();
    eprintln!("missing bucket: {e}");
    assert!(
        e.contains("no-such-bucket") && e.contains("not reachable"),
        "{e}"
    );
    let e = ArtifactStore::open(&format!("s3://{}/p?endpont={}", s3.bucket, s3.endpoint))
        .expect_err("a misspelt option is refused")
        .to_string();
    eprintln!("misspelt option: {e}");
    assert!(e.contains("\"endpont\""), "{e}");
    // The secret in a URL option never shows in messages.
    let e = ArtifactStore::open(&format!(
        "s3://no-such-bucket-x/p?endpoint={}&allow_http=true&secret_access_key=hunter2",
        s3.endpoint
    ))
    .expect_err("missing bucket")
    .to_string();
    assert!(!e.contains("hunter2"), "{e}");
}
