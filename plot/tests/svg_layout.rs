//! Layout checks on the produced SVG files, parsed back: tick labels state the value at their
//! position (log and linear axes, compared with the axis mapping of known data points), every
//! data series has a legend entry, texts do not overlap each other (extents estimated from font
//! size and length), the legend covers no data, unordered series are not joined, and
//! coordinates are fractional (no whole-pixel stair steps).

mod common;

use bf_plot::paper::*;
use bf_plot::scene3d::{NamedPath, View, fig_compare_paths};
use bf_plot::*;
use common::{grid, tmp, ts};

/// One SVG element: tag, attributes, text content.
#[derive(Debug, Clone)]
struct El {
    tag: String,
    attrs: Vec<(String, String)>,
    text: String,
}

impl El {
    fn get(&self, k: &str) -> Option<&str> {
        self.attrs
            .iter()
            .find(|(a, _)| a == k)
            .map(|(_, v)| v.as_str())
    }
    fn num(&self, k: &str) -> f64 {
        self.get(k)
            .unwrap_or_else(|| panic!("{k} missing in {self:?}"))
            .parse()
            .unwrap()
    }
    fn class(&self) -> &str {
        self.get("class").unwrap_or("")
    }
}

fn unescape(s: &str) -> String {
    s.replace("&lt;", "<")
        .replace("&gt;", ">")
        .replace("&quot;", "\"")
        .replace("&amp;", "&")
}

/// A minimal parser for the flat SVG the crate writes (one element per line).
fn parse(svg: &str) -> Vec<El> {
    let mut out = Vec::new();
    let mut rest = svg;
    while let Some(i) = rest.find('<') {
        rest = &rest[i + 1..];
        if rest.starts_with('/') {
            continue;
        }
        let end = rest.find('>').unwrap();
        let head = &rest[..end];
        let tag: String = head.chars().take_while(|c| c.is_alphanumeric()).collect();
        let mut attrs = Vec::new();
        let mut h = &head[tag.len()..];
        while let Some(eq) = h.find("=\"") {
            let key = h[..eq].trim().to_string();
            let v0 = eq + 2;
            let v1 = v0 + h[v0..].find('"').unwrap();
            attrs.push((key, unescape(&h[v0..v1])));
            h = &h[v1 + 1..];
        }
        let mut text = String::new();
        if tag == "text" {
            let close = rest.find("</text>").unwrap();
            text = unescape(&rest[end + 1..close]);
        }
        rest = &rest[end + 1..];
        out.push(El { tag, attrs, text });
    }
    out
}

fn read(p: &std::path::Path) -> Vec<El> {
    parse(&std::fs::read_to_string(p).unwrap())
}

/// Axes of a panel: pixel rectangle, ranges in plotting coordinates, scales.
#[derive(Debug, Clone, Copy)]
struct Axes {
    x0: f64,
    y0: f64,
    x1: f64,
    y1: f64,
    xr: (f64, f64),
    yr: (f64, f64),
    xlog: bool,
    ylog: bool,
}

impl Axes {
    fn px(&self, x: f64) -> f64 {
        let v = if self.xlog { libm::log10(x) } else { x };
        self.x0 + (v - self.xr.0) / (self.xr.1 - self.xr.0) * (self.x1 - self.x0)
    }
    fn py(&self, y: f64) -> f64 {
        let v = if self.ylog { libm::log10(y) } else { y };
        self.y1 - (v - self.yr.0) / (self.yr.1 - self.yr.0) * (self.y1 - self.y0)
    }
}

fn axes(els: &[El]) -> Vec<Axes> {
    els.iter()
        .filter(|e| e.class() == "axes")
        .map(|e| {
            let f = |k: &str| -> Vec<f64> {
                e.get(k)
                    .unwrap()
                    .split_whitespace()
                    .map(|v| v.parse().unwrap())
                    .collect()
            };
            let (p, xr, yr) = (f("data-plot"), f("data-xr"), f("data-yr"));
            Axes {
                x0: p[0],
                y0: p[1],
                x1: p[2],
                y1: p[3],
                xr: (xr[0], xr[1]),
                yr: (yr[0], yr[1]),
                xlog: e.get("data-xscale") == Some("log10"),
                ylog: e.get("data-yscale") == Some("log10"),
            }
        })
        .collect()
}

/// Circles of a given fill colour (data markers).
fn markers(els: &[El], fill: &str) -> Vec<(f64, f64)> {
    els.iter()
        .filter(|e| e.tag == "circle" && e.class() == "marker" && e.get("fill") == Some(fill))
        .map(|e| (e.num("cx"), e.num("cy")))
        .collect()
}

