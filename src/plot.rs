//! SVG plotting shared by every figure ashlar writes (the study's plots, the fragility curve, a
//! record's response spectrum): every element string (the document, frame, grid lines,
//! polylines, lines, circles, squares, text labels, rotated axis titles, tooltips), escaping,
//! tick steps and short numbers, written once; a figure only chooses positions, colours and
//! content. Sits beside `quantity` at the bottom of the flow: any layer that draws may use it
//! (`motion` for the spectrum, `analysis` for the rest); it knows nothing of ashlar's types.
//! Coordinates are SVG user units (px), y down.

use std::fmt;

/// A coordinate as written in the file: a bare `f64` is written as Rust prints it (`360`,
/// `12.5`), [`tenth`] rounds it to one decimal (`360.0`, `12.5`). The figures use both, and the
/// choice is kept so that their files do not change.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Coord {
    value: f64,
    tenth: bool,
}

impl From<f64> for Coord {
    fn from(value: f64) -> Self {
        Self {
            value,
            tenth: false,
        }
    }
}

/// `x` written with one decimal (a tenth of a px is below what a screen shows).
pub fn tenth(x: f64) -> Coord {
    Coord {
        value: x,
        tenth: true,
    }
}

impl fmt::Display for Coord {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        if self.tenth {
            write!(f, "{:.1}", self.value)
        } else {
            write!(f, "{}", self.value)
        }
    }
}

/// Where a text label's (x, y) sits on its baseline: its start (SVG's default, no attribute
/// written), middle or end.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Anchor {
    Start,
    Middle,
    End,
}

impl Anchor {
    fn attr(self) -> &'static str {
        match self {
            Anchor::Start => "",
            Anchor::Middle => " text-anchor=\"middle\"",
            Anchor::End => " text-anchor=\"end\"",
        }
    }
}

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
    rect(x, y, w, h, "none", &attr("stroke", "black"), None)
}

/// A light grey grid line from (x1, y1) to (x2, y2).
pub fn grid_line(x1: f64, y1: f64, x2: f64, y2: f64) -> String {
    line(tenth(x1), tenth(y1), tenth(x2), tenth(y2), "#ddd", "")
}

/// A line through `points` (px), unfilled, `width` px wide, in `colour`; extra attributes
/// (e.g. a dash pattern) in `extra`, written as given.
pub fn polyline(points: &[(f64, f64)], colour: &str, width: f64, extra: &str) -> String {
    let pts: Vec<String> = points
        .iter()
        .map(|(x, y)| format!("{x:.1},{y:.1}"))
        .collect();
    format!(
        "<polyline fill=\"none\" stroke=\"{}\" stroke-width=\"{width}\"{extra} points=\"{}\"/>\n",
        escape(colour),
        pts.join(" ")
    )
}

/// One extra attribute, ` name="value"` (the value escaped), for the `extra` argument of the
/// element functions: e.g. `attr("font-size", 14)`, `attr("fill", "#555")`,
/// `attr("stroke-dasharray", "4 3")`.
pub fn attr(name: &str, value: impl fmt::Display) -> String {
    format!(" {name}=\"{}\"", escape(&value.to_string()))
}

/// A text label: `content` (escaped here) with its baseline's `anchor` at (`x`, `y`); `extra`
/// attributes (from [`attr`]: a font size, a fill) follow the anchor.
pub fn text(
    x: impl Into<Coord>,
    y: impl Into<Coord>,
    anchor: Anchor,
    extra: &str,
    content: &str,
) -> String {
    format!(
        "<text x=\"{}\" y=\"{}\"{}{extra}>{}</text>\n",
        x.into(),
        y.into(),
        anchor.attr(),
        escape(content)
    )
}

/// One line of a figure's title: centred at (`x`, `y`), `size` px, marked `class="title"` (so
/// that a test can find the title's lines).
pub fn title_line(x: impl Into<Coord>, y: impl Into<Coord>, size: f64, content: &str) -> String {
    format!(
        "<text class=\"title\" x=\"{}\" y=\"{}\" text-anchor=\"middle\" font-size=\"{size}\">{}</text>\n",
        x.into(),
        y.into(),
        escape(content)
    )
}

