//! Builders for the time-series figures of Sect. 6 and the speed–accuracy report.
//!
//! | builder | paper figure | content |
//! |---|---|---|
//! | [`fig_ball_omega`] | Fig. 6, 13 | ball angular velocity ω (world axes) with switching times t_f^(i) |
//! | [`fig_distance`] | Fig. 7, 14 | minimum distance h (eq. 5) and contact-point distance from the fingertip, |sat(α)| (eq. 3) |
//! | [`fig_torques`] | Fig. 8, 15 | joint torques τ_1..τ_3 with the limit |τ_i| ≤ τ_max |
//! | [`fig_contact_forces`] | Fig. 9, 16 | normal force λ_n, tangential ‖λ_∥‖ and the friction-cone bound μ_s λ_n, drawn in contact only, zoomed on short contact windows ([`contact_zoom`]) |
//! | [`fig_open_loop_vs_optimal`] | Fig. 17 | optimal vs open-loop simulated ω, one panel per axis |
//! | [`fig_ball_omega_ref`] | Fig. 13 | as Fig. 6, with the reference ω_ref as dashed lines |
//! | [`fig_open_loop_vs_optimal_modes`] | Fig. 17 | as above, shaded by the simulation's slip/stick modes |
//! | [`fig_work_precision`] | — | log–log error vs computing time, one series per method |
//! | [`fig_work_precision_sets`] | — | as above with labelled runs; unordered sets as markers only |
//!
//! Inputs are plain [`TimeSeries`] (no dependency on the physics crates) and [`Phases`]
//! (switching times and the contact intervals, drawn as markers and shaded bands); a
//! simulation's contact modes are bf-scene's [`Mode`].

use crate::PlotError;
use crate::figure::{
    Band, Colour, Dash, HLine, Layout, LineFigure, PanelFigure, Scale, Series, SeriesStyle,
};

/// Sampled signals on a common time grid: `values[k][i]` is component `k` at `t[i]`.
#[derive(Clone, Debug, PartialEq, Default)]
pub struct TimeSeries {
    /// Sample times \[s\].
    pub t: Vec<f64>,
    /// One vector per component, each as long as `t`.
    pub values: Vec<Vec<f64>>,
    /// One name per component (legend text).
    pub names: Vec<String>,
}

impl TimeSeries {
    /// Checks that every component has one value per time and one name.
    pub fn validate(&self, what: &str) -> Result<(), PlotError> {
        if self.names.len() != self.values.len() {
            return Err(PlotError::Shape {
                what: what.into(),
                detail: format!(
                    "{} names for {} components",
                    self.names.len(),
                    self.values.len()
                ),
            });
        }
        for (k, v) in self.values.iter().enumerate() {
            if v.len() != self.t.len() {
                return Err(PlotError::Shape {
                    what: what.into(),
                    detail: format!(
                        "component {k} has {} values for {} times",
                        v.len(),
                        self.t.len()
                    ),
                });
            }
        }
        Ok(())
    }

    /// Component `k` as (t, value) points.
    pub fn points(&self, k: usize) -> Vec<(f64, f64)> {
        self.t
            .iter()
            .copied()
            .zip(self.values[k].iter().copied())
            .collect()
    }

    fn expect_components(&self, what: &str, n: usize) -> Result<(), PlotError> {
        self.validate(what)?;
        if self.values.len() != n {
            return Err(PlotError::Shape {
                what: what.into(),
                detail: format!("expected {n} components, found {}", self.values.len()),
            });
        }
        Ok(())
    }
}

/// Phase structure of a trajectory (Sect. 4.2): switching times and the contact intervals.
#[derive(Clone, Debug, PartialEq, Default)]
pub struct Phases {
    /// (time \[s\], short label) of each switch, e.g. (0.8, "impact"), (1.3, "lift-off").
    pub switches: Vec<(f64, String)>,
    /// Closed intervals \[s\] during which the finger touches the ball (shaded).
    pub contact: Vec<(f64, f64)>,
}

impl Phases {
    fn apply(&self, fig: &mut LineFigure) {
        fig.vertical_markers = self.switches.clone();
        fig.bands = self
            .contact
            .iter()
            .map(|&(x0, x1)| Band {
                x0,
                x1,
                label: "contact".into(),
                colour: Colour::Auto,
            })
            .collect();
    }
}

