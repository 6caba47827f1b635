//! Saturation functions of Sect. 2.2 / 4.3 and the paper's Fig. 4.
//!
//! * [`sat_exact`]: sat_L^U(x) = ½ (L + U + |x − L| − |x − U|) (eq. 58) = clamp(x, L, U); in the
//!   collision model (eq. 3) it is sat_{−ℓ}^{0}(α), the signed offset of the contact point from the
//!   fingertip along the last link.
//! * [`sat_smooth`]: eq. (58) with |x| ≈ √(x² + ε²) (eq. 59); the paper uses ε = 0.01.
//! * [`sat_tanh`]: the scaled and shifted tanh of Fig. 4 (green curve): same limits L, U and the
//!   same unit slope at the midpoint, ½(L+U) + ½(U−L) tanh(2(x − ½(L+U))/(U−L)).
//!
//! All three have point symmetry about (½(L+U), ½(L+U)), which is (−0.5, −0.5) for L = −1, U = 0;
//! that is why Fig. 4 shows only the first quadrant around that point.

use crate::figure::{Colour, Dash, LineFigure, Series, SeriesStyle};

/// Exact saturation sat_L^U(x) (eq. 58), i.e. x clamped to [L, U] (NaN stays NaN).
pub fn sat_exact(x: f64, lower: f64, upper: f64) -> f64 {
    0.5 * (lower + upper + (x - lower).abs() - (x - upper).abs())
}

/// Smooth saturation: eq. (58) with |x| replaced by √(x² + ε²) (eq. 59).
pub fn sat_smooth(x: f64, lower: f64, upper: f64, eps: f64) -> f64 {
    let sabs = |v: f64| (v * v + eps * eps).sqrt();
    0.5 * (lower + upper + sabs(x - lower) - sabs(x - upper))
}

/// Scaled and shifted tanh with the limits and the midpoint slope (= 1) of sat_L^U.
pub fn sat_tanh(x: f64, lower: f64, upper: f64) -> f64 {
    let mid = 0.5 * (lower + upper);
    let half = 0.5 * (upper - lower);
    mid + half * (libm::tanh((x - mid) / half))
}

/// Fig. 4: sat_{−1}^{0} exact vs the smooth approximation for each ε in `eps` (the paper:
/// 0.01; pass `&[0.01, 0.1]` to also show a visibly smooth one) vs the scaled tanh, on the first
/// quadrant around the symmetry point (−0.5, −0.5): x ∈ [−0.5, 0.5]. `n` samples per curve
/// (at least 2; more resolve the ε = 0.01 corner at x = 0: use ≥ 400).
pub fn fig4_saturation(eps: &[f64], n: usize) -> LineFigure {
    let (lo, hi) = (-1.0, 0.0);
    let n = n.max(2);
    let xs: Vec<f64> = (0..n).map(|i| -0.5 + i as f64 / (n - 1) as f64).collect();
    let mut fig = LineFigure::new(
        "Fig. 4 counterpart: saturation sat₋₁⁰(x) and its approximations",
        "x [-]",
        "sat(x) [-]",
    );
    let style = |c: (u8, u8, u8), d: Dash, w: u32| SeriesStyle {
        colour: Colour::Rgb(c.0, c.1, c.2),
        dash: d,
        width: w,
        ..SeriesStyle::default()
    };
    fig.series.push(
        Series::new(
            "sat (exact, eq. 58)",
            xs.iter().map(|&x| (x, sat_exact(x, lo, hi))).collect(),
        )
        .styled(style((0, 0, 0), Dash::Solid, 3)),
    );
    let eps_colours = [
        (31, 119, 180),
        (214, 39, 40),
        (148, 103, 189),
        (140, 86, 75),
    ];
    let eps_dashes = [Dash::Dashed, Dash::Dotted, Dash::LongDash, Dash::Dashed];
    for (k, &e) in eps.iter().enumerate() {
        fig.series.push(
            Series::new(
                format!("smooth, ε = {e} (eq. 59)"),
                xs.iter().map(|&x| (x, sat_smooth(x, lo, hi, e))).collect(),
            )
            .styled(style(eps_colours[k % 4], eps_dashes[k % 4], 2)),
        );
    }
    fig.series.push(
        Series::new(
            "scaled/shifted tanh",
            xs.iter().map(|&x| (x, sat_tanh(x, lo, hi))).collect(),
        )
        .styled(style((44, 160, 44), Dash::Solid, 2)),
    );
    fig.x_range = Some((-0.5, 0.5));
    fig.y_range = Some((-0.5, 0.05));
    fig.legend = crate::figure::LegendPos::LowerRight;
    fig
}

