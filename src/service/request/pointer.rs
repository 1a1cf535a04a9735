//! Service: JSON pointers of request members (RFC 6901), from the dotted paths the scene and
//! motion readers and serde name (`blocks[2].vertices` → `/scene/blocks/2/vertices`). Part of
//! `request`, whose errors carry them; `http` re-exports them for its own readers.

/// serde names missing and unknown fields in its message, not in the path: point at them.
pub fn point_at_named_field(pointer: String, msg: &str) -> String {
    for marker in ["missing field `", "unknown field `"] {
        if let Some(name) = msg
            .strip_prefix(marker)
            .and_then(|rest| rest.split('`').next())
        {
            let escaped = name.replace('~', "~0").replace('/', "~1");
            if !pointer.ends_with(&format!("/{escaped}")) {
                return format!("{pointer}/{escaped}");
            }
        }
    }
    pointer
}

/// Turn a scene-style dotted path (`blocks[2].vertices[0]`, `materials.stone.density`) into a
/// JSON pointer below `prefix` (`/scene/blocks/2/vertices/0`). serde_path_to_error's `.` for
/// "the whole document" maps to `prefix` itself.
pub fn dotted_to_pointer(prefix: &str, path: &str) -> String {
    let mut out = String::from(prefix);
    if path.is_empty() || path == "." || path == "(document)" {
        return out;
    }
    let mut seg = String::new();
    let flush = |seg: &mut String, out: &mut String| {
        if !seg.is_empty() {
            out.push('/');
            out.push_str(&seg.replace('~', "~0").replace('/', "~1"));
            seg.clear();
        }
    };
    for ch in path.chars() {
        match ch {
            '.' | '[' => flush(&mut seg, &mut out),
            ']' => {}
            c => seg.push(c),
        }
    }
    flush(&mut seg, &mut out);
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pointers_from_dotted_paths() {
        assert_eq!(
            dotted_to_pointer("/scene", "blocks[2].vertices[0]"),
            "/scene/blocks/2/vertices/0"
        );
        assert_eq!(
            dotted_to_pointer("/scene", "materials.stone.density"),
            "/scene/materials/stone/density"
        );
        assert_eq!(dotted_to_pointer("/scene", "."), "/scene");
        assert_eq!(
            dotted_to_pointer("", "motion.horizontal.pulse"),
            "/motion/horizontal/pulse"
        );
        assert_eq!(dotted_to_pointer("/x", "a/b"), "/x/a~1b");
    }
}
