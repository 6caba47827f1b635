//! Line figures over plain data, rendered to SVG and PNG with the same layout.
//!
//! [`LineFigure`]: one axes with [`Series`], switching-time markers (the phase boundaries
//! t_f^(i) of Sect. 4.2 / Fig. 6), horizontal limit lines ([`HLine`], e.g. the torque limit
//! |τ_i| ≤ 1 N m) and shaded x-intervals ([`Band`], e.g. the sticking phase).
//! [`PanelFigure`]: several `LineFigure`s stacked in rows or side by side (e.g. ω_x, ω_y, ω_z).
//!
//! Non-finite points (and non-positive points on a log axis) split a series into separate line
//! pieces — a gap, as in other plotting tools — and are counted in [`RenderReport::skipped_points`].
//! Lines are clipped to the axes rectangle (Liang–Barsky, `clip_segment`) before drawing, so
//! explicit `x_range`/`y_range` narrower than the data never draw outside the axes, and thick
//! lines are split at sharp turns (`split_sharp_turns`) because plotters' bitmap stroker
//! would otherwise extend hairpins into spikes across the whole image. Default ranges cover
//! every finite point of every series (equal-aspect views: 5 % margin on both axes).
//! Colours follow a 10-colour qualitative palette and dash patterns cycle with period 4, so the
//! first 20 automatically styled series of a figure are pairwise distinct even in grey-scale print.

use crate::{FONT, PlotError, ensure_font};
use plotters::chart::SeriesAnno;
use plotters::coord::Shift;
use plotters::element::DashedPathElement;
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

/// One named polyline.
#[derive(Clone, Debug, PartialEq)]
pub struct Series {
    /// Legend text.
    pub name: String,
    /// Points (x, y) in data units, drawn in this order.
    pub points: Vec<(f64, f64)>,
    /// Appearance.
    pub style: SeriesStyle,
}

impl Series {
    /// A series with the default (automatic) style.
    pub fn new(name: impl Into<String>, points: Vec<(f64, f64)>) -> Self {
        Self {
            name: name.into(),
            points,
            style: SeriesStyle::default(),
        }
    }