/// Checks that the axes mapping agrees with known data points (marker centres), then that
/// every tick label sits at the pixel of the value it states. Returns the number of labels.
fn check_ticks(els: &[El], ax: &Axes, known: &[(f64, f64)], fill: &str) -> usize {
    let m = markers(els, fill);
    for &(x, y) in known {
        let (px, py) = (ax.px(x), ax.py(y));
        assert!(
            m.iter()
                .any(|&(a, b)| (a - px).abs() < 0.02 && (b - py).abs() < 0.02),
            "no marker at ({x}, {y}) → ({px}, {py}); markers {m:?}"
        );
    }
    let mut n = 0;
    for e in els.iter().filter(|e| e.tag == "text") {
        let inside_x = e.num("x") >= ax.x0 - 1.0 && e.num("x") <= ax.x1 + 1.0;
        let inside_y = e.num("y") >= ax.y0 - 10.0 && e.num("y") <= ax.y1 + 10.0;
        match e.class() {
            "tick-x" if inside_x && e.num("y") > ax.y1 && e.num("y") < ax.y1 + 40.0 => {
                let v: f64 = e.text.parse().unwrap();
                assert!(
                    (ax.px(v) - e.num("x")).abs() < 0.02,
                    "x label {} at {} but value maps to {}",
                    e.text,
                    e.num("x"),
                    ax.px(v)
                );
                n += 1;
            }
            "tick-y" if inside_y && e.num("x") < ax.x0 && e.num("x") > ax.x0 - 20.0 => {
                let v: f64 = e.text.parse().unwrap();
                // Baseline half a capital height below the label's middle (DejaVu Sans:
                // capitals 1493/2048 em high).
                let mid = e.num("y") - CAP_HALF * e.num("font-size");
                assert!(
                    (ax.py(v) - mid).abs() < 0.02,
                    "y label {} at {mid} but value maps to {}",
                    e.text,
                    ax.py(v)
                );
                n += 1;
            }
            _ => {}
        }
    }
    n
}

fn st(c: (u8, u8, u8)) -> SeriesStyle {
    SeriesStyle {
        colour: Colour::Rgb(c.0, c.1, c.2),
        markers: true,
        ..SeriesStyle::default()
    }
}

#[test]
fn log_tick_labels_match_positions() {
    let d = tmp("log");
    // The sa_kernels situation: times between 1e-7 and 1e-6 s, where "2e-7" must sit at 2e-7.
    for (i, (xr, yr)) in [
        ((1.2e-7, 9.0e-7), (1e-16, 3e-13)),
        ((3e-4, 40.0), (2.2e-9, 2.8e-9)),
        ((1e-9, 1e3), (0.5, 7.0)),
    ]
    .into_iter()
    .enumerate()
    {
        let mut f = LineFigure::new("log ticks", "time [s]", "error [-]");
        f.x_scale = Scale::Log10;
        f.y_scale = Scale::Log10;
        f.x_range = Some(xr);
        f.y_range = Some(yr);
        let known = vec![
            (xr.0 * 1.3, yr.0 * 1.1),
            ((xr.0 * xr.1).sqrt(), (yr.0 * yr.1).sqrt()),
        ];
        f.series
            .push(Series::new("runs", known.clone()).styled(st((200, 0, 100))));
        let p = render(&f, d.join(format!("log{i}"))).unwrap();
        let els = read(&p[0]);
        let ax = axes(&els)[0];
        assert!(
            (ax.xr.0 - libm::log10(xr.0)).abs() < 1e-12
                && (ax.yr.1 - libm::log10(yr.1)).abs() < 1e-12
        );
        let n = check_ticks(&els, &ax, &known, "#C80064");
        assert!(n >= 5, "case {i}: only {n} labelled ticks");
        let labels: Vec<&str> = els
            .iter()
            .filter(|e| e.class() == "tick-x")
            .map(|e| e.text.as_str())
            .collect();
        if i == 0 {
            assert_eq!(
                labels,
                [
                    "2e-7", "3e-7", "4e-7", "5e-7", "6e-7", "7e-7", "8e-7", "9e-7"
                ]
            );
        }
        // Minor ticks: more tick marks than labels on the 5-decade x axis.
        if i == 1 {
            let marks = els
                .iter()
                .filter(|e| {
                    e.class() == "tick" && {
                        let x: f64 = e
                            .get("points")
                            .unwrap()
                            .split(',')
                            .next()
                            .unwrap()
                            .parse()
                            .unwrap();
                        x >= ax.x0 - 1.0 && x <= ax.x1 + 1.0
                    }
                })
                .count();
            assert!(marks > labels.len());
        }
    }
}

#[test]
fn linear_tick_labels_match_positions() {
    let d = tmp("lin");
    for (i, (x0, x1, y0, y1)) in [
        (0.0, 2.5, -0.153, 0.149),
        (-3e-5, 7e-5, 1e6, 3.5e6),
        (0.77, 0.81, -2.0, 9.0),
    ]
    .into_iter()
    .enumerate()
    {
        let mut f = LineFigure::new("linear ticks", "t [s]", "y [-]");
        let known = vec![
            (x0, y0),
            (0.3 * x0 + 0.7 * x1, 0.6 * y0 + 0.4 * y1),
            (x1, y1),
        ];
        f.series
            .push(Series::new("data", known.clone()).styled(st((0, 120, 60))));
        let p = render(&f, d.join(format!("lin{i}"))).unwrap();
        let els = read(&p[0]);
        let ax = axes(&els)[0];
        let n = check_ticks(&els, &ax, &known, "#00783C");
        assert!(n >= 6, "case {i}: only {n} labelled ticks");
    }
}

