//! Drawing primitives shared by the SVG and PNG outputs, in fractional pixel coordinates.
//!
//! [`SvgCanvas`] writes the SVG itself, so coordinates keep two decimals (plotters' SVG backend
//! rounds every coordinate to a whole pixel, which turns smooth curves into stair steps).
//! [`PngCanvas`] draws through plotters' bitmap backend (whole pixels are the resolution of a
//! bitmap anyway) and splits thick polylines at sharp turns ([`split_sharp_turns`]).
//! Text is measured with the embedded font's own metrics ([`text_size`], `crate::font`) at the
//! em size both outputs draw it at: the SVG names DejaVu Sans with that `font-size`, the PNG
//! draws the embedded file at the same em size. A viewer without DejaVu Sans substitutes its
//! `sans-serif`, which is narrower for the common ones (Arial, Helvetica, Liberation Sans).

use crate::font;
use crate::{FONT, PlotError};
use plotters::coord::Shift;
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};
use std::fmt::Write as _;

/// An RGB colour.
pub(crate) type Rgb = (u8, u8, u8);

/// A point in fractional pixels, (x, y) with y downwards.
pub(crate) type Point = (f64, f64);

/// Horizontal anchor of a text.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Anchor {
    Start,
    Middle,
    End,
}

/// A text to draw: `(x, y)` is the anchor point, vertically the middle of the text's capitals;
/// `size` is the em size in pixels.
pub(crate) struct TextSpec<'a> {
    pub text: &'a str,
    pub x: f64,
    pub y: f64,
    pub size: f64,
    pub colour: Rgb,
    pub anchor: Anchor,
    /// Rotated by −90° (reading upwards), for the y-axis description.
    pub vertical: bool,
    /// Role of the text in the SVG (`class` attribute), e.g. `tick-x`, `legend`.
    pub class: &'a str,
}

/// How a polyline is stroked: colour, width in pixels and an optional dash pattern
/// (on, off) in pixels.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Stroke {
    pub colour: Rgb,
    pub width: f64,
    pub dash: Option<(f64, f64)>,
}

impl Stroke {
    pub fn new(colour: Rgb, width: f64, dash: Option<(f64, f64)>) -> Self {
        Self {
            colour,
            width,
            dash,
        }
    }
}

/// An axis-parallel rectangle to draw between the corners `p0` and `p1` (any two opposite
/// corners), filled with `fill` = (colour, opacity) and/or stroked 1 px in `stroke`.
pub(crate) struct RectSpec<'a> {
    pub p0: (f64, f64),
    pub p1: (f64, f64),
    pub fill: Option<(Rgb, f64)>,
    pub stroke: Option<Rgb>,
    /// Role of the rectangle in the SVG (`class` attribute), e.g. `frame`, `legend-box`.
    pub class: &'a str,
}

/// Advance width and line height (ascent + descent) in pixels of `text` at em size `size` in
/// the embedded font.
pub(crate) fn text_size(text: &str, size: f64) -> (f64, f64) {
    (font::text_width(text, size), font::line_height(size))
}

/// The drawing operations the figure layout needs.
pub(crate) trait Canvas {
    /// An open polyline.
    fn polyline(&mut self, pts: &[Point], stroke: Stroke, class: &str) -> Result<(), PlotError>;
    /// An axis-parallel rectangle, filled (with opacity) and/or stroked.
    fn rect(&mut self, r: &RectSpec) -> Result<(), PlotError>;
    /// A filled circle.
    fn circle(&mut self, c: (f64, f64), r: f64, fill: Rgb, class: &str) -> Result<(), PlotError>;
    /// A text.
    fn text(&mut self, t: &TextSpec) -> Result<(), PlotError>;
    /// Machine-readable metadata (the SVG keeps it as an empty element; bitmaps ignore it).
    fn meta(&mut self, _element: &str) {}
}

fn hex(c: Rgb) -> String {
    format!("#{:02X}{:02X}{:02X}", c.0, c.1, c.2)
}

fn f2(v: f64) -> String {
    let s = format!("{v:.2}");
    let s = s.trim_end_matches('0').trim_end_matches('.');
    if s == "-0" { "0".into() } else { s.into() }
}

fn xml_escape(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
        .replace('"', "&quot;")
}

/// SVG text output with fractional coordinates.
pub(crate) struct SvgCanvas {
    out: String,
}

impl SvgCanvas {
    /// An empty white page of `size` pixels.
    pub fn new(size: (u32, u32)) -> Self {
        let (w, h) = size;
        let mut out = String::new();
        let _ = write!(
            out,
            "<svg width=\"{w}\" height=\"{h}\" viewBox=\"0 0 {w} {h}\" \
             xmlns=\"http://www.w3.org/2000/svg\">\n\
             <rect x=\"0\" y=\"0\" width=\"{w}\" height=\"{h}\" fill=\"#FFFFFF\"/>\n"
        );
        Self { out }
    }

    /// The finished document.
    pub fn finish(mut self) -> String {
        self.out.push_str("</svg>\n");
        self.out
    }
}