#[cfg(test)]
mod tests {
    use super::*;

    fn grid() -> impl Iterator<Item = f64> {
        (0..=4000).map(|i| -3.0 + 6.0 * i as f64 / 4000.0)
    }

    #[test]
    fn exact_is_clamp() {
        for x in grid() {
            assert!((sat_exact(x, -1.0, 0.0) - x.clamp(-1.0, 0.0)).abs() < 1e-15);
            assert!((sat_exact(x, -0.7, 0.4) - x.clamp(-0.7, 0.4)).abs() < 1e-15);
        }
    }

    #[test]
    fn smooth_converges_to_exact_with_error_between_eps_over_2_and_eps() {
        let mut prev = f64::INFINITY;
        for eps in [0.3, 0.1, 0.03, 0.01, 0.001, 1e-5] {
            let err = grid()
                .chain([0.0, -1.0])
                .map(|x| (sat_smooth(x, -1.0, 0.0, eps) - sat_exact(x, -1.0, 0.0)).abs())
                .fold(0.0, f64::max);
            // |√(a²+ε²) − |a|| ≤ ε for each of the two terms, halved by eq. (58): err ≤ ε.
            assert!(err <= eps + 1e-15, "eps {eps}: err {err}");
            // At the corner x = 0 one term contributes exactly ε/2 (minus an O(ε²) term): the
            // smoothing is real, not a no-op.
            assert!(err >= 0.5 * eps - eps * eps, "eps {eps}: err {err}");
            assert!(err < prev);
            prev = err;
        }
    }

    #[test]
    fn point_symmetry_about_minus_half() {
        for x in grid() {
            for eps in [0.01, 0.1, 0.5] {
                let s = sat_smooth(x, -1.0, 0.0, eps) + sat_smooth(-1.0 - x, -1.0, 0.0, eps);
                assert!((s + 1.0).abs() < 1e-14, "x {x} eps {eps}: {s}");
            }
            let t = sat_tanh(x, -1.0, 0.0) + sat_tanh(-1.0 - x, -1.0, 0.0);
            assert!((t + 1.0).abs() < 1e-14);
            let e = sat_exact(x, -1.0, 0.0) + sat_exact(-1.0 - x, -1.0, 0.0);
            assert!((e + 1.0).abs() < 1e-14);
        }
    }

    #[test]
    fn tanh_has_sat_limits_and_unit_midpoint_slope() {
        let h = 1e-6;
        let slope = (sat_tanh(-0.5 + h, -1.0, 0.0) - sat_tanh(-0.5 - h, -1.0, 0.0)) / (2.0 * h);
        assert!((slope - 1.0).abs() < 1e-8);
        assert!((sat_tanh(50.0, -1.0, 0.0) - 0.0).abs() < 1e-12);
        assert!((sat_tanh(-50.0, -1.0, 0.0) + 1.0).abs() < 1e-12);
        // Fig. 4's remark: the tanh is far from sat at the corner x = 0 (error 0.5(1 − tanh 1)).
        let err0 = sat_tanh(0.0, -1.0, 0.0).abs();
        assert!((err0 - 0.5 * (1.0 - libm::tanh(1f64))).abs() < 1e-14);
        assert!(err0 > 0.1);
    }

    #[test]
    fn smooth_is_monotone_with_slope_at_most_one() {
        let eps = 0.01;
        let h = 1e-7;
        for x in grid() {
            let d =
                (sat_smooth(x + h, -1.0, 0.0, eps) - sat_smooth(x - h, -1.0, 0.0, eps)) / (2.0 * h);
            assert!(d > 0.0 && d <= 1.0 + 1e-6, "x {x}: slope {d}");
        }
    }

    #[test]
    fn fig4_has_exact_smooth_and_tanh_curves() {
        let f = fig4_saturation(&[0.01, 0.1], 401);
        assert_eq!(f.series.len(), 4);
        assert!(f.series.iter().all(|s| s.points.len() == 401));
        assert_eq!(f.series[0].points[0], (-0.5, -0.5));
        assert_eq!(f.series[0].points[400], (0.5, 0.0));
    }
}