/// An x axis of counts (`x_whole`: periods 1, 2, 3) has ticks at whole numbers only, where
/// the 1-2-5 ticks of the same range would put some at halves.
#[test]
fn an_axis_of_counts_has_whole_ticks() {
    let d = tmp("whole");
    let x_labels = |whole: bool, name: &str, known: &[(f64, f64)]| -> Vec<String> {
        let mut f = LineFigure::new("counts", "period", "e [%]");
        f.x_whole = whole;
        f.series
            .push(Series::new("data", known.to_vec()).styled(st((0, 120, 60))));
        let p = render(&f, d.join(name)).unwrap();
        let els = read(&p[0]);
        let ax = axes(&els)[0];
        check_ticks(&els, &ax, known, "#00783C");
        els.iter()
            .filter(|e| e.class() == "tick-x")
            .map(|e| e.text.clone())
            .collect()
    };
    let known = [(1.0, 1.0), (2.0, 3.0), (3.0, 2.0)];
    let halves = x_labels(false, "halves", &known);
    assert!(halves.iter().any(|l| l == "1.5"), "{halves:?}");
    assert_eq!(x_labels(true, "whole", &known), ["1", "2", "3"]);
    // A range without a whole number keeps its ticks rather than losing them all.
    let inside = x_labels(true, "inside", &[(1.2, 1.0), (1.8, 2.0)]);
    assert!(inside.len() >= 2, "{inside:?}");
}

/// Half the capital height of DejaVu Sans in em (1493 of 2048 units): the layout centres texts
/// on their capitals.
const CAP_HALF: f64 = 0.5 * 1493.0 / 2048.0;

/// Estimated text box: 0.55 em per character, 1 em high, from the anchor and baseline.
fn text_box(e: &El) -> (f64, f64, f64, f64) {
    let size = e.num("font-size");
    let w = 0.55 * size * e.text.chars().count() as f64;
    let (x, base) = (e.num("x"), e.num("y"));
    if e.get("transform").is_some() {
        // Rotated by −90° about (x, base): vertical extent w, horizontal 1 em left of x.
        return (x - size, base - 0.5 * w, x, base + 0.5 * w);
    }
    let x0 = match e.get("text-anchor") {
        Some("middle") => x - 0.5 * w,
        Some("end") => x - w,
        _ => x,
    };
    let mid = base - CAP_HALF * size;
    (x0, mid - 0.5 * size, x0 + w, mid + 0.5 * size)
}

fn overlap(a: (f64, f64, f64, f64), b: (f64, f64, f64, f64)) -> bool {
    a.0 < b.2 - 0.5 && b.0 < a.2 - 0.5 && a.1 < b.3 - 0.5 && b.1 < a.3 - 0.5
}

fn assert_no_text_overlap(els: &[El], what: &str) {
    let texts: Vec<&El> = els.iter().filter(|e| e.tag == "text").collect();
    for (i, a) in texts.iter().enumerate() {
        for b in &texts[i + 1..] {
            assert!(
                !overlap(text_box(a), text_box(b)),
                "{what}: texts '{}' ({}) and '{}' ({}) overlap: {:?} {:?}",
                a.text,
                a.class(),
                b.text,
                b.class(),
                text_box(a),
                text_box(b)
            );
        }
    }
}

fn polyline_points(e: &El) -> Vec<(f64, f64)> {
    e.get("points")
        .unwrap()
        .split_whitespace()
        .map(|p| {
            let (a, b) = p.split_once(',').unwrap();
            (a.parse().unwrap(), b.parse().unwrap())
        })
        .collect()
}

