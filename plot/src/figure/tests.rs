//! Unit tests of the figure internals (ranges, clipping, stroke splitting, labels).

use super::clip::*;
use super::layout::*;
use super::prepare::*;
use super::*;
use crate::canvas::{Polyline, split_sharp_turns};

#[test]
fn widen_handles_degenerate_ranges() {
    assert_eq!(widen((0.0, 0.0), 0.05), (-1.0, 1.0));
    let (a, b) = widen((2.0, 2.0), 0.05);
    assert!(a < 2.0 && b > 2.0);
    let (a, b) = widen((0.0, 10.0), 0.1);
    assert!((a + 1.0).abs() < 1e-12 && (b - 11.0).abs() < 1e-12);
}

/// A quantity that cannot be negative gets a [0, …] axis: [0, 1] when it is identically 0
/// (not −1…1), and no tick below 0 otherwise; only a sliver of the range lies below 0, so
/// that a line at 0 is drawn off the frame; without the flag nothing changes.
#[test]
fn non_negative_axes_start_at_zero() {
    let mut f = LineFigure::new("t", "t [s]", "d [m]");
    f.series
        .push(Series::new("d", vec![(0.0, 0.0), (1.0, 0.0), (2.0, 0.0)]));
    assert_eq!(prepare(&f).unwrap().yr, (-1.0, 1.0));
    f.y_non_negative = true;
    let ticks_from_zero = |r: (f64, f64)| {
        let t = axis_ticks(Scale::Linear, r, 150.0, false, false);
        assert!(t.iter().all(|t| t.pos >= -1e-12 * r.1), "{r:?}: {t:?}");
        assert!(
            t.iter().any(|t| t.pos.abs() <= 1e-12 * r.1),
            "{r:?}: no tick at 0"
        );
    };
    let (lo, hi) = prepare(&f).unwrap().yr;
    assert!((-ZERO_LIFT..0.0).contains(&lo) && hi == 1.0, "{lo} {hi}");
    ticks_from_zero((lo, hi));
    for top in [0.5, 0.013, 7.0, 1e-6] {
        f.series[0].points[1].1 = top;
        let (lo, hi) = prepare(&f).unwrap().yr;
        assert!(
            (-ZERO_LIFT * hi..0.0).contains(&lo) && hi > top,
            "{lo} {hi}"
        );
        ticks_from_zero((lo, hi));
    }
}

/// An autoscaled log axis ends at ticks: at whole decades when it spans two or more (both
/// ends labelled), at mantissa ticks otherwise, so no point lies beyond the outermost tick.
#[test]
fn log_axes_end_at_ticks() {
    let lg = |v: f64| libm::log10(v);
    let near = |a: (f64, f64), b: (f64, f64)| (a.0 - b.0).abs() < 1e-9 && (a.1 - b.1).abs() < 1e-9;
    // Solve times 0.12–0.35 s: from the tick 1e-1 to the tick 4e-1.
    let r = snap_log((lg(0.12), lg(0.35)), Scale::Log10);
    assert!(near(r, (lg(0.1), lg(0.4))), "{r:?}");
    // On ticks already: unchanged.
    let r = snap_log((lg(0.2), lg(0.5)), Scale::Log10);
    assert!(near(r, (lg(0.2), lg(0.5))), "{r:?}");
    // Errors 5.25e-9 … 3.58e-3: whole decades 1e-9 … 1e-2.
    let r = snap_log((lg(5.25e-9), lg(3.58e-3)), Scale::Log10);
    assert!(near(r, (-9.0, -2.0)), "{r:?}");
    // Up to the next decade from 9.5.
    let r = snap_log((lg(2.0), lg(9.5)), Scale::Log10);
    assert!(near(r, (lg(2.0), 1.0)), "{r:?}");
    assert_eq!(snap_log((0.3, 0.7), Scale::Linear), (0.3, 0.7));
    // Through prepare: the x range of a log axis ends at the ticks.
    let mut f = LineFigure::new("t", "time [s]", "error");
    f.x_scale = Scale::Log10;
    f.y_scale = Scale::Log10;
    f.series.push(Series::new(
        "runs",
        vec![
            (0.12, 3.58e-3),
            (0.15, 4.7e-4),
            (0.18, 5.25e-5),
            (0.35, 5.25e-9),
        ],
    ));
    let p = prepare(&f).unwrap();
    assert!(
        p.xr.0 <= lg(0.1) + 1e-12 && p.xr.1 >= lg(0.35),
        "{:?}",
        p.xr
    );
    assert_eq!((p.yr.0.fract(), p.yr.1.fract()), (0.0, 0.0), "{:?}", p.yr);
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
            (1000.0 * libm::cos(r)).round() as i32,
            (1000.0 * libm::sin(r)).round() as i32,
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
                libm::hypot(qx - t * dx, qy - t * dy)
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
                let sp: Vec<(i32, i32)> = s.iter().map(|&(x, y)| (x as i32, y as i32)).collect();
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

/// A combining mark in a figure's text is refused, naming it: the PNG cannot place it, and
/// would show another symbol than the SVG (ω̄ as ω and a stray bar).
#[test]
fn combining_marks_are_refused() {
    let mut f = LineFigure::new("t", "t [s]", "\u{3c9}\u{304} [rad/s]");
    f.series
        .push(Series::new("w", vec![(0.0, 1.0), (1.0, 2.0)]));
    let e = prepare(&f).err().expect("refused").to_string();
    assert!(e.contains("U+0304"), "{e}");
    f.y_label = "ω [rad/s]".into();
    assert!(prepare(&f).is_ok());
    f.series[0].name = "a\u{301}".into();
    assert!(prepare(&f).is_err());
}
