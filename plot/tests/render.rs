//! End-to-end rendering tests: every figure type is written as SVG + PNG into a temporary
//! directory, the PNG is decoded and checked for real content (non-background pixels and the
//! series colours), and the SVG for the legend texts and one stroke colour per series.
//! Bad input must give a clear error and leave no file behind.

mod common;

use bf_plot::anim::{AnimFrame, Animation, animation_html, write_animation_html};
use bf_plot::figure::palette;
use bf_plot::paper::*;
use bf_plot::scene3d::{FingerPaths, View, fig_finger_paths};
use bf_plot::*;
use common::{grid, hairpin_snapshots, hairpin_tip_path, rot_z, tmp, ts};
use std::path::{Path, PathBuf};

/// Decoded PNG: (width, height, rgb pixels).
fn png(path: &Path) -> (u32, u32, Vec<[u8; 3]>) {
    let file = std::fs::File::open(path).expect("PNG opens");
    let mut reader = png::Decoder::new(std::io::BufReader::new(file))
        .read_info()
        .expect("PNG header decodes");
    let mut buf = vec![0; reader.output_buffer_size()];
    let info = reader.next_frame(&mut buf).expect("PNG decodes");
    assert_eq!(
        (info.color_type, info.bit_depth),
        (png::ColorType::Rgb, png::BitDepth::Eight),
        "8-bit RGB"
    );
    let px = buf[..info.buffer_size()]
        .chunks_exact(3)
        .map(|c| [c[0], c[1], c[2]])
        .collect();
    (info.width, info.height, px)
}

fn count_colour(px: &[[u8; 3]], c: (u8, u8, u8)) -> usize {
    px.iter().filter(|p| **p == [c.0, c.1, c.2]).count()
}

fn hex(c: (u8, u8, u8)) -> String {
    format!("#{:02X}{:02X}{:02X}", c.0, c.1, c.2)
}

/// Checks common to every rendered figure; returns (svg text, png pixels).
fn check_files(paths: &[PathBuf; 2], size: (u32, u32), legend: &[&str]) -> (String, Vec<[u8; 3]>) {
    assert_eq!(paths[0].extension().unwrap(), "svg");
    assert_eq!(paths[1].extension().unwrap(), "png");
    let svg = std::fs::read_to_string(&paths[0]).unwrap();
    assert!(svg.starts_with("<svg"), "SVG header");
    for l in legend {
        let esc = l.replace('&', "&amp;").replace('<', "&lt;");
        assert!(svg.contains(&esc), "legend text '{l}' missing from SVG");
    }
    let (w, h, px) = png(&paths[1]);
    assert_eq!((w, h), size);
    let ink = px.iter().filter(|p| **p != [255, 255, 255]).count();
    assert!(
        ink > (w * h / 50) as usize,
        "only {ink} non-background pixels"
    );
    // No temporary files left next to the outputs.
    let dir = paths[0].parent().unwrap();
    for e in std::fs::read_dir(dir).unwrap() {
        let n = e.unwrap().file_name().to_string_lossy().into_owned();
        assert!(!n.contains(".tmp"), "temporary file {n} left behind");
    }
    (svg, px)
}

fn phases() -> Phases {
    Phases {
        switches: vec![(1.0, "impact".into()), (1.6, "lift-off".into())],
        contact: vec![(1.0, 1.6)],
    }
}

#[test]
fn fig4_saturation_renders_all_curves() {
    let d = tmp("fig4");
    let fig = sat::fig4_saturation(&[0.01, 0.1], 801);
    let r = render_report(&fig, d.join("fig4")).unwrap();
    assert_eq!(r.skipped_points, 0);
    let names: Vec<&str> = fig.series.iter().map(|s| s.name.as_str()).collect();
    let (svg, px) = check_files(&r.paths, fig.size, &names);
    // The exact sat is black, the tanh green: both must be visible in the bitmap and the SVG.
    for c in [(0, 0, 0), (44, 160, 44), (214, 39, 40)] {
        assert!(count_colour(&px, c) > 100, "colour {c:?} hardly present");
        assert!(svg.contains(&hex(c)), "colour {} not in SVG", hex(c));
    }
}

