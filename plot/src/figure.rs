//! Line figures over plain data, rendered to SVG and PNG with the same layout.
//!
//! [`LineFigure`]: one axes with [`Series`] (polylines, or unjoined markers for unordered
//! points, optionally with per-point labels), switching-time markers (the phase boundaries
//! t_f^(i) of Sect. 4.2 / Fig. 6), horizontal limit lines ([`HLine`], e.g. the torque limit
//! |τ_i| ≤ 1 N m) and shaded x-intervals ([`Band`], e.g. the sticking phase).
//! [`PanelFigure`]: several `LineFigure`s stacked in rows or side by side (e.g. ω_x, ω_y, ω_z).
//!
//! Layout is decided in pixels before anything is drawn, identically for both outputs (the SVG
//! is written with fractional coordinates, the PNG through plotters' bitmap backend, see
//! `canvas`): ticks come from [`crate::ticks`] (labels equal the value at their position);
//! switching-time labels sit in rows above the axes, staggered so that none overlap; the
//! legend goes into the corner with no data under it, and if every corner has data, head room
//! is added above the data for it; point labels are placed next to their point, clear of the
//! legend and of each other.
//!
//! Non-finite points (and non-positive points on a log axis) split a series into separate line
//! pieces — a gap, as in other plotting tools — and are counted in [`RenderReport::skipped_points`].
//! Lines are clipped to the axes rectangle (Liang–Barsky, `clip_segment`) before drawing, so
//! explicit `x_range`/`y_range` narrower than the data never draw outside the axes, and thick
//! bitmap lines are split at sharp turns (`split_sharp_turns`) because plotters' bitmap stroker
//! would otherwise extend hairpins into spikes across the whole image. Default ranges cover
//! every finite point of every series (equal-aspect views: 5 % margin on both axes).
//! Colours follow a 10-colour qualitative palette and dash patterns cycle with period 4, so the
//! first 20 automatically styled series of a figure are pairwise distinct even in grey-scale print.

use crate::canvas::{Anchor, Canvas, PngCanvas, Rgb, SvgCanvas, TextSpec, text_size};
use crate::ticks::{self, Tick};
use crate::{PlotError, ensure_font};
use plotters::prelude::*;
use std::path::{Path, PathBuf};

/// Colour of a series.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum Colour {
    /// Palette colour chosen from the series index within its figure.
    #[default]
    Auto,
    /// Fixed colour (r, g, b).
    Rgb(u8, u8, u8),
}

/// Dash pattern of a series.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum Dash {
    /// Pattern chosen from the series index within its figure (solid, dashed, dotted, long dash).
    #[default]
    Auto,
    /// Continuous line.
    Solid,
    /// 10 px dash, 6 px gap.
    Dashed,
    /// Dots.
    Dotted,
    /// 20 px dash, 7 px gap.
    LongDash,
}

/// Axis scale.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum Scale {
    /// Linear axis.
    #[default]
    Linear,
    /// Decadic logarithmic axis; non-positive values are skipped.
    Log10,
}

/// Where the legend goes.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum LegendPos {
    /// The corner of the plotting area that covers the fewest data points.
    #[default]
    Auto,
    /// Upper left corner.
    UpperLeft,
    /// Upper right corner.
    UpperRight,
    /// Lower left corner.
    LowerLeft,
    /// Lower right corner.
    LowerRight,
    /// No legend.
    Hidden,
}

/// How the panels of a [`PanelFigure`] are arranged.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum Layout {
    /// Stacked vertically (one panel per row).
    #[default]
    Rows,
    /// Side by side (one panel per column).
    Columns,
}

/// Appearance of one series.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct SeriesStyle {
    /// Line colour (default: [`Colour::Auto`]).
    pub colour: Colour,
    /// Dash pattern (default: [`Dash::Auto`]).
    pub dash: Dash,
    /// Line width in pixels (default: 2).
    pub width: u32,
    /// Draw a filled circle at every point (default: false; used by work–precision plots).
    pub markers: bool,
    /// Show the series in the legend (default: true).
    pub in_legend: bool,
}

impl Default for SeriesStyle {
    fn default() -> Self {
        Self {
            colour: Colour::Auto,
            dash: Dash::Auto,
            width: 2,
            markers: false,
            in_legend: true,
        }
    }
}

/// One named data series: a polyline, or (when not [`joined`](Series::joined)) a set of
/// markers.
#[derive(Clone, Debug, PartialEq)]
pub struct Series {
    /// Legend text (every series with a non-empty name and `style.in_legend` gets an entry).
    pub name: String,
    /// Points (x, y) in data units, drawn in this order.
    pub points: Vec<(f64, f64)>,
    /// Appearance.
    pub style: SeriesStyle,
    /// Per-point labels drawn next to the points (e.g. the tolerance, mesh or ε of a run):
    /// empty, or one per point (empty strings: no label).
    pub labels: Vec<String>,
    /// `true` (default): consecutive points are joined by a line. `false`: the points are
    /// unordered or unrelated (runs on different local optima, settings without a natural
    /// order), so they are drawn as markers only.
    pub joined: bool,
}

impl Series {
    /// A series with the default (automatic) style.
    pub fn new(name: impl Into<String>, points: Vec<(f64, f64)>) -> Self {
        Self {
            name: name.into(),
            points,
            style: SeriesStyle::default(),
            labels: Vec::new(),
            joined: true,
        }
    }

    /// The same series with another style.
    pub fn styled(mut self, style: SeriesStyle) -> Self {
        self.style = style;
        self
    }

    /// The same series with one label per point (see [`Series::labels`]).
    pub fn with_labels(mut self, labels: Vec<String>) -> Self {
        self.labels = labels;
        self
    }

    /// The same series drawn as unjoined markers (see [`Series::joined`]).
    pub fn unjoined(mut self) -> Self {
        self.joined = false;
        self
    }
}

/// A horizontal reference line across the whole axes (limits, bounds, zero lines).
#[derive(Clone, Debug, PartialEq)]
pub struct HLine {
    /// Ordinate in data units.
    pub y: f64,
    /// Legend text; empty: not in the legend.
    pub label: String,
    /// Colour (default grey when [`Colour::Auto`]).
    pub colour: Colour,
    /// Whether the autoscaled y range must include the line. `false` for a limit far from the
    /// data (e.g. a torque bound of 1 N m for torques of 0.1 N m): the axis then fits the
    /// data, and a line outside it is listed in the legend as "(off scale)" instead of drawn.
    pub fit: bool,
}

