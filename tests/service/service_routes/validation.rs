//! Bad requests get problems naming the field (see `mod.rs`).
use super::*;

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn bad_requests_get_problems_naming_the_field() {
    let limits = Limits {
        max_body_bytes: 20_000,
        max_blocks: 3,
        max_record_samples: 100,
        max_total_steps: 5000,
        ..Limits::default()
    };
    let (svc, app, dir) = start("routes-errors", 1, FAST, limits);
    let scene = column_scene(1.0);

    // JSON syntax error: 400, with line and column.
    let p = call(
        &app,
        post_raw("/v1/jobs", "application/json", "{\"scene\": {,}"),
    )
    .await
    .problem(400);
    assert!(
        p["detail"]
            .as_str()
            .unwrap_or_default()
            .contains("line 1, column"),
        "{p}"
    );
    let p = call(&app, post_raw("/v1/jobs", "application/json", ""))
        .await
        .problem(400);
    assert!(
        p["detail"].as_str().unwrap_or_default().contains("empty"),
        "{p}"
    );
    // Not JSON content: 415 naming the header.
    let p = call(&app, post_raw("/v1/jobs", "text/plain", scene.to_string()))
        .await
        .problem(415);
    assert_eq!(p["parameter"], "Content-Type");
    // Body over the size limit: 413.
    let big = json!({"scene": scene, "motion": {"horizontal": {"samples": vec![0.125; 5000], "dt": 0.01}}});
    call(&app, post_json("/v1/jobs", &big)).await.problem(413);

    // Schema and semantic errors: 422 with a JSON pointer to the field.
    let cases: Vec<(Value, &str)> = vec![
        (json!([1, 2]), ""),
        (json!({"motion": null}), "/scene"),
        (json!({"scene": scene, "extra": true}), "/extra"),
        (
            json!({"scene": {"format": "ashlar.scene/1"}}),
            "/scene/materials",
        ),
        (
            {
                let mut s = scene.clone();
                s["blocks"][1]["vertices"] = json!([[0, 0], [1, 1]]);
                json!({"scene": s})
            },
            "/scene/blocks/1/vertices",
        ),
        (
            {
                let mut s = scene.clone();
                s["blocks"][1]["material"] = json!("granite");
                json!({"scene": s})
            },
            "/scene/blocks/1/material",
        ),
        (
            {
                let mut s = scene.clone();
                s["control"]["time_stpe"] = json!(0.001);
                json!({"scene": s})
            },
            "/scene/control/time_stpe",
        ),
        (
            {
                let mut s = scene.clone();
                s["joints"]["dry"]["friction_angle"] = json!(95);
                json!({"scene": s})
            },
            "/scene/joints/dry/friction_angle",
        ),
        (
            {
                let mut s = scene.clone();
                s["excitation"] = json!({"type": "base_acceleration", "block": "x"});
                json!({"scene": s})
            },
            "/scene/excitation/block",
        ),
        (
            // The range check (docs/format.md "Ranges") names the member itself.
            json!({"scene": scene, "motion": {"horizontal": {"pulse": {"amplitude": 1, "period": 0}}}}),
            "/motion/horizontal/pulse/period",
        ),
        (
            json!({"scene": scene, "motion": {"horizontal": {"pulse": {"amplitude": 1, "period": 1}, "sine": {}}}}),
            "/motion/horizontal/sine",
        ),
        (
            json!({"scene": scene, "motion": {"horizontal": {"sine": {"amplitude": 1, "frequency": 1}}, "wobble": 1}}),
            "/motion/wobble",
        ),
        (
            json!({"scene": scene, "motion": {"horizontal": {"sine": {"amplitude": 1, "frequency": 1}},
                   "scale": {"target_pga": 1.0, "units": null}}}),
            "/motion/scale/units",
        ),
        (
            {
                let mut s = scene.clone();
                s["control"] = json!({});
                json!({"scene": s})
            },
            "/scene/control/duration",
        ),
        (
            // A forced reduced model on a scene it cannot represent: refused at submission,
            // not failed later by a worker.
            {
                let mut s = scene.clone();
                s["control"]["model"] = json!("rocking");
                s["blocks"]
                    .as_array_mut()
                    .expect("blocks")
                    .push(json!({"id": "b2", "material": "limestone",
                    "vertices": [[2.0, 0.0], [2.5, 0.0], [2.5, 0.5]]}));
                json!({"scene": s})
            },
            "/scene/control/model",
        ),
        (
            // A dual-solver knob with the penalty solver: refused, not silently ignored.
            {
                let mut s = scene.clone();
                s["control"]["dual_tolerance"] = json!(1e-4);
                json!({"scene": s})
            },
            "/scene/control/dual_tolerance",
        ),
    ];
    for (body, pointer) in cases {
        let r = call(&app, post_json("/v1/jobs", &body)).await;
        let p = r.problem(422);
        assert_eq!(p["pointer"], pointer, "body {body}: {p}");
        assert!(p["detail"].as_str().unwrap_or_default().len() > 10, "{p}");
    }
    // Limits: blocks, record length, steps, frames; each 422 naming the field and the flag.
    let mut s = scene.clone();
    let extra: Vec<Value> = (0..3)
        .map(|k| {
            json!({"id": format!("b{k}"), "material": "limestone",
        "vertices": [[2.0 + k as f64, 0.0], [2.5 + k as f64, 0.0], [2.5 + k as f64, 0.5]]})
        })
        .collect();
    s["blocks"].as_array_mut().expect("blocks").extend(extra);
    let p = call(&app, post_json("/v1/jobs", &json!({"scene": s})))
        .await
        .problem(422);
    assert_eq!(
        (p["pointer"].as_str(), p["type"].as_str()),
        (
            Some("/scene/blocks"),
            Some("urn:ashlar:problem:limit-exceeded")
        )
    );
    assert!(p["detail"]
        .as_str()
        .unwrap_or_default()
        .contains("--max-blocks"));
    let m = json!({"horizontal": {"samples": vec![0.0; 101], "dt": 0.01}});
    assert_eq!(
        call(
            &app,
            post_json("/v1/jobs", &json!({"scene": scene, "motion": m}))
        )
        .await
        .problem(422)["pointer"],
        "/motion"
    );
    let mut s = scene.clone();
    s["control"]["duration"] = json!(6.0); // 6000 steps of 1 ms > 5000
    assert_eq!(
        call(&app, post_json("/v1/jobs", &json!({"scene": s})))
            .await
            .problem(422)["pointer"],
        "/scene/control/duration"
    );
    let mut s = scene.clone();
    s["control"] = json!({"duration": 1.0, "time_step": 0.01, "output_interval": 1e-4}); // 10000 frames
    assert_eq!(
        call(&app, post_json("/v1/jobs", &json!({"scene": s})))
            .await
            .problem(422)["pointer"],
        "/scene/control/output_interval"
    );

    // Path and query parameters.
    assert_eq!(
        call(&app, get("/v1/jobs/not-a-uuid")).await.problem(400)["parameter"],
        "id"
    );
    let unknown = uuid::Uuid::new_v4();
    assert_eq!(
        call(&app, get(&format!("/v1/jobs/{unknown}")))
            .await
            .problem(404)["parameter"],
        "id"
    );
    call(&app, get(&format!("/v1/jobs/{unknown}/histories")))
        .await
        .problem(404);
    call(&app, get(&format!("/v1/jobs/{unknown}/trajectory.mcap")))
        .await
        .problem(404);
    call(&app, get(&format!("/v1/jobs/{unknown}/events")))
        .await
        .problem(404);
    cancel(&app, &unknown.to_string()).await.problem(404);
    call(&app, get(&format!("/v1/pga-searches/{unknown}")))
        .await
        .problem(404);

    let id = submit(&app, &json!({"scene": scene, "motion": pulse(2.0)})).await;
    let uri = format!("/v1/jobs/{id}");
    // A run id is not a PGA search id.
    call(&app, get(&format!("/v1/pga-searches/{id}")))
        .await
        .problem(404);
    wait_for(&app, &uri, Duration::from_secs(20), is_terminal).await;
    assert_eq!(
        call(&app, get(&format!("{uri}/histories?format=xml")))
            .await
            .problem(400)["parameter"],
        "format"
    );
    assert_eq!(
        call(&app, get(&format!("{uri}/histories?blok=column")))
            .await
            .problem(400)["parameter"],
        "blok"
    );
    let p = call(&app, get(&format!("{uri}/histories?block=plinth")))
        .await
        .problem(404);
    assert_eq!(p["parameter"], "block");
    assert!(
        p["detail"]
            .as_str()
            .unwrap_or_default()
            .contains("\"plinth\""),
        "{p}"
    );
    let req = Request::builder()
        .uri(format!("{uri}/histories"))
        .header("accept", "image/png")
        .body(Body::empty())
        .expect("req");
    call(&app, req).await.problem(406);

    // Unknown endpoints and methods are problems too.
    assert_eq!(
        call(&app, get("/v2/nothing")).await.problem(404)["type"],
        "urn:ashlar:problem:no-route"
    );
    let req = Request::builder()
        .method("PUT")
        .uri(&uri)
        .body(Body::empty())
        .expect("req");
    let r = call(&app, req).await;
    let p = r.problem(405);
    assert!(r.header("allow").unwrap_or_default().contains("GET"));
    // The detail names the methods the path takes (it used to say "see /openapi.yaml").
    let detail = p["detail"].as_str().unwrap_or_default();
    assert!(
        detail.contains("GET") && detail.contains("DELETE"),
        "{detail}"
    );
    svc.shutdown(Duration::from_secs(5));
    std::fs::remove_dir_all(dir).ok();
}
