//! `GET /v1/templates` and `POST /v1/templates/{name}` (docs/templates.md) through the router
//! (`oneshot`, no socket): the list agrees with `scene::templates::list`, a built scene is the
//! one the library builds and is accepted as a job's scene, and bad requests are problems
//! naming the template or the parameter.
use crate::common::{listed_names, TEMPLATE_NAMES};
use crate::service_support;

use ashlar::scene::templates;
use serde_json::{json, Value};
use service_support::*;
use std::collections::BTreeMap;
use std::time::Duration;

fn start(tag: &str) -> (ashlar::service::Service, axum::Router, std::path::PathBuf) {
    service_support::start_fake(tag)
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn templates_are_listed_built_and_refused_with_problems() {
    let (svc, router, dir) = start("templates");

    let r = call(&router, get("/v1/templates")).await;
    assert_eq!(r.status, 200, "{}", r.text());
    let listed = r.json()["templates"].clone();
    let expected = serde_json::to_value(templates::list()).expect("list");
    assert_eq!(listed, expected);
    let names = listed_names(&listed);
    for n in TEMPLATE_NAMES {
        assert!(names.contains(&n), "{n} missing from {names:?}");
    }

    // Built with parameters: the library's scene, byte for byte as JSON.
    let body = json!({"parameters": {"drums": 5, "shaft_height": "4.0"}});
    let r = call(&router, post_json("/v1/templates/drum-column", &body)).await;
    assert_eq!(r.status, 200, "{}", r.text());
    let mut given = BTreeMap::new();
    given.insert("drums".to_string(), Value::from(5));
    given.insert("shaft_height".to_string(), Value::from("4.0"));
    let (spec, _) = templates::build("drum-column", &given).expect("build");
    assert_eq!(r.json(), serde_json::to_value(&spec).expect("spec"));
    let drums = r.json()["blocks"]
        .as_array()
        .expect("blocks")
        .iter()
        .filter(|b| b["id"].as_str().unwrap_or("").starts_with("drum"))
        .count();
    assert_eq!(drums, 5);

    // Without a body: the defaults; and the scene is accepted as a job's scene.
    let r = call(
        &router,
        post_raw("/v1/templates/arch", "application/json", ""),
    )
    .await;
    assert_eq!(r.status, 200, "{}", r.text());
    let mut scene = r.json();
    scene["control"]["duration"] = json!(0.5);
    let job = call(&router, post_json("/v1/jobs", &json!({"scene": scene}))).await;
    assert_eq!(job.status, 202, "{}", job.text());

    // Unknown template: 404 naming it; out of range / unknown parameter: 422 with a pointer.
    let p = call(&router, post_json("/v1/templates/temple", &json!({})))
        .await
        .problem(404);
    assert_eq!(p["parameter"], "name");
    assert!(p["detail"].as_str().unwrap_or("").contains("temple"), "{p}");
    let body = json!({"parameters": {"thickness_ratio": 0.9}});
    let p = call(&router, post_json("/v1/templates/arch", &body))
        .await
        .problem(422);
    assert_eq!(p["pointer"], "/parameters/thickness_ratio", "{p}");
    assert!(
        p["detail"].as_str().unwrap_or("").contains("must be in"),
        "{p}"
    );
    let body = json!({"parameters": {"voussoir": 9}});
    let p = call(&router, post_json("/v1/templates/arch", &body))
        .await
        .problem(422);
    assert_eq!(p["pointer"], "/parameters/voussoir", "{p}");
    let p = call(
        &router,
        post_json("/v1/templates/arch", &json!({"params": {}})),
    )
    .await
    .problem(422);
    assert_eq!(p["pointer"], "/params", "{p}");
    let r = call(&router, post_raw("/v1/templates/arch", "text/plain", "{}")).await;
    r.problem(415);

    svc.shutdown(Duration::ZERO);
    std::fs::remove_dir_all(dir).ok();
}