/// No data line (sampled every pixel), data marker or reference line inside a legend box.
fn assert_legend_clear_of_data(els: &[El], what: &str) {
    let boxes: Vec<(f64, f64, f64, f64)> = els
        .iter()
        .filter(|e| e.class() == "legend-box")
        .map(|e| {
            let (x, y) = (e.num("x"), e.num("y"));
            (x, y, x + e.num("width"), y + e.num("height"))
        })
        .collect();
    assert!(!boxes.is_empty(), "{what}: no legend");
    let inside = |b: &(f64, f64, f64, f64), (x, y): (f64, f64)| {
        x > b.0 + 1.0 && x < b.2 - 1.0 && y > b.1 + 1.0 && y < b.3 - 1.0
    };
    for e in els {
        let pts: Vec<(f64, f64)> = match (e.tag.as_str(), e.class()) {
            ("polyline", "series" | "hline") => {
                let p = polyline_points(e);
                let mut s = Vec::new();
                for w in p.windows(2) {
                    let n = (libm::hypot(w[1].0 - w[0].0, w[1].1 - w[0].1))
                        .ceil()
                        .max(1.0) as usize;
                    for k in 0..=n {
                        let f = k as f64 / n as f64;
                        s.push((
                            w[0].0 + f * (w[1].0 - w[0].0),
                            w[0].1 + f * (w[1].1 - w[0].1),
                        ));
                    }
                }
                s
            }
            ("circle", "marker") => vec![(e.num("cx"), e.num("cy"))],
            ("text", "point-label") => {
                let b = text_box(e);
                vec![(b.0, b.1), (b.2, b.3), (b.0, b.3), (b.2, b.1)]
            }
            _ => continue,
        };
        for b in &boxes {
            if let Some(p) = pts.iter().find(|p| inside(b, **p)) {
                panic!(
                    "{what}: {} ({}) at {p:?} under the legend {b:?}",
                    e.tag,
                    e.class()
                );
            }
        }
    }
}

fn legend_texts(els: &[El]) -> Vec<String> {
    els.iter()
        .filter(|e| e.class() == "legend")
        .map(|e| e.text.clone())
        .collect()
}

fn assert_fractional(els: &[El], what: &str) {
    let mut all = 0usize;
    let mut frac = 0usize;
    for e in els.iter().filter(|e| e.class() == "series") {
        for (x, y) in polyline_points(e) {
            for v in [x, y] {
                all += 1;
                if (v - v.round()).abs() > 1e-9 {
                    frac += 1;
                }
            }
        }
    }
    assert!(all > 0, "{what}: no data polyline");
    assert!(
        frac * 2 > all,
        "{what}: only {frac} of {all} coordinates fractional"
    );
}

#[test]
fn crowded_figures_have_legends_and_no_overlaps() {
    let d = tmp("crowd");
    let t = grid(600, 3.0);
    // Close switching times: their labels must be staggered.
    let phases = Phases {
        switches: vec![
            (1.0, "impact".into()),
            (1.03, "lift-off".into()),
            (1.06, "impact".into()),
            (2.9, "lift-off".into()),
        ],
        contact: vec![(1.0, 1.03), (1.06, 2.9)],
    };
    // Data filling every corner: the legend needs head room.
    let omega = ts(
        &t,
        &[&|x| libm::sin(9.0 * x), &|x| libm::cos(9.0 * x), &|x| {
            0.8 * libm::sin(5.0 * x)
        }],
        &["ω_x", "ω_y", "ω_z"],
    );
    let f = fig_ball_omega_ref(
        "Fig. 13 counterpart: ω",
        &omega,
        &phases,
        &[("ω_ref,z".into(), 0.5)],
    )
    .unwrap();
    let p = render(&f, d.join("omega")).unwrap();
    let els = read(&p[0]);
    assert_no_text_overlap(&els, "omega");
    assert_legend_clear_of_data(&els, "omega");
    assert_fractional(&els, "omega");
    let leg = legend_texts(&els);
    for n in ["ω_x", "ω_y", "ω_z", "ω_ref,z = 0.5 rad/s", "contact"] {
        assert_eq!(leg.iter().filter(|l| *l == n).count(), 1, "{n} in {leg:?}");
    }
    // Three of the four switching-time labels are within 0.06 s: at least two rows.
    let rows: std::collections::BTreeSet<i64> = els
        .iter()
        .filter(|e| e.class() == "marker-label")
        .map(|e| e.num("y").round() as i64)
        .collect();
    assert!(rows.len() >= 2, "{rows:?}");

    // Torques of ≤ 0.15 N m with a 1 N m limit: the axis fits the data.
    let tau = ts(
        &t,
        &[&|x| 0.15 * libm::sin(x), &|x| -0.1 * libm::cos(x), &|x| {
            0.9 * (x - 1.5)
        }],
        &["τ1", "τ2", "τ3"],
    );
    let f = fig_torques("Fig. 8 counterpart: torques", &tau, Some(1.0), &phases).unwrap();
    let p = render_panels(&f, d.join("tau")).unwrap();
    let els = read(&p[0]);
    let ax = axes(&els);
    assert_eq!(ax.len(), 3);
    // Fitted to ±0.15 (plus head room for the legend), not stretched to ±1.
    assert!(ax[0].yr.1 < 0.6 && ax[0].yr.0 > -0.2, "{:?}", ax[0].yr);
    assert!(ax[2].yr.1 >= 1.0 && ax[2].yr.0 <= -1.0, "{:?}", ax[2].yr);
    let leg = legend_texts(&els);
    assert!(
        leg.contains(&"torque limit ±1 N m (off scale)".to_string()),
        "{leg:?}"
    );
    assert!(leg.contains(&"torque limit ±1 N m".to_string()), "{leg:?}");
    assert_eq!(
        els.iter().filter(|e| e.class() == "hline").count(),
        2,
        "limit lines drawn only in the third panel"
    );
    for n in ["τ1", "τ2", "τ3"] {
        assert!(leg.contains(&n.to_string()));
    }
    assert_no_text_overlap(&els, "torques");
    assert_legend_clear_of_data(&els, "torques");
}

