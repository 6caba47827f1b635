//! Lays out every text of an SVG written by bf-plot with usvg (an independent SVG
//! implementation, with HarfBuzz-style shaping), given only the crate's own font file, and lists
//! the texts that do not fit: ink outside the canvas, a legend entry outside its legend box, or
//! an advance width other than the one the layout measured ([`bf_plot::text_width`]).
//!
//! Each `<text>` element is laid out alone in an otherwise empty SVG of the same size, so that
//! every box is known to belong to its element (the crate writes one element per line).

#![allow(dead_code)]

/// usvg options whose font database holds only the embedded DejaVu Sans: no system font can
/// stand in for it, and a text that names a font the database lacks is not laid out at all.
pub fn options() -> usvg::Options<'static> {
    let mut opt = usvg::Options::default();
    opt.fontdb_mut()
        .load_font_data(include_bytes!("../../assets/DejaVuSans.ttf").to_vec());
    opt
}

/// An axis-parallel box (x0, y0, x1, y1).
pub type Rect = (f64, f64, f64, f64);

fn attr<'a>(line: &'a str, key: &str) -> Option<&'a str> {
    let pat = format!(" {key}=\"");
    let i = line.find(&pat)? + pat.len();
    Some(&line[i..i + line[i..].find('"')?])
}

fn num(line: &str, key: &str) -> f64 {
    attr(line, key)
        .and_then(|v| v.parse().ok())
        .unwrap_or(f64::NAN)
}

fn unescape(s: &str) -> String {
    s.replace("&lt;", "<")
        .replace("&gt;", ">")
        .replace("&quot;", "\"")
        .replace("&amp;", "&")
}

/// One text as usvg laid it out.
#[derive(Debug, Clone)]
pub struct LaidOut {
    /// The `class` attribute (tick-x, legend, title, …).
    pub class: String,
    /// The text.
    pub text: String,
    /// Ink box in canvas pixels (glyph outlines, after the element's transform).
    pub ink: Rect,
    /// Advance width usvg gave the text (pixels, before any rotation).
    pub advance: f64,
    /// Advance width the layout measured for it.
    pub layout_width: f64,
}

/// Every text of `svg` laid out by usvg, in document order, and the legend boxes.
pub fn lay_out(svg: &str, opt: &usvg::Options) -> (Vec<LaidOut>, Vec<Rect>, (f64, f64)) {
    let head = svg.lines().next().expect("SVG header");
    let (w, h) = (num(head, "width"), num(head, "height"));
    let mut texts = Vec::new();
    let mut legends = Vec::new();
    for line in svg.lines() {
        if line.starts_with("<rect class=\"legend-box\"") {
            let (x, y) = (num(line, "x"), num(line, "y"));
            legends.push((x, y, x + num(line, "width"), y + num(line, "height")));
        }
        if !line.starts_with("<text") {
            continue;
        }
        let doc = format!(
            "<svg width=\"{w}\" height=\"{h}\" viewBox=\"0 0 {w} {h}\" \
             xmlns=\"http://www.w3.org/2000/svg\">\n{line}\n</svg>\n"
        );
        let tree = usvg::Tree::from_str(&doc, opt).expect("usvg parses the text element");
        let text = find_text(tree.root()).unwrap_or_else(|| panic!("no text laid out: {line}"));
        let ink = text.abs_stroke_bounding_box();
        let content = unescape(&line[line.find('>').unwrap() + 1..line.rfind("</text>").unwrap()]);
        texts.push(LaidOut {
            class: attr(line, "class").unwrap_or("").to_string(),
            layout_width: bf_plot::text_width(&content, num(line, "font-size")),
            text: content,
            ink: (
                ink.left() as f64,
                ink.top() as f64,
                ink.right() as f64,
                ink.bottom() as f64,
            ),
            advance: text.bounding_box().width() as f64,
        });
    }
    (texts, legends, (w, h))
}

fn find_text(g: &usvg::Group) -> Option<&usvg::Text> {
    g.children().iter().find_map(|n| match n {
        usvg::Node::Text(t) => Some(t.as_ref()),
        usvg::Node::Group(g) => find_text(g),
        _ => None,
    })
}

fn inside(a: Rect, b: Rect, tol: f64) -> bool {
    a.0 >= b.0 - tol && a.1 >= b.1 - tol && a.2 <= b.2 + tol && a.3 <= b.3 + tol
}

/// The problems of one SVG: texts whose ink leaves the canvas, legend texts whose ink leaves
/// every legend box, and texts whose advance differs from the layout's measure by more than
/// 0.5 px + 1 %. Empty when everything fits.
pub fn problems(svg: &str, opt: &usvg::Options) -> Vec<String> {
    let (texts, legends, (w, h)) = lay_out(svg, opt);
    let mut out = Vec::new();
    for t in &texts {
        if !inside(t.ink, (0.0, 0.0, w, h), 0.0) {
            out.push(format!(
                "'{}' ({}) leaves the {w} × {h} canvas: ink {:?}",
                t.text, t.class, t.ink
            ));
        }
        if t.class == "legend" && !legends.iter().any(|b| inside(t.ink, *b, 0.0)) {
            out.push(format!(
                "legend text '{}' leaves its box: ink {:?}, boxes {legends:?}",
                t.text, t.ink
            ));
        }
        if (t.advance - t.layout_width).abs() > 0.5 + 0.01 * t.layout_width {
            out.push(format!(
                "'{}' ({}) is {:.2} px wide in usvg, the layout measured {:.2} px",
                t.text, t.class, t.advance, t.layout_width
            ));
        }
    }
    out
}
