//! Drawing a laid-out figure on a [`Canvas`] (the same calls for SVG and PNG): panels, bands,
//! grid, reference lines, switching-time markers, data, frame and ticks, texts, legend.

use super::clip::clip_polyline;
use super::layout::*;
use super::prepare::{Prepared, dash_pattern, tx};
use super::{Layout, LineFigure, Scale};
use crate::PlotError;
use crate::canvas::{Anchor, Canvas, RectSpec, Stroke, TextSpec};

/// Fill opacity factor of a band drawn wider than its data ([`super::MIN_BAND_PX`]).
const NARROW_BAND_OPACITY_GAIN: f64 = 3.0;
pub(super) fn draw_all(
    cv: &mut dyn Canvas,
    size: (u32, u32),
    title: &str,
    panels: &[LineFigure],
    prepared: &[Prepared],
    layout: Layout,
) -> Result<(), PlotError> {
    let (w, h) = (size.0 as f64, size.1 as f64);
    let mut top = 0.0;
    if !title.is_empty() {
        let (title, size) = fit_text(title, TITLE_FONT, w - 2.0 * MARGIN);
        cv.text(&TextSpec {
            text: &title,
            x: 0.5 * w,
            y: 0.75 * TITLE_FONT,
            size,
            colour: (0, 0, 0),
            anchor: Anchor::Middle,
            vertical: false,
            class: "title",
        })?;
        top = 1.5 * TITLE_FONT;
    }
    let n = panels.len() as f64;
    let title_font = if panels.len() > 1 || !title.is_empty() {
        PANEL_TITLE_FONT
    } else {
        TITLE_FONT
    };
    let areas: Vec<PxRect> = (0..panels.len())
        .map(|k| {
            let k = k as f64;
            match layout {
                Layout::Rows => {
                    let ph = (h - top) / n;
                    PxRect {
                        x0: 0.0,
                        y0: top + k * ph,
                        x1: w,
                        y1: top + (k + 1.0) * ph,
                    }
                }
                Layout::Columns => PxRect {
                    x0: k * w / n,
                    y0: top,
                    x1: (k + 1.0) * w / n,
                    y1: h,
                },
            }
        })
        .collect();
    let mut lays: Vec<PanelLayout> = panels
        .iter()
        .zip(prepared)
        .zip(&areas)
        .map(|((f, p), a)| layout_panel(f, p, *a, title_font, (Y_LABEL_AREA, 0.0)))
        .collect();
    if layout == Layout::Rows && panels.len() > 1 {
        // Stacked panels share their time axis: same left edge and same width. A panel laid
        // out again may need more room than the others got (a wider legend beside the axes),
        // so repeat until they agree; the room only grows, and is bounded by the widest need.
        for _ in 0..4 {
            let ya = lays.iter().map(|l| l.y_area).fold(0.0f64, f64::max);
            let out = lays.iter().map(|l| l.outside).fold(0.0f64, f64::max);
            if lays.iter().all(|l| l.y_area >= ya && l.outside >= out) {
                break;
            }
            lays = panels
                .iter()
                .zip(prepared)
                .zip(&areas)
                .map(|((f, p), a)| layout_panel(f, p, *a, title_font, (ya, out)))
                .collect();
        }
    }
    for ((fig, prep), lay) in panels.iter().zip(prepared).zip(&lays) {
        draw_panel(cv, fig, prep, lay, title_font)?;
    }
    Ok(())
}