impl Canvas for SvgCanvas {
    fn meta(&mut self, element: &str) {
        self.out.push_str(element);
        self.out.push('\n');
    }

    fn polyline(&mut self, pts: &[Point], stroke: Stroke, class: &str) -> Result<(), PlotError> {
        if pts.len() < 2 {
            return Ok(());
        }
        let mut p = String::with_capacity(pts.len() * 14);
        for (i, &(x, y)) in pts.iter().enumerate() {
            if i > 0 {
                p.push(' ');
            }
            let _ = write!(p, "{},{}", f2(x), f2(y));
        }
        let dash = stroke
            .dash
            .map(|(a, b)| format!(" stroke-dasharray=\"{} {}\"", f2(a), f2(b)))
            .unwrap_or_default();
        let _ = writeln!(
            self.out,
            "<polyline class=\"{class}\" fill=\"none\" stroke=\"{}\" stroke-width=\"{}\" \
             stroke-linejoin=\"round\" stroke-linecap=\"round\"{dash} points=\"{p}\"/>",
            hex(stroke.colour),
            f2(stroke.width)
        );
        Ok(())
    }

    fn rect(&mut self, r: &RectSpec) -> Result<(), PlotError> {
        let (p0, p1, class) = (r.p0, r.p1, r.class);
        let (x, y) = (p0.0.min(p1.0), p0.1.min(p1.1));
        let (w, h) = ((p1.0 - p0.0).abs(), (p1.1 - p0.1).abs());
        let fill = match r.fill {
            Some((c, o)) => format!("fill=\"{}\" fill-opacity=\"{}\"", hex(c), f2(o)),
            None => "fill=\"none\"".into(),
        };
        let stroke = r
            .stroke
            .map(|c| format!(" stroke=\"{}\" stroke-width=\"1\"", hex(c)))
            .unwrap_or_default();
        let _ = writeln!(
            self.out,
            "<rect class=\"{class}\" x=\"{}\" y=\"{}\" width=\"{}\" height=\"{}\" {fill}{stroke}/>",
            f2(x),
            f2(y),
            f2(w),
            f2(h)
        );
        Ok(())
    }

    fn circle(&mut self, c: (f64, f64), r: f64, fill: Rgb, class: &str) -> Result<(), PlotError> {
        let _ = writeln!(
            self.out,
            "<circle class=\"{class}\" cx=\"{}\" cy=\"{}\" r=\"{}\" fill=\"{}\"/>",
            f2(c.0),
            f2(c.1),
            f2(r),
            hex(fill)
        );
        Ok(())
    }

    fn text(&mut self, t: &TextSpec) -> Result<(), PlotError> {
        let anchor = match t.anchor {
            Anchor::Start => "start",
            Anchor::Middle => "middle",
            Anchor::End => "end",
        };
        // The anchor is the middle of the capitals: the baseline is half a capital height lower
        // (to the right, for text rotated to read upwards).
        let b = font::baseline_below_middle(t.size);
        let (x, y) = (t.x, t.y);
        let (bx, by, rot) = if t.vertical {
            (
                x + b,
                y,
                format!(" transform=\"rotate(-90 {} {})\"", f2(x + b), f2(y)),
            )
        } else {
            (x, y + b, String::new())
        };
        let _ = writeln!(
            self.out,
            "<text class=\"{}\" x=\"{}\" y=\"{}\" font-family=\"{}, {FONT}\" font-size=\"{}\" \
             fill=\"{}\" text-anchor=\"{anchor}\"{rot}>{}</text>",
            t.class,
            f2(bx),
            f2(by),
            font::FAMILY,
            f2(t.size),
            hex(t.colour),
            xml_escape(t.text)
        );
        Ok(())
    }
}

fn de<E: std::fmt::Display>(e: E) -> PlotError {
    PlotError::Draw(e.to_string())
}

/// Bitmap output through plotters.
pub(crate) struct PngCanvas<'a, DB: DrawingBackend> {
    area: &'a DrawingArea<DB, Shift>,
}

impl<'a, DB: DrawingBackend> PngCanvas<'a, DB> {
    /// Draws on `area` (already filled white by the caller).
    pub fn new(area: &'a DrawingArea<DB, Shift>) -> Self {
        Self { area }
    }
}

fn ipt((x, y): (f64, f64)) -> (i32, i32) {
    (x.round() as i32, y.round() as i32)
}

