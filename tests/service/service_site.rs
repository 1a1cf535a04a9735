//! Site analyses through the service (`POST /v1/site-analyses`, docs/observations.md) on the
//! real engine: the stored result is exactly what `analysis::observations::site_analysis` gives
//! for the same scene, records and observations (the service adds plumbing, not physics: the
//! physics is checked in tests/analysis/site_observations.rs and site_distribution.rs);
//! progress streams and never goes back; a running analysis is cancellable; bad requests are
//! 422 problems naming the field, and work over the budget is refused at submission.
use crate::service_support;

use ashlar::analysis::observations::{site_analysis, Observation};
use ashlar::analysis::pga::{Combine, Criterion, PgaRequest};
use ashlar::service::{Limits, Service};
use serde_json::{json, Value};
use service_support::*;
use std::time::Duration;

fn start(tag: &str, limits: Limits) -> (Service, axum::Router, std::path::PathBuf) {
    start_analysis(tag, limits)
}

/// The bundled two columns (A slender, B stocky; docs/observations.md), `duration` s a run.
fn two_columns(duration: f64) -> Value {
    let text = std::fs::read_to_string(
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("examples/two-columns.json"),
    )
    .expect("examples/two-columns.json");
    let mut s: Value = serde_json::from_str(&text).expect("scene JSON");
    s["control"]["duration"] = json!(duration);
    s
}

fn body(duration: f64) -> Value {
    json!({
        "scene": two_columns(duration),
        "motions": [half_sine(0.5, "T = 0.5 s"), half_sine(0.7, "T = 0.7 s")],
        "observations": [
            {"criterion": {"kind": "fallen", "blocks": ["A"]}, "observed": true},
            {"criterion": "toppled:B", "observed": false}
        ],
        "range": {"min": 2.0, "max": 14.0, "units": "m/s2"},
        "tolerance": 0.25,
        "scan_points": 4
    })
}