#[test]
fn work_precision_sets_label_points_and_do_not_join_unordered_runs() {
    let d = tmp("wp");
    let eps = WorkPrecisionSet {
        name: "smooth sat, ε ladder".into(),
        // Solve times not monotone in ε: joining in any order would suggest a trend.
        time_s: vec![0.9, 0.35, 1.4, 0.5, 0.52],
        error: vec![1e-3, 1e-4, 1e-5, 1e-6, 1.1e-6],
        labels: ["1e-2", "1e-3", "1e-4", "1e-5", "1e-6"]
            .iter()
            .map(|e| format!("ε = {e}"))
            .collect(),
        joined: false,
    };
    let rtol = WorkPrecisionSet {
        name: "DOPRI5".into(),
        time_s: vec![0.05, 0.1, 0.2, 0.4],
        error: vec![1e-4, 1e-6, 1e-8, 1e-10],
        labels: ["1e-4", "1e-6", "1e-8", "1e-10"]
            .iter()
            .map(|e| format!("rtol {e}"))
            .collect(),
        joined: true,
    };
    let f = fig_work_precision_sets("labelled runs", "error [m]", &[eps, rtol]).unwrap();
    let p = render(&f, d.join("wp")).unwrap();
    let els = read(&p[0]);
    let ax = axes(&els)[0];
    assert!(ax.xlog && ax.ylog);
    let c0 = {
        let (r, g, b) = bf_plot::figure::palette(0);
        format!("#{r:02X}{g:02X}{b:02X}")
    };
    let c1 = {
        let (r, g, b) = bf_plot::figure::palette(1);
        format!("#{r:02X}{g:02X}{b:02X}")
    };
    let joined = |c: &str| {
        els.iter()
            .filter(|e| e.class() == "series" && e.get("stroke") == Some(c))
            .count()
    };
    assert_eq!(joined(&c0), 0, "the ε ladder is joined");
    assert_eq!(joined(&c1), 1, "the rtol ladder is not one line");
    assert_eq!(markers(&els, &c0).len(), 5);
    let n = check_ticks(&els, &ax, &[(0.9, 1e-3), (0.5, 1e-6)], &c0);
    assert!(n >= 4);
    let labels: Vec<&El> = els.iter().filter(|e| e.class() == "point-label").collect();
    assert_eq!(labels.len(), 9);
    // Each label is next to its own point (within 30 px of the marker).
    for (i, l) in ["ε = 1e-2", "ε = 1e-5", "rtol 1e-8"].iter().enumerate() {
        let (x, y) = [(0.9, 1e-3), (0.5, 1e-6), (0.2, 1e-8)][i];
        let e = labels.iter().find(|e| e.text == *l).unwrap();
        let b = text_box(e);
        let (px, py) = (ax.px(x), ax.py(y));
        let dx = (b.0 - px).max(px - b.2).max(0.0);
        let dy = (b.1 - py).max(py - b.3).max(0.0);
        assert!(libm::hypot(dx, dy) < 30.0, "{l} far from its point");
    }
    assert_no_text_overlap(&els, "wp");
    assert_legend_clear_of_data(&els, "wp");
    let leg = legend_texts(&els);
    assert_eq!(leg, ["smooth sat, ε ladder", "DOPRI5"]);
}

#[test]
fn contact_forces_zoom_and_fig17_modes() {
    let d = tmp("forces");
    let t = grid(3000, 3.0);
    let ph = Phases {
        switches: vec![(1.0, "impact".into()), (1.12, "lift-off".into())],
        contact: vec![(1.0, 1.12)],
    };
    let ln: Vec<f64> = t
        .iter()
        .map(|&x| if (1.0..=1.12).contains(&x) { 5.0 } else { 0.0 })
        .collect();
    let lt: Vec<f64> = ln.iter().map(|v| 0.7 * v).collect();
    let f = fig_contact_forces("Fig. 9 counterpart", &t, &ln, &lt, 0.8, &ph).unwrap();
    let (a, b) = f.x_range.expect("a 0.12 s contact in 3 s is zoomed");
    assert!(a < 1.0 && a > 0.9 && b > 1.12 && b < 1.22, "{a} {b}");
    // The cone bound is drawn in contact only (zero outside is not a bound).
    assert!(
        f.series[2]
            .points
            .iter()
            .all(|&(x, y)| (1.0..=1.12).contains(&x) || y.is_nan())
    );
    let p = render(&f, d.join("forces")).unwrap();
    let els = read(&p[0]);
    assert_no_text_overlap(&els, "forces");
    assert_legend_clear_of_data(&els, "forces");

    let omega = ts(&t, &[&|x| x, &|x| -x, &|x| 0.1 * x], &["ω_x", "ω_y", "ω_z"]);
    let ol = ts(
        &t,
        &[&|x| 1.1 * x, &|x| -0.9 * x, &|x| 0.12 * x],
        &["ω_x", "ω_y", "ω_z"],
    );
    let modes = SimModes {
        slip: vec![(1.0, 1.01)],
        stick: vec![(1.01, 1.12)],
    };
    let f =
        fig_open_loop_vs_optimal_modes("Fig. 17 counterpart", &omega, &ol, &ph, &modes).unwrap();
    let p = render_panels(&f, d.join("fig17")).unwrap();
    let els = read(&p[0]);
    let leg = legend_texts(&els);
    for n in [
        "optimal",
        "open-loop simulation",
        "open loop: slip",
        "open loop: stick",
    ] {
        assert_eq!(leg.iter().filter(|l| *l == n).count(), 3, "{n}: {leg:?}");
    }
    let bands: Vec<&str> = els
        .iter()
        .filter(|e| e.class() == "band")
        .filter_map(|e| e.get("fill"))
        .collect();
    assert!(
        bands.contains(&"#FF7F0E") && bands.contains(&"#2CA02C"),
        "{bands:?}"
    );
    assert!(els.iter().any(|e| e.text == "optimum: impact"));
    assert_no_text_overlap(&els, "fig17");
    assert_legend_clear_of_data(&els, "fig17");
}

