//! The scene channel's outlines against the block states of the same frames.
use super::*;
use ashlar::record::messages::fill_color;
use ashlar::record::triangulate::signed_area;
use ashlar::record::{BlockMotionState, FrameBlockKind};

fn centroid(p: &[[f64; 2]]) -> [f64; 2] {
    let a = signed_area(p);
    let n = p.len();
    let (mut cx, mut cy) = (0.0, 0.0);
    for i in 0..n {
        let (u, v) = (p[i], p[(i + 1) % n]);
        let w = u[0] * v[1] - v[0] * u[1];
        cx += (u[0] + v[0]) * w;
        cy += (u[1] + v[1]) * w;
    }
    [cx / (6.0 * a), cy / (6.0 * a)]
}

fn points(v: &Value) -> Vec<[f64; 2]> {
    v.as_array()
        .expect("points")
        .iter()
        .map(|p| {
            assert_eq!(p["z"].as_f64(), Some(0.0), "the 2D scene lies in z = 0");
            [p["x"].as_f64().expect("x"), p["y"].as_f64().expect("y")]
        })
        .collect()
}

#[test]
fn scene_outlines_agree_with_block_states() {
    // Second method: the displacement and rotation in `/ashlar/blocks` are recomputed from the
    // outlines drawn in `/ashlar/scene` (polygon centroid, edge angle). 1e-12 m / rad: the
    // centroid formula's rounding on coordinates of order 1 m.
    let run = RockingSquare::default();
    let header = run.header();
    let path = tmp("scene.mcap");
    record(&path, &run, run.frame_count(), &McapParams::default());
    let bytes = std::fs::read(&path).expect("read");
    let msgs = read_messages(&bytes);
    let scenes = on(&msgs, TOPIC_SCENE);
    let blocks = on(&msgs, TOPIC_BLOCKS);
    let first = run.frame(0);
    let mut states_seen = BTreeSet::new();
    for (scene, bm) in scenes.iter().zip(&blocks) {
        let entities = scene.json["entities"].as_array().expect("entities");
        assert_eq!(entities.len(), header.block_ids.len(), "one entity a block");
        for (i, e) in entities.iter().enumerate() {
            assert_eq!(e["id"], header.block_ids[i].as_str());
            assert_eq!(e["frame_id"], "world");
            let line = &e["lines"][0];
            assert_eq!(line["type"], 1, "LINE_LOOP closes the outline");
            let outline = points(&line["points"]);
            let fill = &e["triangles"][0];
            assert_eq!(points(&fill["points"]), outline);
            // The triangles tile the outline: their areas add up to the polygon's.
            let idx: Vec<usize> = fill["indices"]
                .as_array()
                .expect("indices")
                .iter()
                .map(|i| i.as_u64().expect("index") as usize)
                .collect();
            assert_eq!(idx.len() % 3, 0);
            let tri_area: f64 = idx
                .chunks(3)
                .map(|t| signed_area(&[outline[t[0]], outline[t[1]], outline[t[2]]]))
                .sum();
            let area = signed_area(&outline);
            assert!(
                (tri_area - area).abs() < 1e-12 * area.abs(),
                "fill area {tri_area} vs {area}"
            );

            let b = &bm.json["blocks"][i];
            let c0 = centroid(&first.blocks[i].outline);
            let c = centroid(&outline);
            assert!((c[0] - c0[0] - b["x"].as_f64().expect("x")).abs() < 1e-12);
            assert!((c[1] - c0[1] - b["y"].as_f64().expect("y")).abs() < 1e-12);
            let o0 = &first.blocks[i].outline;
            let ang = |p: &[[f64; 2]]| (p[1][1] - p[0][1]).atan2(p[1][0] - p[0][0]);
            let rot = ang(&outline) - ang(o0);
            assert!((rot - b["rotation"].as_f64().expect("rotation")).abs() < 1e-12);

            // Colour and metadata follow the block's kind and state.
            let state: BlockMotionState = match b["state"].as_str().expect("state") {
                "at_rest" => BlockMotionState::AtRest,
                "sliding" => BlockMotionState::Sliding,
                "rocking" => BlockMotionState::Rocking,
                "toppled" => BlockMotionState::Toppled,
                other => panic!("unknown state {other}"),
            };
            let c = fill_color(header.block_kinds[i], state);
            let col = &fill["color"];
            assert_eq!(
                [
                    col["r"].as_f64(),
                    col["g"].as_f64(),
                    col["b"].as_f64(),
                    col["a"].as_f64()
                ],
                [Some(c.r), Some(c.g), Some(c.b), Some(c.a)]
            );
            assert_eq!(e["metadata"][1]["value"], b["state"]);
            if header.block_kinds[i] == FrameBlockKind::Free {
                states_seen.insert(b["state"].as_str().expect("state").to_string());
            }
        }
    }
    assert_eq!(
        states_seen.len(),
        4,
        "the run shows all four colours: {states_seen:?}"
    );
    // Four states on free blocks give four different colours.
    let colours: BTreeSet<String> = [
        BlockMotionState::AtRest,
        BlockMotionState::Sliding,
        BlockMotionState::Rocking,
        BlockMotionState::Toppled,
    ]
    .iter()
    .map(|&s| format!("{:?}", fill_color(FrameBlockKind::Free, s)))
    .collect();
    assert_eq!(colours.len(), 4);
}
