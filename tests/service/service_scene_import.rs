//! `POST /v1/scenes/import` (docs/import.md) through the router (`oneshot`, no socket): a DXF
//! drawing written by ezdxf (tests/fixtures/dxf/) gives the scene the library builds, accepted as
//! a job's scene; a refused drawing is a 422 at `/dxf` naming the entity handle and layer; a bad
//! option a 422 at `/options/...`; a body that is not the contract's shape a 4xx naming the member.
use crate::service_support;

use ashlar::scene::import::dxf::{self, ImportOptions};
use serde_json::{json, Value};
use service_support::*;
use std::time::Duration;

fn fixture(name: &str) -> String {
    let p = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/fixtures/dxf")
        .join(name);
    std::fs::read_to_string(&p).unwrap_or_else(|e| panic!("{}: {e}", p.display()))
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn dxf_drawings_import_to_scenes_and_bad_ones_are_problems() {
    let (svc, router, dir) = start_fake("scene-import");

    // A good drawing with options: the library's scene, as JSON; accepted as a job's scene.
    let wall = fixture("wall_mm.dxf");
    let options = json!({"materials": {"limestone": {"density": 2400, "young_modulus": 1.5e10, "poisson_ratio": 0.2}}});
    let r = call(
        &router,
        post_json(
            "/v1/scenes/import",
            &json!({"dxf": wall, "options": options}),
        ),
    )
    .await;
    assert_eq!(r.status, 200, "{}", r.text());
    let lib = dxf::import(
        wall.as_bytes(),
        &ImportOptions::from_value(&options).expect("options"),
    )
    .expect("library");
    // Compared as both sides read back through serde_json's text parser (which may read a
    // shortest decimal one ulp off: it is built without `float_roundtrip`).
    let lib_json: Value =
        serde_json::from_str(&serde_json::to_string(&lib.spec).expect("spec")).expect("json");
    assert_eq!(r.json(), lib_json);
    assert_eq!(r.json()["materials"]["limestone"]["density"], 2400.0);
    let mut scene = r.json();
    scene["control"]["duration"] = json!(0.2);
    let job = call(&router, post_json("/v1/jobs", &json!({"scene": scene}))).await;
    assert_eq!(job.status, 202, "{}", job.text());

    // `options` null or absent: the defaults.
    for body in [json!({"dxf": wall, "options": null}), json!({"dxf": wall})] {
        let r = call(&router, post_json("/v1/scenes/import", &body)).await;
        assert_eq!(r.status, 200, "{}", r.text());
        assert_eq!(r.json()["materials"]["limestone"]["density"], 2500.0);
    }

    // Bad drawings: 422 at /dxf, the detail naming handle and layer.
    for name in [
        "bad_open",
        "bad_arc",
        "bad_overlap",
        "bad_bulge",
        "bad_self_intersecting",
    ] {
        let exp: Value = serde_json::from_str(&fixture(&format!("{name}.json"))).expect("json");
        let body = json!({"dxf": fixture(&format!("{name}.dxf"))});
        let p = call(&router, post_json("/v1/scenes/import", &body))
            .await
            .problem(422);
        assert_eq!(p["pointer"], "/dxf", "{name}: {p}");
        let detail = p["detail"].as_str().unwrap_or("");
        let (h, l) = (
            exp["handle"].as_str().expect("h"),
            exp["layer"].as_str().expect("l"),
        );
        assert!(
            detail.contains(&format!("entity {h} on layer {l:?}")),
            "{name}: {detail}"
        );
    }
    for text in [
        "",
        "not a drawing",
        "0\nSECTION\n2\nENTITIES\n0\nENDSEC\n0\nEOF\n",
    ] {
        let p = call(
            &router,
            post_json("/v1/scenes/import", &json!({"dxf": text})),
        )
        .await
        .problem(422);
        assert_eq!(p["pointer"], "/dxf", "{text:?}: {p}");
    }

    // Bad options and bodies: the member named.
    let cases = [
        (
            json!({"dxf": wall, "options": {"unit": "mm"}}),
            "/options/unit",
        ),
        (
            json!({"dxf": wall, "options": {"units": "cm"}}),
            "/options/units",
        ),
        (
            json!({"dxf": wall, "options": {"materials": {"limestone": {"density": 1e9, "young_modulus": 1e10, "poisson_ratio": 0.2}}}}),
            "/options/materials/limestone/density",
        ),
        (
            json!({"dxf": wall, "options": {"materials": {"limestone": {"density": 2500, "young_modulus": 1e10, "poisson_ratio": 0.6}}}}),
            "/options/materials/limestone/poisson_ratio",
        ),
        (
            json!({"dxf": wall, "options": {"joint": {"friction_angle": 37, "cohesion": 1e12}}}),
            "/options/joint/cohesion",
        ),
        (
            json!({"dxf": wall, "options": {"joint": {"friction_angle": 90}}}),
            "/options/joint/friction_angle",
        ),
        (json!({"dxf": wall, "options": 3}), "/options"),
        (json!({"dxf": wall, "options": [null, null]}), "/options"),
        (json!({"dxf": 3}), "/dxf"),
        (json!({"options": {}}), "/dxf"),
        (json!({"dxf": wall, "drawing": 1}), "/drawing"),
        (json!([1]), ""),
    ];
    for (body, pointer) in cases {
        let p = call(&router, post_json("/v1/scenes/import", &body))
            .await
            .problem(422);
        assert_eq!(p["pointer"], pointer, "{p}");
    }
    call(
        &router,
        post_raw("/v1/scenes/import", "application/json", "{"),
    )
    .await
    .problem(400);
    call(&router, post_raw("/v1/scenes/import", "text/plain", "{}"))
        .await
        .problem(415);

    svc.shutdown(Duration::ZERO);
    std::fs::remove_dir_all(dir).ok();
}