fn fixed(c: (u8, u8, u8), dash: Dash) -> SeriesStyle {
    SeriesStyle {
        colour: Colour::Rgb(c.0, c.1, c.2),
        dash,
        ..SeriesStyle::default()
    }
}

const C_BLUE: (u8, u8, u8) = (31, 119, 180);
const C_ORANGE: (u8, u8, u8) = (255, 127, 14);
const C_GREEN: (u8, u8, u8) = (44, 160, 44);
const C_RED: (u8, u8, u8) = (214, 39, 40);

/// Fig. 6 / 13: the three components of the ball angular velocity ω [rad/s] in one axes, with
/// the switching times and contact intervals. `omega` must have exactly 3 components.
pub fn fig_ball_omega(
    title: &str,
    omega: &TimeSeries,
    phases: &Phases,
) -> Result<LineFigure, PlotError> {
    omega.expect_components("ball angular velocity", 3)?;
    let mut fig = LineFigure::new(title, "t [s]", "ω [rad/s]");
    for k in 0..3 {
        fig.series
            .push(Series::new(omega.names[k].clone(), omega.points(k)));
    }
    phases.apply(&mut fig);
    Ok(fig)
}

/// Fig. 7 / 14: two stacked panels over the same time axis: the minimum distance h \[m\]
/// (with the h = 0 contact line) and the distance of the contact point from the fingertip,
/// |sat_{−ℓ}^{0}(α)| \[m\] (0: tip contact; ℓ: the joint end of the last link).
pub fn fig_distance(
    title: &str,
    t: &[f64],
    h: &[f64],
    contact_from_tip: &[f64],
    phases: &Phases,
) -> Result<PanelFigure, PlotError> {
    for (name, v) in [("h", h), ("contact-point distance", contact_from_tip)] {
        if v.len() != t.len() {
            return Err(PlotError::Shape {
                what: name.into(),
                detail: format!("{} values for {} times", v.len(), t.len()),
            });
        }
    }
    let pts = |v: &[f64]| t.iter().copied().zip(v.iter().copied()).collect::<Vec<_>>();
    let mut a = LineFigure::new("minimum distance h", "t [s]", "h [m]");
    a.series
        .push(Series::new("h", pts(h)).styled(fixed(C_BLUE, Dash::Solid)));
    a.hlines.push(HLine {
        y: 0.0,
        label: "h = 0: touching the ball".into(),
        colour: Colour::Auto,
        fit: true,
    });
    phases.apply(&mut a);
    // The legend names the plotted quantity as the axis does (with its definition by the
    // saturated contact parameter, eq. 3); a distance: the axis starts at 0.
    let mut b = LineFigure::new("contact point to fingertip", "t [s]", "|p_c − p_e| [m]");
    b.y_non_negative = true;
    b.series.push(
        Series::new("|p_c − p_e| = |sat(α)|", pts(contact_from_tip))
            .styled(fixed(C_ORANGE, Dash::Solid)),
    );
    phases.apply(&mut b);
    Ok(PanelFigure {
        title: title.into(),
        panels: vec![a, b],
        layout: Layout::Rows,
        size: None,
    })
}

/// A torque limit is drawn inside the autoscaled axis when it is at most this multiple of the
/// panel's peak |τ|; beyond that the axis fits the data alone.
pub const LIMIT_FIT_RATIO: f64 = 2.0;

