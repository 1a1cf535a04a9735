//! Every message against its embedded JSON schema, and the Foxglove schemas' published fields.
use super::*;

/// A small JSON Schema checker (the subset the recording's schemas use): `type`, `required`,
/// `properties` (and no property the schema does not declare), `items`, `enum`, `oneOf` of
/// consts, `minimum`, `maximum`.
fn validate(schema: &Value, v: &Value, at: &str) -> Result<(), String> {
    if let Some(ty) = schema.get("type").and_then(Value::as_str) {
        let ok = match ty {
            "object" => v.is_object(),
            "array" => v.is_array(),
            "number" => v.is_number(),
            "integer" => v.is_u64() || v.is_i64(),
            "string" => v.is_string(),
            "boolean" => v.is_boolean(),
            other => return Err(format!("{at}: schema type {other} not handled")),
        };
        if !ok {
            return Err(format!("{at}: expected {ty}, got {v}"));
        }
    }
    if let Some(options) = schema.get("oneOf").and_then(Value::as_array) {
        if !options.iter().any(|o| o.get("const") == Some(v)) {
            return Err(format!("{at}: {v} is none of the enumerated values"));
        }
    }
    if let Some(options) = schema.get("enum").and_then(Value::as_array) {
        if !options.contains(v) {
            return Err(format!("{at}: {v} not in enum"));
        }
    }
    if let (Some(min), Some(x)) = (schema.get("minimum").and_then(Value::as_f64), v.as_f64()) {
        if x < min {
            return Err(format!("{at}: {x} < minimum {min}"));
        }
    }
    if let (Some(max), Some(x)) = (schema.get("maximum").and_then(Value::as_f64), v.as_f64()) {
        if x > max {
            return Err(format!("{at}: {x} > maximum {max}"));
        }
    }
    if let Some(req) = schema.get("required").and_then(Value::as_array) {
        for key in req.iter().filter_map(Value::as_str) {
            if v.get(key).is_none() {
                return Err(format!("{at}: required field {key} missing"));
            }
        }
    }
    if let (Some(props), Some(obj)) = (
        schema.get("properties").and_then(Value::as_object),
        v.as_object(),
    ) {
        for (key, val) in obj {
            let sub = props
                .get(key)
                .ok_or_else(|| format!("{at}: field {key} not in the schema"))?;
            validate(sub, val, &format!("{at}.{key}"))?;
        }
    }
    if let (Some(items), Some(arr)) = (schema.get("items"), v.as_array()) {
        for (i, x) in arr.iter().enumerate() {
            validate(items, x, &format!("{at}[{i}]"))?;
        }
    }
    Ok(())
}

#[test]
fn every_message_validates_against_its_embedded_schema() {
    let run = RockingSquare {
        copies: 2,
        ..RockingSquare::default()
    };
    let path = tmp("schemas.mcap");
    record(&path, &run, 120, &McapParams::default());
    let bytes = std::fs::read(&path).expect("read");
    let summary = mcap::Summary::read(&bytes)
        .expect("summary")
        .expect("present");
    let schemas: BTreeMap<String, Value> = summary
        .schemas
        .values()
        .map(|s| {
            let v: Value = serde_json::from_slice(&s.data).expect("schema is JSON");
            assert_eq!(
                v["title"].as_str(),
                Some(s.name.as_str()),
                "schema title = schema name"
            );
            (s.name.clone(), v)
        })
        .collect();
    let msgs = read_messages(&bytes);
    for m in &msgs {
        validate(&schemas[&m.schema_name], &m.json, &m.topic).unwrap_or_else(|e| panic!("{e}"));
    }
    // The checker does reject: a scene entity without `cubes`, and an unknown line type.
    let scene = &on(&msgs, TOPIC_SCENE)[0].json;
    let mut broken = scene.clone();
    broken["entities"][0]
        .as_object_mut()
        .expect("entity")
        .remove("cubes");
    assert!(validate(&schemas["foxglove.SceneUpdate"], &broken, "x").is_err());
    let mut broken = scene.clone();
    broken["entities"][0]["lines"][0]["type"] = 7.into();
    assert!(validate(&schemas["foxglove.SceneUpdate"], &broken, "x").is_err());
}

#[test]
fn foxglove_schemas_have_the_published_fields() {
    // Reference: tests/fixtures/record/foxglove_fields.json, the field lists of Foxglove's
    // published JSON Schemas. Every titled object in the embedded schemas must have exactly
    // those properties, required in that order; every listed type must appear.
    let fixture =
        Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures/record/foxglove_fields.json");
    let expected: BTreeMap<String, Value> =
        serde_json::from_str(&std::fs::read_to_string(fixture).expect("fixture")).expect("JSON");
    let run = RockingSquare::default();
    let path = tmp("fields.mcap");
    record(&path, &run, 2, &McapParams::default());
    let bytes = std::fs::read(&path).expect("read");
    let summary = mcap::Summary::read(&bytes)
        .expect("summary")
        .expect("present");
    let mut seen = BTreeSet::new();
    fn walk(v: &Value, expected: &BTreeMap<String, Value>, seen: &mut BTreeSet<String>) {
        if let (Some(title), Some(props)) = (
            v.get("title").and_then(Value::as_str),
            v.get("properties").and_then(Value::as_object),
        ) {
            if let Some(fields) = expected.get(title).and_then(Value::as_array) {
                let want: Vec<&str> = fields.iter().filter_map(Value::as_str).collect();
                let mut have: Vec<&str> = props.keys().map(String::as_str).collect();
                let mut sorted_want = want.clone();
                sorted_want.sort();
                have.sort();
                assert_eq!(have, sorted_want, "{title}: properties");
                if title != "time" && title != "duration" {
                    let req: Vec<&str> = v["required"]
                        .as_array()
                        .expect("required")
                        .iter()
                        .filter_map(Value::as_str)
                        .collect();
                    assert_eq!(req, want, "{title}: required");
                }
                seen.insert(title.to_string());
            }
        }
        if let Some(obj) = v.as_object() {
            obj.values().for_each(|x| walk(x, expected, seen));
        }
        if let Some(arr) = v.as_array() {
            arr.iter().for_each(|x| walk(x, expected, seen));
        }
    }
    for s in summary
        .schemas
        .values()
        .filter(|s| s.name.starts_with("foxglove."))
    {
        walk(
            &serde_json::from_slice(&s.data).expect("JSON"),
            &expected,
            &mut seen,
        );
    }
    let listed: BTreeSet<String> = expected
        .keys()
        .filter(|k| !k.starts_with('_'))
        .cloned()
        .collect();
    assert_eq!(seen, listed);
}
