//! Pixel layout of one panel, decided before anything is drawn: axes rectangle, ticks,
//! rows of switching-time labels, legend placement (free corner, head room, or beside the
//! axes) and point-label placement.

use super::clip::clip_polyline;
use super::prepare::{Prepared, dash_pattern, tx};
use super::{Band, Colour, HLine, LegendPos, LineFigure, Scale};
use crate::canvas::{Anchor, Rgb, text_size};
use crate::ticks::{self, Tick};

// Layout constants (pixels). Shared by SVG and PNG so both look the same.
pub(super) const MARGIN: f64 = 14.0;
pub(super) const X_LABEL_AREA: f64 = 58.0;
pub(super) const Y_LABEL_AREA: f64 = 92.0;
// Font sizes are em sizes (SVG `font-size`).
pub(super) const TITLE_FONT: f64 = 20.5;
pub(super) const PANEL_TITLE_FONT: f64 = 17.0;
pub(super) const DESC_FONT: f64 = 15.5;
pub(super) const TICK_FONT: f64 = 13.0;
pub(super) const LEGEND_FONT: f64 = 13.0;
pub(super) const MARKER_FONT: f64 = 11.0;
pub(super) const POINT_LABEL_FONT: f64 = 10.5;

/// The largest share of an axes' height that head room for a legend may take: the data keep
/// at least the rest.
const MAX_HEADROOM: f64 = 0.6;

/// Titles and axis descriptions are never drawn smaller than this fraction of their size; a
/// longer one is cut to fit (with an ellipsis) rather than drawn unreadably small.
const MIN_FIT_SCALE: f64 = 0.7;
/// Rows of switching-time labels above the axes at most.
pub(super) const MAX_MARKER_ROWS: usize = 3;
pub(super) const LEGEND_ROW: f64 = 22.0;
pub(super) const TEXT_COLOUR: Rgb = (40, 40, 40);

/// A pixel rectangle (x0, y0) – (x1, y1), y downwards.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) struct PxRect {
    pub(super) x0: f64,
    pub(super) y0: f64,
    pub(super) x1: f64,
    pub(super) y1: f64,
}

impl PxRect {
    pub(super) fn w(&self) -> f64 {
        self.x1 - self.x0
    }
    pub(super) fn h(&self) -> f64 {
        self.y1 - self.y0
    }
    pub(super) fn overlaps(&self, o: &PxRect) -> bool {
        self.x0 < o.x1 && o.x0 < self.x1 && self.y0 < o.y1 && o.y0 < self.y1
    }
    pub(super) fn overlap_area(&self, o: &PxRect) -> f64 {
        let w = (self.x1.min(o.x1) - self.x0.max(o.x0)).max(0.0);
        let h = (self.y1.min(o.y1) - self.y0.max(o.y0)).max(0.0);
        w * h
    }
    pub(super) fn contains(&self, (x, y): (f64, f64)) -> bool {
        x >= self.x0 && x <= self.x1 && y >= self.y0 && y <= self.y1
    }
    pub(super) fn inflate(&self, d: f64) -> PxRect {
        PxRect {
            x0: self.x0 - d,
            y0: self.y0 - d,
            x1: self.x1 + d,
            y1: self.y1 + d,
        }
    }
}

/// How a legend entry's sample looks.
#[derive(Clone, Copy, Debug)]
pub(super) enum Sample {
    Line {
        colour: Rgb,
        width: f64,
        dash: Option<(f64, f64)>,
        marker: bool,
    },
    Marker(Rgb),
    Fill(Rgb, f64),
}

/// The pixel mapping of one axes.
#[derive(Clone, Copy, Debug)]
pub(super) struct Mapping {
    pub(super) plot: PxRect,
    pub(super) xr: (f64, f64),
    pub(super) yr: (f64, f64),
}

impl Mapping {
    pub(super) fn x(&self, v: f64) -> f64 {
        self.plot.x0 + (v - self.xr.0) / (self.xr.1 - self.xr.0) * self.plot.w()
    }
    pub(super) fn y(&self, v: f64) -> f64 {
        self.plot.y1 - (v - self.yr.0) / (self.yr.1 - self.yr.0) * self.plot.h()
    }
    pub(super) fn px(&self, (x, y): (f64, f64)) -> (f64, f64) {
        (self.x(x), self.y(y))
    }
}