/// An axis title turned by `degrees` (−90: reading upwards, beside a y axis on the left; 90:
/// downwards, on the right), centred on (`x`, `y`).
pub fn axis_title(x: impl Into<Coord>, y: impl Into<Coord>, degrees: f64, content: &str) -> String {
    format!(
        "<text transform=\"translate({},{}) rotate({degrees})\" text-anchor=\"middle\">{}</text>\n",
        x.into(),
        y.into(),
        escape(content)
    )
}

/// The drawing's own title (a viewer shows it as the document's name), escaped.
pub fn title(content: &str) -> String {
    format!("<title>{}</title>\n", escape(content))
}

/// A straight line from (x1, y1) to (x2, y2) in `colour`, with `extra` attributes (from
/// [`attr`]: a width, a dash pattern).
pub fn line(
    x1: impl Into<Coord>,
    y1: impl Into<Coord>,
    x2: impl Into<Coord>,
    y2: impl Into<Coord>,
    colour: &str,
    extra: &str,
) -> String {
    format!(
        "<line x1=\"{}\" y1=\"{}\" x2=\"{}\" y2=\"{}\" stroke=\"{}\"{extra}/>\n",
        x1.into(),
        y1.into(),
        x2.into(),
        y2.into(),
        escape(colour)
    )
}

/// A disc of radius `r` px at (`cx`, `cy`) filled with `fill`, with `extra` attributes (from
/// [`attr`]: an opacity) and a `tooltip` (escaped) shown on hover.
pub fn circle(
    cx: impl Into<Coord>,
    cy: impl Into<Coord>,
    r: f64,
    fill: &str,
    extra: &str,
    tooltip: Option<&str>,
) -> String {
    let at = format!("cx=\"{}\" cy=\"{}\" r=\"{r}\"", cx.into(), cy.into());
    shape("circle", &at, fill, extra, tooltip)
}

/// A `w` × `h` rectangle with its top left corner at (`x`, `y`) filled with `fill` (`"none"` for
/// an outline), with `extra` attributes (from [`attr`]: a stroke, an opacity) and a `tooltip`
/// (escaped) shown on hover.
pub fn rect(
    x: impl Into<Coord>,
    y: impl Into<Coord>,
    w: f64,
    h: f64,
    fill: &str,
    extra: &str,
    tooltip: Option<&str>,
) -> String {
    let at = format!(
        "x=\"{}\" y=\"{}\" width=\"{w}\" height=\"{h}\"",
        x.into(),
        y.into()
    );
    shape("rect", &at, fill, extra, tooltip)
}

/// A filled shape `name` placed by the attributes `at`, then its fill, `extra` attributes, and
/// its tooltip as a `<title>` child (or none: an empty element).
fn shape(name: &str, at: &str, fill: &str, extra: &str, tooltip: Option<&str>) -> String {
    let open = format!("<{name} {at} fill=\"{}\"{extra}", escape(fill));
    match tooltip {
        Some(t) => format!("{open}><title>{}</title></{name}>\n", escape(t)),
        None => format!("{open}/>\n"),
    }
}