impl<DB: DrawingBackend> Canvas for PngCanvas<'_, DB> {
    fn polyline(&mut self, pts: &[Point], stroke: Stroke, _class: &str) -> Result<(), PlotError> {
        let c = RGBColor(stroke.colour.0, stroke.colour.1, stroke.colour.2);
        let w = stroke.width.round().max(1.0) as u32;
        let style = c.stroke_width(w);
        let px: Vec<(i32, i32)> = pts.iter().map(|&p| ipt(p)).collect();
        let (strokes, joins) = split_sharp_turns(pts, &px);
        for s in strokes {
            let sp: Vec<(i32, i32)> = s.iter().map(|&p| ipt(p)).collect();
            match stroke.dash {
                None => self.area.draw(&PathElement::new(sp, style)).map_err(de)?,
                Some((on, off)) => self
                    .area
                    .draw(&plotters::element::DashedPathElement::new(
                        sp,
                        on.round().max(1.0) as i32,
                        off.round().max(1.0) as i32,
                        style,
                    ))
                    .map_err(de)?,
            }
        }
        // Round joins where a solid line was split (dashes simply restart).
        if stroke.dash.is_none() && w >= 2 {
            let r = (w / 2).max(1);
            for j in joins {
                self.area
                    .draw(&Circle::new(ipt(j), r, style.filled()))
                    .map_err(de)?;
            }
        }
        Ok(())
    }

    fn rect(&mut self, r: &RectSpec) -> Result<(), PlotError> {
        let (p0, p1) = (r.p0, r.p1);
        if let Some((c, o)) = r.fill {
            let s = RGBColor(c.0, c.1, c.2).mix(o).filled();
            self.area
                .draw(&Rectangle::new([ipt(p0), ipt(p1)], s))
                .map_err(de)?;
        }
        if let Some(c) = r.stroke {
            let s = RGBColor(c.0, c.1, c.2).stroke_width(1);
            self.area
                .draw(&Rectangle::new([ipt(p0), ipt(p1)], s))
                .map_err(de)?;
        }
        Ok(())
    }

    fn circle(&mut self, c: (f64, f64), r: f64, fill: Rgb, _class: &str) -> Result<(), PlotError> {
        let s = RGBColor(fill.0, fill.1, fill.2).filled();
        self.area
            .draw(&Circle::new(ipt(c), r.round().max(1.0) as u32, s))
            .map_err(de)?;
        Ok(())
    }

    fn text(&mut self, t: &TextSpec) -> Result<(), PlotError> {
        // Placed from its top-left corner with our own width, so that both outputs put the
        // text where the layout measured it: plotters' ab_glyph backend puts the baseline half
        // its size below the top-left anchor, and scales to ascent − descent (see
        // `font::plotters_size`).
        let size = font::plotters_size(t.size);
        let w = font::text_width(t.text, t.size);
        let before = match t.anchor {
            Anchor::Start => 0.0,
            Anchor::Middle => 0.5 * w,
            Anchor::End => w,
        };
        let b = font::baseline_below_middle(t.size);
        let colour = RGBColor(t.colour.0, t.colour.1, t.colour.2);
        let mut style = TextStyle::from((FONT, size).into_font())
            .color(&colour)
            .pos(Pos::new(HPos::Left, VPos::Top));
        let pos = if t.vertical {
            // Rotated by 270°: the text runs upwards from the anchor, the glyphs' "down" is +x.
            style = style.transform(FontTransform::Rotate270);
            (t.x + b - 0.5 * size, t.y + before)
        } else {
            (t.x - before, t.y + b - 0.5 * size)
        };
        self.area
            .draw(&Text::new(t.text.to_string(), ipt(pos), style))
            .map_err(de)?;
        Ok(())
    }
}

/// Points of one polyline in plotting coordinates.
pub(crate) type Polyline = Vec<(f64, f64)>;

/// Splits a run (data points `pts`, their pixel positions `px`) into strokes that turn by less
/// than 120° at every interior vertex, dropping points on the same pixel as their predecessor.
/// Returns the strokes (with at least two distinct pixels each) and the split vertices.
///
/// Why: plotters turns a thick path into a polygon through the intersections of the offset
/// edges; at a hairpin the intersection lies d / sin(φ/2) from the vertex (d = half the width,
/// φ the angle between the two edges), i.e. thousands of pixels away for φ → 0. Keeping
/// φ ≥ 60° bounds that overshoot by 2 d, one line width.
pub(crate) fn split_sharp_turns(
    pts: &[(f64, f64)],
    px: &[(i32, i32)],
) -> (Vec<Polyline>, Polyline) {
    let mut keep: Vec<usize> = Vec::with_capacity(pts.len());
    for (i, p) in px.iter().enumerate() {
        if keep.last().is_none_or(|&k| px[k] != *p) {
            keep.push(i);
        }
    }
    let (mut strokes, mut joins) = (Vec::new(), Vec::new());
    if keep.len() < 2 {
        return (strokes, joins);
    }
    let mut cur = vec![pts[keep[0]]];
    for w in keep.windows(3) {
        let (a, v, b) = (px[w[0]], px[w[1]], px[w[2]]);
        let e1 = ((a.0 - v.0) as f64, (a.1 - v.1) as f64);
        let e2 = ((b.0 - v.0) as f64, (b.1 - v.1) as f64);
        cur.push(pts[w[1]]);
        // cos φ > 1/2 ⇔ φ < 60°.
        if e1.0 * e2.0 + e1.1 * e2.1 > 0.5 * libm::hypot(e1.0, e1.1) * libm::hypot(e2.0, e2.1) {
            strokes.push(std::mem::replace(&mut cur, vec![pts[w[1]]]));
            joins.push(pts[w[1]]);
        }
    }
    cur.push(pts[keep[keep.len() - 1]]);
    strokes.push(cur);
    (strokes, joins)
}