/// A placed text (anchor point and class as for [`TextSpec`]) with its estimated box.
#[derive(Clone, Debug)]
pub(super) struct Placed {
    pub(super) text: String,
    pub(super) x: f64,
    pub(super) y: f64,
    pub(super) anchor: Anchor,
    pub(super) bbox: PxRect,
}

/// Everything about a panel that depends on pixel sizes: decided before anything is drawn.
pub(super) struct PanelLayout {
    pub(super) title_y: Option<f64>,
    pub(super) map: Mapping,
    pub(super) x_ticks: Vec<Tick>,
    pub(super) y_ticks: Vec<Tick>,
    pub(super) y_area: f64,
    /// Width reserved right of the axes for the legend (0: legend inside).
    pub(super) outside: f64,
    pub(super) area: PxRect,
    /// Marker label per vertical marker (same order; `None`: unlabelled or outside).
    pub(super) marker_labels: Vec<Option<Placed>>,
    pub(super) legend: Option<(PxRect, Vec<(String, Sample)>)>,
    pub(super) point_labels: Vec<(Placed, Rgb)>,
    /// Horizontal lines outside the y range (listed in the legend as off scale).
    pub(super) off_scale: Vec<bool>,
}

pub(super) fn text_box(text: &str, x: f64, y: f64, size: f64, anchor: Anchor) -> PxRect {
    // Never narrower than 0.55 em per character: SVG viewers may substitute a wider font.
    let (w, h) = text_size(text, size);
    let w = w.max(0.55 * size * text.chars().count() as f64);
    let x0 = match anchor {
        Anchor::Start => x,
        Anchor::Middle => x - 0.5 * w,
        Anchor::End => x - w,
    };
    PxRect {
        x0,
        y0: y - 0.5 * h,
        x1: x0 + w,
        y1: y + 0.5 * h,
    }
}

/// A text and the em size that make it at most `avail` pixels wide: `size` if it fits, else a
/// smaller size down to `MIN_FIT_SCALE` of it, else the text cut short with an ellipsis.
pub(super) fn fit_text(text: &str, size: f64, avail: f64) -> (String, f64) {
    let w = text_size(text, size).0;
    if w <= avail {
        return (text.to_string(), size);
    }
    let s = size * (avail / w).max(MIN_FIT_SCALE);
    if text_size(text, s).0 <= avail {
        return (text.to_string(), s);
    }
    let chars: Vec<char> = text.chars().collect();
    let mut n = chars.len();
    while n > 0 {
        n -= 1;
        let cut: String = chars[..n].iter().collect::<String>().trim_end().to_string() + "…";
        if text_size(&cut, s).0 <= avail {
            return (cut, s);
        }
    }
    ("…".into(), s)
}

/// Whether any part of band `b` lies in the x range `xr` (plotting coordinates): only then is
/// it drawn, and only then is it listed in the legend.
pub(super) fn band_visible(b: &Band, scale: Scale, xr: (f64, f64)) -> bool {
    match (tx(b.x0, scale), tx(b.x1, scale)) {
        (Some(a), Some(c)) => a.max(xr.0) <= c.min(xr.1),
        _ => false,
    }
}

pub(super) fn legend_entries(
    fig: &LineFigure,
    prep: &Prepared,
    off_scale: &[bool],
    xr: (f64, f64),
) -> Vec<(String, Sample)> {
    let mut out: Vec<(String, Sample)> = Vec::new();
    let listed: Vec<_> = prep.series.iter().filter(|s| s.in_legend).collect();
    for (i, s) in listed.iter().enumerate() {
        let c = s.colour;
        let sample = if s.joined {
            Sample::Line {
                colour: c,
                width: s.width as f64,
                dash: dash_pattern(s.dash),
                marker: s.markers,
            }
        } else {
            Sample::Marker(c)
        };
        // A series drawn over an earlier one with the very same points hides it: the legend
        // says so, or the earlier one would seem missing.
        let name = match listed[..i].iter().find(|o| o.pieces == s.pieces) {
            Some(o) => format!("{} (the same points as {})", s.name, o.name),
            None => s.name.clone(),
        };
        out.push((name, sample));
    }
    for (h, &off) in fig.hlines.iter().zip(off_scale) {
        if h.label.is_empty() {
            continue;
        }
        let label = if off {
            format!("{} (off scale)", h.label)
        } else {
            h.label.clone()
        };
        out.push((
            label,
            Sample::Line {
                colour: hline_colour(h),
                width: 2.0,
                dash: Some((14.0, 5.0)),
                marker: false,
            },
        ));
    }
    for b in fig
        .bands
        .iter()
        .filter(|b| band_visible(b, fig.x_scale, xr))
    {
        if !b.label.is_empty() && !out.iter().any(|(l, _)| *l == b.label) {
            let (c, o) = band_fill(b);
            out.push((b.label.clone(), Sample::Fill(c, o)));
        }
    }
    out
}

