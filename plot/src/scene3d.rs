//! Orthographic views of finger paths around the ball (Fig. 5, 10, 11, 12).
//!
//! The scene of Sect. 2.1: ball of radius r centred at o_b, finger frames from the base o_f through
//! the DH frames to the fingertip p_e. Each [`View`] is an orthographic projection, so the sphere's
//! outline is exactly a circle of radius r around the projected centre; a wireframe of three great
//! circles (equator and two meridians) gives depth cues, all but one lying in the view plane,
//! which would only retrace the outline. Paths: fingertip p_e(t) and contact point
//! p_c(t) (eq. 3; NaN samples = not in contact leave gaps). [`fig_finger_paths`] draws one
//! finger (Fig. 5, 10, 12); [`fig_compare_paths`] overlays several paths (Fig. 11: the closest
//! points of the human and the robotic finger).

use crate::PlotError;
use crate::figure::{
    Colour, Dash, Layout, LegendPos, LineFigure, PanelFigure, Series, SeriesStyle,
};

/// One projection of 3D world coordinates onto a drawing plane.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum View {
    /// Horizontal x, vertical z (looking along +y).
    FrontXZ,
    /// Horizontal y, vertical z (looking along −x).
    SideYZ,
    /// Horizontal x, vertical y (looking down −z).
    TopXY,
    /// Isometric view from the (1, 1, 1) direction, z pointing up on screen.
    Iso,
}

/// Screen axes (e_u right, e_v up) of the isometric view; the camera looks along −(1,1,1)/√3.
pub const ISO_EU: [f64; 3] = [
    -std::f64::consts::FRAC_1_SQRT_2,
    std::f64::consts::FRAC_1_SQRT_2,
    0.0,
];
/// Screen up axis of the isometric view, (−1, −1, 2)/√6.
pub const ISO_EV: [f64; 3] = [
    -0.408_248_290_463_863,
    -0.408_248_290_463_863,
    0.816_496_580_927_726,
];
/// Direction from the scene towards the isometric camera, (1, 1, 1)/√3.
pub const ISO_D: [f64; 3] = [
    0.577_350_269_189_626,
    0.577_350_269_189_626,
    0.577_350_269_189_626,
];