/// Fig. 8 / 15: joint torques, one panel per joint, autoscaled to the data and zero (the sign
/// of a torque matters, and every panel reads the same way), with dashed
/// ±`limit` lines when given (drawn when within [`LIMIT_FIT_RATIO`] × the peak |τ| of the
/// panel, otherwise listed in the legend as off scale).
pub fn fig_torques(
    title: &str,
    tau: &TimeSeries,
    limit: Option<f64>,
    phases: &Phases,
) -> Result<PanelFigure, PlotError> {
    tau.validate("torques")?;
    if tau.values.is_empty() {
        return Err(PlotError::NoSeries(title.into()));
    }
    let colours = [C_BLUE, C_ORANGE, C_GREEN, C_RED];
    let panels = (0..tau.values.len())
        .map(|k| {
            let mut p = LineFigure::new("", "t [s]", format!("{} [N m]", tau.names[k]));
            p.y_includes_zero = true;
            p.series.push(
                Series::new(tau.names[k].clone(), tau.points(k))
                    .styled(fixed(colours[k % 4], Dash::Solid)),
            );
            if let Some(l) = limit {
                // The axis fits the data; the limit joins the range only when it is close to
                // the data (otherwise small torques would be squashed against zero, and the
                // legend says the limit is off scale).
                let peak = tau.values[k]
                    .iter()
                    .filter(|v| v.is_finite())
                    .fold(0.0f64, |m, v| m.max(v.abs()));
                let fit = l.abs() <= LIMIT_FIT_RATIO * peak;
                p.hlines.push(HLine {
                    y: l,
                    label: format!("torque limit ±{l} N m"),
                    colour: Colour::Rgb(120, 0, 0),
                    fit,
                });
                p.hlines.push(HLine {
                    y: -l,
                    label: String::new(),
                    colour: Colour::Rgb(120, 0, 0),
                    fit,
                });
            }
            phases.apply(&mut p);
            p
        })
        .collect();
    Ok(PanelFigure {
        title: title.into(),
        panels,
        layout: Layout::Rows,
        size: None,
    })
}

/// Fig. 9 / 16: contact force: λ_n, ‖λ_∥‖ and the friction-cone bound μ_s λ_n \[N\], on an axis
/// that includes zero. Sticking
/// requires ‖λ_∥‖ ≤ μ_s λ_n; where the two curves touch the motion is on the verge of slipping
/// (Fig. 16). Samples outside contact may be NaN (they leave gaps).
pub fn fig_contact_forces(
    title: &str,
    t: &[f64],
    lambda_n: &[f64],
    lambda_t_norm: &[f64],
    mu_s: f64,
    phases: &Phases,
) -> Result<LineFigure, PlotError> {
    for (name, v) in [("λ_n", lambda_n), ("‖λ_∥‖", lambda_t_norm)] {
        if v.len() != t.len() {
            return Err(PlotError::Shape {
                what: name.into(),
                detail: format!("{} values for {} times", v.len(), t.len()),
            });
        }
    }
    if !(mu_s.is_finite() && mu_s >= 0.0) {
        return Err(PlotError::InvalidInput {
            figure: title.into(),
            what: "μ_s".into(),
            detail: format!("{mu_s}"),
        });
    }
    // Forces exist only in contact: outside the contact intervals (when given) nothing is
    // drawn, so the cone bound is not shown along zero in free flight.
    let in_contact =
        |x: f64| phases.contact.is_empty() || phases.contact.iter().any(|&(a, b)| x >= a && x <= b);
    let pts = |f: &dyn Fn(usize) -> f64| {
        (0..t.len())
            .map(|i| (t[i], if in_contact(t[i]) { f(i) } else { f64::NAN }))
            .collect::<Vec<_>>()
    };
    let mut fig = LineFigure::new(title, "t [s]", "force [N]");
    fig.y_includes_zero = true;
    fig.series
        .push(Series::new("normal λ_n", pts(&|i| lambda_n[i])).styled(fixed(C_BLUE, Dash::Solid)));
    fig.series.push(
        Series::new("tangential ‖λ_∥‖", pts(&|i| lambda_t_norm[i]))
            .styled(fixed(C_ORANGE, Dash::Solid)),
    );
    fig.series.push(
        Series::new(
            format!("cone bound μ_s λ_n (μ_s = {mu_s})"),
            pts(&|i| mu_s * lambda_n[i]),
        )
        .styled(fixed((0, 0, 0), Dash::Dashed)),
    );
    phases.apply(&mut fig);
    fig.x_range = contact_zoom(t, phases);
    if fig.x_range.is_some() {
        fig.title = format!("{title} (zoom on the contact window)");
    }
    Ok(fig)
}

/// Contact windows covering less than this share of the time axis are zoomed in on.
pub const ZOOM_BELOW_SHARE: f64 = 0.3;