/// A shaded x-interval spanning the full height of the axes (e.g. a contact phase).
#[derive(Clone, Debug, PartialEq)]
pub struct Band {
    /// Left end in data units.
    pub x0: f64,
    /// Right end in data units.
    pub x1: f64,
    /// Legend text (shown once per distinct label); empty: not in the legend.
    pub label: String,
    /// Fill colour (drawn translucent); [`Colour::Auto`]: grey.
    pub colour: Colour,
}

/// A single axes with several series.
#[derive(Clone, Debug, PartialEq)]
pub struct LineFigure {
    /// Caption above the axes (may be empty inside a [`PanelFigure`]).
    pub title: String,
    /// x-axis description including the unit, e.g. "t [s]".
    pub x_label: String,
    /// y-axis description including the unit, e.g. "ω [rad/s]".
    pub y_label: String,
    /// The data.
    pub series: Vec<Series>,
    /// Vertical dashed lines with a short label at the top (phase switching times).
    pub vertical_markers: Vec<(f64, String)>,
    /// Horizontal reference lines.
    pub hlines: Vec<HLine>,
    /// Shaded x-intervals.
    pub bands: Vec<Band>,
    /// x-axis scale (default linear).
    pub x_scale: Scale,
    /// y-axis scale (default linear).
    pub y_scale: Scale,
    /// Fixed x range in data units; `None`: fitted to the data.
    pub x_range: Option<(f64, f64)>,
    /// Fixed y range in data units; `None`: fitted to the data (+5 % padding).
    pub y_range: Option<(f64, f64)>,
    /// Same data-to-pixel scale on both axes (for geometric views; linear axes only).
    pub equal_aspect: bool,
    /// Legend placement (default [`LegendPos::Auto`]).
    pub legend: LegendPos,
    /// Output size in pixels when rendered alone (default 1000 × 600).
    pub size: (u32, u32),
}

impl LineFigure {
    /// An empty figure with title and axis descriptions; add series before rendering.
    pub fn new(
        title: impl Into<String>,
        x_label: impl Into<String>,
        y_label: impl Into<String>,
    ) -> Self {
        Self {
            title: title.into(),
            x_label: x_label.into(),
            y_label: y_label.into(),
            series: Vec::new(),
            vertical_markers: Vec::new(),
            hlines: Vec::new(),
            bands: Vec::new(),
            x_scale: Scale::Linear,
            y_scale: Scale::Linear,
            x_range: None,
            y_range: None,
            equal_aspect: false,
            legend: LegendPos::Auto,
            size: (1000, 600),
        }
    }

    /// Number of points over all series that will not be drawn (NaN/inf, or ≤ 0 on a log axis).
    pub fn skipped_points(&self) -> usize {
        self.series
            .iter()
            .flat_map(|s| s.points.iter())
            .filter(|&&(x, y)| tx(x, self.x_scale).is_none() || tx(y, self.y_scale).is_none())
            .count()
    }
}

/// Several axes in one image.
#[derive(Clone, Debug, PartialEq)]
pub struct PanelFigure {
    /// Overall caption.
    pub title: String,
    /// The panels, top to bottom ([`Layout::Rows`]) or left to right ([`Layout::Columns`]).
    pub panels: Vec<LineFigure>,
    /// Arrangement.
    pub layout: Layout,
    /// Output size in pixels; `None`: 1000 × (60 + 300 n) for rows, (520 n) × 620 for columns.
    pub size: Option<(u32, u32)>,
}

/// What a render call produced.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct RenderReport {
    /// `[stem.svg, stem.png]`.
    pub paths: [PathBuf; 2],
    /// Points not drawn (NaN/inf, or ≤ 0 on a log axis), over all panels.
    pub skipped_points: usize,
}

/// Renders `fig` to `<stem>.svg` and `<stem>.png` (parent directories are created).
pub fn render(fig: &LineFigure, stem: impl AsRef<Path>) -> Result<[PathBuf; 2], PlotError> {
    render_report(fig, stem).map(|r| r.paths)
}

/// As [`render`], also reporting how many points were skipped.
pub fn render_report(fig: &LineFigure, stem: impl AsRef<Path>) -> Result<RenderReport, PlotError> {
    render_impl(
        "",
        std::slice::from_ref(fig),
        Layout::Rows,
        fig.size,
        stem.as_ref(),
    )
}

/// Renders a multi-panel figure to `<stem>.svg` and `<stem>.png`.
pub fn render_panels(fig: &PanelFigure, stem: impl AsRef<Path>) -> Result<[PathBuf; 2], PlotError> {
    render_panels_report(fig, stem).map(|r| r.paths)
}

/// As [`render_panels`], also reporting how many points were skipped.
pub fn render_panels_report(
    fig: &PanelFigure,
    stem: impl AsRef<Path>,
) -> Result<RenderReport, PlotError> {
    if fig.panels.is_empty() {
        return Err(PlotError::NoSeries(fig.title.clone()));
    }
    let n = fig.panels.len() as u32;
    let size = fig.size.unwrap_or(match fig.layout {
        Layout::Rows => (1000, 60 + 300 * n),
        Layout::Columns => (520 * n, 620),
    });
    render_impl(&fig.title, &fig.panels, fig.layout, size, stem.as_ref())
}

// ---------------------------------------------------------------------------------------------

/// Qualitative palette (Tableau 10): distinguishable, and dark enough on white.
const PALETTE: [(u8, u8, u8); 10] = [
    (31, 119, 180),
    (255, 127, 14),
    (44, 160, 44),
    (214, 39, 40),
    (148, 103, 189),
    (140, 86, 75),
    (227, 119, 194),
    (127, 127, 127),
    (188, 189, 34),
    (23, 190, 207),
];

/// The palette colour of automatically styled series number `i` (public so tests and callers can
/// match colours in the output).
pub fn palette(i: usize) -> (u8, u8, u8) {
    PALETTE[i % PALETTE.len()]
}

const DASHES: [Dash; 4] = [Dash::Solid, Dash::Dashed, Dash::Dotted, Dash::LongDash];

/// Maps a data value into plotting coordinates (log10 on log axes); `None` if not plottable.
fn tx(v: f64, s: Scale) -> Option<f64> {
    match s {
        Scale::Linear => v.is_finite().then_some(v),
        Scale::Log10 => (v.is_finite() && v > 0.0).then(|| v.log10()),
    }
}

struct PreparedSeries {
    name: String,
    pieces: Vec<Vec<(f64, f64)>>,
    /// Labelled points (plotting coordinates) and their text.
    labels: Vec<((f64, f64), String)>,
    joined: bool,
    colour: Rgb,
    dash: Dash,
    width: u32,
    markers: bool,
    in_legend: bool,
}