#[test]
fn eight_series_get_distinct_colours_legend_and_paths() {
    let d = tmp("eight");
    let mut f = LineFigure::new("Eight series", "t [s]", "y [m]");
    for k in 0..8 {
        f.series.push(Series::new(
            format!("series {k}"),
            (0..300)
                .map(|i| {
                    let t = i as f64 * 0.03;
                    (t, libm::sin(t + 0.5 * k as f64) + 0.3 * k as f64)
                })
                .collect(),
        ));
    }
    f.vertical_markers = vec![(2.0, "t₁".into()), (6.0, "t₂".into())];
    f.hlines.push(HLine {
        y: 3.0,
        label: "limit".into(),
        colour: Colour::Auto,
        fit: true,
    });
    let names: Vec<String> = f.series.iter().map(|s| s.name.clone()).collect();
    let mut legend: Vec<&str> = names.iter().map(|s| s.as_str()).collect();
    legend.extend(["limit", "t₁", "t₂", "Eight series", "t [s]", "y [m]"]);
    let paths = render(&f, d.join("eight")).unwrap();
    let (svg, px) = check_files(&paths, f.size, &legend);
    let colours: Vec<(u8, u8, u8)> = (0..8).map(palette).collect();
    for (i, &c) in colours.iter().enumerate() {
        assert!(
            colours[..i].iter().all(|&o| o != c),
            "palette colour repeats within 8"
        );
        assert!(
            count_colour(&px, c) > 50,
            "series {i} colour {c:?} missing in PNG"
        );
        assert!(svg.contains(&hex(c)), "series {i} colour missing in SVG");
    }
    // Solid series are one <polyline> each; dashed ones one per dash: at least one per series.
    assert!(svg.matches("<polyline").count() >= 8);
}

#[test]
fn nan_points_are_skipped_and_counted() {
    let d = tmp("nan");
    let mut f = LineFigure::new("gaps", "t [s]", "y [-]");
    f.series.push(Series::new(
        "a",
        (0..100)
            .map(|i| (i as f64, if i % 10 == 5 { f64::NAN } else { i as f64 }))
            .collect(),
    ));
    f.series.push(Series::new(
        "b",
        vec![(0.0, 1.0), (1.0, f64::INFINITY), (2.0, 3.0)],
    ));
    let r = render_report(&f, d.join("gaps")).unwrap();
    assert_eq!(r.skipped_points, 11);
    check_files(&r.paths, f.size, &["a", "b"]);
}

#[test]
fn bad_input_gives_clear_errors_and_no_files() {
    let d = tmp("bad");
    let f = LineFigure::new("empty fig", "t [s]", "y [-]");
    let e = render(&f, d.join("a")).unwrap_err();
    assert!(matches!(e, PlotError::NoSeries(_)));
    assert!(e.to_string().contains("empty fig"));

    let mut f2 = f.clone();
    f2.series.push(Series::new("nothing", vec![]));
    let e = render(&f2, d.join("b")).unwrap_err();
    assert!(matches!(e, PlotError::EmptySeries { .. }) && e.to_string().contains("nothing"));

    let mut f3 = f.clone();
    f3.series.push(Series::new(
        "nan only",
        vec![(f64::NAN, 1.0), (1.0, f64::NAN)],
    ));
    let e = render(&f3, d.join("c")).unwrap_err();
    assert!(
        matches!(e, PlotError::NoFinitePoints { skipped: 2, .. }),
        "{e}"
    );

    let mut f4 = f.clone();
    f4.series.push(Series::new("ok", vec![(0.0, 1.0)]));
    f4.x_range = Some((1.0, 0.0));
    assert!(matches!(
        render(&f4, d.join("d")),
        Err(PlotError::InvalidInput { .. })
    ));

    let p = PanelFigure {
        title: "none".into(),
        panels: vec![],
        layout: Layout::Rows,
        size: None,
    };
    assert!(matches!(
        render_panels(&p, d.join("e")),
        Err(PlotError::NoSeries(_))
    ));
    assert_eq!(
        std::fs::read_dir(&d).unwrap().count(),
        0,
        "files written despite errors"
    );
}