/// The x range of a zoom on the contact intervals when they cover less than
/// [`ZOOM_BELOW_SHARE`] of the sampled time span: from the first contact start to the last
/// contact end, padded by 15 % of that window on each side and kept within the samples.
pub fn contact_zoom(t: &[f64], phases: &Phases) -> Option<(f64, f64)> {
    let (t0, t1) = t
        .iter()
        .filter(|v| v.is_finite())
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &v| {
            (a.min(v), b.max(v))
        });
    let (c0, c1) = phases
        .contact
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &(x, y)| {
            (a.min(x), b.max(y))
        });
    let (span, window) = (t1 - t0, c1 - c0);
    if !(span > 0.0 && window > 0.0) {
        return None;
    }
    let covered: f64 = phases.contact.iter().map(|&(a, b)| (b - a).max(0.0)).sum();
    if covered >= ZOOM_BELOW_SHARE * span {
        return None;
    }
    let pad = 0.15 * window;
    let r = ((c0 - pad).max(t0), (c1 + pad).min(t1));
    (r.0 < r.1).then_some(r)
}

/// Fig. 6 / 13 with reference lines: as [`fig_ball_omega`], plus a dashed horizontal line
/// per `(name, value)` in `reference`, e.g. `("ω_ref,z", 2.0)` for the quadratic criterion's
/// reference angular velocity (Sect. 6.1).
pub fn fig_ball_omega_ref(
    title: &str,
    omega: &TimeSeries,
    phases: &Phases,
    reference: &[(String, f64)],
) -> Result<LineFigure, PlotError> {
    let mut fig = fig_ball_omega(title, omega, phases)?;
    for (name, v) in reference {
        if !v.is_finite() {
            return Err(PlotError::InvalidInput {
                figure: title.into(),
                what: "reference value".into(),
                detail: format!("'{name}' = {v}"),
            });
        }
        fig.hlines.push(HLine {
            y: *v,
            label: format!("{name} = {v} rad/s"),
            colour: Colour::Rgb(60, 60, 60),
            fit: true,
        });
    }
    Ok(fig)
}

/// Contact modes of a simulation over time, for shading (Fig. 17): closed intervals \[s\].
#[derive(Clone, Debug, PartialEq, Default)]
pub struct SimModes {
    /// Intervals in which the finger slips on the ball.
    pub slip: Vec<(f64, f64)>,
    /// Intervals in which the finger sticks to (rolls without slipping on) the ball.
    pub stick: Vec<(f64, f64)>,
}

/// Contact mode of one sample, for [`SimModes::from_trace`] (the one contact-mode type of
/// the workspace, defined in bf-scene).
pub use bf_scene::Mode;

impl SimModes {
    /// Intervals from a sampled mode trace (`modes[i]` holds at `t[i]`): each maximal run of
    /// equal modes spans from its first sample to the next run's first sample (the last run to
    /// the last sample), so adjacent intervals meet without gaps.
    pub fn from_trace(t: &[f64], modes: &[Mode]) -> Result<Self, PlotError> {
        if t.len() != modes.len() {
            return Err(PlotError::Shape {
                what: "contact-mode trace".into(),
                detail: format!("{} times for {} modes", t.len(), modes.len()),
            });
        }
        let mut out = SimModes::default();
        let mut i = 0;
        while i < t.len() {
            let mut j = i + 1;
            while j < t.len() && modes[j] == modes[i] {
                j += 1;
            }
            let end = t[j.min(t.len() - 1)];
            match modes[i] {
                Mode::Stick => out.stick.push((t[i], end)),
                Mode::Slip => out.slip.push((t[i], end)),
                Mode::Free => {}
            }
            i = j;
        }
        Ok(out)
    }
}

