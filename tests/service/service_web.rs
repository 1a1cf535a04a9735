//! The endpoints of the web page (docs/web.md), through the router without a socket: the page and
//! its assets, the bundled examples, record inspection (checked against closed forms and against
//! `ashlar motion` reading the same file), the job list, and a run's geometry and ground motion.
use crate::service_support;

use ashlar::cli::motion::{report_json, MotionArgs};
use ashlar::service::fake::fake_runner;
use ashlar::service::{app, Service, ServiceConfig, WorkerParams};
use serde_json::{json, Value};
use service_support::*;
use std::f64::consts::PI;
use std::path::PathBuf;
use std::time::Duration;

fn start(tag: &str, job_time: Duration) -> (Service, axum::Router, PathBuf) {
    let dir = temp_dir(tag);
    let mut cfg = ServiceConfig::new(&dir);
    cfg.workers = WorkerParams {
        workers: 1,
        ..WorkerParams::default()
    };
    let svc = Service::start(cfg, fake_runner(job_time)).expect("start");
    let router = app(svc.state());
    (svc, router, dir)
}

fn fixture(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("data/ground-motions")
        .join(name)
}

fn f(v: &Value) -> f64 {
    v.as_f64().unwrap_or_else(|| panic!("not a number: {v}"))
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn page_assets_and_examples_are_served_from_the_binary() {
    let (svc, router, dir) = start("web-assets", Duration::from_millis(1));
    let r = call(&router, get("/")).await;
    assert_eq!(r.status, 200);
    assert_eq!(
        r.header("content-type").as_deref(),
        Some("text/html; charset=utf-8")
    );
    let html = r.text();
    for needle in [
        "id=\"anim\"",
        "/assets/app.js",
        "/assets/plot.js",
        "/assets/app.css",
    ] {
        assert!(html.contains(needle), "the page lacks {needle}");
    }
    // No asset is fetched from another host (the page must work offline).
    assert!(
        !html.contains("http://") && !html.contains("//cdn"),
        "{html}"
    );
    for (name, ct) in [
        ("app.js", "text/javascript; charset=utf-8"),
        ("plot.js", "text/javascript; charset=utf-8"),
        ("app.css", "text/css; charset=utf-8"),
    ] {
        let r = call(&router, get(&format!("/assets/{name}"))).await;
        assert_eq!(r.status, 200, "{name}");
        assert_eq!(r.header("content-type").as_deref(), Some(ct), "{name}");
        assert!(!r.body.is_empty(), "{name}");
    }
    let p = call(&router, get("/assets/secret.txt")).await.problem(404);
    assert_eq!(p["parameter"], "name");

    let list = call(&router, get("/v1/examples")).await.json();
    let names: Vec<&str> = list["examples"]
        .as_array()
        .expect("examples")
        .iter()
        .map(|e| e["name"].as_str().expect("name"))
        .collect();
    assert!(names.contains(&"column") && names.contains(&"half-sine-pulse"));
    let col = call(&router, get("/v1/examples/column")).await.json();
    let on_disk: Value = serde_json::from_str(
        &std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/examples/column.json"))
            .expect("examples/column.json"),
    )
    .expect("json");
    assert_eq!(
        col, on_disk,
        "the bundled example is the file of the repository"
    );
    // Every JSON example of the repository is bundled, byte for byte the same value (the page
    // lists them; a new example file not added to web.rs's table fails here).
    let dir_ex = concat!(env!("CARGO_MANIFEST_DIR"), "/examples");
    for entry in std::fs::read_dir(dir_ex).expect("examples/") {
        let path = entry.expect("entry").path();
        if path.extension().and_then(|e| e.to_str()) != Some("json") {
            continue;
        }
        let stem = path.file_stem().and_then(|s| s.to_str()).expect("name");
        assert!(names.contains(&stem), "examples/{stem}.json is not bundled");
        let served = call(&router, get(&format!("/v1/examples/{stem}")))
            .await
            .json();
        let on_disk: Value =
            serde_json::from_str(&std::fs::read_to_string(&path).expect("read")).expect("json");
        assert_eq!(served, on_disk, "{stem}");
    }
    call(&router, get("/v1/examples/nope")).await.problem(404);
    svc.shutdown(Duration::ZERO);
    std::fs::remove_dir_all(dir).ok();
}

/// A half-sine pulse has closed-form peaks: PGA = A, PGV = ∫₀^{T/2} A sin(2πt/T) dt = A·T/π
/// (reached at the end of the pulse), and the displacement keeps growing after it.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn inspect_matches_closed_forms_of_a_pulse() {
    let (svc, router, dir) = start("web-inspect-pulse", Duration::from_millis(1));
    let (a, t) = (5.0, 1.0);
    let body = json!({"horizontal": {"pulse": {"shape": "sine", "amplitude": a, "period": t, "cycles": 0.5, "units": "m/s2"}}});
    let r = call(&router, post_json("/v1/motions/inspect", &body)).await;
    assert_eq!(r.status, 200, "{}", r.text());
    let im = r.json();
    // The pulse is evaluated exactly on a 1 ms grid that contains its crest (t = 0.25 s) and its
    // end (t = 0.5 s): both peaks are exact up to round-off (1e-12 relative).
    assert!((f(&im["pga"]) - a).abs() < 1e-12 * a, "{}", im["pga"]);
    let pgv = a * t / PI;
    assert!((f(&im["pgv"]) - pgv).abs() < 1e-12 * pgv, "{}", im["pgv"]);
    assert_eq!(f(&im["scale"]), 1.0);
    let n = im["series"]["time"].as_array().expect("series").len();
    assert_eq!(n, im["series"]["acceleration"].as_array().expect("a").len());
    assert!(n > 100, "{n} points");
    for (tv, av) in im["series"]["time"]
        .as_array()
        .expect("t")
        .iter()
        .zip(im["series"]["acceleration"].as_array().expect("a"))
    {
        let want = if f(tv) <= t / 2.0 {
            a * (2.0 * PI * f(tv) / t).sin()
        } else {
            0.0
        };
        assert!((f(av) - want).abs() < 1e-9, "a({tv}) = {av}, want {want}");
    }
    // Scaled to a target PGA: the factor is target / peak and every measure follows.
    let mut scaled = body.clone();
    scaled["scale"] = json!({"target_pga": 2.5, "units": "m/s2"});
    let im2 = call(&router, post_json("/v1/motions/inspect", &scaled))
        .await
        .json();
    assert!((f(&im2["pga"]) - 2.5).abs() < 1e-12);
    assert!((f(&im2["scale"]) - 0.5).abs() < 1e-15);
    assert!((f(&im2["pgv"]) - pgv / 2.0).abs() < 1e-12);
    svc.shutdown(Duration::ZERO);
    std::fs::remove_dir_all(dir).ok();
}

