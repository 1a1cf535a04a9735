//! SVG plotting shared by every figure ashlar writes (the study's plots, the fragility curve, a
//! record's response spectrum): the document, its background and frame, grid lines, polylines,
//! escaping, tick steps and short numbers, written once. Sits beside `quantity` at the bottom
//! of the flow: any layer that draws may use it (`motion` for the spectrum, `analysis` for the
//! rest); it knows nothing of ashlar's types. Coordinates are SVG user units (px), y down.

/// `text` escaped for SVG text and attribute values.
pub fn escape(text: &str) -> String {
    text.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
        .replace('"', "&quot;")
}

/// The opening `<svg>` tag of a `w` × `h` drawing (with a matching viewBox when `view_box`),
/// sans-serif at `font_size` px, and its white background.
pub fn document(w: f64, h: f64, font_size: f64, view_box: bool) -> String {
    let vb = if view_box {
        format!(" viewBox=\"0 0 {w} {h}\"")
    } else {
        String::new()
    };
    format!(
        "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"{w}\" height=\"{h}\"{vb} font-family=\"sans-serif\" font-size=\"{font_size}\">\n<rect width=\"100%\" height=\"100%\" fill=\"white\"/>\n"
    )
}

/// The closing tag.
pub const END: &str = "</svg>\n";

/// The plot area's frame: the rectangle at (`x`, `y`), `w` × `h`, unfilled, black.
pub fn frame(x: f64, y: f64, w: f64, h: f64) -> String {
    format!(
        "<rect x=\"{x}\" y=\"{y}\" width=\"{w}\" height=\"{h}\" fill=\"none\" stroke=\"black\"/>\n"
    )
}

/// A light grey grid line from (x1, y1) to (x2, y2).
pub fn grid_line(x1: f64, y1: f64, x2: f64, y2: f64) -> String {
    format!("<line x1=\"{x1:.1}\" y1=\"{y1:.1}\" x2=\"{x2:.1}\" y2=\"{y2:.1}\" stroke=\"#ddd\"/>\n")
}

/// A line through `points` (px), unfilled, `width` px wide, in `colour`; extra attributes
/// (e.g. a dash pattern) in `extra`, written as given.
pub fn polyline(points: &[(f64, f64)], colour: &str, width: f64, extra: &str) -> String {
    let pts: Vec<String> = points
        .iter()
        .map(|(x, y)| format!("{x:.1},{y:.1}"))
        .collect();
    format!(
        "<polyline fill=\"none\" stroke=\"{colour}\" stroke-width=\"{width}\"{extra} points=\"{}\"/>\n",
        pts.join(" ")
    )
}

/// A "nice" tick step (1, 2 or 5 × 10^k) that cuts `span` into about `target` intervals.
pub fn tick_step(span: f64, target: usize) -> f64 {
    let raw = span / target.max(1) as f64;
    let mag = 10f64.powf(raw.log10().floor());
    let r = raw / mag;
    mag * if r < 1.5 {
        1.0
    } else if r < 3.5 {
        2.0
    } else if r < 7.5 {
        5.0
    } else {
        10.0
    }
}

/// The smallest of 1, 2, 2.5, 5 × 10ᵏ at or above `x` (an axis's upper end).
pub fn nice_ceiling(x: f64) -> f64 {
    let e = 10f64.powf(x.log10().floor());
    [1.0, 2.0, 2.5, 5.0, 10.0]
        .iter()
        .map(|m| m * e)
        .find(|v| *v >= x * (1.0 - 1e-12))
        .unwrap_or(10.0 * e)
}

/// `x` with at most `decimals` decimals and no trailing zeros (a tick label, a value in a
/// legend); `0` for what rounds to nothing.
pub fn short(x: f64, decimals: usize) -> String {
    let t = format!("{x:.decimals$}");
    let t = if t.contains('.') {
        t.trim_end_matches('0').trim_end_matches('.')
    } else {
        t.as_str()
    };
    if t.is_empty() || t == "-" || t == "-0" {
        "0".to_string()
    } else {
        t.to_string()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ticks_and_numbers_are_round() {
        assert_eq!(tick_step(10.0, 5), 2.0);
        assert_eq!(tick_step(7.3, 6), 1.0);
        assert_eq!(nice_ceiling(3.1), 5.0);
        assert_eq!(nice_ceiling(2.0), 2.0);
        assert_eq!(short(2.50, 3), "2.5");
        assert_eq!(short(-0.00001, 3), "0");
        assert_eq!(escape("a<b & \"c\""), "a&lt;b &amp; &quot;c&quot;");
    }
}
