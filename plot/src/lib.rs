//! `bf-plot`: the figure layer of the ball-and-finger reproduction.
//!
//! Pure Rust (the SVG is written directly with fractional coordinates; the PNG goes through
//! plotters' bitmap backend without system fonts; DejaVu Sans is embedded, see
//! `assets/LICENSE-DejaVu.txt`) and independent of the physics crates: every input is plain data.
//!
//! | module | what | paper |
//! |---|---|---|
//! | [`figure`] | [`LineFigure`] / [`PanelFigure`] rendered to SVG + PNG ([`render`], [`render_panels`]) | all 2D figures |
//! | `font` | metrics of the embedded DejaVu Sans ([`text_width`]): the layout measures with them, the SVG names that font at the same em size | — |
//! | [`ticks`] | axis ticks whose labels are exactly the value at their position (linear 1-2-5, decadic log) | — |
//! | [`sat`] | exact and smooth saturation, the scaled tanh, and Fig. 4 ([`sat::fig4_saturation`]) | eq. (3), (58)–(59), Fig. 4 |
//! | [`paper`] | builders for Fig. 6–9, 13–17 and work–precision plots over [`paper::TimeSeries`] | Sect. 6 |
//! | [`scene3d`] | orthographic/isometric views of finger paths around the ball; several paths compared ([`scene3d::fig_compare_paths`]) | Fig. 5, 10, 11, 12 |
//! | [`anim`] | self-contained HTML animation (inline SVG + JS, no network): time-based playback up to 10×, depth-ordered finger and ball, axes triad, ω and phase readout | Fig. 5/12 in motion |
//!
//! Figures are written atomically (temporary file in the target directory, then rename), so a
//! crashed run never leaves a half-written PNG behind.

pub mod anim;
mod canvas;
pub mod figure;
mod font;
pub mod paper;
pub mod sat;
pub mod scene3d;
pub mod ticks;

pub use font::text_width;

pub use figure::{
    Band, Colour, Dash, HLine, Layout, LegendPos, LineFigure, MIN_BAND_PX, PanelFigure,
    RenderReport, Scale, Series, SeriesStyle, render, render_panels, render_panels_report,
    render_report,
};

/// Everything that can go wrong while building or rendering a figure.
#[derive(Debug, thiserror::Error)]
pub enum PlotError {
    /// A figure (or panel) has no series at all.
    #[error("figure '{0}' has no series to plot")]
    NoSeries(String),
    /// A series has no points.
    #[error("series '{series}' of figure '{figure}' is empty")]
    EmptySeries {
        /// Figure title.
        figure: String,
        /// Series name.
        series: String,
    },
    /// A series has points, but none of them is finite (or positive, on a log axis).
    #[error(
        "series '{series}' of figure '{figure}' has no plottable point ({skipped} NaN/inf or non-positive-on-log-axis points)"
    )]
    NoFinitePoints {
        /// Figure title.
        figure: String,
        /// Series name.
        series: String,
        /// Number of points that were rejected.
        skipped: usize,
    },
    /// An explicit axis range or a marker position is not usable.
    #[error("invalid {what} in figure '{figure}': {detail}")]
    InvalidInput {
        /// Figure title.
        figure: String,
        /// Which input.
        what: String,
        /// Why it is invalid.
        detail: String,
    },
    /// Inconsistent lengths in the plain input data (e.g. `t` and `values` of a time series).
    #[error("shape mismatch in {what}: {detail}")]
    Shape {
        /// Which input.
        what: String,
        /// Expected vs found.
        detail: String,
    },
    /// The embedded font could not be registered (corrupt asset).
    #[error("embedded font could not be registered")]
    Font,
    /// A drawing backend failed.
    #[error("drawing failed: {0}")]
    Draw(String),
    /// Writing or renaming an output file failed.
    #[error(transparent)]
    Io(#[from] bf_output::FileError),
}

/// Font family name under which the embedded font is registered with plotters.
pub const FONT: &str = "sans-serif";

/// Registers the embedded font with plotters (idempotent, thread-safe). Every render entry point
/// calls it, so callers never need to.
pub fn ensure_font() -> Result<(), PlotError> {
    use std::sync::OnceLock;
    static DONE: OnceLock<bool> = OnceLock::new();
    let ok = *DONE.get_or_init(|| {
        plotters::style::register_font(FONT, plotters::style::FontStyle::Normal, font::DEJAVU_SANS)
            .is_ok()
    });
    if ok { Ok(()) } else { Err(PlotError::Font) }
}