/// The page shows what `ashlar motion` prints: the same record sent as JSON text must give the
/// same numbers as the CLI reading the file (two entry points, one contract).
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn inspect_agrees_with_ashlar_motion_on_a_real_record() {
    let (svc, router, dir) = start("web-inspect-at2", Duration::from_millis(1));
    let path = fixture("friuli-1976-tolmezzo-000.at2");
    let content = std::fs::read_to_string(&path).expect("record");
    let body =
        json!({"horizontal": {"format": "at2", "content": content}, "scale": {"factor": 1.5}});
    let r = call(&router, post_json("/v1/motions/inspect", &body)).await;
    assert_eq!(r.status, 200, "{}", r.text());
    let im = r.json();
    let cli: Value = serde_json::from_str(
        &report_json(&MotionArgs {
            record: path,
            svg: None,
            record_options: ashlar::motion::RecordArgs {
                scale: Some(1.5),
                ..Default::default()
            },
            highpass: None,
            order: 4,
            baseline: "none".into(),
            damping: 0.05,
        })
        .expect("ashlar motion"),
    )
    .expect("json");
    for key in crate::common::MOTION_REPORT_FIELDS {
        assert_eq!(im[key], cli[key], "{key}");
    }
    // The README's table: Friuli Tolmezzo 000 has PGA 0.351 g; scaled by 1.5.
    let pga_g = f(&im["pga"]) / 9.80665;
    assert!((pga_g - 1.5 * 0.351).abs() < 0.0015, "PGA {pga_g} g");
    // 7269 samples: the series is thinned to the default 4000 intervals, never finer.
    assert_eq!(im["series"]["time"].as_array().expect("t").len(), 4001);
    svc.shutdown(Duration::ZERO);
    std::fs::remove_dir_all(dir).ok();
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn inspect_errors_name_the_field() {
    let (svc, router, dir) = start("web-inspect-errors", Duration::from_millis(1));
    let inspect = |body: Value| {
        let router = router.clone();
        async move { call(&router, post_json("/v1/motions/inspect", &body)).await }
    };
    // A damaged AT2: the pointer names the content and the detail the line.
    let content =
        std::fs::read_to_string(fixture("northridge-1994-mulholland-009.at2")).expect("record");
    let mut lines: Vec<String> = content.lines().map(str::to_string).collect();
    lines[9] = "0.001 oops 0.002".into();
    let bad = json!({"horizontal": {"format": "at2", "content": lines.join("\n")}});
    let p = inspect(bad).await.problem(422);
    assert_eq!(p["pointer"], "/horizontal/content");
    assert!(
        p["detail"].as_str().expect("detail").contains("line 10"),
        "{p}"
    );
    let p = inspect(json!({"horizontal": {"pulse": {"amplitude": 1, "period": 1, "colour": 3}}}))
        .await
        .problem(422);
    assert_eq!(p["pointer"], "/horizontal/pulse/colour", "{p}");
    let p = inspect(json!({"horizontal": {"pulse": {"amplitude": 1, "period": 1}, "dt": 0.1}}))
        .await
        .problem(422);
    assert_eq!(p["pointer"], "/horizontal/dt", "{p}");
    let p =
        inspect(json!({"horizontal": {"format": "csv", "content": "0,1\n0.1,2\n", "units": null}}))
            .await
            .problem(422);
    assert_eq!(p["pointer"], "/horizontal/units", "{p}");
    let p = inspect(json!({"horizontal": {"pulse": {"amplitude": 1, "period": -1}}}))
        .await
        .problem(422);
    // The range check (docs/format.md "Ranges") names the member itself.
    assert_eq!(p["pointer"], "/horizontal/pulse/period", "{p}");
    let p = inspect(json!({"vertical": {"sine": {"amplitude": 1, "frequency": 2}}}))
        .await
        .problem(422);
    assert_eq!(p["pointer"], "/horizontal", "{p}");
    let p = inspect(
        json!({"horizontal": {"samples": [1.0, -2.0], "dt": 0.01}, "scale": {"factor": 1e308}}),
    )
    .await
    .problem(422);
    assert_eq!(p["pointer"], "/scale", "{p}");
    let p = inspect(json!({"horizontal": {"pulse": {"amplitude": 1, "period": 1, "cycles": 1e9}}}))
        .await
        .problem(422);
    assert_eq!(p["pointer"], "/horizontal/pulse/cycles", "{p}");
    assert_eq!(p["type"], "urn:ashlar:problem:limit-exceeded");
    // Many samples at a coarse step would make the spectrum's substeps explode: refused.
    let p = inspect(json!({"horizontal": {"samples": vec![0.1; 200_000], "dt": 10.0}}))
        .await
        .problem(422);
    assert_eq!(p["pointer"], "/horizontal", "{p}");
    let p = inspect(json!([1, 2])).await.problem(422);
    assert_eq!(p["pointer"], "");
    let r = call(
        &router,
        post_raw("/v1/motions/inspect", "application/json", "{nope"),
    )
    .await;
    r.problem(400);
    let r = call(&router, post_raw("/v1/motions/inspect", "text/plain", "{}")).await;
    r.problem(415);
    let r = call(
        &router,
        post_json(
            "/v1/motions/inspect?points=0",
            &json!({"horizontal": {"sine": {"amplitude": 1, "frequency": 1}}}),
        ),
    )
    .await;
    assert_eq!(r.problem(400)["parameter"], "points");
    svc.shutdown(Duration::ZERO);
    std::fs::remove_dir_all(dir).ok();
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn jobs_are_listed_newest_first_and_filtered() {
    let (svc, router, dir) = start("web-list", Duration::from_millis(1));
    let empty = call(&router, get("/v1/jobs")).await;
    assert_eq!(empty.status, 200);
    assert_eq!(empty.json(), json!({"jobs": []}));
    let mut ids = Vec::new();
    for amp in [1.0, 2.0, 3.0] {
        let r = call(
            &router,
            post_json(
                "/v1/jobs",
                &json!({"scene": column_scene(0.5), "motion": pulse(amp)}),
            ),
        )
        .await;
        assert_eq!(r.status, 202, "{}", r.text());
        ids.push(r.json()["id"].as_str().expect("id").to_string());
    }
    let search = json!({"scene": column_scene(0.5), "motion": pulse(1.0), "criterion": "toppled:column",
                        "range": {"min": 0.1, "max": 10.0, "units": "m/s2"}});
    let r = call(&router, post_json("/v1/pga-searches", &search)).await;
    assert_eq!(r.status, 202, "{}", r.text());
    let sid = r.json()["id"].as_str().expect("id").to_string();

    let all = call(&router, get("/v1/jobs")).await.json();
    let listed: Vec<&str> = all["jobs"]
        .as_array()
        .expect("jobs")
        .iter()
        .map(|j| j["id"].as_str().expect("id"))
        .collect();
    assert_eq!(listed, vec![&sid, &ids[2], &ids[1], &ids[0]]);
    // Each item is what the job's own URL answers (status aside, which may move on).
    let one = &all["jobs"][1];
    let direct = call(&router, get(&format!("/v1/jobs/{}", ids[2])))
        .await
        .json();
    for k in ["id", "kind", "created_at", "motion", "links"] {
        assert_eq!(one[k], direct[k], "{k}");
    }
    assert!(all["jobs"][0].get("result").is_some() && one.get("summary").is_some());

    let runs = call(&router, get("/v1/jobs?kind=run&limit=2")).await.json();
    let got: Vec<&str> = runs["jobs"]
        .as_array()
        .expect("jobs")
        .iter()
        .map(|j| j["id"].as_str().expect("id"))
        .collect();
    assert_eq!(got, vec![&ids[2], &ids[1]]);
    let searches = call(&router, get("/v1/jobs?kind=pga_search")).await.json();
    assert_eq!(searches["jobs"].as_array().expect("jobs").len(), 1);
    for bad in ["limit=0", "limit=501", "limit=x", "kind=study"] {
        let r = call(&router, get(&format!("/v1/jobs?{bad}"))).await;
        let p = r.problem(400);
        assert_eq!(p["parameter"], bad.split('=').next().expect("name"));
    }
    svc.shutdown(Duration::ZERO);
    std::fs::remove_dir_all(dir).ok();
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_runs_geometry_and_ground_motion() {
    let (svc, router, dir) = start("web-scene", Duration::from_millis(1));
    let (amp, period) = (3.0, 0.4);
    let r = call(
        &router,
        post_json(
            "/v1/jobs",
            &json!({"scene": column_scene(1.0), "motion": pulse(amp)}),
        ),
    )
    .await;
    let id = r.json()["id"].as_str().expect("id").to_string();
    let geo = call(&router, get(&format!("/v1/jobs/{id}/scene")))
        .await
        .json();
    assert_eq!(geo["excitation"]["type"], "base_acceleration");
    let blocks = geo["blocks"].as_array().expect("blocks");
    assert_eq!(blocks.len(), 2);
    assert_eq!(blocks[0]["id"], "plinth");
    assert_eq!(blocks[0]["fixed"], true);
    // The 0.4 × 1.2 m column standing on y = 0: area 0.48 m², centroid (0, 0.6) (exact in
    // binary floating point up to round-off of the polygon sums).
    let col = &blocks[1];
    assert_eq!(col["fixed"], false);
    assert!((f(&col["area"]) - 0.48).abs() < 1e-12);
    assert!(f(&col["centroid"][0]).abs() < 1e-12);
    assert!((f(&col["centroid"][1]) - 0.6).abs() < 1e-12);
    assert_eq!(geo["bounds"]["min"], json!([-1.0, -0.5]));
    assert_eq!(geo["bounds"]["max"], json!([1.0, 1.2]));

    let g = call(&router, get(&format!("/v1/jobs/{id}/ground?points=100")))
        .await
        .json();
    let time = g["time"].as_array().expect("time");
    assert_eq!(time.len(), 101, "100 intervals over the 1 s run");
    assert_eq!(f(&time[100]), 1.0);
    assert!((f(&g["pga"]) - amp).abs() < 1e-12);
    assert!(g["vertical_acceleration"].is_null());
    // Closed forms of the half-sine pulse a = A sin(ωt), 0 ≤ t ≤ T/2: after it the ground moves
    // at v = 2A/ω and its displacement grows by v·(t − T/2) from d(T/2) = A·T/(2ω).
    let w = 2.0 * PI / period;
    for (i, tv) in time.iter().enumerate() {
        let t = f(tv);
        let (a, v, d) = if t <= period / 2.0 {
            (
                amp * (w * t).sin(),
                amp / w * (1.0 - (w * t).cos()),
                amp / w * t - amp / (w * w) * (w * t).sin(),
            )
        } else {
            let v_end = 2.0 * amp / w;
            (
                0.0,
                v_end,
                amp / w * period / 2.0 + v_end * (t - period / 2.0),
            )
        };
        assert!((f(&g["acceleration"][i]) - a).abs() < 1e-9, "a({t})");
        assert!((f(&g["velocity"][i]) - v).abs() < 1e-9, "v({t})");
        assert!((f(&g["displacement"][i]) - d).abs() < 1e-9, "d({t})");
    }
    let p = call(&router, get(&format!("/v1/jobs/{id}/ground?points=-3")))
        .await
        .problem(400);
    assert_eq!(p["parameter"], "points");
    let other = uuid::Uuid::new_v4();
    call(&router, get(&format!("/v1/jobs/{other}/scene")))
        .await
        .problem(404);
    call(&router, get(&format!("/v1/jobs/{other}/ground")))
        .await
        .problem(404);
    svc.shutdown(Duration::ZERO);
    std::fs::remove_dir_all(dir).ok();
}

/// `ashlar serve` wrote its log with ANSI colour codes to a file (`2> server.log` was full of
/// `ESC[2m…`): colours are for a terminal only. The real binary, its stderr to a file, must log
/// plain text (and log at all: the check is void on an empty log).
#[test]
fn server_log_to_a_file_has_no_colour_codes() {
    use std::io::BufRead;
    let dir = temp_dir("web-plain-log");
    let log_path = dir.join("server.log");
    let log = std::fs::File::create(&log_path).expect("create the log file");
    let mut child = std::process::Command::new(env!("CARGO_BIN_EXE_ashlar"))
        .args(["serve", "--addr", "127.0.0.1:0", "--workers", "1", "--data"])
        .arg(dir.join("data"))
        .env_remove("RUST_LOG")
        .stdout(std::process::Stdio::piped())
        .stderr(log)
        .spawn()
        .expect("spawn ashlar serve");
    // Held open until the server has exited: it writes to stdout on shutdown too.
    let mut stdout = std::io::BufReader::new(child.stdout.take().expect("stdout"));
    let mut line = String::new();
    stdout
        .read_line(&mut line)
        .expect("read the listening line");
    assert!(line.contains("listening on"), "first line {line:?}");
    let status = std::process::Command::new("kill")
        .args(["-TERM", &child.id().to_string()])
        .status()
        .expect("kill -TERM");
    assert!(status.success());
    let mut rest = String::new();
    std::io::Read::read_to_string(&mut stdout, &mut rest).expect("read stdout");
    let exit = child.wait().expect("wait");
    assert!(exit.success(), "ashlar serve: {exit}, stdout {rest:?}");
    let text = std::fs::read(&log_path).expect("read the log");
    let shown = String::from_utf8_lossy(&text);
    assert!(shown.contains("listening"), "no log line: {shown:?}");
    assert!(!text.contains(&0x1b), "ESC in the log: {shown:?}");
    let _ = std::fs::remove_dir_all(&dir);
}
