//! Damage criteria in `POST /v1/pga-searches` and `POST /v1/jobs` (docs/format.md §3 "Damage criteria";
//! docs/service.md): a criterion is a string or a damage object, in single-record searches and
//! in fragility studies (`motions`), and a submission naming blocks that are not free blocks of
//! the scene is refused at once with one 422 that names every such block (before, only the
//! first criterion's first block was checked there and the others failed the job later).
use crate::service_support;

use serde_json::json;
use service_support::*;
use std::time::Duration;

fn start(tag: &str) -> (ashlar::service::Service, axum::Router, std::path::PathBuf) {
    service_support::start_fake(tag)
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn site_criteria_as_objects_are_accepted_and_every_missing_block_is_named() {
    let (svc, router, dir) = start("criteria");
    let damage = json!({"kind": "fallen", "blocks": ["column"]});
    let body = json!({"scene": column_scene(1.0), "motion": pulse(1.0), "criterion": damage,
                      "range": {"min": 0.0, "max": 1.0, "units": "g"}});
    let r = call(&router, post_json("/v1/pga-searches", &body)).await;
    assert_eq!(r.status, 202, "{}", r.text());
    // A fragility study (several records) with a damage object among strings.
    let study = json!({"scene": column_scene(1.0), "motions": [pulse(1.0), pulse(2.0)],
                       "criterion": ["toppled:column", {"kind": "rotation", "block": "column", "degrees": 10}],
                       "range": {"min": 0.0, "max": 1.0, "units": "g"}});
    let r = call(&router, post_json("/v1/pga-searches", &study)).await;
    assert_eq!(r.status, 202, "{}", r.text());

    // Three missing blocks in two criteria, and a fixed one: all four named, the pointer at
    // the first criterion that names one.
    let mut bad = body.clone();
    bad["criterion"] = json!([
        "toppled:column",
        {"kind": "any", "of": [{"kind": "fallen", "blocks": ["drum1", "column", "drum2"]}]},
        {"kind": "relative_sliding", "blocks": ["plinth", "capital"], "metres": 0.03}
    ]);
    let p = call(&router, post_json("/v1/pga-searches", &bad))
        .await
        .problem(422);
    assert_eq!(p["pointer"], "/criterion/1", "{p}");
    let detail = p["detail"].as_str().unwrap_or_default();
    for named in [
        "/criterion/1: \"drum1\"",
        "/criterion/1: \"drum2\"",
        "/criterion/2: \"plinth\"",
        "/criterion/2: \"capital\"",
        "(4 in all)",
    ] {
        assert!(detail.contains(named), "{named} missing from {detail}");
    }
    assert!(!detail.contains("\"column\""), "{detail}");
    // A damage object with a bad field names its path; neither a string nor an object is a 422.
    bad["criterion"] = json!({"kind": "drop", "block": "column", "metres": -1});
    let p = call(&router, post_json("/v1/pga-searches", &bad))
        .await
        .problem(422);
    assert_eq!(p["pointer"], "/criterion", "{p}");
    assert!(
        p["detail"].as_str().unwrap_or_default().contains("metres"),
        "{p}"
    );
    bad["criterion"] = json!({"kind": "dropped", "block": "column"});
    call(&router, post_json("/v1/pga-searches", &bad))
        .await
        .problem(422);
    bad["criterion"] = json!(3);
    call(&router, post_json("/v1/pga-searches", &bad))
        .await
        .problem(422);
    bad["criterion"] = json!([]);
    call(&router, post_json("/v1/pga-searches", &bad))
        .await
        .problem(422);
    svc.shutdown(Duration::ZERO);
    std::fs::remove_dir_all(dir).ok();
}

/// A run's `criterion` (`POST /v1/jobs`, as `ashlar run --criterion`), judged on the finished
/// run by the real engine. Reference: docs/observations.md's two columns under the half-sine
/// pulse of period 1 s, whose thresholds were searched to 0.02 m/s² (A falls from 5.64 m/s², B
/// from 8.60 m/s², both monotonic; A's is Housner's amplitude, checked by an independent RK4 in
/// tests/engine/rocking.rs): at 7 m/s², 1.4 m/s² clear of both, A falls and B stands.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_runs_criteria_are_judged_on_its_summary() {
    let (svc, router, dir) = start_analysis("run-criteria", ashlar::service::Limits::default());
    let read = |name: &str| -> serde_json::Value {
        let p = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join(name);
        serde_json::from_str(&std::fs::read_to_string(p).expect("read")).expect("json")
    };
    let mut motion = read("examples/half-sine-pulse.json");
    motion["scale"] = json!({"target_pga": 7.0});
    let criteria = json!([
        "toppled:A",
        {"kind": "fallen", "blocks": ["B"]},
        {"kind": "not", "of": {"kind": "fallen", "blocks": ["B"]}}
    ]);
    let body = json!({"scene": read("examples/two-columns.json"), "motion": motion, "criterion": criteria});
    let (_, j) = submit_and_wait(&router, "/v1/jobs", &body, Duration::from_secs(300)).await;
    assert_eq!(j["status"], "succeeded", "{j}");
    let got: Vec<(String, bool)> = j["summary"]["criteria"]
        .as_array()
        .expect("summary.criteria")
        .iter()
        .map(|v| {
            (
                v["criterion"].as_str().expect("c").to_string(),
                v["met"].as_bool().expect("met"),
            )
        })
        .collect();
    assert_eq!(
        got,
        vec![
            ("toppled:A".to_string(), true),
            (r#"{"kind":"fallen","blocks":["B"]}"#.to_string(), false),
            (
                r#"{"kind":"not","of":{"kind":"fallen","blocks":["B"]}}"#.to_string(),
                true
            ),
        ],
        "{}",
        j["summary"]
    );
    // Without a criterion the summary has none; a block that is not free is a 422 at once.
    let mut plain = body.clone();
    plain.as_object_mut().expect("o").remove("criterion");
    plain["scene"]["control"]["duration"] = json!(0.1);
    let (_, j) = submit_and_wait(&router, "/v1/jobs", &plain, Duration::from_secs(120)).await;
    assert!(j["summary"].get("criteria").is_none(), "{j}");
    let mut bad = body;
    bad["criterion"] = json!(["toppled:A", "toppled:base"]);
    let p = call(&router, post_json("/v1/jobs", &bad))
        .await
        .problem(422);
    assert_eq!(p["pointer"], "/criterion/1", "{p}");
    svc.shutdown(Duration::ZERO);
    std::fs::remove_dir_all(dir).ok();
}
