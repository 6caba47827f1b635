//! Data preparation: styles resolved to colours and dashes (and the pixel pattern of a dash,
//! `dash_pattern`), points mapped to plotting coordinates (log10 on log axes) and split at
//! non-plottable points, inputs validated, and the default axis ranges.

use super::{Colour, Dash, LineFigure, Scale};
use crate::PlotError;
use crate::canvas::Rgb;

/// Qualitative palette (Tableau 10): distinguishable, and dark enough on white.
pub(super) const PALETTE: [(u8, u8, u8); 10] = [
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

pub(super) const DASHES: [Dash; 4] = [Dash::Solid, Dash::Dashed, Dash::Dotted, Dash::LongDash];

/// Maps a data value into plotting coordinates (log10 on log axes); `None` if not plottable.
pub(super) fn tx(v: f64, s: Scale) -> Option<f64> {
    match s {
        Scale::Linear => v.is_finite().then_some(v),
        Scale::Log10 => (v.is_finite() && v > 0.0).then(|| libm::log10(v)),
    }
}

pub(super) struct PreparedSeries {
    pub(super) name: String,
    pub(super) pieces: Vec<Vec<(f64, f64)>>,
    /// Labelled points (plotting coordinates) and their text.
    pub(super) labels: Vec<((f64, f64), String)>,
    pub(super) joined: bool,
    pub(super) colour: Rgb,
    pub(super) dash: Dash,
    pub(super) width: u32,
    pub(super) markers: bool,
    pub(super) in_legend: bool,
}

pub(super) struct Prepared {
    pub(super) series: Vec<PreparedSeries>,
    pub(super) skipped: usize,
    /// Ranges in plotting coordinates (before the equal-aspect adjustment).
    pub(super) xr: (f64, f64),
    pub(super) yr: (f64, f64),
}

pub(super) fn invalid(fig: &LineFigure, what: &str, detail: String) -> PlotError {
    PlotError::InvalidInput {
        figure: fig.title.clone(),
        what: what.into(),
        detail,
    }
}

pub(super) fn prepare(fig: &LineFigure) -> Result<Prepared, PlotError> {
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
    // The PNG draws glyph by glyph: a combining mark (ω̄ as ω + U+0304) lands beside its
    // letter or not at all, so the PNG would name another quantity than the SVG.
    let texts = [&fig.title, &fig.x_label, &fig.y_label]
        .into_iter()
        .chain(fig.series.iter().map(|s| &s.name));
    for t in texts {
        if let Some(c) = t.chars().find(|c| ('\u{300}'..='\u{36f}').contains(c)) {
            return Err(invalid(
                fig,
                "text",
                format!(
                    "'{t}' holds the combining mark U+{:04X}, which the PNG cannot place",
                    u32::from(c)
                ),
            ));
        }
    }
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
    let xr = xr_fixed.unwrap_or_else(|| snap_log(widen(fold(|p| p.0), x_pad), fig.x_scale));
    let yr = yr_fixed.unwrap_or_else(|| {
        let (mut lo, mut hi) = fold(|p| p.1);
        for h in fig.hlines.iter().filter(|h| h.fit) {
            if let Some(y) = tx(h.y, fig.y_scale) {
                lo = lo.min(y);
                hi = hi.max(y);
            }
        }
        if fig.y_includes_zero && fig.y_scale == Scale::Linear {
            lo = lo.min(0.0);
            hi = hi.max(0.0);
        }
        let non_negative = fig.y_non_negative && fig.y_scale == Scale::Linear && lo >= 0.0;
        if non_negative && hi <= 0.0 {
            // Identically 0: the axis of a quantity that cannot be negative is [0, 1], its
            // line lifted off the frame as below.
            return (-ZERO_LIFT, 1.0);
        }
        let (lo, hi) = widen((lo, hi), 0.05);
        if non_negative {
            // No negative range (nor tick) for a quantity that cannot be negative, but a line
            // at 0 is drawn just above the frame, not hidden in it.
            (lo.max(-ZERO_LIFT * hi), hi)
        } else {
            snap_log((lo, hi), fig.y_scale)
        }
    });
    Ok(Prepared {
        series: out,
        skipped,
        xr,
        yr,
    })
}

/// On a log axis, the range `(lo, hi)` (log10 units) widened to ticks: to whole decades where it
/// spans two decades or more, so that the decade labels include both ends, otherwise to the
/// nearest mantissa ticks m·10^e (m = 1…9) at or beyond its ends, so that no data lies beyond
/// the outermost tick. Linear ranges are returned as they are.
pub(super) fn snap_log((lo, hi): (f64, f64), scale: Scale) -> (f64, f64) {
    if scale != Scale::Log10 || !(lo.is_finite() && hi.is_finite() && hi > lo) {
        return (lo, hi);
    }
    // Positions within this of a tick count as on it (rounding of log10).
    const ON: f64 = 1e-9;
    if hi - lo >= 2.0 - ON {
        return ((lo + ON).floor(), (hi - ON).ceil());
    }
    let down = |v: f64| {
        let e = (v + ON).floor();
        let m = libm::pow(10.0, v - e);
        e + libm::log10((m + ON).floor().max(1.0))
    };
    let up = |v: f64| {
        let e = (v - ON).floor();
        let m = (libm::pow(10.0, v - e) - ON).ceil();
        if m >= 10.0 {
            e + 1.0
        } else {
            e + libm::log10(m)
        }
    };
    (down(lo), up(hi))
}

/// The share of a non-negative axis's range left below 0, so that a line at 0 is not drawn
/// on the frame: under half the smallest tick step (a tenth of the range at most 8 ticks),
/// so that no tick falls below 0.
pub(super) const ZERO_LIFT: f64 = 0.02;

/// Pads a range by `frac` of its span and makes degenerate ranges non-empty.
pub(super) fn widen((lo, hi): (f64, f64), frac: f64) -> (f64, f64) {
    let span = hi - lo;
    if span > 1e-12 * lo.abs().max(hi.abs()).max(1e-300) {
        (lo - frac * span, hi + frac * span)
    } else {
        let d = if lo.abs() > 0.0 { 0.1 * lo.abs() } else { 1.0 };
        (lo - d, hi + d)
    }
}

/// (dash, gap) in pixels; `None` for solid lines.
pub(super) fn dash_pattern(d: Dash) -> Option<(f64, f64)> {
    match d {
        Dash::Auto | Dash::Solid => None,
        Dash::Dashed => Some((10.0, 6.0)),
        Dash::Dotted => Some((2.0, 5.0)),
        Dash::LongDash => Some((20.0, 7.0)),
    }
}
