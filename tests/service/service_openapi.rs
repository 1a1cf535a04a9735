//! Every route of the router is described in `openapi.yaml`, and every operation described there
//! is served: compared as sets of (method, path), then each described operation is sent to the
//! router to prove it is routed (answered by a handler, not by the 404 fallback or a 405).
use crate::service_support;

use ashlar::service::{route_table, OPENAPI_YAML};
use axum::body::Body;
use axum::http::Request;
use service_support::*;
use std::collections::BTreeSet;
use std::time::Duration;

/// (METHOD, path) of every operation under `paths:`. The file is hand-written with a fixed
/// layout: paths at two spaces of indentation, methods at four.
fn spec_operations(yaml: &str) -> BTreeSet<(String, String)> {
    let mut out = BTreeSet::new();
    let mut in_paths = false;
    let mut path: Option<String> = None;
    for line in yaml.lines() {
        if !line.starts_with(' ') && !line.trim().is_empty() {
            in_paths = line.trim_end() == "paths:";
            continue;
        }
        if !in_paths {
            continue;
        }
        if let Some(rest) = line.strip_prefix("  ") {
            if rest.starts_with('/') {
                path = Some(rest.trim_end().trim_end_matches(':').to_string());
                continue;
            }
            if let Some(m) = rest.strip_prefix("  ") {
                let key = m.split(':').next().unwrap_or("").trim();
                if !m.starts_with(' ')
                    && [
                        "get", "put", "post", "delete", "patch", "head", "options", "trace",
                    ]
                    .contains(&key)
                {
                    out.insert((
                        key.to_uppercase(),
                        path.clone().expect("a method under a path"),
                    ));
                }
            }
        }
    }
    out
}

#[test]
fn the_spec_parser_sees_what_is_there() {
    let yaml = "openapi: 3.1.0\npaths:\n  /a/{id}:\n    get:\n      x: 1\n    post:\n      y: 2\n  /b:\n    get: {}\ncomponents:\n  /c:\n    get: {}\n";
    let ops = spec_operations(yaml);
    let want: BTreeSet<(String, String)> = [("GET", "/a/{id}"), ("POST", "/a/{id}"), ("GET", "/b")]
        .iter()
        .map(|(m, p)| (m.to_string(), p.to_string()))
        .collect();
    assert_eq!(ops, want);
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn router_and_openapi_describe_the_same_operations() {
    let spec = spec_operations(OPENAPI_YAML);
    let routes: BTreeSet<(String, String)> = route_table()
        .iter()
        .map(|(m, p, _)| (m.to_string(), p.to_string()))
        .collect();
    let missing_in_spec: Vec<_> = routes.difference(&spec).collect();
    let missing_in_router: Vec<_> = spec.difference(&routes).collect();
    assert!(
        missing_in_spec.is_empty(),
        "routes not in openapi.yaml: {missing_in_spec:?}"
    );
    assert!(
        missing_in_router.is_empty(),
        "operations of openapi.yaml not in the router: {missing_in_router:?}"
    );
    // docs/format.md §4's minimum is all there.
    for (m, p) in [
        ("POST", "/v1/jobs"),
        ("GET", "/v1/jobs/{id}"),
        ("GET", "/v1/jobs/{id}/histories"),
        ("GET", "/v1/jobs/{id}/trajectory.mcap"),
        ("GET", "/v1/jobs/{id}/events"),
        ("POST", "/v1/jobs/{id}/cancel"),
        ("POST", "/v1/pga-searches"),
        ("GET", "/v1/pga-searches/{id}"),
        ("GET", "/healthz"),
        ("GET", "/openapi.yaml"),
    ] {
        assert!(
            spec.contains(&(m.to_string(), p.to_string())),
            "docs/format.md §4 requires {m} {p}"
        );
    }

    // The table is what the router serves: each operation reaches a handler.
    let (svc, router, dir) = start_fake("openapi-routes");
    let id = uuid::Uuid::new_v4();
    for (method, path) in &spec {
        let uri = path.replace("{id}", &id.to_string());
        let req = Request::builder()
            .method(method.as_str())
            .uri(&uri)
            .header("content-type", "application/json")
            .body(Body::from("{}"))
            .expect("req");
        let r = call(&router, req).await;
        assert_ne!(r.status, 405, "{method} {uri} is not routed: {}", r.text());
        if r.status == 404 {
            // A handler's 404 names the job; the fallback's says there is no endpoint.
            assert_ne!(
                r.json()["type"],
                "urn:ashlar:problem:no-route",
                "{method} {uri} is not routed"
            );
        }
    }
    svc.shutdown(Duration::ZERO);
    std::fs::remove_dir_all(dir).ok();
}
