//! Metrics of the embedded font, DejaVu Sans, read from the font file itself: the layout
//! measures every text with them, the SVG names that font with the same em size, and the PNG
//! draws it at the same em size, so a viewer that has DejaVu Sans (or is given the file, as the
//! render tests do) lays each text out to the width the layout reserved.
//!
//! Sizes are em sizes in pixels (CSS `font-size`). Plotters' `ab_glyph` backend scales a font
//! to its ascent − descent instead (1.164 em for DejaVu Sans), so [`plotters_size`] converts.

use ab_glyph::{Font, FontRef, GlyphId};
use std::sync::OnceLock;

/// The embedded DejaVu Sans (Bitstream Vera licence, see `assets/LICENSE-DejaVu.txt`).
pub(crate) static DEJAVU_SANS: &[u8] = include_bytes!("../assets/DejaVuSans.ttf");

/// The family name the SVG asks for: the embedded font's own name.
pub(crate) const FAMILY: &str = "DejaVu Sans";

/// Vertical metrics in em, and the parsed font for advance widths.
struct Metrics {
    font: FontRef<'static>,
    /// Font units per em.
    upem: f64,
    /// Ascent above the baseline, em.
    ascent: f64,
    /// Descent below the baseline, em (positive).
    descent: f64,
    /// Height of a capital letter ('H'), em.
    cap: f64,
}

/// The metrics, or `None` when the embedded file does not parse (then [`crate::ensure_font`]
/// fails too, so no figure is drawn with the fallback estimate).
fn metrics() -> Option<&'static Metrics> {
    static M: OnceLock<Option<Metrics>> = OnceLock::new();
    M.get_or_init(|| {
        let font = FontRef::try_from_slice(DEJAVU_SANS).ok()?;
        let upem = f64::from(font.units_per_em()?);
        let h = font.outline(font.glyph_id('H'))?;
        Some(Metrics {
            upem,
            ascent: f64::from(font.ascent_unscaled()) / upem,
            descent: -f64::from(font.descent_unscaled()) / upem,
            // ab_glyph's unscaled outline bounds put min and max in y-down order.
            cap: f64::from(h.bounds.max.y - h.bounds.min.y).abs() / upem,
            font,
        })
    })
    .as_ref()
}

/// Advance width in pixels of `text` at em size `em` (SVG `font-size`) in the embedded DejaVu
/// Sans: the sum of the glyph advances plus the pair kerning of the font's `kern` table, as a
/// browser lays out a single line. Every figure's layout reserves this width for its texts.
pub fn text_width(text: &str, em: f64) -> f64 {
    let Some(m) = metrics() else {
        // Wider than any DejaVu glyph but the widest few: an overestimate keeps texts apart.
        return 0.65 * em * text.chars().count() as f64;
    };
    let mut units = 0.0f64;
    let mut prev: Option<GlyphId> = None;
    for c in text.chars() {
        let g = m.font.glyph_id(c);
        units += f64::from(m.font.h_advance_unscaled(g));
        if let Some(p) = prev {
            units += f64::from(m.font.kern_unscaled(p, g));
        }
        prev = Some(g);
    }
    units / m.upem * em
}

/// Height in pixels of a line (ascent + descent) at em size `em`.
pub(crate) fn line_height(em: f64) -> f64 {
    metrics().map_or(1.164, |m| m.ascent + m.descent) * em
}

/// Distance in pixels from the visual middle of a text (the middle of its capitals) down to its
/// baseline, at em size `em`.
pub(crate) fn baseline_below_middle(em: f64) -> f64 {
    0.5 * metrics().map_or(0.729, |m| m.cap) * em
}

/// The size to give plotters' `ab_glyph` backend for em size `em` (it scales the font so that
/// ascent − descent equals the size).
pub(crate) fn plotters_size(em: f64) -> f64 {
    line_height(em)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// DejaVu Sans's published metrics (2048 units per em; hhea ascent 1901, descent −483;
    /// capital height 1493; advance of 'H' 1540, of a digit 1303, of a space 651).
    #[test]
    fn metrics_match_the_published_dejavu_sans_values() {
        let m = metrics().expect("embedded font parses");
        assert_eq!(m.upem, 2048.0);
        assert!((m.ascent - 1901.0 / 2048.0).abs() < 1e-12);
        assert!((m.descent - 483.0 / 2048.0).abs() < 1e-12);
        assert!((m.cap - 1493.0 / 2048.0).abs() < 1e-12);
        assert!((text_width("H", 2048.0) - 1540.0).abs() < 1e-9);
        assert!((text_width("0123456789", 2048.0) - 13030.0).abs() < 1e-9);
        assert!((text_width("1 1", 2048.0) - (2.0 * 1303.0 + 651.0)).abs() < 1e-9);
        // Widths scale with the em size.
        let w = text_width("ω_ref [rad/s]", 15.0);
        assert!((text_width("ω_ref [rad/s]", 30.0) - 2.0 * w).abs() < 1e-9);
    }
}
