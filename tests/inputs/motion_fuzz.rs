//! Robustness: arbitrary bytes and mutated valid files never panic any reader; whatever a
//! reader accepts is a usable record (positive finite step, finite non-empty samples).
//! 256 cases a property keeps the file to a few seconds.
use ashlar::motion::{Format, RawRecord, Units};
use proptest::prelude::*;

const FIXTURES: [(&str, Format); 6] = [
    ("old_style.at2", Format::At2),
    ("new_style.at2", Format::At2),
    ("semicolon_units_comment.csv", Format::Csv),
    ("synthetic.v1", Format::Cosmos),
    ("synthetic.v2", Format::Cosmos),
    ("synthetic.asc", Format::Esm),
];

fn fixture(name: &str) -> Vec<u8> {
    std::fs::read(format!(
        "{}/tests/fixtures/motion/{name}",
        env!("CARGO_MANIFEST_DIR")
    ))
    .expect("fixture")
}

fn usable(r: &RawRecord) -> bool {
    r.dt.is_finite() && r.dt > 0.0 && !r.values.is_empty() && r.values.iter().all(|v| v.is_finite())
}

fn parse_all(bytes: &[u8]) {
    let text = String::from_utf8_lossy(bytes);
    for format in [Format::At2, Format::Csv, Format::Cosmos, Format::Esm] {
        for units in [None, Some(Units::G)] {
            if let Ok(r) = format.parse("fuzz", &text, units) {
                assert!(usable(&r), "{format:?} accepted an unusable record {r:?}");
            }
        }
    }
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 256, ..ProptestConfig::default() })]

    #[test]
    fn arbitrary_bytes_never_panic(bytes in proptest::collection::vec(any::<u8>(), 0..600)) {
        parse_all(&bytes);
    }

    /// Replace, insert or delete a few bytes of a valid file, or cut it short.
    #[test]
    fn mutated_files_never_panic(
        which in 0..FIXTURES.len(),
        edits in proptest::collection::vec((any::<prop::sample::Index>(), 0u8..3, any::<u8>()), 1..6),
        cut in any::<prop::sample::Index>(),
        do_cut in any::<bool>(),
    ) {
        let (name, format) = FIXTURES[which];
        let mut b = fixture(name);
        for (at, op, byte) in edits {
            if b.is_empty() { break; }
            let i = at.index(b.len());
            // Bias replacements toward the characters that matter to the parsers.
            const SET: &[u8] = b"0123456789.-+eEDN :,=\n\r()";
            let byte = SET[byte as usize % SET.len()];
            match op {
                0 => b[i] = byte,
                1 => b.insert(i, byte),
                _ => { b.remove(i); }
            }
        }
        if do_cut && !b.is_empty() {
            b.truncate(cut.index(b.len()));
        }
        let text = String::from_utf8_lossy(&b);
        if let Ok(r) = format.parse("fuzz", &text, None) {
            prop_assert!(usable(&r));
        }
        parse_all(&b);
    }
}