struct Prepared {
    series: Vec<PreparedSeries>,
    skipped: usize,
    /// Ranges in plotting coordinates (before the equal-aspect adjustment).
    xr: (f64, f64),
    yr: (f64, f64),
}

fn invalid(fig: &LineFigure, what: &str, detail: String) -> PlotError {
    PlotError::InvalidInput {
        figure: fig.title.clone(),
        what: what.into(),
        detail,
    }
}

fn prepare(fig: &LineFigure) -> Result<Prepared, PlotError> {
    if fig.series.is_empty() {
        return Err(PlotError::NoSeries(fig.title.clone()));
    }
    let mut out = Vec::with_capacity(fig.series.len());
    let mut skipped = 0;
    for (i, s) in fig.series.iter().enumerate() {
        if s.points.is_empty() {
            return Err(PlotError::EmptySeries {
                figure: fig.title.clone(),
                series: s.name.clone(),
            });
        }
        let mut pieces: Vec<Vec<(f64, f64)>> = vec![Vec::new()];
        let mut bad = 0;
        for &(x, y) in &s.points {
            match (tx(x, fig.x_scale), tx(y, fig.y_scale)) {
                (Some(a), Some(b)) => pieces.last_mut().map_or((), |p| p.push((a, b))),
                _ => {
                    bad += 1;
                    if pieces.last().is_some_and(|p| !p.is_empty()) {
                        pieces.push(Vec::new());
                    }
                }
            }
        }
        pieces.retain(|p| !p.is_empty());
        if !s.labels.is_empty() && s.labels.len() != s.points.len() {
            return Err(invalid(
                fig,
                "point labels",
                format!(
                    "series '{}' has {} labels for {} points",
                    s.name,
                    s.labels.len(),
                    s.points.len()
                ),
            ));
        }
        let labels: Vec<((f64, f64), String)> = s
            .labels
            .iter()
            .zip(&s.points)
            .filter(|(l, _)| !l.is_empty())
            .filter_map(|(l, &(x, y))| {
                Some(((tx(x, fig.x_scale)?, tx(y, fig.y_scale)?), l.clone()))
            })
            .collect();
        if pieces.is_empty() {
            return Err(PlotError::NoFinitePoints {
                figure: fig.title.clone(),
                series: s.name.clone(),
                skipped: bad,
            });
        }
        skipped += bad;
        let (r, g, b) = match s.style.colour {
            Colour::Auto => palette(i),
            Colour::Rgb(r, g, b) => (r, g, b),
        };
        let dash = match s.style.dash {
            Dash::Auto => DASHES[i % DASHES.len()],
            d => d,
        };
        out.push(PreparedSeries {
            name: s.name.clone(),
            pieces,
            colour: (r, g, b),
            labels,
            joined: s.joined,
            dash,
            width: s.style.width.max(1),
            markers: s.style.markers,
            in_legend: s.style.in_legend && !s.name.is_empty(),
        });
    }
    let pts = || out.iter().flat_map(|s| s.pieces.iter().flatten());
    let fold = |f: fn(&(f64, f64)) -> f64| {
        pts()
            .map(f)
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), v| {
                (lo.min(v), hi.max(v))
            })
    };
    let check =
        |r: Option<(f64, f64)>, s: Scale, what: &str| -> Result<Option<(f64, f64)>, PlotError> {
            match r {
                None => Ok(None),
                Some((a, b)) => match (tx(a, s), tx(b, s)) {
                    (Some(a2), Some(b2)) if a2 < b2 => Ok(Some((a2, b2))),
                    _ => Err(invalid(
                        fig,
                        what,
                        format!("({a}, {b}) is not an increasing finite range"),
                    )),
                },
            }
        };
    let xr_fixed = check(fig.x_range, fig.x_scale, "x_range")?;
    let yr_fixed = check(fig.y_range, fig.y_scale, "y_range")?;
    for &(t, ref l) in &fig.vertical_markers {
        if !t.is_finite() {
            return Err(invalid(fig, "vertical marker", format!("'{l}' at {t}")));
        }
    }
    for h in &fig.hlines {
        if tx(h.y, fig.y_scale).is_none() {
            return Err(invalid(
                fig,
                "horizontal line",
                format!("'{}' at {}", h.label, h.y),
            ));
        }
    }
    for b in &fig.bands {
        if !(b.x0.is_finite() && b.x1.is_finite() && b.x0 <= b.x1) {
            return Err(invalid(
                fig,
                "band",
                format!("'{}' [{}, {}]", b.label, b.x0, b.x1),
            ));
        }
    }
    // Time axes end exactly at the data; geometric (equal-aspect) views get the same 5 % margin
    // on both axes so points on the extremes are not drawn on top of the frame.
    // Marker-only and marked series get a small x margin too, so their end markers and labels
    // are not cut by the frame.
    let marked = out.iter().any(|s| s.markers || !s.joined);
    let x_pad = if fig.equal_aspect {
        0.05
    } else if marked {
        0.04
    } else {
        0.0
    };
    let xr = xr_fixed.unwrap_or_else(|| widen(fold(|p| p.0), x_pad));
    let yr = yr_fixed.unwrap_or_else(|| {
        let (mut lo, mut hi) = fold(|p| p.1);
        for h in fig.hlines.iter().filter(|h| h.fit) {
            if let Some(y) = tx(h.y, fig.y_scale) {
                lo = lo.min(y);
                hi = hi.max(y);
            }
        }
        widen((lo, hi), 0.05)
    });
    Ok(Prepared {
        series: out,
        skipped,
        xr,
        yr,
    })
}

/// Pads a range by `frac` of its span and makes degenerate ranges non-empty.
fn widen((lo, hi): (f64, f64), frac: f64) -> (f64, f64) {
    let span = hi - lo;
    if span > 1e-12 * lo.abs().max(hi.abs()).max(1e-300) {
        (lo - frac * span, hi + frac * span)
    } else {
        let d = if lo.abs() > 0.0 { 0.1 * lo.abs() } else { 1.0 };
        (lo - d, hi + d)
    }
}

// Layout constants (pixels). Shared by SVG and PNG so both look the same.
const MARGIN: f64 = 14.0;
const X_LABEL_AREA: f64 = 58.0;
const Y_LABEL_AREA: f64 = 92.0;
const TITLE_FONT: f64 = 24.0;
const PANEL_TITLE_FONT: f64 = 20.0;
const DESC_FONT: f64 = 18.0;
const TICK_FONT: f64 = 15.0;
const LEGEND_FONT: f64 = 15.0;
const MARKER_FONT: f64 = 13.0;
const POINT_LABEL_FONT: f64 = 12.0;
/// Rows of switching-time labels above the axes at most.
const MAX_MARKER_ROWS: usize = 3;
const LEGEND_ROW: f64 = 22.0;
const TEXT_COLOUR: Rgb = (40, 40, 40);