/// Two elements written on one line of the file (a legend's marker and its label).
pub fn beside(marker: &str, label: &str) -> String {
    format!("{}{label}", marker.trim_end_matches('\n'))
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

/// Reading back what this module writes, for the figures' tests.
#[cfg(test)]
pub(crate) mod read {
    /// How many `name` elements `svg` holds.
    pub fn count(svg: &str, name: &str) -> usize {
        svg.matches(&format!("<{name} ")).count()
    }

    /// A text and its box: (text, x0, y0, x1, y1) in the SVG's user units.
    pub type TextBox = (String, f64, f64, f64, f64);

    /// Boxes of every text label of an SVG written with [`super::text`], [`super::title_line`]
    /// and [`super::axis_title`], estimated independently of the writer's own layout: 0.7 em a
    /// character (DejaVu Sans averages 0.68 em over capitals, less over anything else, so the
    /// estimate is conservative), a font size above the baseline and 0.3 of it below
    /// (descenders); `rotate(±90)` about a `translate` swaps the extents. Returns (text, x0, y0,
    /// x1, y1) and the viewBox.
    pub fn text_boxes(svg: &str) -> (Vec<TextBox>, [f64; 4]) {
        let attr = |tag: &str, name: &str| -> Option<String> {
            let key = format!(" {name}=\"");
            let i = tag.find(&key)? + key.len();
            Some(tag[i..i + tag[i..].find('"')?].to_string())
        };
        let root = &svg[..svg.find('>').expect("svg tag")];
        let vb: Vec<f64> = attr(root, "viewBox")
            .expect("viewBox")
            .split_whitespace()
            .map(|v| v.parse().expect("viewBox number"))
            .collect();
        let base_size: f64 = attr(root, "font-size").map_or(16.0, |v| v.parse().expect("size"));
        let mut boxes = Vec::new();
        for chunk in svg.split("<text").skip(1) {
            let close = chunk.find('>').expect("text tag");
            let tag = &chunk[..close];
            let content = &chunk[close + 1..chunk.find("</text>").expect("</text>")];
            let text = content
                .replace("&lt;", "<")
                .replace("&gt;", ">")
                .replace("&quot;", "\"")
                .replace("&amp;", "&");
            let size: f64 = attr(tag, "font-size").map_or(base_size, |v| v.parse().expect("size"));
            let width = 0.7 * size * text.chars().count() as f64;
            let (along0, along1) = match attr(tag, "text-anchor").as_deref() {
                Some("middle") => (-width / 2.0, width / 2.0),
                Some("end") => (-width, 0.0),
                _ => (0.0, width),
            };
            let (across0, across1) = (-size, 0.3 * size);
            let num = |v: &str| v.trim().parse::<f64>().expect("coordinate");
            let (x0, y0, x1, y1) = match attr(tag, "transform") {
                None => {
                    let (x, y) = (
                        num(&attr(tag, "x").expect("x")),
                        num(&attr(tag, "y").expect("y")),
                    );
                    (x + along0, y + across0, x + along1, y + across1)
                }
                Some(tr) => {
                    let inner = |f: &str| {
                        tr[tr.find(f).expect(f) + f.len()..]
                            .split(')')
                            .next()
                            .expect("a closing parenthesis")
                            .to_string()
                    };
                    let xy: Vec<f64> = inner("translate(").split(',').map(num).collect();
                    let (x, y) = (xy[0], xy[1]);
                    match num(&inner("rotate(")) as i64 {
                        // rotate(-90): text runs upwards, its top faces left.
                        -90 => (x + across0, y - along1, x + across1, y - along0),
                        90 => (x - across1, y + along0, x - across0, y + along1),
                        other => panic!("rotation {other} not handled"),
                    }
                }
            };
            boxes.push((text, x0, y0, x1, y1));
        }
        (boxes, [vb[0], vb[1], vb[0] + vb[2], vb[1] + vb[3]])
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

    /// A bare number is written as Rust prints it, `tenth` with exactly one decimal; the
    /// figures' files depend on both (e.g. `x="360"` and `y="396.0"`).
    #[test]
    fn coordinates_are_written_exactly_or_to_a_tenth() {
        assert_eq!(Coord::from(360.0).to_string(), "360");
        assert_eq!(Coord::from(37.75).to_string(), "37.75");
        assert_eq!(tenth(396.0).to_string(), "396.0");
        assert_eq!(tenth(123.46).to_string(), "123.5");
        assert_eq!(tenth(-0.04).to_string(), "-0.0");
        assert_eq!(
            text(360.0, tenth(22.0), Anchor::Start, "", "a"),
            "<text x=\"360\" y=\"22.0\">a</text>\n"
        );
    }

    /// Every element escapes what it writes, content, tooltips and attribute values alike, so
    /// that a caller cannot forget it (a record's file name or a scene's name may hold `&`).
    #[test]
    fn elements_escape_their_text_and_write_their_attributes() {
        assert_eq!(
            text(1.0, 2.0, Anchor::Middle, &attr("font-size", 14), "a<b> & \"c\""),
            "<text x=\"1\" y=\"2\" text-anchor=\"middle\" font-size=\"14\">a&lt;b&gt; &amp; &quot;c&quot;</text>\n"
        );
        assert_eq!(
            text(1.0, 2.0, Anchor::End, &attr("fill", "#555"), "x"),
            "<text x=\"1\" y=\"2\" text-anchor=\"end\" fill=\"#555\">x</text>\n"
        );
        assert_eq!(
            title_line(360.0, tenth(22.2), 12.0, "R&D"),
            "<text class=\"title\" x=\"360\" y=\"22.2\" text-anchor=\"middle\" font-size=\"12\">R&amp;D</text>\n"
        );
        assert_eq!(
            axis_title(18.0, tenth(205.0), -90.0, "PSA <g>"),
            "<text transform=\"translate(18,205.0) rotate(-90)\" text-anchor=\"middle\">PSA &lt;g&gt;</text>\n"
        );
        assert_eq!(title("a & b"), "<title>a &amp; b</title>\n");
        assert_eq!(attr("title", "\"q\""), " title=\"&quot;q&quot;\"");
        assert_eq!(
            circle(tenth(1.04), tenth(2.0), 3.5, "#c00", &attr("opacity", 0.8), Some("<x>")),
            "<circle cx=\"1.0\" cy=\"2.0\" r=\"3.5\" fill=\"#c00\" opacity=\"0.8\"><title>&lt;x&gt;</title></circle>\n"
        );
        assert_eq!(
            rect(1.0, 2.0, 7.0, 7.0, "black", "", None),
            "<rect x=\"1\" y=\"2\" width=\"7\" height=\"7\" fill=\"black\"/>\n"
        );
        assert_eq!(
            frame(70.0, 40.0, 500.0, 330.0),
            "<rect x=\"70\" y=\"40\" width=\"500\" height=\"330\" fill=\"none\" stroke=\"black\"/>\n"
        );
        assert_eq!(
            line(70.0, tenth(5.0), 90.0, tenth(5.0), "#c00", &attr("stroke-dasharray", "4 3")),
            "<line x1=\"70\" y1=\"5.0\" x2=\"90\" y2=\"5.0\" stroke=\"#c00\" stroke-dasharray=\"4 3\"/>\n"
        );
        assert_eq!(
            grid_line(1.0, 2.04, 3.0, 4.0),
            "<line x1=\"1.0\" y1=\"2.0\" x2=\"3.0\" y2=\"4.0\" stroke=\"#ddd\"/>\n"
        );
        assert_eq!(
            beside(&rect(1.0, 2.0, 7.0, 7.0, "red", "", None), &text(3.0, 4.0, Anchor::Start, "", "k")),
            "<rect x=\"1\" y=\"2\" width=\"7\" height=\"7\" fill=\"red\"/><text x=\"3\" y=\"4\">k</text>\n"
        );
    }

    /// The read-back helpers find what the writers wrote, rotated labels included.
    #[test]
    fn text_boxes_read_back_plain_and_rotated_labels() {
        let svg = document(100.0, 50.0, 10.0, true)
            + &text(50.0, 20.0, Anchor::Middle, "", "abcd")
            + &axis_title(10.0, 25.0, -90.0, "ab")
            + END;
        let (boxes, vb) = read::text_boxes(&svg);
        assert_eq!(vb, [0.0, 0.0, 100.0, 50.0]);
        assert_eq!(read::count(&svg, "text"), 2);
        // "abcd" at 10 px: 28 px wide, centred on 50; 10 px above the baseline, 3 below.
        let close = |a: f64, b: f64| (a - b).abs() < 1e-9;
        let (t, x0, y0, x1, y1) = &boxes[0];
        assert!(
            t == "abcd"
                && close(*x0, 36.0)
                && close(*y0, 10.0)
                && close(*x1, 64.0)
                && close(*y1, 23.0)
        );
        // "ab" turned upwards about (10, 25): 14 px tall, 13 px wide.
        let (_, x0, y0, x1, y1) = &boxes[1];
        assert!(
            close(*x0, 0.0) && close(*y0, 18.0) && close(*x1, 13.0) && close(*y1, 32.0),
            "{:?}",
            boxes[1]
        );
    }
}