#[test]
fn paper_time_series_figures_render() {
    let d = tmp("paper");
    let t = grid(400, 2.5);
    let omega = ts(
        &t,
        &[
            &|x| 0.5 * (x - 1.0).clamp(0.0, 0.6),
            &|x| -0.4 * (x - 1.0).clamp(0.0, 0.6),
            &|x| 0.1 * libm::sin(x),
        ],
        &["ω_x", "ω_y", "ω_z"],
    );
    let f6 = fig_ball_omega("Fig. 6: ball angular velocity", &omega, &phases()).unwrap();
    assert_eq!(f6.series.len(), 3);
    let p = render(&f6, d.join("fig6")).unwrap();
    let (_, px) = check_files(
        &p,
        f6.size,
        &["ω_x", "ω_y", "ω_z", "impact", "lift-off", "contact"],
    );
    for i in 0..3 {
        assert!(count_colour(&px, palette(i)) > 50);
    }

    let h: Vec<f64> = t
        .iter()
        .map(|&x| {
            if (1.0..=1.6).contains(&x) {
                0.0
            } else {
                0.3 * (x - 1.3).abs() - 0.09
            }
        })
        .collect();
    let off: Vec<f64> = t
        .iter()
        .map(|&x| {
            if (1.0..=1.6).contains(&x) {
                0.2 + 0.05 * x
            } else {
                0.0
            }
        })
        .collect();
    let f7 = fig_distance("Fig. 7: distance", &t, &h, &off, &phases()).unwrap();
    assert_eq!(f7.panels.len(), 2);
    let p = render_panels(&f7, d.join("fig7")).unwrap();
    check_files(&p, (1000, 660), &["h", "|sat(α)|", "h [m]"]);

    let tau = ts(
        &t,
        &[&|x| libm::sin(x), &|x| libm::cos(2.0 * x) * 1.2, &|x| {
            0.3 * x
        }],
        &["τ₁", "τ₂", "τ₃"],
    );
    let f8 = fig_torques("Fig. 8: torques", &tau, Some(1.0), &phases()).unwrap();
    assert_eq!(f8.panels.len(), 3);
    assert!(
        f8.panels
            .iter()
            .all(|p| p.series.len() == 1 && p.hlines.len() == 2)
    );
    let p = render_panels(&f8, d.join("fig8")).unwrap();
    check_files(
        &p,
        (1000, 960),
        &["τ₁ [N m]", "τ₂ [N m]", "τ₃ [N m]", "torque limit"],
    );

    let ln: Vec<f64> = t
        .iter()
        .map(|&x| {
            if (1.0..=1.6).contains(&x) {
                2.0 + x
            } else {
                f64::NAN
            }
        })
        .collect();
    let lt: Vec<f64> = ln.iter().map(|v| 0.8 * v * 0.9).collect();
    let f9 = fig_contact_forces("Fig. 9: contact force", &t, &ln, &lt, 0.8, &phases()).unwrap();
    assert_eq!(f9.series.len(), 3);
    let r = render_report(&f9, d.join("fig9")).unwrap();
    assert!(r.skipped_points > 0);
    check_files(
        &r.paths,
        f9.size,
        &[
            "normal λ_n",
            "tangential ‖λ_∥‖",
            "cone bound μ_s λ_n (μ_s = 0.8)",
        ],
    );

    let ol = ts(
        &t,
        &[
            &|x| 0.5 * (x - 1.0).clamp(0.0, 0.5),
            &|x| -0.4 * (x - 1.0).clamp(0.0, 0.7),
            &|x| 0.12 * libm::sin(x),
        ],
        &["ω_x", "ω_y", "ω_z"],
    );
    let f17 =
        fig_open_loop_vs_optimal("Fig. 17: open loop vs optimal", &omega, &ol, &phases()).unwrap();
    assert!(f17.panels.iter().all(|p| p.series.len() == 2));
    let p = render_panels(&f17, d.join("fig17")).unwrap();
    check_files(
        &p,
        (1000, 960),
        &["optimal", "open-loop simulation", "ω_z [rad/s]"],
    );
}