fn render_impl(
    title: &str,
    panels: &[LineFigure],
    layout: Layout,
    size: (u32, u32),
    stem: &Path,
) -> Result<RenderReport, PlotError> {
    ensure_font()?;
    let prepared = panels.iter().map(prepare).collect::<Result<Vec<_>, _>>()?;
    let skipped_points = prepared.iter().map(|p| p.skipped).sum();
    if size.0 < 200 || size.1 < 150 {
        return Err(PlotError::InvalidInput {
            figure: title.into(),
            what: "size".into(),
            detail: format!("{size:?} is too small (min 200 × 150)"),
        });
    }
    let svg_path = with_ext(stem, "svg");
    let png_path = with_ext(stem, "png");
    if let Some(dir) = svg_path.parent().filter(|d| !d.as_os_str().is_empty()) {
        std::fs::create_dir_all(dir).map_err(|source| PlotError::Io {
            path: dir.into(),
            source,
        })?;
    }

    let mut svg = SvgCanvas::new(size);
    draw_all(&mut svg, size, title, panels, &prepared, layout)?;
    write_atomic(&svg_path, svg.finish().as_bytes())?;

    let tmp = tmp_sibling(&png_path);
    let res = (|| {
        let root = BitMapBackend::new(&tmp, size).into_drawing_area();
        root.fill(&WHITE).map_err(de)?;
        draw_all(
            &mut PngCanvas::new(&root),
            size,
            title,
            panels,
            &prepared,
            layout,
        )?;
        root.present().map_err(de)
    })();
    match res {
        Ok(()) => std::fs::rename(&tmp, &png_path).map_err(|source| PlotError::Io {
            path: png_path.clone(),
            source,
        })?,
        Err(e) => {
            let _ = std::fs::remove_file(&tmp);
            return Err(e);
        }
    }
    Ok(RenderReport {
        paths: [svg_path, png_path],
        skipped_points,
    })
}

fn de<E: std::fmt::Display>(e: E) -> PlotError {
    PlotError::Draw(e.to_string())
}

/// `stem` with `.ext` appended (not replacing: stems like `fig6.omega` keep their dot).
fn with_ext(stem: &Path, ext: &str) -> PathBuf {
    let mut s = stem.as_os_str().to_owned();
    s.push(".");
    s.push(ext);
    PathBuf::from(s)
}

/// A temporary name next to `path`, keeping its extension (the bitmap encoder picks the
/// format from it).
fn tmp_sibling(path: &Path) -> PathBuf {
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    let ext = path
        .extension()
        .map(|e| e.to_string_lossy().into_owned())
        .unwrap_or_default();
    path.with_file_name(format!(".{name}.tmp{}.{ext}", std::process::id()))
}

/// Writes `bytes` to `path` via a uniquely named temporary sibling and a rename, so readers
/// never see a partially written file (the workspace's one helper, `bf_output::replace_file`).
pub(crate) fn write_atomic(path: &Path, bytes: &[u8]) -> Result<(), PlotError> {
    bf_output::replace_file(path, bytes).map_err(|source| PlotError::Io {
        path: path.into(),
        source,
    })
}

/// A pixel rectangle (x0, y0) – (x1, y1), y downwards.
#[derive(Clone, Copy, Debug, PartialEq)]
struct PxRect {
    x0: f64,
    y0: f64,
    x1: f64,
    y1: f64,
}

impl PxRect {
    fn w(&self) -> f64 {
        self.x1 - self.x0
    }
    fn h(&self) -> f64 {
        self.y1 - self.y0
    }
    fn overlaps(&self, o: &PxRect) -> bool {
        self.x0 < o.x1 && o.x0 < self.x1 && self.y0 < o.y1 && o.y0 < self.y1
    }
    fn overlap_area(&self, o: &PxRect) -> f64 {
        let w = (self.x1.min(o.x1) - self.x0.max(o.x0)).max(0.0);
        let h = (self.y1.min(o.y1) - self.y0.max(o.y0)).max(0.0);
        w * h
    }
    fn contains(&self, (x, y): (f64, f64)) -> bool {
        x >= self.x0 && x <= self.x1 && y >= self.y0 && y <= self.y1
    }
    fn inflate(&self, d: f64) -> PxRect {
        PxRect {
            x0: self.x0 - d,
            y0: self.y0 - d,
            x1: self.x1 + d,
            y1: self.y1 + d,
        }
    }
}