pub(super) fn draw_panel(
    cv: &mut dyn Canvas,
    fig: &LineFigure,
    prep: &Prepared,
    lay: &PanelLayout,
    title_font: f64,
) -> Result<(), PlotError> {
    let m = &lay.map;
    let p = m.plot;
    let txt = |text: &str, x: f64, y: f64, size: f64, anchor: Anchor, class: &'static str| {
        (text.to_string(), x, y, size, anchor, class)
    };
    let mut texts: Vec<(String, f64, f64, f64, Anchor, &'static str)> = Vec::new();
    if let Some(y) = lay.title_y {
        let (title, size) = fit_text(&fig.title, title_font, lay.area.w() - 2.0 * MARGIN);
        texts.push(txt(
            &title,
            0.5 * (lay.area.x0 + lay.area.x1),
            y,
            size,
            Anchor::Middle,
            "panel-title",
        ));
    }

    // Shaded bands.
    for b in &fig.bands {
        let (Some(a), Some(c)) = (tx(b.x0, fig.x_scale), tx(b.x1, fig.x_scale)) else {
            continue;
        };
        let (a, c) = (a.max(m.xr.0), c.min(m.xr.1));
        if a > c {
            continue;
        }
        // At least MIN_BAND_PX wide about its middle, kept inside the axes.
        let (mut xa, mut xc) = (m.x(a), m.x(c));
        let grow = 0.5 * (super::MIN_BAND_PX - (xc - xa)).max(0.0);
        xa = (xa - grow).max(p.x0);
        xc = (xc + grow).min(p.x1);
        // A widened band is a few pixels next to the dashed switch markers: at the fill of a
        // wide band it does not show, so it gets a stronger one.
        let (colour, opacity) = band_fill(b);
        let opacity = if grow > 0.0 {
            (NARROW_BAND_OPACITY_GAIN * opacity).min(1.0)
        } else {
            opacity
        };
        cv.rect(&RectSpec {
            p0: (xa, p.y0),
            p1: (xc, p.y1),
            fill: Some((colour, opacity)),
            stroke: None,
            class: "band",
        })?;
    }

    // Grid: major lines at labelled ticks, light lines at the others.
    let grid = |labelled: bool| {
        let c = if labelled { 218 } else { 238 };
        Stroke::new((c, c, c), 1.0, None)
    };
    for t in &lay.x_ticks {
        let x = m.x(t.pos);
        cv.polyline(&[(x, p.y0), (x, p.y1)], grid(t.label.is_some()), "grid")?;
    }
    for t in &lay.y_ticks {
        let y = m.y(t.pos);
        cv.polyline(&[(p.x0, y), (p.x1, y)], grid(t.label.is_some()), "grid")?;
    }

    // Horizontal reference lines.
    for (h, &off) in fig.hlines.iter().zip(&lay.off_scale) {
        if off {
            continue;
        }
        let Some(y) = tx(h.y, fig.y_scale) else {
            continue;
        };
        cv.polyline(
            &[(p.x0, m.y(y)), (p.x1, m.y(y))],
            Stroke::new(hline_colour(h), 2.0, Some((14.0, 5.0))),
            "hline",
        )?;
    }

    // Switching-time markers: dashed lines from the bottom of the axes up to their label row.
    for ((t, _), lab) in fig.vertical_markers.iter().zip(&lay.marker_labels) {
        let Some(x) = tx(*t, fig.x_scale).filter(|x| (m.xr.0..=m.xr.1).contains(x)) else {
            continue;
        };
        let top = lab.as_ref().map_or(p.y0, |l| l.bbox.y1);
        cv.polyline(
            &[(m.x(x), p.y1), (m.x(x), top)],
            Stroke::new((90, 90, 90), 1.0, Some((5.0, 4.0))),
            "vmarker",
        )?;
    }

    // Data, in series order (later series above earlier ones): lines clipped to the axes,
    // then that series' markers.
    for s in &prep.series {
        for piece in &s.pieces {
            if s.joined {
                for run in clip_polyline(piece, m.xr, m.yr) {
                    let px: Vec<(f64, f64)> = run.iter().map(|q| m.px(*q)).collect();
                    cv.polyline(
                        &px,
                        Stroke::new(s.colour, s.width as f64, dash_pattern(s.dash)),
                        "series",
                    )?;
                }
            }
            if s.markers || !s.joined {
                for q in piece {
                    let c = m.px(*q);
                    if p.contains(c) {
                        cv.circle(c, 4.0, s.colour, "marker")?;
                    }
                }
            }
        }
    }

    // Frame, ticks and axis descriptions.
    cv.rect(&RectSpec {
        p0: (p.x0, p.y0),
        p1: (p.x1, p.y1),
        fill: None,
        stroke: Some((60, 60, 60)),
        class: "frame",
    })?;
    cv.meta(&format!(
        "<g class=\"axes\" data-plot=\"{} {} {} {}\" data-xr=\"{:e} {:e}\" data-yr=\"{:e} {:e}\" \
         data-xscale=\"{}\" data-yscale=\"{}\"/>",
        p.x0,
        p.y0,
        p.x1,
        p.y1,
        m.xr.0,
        m.xr.1,
        m.yr.0,
        m.yr.1,
        scale_name(fig.x_scale),
        scale_name(fig.y_scale)
    ));
    for t in &lay.x_ticks {
        let x = m.x(t.pos);
        let len = if t.label.is_some() { 6.0 } else { 3.0 };
        cv.polyline(
            &[(x, p.y1), (x, p.y1 + len)],
            Stroke::new((60, 60, 60), 1.0, None),
            "tick",
        )?;
        if let Some(l) = &t.label {
            texts.push(txt(
                l,
                x,
                p.y1 + 8.0 + 0.5 * TICK_FONT,
                TICK_FONT,
                Anchor::Middle,
                "tick-x",
            ));
        }
    }
    for t in &lay.y_ticks {
        let y = m.y(t.pos);
        let len = if t.label.is_some() { 6.0 } else { 3.0 };
        cv.polyline(
            &[(p.x0 - len, y), (p.x0, y)],
            Stroke::new((60, 60, 60), 1.0, None),
            "tick",
        )?;
        if let Some(l) = &t.label {
            texts.push(txt(l, p.x0 - 9.0, y, TICK_FONT, Anchor::End, "tick-y"));
        }
    }
    let (x_label, x_size) = fit_text(&fig.x_label, DESC_FONT, p.w());
    texts.push(txt(
        &x_label,
        0.5 * (p.x0 + p.x1),
        p.y1 + X_LABEL_AREA - 0.5 * DESC_FONT - 4.0,
        x_size,
        Anchor::Middle,
        "xdesc",
    ));
    for (s, x, y, size, anchor, class) in &texts {
        cv.text(&TextSpec {
            text: s,
            x: *x,
            y: *y,
            size: *size,
            colour: TEXT_COLOUR,
            anchor: *anchor,
            vertical: false,
            class,
        })?;
    }
    let (y_label, y_size) = fit_text(&fig.y_label, DESC_FONT, p.h());
    cv.text(&TextSpec {
        text: &y_label,
        x: p.x0 - lay.y_area + 0.5 * DESC_FONT + 2.0,
        y: 0.5 * (p.y0 + p.y1),
        size: y_size,
        colour: TEXT_COLOUR,
        anchor: Anchor::Middle,
        vertical: true,
        class: "ydesc",
    })?;
    for l in lay.marker_labels.iter().flatten() {
        // On white, so that the dashed line of a neighbouring marker does not cross the text.
        let b = l.bbox.inflate(1.0);
        cv.rect(&RectSpec {
            p0: (b.x0, b.y0),
            p1: (b.x1, b.y1),
            fill: Some(((255, 255, 255), 1.0)),
            stroke: None,
            class: "label-bg",
        })?;
        cv.text(&TextSpec {
            text: &l.text,
            x: l.x,
            y: l.y,
            size: MARKER_FONT,
            colour: (60, 60, 60),
            anchor: l.anchor,
            vertical: false,
            class: "marker-label",
        })?;
    }
    for (l, c) in &lay.point_labels {
        // Dark version of the series colour: readable on white, still matched to its points.
        let dark = (c.0 / 2, c.1 / 2, c.2 / 2);
        cv.text(&TextSpec {
            text: &l.text,
            x: l.x,
            y: l.y,
            size: POINT_LABEL_FONT,
            colour: dark,
            anchor: l.anchor,
            vertical: false,
            class: "point-label",
        })?;
    }

    // Legend last, above everything it may touch.
    if let Some((b, entries)) = &lay.legend {
        cv.rect(&RectSpec {
            p0: (b.x0, b.y0),
            p1: (b.x1, b.y1),
            fill: Some(((255, 255, 255), 0.9)),
            stroke: Some((160, 160, 160)),
            class: "legend-box",
        })?;
        for (i, (label, sample)) in entries.iter().enumerate() {
            let y = b.y0 + 5.0 + (i as f64 + 0.5) * LEGEND_ROW;
            let (x0, x1) = (b.x0 + 8.0, b.x0 + 34.0);
            match *sample {
                Sample::Line {
                    colour,
                    width,
                    dash,
                    marker,
                } => {
                    cv.polyline(
                        &[(x0, y), (x1, y)],
                        Stroke {
                            colour,
                            width,
                            dash,
                        },
                        "legend-sample",
                    )?;
                    if marker {
                        cv.circle((0.5 * (x0 + x1), y), 4.0, colour, "legend-sample")?;
                    }
                }
                Sample::Marker(c) => cv.circle((0.5 * (x0 + x1), y), 4.0, c, "legend-sample")?,
                Sample::Fill(c, o) => cv.rect(&RectSpec {
                    p0: (x0, y - 6.0),
                    p1: (x1, y + 6.0),
                    fill: Some((c, o)),
                    stroke: None,
                    class: "legend-sample",
                })?,
            }
            cv.text(&TextSpec {
                text: label,
                x: b.x0 + 42.0,
                y,
                size: LEGEND_FONT,
                colour: TEXT_COLOUR,
                anchor: Anchor::Start,
                vertical: false,
                class: "legend",
            })?;
        }
    }
    Ok(())
}

pub(super) fn scale_name(s: Scale) -> &'static str {
    match s {
        Scale::Linear => "linear",
        Scale::Log10 => "log10",
    }
}