/// Fig. 17 with the simulation's contact modes: as [`fig_open_loop_vs_optimal`] (whose
/// markers are the optimum's switching times from `phases`), with the open-loop simulation's
/// slip intervals shaded orange and its stick intervals shaded green instead of the optimum's
/// contact band.
pub fn fig_open_loop_vs_optimal_modes(
    title: &str,
    optimal: &TimeSeries,
    open_loop: &TimeSeries,
    phases: &Phases,
    modes: &SimModes,
) -> Result<PanelFigure, PlotError> {
    let mut fig = fig_open_loop_vs_optimal(title, optimal, open_loop, phases)?;
    let band = |(x0, x1): (f64, f64), label: &str, c: (u8, u8, u8)| Band {
        x0,
        x1,
        label: label.into(),
        colour: Colour::Rgb(c.0, c.1, c.2),
    };
    for p in &mut fig.panels {
        p.bands = modes
            .slip
            .iter()
            .map(|&i| band(i, "open loop: slip", C_ORANGE))
            .chain(
                modes
                    .stick
                    .iter()
                    .map(|&i| band(i, "open loop: stick", C_GREEN)),
            )
            .collect();
        p.vertical_markers = phases
            .switches
            .iter()
            .map(|(t, l)| (*t, format!("optimum: {l}")))
            .collect();
    }
    Ok(fig)
}

/// Fig. 17: optimal vs open-loop simulated ball angular velocity, one panel per component
/// (both series must have 3 components; the time grids may differ).
pub fn fig_open_loop_vs_optimal(
    title: &str,
    optimal: &TimeSeries,
    open_loop: &TimeSeries,
    phases: &Phases,
) -> Result<PanelFigure, PlotError> {
    optimal.expect_components("optimal ω", 3)?;
    open_loop.expect_components("open-loop ω", 3)?;
    let panels = (0..3)
        .map(|k| {
            let mut p = LineFigure::new("", "t [s]", format!("{} [rad/s]", optimal.names[k]));
            p.series
                .push(Series::new("optimal", optimal.points(k)).styled(fixed(C_BLUE, Dash::Solid)));
            p.series.push(
                Series::new("open-loop simulation", open_loop.points(k))
                    .styled(fixed(C_RED, Dash::Dashed)),
            );
            phases.apply(&mut p);
            p
        })
        .collect();
    Ok(PanelFigure {
        title: title.into(),
        panels,
        layout: Layout::Rows,
        size: None,
    })
}

/// One method of a work–precision diagram: (computing time \[s\], error) per setting.
#[derive(Clone, Debug, PartialEq, Default)]
pub struct WorkPrecision {
    /// Method name (legend).
    pub name: String,
    /// Computing time per run, in the figure's x unit (\[s\] unless the caller relabels the
    /// axis).
    pub time_s: Vec<f64>,
    /// Error per run (same length); non-positive errors are skipped on the log axis.
    pub error: Vec<f64>,
}

/// Work–precision plot: log–log error vs computing time, one marked line per method, sorted
/// by time so each line runs from cheap to expensive.
pub fn fig_work_precision(
    title: &str,
    error_label: &str,
    methods: &[WorkPrecision],
) -> Result<LineFigure, PlotError> {
    let mut fig = LineFigure::new(title, "computing time [s]", error_label);
    fig.x_scale = Scale::Log10;
    fig.y_scale = Scale::Log10;
    for m in methods {
        if m.time_s.len() != m.error.len() {
            return Err(PlotError::Shape {
                what: format!("work-precision '{}'", m.name),
                detail: format!("{} times for {} errors", m.time_s.len(), m.error.len()),
            });
        }
        let mut pts: Vec<(f64, f64)> = m
            .time_s
            .iter()
            .copied()
            .zip(m.error.iter().copied())
            .collect();
        pts.sort_by(|a, b| a.0.total_cmp(&b.0));
        fig.series
            .push(Series::new(m.name.clone(), pts).styled(SeriesStyle {
                markers: true,
                ..SeriesStyle::default()
            }));
    }
    Ok(fig)
}

/// One set of work–precision runs with per-run labels, for [`fig_work_precision_sets`].
#[derive(Clone, Debug, PartialEq, Default)]
pub struct WorkPrecisionSet {
    /// Legend text.
    pub name: String,
    /// Computing time per run, in the figure's x unit (\[s\] unless the caller relabels the
    /// axis).
    pub time_s: Vec<f64>,
    /// Error per run (same length); non-positive errors are skipped on the log axis.
    pub error: Vec<f64>,
    /// Label per run drawn next to its point (e.g. "rtol 1e-8", "Radau 3×12", "ε = 1e-4");
    /// empty: no labels.
    pub labels: Vec<String>,
    /// `true`: the runs form a sequence (a tolerance ladder) and are joined in the order
    /// given, the ladder's: computing times measured on a shared machine need not rise along
    /// it, and a line through them sorted by time would draw that noise as a trend. `false`: unordered or unrelated runs (an ε ladder whose solve times are
    /// not monotone, meshes that landed on different local optima, different kernels), drawn
    /// as markers only.
    pub joined: bool,
}