pub(super) fn hline_colour(h: &HLine) -> Rgb {
    match h.colour {
        Colour::Auto => (70, 70, 70),
        Colour::Rgb(r, g, b) => (r, g, b),
    }
}

pub(super) fn band_fill(b: &Band) -> (Rgb, f64) {
    match b.colour {
        Colour::Auto => ((110, 110, 110), 0.13),
        Colour::Rgb(r, g, bl) => ((r, g, bl), 0.2),
    }
}

/// Pixel sample points of everything drawn as data (every ≤ 4 px along lines), used to find a
/// free place for the legend.
pub(super) fn data_samples(fig: &LineFigure, prep: &Prepared, m: &Mapping) -> Vec<(f64, f64)> {
    let mut out = Vec::new();
    let mut line = |a: (f64, f64), b: (f64, f64)| {
        let n = (libm::hypot(b.0 - a.0, b.1 - a.1) / 4.0)
            .ceil()
            .clamp(1.0, 2000.0) as usize;
        for k in 0..=n {
            let f = k as f64 / n as f64;
            out.push((a.0 + f * (b.0 - a.0), a.1 + f * (b.1 - a.1)));
        }
    };
    for s in &prep.series {
        for piece in &s.pieces {
            if s.joined {
                for run in clip_polyline(piece, m.xr, m.yr) {
                    if let [p] = run.as_slice() {
                        line(m.px(*p), m.px(*p));
                    }
                    for w in run.windows(2) {
                        line(m.px(w[0]), m.px(w[1]));
                    }
                }
            } else {
                for p in piece {
                    if m.plot.contains(m.px(*p)) {
                        line(m.px(*p), m.px(*p));
                    }
                }
            }
        }
    }
    for h in &fig.hlines {
        if let Some(y) = tx(h.y, fig.y_scale).filter(|y| (m.yr.0..=m.yr.1).contains(y)) {
            line((m.plot.x0, m.y(y)), (m.plot.x1, m.y(y)));
        }
    }
    out
}

/// Pixel geometry for given extra room: `y_area` left of the axes, `strip` above them for the
/// switching-time labels, `headroom` pixels added above the data for the legend, `outside`
/// pixels right of the axes for a legend placed there.
pub(super) fn mapping(
    fig: &LineFigure,
    prep: &Prepared,
    area: PxRect,
    title_h: f64,
    y_area: f64,
    strip: f64,
    headroom: f64,
    outside: f64,
) -> Mapping {
    let plot = PxRect {
        x0: area.x0 + MARGIN + y_area,
        y0: area.y0 + title_h + strip + MARGIN,
        x1: area.x1 - 2.0 * MARGIN - outside,
        y1: area.y1 - MARGIN - X_LABEL_AREA,
    };
    let plot = PxRect {
        x1: plot.x1.max(plot.x0 + 10.0),
        y1: plot.y1.max(plot.y0 + 10.0),
        ..plot
    };
    let (xr, mut yr) = (prep.xr, prep.yr);
    if headroom > 0.0 && fig.y_range.is_none() {
        let f = (headroom / plot.h()).min(MAX_HEADROOM);
        yr.1 += (yr.1 - yr.0) * f / (1.0 - f);
    }
    let (xr, yr) = if fig.equal_aspect {
        equal_aspect_ranges(xr, yr, (plot.w(), plot.h()))
    } else {
        (xr, yr)
    };
    Mapping { plot, xr, yr }
}

