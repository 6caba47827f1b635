//! Line figures over plain data, rendered to SVG and PNG with the same layout.
//!
//! [`LineFigure`]: one axes with [`Series`] (polylines, or unjoined markers for unordered
//! points, optionally with per-point labels), switching-time markers (the phase boundaries
//! t_f^(i) of Sect. 4.2 / Fig. 6), horizontal limit lines ([`HLine`], e.g. the torque limit
//! |τ_i| ≤ 1 N m) and shaded x-intervals ([`Band`], e.g. the sticking phase).
//! [`PanelFigure`]: several `LineFigure`s stacked in rows or side by side (e.g. ω_x, ω_y, ω_z).
//!
//! Layout is decided in pixels before anything is drawn, identically for both outputs (the SVG
//! is written with fractional coordinates, the PNG through plotters' bitmap backend into memory, encoded by the `png` crate, see
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
//! bitmap lines are split at sharp turns (`canvas::split_sharp_turns`) because plotters' bitmap stroker
//! would otherwise extend hairpins into spikes across the whole image. Default ranges cover
//! every finite point of every series (equal-aspect views: 5 % margin on both axes); a log axis
//! ends at ticks (whole decades where it spans two or more, so that its ends are labelled).
//! Colours follow a 10-colour qualitative palette and dash patterns cycle with period 4, so the
//! first 20 automatically styled series of a figure are pairwise distinct even in grey-scale print.
//!
//! Internals: `prepare` (styles, plotting coordinates, ranges), `layout` (pixel layout of a
//! panel), `draw` (drawing a laid-out panel on a canvas), `clip` (clipping).

mod clip;
mod draw;
mod layout;
mod prepare;
#[cfg(test)]
mod tests;

use crate::canvas::{PngCanvas, SvgCanvas};
use crate::{PlotError, ensure_font};
use bf_output::FileError;
use draw::draw_all;
use plotters::prelude::*;
use prepare::{prepare, tx};
use std::path::{Path, PathBuf};

pub use prepare::palette;

/// Least drawn width of a [`Band`] in pixels.
pub const MIN_BAND_PX: f64 = 6.0;

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

/// A shaded x-interval spanning the full height of the axes (e.g. a contact phase). It is
/// drawn at least [`MIN_BAND_PX`] wide, so that a short interval (a 0.01 s stick phase in a
/// 10 s period) stays visible; its label is listed in the legend only when some band with
/// that label lies in the x range.
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
    /// x-axis description including the unit, e.g. "t \[s\]".
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
    /// The fitted y range includes 0 (linear axes; default false): for quantities whose sign
    /// matters (torques, forces), so that a small variation about a non-zero value is not
    /// blown up to the full height, and all panels of a figure read the same way.
    pub y_includes_zero: bool,
    /// The quantity cannot be negative (a distance, a norm; linear axes; default false): the
    /// fitted y range does not extend below 0, and a series that is identically 0 gets the
    /// range [0, 1] rather than one around 0.
    pub y_non_negative: bool,
    /// Same data-to-pixel scale on both axes (for geometric views; linear axes only).
    pub equal_aspect: bool,
    /// The x values are counts (periods, iterations; linear axes; default false): ticks only
    /// at whole numbers, so that no tick stands where no sample can be (unless the range holds
    /// fewer than two).
    pub x_whole: bool,
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
            y_includes_zero: false,
            y_non_negative: false,
            equal_aspect: false,
            x_whole: false,
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
        std::fs::create_dir_all(dir)
            .map_err(|e| FileError::new("cannot create directory", dir, e))?;
    }

    let mut svg = SvgCanvas::new(size);
    draw_all(&mut svg, size, title, panels, &prepared, layout)?;
    write_atomic(&svg_path, svg.finish().as_bytes())?;

    // Drawn into memory and encoded here, so that a failed draw leaves no file behind and the
    // PNG is replaced atomically like the SVG.
    let mut rgb = vec![0u8; 3 * size.0 as usize * size.1 as usize];
    {
        let root = BitMapBackend::with_buffer(&mut rgb, size).into_drawing_area();
        root.fill(&WHITE).map_err(de)?;
        draw_all(
            &mut PngCanvas::new(&root),
            size,
            title,
            panels,
            &prepared,
            layout,
        )?;
        root.present().map_err(de)?;
    }
    write_atomic(&png_path, &encode_png(&rgb, size)?)?;
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

/// Encodes 8-bit RGB pixels (row-major, `3 · width · height` bytes) as a PNG file's bytes.
pub(crate) fn encode_png(rgb: &[u8], (width, height): (u32, u32)) -> Result<Vec<u8>, PlotError> {
    let mut out = Vec::new();
    let mut encoder = png::Encoder::new(&mut out, width, height);
    encoder.set_color(png::ColorType::Rgb);
    encoder.set_depth(png::BitDepth::Eight);
    encoder
        .write_header()
        .and_then(|mut w| w.write_image_data(rgb))
        .map_err(|e| PlotError::Draw(format!("PNG encoding failed: {e}")))?;
    Ok(out)
}

/// Writes `bytes` to `path` via a uniquely named temporary sibling and a rename, so readers
/// never see a partially written file (the workspace's one helper, `bf_output::replace_file`).
pub(crate) fn write_atomic(path: &Path, bytes: &[u8]) -> Result<(), PlotError> {
    bf_output::replace_file(path, bytes).map_err(|e| FileError::new("cannot write", path, e).into())
}
