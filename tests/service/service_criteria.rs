//! Damage criteria in `POST /v1/pga-searches` (docs/format.md §3 "Damage criteria";
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