#[test]
fn work_precision_loglog() {
    let d = tmp("wp");
    // error = C h^p, time = K / h for orders 1, 2, 4, 5: straight lines of slope −p in log–log.
    let methods: Vec<WorkPrecision> = [(1, "Euler"), (2, "Heun"), (4, "RK4"), (5, "DOPRI5")]
        .iter()
        .map(|&(p, n)| {
            let hs: Vec<f64> = (0..6).map(|k| 0.1 / 2f64.powi(k)).collect();
            WorkPrecision {
                name: n.into(),
                time_s: hs.iter().map(|h| 1e-4 * p as f64 / h).collect(),
                error: hs.iter().map(|h| h.powi(p)).collect(),
            }
        })
        .collect();
    let f = fig_work_precision("Work-precision", "max error [rad/s]", &methods).unwrap();
    assert_eq!(f.series.len(), 4);
    let p = render(&f, d.join("wp")).unwrap();
    let (svg, _) = check_files(
        &p,
        f.size,
        &["Euler", "Heun", "RK4", "DOPRI5", "computing time [s]"],
    );
    assert!(svg.contains("1e-"), "decade tick labels expected");
    assert!(svg.matches("<circle").count() >= 24, "one marker per run");
}

fn finger(q1: f64, q2: f64, q3: f64) -> Vec<[f64; 3]> {
    // Planar-ish 3-link chain from the base at (2, 0, 0); plain geometry for the test scene.
    let base = [2.0, 0.0, 0.0];
    let mut pts = vec![base];
    let (mut p, mut a) = (base, std::f64::consts::PI + q1);
    for q in [0.0, q2, q3] {
        a += q;
        p = [
            p[0] + libm::cos(a) * 0.9,
            p[1] + 0.2 * libm::sin(q1),
            p[2] + libm::sin(a) * 0.9,
        ];
        pts.push(p);
    }
    pts
}

#[test]
fn finger_paths_3d_renders_views() {
    let d = tmp("paths");
    let snaps: Vec<Vec<[f64; 3]>> = (0..4)
        .map(|k| finger(0.3 * k as f64 - 0.4, 0.5, 0.4))
        .collect();
    let tip: Vec<[f64; 3]> = (0..100)
        .map(|k| *finger(0.012 * k as f64 - 0.4, 0.5, 0.4).last().unwrap())
        .collect();
    let contact: Vec<[f64; 3]> = tip
        .iter()
        .enumerate()
        .map(|(k, p)| {
            if (40..60).contains(&k) {
                *p
            } else {
                [f64::NAN; 3]
            }
        })
        .collect();
    let data = FingerPaths {
        ball_center: [0.0; 3],
        ball_radius: 1.0,
        snapshots: snaps,
        tip_path: tip,
        contact_path: contact,
    };
    let fig = fig_finger_paths(
        "Fig. 5: finger path",
        &data,
        &[View::FrontXZ, View::TopXY, View::Iso],
    )
    .unwrap();
    assert_eq!(fig.panels.len(), 3);
    // ball + the wireframe's great circles + 4 snapshots + tip path + contact path; the
    // circle in a front or top view's own plane would retrace the outline and is left out.
    let series: Vec<usize> = fig.panels.iter().map(|p| p.series.len()).collect();
    assert_eq!(series, [9, 9, 10]);
    assert!(fig.panels.iter().all(|p| p.equal_aspect));
    let r = render_panels_report(&fig, d.join("fig5")).unwrap();
    assert_eq!(r.skipped_points, 3 * 80);
    let (_, px) = check_files(
        &r.paths,
        (1560, 620),
        &[
            "ball",
            "finger (snapshots)",
            "fingertip path",
            "contact point path",
            "isometric",
        ],
    );
    assert!(count_colour(&px, (214, 39, 40)) > 30 && count_colour(&px, (31, 119, 180)) > 30);
}