#[test]
fn fig11_compares_paths_with_a_legend_entry_each() {
    let d = tmp("fig11");
    let arc = |r: f64, z: f64| -> Vec<[f64; 3]> {
        (0..80)
            .map(|k| {
                let a = 0.02 * k as f64;
                [r * libm::cos(a), r * libm::sin(a), z]
            })
            .collect()
    };
    let paths = [
        NamedPath {
            name: "robotic finger: closest point".into(),
            points: arc(1.05, 0.3),
        },
        NamedPath {
            name: "human finger: closest point".into(),
            points: arc(1.1, 0.5),
        },
    ];
    let f = fig_compare_paths(
        "Fig. 11 counterpart: closest-point paths",
        [0.0; 3],
        1.0,
        &paths,
        &[View::FrontXZ, View::TopXY, View::Iso],
    )
    .unwrap();
    let p = render_panels(&f, d.join("fig11")).unwrap();
    let els = read(&p[0]);
    let leg = legend_texts(&els);
    for n in [
        "ball",
        "robotic finger: closest point",
        "human finger: closest point",
    ] {
        assert_eq!(leg.iter().filter(|l| *l == n).count(), 3, "{n}: {leg:?}");
    }
    assert_no_text_overlap(&els, "fig11");
    assert_legend_clear_of_data(&els, "fig11");
    assert!(matches!(
        fig_compare_paths("x", [0.0; 3], 1.0, &[], &[View::Iso]),
        Err(PlotError::NoSeries(_))
    ));
}

#[test]
fn random_figures_keep_texts_apart_and_legends_off_the_data() {
    use rand::{Rng, SeedableRng};
    let d = tmp("random");
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(5);
    for case in 0..12 {
        let mut f = LineFigure::new(format!("random figure {case}"), "t [s]", "y [-]");
        let log = case % 3 == 2;
        if log {
            f.x_scale = Scale::Log10;
            f.y_scale = Scale::Log10;
        }
        for k in 0..rng.random_range(1..5) {
            let n = rng.random_range(3..60);
            let (a, b, c) = (
                rng.random_range(0.5..3.0),
                rng.random_range(-2.0..2.0),
                rng.random_range(0.1..10.0),
            );
            let pts: Vec<(f64, f64)> = (0..n)
                .map(|i| {
                    let t = 0.1 + 3.0 * i as f64 / n as f64;
                    let y = c * libm::sin(a * t + b);
                    if log {
                        (
                            libm::pow(10f64, t - 2.0),
                            libm::pow(10f64, y.abs().min(8.0) - 6.0),
                        )
                    } else {
                        (t, y)
                    }
                })
                .collect();
            let mut s = Series::new(format!("series {k}"), pts);
            if k % 2 == 1 {
                let labels = (0..n)
                    .map(|i| {
                        if i % (n / 4).max(1) == 0 {
                            format!("run {i}")
                        } else {
                            String::new()
                        }
                    })
                    .collect();
                s = s.with_labels(labels).unjoined();
            }
            f.series.push(s);
        }
        if !log {
            for m in 0..rng.random_range(0..5) {
                let t = rng.random_range(0.2..3.0);
                f.vertical_markers.push((
                    t,
                    if m % 2 == 0 {
                        "impact".into()
                    } else {
                        "lift-off".into()
                    },
                ));
            }
        }
        let p = render(&f, d.join(format!("r{case}"))).unwrap();
        let els = read(&p[0]);
        assert_no_text_overlap(&els, &format!("case {case}"));
        assert_legend_clear_of_data(&els, &format!("case {case}"));
        let leg = legend_texts(&els);
        for s in &f.series {
            assert!(
                leg.contains(&s.name),
                "case {case}: {} not in the legend",
                s.name
            );
        }
        assert_fractional(&els, &format!("case {case}"));
    }
}