pub(super) fn axis_ticks(
    scale: Scale,
    r: (f64, f64),
    len_px: f64,
    horizontal: bool,
    whole: bool,
) -> Vec<Tick> {
    // Labels of neighbouring ticks must be apart by the text extent plus a gap.
    let fits = |t: &[Tick]| -> bool {
        let ext: Vec<(f64, f64)> = t
            .iter()
            .map(|t| {
                let p = (t.pos - r.0) / (r.1 - r.0) * len_px;
                let (w, h) = text_size(t.label.as_deref().unwrap_or(""), TICK_FONT);
                let half = if horizontal { 0.5 * w } else { 0.5 * h };
                (p - half, p + half)
            })
            .collect();
        ext.windows(2)
            .all(|w| w[1].0 - w[0].1 >= if horizontal { 14.0 } else { 8.0 })
    };
    match scale {
        Scale::Linear => {
            let max = if horizontal { 10 } else { 8 };
            // Counts tick whole numbers, unless the range holds fewer than two of them.
            let whole_ticks = if whole {
                ticks::linear_ticks_of_step(r.0, r.1, max, 0, &fits)
            } else {
                Vec::new()
            };
            if whole_ticks.len() >= 2 {
                whole_ticks
            } else {
                ticks::linear_ticks(r.0, r.1, max, &fits)
            }
        }
        Scale::Log10 => ticks::log_ticks(r.0, r.1, &fits),
    }
}