#[test]
fn animation_html_is_self_contained_with_all_frames() {
    let d = tmp("anim");
    let n = 37;
    let frames: Vec<AnimFrame> = (0..n)
        .map(|k| {
            let t = 0.05 * k as f64;
            AnimFrame {
                t,
                joints: finger(0.3 * t, 0.5, 0.4),
                ball_rotation: rot_z(2.2 * t),
                contact: (k > 10 && k < 20).then_some([1.0, 0.0, 0.0]),
            }
        })
        .collect();
    let a = Animation {
        title: "Ball & finger <QC>".into(),
        ball_center: [0.0; 3],
        ball_radius: 1.0,
        frames,
    };
    let path = write_animation_html(&a, d.join("anim.html")).unwrap();
    let html = std::fs::read_to_string(path).unwrap();
    assert_eq!(html.matches("{t:").count(), n);
    assert!(html.contains(&format!("data-frames=\"{n}\"")));
    // The scrubber runs in time (seconds), from the first to the last frame's time.
    assert!(html.contains("min=\"0\" max=\"1.8\""));
    assert_eq!(html.matches("c:null").count(), n - 9);
    assert!(html.contains("Ball &amp; finger &lt;QC&gt;"));
    for bad in ["http:", "https:", "src=", "href=", "@import", "url("] {
        assert!(
            !html.contains(bad),
            "external reference '{bad}' in the page"
        );
    }
    for id in ["id=\"play\"", "id=\"scrub\"", "id=\"time\""] {
        assert!(html.contains(id));
    }
    // Rotation matrices are stored row-major: frame 1 has R = Rz(0.11).
    assert!(html.contains(&format!("r:[{},", fmt5(libm::cos(0.11f64)))));

    // Bad input.
    let mut b = a.clone();
    b.frames[3].ball_rotation[0][0] = 2.0;
    assert!(matches!(
        animation_html(&b),
        Err(PlotError::InvalidInput { .. })
    ));
    let mut b = a.clone();
    b.frames[5].joints.pop();
    assert!(matches!(animation_html(&b), Err(PlotError::Shape { .. })));
    let mut b = a.clone();
    b.frames.clear();
    assert!(animation_html(&b).is_err());
    let mut b = a;
    b.frames[2].joints[1][2] = f64::NAN;
    assert!(animation_html(&b).is_err());
}

fn fmt5(v: f64) -> String {
    let s = format!("{v:.5}");
    s.trim_end_matches('0').trim_end_matches('.').to_string()
}

// ---------------------------------------------------------------------------------------------
// Clipping: nothing may be drawn outside a panel's axes rectangle.

/// Three side-by-side panels (default size 1560 × 620): the axes rectangle of panel k spans
/// x ∈ [520 k + 106, 520 (k + 1) − 28] and y ∈ [≈ 80, 548] (margins 14 px, label areas 92/58 px,
/// titles above). These bands lie outside every axes rectangle, with a few pixels of slack for
/// line width and marker dots drawn at the axes edge.
fn outside_all_axes(x: u32, y: u32) -> bool {
    let in_gap = (0..=3).any(|k| {
        let (lo, hi) = ((520 * k) as i64 - 22, (520 * k) as i64 + 100);
        (lo..=hi).contains(&(x as i64))
    });
    in_gap || !(60..=556).contains(&y)
}

/// Pixels of colour `c` (within a small tolerance for anti-aliasing) in the outside bands.
fn stray_pixels(px: &[[u8; 3]], w: u32, c: (u8, u8, u8)) -> Vec<(u32, u32)> {
    px.iter()
        .enumerate()
        .filter(|(_, p)| {
            (p[0] as i32 - c.0 as i32).abs() <= 8
                && (p[1] as i32 - c.1 as i32).abs() <= 8
                && (p[2] as i32 - c.2 as i32).abs() <= 8
        })
        .map(|(i, _)| (i as u32 % w, i as u32 / w))
        .filter(|&(x, y)| outside_all_axes(x, y))
        .collect()
}