#[test]
fn many_switching_times_keep_three_label_rows_and_every_line() {
    let d = tmp("many");
    let mut f = LineFigure::new("ten periods", "t [s]", "ω [rad/s]");
    f.series.push(Series::new(
        "ω_x",
        (0..500)
            .map(|i| (0.02 * i as f64, libm::sin(0.1 * i as f64)))
            .collect(),
    ));
    for p in 0..10 {
        for (dt, l) in [(0.0, "impact"), (0.12, "lift-off"), (0.6, "t_f")] {
            f.vertical_markers
                .push((p as f64 + dt, format!("optimum: {l}")));
        }
    }
    let p = render(&f, d.join("many")).unwrap();
    let els = read(&p[0]);
    assert_eq!(els.iter().filter(|e| e.class() == "vmarker").count(), 30);
    let rows: std::collections::BTreeSet<i64> = els
        .iter()
        .filter(|e| e.class() == "marker-label")
        .map(|e| e.num("y").round() as i64)
        .collect();
    assert!((2..=3).contains(&rows.len()), "{rows:?}");
    assert!(els.iter().filter(|e| e.class() == "marker-label").count() >= 10);
    assert_no_text_overlap(&els, "many markers");
}

#[test]
fn torque_and_force_axes_include_zero_in_every_panel() {
    let d = tmp("zero");
    let t = grid(300, 9.6);
    // τ1 varies by ±3 % about 0.3 N m: without zero on the axis it would fill the panel.
    let tau = ts(
        &t,
        &[
            &|x| 0.3 + 0.01 * libm::sin(x),
            &|x| -0.5 - 0.1 * libm::cos(x),
            &|x| 0.2 * libm::sin(x),
        ],
        &["τ1", "τ2", "τ3"],
    );
    let ph = Phases::default();
    let f = fig_torques("torques", &tau, Some(1.0), &ph).unwrap();
    let p = render_panels(&f, d.join("tau")).unwrap();
    let ax = axes(&read(&p[0]));
    assert_eq!(ax.len(), 3);
    for a in &ax {
        assert!(a.yr.0 <= 0.0 && a.yr.1 >= 0.0, "{:?}", a.yr);
    }
    // τ1's ±0.01 N m variation takes under a tenth of its axis: shown against its value.
    assert!(0.02 / (ax[0].yr.1 - ax[0].yr.0) < 0.1);
    let ln: Vec<f64> = t.iter().map(|&x| 5.0 + 0.1 * x).collect();
    let lt: Vec<f64> = ln.iter().map(|v| 0.5 * v).collect();
    let f = fig_contact_forces("forces", &t, &ln, &lt, 0.8, &ph).unwrap();
    let p = render(&f, d.join("forces")).unwrap();
    let a = axes(&read(&p[0]))[0];
    assert!(a.yr.0 <= 0.0 && a.yr.1 >= 5.96, "{:?}", a.yr);
    // Other figures still fit their data (ω about 2.2 rad/s keeps its own range).
    let omega = ts(
        &t,
        &[&|x| 2.2 + 0.01 * x, &|_| 2.1, &|_| 2.3],
        &["ω_x", "ω_y", "ω_z"],
    );
    let p = render(&fig_ball_omega("ω", &omega, &ph).unwrap(), d.join("omega")).unwrap();
    let a = axes(&read(&p[0]))[0];
    assert!(a.yr.0 > 2.0, "{:?}", a.yr);
}

#[test]
fn contact_bands_are_visible_or_not_listed() {
    let d = tmp("bands");
    let t = grid(1000, 10.0);
    let omega = ts(&t, &[&|x| x, &|x| -x, &|x| 0.5 * x], &["ω_x", "ω_y", "ω_z"]);
    // A 0.01 s stick phase in a 10 s period: 0.8 px of axis, drawn at least MIN_BAND_PX wide.
    let short = Phases {
        switches: vec![(4.0, "impact".into()), (4.01, "lift-off".into())],
        contact: vec![(4.0, 4.01)],
    };
    let p = render(
        &fig_ball_omega("ω", &omega, &short).unwrap(),
        d.join("short"),
    )
    .unwrap();
    let els = read(&p[0]);
    let bands: Vec<&El> = els.iter().filter(|e| e.class() == "band").collect();
    assert_eq!(bands.len(), 1);
    assert!(
        bands[0].num("width") >= MIN_BAND_PX - 1e-9,
        "{:?}",
        bands[0]
    );
    let ax = axes(&els)[0];
    let mid = bands[0].num("x") + 0.5 * bands[0].num("width");
    assert!(
        (mid - ax.px(4.005)).abs() < 0.02,
        "{mid} vs {}",
        ax.px(4.005)
    );
    assert!(legend_texts(&els).iter().any(|l| l == "contact"));
    // Widened, it is filled more strongly than a band of its own width, which would not show
    // between the dashed switch markers.
    let wide = Phases {
        switches: vec![(4.0, "impact".into()), (6.0, "lift-off".into())],
        contact: vec![(4.0, 6.0)],
    };
    let pw = render(&fig_ball_omega("ω", &omega, &wide).unwrap(), d.join("wide")).unwrap();
    let wide_els = read(&pw[0]);
    let wide_band = wide_els.iter().find(|e| e.class() == "band").unwrap();
    assert!(wide_band.num("width") > 10.0 * MIN_BAND_PX);
    assert!(bands[0].num("fill-opacity") >= 2.0 * wide_band.num("fill-opacity"));
    // A contact interval outside the x range is not drawn and not listed.
    let mut f = fig_ball_omega("ω", &omega, &short).unwrap();
    f.x_range = Some((5.0, 10.0));
    let p = render(&f, d.join("outside")).unwrap();
    let els = read(&p[0]);
    assert!(els.iter().all(|e| e.class() != "band"));
    assert!(!legend_texts(&els).iter().any(|l| l == "contact"));
}