/// Lays out one panel; `min` = (least y label area, least room for a legend right of the
/// axes), so that stacked panels can be aligned.
pub(super) fn layout_panel(
    fig: &LineFigure,
    prep: &Prepared,
    area: PxRect,
    title_font: f64,
    min: (f64, f64),
) -> PanelLayout {
    let (title_h, title_y) = if fig.title.is_empty() {
        (0.0, None)
    } else {
        (1.5 * title_font, Some(area.y0 + 0.75 * title_font))
    };
    let labelled_markers = fig
        .vertical_markers
        .iter()
        .filter(|(_, l)| !l.is_empty())
        .count();
    let row = MARKER_FONT + 5.0;
    let mut levels = usize::from(labelled_markers > 0);
    let mut y_area = min.0.max(Y_LABEL_AREA);
    let mut headroom = 0.0;
    let mut outside = min.1;
    let mut forced_corner: Option<[LegendPos; 2]> = None;
    // Each pass may grow one bounded quantity (label area, label rows, legend room) and start
    // over; the last pass accepts what it has.
    let mut pass = 0;
    loop {
        pass += 1;
        let last = pass >= 12;
        let strip = if levels > 0 {
            levels as f64 * row + 4.0
        } else {
            0.0
        };
        let m = mapping(fig, prep, area, title_h, y_area, strip, headroom, outside);
        let x_ticks = axis_ticks(fig.x_scale, m.xr, m.plot.w(), true, fig.x_whole);
        let y_ticks = axis_ticks(fig.y_scale, m.yr, m.plot.h(), false, false);
        // Room for the widest y tick label and the rotated description.
        let widest = y_ticks
            .iter()
            .filter_map(|t| t.label.as_deref())
            .map(|l| text_size(l, TICK_FONT).0)
            .fold(0.0f64, f64::max);
        let need = (widest + 10.0 + DESC_FONT + 14.0).max(Y_LABEL_AREA);
        if need > y_area + 0.5 && !last {
            y_area = need;
            continue;
        }
        // Switching-time labels: greedy rows so that no two labels overlap.
        let mut rows: Vec<Vec<PxRect>> = Vec::new();
        let mut marker_labels = Vec::with_capacity(fig.vertical_markers.len());
        let mut order: Vec<usize> = (0..fig.vertical_markers.len()).collect();
        order.sort_by(|&a, &b| {
            fig.vertical_markers[a]
                .0
                .total_cmp(&fig.vertical_markers[b].0)
        });
        let mut placed: Vec<Option<(Placed, usize)>> = vec![None; fig.vertical_markers.len()];
        for &i in &order {
            let (t, label) = &fig.vertical_markers[i];
            let Some(x) = tx(*t, fig.x_scale).filter(|x| (m.xr.0..=m.xr.1).contains(x)) else {
                continue;
            };
            if label.is_empty() {
                continue;
            }
            let px = m.x(x);
            let (w, _) = text_size(label, MARKER_FONT);
            let (anchor, x0) = if px + 3.0 + w <= m.plot.x1 + MARGIN {
                (Anchor::Start, px + 3.0)
            } else {
                (Anchor::End, px - 3.0)
            };
            let b0 = text_box(label, x0, 0.0, MARKER_FONT, anchor);
            // At most MAX_MARKER_ROWS rows: a label that fits in none is left out (its line
            // is still drawn), so that many switching times do not eat the axes' height.
            let Some(r) = (0..MAX_MARKER_ROWS).find(|&r| {
                rows.get(r)
                    .is_none_or(|v: &Vec<PxRect>| v.iter().all(|o| !o.inflate(3.0).overlaps(&b0)))
            }) else {
                continue;
            };
            if rows.len() <= r {
                rows.resize(r + 1, Vec::new());
            }
            rows[r].push(b0);
            placed[i] = Some((
                Placed {
                    text: label.clone(),
                    x: x0,
                    y: 0.0,
                    anchor,
                    bbox: b0,
                },
                r,
            ));
        }
        if rows.len() > levels && !last {
            levels = rows.len();
            continue;
        }
        let strip_top = m.plot.y0 - strip;
        for p in placed.into_iter() {
            marker_labels.push(p.map(|(mut pl, r)| {
                // Row 0 nearest to the axes.
                let yc = m.plot.y0 - 2.0 - (r as f64 + 0.5) * row;
                pl.y = yc;
                pl.bbox = text_box(&pl.text, pl.x, yc, MARKER_FONT, pl.anchor);
                debug_assert!(pl.bbox.y0 >= strip_top - 1.0);
                pl
            }));
        }

        let off_scale: Vec<bool> = fig
            .hlines
            .iter()
            .map(|h| tx(h.y, fig.y_scale).is_none_or(|y| y < m.yr.0 || y > m.yr.1))
            .collect();
        let entries = legend_entries(fig, prep, &off_scale, m.xr);
        let mut legend = None;
        if !entries.is_empty() && fig.legend != LegendPos::Hidden {
            let tw = entries
                .iter()
                .map(|(l, _)| text_size(l, LEGEND_FONT).0)
                .fold(0.0f64, f64::max);
            let (bw, bh) = (tw + 52.0, LEGEND_ROW * entries.len() as f64 + 10.0);
            let corner = |c: LegendPos| -> PxRect {
                let (l, t) = match c {
                    LegendPos::UpperLeft | LegendPos::LowerLeft => (m.plot.x0 + 8.0, true),
                    _ => (m.plot.x1 - 8.0 - bw, true),
                };
                let _ = t;
                let top = match c {
                    LegendPos::LowerLeft | LegendPos::LowerRight => m.plot.y1 - 8.0 - bh,
                    _ => m.plot.y0 + 8.0,
                };
                PxRect {
                    x0: l,
                    y0: top,
                    x1: l + bw,
                    y1: top + bh,
                }
            };
            let chosen = match fig.legend {
                LegendPos::Auto if outside > 0.0 && outside < bw + 30.0 && !last => {
                    // Room beside the axes set by a neighbouring panel, too narrow for this
                    // legend.
                    outside = bw + 30.0;
                    continue;
                }
                LegendPos::Auto if outside > 0.0 => {
                    // Clear of the last x tick label, which reaches past the frame.
                    let x0 = m.plot.x1 + 24.0;
                    legend = Some((
                        PxRect {
                            x0,
                            y0: m.plot.y0,
                            x1: x0 + bw,
                            y1: m.plot.y0 + bh,
                        },
                        entries.clone(),
                    ));
                    LegendPos::Hidden
                }
                LegendPos::Auto => {
                    let samples = data_samples(fig, prep, &m);
                    let cands: &[LegendPos] = match &forced_corner {
                        Some(c) => c,
                        None => &[
                            LegendPos::UpperRight,
                            LegendPos::UpperLeft,
                            LegendPos::LowerRight,
                            LegendPos::LowerLeft,
                        ],
                    };
                    let mut best = (usize::MAX, LegendPos::UpperRight);
                    for &c in cands {
                        let b = corner(c).inflate(6.0);
                        let n = samples.iter().filter(|p| b.contains(**p)).count();
                        if n < best.0 {
                            best = (n, c);
                        }
                    }
                    // No free corner: beside the axes when head room would take more than a
                    // quarter of a (non-geometric) axes and 60 % of its width remain, or when
                    // head room cannot hold the legend at all (`mapping` gives at most
                    // `MAX_HEADROOM` of the height) and 40 % remain; otherwise room above the
                    // data and an upper corner.
                    let room = bh + 22.0;
                    let remains =
                        |share: f64| m.plot.w() - bw - 30.0 >= (share * m.plot.w()).max(300.0);
                    let beside = if fig.y_range.is_some() || room > MAX_HEADROOM * m.plot.h() {
                        remains(0.4)
                    } else {
                        room > 0.25 * m.plot.h() && remains(0.6)
                    };
                    if best.0 > 0 && !last && forced_corner.is_none() && !fig.equal_aspect && beside
                    {
                        outside = bw + 30.0;
                        continue;
                    }
                    if best.0 > 0 && !last && forced_corner.is_none() && fig.y_range.is_none() {
                        headroom = room;
                        forced_corner = Some([LegendPos::UpperRight, LegendPos::UpperLeft]);
                        continue;
                    }
                    best.1
                }
                c => c,
            };
            if chosen != LegendPos::Hidden {
                legend = Some((corner(chosen), entries));
            }
        }

        // Point labels: next to their point, clear of the legend, of each other and of other
        // labelled points.
        let mut point_labels: Vec<(Placed, Rgb)> = Vec::new();
        let mut taken: Vec<PxRect> = legend.iter().map(|(r, _)| r.inflate(2.0)).collect();
        let dots: Vec<(f64, f64)> = prep
            .series
            .iter()
            .flat_map(|s| s.labels.iter().map(|(p, _)| m.px(*p)))
            .collect();
        for s in &prep.series {
            for (p, text) in &s.labels {
                let (px, py) = m.px(*p);
                if !m.plot.contains((px, py)) {
                    continue;
                }
                let cands = [
                    (Anchor::Start, px + 7.0, py - 10.0),
                    (Anchor::Start, px + 7.0, py + 10.0),
                    (Anchor::End, px - 7.0, py - 10.0),
                    (Anchor::End, px - 7.0, py + 10.0),
                    (Anchor::Middle, px, py - 15.0),
                    (Anchor::Middle, px, py + 15.0),
                    (Anchor::Start, px + 9.0, py),
                    (Anchor::End, px - 9.0, py),
                ];
                let mut best: Option<(f64, Placed)> = None;
                for (anchor, x, y) in cands {
                    let b = text_box(text, x, y, POINT_LABEL_FONT, anchor);
                    let mut cost: f64 = taken.iter().map(|o| o.overlap_area(&b.inflate(1.0))).sum();
                    cost +=
                        dots.iter().filter(|d| b.inflate(4.0).contains(**d)).count() as f64 * 50.0;
                    if !(b.x0 >= m.plot.x0
                        && b.x1 <= m.plot.x1
                        && b.y0 >= m.plot.y0
                        && b.y1 <= m.plot.y1)
                    {
                        cost += 1e6;
                    }
                    if best.as_ref().is_none_or(|(c, _)| cost < *c) {
                        best = Some((
                            cost,
                            Placed {
                                text: text.clone(),
                                x,
                                y,
                                anchor,
                                bbox: b,
                            },
                        ));
                    }
                    if cost == 0.0 {
                        break;
                    }
                }
                if let Some((_, pl)) = best {
                    taken.push(pl.bbox);
                    point_labels.push((pl, s.colour));
                }
            }
        }
        return PanelLayout {
            title_y,
            map: m,
            x_ticks,
            y_ticks,
            y_area,
            outside,
            area,
            marker_labels,
            legend,
            point_labels,
            off_scale,
        };
    }
}

/// Grows one of the ranges about its centre so both axes get the same data-per-pixel scale on
/// a `(pw, ph)` pixel plotting area; the result always contains the input ranges.
pub(super) fn equal_aspect_ranges(
    xr: (f64, f64),
    yr: (f64, f64),
    (pw, ph): (f64, f64),
) -> ((f64, f64), (f64, f64)) {
    let sx = (xr.1 - xr.0) / pw;
    let sy = (yr.1 - yr.0) / ph;
    let (mut x2, mut y2) = (xr, yr);
    if sx > sy {
        let c = 0.5 * (yr.0 + yr.1);
        y2 = (c - 0.5 * sx * ph, c + 0.5 * sx * ph);
    } else {
        let c = 0.5 * (xr.0 + xr.1);
        x2 = (c - 0.5 * sy * pw, c + 0.5 * sy * pw);
    }
    // Rounding in the centre/half-width form must not lose a point on the old boundary.
    (
        (x2.0.min(xr.0), x2.1.max(xr.1)),
        (y2.0.min(yr.0), y2.1.max(yr.1)),
    )
}