/// Work–precision plot with labelled points: log–log error vs computing time, one series per
/// set; joined sets in the order of their runs.
pub fn fig_work_precision_sets(
    title: &str,
    error_label: &str,
    sets: &[WorkPrecisionSet],
) -> Result<LineFigure, PlotError> {
    let mut fig = LineFigure::new(title, "computing time [s]", error_label);
    fig.x_scale = Scale::Log10;
    fig.y_scale = Scale::Log10;
    for m in sets {
        if m.time_s.len() != m.error.len()
            || (!m.labels.is_empty() && m.labels.len() != m.time_s.len())
        {
            return Err(PlotError::Shape {
                what: format!("work-precision '{}'", m.name),
                detail: format!(
                    "{} times, {} errors, {} labels",
                    m.time_s.len(),
                    m.error.len(),
                    m.labels.len()
                ),
            });
        }
        let pts: Vec<(f64, f64)> = m
            .time_s
            .iter()
            .copied()
            .zip(m.error.iter().copied())
            .collect();
        let labels: Vec<String> = (0..pts.len())
            .map(|i| m.labels.get(i).cloned().unwrap_or_default())
            .collect();
        let mut s = Series::new(m.name.clone(), pts).styled(SeriesStyle {
            markers: true,
            ..SeriesStyle::default()
        });
        if labels.iter().any(|l| !l.is_empty()) {
            s = s.with_labels(labels);
        }
        if !m.joined {
            s = s.unjoined();
        }
        fig.series.push(s);
    }
    Ok(fig)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn ts(n: usize, comps: usize) -> TimeSeries {
        TimeSeries {
            t: (0..n).map(|i| i as f64).collect(),
            values: (0..comps)
                .map(|k| (0..n).map(|i| (i * k) as f64).collect())
                .collect(),
            names: (0..comps).map(|k| format!("c{k}")).collect(),
        }
    }

    /// The contact-point panel's legend names the quantity its axis plots, and the axis of that
    /// distance starts at 0 (an identically-zero series is not centred on an axis −1…1).
    #[test]
    fn the_contact_distance_panel_is_consistent_and_non_negative() {
        let t = [0.0, 1.0, 2.0];
        let f = fig_distance("d", &t, &[0.3, 0.0, 0.3], &[0.0; 3], &Phases::default()).unwrap();
        let b = &f.panels[1];
        assert!(b.y_non_negative && !f.panels[0].y_non_negative);
        let quantity = b.y_label.trim_end_matches(" [m]");
        assert!(
            b.series[0].name.starts_with(quantity),
            "{} vs {}",
            b.series[0].name,
            b.y_label
        );
    }

    #[test]
    fn shape_errors_are_reported() {
        let mut a = ts(5, 3);
        a.values[1].pop();
        assert!(matches!(
            fig_ball_omega("x", &a, &Phases::default()),
            Err(PlotError::Shape { .. })
        ));
        assert!(matches!(
            fig_ball_omega("x", &ts(5, 2), &Phases::default()),
            Err(PlotError::Shape { .. })
        ));
        assert!(
            fig_contact_forces(
                "f",
                &[0.0, 1.0],
                &[1.0],
                &[1.0, 1.0],
                0.8,
                &Phases::default()
            )
            .is_err()
        );
        assert!(
            fig_contact_forces("f", &[0.0], &[1.0], &[1.0], f64::NAN, &Phases::default()).is_err()
        );
    }

    #[test]
    fn cone_bound_is_mu_times_normal() {
        let f = fig_contact_forces(
            "f",
            &[0.0, 1.0],
            &[2.0, 3.0],
            &[1.0, 1.0],
            0.8,
            &Phases::default(),
        )
        .unwrap();
        assert_eq!(f.series[2].points, vec![(0.0, 1.6), (1.0, 0.8 * 3.0)]);
    }

    #[test]
    fn torque_panels_get_symmetric_limits() {
        let p = fig_torques("τ", &ts(4, 3), Some(1.0), &Phases::default()).unwrap();
        assert_eq!(p.panels.len(), 3);
        for panel in &p.panels {
            let ys: Vec<f64> = panel.hlines.iter().map(|h| h.y).collect();
            assert_eq!(ys, vec![1.0, -1.0]);
        }
    }

    #[test]
    fn work_precision_sorts_by_time() {
        let m = WorkPrecision {
            name: "rk4".into(),
            time_s: vec![3.0, 1.0, 2.0],
            error: vec![1e-9, 1e-3, 1e-6],
        };
        let f = fig_work_precision("wp", "error [-]", &[m]).unwrap();
        assert_eq!(
            f.series[0].points,
            vec![(1.0, 1e-3), (2.0, 1e-6), (3.0, 1e-9)]
        );
    }

    #[test]
    fn contact_zoom_only_for_short_contact() {
        let t: Vec<f64> = (0..=100).map(|i| 0.03 * i as f64).collect();
        let ph = |c: Vec<(f64, f64)>| Phases {
            switches: vec![],
            contact: c,
        };
        // 0.12 s of 3 s: zoomed to the window ± 15 %.
        let z = contact_zoom(&t, &ph(vec![(1.0, 1.12)])).unwrap();
        assert!(
            (z.0 - 0.982).abs() < 1e-12 && (z.1 - 1.138).abs() < 1e-12,
            "{z:?}"
        );
        // Two windows: from the first start to the last end.
        let z = contact_zoom(&t, &ph(vec![(1.0, 1.1), (1.5, 1.6)])).unwrap();
        assert!(
            (z.0 - 0.91).abs() < 1e-12 && (z.1 - 1.69).abs() < 1e-12,
            "{z:?}"
        );
        // 1.2 s of 3 s (40 %): no zoom; none without contact; clamped to the samples.
        assert_eq!(contact_zoom(&t, &ph(vec![(1.0, 2.2)])), None);
        assert_eq!(contact_zoom(&t, &ph(vec![])), None);
        let z = contact_zoom(&t, &ph(vec![(0.0, 0.3)])).unwrap();
        assert_eq!(z.0, 0.0);
    }

    #[test]
    fn work_precision_sets_keep_labels_with_their_runs() {
        let set = |joined| WorkPrecisionSet {
            name: "m".into(),
            time_s: vec![3.0, 1.0, 2.0],
            error: vec![1e-9, 1e-3, 1e-6],
            labels: vec!["c".into(), "a".into(), "b".into()],
            joined,
        };
        // A ladder is joined in its own order, whatever its computing times: times measured
        // on a shared machine need not rise along it, and a line sorted by time would draw
        // their noise as a trend.
        let f = fig_work_precision_sets("wp", "e", &[set(true)]).unwrap();
        assert_eq!(f.series[0].labels, ["c", "a", "b"]);
        assert_eq!(f.series[0].points, [(3.0, 1e-9), (1.0, 1e-3), (2.0, 1e-6)]);
        assert!(f.series[0].joined);
        let f = fig_work_precision_sets("wp", "e", &[set(false)]).unwrap();
        assert_eq!(f.series[0].labels, ["c", "a", "b"]);
        assert!(!f.series[0].joined);
        let mut bad = set(true);
        bad.labels.pop();
        assert!(matches!(
            fig_work_precision_sets("wp", "e", &[bad]),
            Err(PlotError::Shape { .. })
        ));
        assert!(
            fig_ball_omega_ref(
                "o",
                &ts(3, 3),
                &Phases::default(),
                &[("r".into(), f64::NAN)]
            )
            .is_err()
        );
    }

    #[test]
    fn mode_trace_to_intervals() {
        use Mode::*;
        let t = [0.0, 0.1, 0.2, 0.3, 0.4, 0.5];
        let m = SimModes::from_trace(&t, &[Free, Slip, Stick, Stick, Free, Stick]).unwrap();
        assert_eq!(m.slip, vec![(0.1, 0.2)]);
        assert_eq!(m.stick, vec![(0.2, 0.4), (0.5, 0.5)]);
        assert!(SimModes::from_trace(&t, &[Free]).is_err());
        assert_eq!(SimModes::from_trace(&[], &[]).unwrap(), SimModes::default());
    }
}