fn progress_of(text: &str) -> Vec<f64> {
    text.split("\n\n")
        .filter_map(|b| b.lines().find_map(|l| l.strip_prefix("data:")))
        .filter_map(|d| serde_json::from_str::<Value>(d.trim()).ok())
        .filter_map(|e| e["progress"].as_f64())
        .collect()
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_site_analysis_runs_as_a_job_and_matches_the_library() {
    let (svc, app, dir) = start("site", Limits::default());
    let b = body(2.0);
    let r = call(&app, post_json("/v1/site-analyses", &b)).await;
    assert_eq!(r.status, 202, "{}", r.text());
    let accepted = r.json();
    assert_eq!(accepted["kind"], "site_analysis");
    let id = accepted["id"].as_str().expect("id").to_string();
    let uri = format!("/v1/site-analyses/{id}");
    assert_eq!(r.header("location").as_deref(), Some(uri.as_str()));
    assert_eq!(accepted["links"]["events"], format!("{uri}/events"));
    // Not served as a run or a PGA search.
    call(&app, get(&format!("/v1/pga-searches/{id}")))
        .await
        .problem(404);
    call(&app, get(&format!("/v1/jobs/{id}")))
        .await
        .problem(404);

    let stream = call(&app, get(&format!("{uri}/events"))).await;
    assert_eq!(stream.status, 200);
    let p = progress_of(&stream.text());
    assert!(p.windows(2).all(|w| w[0] <= w[1]), "monotonic: {p:?}");
    let j = wait_for(&app, &uri, Duration::from_secs(300), is_terminal).await;
    assert_eq!(j["status"], "succeeded", "{j}");
    assert_eq!(j["kind"], "site_analysis");
    assert_eq!(j["motion"]["records"].as_array().map(Vec::len), Some(2));
    let res = &j["result"];

    // The same analysis through the library, directly.
    let scene = ashlar::scene::scene_from_value(&b["scene"]).expect("scene");
    let records: Vec<(String, ashlar::motion::GroundMotion)> = b["motions"]
        .as_array()
        .expect("motions")
        .iter()
        .map(|m| {
            let mut m = m.clone();
            let name = m
                .as_object_mut()
                .and_then(|o| o.remove("name"))
                .and_then(|n| n.as_str().map(str::to_string))
                .expect("name");
            let gm = ashlar::motion::from_json(&m).expect("ground motion");
            (name, gm)
        })
        .collect();
    let observations = vec![
        Observation {
            criterion: Criterion::parse(r#"{"kind": "fallen", "blocks": ["A"]}"#).expect("c"),
            observed: true,
        },
        Observation {
            criterion: Criterion::parse("toppled:B").expect("c"),
            observed: false,
        },
    ];
    let base = PgaRequest {
        criteria: Vec::new(),
        combine: Combine::All,
        min: 2.0,
        max: 14.0,
        tolerance: 0.25,
        scan_points: 4,
        resolution: None,
        scan: ashlar::analysis::pga::ScanOrder::Full,
    };
    let direct = site_analysis(&scene, &records, &observations, &base, &Default::default())
        .expect("library");
    // Through text and the same parser as the reply (serde_json's default float parsing may
    // move a number by one ULP, the same way on both sides): equal texts compare equal.
    let direct: Value =
        serde_json::from_str(&serde_json::to_string(&direct).expect("json")).expect("parse");
    assert_eq!(res, &direct, "the service's result is the library's");

    // What the result states, read as a user would.
    let recs = res["records"].as_array().expect("records");
    assert_eq!(recs.len(), 2);
    assert_eq!(recs[0]["record"], "T = 0.5 s");
    for rec in recs {
        let (lo, hi) = (
            rec["lower"].as_f64().expect("lower"),
            rec["upper"].as_f64().expect("upper"),
        );
        let seen = &rec["observations"][0];
        let unseen = &rec["observations"][1];
        assert_eq!(seen["observed"], true);
        assert_eq!(Some(lo), seen["safe_pga"].as_f64(), "{rec}");
        if let Some(f) = unseen["failing_pga"].as_f64() {
            assert_eq!(hi, f, "{rec}");
        }
        assert_eq!(rec["consistent"], lo < hi, "{rec}");
    }
    let d = &res["distribution"];
    assert!(d["assumes"]
        .as_str()
        .is_some_and(|a| a.contains("independent given the PGA")));
    assert_eq!(d["range"], json!([2.0, 14.0]));
    assert_eq!(d["criteria"].as_array().map(Vec::len), Some(2));
    if let Some(e) = d["empirical"].as_object() {
        let m = e["median"].as_f64().expect("median");
        assert!((2.0..=14.0).contains(&m), "{m}");
    } else {
        assert!(d["empirical_error"].is_string(), "{d}");
    }
    // Listed by kind, and deletable once finished.
    let list = call(&app, get("/v1/jobs?kind=site_analysis")).await.json();
    assert_eq!(list["jobs"].as_array().map(Vec::len), Some(1), "{list}");
    let del = call(
        &app,
        axum::http::Request::builder()
            .method("DELETE")
            .uri(&uri)
            .body(axum::body::Body::empty())
            .expect("request"),
    )
    .await;
    assert_eq!(del.status, 204, "{}", del.text());
    call(&app, get(&uri)).await.problem(404);
    svc.shutdown(Duration::ZERO);
    std::fs::remove_dir_all(dir).ok();
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_running_site_analysis_is_cancellable() {
    let (svc, app, dir) = start("site-cancel", Limits::default());
    let mut b = body(60.0);
    b["tolerance"] = json!(0.001);
    let uri = submit_and_cancel_when_running(&app, "/v1/site-analyses", &b).await;
    let j = wait_for(&app, &uri, Duration::from_secs(60), is_terminal).await;
    assert_eq!(j["status"], "cancelled", "{j}");
    assert!(j["result"].is_null(), "{j}");
    svc.shutdown(Duration::ZERO);
    std::fs::remove_dir_all(dir).ok();
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn bad_site_analyses_name_the_field_and_the_budget_is_checked_at_submission() {
    let limits = Limits {
        max_search_block_steps: 2_000_000,
        ..Limits::default()
    };
    let (svc, app, dir) = start("site-bad", limits);
    let check = |body: Value, want: &'static str| {
        let app = app.clone();
        async move {
            let r = call(&app, post_json("/v1/site-analyses", &body)).await;
            let p = r.problem(422);
            let got = p["errors"][0]["pointer"]
                .as_str()
                .or_else(|| p["pointer"].as_str())
                .map(str::to_string);
            assert_eq!(got.as_deref(), Some(want), "{p}");
            assert!(p["detail"].as_str().unwrap_or("").contains(want), "{p}");
            p
        }
    };
    let small = || {
        let mut b = body(1.0);
        b["tolerance"] = json!(3.0);
        b["scan_points"] = json!(2);
        b
    };
    let mut b = small();
    b["observations"] = json!([]);
    check(b, "/observations").await;
    let mut b = small();
    b["observations"][1]["criterion"] = json!("toppled:base");
    check(b, "/observations/1/criterion").await;
    let mut b = small();
    b["observations"][0]["observed"] = json!("fell");
    check(b, "/observations/0/observed").await;
    let mut b = small();
    b["observations"][0]["seen"] = json!(true);
    check(b, "/observations/0/seen").await;
    let mut b = small();
    b["observations"][0]["criterion"] = json!(["toppled:A", "toppled:B"]);
    check(b, "/observations/0/criterion").await;
    let mut b = small();
    b["motions"] = json!([]);
    check(b, "/motions").await;
    let mut b = small();
    b["motions"][1]["horizontal"]["pulse"]["period"] = json!(-1.0);
    let p = call(&app, post_json("/v1/site-analyses", &b))
        .await
        .problem(422);
    assert!(p.to_string().contains("/motions/1"), "{p}");
    let mut b = small();
    b["range"]["max"] = json!(1.0);
    check(b, "/range/max").await;
    let mut b = small();
    b["scan_points"] = json!(1);
    check(b, "/scan_points").await;
    // 2 observations × 2 records × (2 scan points + 2 bisections) runs × 3 blocks × 1000
    // steps = 48 000 block-steps fits 2e6; at 60 s (60 000 steps) it is 2.9e6: refused, before
    // anything is queued.
    let r = call(&app, post_json("/v1/site-analyses", &small())).await;
    assert_eq!(r.status, 202, "{}", r.text());
    let mut b = small();
    b["scene"]["control"]["duration"] = json!(60.0);
    let p = check(b, "/scan_points").await;
    assert_eq!(
        p["type"].as_str().map(|t| t.ends_with("limit-exceeded")),
        Some(true),
        "{p}"
    );
    svc.shutdown(Duration::ZERO);
    std::fs::remove_dir_all(dir).ok();
}