fn dot(a: [f64; 3], b: [f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

impl View {
    /// Projects a world point onto (horizontal, vertical) screen coordinates \[m\].
    pub fn project(self, p: [f64; 3]) -> (f64, f64) {
        match self {
            View::FrontXZ => (p[0], p[2]),
            View::SideYZ => (p[1], p[2]),
            View::TopXY => (p[0], p[1]),
            View::Iso => (dot(p, ISO_EU), dot(p, ISO_EV)),
        }
    }

    fn labels(self) -> (&'static str, &'static str, &'static str) {
        match self {
            View::FrontXZ => ("front (x–z)", "x [m]", "z [m]"),
            View::SideYZ => ("side (y–z)", "y [m]", "z [m]"),
            View::TopXY => ("top (x–y)", "x [m]", "y [m]"),
            View::Iso => ("isometric", "u [m]", "v [m]"),
        }
    }
}

/// Finger configurations and paths around the ball.
#[derive(Clone, Debug, PartialEq, Default)]
pub struct FingerPaths {
    /// Ball centre o_b \[m\].
    pub ball_center: [f64; 3],
    /// Ball radius r \[m\].
    pub ball_radius: f64,
    /// Finger snapshots: each the frame origins from the base o_f to the fingertip p_e \[m\].
    pub snapshots: Vec<Vec<[f64; 3]>>,
    /// Fingertip path p_e(t) \[m\].
    pub tip_path: Vec<[f64; 3]>,
    /// Contact-point path p_c(t) \[m\]; NaN samples (no contact) leave gaps; may be empty.
    pub contact_path: Vec<[f64; 3]>,
}

fn style(c: (u8, u8, u8), dash: Dash, width: u32, markers: bool, in_legend: bool) -> SeriesStyle {
    SeriesStyle {
        colour: Colour::Rgb(c.0, c.1, c.2),
        dash,
        width,
        markers,
        in_legend,
    }
}

/// Fig. 5 / 10 / 12: one equal-aspect panel per view, side by side.
pub fn fig_finger_paths(
    title: &str,
    data: &FingerPaths,
    views: &[View],
) -> Result<PanelFigure, PlotError> {
    if views.is_empty() {
        return Err(PlotError::NoSeries(title.into()));
    }
    if !(data.ball_radius.is_finite() && data.ball_radius > 0.0)
        || data.ball_center.iter().any(|v| !v.is_finite())
    {
        return Err(PlotError::InvalidInput {
            figure: title.into(),
            what: "ball".into(),
            detail: format!("centre {:?}, radius {}", data.ball_center, data.ball_radius),
        });
    }
    if data.snapshots.is_empty() && data.tip_path.is_empty() {
        return Err(PlotError::NoSeries(format!(
            "{title} (no snapshots and no tip path)"
        )));
    }
    let (c, r) = (data.ball_center, data.ball_radius);
    let mut panels = Vec::with_capacity(views.len());
    for &v in views {
        let (name, xl, yl) = v.labels();
        let mut p = LineFigure::new(name, xl, yl);
        p.equal_aspect = true;
        p.legend = LegendPos::Auto;
        let proj = |pts: &[[f64; 3]]| pts.iter().map(|&q| v.project(q)).collect::<Vec<_>>();
        p.series.extend(sphere_series(c, r, v));
        for (k, snap) in data.snapshots.iter().enumerate() {
            if snap.len() < 2 {
                return Err(PlotError::Shape {
                    what: format!("snapshot {k}"),
                    detail: format!("{} points (need ≥ 2)", snap.len()),
                });
            }
            p.series.push(
                Series::new(if k == 0 { "finger (snapshots)" } else { "" }, proj(snap))
                    .styled(style((20, 20, 20), Dash::Solid, 3, true, k == 0)),
            );
        }
        if !data.tip_path.is_empty() {
            p.series.push(
                Series::new("fingertip path", proj(&data.tip_path)).styled(style(
                    (31, 119, 180),
                    Dash::Solid,
                    2,
                    false,
                    true,
                )),
            );
        }
        if data
            .contact_path
            .iter()
            .any(|q| q.iter().all(|x| x.is_finite()))
        {
            // Last and thick, with a dot per sample: a contact path of a few millimetres must
            // stay visible above the fingertip path and the snapshots' joint markers.
            p.series.push(
                Series::new("contact point path", proj(&data.contact_path)).styled(style(
                    (214, 39, 40),
                    Dash::Solid,
                    4,
                    true,
                    true,
                )),
            );
        }
        panels.push(p);
    }
    Ok(PanelFigure {
        title: title.into(),
        panels,
        layout: Layout::Columns,
        size: None,
    })
}

/// A named 3D path for [`fig_compare_paths`].
#[derive(Clone, Debug, PartialEq, Default)]
pub struct NamedPath {
    /// Legend text, e.g. "human finger: closest point".
    pub name: String,
    /// Points \[m\]; NaN samples leave gaps.
    pub points: Vec<[f64; 3]>,
}

fn sphere_series(c: [f64; 3], r: f64, v: View) -> Vec<Series> {
    let circle = |a: [f64; 3], b: [f64; 3]| -> Vec<(f64, f64)> {
        (0..=120)
            .map(|i| {
                let th = i as f64 * std::f64::consts::TAU / 120.0;
                let (s, co) = libm::sincos(th);
                v.project([0, 1, 2].map(|k| c[k] + r * (co * a[k] + s * b[k])))
            })
            .collect()
    };
    let (cu, cv) = v.project(c);
    let outline = (0..=120)
        .map(|i| {
            let th = i as f64 * std::f64::consts::TAU / 120.0;
            (cu + r * libm::cos(th), cv + r * libm::sin(th))
        })
        .collect();
    let (ex, ey, ez) = ([1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]);
    let mut out =
        vec![Series::new("ball", outline).styled(style((60, 60, 60), Dash::Solid, 2, false, true))];
    for (a, b) in [(ex, ey), (ex, ez), (ey, ez)] {
        let wire = circle(a, b);
        // The great circle in the view plane projects onto the outline itself: drawn again,
        // thinner and grey, over it, it only blurs the outline.
        let on_outline = wire
            .iter()
            .all(|&(x, y)| (libm::hypot(x - cu, y - cv) - r).abs() <= 1e-9 * r);
        if on_outline {
            continue;
        }
        out.push(Series::new("", wire).styled(style(
            (190, 190, 190),
            Dash::Solid,
            1,
            false,
            false,
        )));
    }
    out
}

/// Fig. 11: several paths around the same ball compared (the closest points of the human and
/// the robotic finger), one equal-aspect panel per view, one colour per path.
pub fn fig_compare_paths(
    title: &str,
    ball_center: [f64; 3],
    ball_radius: f64,
    paths: &[NamedPath],
    views: &[View],
) -> Result<PanelFigure, PlotError> {
    if views.is_empty() || paths.is_empty() {
        return Err(PlotError::NoSeries(title.into()));
    }
    if !(ball_radius.is_finite() && ball_radius > 0.0) || ball_center.iter().any(|v| !v.is_finite())
    {
        return Err(PlotError::InvalidInput {
            figure: title.into(),
            what: "ball".into(),
            detail: format!("centre {ball_center:?}, radius {ball_radius}"),
        });
    }
    const COLOURS: [(u8, u8, u8); 4] = [
        (31, 119, 180),
        (214, 39, 40),
        (44, 160, 44),
        (148, 103, 189),
    ];
    const DASHES: [Dash; 4] = [Dash::Solid, Dash::Dashed, Dash::Solid, Dash::Dashed];
    let mut panels = Vec::with_capacity(views.len());
    for &v in views {
        let (name, xl, yl) = v.labels();
        let mut p = LineFigure::new(name, xl, yl);
        p.equal_aspect = true;
        p.series = sphere_series(ball_center, ball_radius, v);
        for (k, path) in paths.iter().enumerate() {
            if path.points.is_empty() {
                return Err(PlotError::EmptySeries {
                    figure: title.into(),
                    series: path.name.clone(),
                });
            }
            p.series.push(
                Series::new(
                    path.name.clone(),
                    path.points.iter().map(|&q| v.project(q)).collect(),
                )
                .styled(style(COLOURS[k % 4], DASHES[k % 4], 3, false, true)),
            );
        }
        panels.push(p);
    }
    Ok(PanelFigure {
        title: title.into(),
        panels,
        layout: Layout::Columns,
        size: None,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn iso_axes_are_orthonormal_and_right_handed() {
        for (a, b, e) in [
            (ISO_EU, ISO_EU, 1.0),
            (ISO_EV, ISO_EV, 1.0),
            (ISO_D, ISO_D, 1.0),
            (ISO_EU, ISO_EV, 0.0),
            (ISO_EU, ISO_D, 0.0),
            (ISO_EV, ISO_D, 0.0),
        ] {
            assert!((dot(a, b) - e).abs() < 1e-12);
        }
        let cross = [
            ISO_EU[1] * ISO_EV[2] - ISO_EU[2] * ISO_EV[1],
            ISO_EU[2] * ISO_EV[0] - ISO_EU[0] * ISO_EV[2],
            ISO_EU[0] * ISO_EV[1] - ISO_EU[1] * ISO_EV[0],
        ];
        for k in 0..3 {
            assert!((cross[k] - ISO_D[k]).abs() < 1e-12);
        }
    }

    #[test]
    fn projected_wireframe_stays_inside_outline() {
        // Orthographic projection never moves a sphere point outside the outline circle; the
        // great circle in the view plane, which would retrace the outline, is left out (the
        // front view shows two of the three, the iso view all three).
        let data = FingerPaths {
            ball_center: [0.5, -0.2, 0.1],
            ball_radius: 1.0,
            tip_path: vec![[2.0, 0.0, 0.0]],
            ..Default::default()
        };
        let views = [View::FrontXZ, View::SideYZ, View::Iso];
        let f = fig_finger_paths("t", &data, &views).unwrap();
        for ((p, v), n) in f.panels.iter().zip(views).zip([2, 2, 3]) {
            let (cu, cv) = v.project(data.ball_center);
            let wire: Vec<&Series> = p.series.iter().filter(|s| s.name.is_empty()).collect();
            assert_eq!(wire.len(), n, "{v:?}");
            for s in wire {
                let d: Vec<f64> = s
                    .points
                    .iter()
                    .map(|&(u, w)| libm::hypot(u - cu, w - cv))
                    .collect();
                assert!(d.iter().all(|&d| d <= 1.0 + 1e-12), "{v:?}");
                assert!(d.iter().any(|&d| d < 0.99), "{v:?}: a wire on the outline");
            }
        }
    }
}
