//! A drawing imported from DXF (`scene::import::dxf`, docs/import.md) stands at rest under its own
//! weight in the full engine, as the templates do (tests/engine/templates.rs): the wall of
//! tests/fixtures/dxf/wall_mm.dxf (written by ezdxf in millimetres: 18 stones in running bond on
//! a fixed foundation, default stone and joint), 3 s under gravity alone, every vertex within
//! 0.1 mm of where it was drawn (the rest bound). A wrong unit (a wall 1000× too large or
//! small), a flipped axis, or stones imported overlapping or apart would move by far more.
use crate::common;
use crate::templates::{settle, REST_BOUND};
use ashlar::scene::import::dxf::{self, ImportOptions};

#[test]
fn imported_wall_stands_at_rest() {
    let path =
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures/dxf/wall_mm.dxf");
    let bytes = std::fs::read(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    let imported = dxf::import(&bytes, &ImportOptions::default()).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(imported.spec.blocks.len(), 19);
    let mut v = serde_json::to_value(&imported.spec).unwrap_or_else(|e| panic!("{e}"));
    v["control"]["model"] = "dda".into();
    v["control"]["duration"] = 3.0.into();
    let scene = common::parse(&v);
    let (worst, _, sim) = settle(&scene, 3.0, |_| false);
    assert!(sim.time() >= 3.0 - 1e-9, "stopped at {} s", sim.time());
    assert!(
        worst <= REST_BOUND,
        "the imported wall moved {worst:.3e} m (bound {REST_BOUND:.0e} m)"
    );
}