/// Every (x, y) point of every SVG polyline drawn in `stroke` (e.g. "#FF00FF").
fn svg_polyline_points(svg: &str, stroke: &str) -> Vec<(f64, f64)> {
    let mut out = Vec::new();
    for el in svg.split("<polyline").skip(1) {
        let el = &el[..el.find("/>").unwrap_or(el.len())];
        if !el.contains(&format!("stroke=\"{stroke}\"")) {
            continue;
        }
        let pts = el
            .split("points=\"")
            .nth(1)
            .unwrap()
            .split('"')
            .next()
            .unwrap();
        for xy in pts.split_whitespace() {
            let mut it = xy.split(',').map(|v| v.parse::<f64>().unwrap());
            out.push((it.next().unwrap(), it.next().unwrap()));
        }
    }
    out
}

#[test]
fn explicit_small_range_clips_segments_to_the_axes() {
    let d = tmp("clip");
    let (magenta, cyan, orange) = ((255, 0, 255), (0, 200, 200), (255, 128, 0));
    let st = |c: (u8, u8, u8), w: u32, dash: Dash, in_legend: bool| SeriesStyle {
        colour: Colour::Rgb(c.0, c.1, c.2),
        dash,
        width: w,
        markers: false,
        in_legend,
    };
    let side = |name: &str| {
        let mut p = LineFigure::new(name, "x [m]", "y [m]");
        p.series.push(Series::new(
            "plain",
            (0..50)
                .map(|i| (i as f64, libm::sin(0.2 * i as f64)))
                .collect(),
        ));
        p
    };
    let mut mid = LineFigure::new("clipped", "x [m]", "y [m]");
    mid.x_range = Some((0.0, 1.0));
    mid.y_range = Some((0.0, 1.0));
    mid.equal_aspect = true;
    // y = 2 x + 1/2, far outside at both ends: enters through the left (or bottom) edge and
    // leaves through the top edge; one straight piece of slope 2 must remain.
    mid.series.push(
        Series::new("crossing", vec![(-50.0, -99.5), (60.0, 120.5)]).styled(st(
            magenta,
            3,
            Dash::Solid,
            true,
        )),
    );
    // Entirely outside, around the axes, over the title and the neighbouring panels: nothing
    // of it may appear (a clamping implementation would draw it along the frame).
    mid.series.push(
        Series::new(
            "outside",
            vec![
                (-40.0, 5.0),
                (40.0, 5.0),
                (40.0, -9.0),
                (-40.0, -9.0),
                (-40.0, 5.0),
            ],
        )
        .styled(st(cyan, 3, Dash::Solid, false)),
    );
    // Dashed, leaving through the top edge and coming back in.
    mid.series.push(
        Series::new(
            "dashed",
            vec![(0.2, 0.2), (0.5, 30.0), (0.8, 0.3), (0.9, -20.0)],
        )
        .styled(st(orange, 2, Dash::Dashed, true)),
    );
    let fig = PanelFigure {
        title: "Clipping test: nothing outside the axes".into(),
        panels: vec![side("left"), mid, side("right")],
        layout: Layout::Columns,
        size: None,
    };
    let paths = render_panels(&fig, d.join("clip")).unwrap();
    let (svg, px) = check_files(&paths, (1560, 620), &["crossing", "dashed"]);
    assert_eq!(count_colour(&px, cyan), 0, "the outside polyline was drawn");
    assert!(svg_polyline_points(&svg, &hex(cyan)).is_empty());
    for c in [magenta, orange] {
        // The clipped lines are visible inside the middle axes ...
        let inside = px
            .iter()
            .enumerate()
            .filter(|&(i, p)| {
                let (x, y) = (i as u32 % 1560, i as u32 / 1560);
                *p == [c.0, c.1, c.2] && (620..1040).contains(&x) && !outside_all_axes(x, y)
            })
            .count();
        assert!(inside > 100, "clipped {c:?} hardly drawn ({inside} px)");
        // ... and nowhere outside (legend samples are inside the axes too).
        let stray = stray_pixels(&px, 1560, c);
        assert!(
            stray.is_empty(),
            "{} {c:?} pixels outside the axes, e.g. {:?}",
            stray.len(),
            &stray[..stray.len().min(5)]
        );
        for (x, y) in svg_polyline_points(&svg, &hex(c)) {
            assert!(
                !outside_all_axes(x as u32, y as u32) && (600.0..1040.0).contains(&x),
                "SVG polyline point ({x}, {y}) outside the middle axes"
            );
        }
    }
    // The crossing line keeps its direction: in equal-aspect pixels |dy/dx| = 2 (a legend
    // sample is horizontal, so take the longest magenta polyline segment).
    let svg_segs: Vec<Vec<(f64, f64)>> = svg
        .split("<polyline")
        .skip(1)
        .filter(|e| {
            e.split("/>")
                .next()
                .unwrap()
                .contains(&format!("stroke=\"{}\"", hex(magenta)))
        })
        .map(|e| svg_polyline_points(&format!("<polyline{e}"), &hex(magenta)))
        .collect();
    let longest = svg_segs
        .iter()
        .filter(|p| p.len() == 2)
        .max_by(|a, b| {
            let l = |p: &Vec<(f64, f64)>| libm::hypot(p[1].0 - p[0].0, p[1].1 - p[0].1);
            l(a).total_cmp(&l(b))
        })
        .expect("clipped crossing segment in the SVG");
    let (dx, dy) = (longest[1].0 - longest[0].0, longest[1].1 - longest[0].1);
    assert!(
        libm::hypot(dx, dy) > 100.0,
        "crossing segment too short: {longest:?}"
    );
    assert!(
        ((dy / dx).abs() - 2.0).abs() < 0.05,
        "crossing segment has slope {} in pixels: {longest:?}",
        dy / dx
    );
}