    /// The same series with another style.
    pub fn styled(mut self, style: SeriesStyle) -> Self {
        self.style = style;
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
    colour: RGBColor,
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
            colour: RGBColor(r, g, b),
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
    let x_pad = if fig.equal_aspect { 0.05 } else { 0.0 };
    let xr = xr_fixed.unwrap_or_else(|| widen(fold(|p| p.0), x_pad));
    let yr = yr_fixed.unwrap_or_else(|| {
        let (mut lo, mut hi) = fold(|p| p.1);
        for h in &fig.hlines {
            if let Some(y) = tx(h.y, fig.y_scale) {
                lo = lo.min(y);
                hi = hi.max(y);
            }
        }
        let (lo, hi) = widen((lo, hi), 0.05);
        // Head room for the switching-time labels drawn along the top edge.
        if fig.vertical_markers.iter().any(|(_, l)| !l.is_empty()) {
            (lo, hi + 0.08 * (hi - lo))
        } else {
            (lo, hi)
        }
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

/// Tick label text for plotting coordinate `v` on an axis spanning `span`.
fn tick_label(v: f64, span: f64, scale: Scale) -> String {
    match scale {
        Scale::Log10 => {
            let k = v.round();
            if (v - k).abs() < 1e-6 {
                format!("1e{}", k as i64)
            } else {
                format!("{:.0e}", 10f64.powf(v))
            }
        }
        Scale::Linear => {
            if v.abs() < 1e-9 * span.max(1e-300) {
                return "0".into();
            }
            let step = span / 8.0;
            let s = if v.abs() >= 1e5 || step < 1e-4 {
                format!("{v:.2e}")
            } else {
                // One digit more than the step needs, then trailing zeros trimmed: 0.25 stays
                // 0.25, 0.50 becomes 0.5, 1.00 becomes 1.
                let dec = (1.0 - step.log10().floor()).clamp(0.0, 7.0) as usize;
                let s = format!("{v:.dec$}");
                if s.contains('.') {
                    s.trim_end_matches('0').trim_end_matches('.').to_string()
                } else {
                    s
                }
            };
            match s.strip_prefix('-') {
                Some(rest) if rest.chars().all(|c| c == '0' || c == '.') => rest.to_string(),
                _ => s,
            }
        }
    }
}

fn de<E: std::fmt::Display>(e: E) -> PlotError {
    PlotError::Draw(e.to_string())
}

// Layout constants (pixels). Shared by SVG and PNG so both look the same.
const MARGIN: u32 = 14;
const X_LABEL_AREA: u32 = 58;
const Y_LABEL_AREA: u32 = 92;
const TITLE_FONT: u32 = 24;
const PANEL_TITLE_FONT: u32 = 20;
const DESC_FONT: u32 = 18;
const TICK_FONT: u32 = 15;
const LEGEND_FONT: u32 = 15;
const MARKER_FONT: u32 = 13;

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

    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, size).into_drawing_area();
        draw_all(&root, title, panels, &prepared, layout)?;
        root.present().map_err(de)?;
    }
    write_atomic(&svg_path, svg.as_bytes())?;

    let tmp = tmp_sibling(&png_path);
    let res = (|| {
        let root = BitMapBackend::new(&tmp, size).into_drawing_area();
        draw_all(&root, title, panels, &prepared, layout)?;
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

fn draw_all<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    title: &str,
    panels: &[LineFigure],
    prepared: &[Prepared],
    layout: Layout,
) -> Result<(), PlotError> {
    root.fill(&WHITE).map_err(de)?;
    let body = if title.is_empty() {
        root.clone()
    } else {
        root.titled(title, (FONT, TITLE_FONT)).map_err(de)?
    };
    let n = panels.len();
    let areas = match layout {
        Layout::Rows => body.split_evenly((n, 1)),
        Layout::Columns => body.split_evenly((1, n)),
    };
    let title_font = if n > 1 || !title.is_empty() {
        PANEL_TITLE_FONT
    } else {
        TITLE_FONT
    };
    for ((area, fig), prep) in areas.iter().zip(panels).zip(prepared) {
        draw_panel(area, fig, prep, title_font)?;
    }
    Ok(())
}

fn dash_element(
    pts: Vec<(i32, i32)>,
    dash: Dash,
    style: ShapeStyle,
) -> DashedPathElement<std::vec::IntoIter<(i32, i32)>, i32> {
    let (on, off) = dash_pattern(dash);
    DashedPathElement::new(pts, on, off, style)
}

/// (dash, gap) in pixels; solid lines are one very long dash.
fn dash_pattern(d: Dash) -> (i32, i32) {
    match d {
        Dash::Auto | Dash::Solid => (1_000_000, 1),
        Dash::Dashed => (10, 6),
        Dash::Dotted => (2, 5),
        Dash::LongDash => (20, 7),
    }
}

fn draw_panel<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    fig: &LineFigure,
    prep: &Prepared,
    title_font: u32,
) -> Result<(), PlotError> {
    let inner = if fig.title.is_empty() {
        area.clone()
    } else {
        area.titled(&fig.title, (FONT, title_font)).map_err(de)?
    };
    let (w, h) = inner.dim_in_pixel();
    let pw = w.saturating_sub(Y_LABEL_AREA + 3 * MARGIN).max(10) as f64;
    let ph = h.saturating_sub(X_LABEL_AREA + 2 * MARGIN).max(10) as f64;
    let (xr, yr) = if fig.equal_aspect {
        equal_aspect_ranges(prep.xr, prep.yr, (pw, ph))
    } else {
        (prep.xr, prep.yr)
    };
    let mut chart = ChartBuilder::on(&inner)
        .margin(MARGIN)
        .margin_right(2 * MARGIN)
        .x_label_area_size(X_LABEL_AREA)
        .y_label_area_size(Y_LABEL_AREA)
        .build_cartesian_2d(xr.0..xr.1, yr.0..yr.1)
        .map_err(de)?;
    let (xs, ys) = (xr.1 - xr.0, yr.1 - yr.0);
    let (xsc, ysc) = (fig.x_scale, fig.y_scale);
    let xfmt = move |v: &f64| tick_label(*v, xs, xsc);
    let yfmt = move |v: &f64| tick_label(*v, ys, ysc);
    chart
        .configure_mesh()
        .x_desc(fig.x_label.as_str())
        .y_desc(fig.y_label.as_str())
        .axis_desc_style((FONT, DESC_FONT))
        .label_style((FONT, TICK_FONT))
        .x_labels(9)
        .y_labels(7)
        .x_label_formatter(&xfmt)
        .y_label_formatter(&yfmt)
        .bold_line_style(RGBColor(215, 215, 215))
        .light_line_style(RGBColor(242, 242, 242))
        .axis_style(RGBColor(60, 60, 60))
        .draw()
        .map_err(de)?;

    // Shaded bands.
    let band_fill = RGBColor(110, 110, 110).mix(0.13);
    let mut band_labels: Vec<&str> = Vec::new();
    for b in &fig.bands {
        let (Some(a), Some(c)) = (tx(b.x0, xsc), tx(b.x1, xsc)) else {
            continue;
        };
        let (a, c) = (a.max(xr.0), c.min(xr.1));
        if a >= c {
            continue;
        }
        let anno = chart
            .draw_series(std::iter::once(Rectangle::new(
                [(a, yr.0), (c, yr.1)],
                band_fill.filled(),
            )))
            .map_err(de)?;
        if !b.label.is_empty() && !band_labels.contains(&b.label.as_str()) {
            band_labels.push(&b.label);
            anno.label(b.label.as_str()).legend(move |(x, y)| {
                Rectangle::new([(x, y - 6), (x + 24, y + 6)], band_fill.filled())
            });
        }
    }

    // Horizontal reference lines.
    for hl in &fig.hlines {
        let Some(y) = tx(hl.y, ysc) else { continue };
        if y < yr.0 || y > yr.1 {
            continue;
        }
        let c = match hl.colour {
            Colour::Auto => RGBColor(70, 70, 70),
            Colour::Rgb(r, g, b) => RGBColor(r, g, b),
        };
        let style = c.stroke_width(2);
        let anno = chart
            .draw_series(DashedLineSeries::new(
                vec![(xr.0, y), (xr.1, y)],
                14,
                5,
                style,
            ))
            .map_err(de)?;
        if !hl.label.is_empty() {
            anno.label(hl.label.as_str()).legend(move |(x, y)| {
                dash_element(vec![(x, y), (x + 24, y)], Dash::LongDash, style)
            });
        }
    }

    // Switching-time markers; labels are staggered when they would collide.
    let marker_style = RGBColor(90, 90, 90).stroke_width(1);
    let mut last_px = f64::NEG_INFINITY;
    let mut level = 0;
    let mut marker_boxes: Vec<(f64, f64)> = Vec::new(); // pixel x of label starts, for the legend
    for (t, label) in &fig.vertical_markers {
        let Some(x) = tx(*t, xsc) else { continue };
        if x < xr.0 || x > xr.1 {
            continue;
        }
        chart
            .draw_series(DashedLineSeries::new(
                vec![(x, yr.0), (x, yr.1)],
                5,
                4,
                marker_style,
            ))
            .map_err(de)?;
        if label.is_empty() {
            continue;
        }
        let px = (x - xr.0) / xs * pw;
        let width = 8.0 * label.chars().count() as f64 + 8.0;
        level = if px - last_px < width {
            (level + 1) % 3
        } else {
            0
        };
        last_px = px;
        marker_boxes.push((px, px + width));
        let text = Text::new(
            label.clone(),
            (4, 4 + 16 * level),
            (FONT, MARKER_FONT).into_font().color(&RGBColor(60, 60, 60)),
        );
        chart
            .draw_series(std::iter::once(EmptyElement::at((x, yr.1)) + text))
            .map_err(de)?;
    }

    // Data: clipped to the axes rectangle (plotters does not clip paths), and split at sharp
    // turns so that the bitmap backend's thick-line polygons grow no miter spikes.
    for s in &prep.series {
        let style = s.colour.stroke_width(s.width);
        let mut labelled = false;
        for piece in &s.pieces {
            for run in clip_polyline(piece, xr, yr) {
                let px: Vec<(i32, i32)> = run.iter().map(|p| chart.backend_coord(p)).collect();
                let (strokes, joins) = split_sharp_turns(&run, &px);
                for stroke in strokes {
                    let anno = match s.dash {
                        Dash::Auto | Dash::Solid => chart
                            .draw_series(LineSeries::new(stroke, style))
                            .map_err(de)?,
                        d => {
                            let (on, off) = dash_pattern(d);
                            chart
                                .draw_series(DashedLineSeries::new(stroke, on, off, style))
                                .map_err(de)?
                        }
                    };
                    if s.in_legend && !labelled {
                        labelled = true;
                        label_series(anno, s, style);
                    }
                }
                // Round joins where a solid line was split (dashes simply restart).
                if matches!(s.dash, Dash::Auto | Dash::Solid) && s.width >= 2 {
                    let r = (s.width / 2).max(1);
                    chart
                        .draw_series(joins.into_iter().map(|p| Circle::new(p, r, style.filled())))
                        .map_err(de)?;
                }
            }
            if s.markers {
                let inside = |&&(x, y): &&(f64, f64)| {
                    (xr.0..=xr.1).contains(&x) && (yr.0..=yr.1).contains(&y)
                };
                chart
                    .draw_series(
                        piece
                            .iter()
                            .filter(inside)
                            .map(|&p| Circle::new(p, 4, style.filled())),
                    )
                    .map_err(de)?;
            }
        }
        if s.in_legend && !labelled {
            // Entirely outside the axes: still listed in the legend.
            let anno = chart
                .draw_series(std::iter::empty::<Circle<(f64, f64), i32>>())
                .map_err(de)?;
            label_series(anno, s, style);
        }
    }

    // Legend.
    let entries: Vec<&str> = prep
        .series
        .iter()
        .filter(|s| s.in_legend)
        .map(|s| s.name.as_str())
        .chain(
            fig.hlines
                .iter()
                .filter(|h| !h.label.is_empty())
                .map(|h| h.label.as_str()),
        )
        .chain(band_labels.iter().copied())
        .collect();
    if entries.is_empty() || fig.legend == LegendPos::Hidden {
        return Ok(());
    }
    let pos = match fig.legend {
        LegendPos::UpperLeft => SeriesLabelPosition::UpperLeft,
        LegendPos::UpperRight => SeriesLabelPosition::UpperRight,
        LegendPos::LowerLeft => SeriesLabelPosition::LowerLeft,
        LegendPos::LowerRight => SeriesLabelPosition::LowerRight,
        LegendPos::Auto | LegendPos::Hidden => {
            let longest = entries
                .iter()
                .map(|e| {
                    inner
                        .estimate_text_size(e, &TextStyle::from((FONT, LEGEND_FONT).into_font()))
                        .map_or(200, |d| d.0)
                })
                .max()
                .unwrap_or(0) as f64;
            let box_w = longest + 60.0;
            let box_h = 22.0 * entries.len() as f64 + 16.0;
            // Reference lines count as data: a legend box should not hide a limit line.
            let hl: Vec<Vec<(f64, f64)>> = fig
                .hlines
                .iter()
                .filter_map(|h| tx(h.y, ysc))
                .map(|y| vec![(xr.0, y), (xr.1, y)])
                .collect();
            auto_legend(prep, &hl, &marker_boxes, xr, yr, (pw, ph), (box_w, box_h))
        }
    };
    chart
        .configure_series_labels()
        .position(pos)
        .margin(10)
        .legend_area_size(32)
        .label_font((FONT, LEGEND_FONT))
        .background_style(WHITE.mix(0.88))
        .border_style(RGBColor(160, 160, 160))
        .draw()
        .map_err(de)?;
    Ok(())
}

/// Attaches the legend entry (line sample, plus a dot for marker series) of `s` to `anno`.
fn label_series<'a, DB: DrawingBackend + 'a>(
    anno: &mut SeriesAnno<'a, DB>,
    s: &PreparedSeries,
    style: ShapeStyle,
) {
    let (dash, markers) = (s.dash, s.markers);
    anno.label(s.name.as_str()).legend(move |(x, y)| {
        let base = EmptyElement::at((x, y)) + dash_element(vec![(0, 0), (24, 0)], dash, style);
        // A transparent dot when there are no markers keeps one element type.
        let dot = if markers {
            style.filled()
        } else {
            TRANSPARENT.filled()
        };
        base + Circle::new((12, 0), 4, dot)
    });
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
fn split_sharp_turns(pts: &[(f64, f64)], px: &[(i32, i32)]) -> (Vec<Polyline>, Polyline) {
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

/// The corner whose legend-sized box covers the fewest data points (and marker labels).
fn auto_legend(
    prep: &Prepared,
    extra: &[Vec<(f64, f64)>],
    marker_boxes: &[(f64, f64)],
    xr: (f64, f64),
    yr: (f64, f64),
    (pw, ph): (f64, f64),
    (bw, bh): (f64, f64),
) -> SeriesLabelPosition {
    // Candidates in preference order; pixel boxes measured from the top-left of the plot.
    let cands = [
        (SeriesLabelPosition::UpperRight, pw - bw - 10.0, 10.0),
        (SeriesLabelPosition::UpperLeft, 10.0, 10.0),
        (
            SeriesLabelPosition::LowerRight,
            pw - bw - 10.0,
            ph - bh - 10.0,
        ),
        (SeriesLabelPosition::LowerLeft, 10.0, ph - bh - 10.0),
    ];
    let to_px = |(x, y): (f64, f64)| {
        (
            (x - xr.0) / (xr.1 - xr.0) * pw,
            (yr.1 - y) / (yr.1 - yr.0) * ph,
        )
    };
    let mut best = (usize::MAX, SeriesLabelPosition::UpperRight);
    for (pos, x0, y0) in cands {
        let inside = |(px, py): (f64, f64)| {
            px >= x0 - 6.0 && px <= x0 + bw + 6.0 && py >= y0 - 6.0 && py <= y0 + bh + 6.0
        };
        let mut count = 0usize;
        for piece in prep
            .series
            .iter()
            .flat_map(|s| s.pieces.iter())
            .chain(extra.iter())
        {
            {
                // Sample densely enough that a line crossing the box is seen even between points.
                for w in piece.windows(2) {
                    let (a, b) = (to_px(w[0]), to_px(w[1]));
                    let n = ((b.0 - a.0).hypot(b.1 - a.1) / 4.0)
                        .ceil()
                        .clamp(1.0, 200.0) as usize;
                    count += (0..n)
                        .filter(|&k| {
                            let f = k as f64 / n as f64;
                            inside((a.0 + f * (b.0 - a.0), a.1 + f * (b.1 - a.1)))
                        })
                        .count();
                }
                if piece.len() == 1 && inside(to_px(piece[0])) {
                    count += 1;
                }
            }
        }
        for &(m0, m1) in marker_boxes {
            if m1 >= x0 && m0 <= x0 + bw && y0 < 60.0 {
                count += 50;
            }
        }
        if count < best.0 {
            best = (count, pos);
        }
    }
    best.1
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tick_labels_are_short_and_signless_zero() {
        assert_eq!(tick_label(0.0, 2.0, Scale::Linear), "0");
        assert_eq!(tick_label(-1e-17, 2.0, Scale::Linear), "0");
        assert_eq!(tick_label(0.25, 2.0, Scale::Linear), "0.25");
        assert_eq!(tick_label(-3.0, 16.0, Scale::Log10), "1e-3");
        assert_eq!(tick_label(2.0, 16.0, Scale::Linear), "2");
    }

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
}
