//! `control.restitution` bad input (docs/restitution.md): out of range, negative, non-finite-like or an
//! unknown keyword gives a `SceneError` naming `control.restitution` and saying what is
//! expected, never a panic or a silently clamped value; the accepted forms parse to the law
//! they name.
use ashlar::scene::{parse_scene, Restitution};
use serde_json::{json, Value};

fn example_with(restitution: Value) -> String {
    let text = std::fs::read_to_string(format!(
        "{}/examples/column.json",
        env!("CARGO_MANIFEST_DIR")
    ))
    .expect("example file");
    let mut v: Value = serde_json::from_str(&text).expect("example is JSON");
    v["control"]["restitution"] = restitution;
    v.to_string()
}

#[test]
fn bad_restitution_is_refused_naming_the_field() {
    for (bad, says) in [
        (json!(1.5), "[0, 1]"),
        (json!(-0.1), "[0, 1]"),
        (json!("foo"), "housner"),
        (json!("foo"), "contact"),
        (json!(true), "housner"),
        (json!([0.5]), "housner"),
    ] {
        let e = parse_scene(&example_with(bad.clone()))
            .expect_err(&format!("restitution {bad} must be refused"));
        let text = e.to_string();
        eprintln!("{bad}: {text}");
        assert_eq!(e.path, "control.restitution", "{bad}: {text}");
        assert!(text.contains(says), "{bad}: {text}");
    }
}

#[test]
fn accepted_restitution_forms() {
    for (given, law) in [
        (json!(0), Restitution::Coefficient(0.0)),
        (json!(0.75), Restitution::Coefficient(0.75)),
        (json!(1), Restitution::Coefficient(1.0)),
        (json!("housner"), Restitution::Housner),
        (json!("contact"), Restitution::Contact),
        (Value::Null, Restitution::Housner),
    ] {
        let s = parse_scene(&example_with(given.clone())).expect("valid restitution");
        assert_eq!(s.control.restitution, law, "{given}");
    }
}