#[test]
fn finger_paths_with_hairpin_projections_stay_inside_the_axes() {
    // In the side view (y–z) the base (2, 0, 0) projects to (0, 0) and the first links of these
    // snapshots fold back on themselves: a polyline turning by almost 180°. Thick lines must not
    // grow miter spikes across the figure.
    let d = tmp("hairpin");
    let data = FingerPaths {
        ball_center: [0.0; 3],
        ball_radius: 1.0,
        snapshots: hairpin_snapshots(),
        tip_path: hairpin_tip_path(400),
        contact_path: vec![],
    };
    let fig = fig_finger_paths(
        "hairpin: finger path",
        &data,
        &[View::FrontXZ, View::SideYZ, View::Iso],
    )
    .unwrap();
    let r = render_panels_report(&fig, d.join("paths")).unwrap();
    let (svg, px) = check_files(&r.paths, (1560, 620), &["finger (snapshots)"]);
    assert!(
        count_colour(&px, (20, 20, 20)) > 500,
        "snapshots hardly drawn"
    );
    // Reference: the same figure (same ranges, same legend place) with the snapshots in white.
    // Text is anti-aliased, so rather than matching colours, every pixel that differs must lie
    // inside an axes rectangle.
    let mut blank = fig.clone();
    for p in &mut blank.panels {
        for s in &mut p.series {
            if s.style.colour == Colour::Rgb(20, 20, 20) {
                s.style.colour = Colour::Rgb(255, 255, 255);
            }
        }
    }
    let rb = render_panels_report(&blank, d.join("blank")).unwrap();
    let (_, _, px_blank) = png(&rb.paths[1]);
    let stray: Vec<(u32, u32)> = px
        .iter()
        .zip(&px_blank)
        .enumerate()
        .filter(|(_, (a, b))| a != b)
        .map(|(i, _)| (i as u32 % 1560, i as u32 / 1560))
        .filter(|&(x, y)| outside_all_axes(x, y))
        .collect();
    assert!(
        stray.is_empty(),
        "{} pixels drawn by the snapshots outside the axes, e.g. {:?}",
        stray.len(),
        &stray[..stray.len().min(5)]
    );
    for &(x, y) in &svg_polyline_points(&svg, "#141414") {
        assert!(
            !outside_all_axes(x as u32, y as u32),
            "SVG point ({x}, {y})"
        );
    }
}