fn draw_all(
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
        cv.text(&TextSpec {
            text: title,
            x: 0.5 * w,
            y: 0.75 * TITLE_FONT,
            size: TITLE_FONT,
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
        // Stacked panels share their time axis: same left edge and same width.
        let ya = lays.iter().map(|l| l.y_area).fold(0.0f64, f64::max);
        let out = lays.iter().map(|l| l.outside).fold(0.0f64, f64::max);
        if lays.iter().any(|l| l.y_area < ya || l.outside < out) {
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

/// (dash, gap) in pixels; `None` for solid lines.
fn dash_pattern(d: Dash) -> Option<(f64, f64)> {
    match d {
        Dash::Auto | Dash::Solid => None,
        Dash::Dashed => Some((10.0, 6.0)),
        Dash::Dotted => Some((2.0, 5.0)),
        Dash::LongDash => Some((20.0, 7.0)),
    }
}

/// How a legend entry's sample looks.
#[derive(Clone, Copy, Debug)]
enum Sample {
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
struct Mapping {
    plot: PxRect,
    xr: (f64, f64),
    yr: (f64, f64),
}

impl Mapping {
    fn x(&self, v: f64) -> f64 {
        self.plot.x0 + (v - self.xr.0) / (self.xr.1 - self.xr.0) * self.plot.w()
    }
    fn y(&self, v: f64) -> f64 {
        self.plot.y1 - (v - self.yr.0) / (self.yr.1 - self.yr.0) * self.plot.h()
    }
    fn px(&self, (x, y): (f64, f64)) -> (f64, f64) {
        (self.x(x), self.y(y))
    }
}

/// A placed text (anchor point and class as for [`TextSpec`]) with its estimated box.
#[derive(Clone, Debug)]
struct Placed {
    text: String,
    x: f64,
    y: f64,
    anchor: Anchor,
    bbox: PxRect,
}

/// Everything about a panel that depends on pixel sizes: decided before anything is drawn.
struct PanelLayout {
    title_y: Option<f64>,
    map: Mapping,
    x_ticks: Vec<Tick>,
    y_ticks: Vec<Tick>,
    y_area: f64,
    /// Width reserved right of the axes for the legend (0: legend inside).
    outside: f64,
    area: PxRect,
    /// Marker label per vertical marker (same order; `None`: unlabelled or outside).
    marker_labels: Vec<Option<Placed>>,
    legend: Option<(PxRect, Vec<(String, Sample)>)>,
    point_labels: Vec<(Placed, Rgb)>,
    /// Horizontal lines outside the y range (listed in the legend as off scale).
    off_scale: Vec<bool>,
}

fn text_box(text: &str, x: f64, y: f64, size: f64, anchor: Anchor) -> PxRect {
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

fn legend_entries(fig: &LineFigure, prep: &Prepared, off_scale: &[bool]) -> Vec<(String, Sample)> {
    let mut out: Vec<(String, Sample)> = Vec::new();
    for s in prep.series.iter().filter(|s| s.in_legend) {
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
        out.push((s.name.clone(), sample));
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
    for b in &fig.bands {
        if !b.label.is_empty() && !out.iter().any(|(l, _)| *l == b.label) {
            let (c, o) = band_fill(b);
            out.push((b.label.clone(), Sample::Fill(c, o)));
        }
    }
    out
}

fn hline_colour(h: &HLine) -> Rgb {
    match h.colour {
        Colour::Auto => (70, 70, 70),
        Colour::Rgb(r, g, b) => (r, g, b),
    }
}

fn band_fill(b: &Band) -> (Rgb, f64) {
    match b.colour {
        Colour::Auto => ((110, 110, 110), 0.13),
        Colour::Rgb(r, g, bl) => ((r, g, bl), 0.2),
    }
}

/// Pixel sample points of everything drawn as data (every ≤ 4 px along lines), used to find a
/// free place for the legend.
fn data_samples(fig: &LineFigure, prep: &Prepared, m: &Mapping) -> Vec<(f64, f64)> {
    let mut out = Vec::new();
    let mut line = |a: (f64, f64), b: (f64, f64)| {
        let n = ((b.0 - a.0).hypot(b.1 - a.1) / 4.0)
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
fn mapping(
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
        let f = (headroom / plot.h()).min(0.6);
        yr.1 += (yr.1 - yr.0) * f / (1.0 - f);
    }
    let (xr, yr) = if fig.equal_aspect {
        equal_aspect_ranges(xr, yr, (plot.w(), plot.h()))
    } else {
        (xr, yr)
    };
    Mapping { plot, xr, yr }
}

fn axis_ticks(scale: Scale, r: (f64, f64), len_px: f64, horizontal: bool) -> Vec<Tick> {
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
            ticks::linear_ticks(r.0, r.1, max, &fits)
        }
        Scale::Log10 => ticks::log_ticks(r.0, r.1, &fits),
    }
}

/// Lays out one panel; `min` = (least y label area, least room for a legend right of the
/// axes), so that stacked panels can be aligned.
fn layout_panel(
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
        let x_ticks = axis_ticks(fig.x_scale, m.xr, m.plot.w(), true);
        let y_ticks = axis_ticks(fig.y_scale, m.yr, m.plot.h(), false);
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
        let entries = legend_entries(fig, prep, &off_scale);
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
                    // quarter of a (non-geometric) axes and 60 % of its width remain, otherwise
                    // room above the data and an upper corner.
                    let room = bh + 22.0;
                    let wide = m.plot.w() - bw - 30.0 >= (0.6 * m.plot.w()).max(300.0);
                    if best.0 > 0
                        && !last
                        && forced_corner.is_none()
                        && !fig.equal_aspect
                        && wide
                        && (room > 0.25 * m.plot.h() || fig.y_range.is_some())
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

fn draw_panel(
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
        texts.push(txt(
            &fig.title,
            0.5 * (lay.area.x0 + lay.area.x1),
            y,
            title_font,
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
        if a >= c {
            continue;
        }
        cv.rect(
            (m.x(a), p.y0),
            (m.x(c), p.y1),
            Some(band_fill(b)),
            None,
            "band",
        )?;
    }

    // Grid: major lines at labelled ticks, light lines at the others.
    for t in &lay.x_ticks {
        let x = m.x(t.pos);
        let c = if t.label.is_some() {
            (218, 218, 218)
        } else {
            (238, 238, 238)
        };
        cv.polyline(&[(x, p.y0), (x, p.y1)], c, 1.0, None, "grid")?;
    }
    for t in &lay.y_ticks {
        let y = m.y(t.pos);
        let c = if t.label.is_some() {
            (218, 218, 218)
        } else {
            (238, 238, 238)
        };
        cv.polyline(&[(p.x0, y), (p.x1, y)], c, 1.0, None, "grid")?;
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
            hline_colour(h),
            2.0,
            Some((14.0, 5.0)),
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
            (90, 90, 90),
            1.0,
            Some((5.0, 4.0)),
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
                        s.colour,
                        s.width as f64,
                        dash_pattern(s.dash),
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
    cv.rect(
        (p.x0, p.y0),
        (p.x1, p.y1),
        None,
        Some((60, 60, 60)),
        "frame",
    )?;
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
            (60, 60, 60),
            1.0,
            None,
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
            (60, 60, 60),
            1.0,
            None,
            "tick",
        )?;
        if let Some(l) = &t.label {
            texts.push(txt(l, p.x0 - 9.0, y, TICK_FONT, Anchor::End, "tick-y"));
        }
    }
    texts.push(txt(
        &fig.x_label,
        0.5 * (p.x0 + p.x1),
        p.y1 + X_LABEL_AREA - 0.5 * DESC_FONT - 4.0,
        DESC_FONT,
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
    cv.text(&TextSpec {
        text: &fig.y_label,
        x: p.x0 - lay.y_area + 0.5 * DESC_FONT + 2.0,
        y: 0.5 * (p.y0 + p.y1),
        size: DESC_FONT,
        colour: TEXT_COLOUR,
        anchor: Anchor::Middle,
        vertical: true,
        class: "ydesc",
    })?;
    for l in lay.marker_labels.iter().flatten() {
        // On white, so that the dashed line of a neighbouring marker does not cross the text.
        let b = l.bbox.inflate(1.0);
        cv.rect(
            (b.x0, b.y0),
            (b.x1, b.y1),
            Some(((255, 255, 255), 1.0)),
            None,
            "label-bg",
        )?;
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
        cv.rect(
            (b.x0, b.y0),
            (b.x1, b.y1),
            Some(((255, 255, 255), 0.9)),
            Some((160, 160, 160)),
            "legend-box",
        )?;
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
                    cv.polyline(&[(x0, y), (x1, y)], colour, width, dash, "legend-sample")?;
                    if marker {
                        cv.circle((0.5 * (x0 + x1), y), 4.0, colour, "legend-sample")?;
                    }
                }
                Sample::Marker(c) => cv.circle((0.5 * (x0 + x1), y), 4.0, c, "legend-sample")?,
                Sample::Fill(c, o) => cv.rect(
                    (x0, y - 6.0),
                    (x1, y + 6.0),
                    Some((c, o)),
                    None,
                    "legend-sample",
                )?,
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

fn scale_name(s: Scale) -> &'static str {
    match s {
        Scale::Linear => "linear",
        Scale::Log10 => "log10",
    }
}

/// Grows one of the ranges about its centre so both axes get the same data-per-pixel scale on
/// a `(pw, ph)` pixel plotting area; the result always contains the input ranges.
fn equal_aspect_ranges(
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

/// Liang–Barsky clipping of the segment a→b to the closed rectangle `xr × yr`: the parameter
/// interval `(t0, t1)` ⊆ [0, 1] of the part inside (points a + t (b − a)), or `None` if the
/// segment misses the rectangle. A degenerate segment (a = b) is kept whole iff a is inside.
fn clip_segment(
    a: (f64, f64),
    b: (f64, f64),
    xr: (f64, f64),
    yr: (f64, f64),
) -> Option<(f64, f64)> {
    let (dx, dy) = (b.0 - a.0, b.1 - a.1);
    let (mut t0, mut t1) = (0.0f64, 1.0f64);
    // Each pair (p, q): the segment is inside this edge's half-plane where t p <= q.
    for (p, q) in [
        (-dx, a.0 - xr.0),
        (dx, xr.1 - a.0),
        (-dy, a.1 - yr.0),
        (dy, yr.1 - a.1),
    ] {
        if p == 0.0 {
            if q < 0.0 {
                return None;
            }
        } else {
            let r = q / p;
            if p < 0.0 {
                t0 = t0.max(r);
            } else {
                t1 = t1.min(r);
            }
        }
        if t0 > t1 {
            return None;
        }
    }
    Some((t0, t1))
}

/// Clips a polyline to the rectangle `xr × yr`: the maximal runs of it inside, in order. A
/// single point is kept iff it is inside. Original vertices are kept exactly; cut points are
/// interpolated on the rectangle's edges.
fn clip_polyline(pts: &[(f64, f64)], xr: (f64, f64), yr: (f64, f64)) -> Vec<Vec<(f64, f64)>> {
    if let [p] = pts {
        return clip_segment(*p, *p, xr, yr)
            .map(|_| vec![vec![*p]])
            .unwrap_or_default();
    }
    let lerp =
        |a: (f64, f64), b: (f64, f64), t: f64| (a.0 + t * (b.0 - a.0), a.1 + t * (b.1 - a.1));
    let mut out = Vec::new();
    let mut cur: Vec<(f64, f64)> = Vec::new();
    for w in pts.windows(2) {
        let (a, b) = (w[0], w[1]);
        let Some((t0, t1)) = clip_segment(a, b, xr, yr) else {
            if !cur.is_empty() {
                out.push(std::mem::take(&mut cur));
            }
            continue;
        };
        // A run continues only through a vertex that is itself inside (t0 = 0 after a t1 = 1).
        if t0 > 0.0 || cur.is_empty() {
            if !cur.is_empty() {
                out.push(std::mem::take(&mut cur));
            }
            cur.push(if t0 > 0.0 { lerp(a, b, t0) } else { a });
        }
        cur.push(if t1 < 1.0 { lerp(a, b, t1) } else { b });
        if t1 < 1.0 {
            out.push(std::mem::take(&mut cur));
        }
    }
    if !cur.is_empty() {
        out.push(cur);
    }
    out
}

/// Points of one polyline in plotting coordinates.
type Polyline = Vec<(f64, f64)>;

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
        if e1.0 * e2.0 + e1.1 * e2.1 > 0.5 * e1.0.hypot(e1.1) * e2.0.hypot(e2.1) {
            strokes.push(std::mem::replace(&mut cur, vec![pts[w[1]]]));
            joins.push(pts[w[1]]);
        }
    }
    cur.push(pts[keep[keep.len() - 1]]);
    strokes.push(cur);
    (strokes, joins)
}
#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn widen_handles_degenerate_ranges() {
        assert_eq!(widen((0.0, 0.0), 0.05), (-1.0, 1.0));
        let (a, b) = widen((2.0, 2.0), 0.05);
        assert!(a < 2.0 && b > 2.0);
        let (a, b) = widen((0.0, 10.0), 0.1);
        assert!((a + 1.0).abs() < 1e-12 && (b - 11.0).abs() < 1e-12);
    }

    #[test]
    fn nan_splits_series_and_is_counted() {
        let mut f = LineFigure::new("t", "x", "y");
        f.series.push(Series::new(
            "a",
            vec![(0.0, 1.0), (1.0, f64::NAN), (2.0, 2.0), (3.0, 3.0)],
        ));
        let p = prepare(&f).unwrap();
        assert_eq!(p.skipped, 1);
        assert_eq!(p.series[0].pieces.len(), 2);
        assert_eq!(f.skipped_points(), 1);
    }

    const UNIT: (f64, f64) = (0.0, 1.0);

    fn close(a: Option<(f64, f64)>, b: Option<(f64, f64)>) -> bool {
        match (a, b) {
            (None, None) => true,
            (Some(a), Some(b)) => (a.0 - b.0).abs() < 1e-12 && (a.1 - b.1).abs() < 1e-12,
            _ => false,
        }
    }

    #[test]
    fn clip_segment_known_cases() {
        let c = |a, b| clip_segment(a, b, UNIT, UNIT);
        // Fully inside, and lying on an edge of the closed rectangle.
        assert!(close(c((0.2, 0.3), (0.7, 0.9)), Some((0.0, 1.0))));
        assert!(close(c((0.0, 0.0), (1.0, 0.0)), Some((0.0, 1.0))));
        // Fully outside: beside, beyond a corner, and a diagonal passing the corner (1, 1)
        // (x + y = 2.1) that every single edge test alone would accept.
        assert_eq!(c((2.0, 2.0), (3.0, 5.0)), None);
        assert_eq!(c((-1.0, 0.5), (-0.5, 2.0)), None);
        assert_eq!(c((0.5, 1.6), (1.6, 0.5)), None);
        assert_eq!(c((-3.0, 1.5), (4.0, 1.5)), None);
        // Crossing one edge: right edge at t = 1/2, bottom edge at t = 1/3.
        assert!(close(c((0.5, 0.5), (1.5, 0.5)), Some((0.0, 0.5))));
        assert!(close(c((0.5, 0.5), (0.5, -1.0)), Some((0.0, 1.0 / 3.0))));
        // Crossing two edges: left and right; bottom (x = 0.5) and right (y = 0.25) of
        // y = x/2 − 1/4.
        assert!(close(
            c((-1.0, 0.5), (2.0, 0.5)),
            Some((1.0 / 3.0, 2.0 / 3.0))
        ));
        assert!(close(c((-0.5, -0.5), (1.5, 0.5)), Some((0.5, 0.75))));
        assert!(close(c((1.5, 0.5), (-0.5, -0.5)), Some((0.25, 0.5))));
        // Touching the corner (1, 1) only.
        assert!(close(c((0.5, 1.5), (1.5, 0.5)), Some((0.5, 0.5))));
        // Degenerate segments: a point inside, on the boundary, outside.
        assert!(close(c((0.3, 0.3), (0.3, 0.3)), Some((0.0, 1.0))));
        assert!(close(c((1.0, 0.5), (1.0, 0.5)), Some((0.0, 1.0))));
        assert_eq!(c((2.0, 0.3), (2.0, 0.3)), None);
    }

    #[test]
    fn clip_segment_agrees_with_dense_sampling() {
        // Endpoints on a grid around a non-square rectangle (edges hit exactly, corners
        // included) plus seeded random ones: the kept interval must be inside, and it must
        // contain every sample of the segment that lies inside.
        use rand::{Rng, SeedableRng};
        let (xr, yr) = ((-0.3, 0.7), (0.1, 2.1));
        let mut pts: Vec<(f64, f64)> = (0..9)
            .flat_map(|i| (0..9).map(move |j| (-1.3 + 0.5 * i as f64, -0.9 + 0.5 * j as f64)))
            .collect();
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(7);
        pts.extend((0..60).map(|_| (rng.random_range(-2.0..2.0), rng.random_range(-1.5..3.5))));
        let inside = |p: (f64, f64), e: f64| {
            p.0 >= xr.0 - e && p.0 <= xr.1 + e && p.1 >= yr.0 - e && p.1 <= yr.1 + e
        };
        for &a in &pts {
            for &b in &pts {
                let at = |t: f64| (a.0 + t * (b.0 - a.0), a.1 + t * (b.1 - a.1));
                let r = clip_segment(a, b, xr, yr);
                if let Some((t0, t1)) = r {
                    assert!((0.0..=t1).contains(&t0) && t1 <= 1.0, "{a:?} {b:?} {r:?}");
                    for t in [t0, 0.5 * (t0 + t1), t1] {
                        assert!(inside(at(t), 1e-12), "{a:?} {b:?} {r:?}");
                    }
                }
                for k in 0..=400 {
                    let t = k as f64 / 400.0;
                    if inside(at(t), -1e-9) {
                        let (t0, t1) = r.unwrap_or_else(|| panic!("{a:?} {b:?} missed"));
                        assert!(t >= t0 - 1e-9 && t <= t1 + 1e-9, "{a:?} {b:?} {r:?} {t}");
                    }
                }
            }
        }
    }

    #[test]
    fn clip_polyline_splits_into_runs() {
        // Leaves through the top edge between the two inner vertices and comes back.
        let pts = [
            (-0.5, 0.5),
            (0.5, 0.5),
            (0.5, 1.5),
            (0.8, 1.5),
            (0.8, 0.5),
            (2.0, 0.5),
        ];
        assert_eq!(
            clip_polyline(&pts, UNIT, UNIT),
            vec![
                vec![(0.0, 0.5), (0.5, 0.5), (0.5, 1.0)],
                vec![(0.8, 1.0), (0.8, 0.5), (1.0, 0.5)]
            ]
        );
        let inner = [(0.1, 0.1), (0.9, 0.2), (0.4, 0.8)];
        assert_eq!(clip_polyline(&inner, UNIT, UNIT), vec![inner.to_vec()]);
        let far = [(3.0, 0.1), (3.0, 5.0), (-2.0, 5.0)];
        assert!(clip_polyline(&far, UNIT, UNIT).is_empty());
        assert_eq!(
            clip_polyline(&[(0.5, 0.5)], UNIT, UNIT),
            vec![vec![(0.5, 0.5)]]
        );
        assert!(clip_polyline(&[(1.5, 0.5)], UNIT, UNIT).is_empty());
        // A vertex exactly on an edge joins its two segments in one run.
        let touch = [(0.2, 0.5), (1.0, 0.5), (0.2, 0.6)];
        assert_eq!(clip_polyline(&touch, UNIT, UNIT), vec![touch.to_vec()]);
    }

    /// Data points equal to their pixels, so strokes can be compared with pixel paths.
    fn split_px(px: &[(i32, i32)]) -> (Vec<Polyline>, Polyline) {
        let pts: Vec<(f64, f64)> = px.iter().map(|&(x, y)| (x as f64, y as f64)).collect();
        split_sharp_turns(&pts, px)
    }

    #[test]
    fn sharp_turns_split_and_gentle_ones_do_not() {
        let (s, j) = split_px(&[(0, 0), (100, 0), (0, 1), (100, 2)]);
        assert_eq!(s.len(), 3);
        assert_eq!(j, vec![(100.0, 0.0), (0.0, 1.0)]);
        assert_eq!(s[1], vec![(100.0, 0.0), (0.0, 1.0)]);
        let (s, j) = split_px(&[(0, 0), (10, 0), (20, 5), (30, 20), (30, 40), (0, 40)]);
        assert_eq!((s.len(), j.len()), (1, 0), "turns of ≤ 90° are kept");
        // Threshold: an angle of 59° between the edges splits, 61° does not.
        for (deg, split) in [(59.0f64, true), (61.0, false)] {
            let r = deg.to_radians();
            let b = (
                (1000.0 * r.cos()).round() as i32,
                (1000.0 * r.sin()).round() as i32,
            );
            let (s, _) = split_px(&[(1000, 0), (0, 0), b]);
            assert_eq!(s.len() == 2, split, "{deg}°");
        }
        // Repeated pixels are dropped; a run on a single pixel draws nothing.
        let (s, j) = split_px(&[(0, 0), (0, 0), (5, 5), (5, 5)]);
        assert_eq!(s, vec![vec![(0.0, 0.0), (5.0, 5.0)]]);
        assert!(j.is_empty());
        assert!(split_px(&[(3, 3), (3, 3)]).0.is_empty());
        // An exact reversal is a (zero-angle) sharp turn too.
        assert_eq!(split_px(&[(0, 0), (50, 0), (20, 0)]).0.len(), 2);
    }

    #[test]
    fn split_strokes_polygonize_without_spikes() {
        // Independent check with plotters' own thick-line polygonizer: random zig-zags with
        // hairpins give polygon vertices thousands of pixels away unless split; after the split
        // every vertex stays within about one line width of the path.
        use rand::{Rng, SeedableRng};
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(11);
        let dist_to_path = |q: (i32, i32), path: &[(i32, i32)]| {
            path.windows(2)
                .map(|w| {
                    let (a, b) = (w[0], w[1]);
                    let (dx, dy) = ((b.0 - a.0) as f64, (b.1 - a.1) as f64);
                    let (qx, qy) = ((q.0 - a.0) as f64, (q.1 - a.1) as f64);
                    let l2 = dx * dx + dy * dy;
                    let t = if l2 > 0.0 {
                        ((qx * dx + qy * dy) / l2).clamp(0.0, 1.0)
                    } else {
                        0.0
                    };
                    (qx - t * dx).hypot(qy - t * dy)
                })
                .fold(f64::INFINITY, f64::min)
        };
        let mut worst_unsplit = 0.0f64;
        for _ in 0..300 {
            let n = rng.random_range(3..12);
            let px: Vec<(i32, i32)> = (0..n)
                .map(|_| (rng.random_range(0..400), rng.random_range(0..300)))
                .collect();
            for width in [2u32, 3, 5] {
                let far = |path: &[(i32, i32)]| {
                    plotters_backend::rasterizer::polygonize(path, width)
                        .into_iter()
                        .map(|q| dist_to_path(q, path))
                        .fold(0.0f64, f64::max)
                };
                worst_unsplit = worst_unsplit.max(far(&px));
                let (strokes, _) = split_px(&px);
                for s in strokes {
                    let sp: Vec<(i32, i32)> =
                        s.iter().map(|&(x, y)| (x as i32, y as i32)).collect();
                    let d = far(&sp);
                    assert!(
                        d <= width as f64 + 1.5,
                        "width {width}: vertex {d} px away, {sp:?}"
                    );
                }
            }
        }
        assert!(
            worst_unsplit > 50.0,
            "test paths too tame ({worst_unsplit} px)"
        );
    }

    #[test]
    fn equal_aspect_keeps_ranges_and_equalises_scales() {
        for (xr, yr, pw, ph) in [
            ((0.0, 1.0), (0.0, 1.0), 400.0, 300.0),
            ((-1.05, 1.35), (-1.3, 1.6), 386.0, 468.0),
            ((2.0, 2.5), (-100.0, 50.0), 800.0, 100.0),
            ((1e3, 1e3 + 1e-3), (-1.0, 1.0), 100.0, 100.0),
        ] {
            let (x2, y2) = equal_aspect_ranges(xr, yr, (pw, ph));
            assert!(x2.0 <= xr.0 && x2.1 >= xr.1 && y2.0 <= yr.0 && y2.1 >= yr.1);
            let (sx, sy) = ((x2.1 - x2.0) / pw, (y2.1 - y2.0) / ph);
            assert!((sx - sy).abs() <= 1e-9 * sx.max(sy), "{sx} vs {sy}");
            // Only one axis grows, about the centre.
            assert!(x2 == xr || y2 == yr);
        }
    }

    #[test]
    fn default_ranges_cover_every_point_of_every_series() {
        let mut f = LineFigure::new("t", "x", "y");
        f.series
            .push(Series::new("a", vec![(0.0, 0.0), (0.5, 1.0)]));
        f.series.push(Series::new(
            "b",
            vec![(1.35, 0.87), (f64::NAN, 9.0), (-1.05, 1.6), (0.2, -1.2)],
        ));
        for equal in [false, true] {
            f.equal_aspect = equal;
            let p = prepare(&f).unwrap();
            let (xs, ys) = (2.4, 2.8); // data spans
            // x: exact fit on time axes, 5 % margin on geometric views; y: 5 % margin always.
            let mx = if equal { 0.05 * xs } else { 0.0 };
            assert!((p.xr.0 - (-1.05 - mx)).abs() < 1e-12 && (p.xr.1 - (1.35 + mx)).abs() < 1e-12);
            assert!((p.yr.0 - (-1.2 - 0.05 * ys)).abs() < 1e-12);
            assert!((p.yr.1 - (1.6 + 0.05 * ys)).abs() < 1e-12);
            // Geometric views: still strictly inside after the equal-aspect adjustment, for
            // tall and wide plotting areas.
            for area in [(386.0, 468.0), (900.0, 200.0)] {
                let (xr, yr) = if equal {
                    equal_aspect_ranges(p.xr, p.yr, area)
                } else {
                    (p.xr, p.yr)
                };
                for &(x, y) in f.series.iter().flat_map(|s| &s.points) {
                    if x.is_finite() && y.is_finite() {
                        assert!(xr.0 <= x && x <= xr.1 && yr.0 < y && y < yr.1);
                        assert!(!equal || (xr.0 < x && x < xr.1), "({x}, {y})");
                    }
                }
            }
        }
    }

    #[test]
    fn log_axis_rejects_non_positive() {
        let mut f = LineFigure::new("t", "x", "y");
        f.y_scale = Scale::Log10;
        f.series
            .push(Series::new("a", vec![(1.0, 0.0), (2.0, -1.0)]));
        assert!(matches!(
            prepare(&f),
            Err(PlotError::NoFinitePoints { skipped: 2, .. })
        ));
    }

    #[test]
    fn point_labels_follow_their_kept_points() {
        let mut f = LineFigure::new("t", "x", "y");
        f.y_scale = Scale::Log10;
        f.series.push(
            Series::new("a", vec![(0.0, 1.0), (1.0, -1.0), (2.0, 10.0)])
                .with_labels(vec!["p".into(), "dropped".into(), String::new()])
                .unjoined(),
        );
        let p = prepare(&f).unwrap();
        assert_eq!(p.series[0].labels, vec![((0.0, 0.0), "p".to_string())]);
        assert!(!p.series[0].joined);
        f.series[0].labels.pop();
        assert!(matches!(prepare(&f), Err(PlotError::InvalidInput { .. })));
    }
}