/// The paper's Fig. 17 counterpart: five legend entries, two of them long, over three short
/// panels whose optimum jumps near the left edge to 2.5 times the start of the other runs.
/// Head room above the data cannot hold such a legend (the mapping gives at most 60 % of an
/// axes' height), so it goes beside the axes, clear of every line.
#[test]
fn a_tall_legend_over_short_panels_stays_off_the_data() {
    let d = tmp("fig17-tall");
    let t = grid(3000, 11.6);
    let ph = Phases {
        switches: vec![
            (2.07, "impact".into()),
            (5.93, "impact".into()),
            (9.79, "impact".into()),
        ],
        contact: vec![],
    };
    // The optimum's ω jumps at every impact (every 3.86 s from 2.07 s) and decays in flight.
    let jump = |x: f64, a: f64, b: f64| {
        if x < 2.07 {
            a * libm::exp(-0.5 * x)
        } else {
            b * libm::exp(-0.5 * ((x - 2.07) % 3.86))
        }
    };
    let optimal = ts(
        &t,
        &[&|x| jump(x, 0.3, 0.77), &|x| jump(x, -0.4, -1.0), &|x| {
            jump(x, 0.035, 0.14)
        }],
        &["ω_x", "ω_y", "ω_z"],
    );
    let open = ts(
        &t,
        &[
            &|x| 0.3 * libm::exp(-0.4 * x),
            &|x| -0.4 * libm::exp(-0.4 * x),
            &|x| 0.035 * libm::exp(-0.4 * x),
        ],
        &["ω_x", "ω_y", "ω_z"],
    );
    let modes = SimModes {
        slip: vec![(2.07, 2.12), (9.7, 9.8)],
        stick: vec![],
    };
    let mut f = fig_open_loop_vs_optimal_modes("Fig. 17 counterpart", &optimal, &open, &ph, &modes)
        .unwrap();
    for (k, name) in [
        "PD 1/0.2, free phases",
        "PD 1/0.2, always (bounces off: no contact phase)",
    ]
    .iter()
    .enumerate()
    {
        let s = 1.0 + 0.05 * k as f64;
        for (j, panel) in f.panels.iter_mut().enumerate() {
            let pts = open
                .points(j)
                .into_iter()
                .map(|(x, y)| (x, s * y))
                .collect();
            panel.series.push(Series::new(name.to_string(), pts));
        }
    }
    let p = render_panels(&f, d.join("fig17")).unwrap();
    let els = read(&p[0]);
    assert_no_text_overlap(&els, "fig17 tall");
    assert_legend_clear_of_data(&els, "fig17 tall");
}

/// A series drawn over an earlier one with the same points hides it; its legend entry names
/// the hidden one, and a series that differs in one point keeps its plain name.
#[test]
fn a_series_that_hides_another_says_so_in_the_legend() {
    let d = tmp("same-points");
    let pts: Vec<(f64, f64)> = (0..50)
        .map(|i| (i as f64, libm::sin(i as f64 * 0.3)))
        .collect();
    let mut f = LineFigure::new("same points", "t [s]", "y [-]");
    f.series.push(Series::new("hybrid", pts.clone()));
    f.series.push(Series::new("hybrid-unbounded", pts.clone()));
    let mut moved = pts;
    moved[10].1 += 0.5;
    f.series.push(Series::new("pd", moved));
    let p = render(&f, d.join("same")).unwrap();
    let leg = legend_texts(&read(&p[0]));
    assert!(leg.contains(&"hybrid".to_string()), "{leg:?}");
    assert!(
        leg.contains(&"hybrid-unbounded (the same points as hybrid)".to_string()),
        "{leg:?}"
    );
    assert!(leg.contains(&"pd".to_string()), "{leg:?}");
}
