//! Every figure type the paper pipeline draws, with the report's long titles and legend texts,
//! written as SVG and laid out again by usvg (an independent SVG implementation) with only the
//! crate's own DejaVu Sans file loaded: every text's ink lies inside the canvas, every legend
//! text inside its legend box, and every advance width is the one the layout measured. This is
//! what a browser or librsvg shows when it has DejaVu Sans, the font the SVG names.

mod common;
#[path = "common/text_fit.rs"]
mod text_fit;

use bf_plot::paper::*;
use bf_plot::scene3d::{FingerPaths, NamedPath, View, fig_compare_paths, fig_finger_paths};
use bf_plot::*;
use common::{grid, tmp, ts};
use std::path::PathBuf;

fn phases() -> Phases {
    Phases {
        switches: vec![(1.0, "impact".into()), (1.6, "lift-off".into())],
        contact: vec![(1.0, 1.6)],
    }
}

/// The SVGs of every figure type, with the titles and legends the `paper` command uses.
fn all_figures(dir: &std::path::Path) -> Vec<PathBuf> {
    let mut out = Vec::new();
    let t = grid(400, 9.6);
    let ph = phases();
    out.push(
        render(&sat::fig4_saturation(&[0.01, 0.1], 801), dir.join("fig4")).unwrap()[0].clone(),
    );
    let omega = ts(
        &t,
        &[&|x| 0.5 * libm::sin(x), &|x| -0.4 * libm::cos(x), &|x| {
            2.2 + 0.1 * libm::sin(x)
        }],
        &["ω_x", "ω_y", "ω_z"],
    );
    let f = fig_ball_omega(
        "Fig. 6 counterpart: periodic-cot: ball angular velocity",
        &omega,
        &ph,
    )
    .unwrap();
    out.push(render(&f, dir.join("fig6")).unwrap()[0].clone());
    let f = fig_ball_omega_ref(
        "Fig. 13 counterpart: periodic-qc: ball angular velocity",
        &omega,
        &ph,
        &[("ω_ref,z".into(), 2.2)],
    )
    .unwrap();
    out.push(render(&f, dir.join("fig13")).unwrap()[0].clone());
    let h: Vec<f64> = t.iter().map(|&x| 0.1 * (x - 1.3).abs()).collect();
    let off: Vec<f64> = t.iter().map(|&x| 0.02 * x).collect();
    let f = fig_distance(
        "Fig. 7 counterpart: periodic-cot: distance h and contact point",
        &t,
        &h,
        &off,
        &ph,
    )
    .unwrap();
    out.push(render_panels(&f, dir.join("fig7")).unwrap()[0].clone());
    let tau = ts(
        &t,
        &[&|x| 0.3 + 0.01 * libm::sin(x), &|x| libm::cos(x), &|x| {
            -0.2 * libm::sin(x)
        }],
        &["τ1", "τ2", "τ3"],
    );
    let f = fig_torques(
        "Fig. 15 counterpart: periodic-qc: joint torques",
        &tau,
        Some(1.0),
        &ph,
    )
    .unwrap();
    out.push(render_panels(&f, dir.join("fig15")).unwrap()[0].clone());
    let ln: Vec<f64> = t.iter().map(|&x| 2.0 + x).collect();
    let lt: Vec<f64> = ln.iter().map(|v| 0.7 * v).collect();
    let f = fig_contact_forces(
        "Fig. 16 counterpart: periodic-qc: contact force",
        &t,
        &ln,
        &lt,
        0.8,
        &ph,
    )
    .unwrap();
    out.push(render(&f, dir.join("fig16")).unwrap()[0].clone());
    let ol = ts(
        &t,
        &[&|x| 0.6 * libm::sin(x), &|x| -0.3 * libm::cos(x), &|x| {
            2.0 + 0.2 * libm::sin(x)
        }],
        &["ω_x", "ω_y", "ω_z"],
    );
    let modes = SimModes {
        slip: vec![(1.0, 1.2)],
        stick: vec![(1.2, 1.6)],
    };
    let f = fig_open_loop_vs_optimal_modes(
        "Fig. 17 counterpart: ball angular velocity, optimal vs open-loop simulation of the \
         optimal torques (periodic-cot, 3 periods)",
        &omega,
        &ol,
        &ph,
        &modes,
    )
    .unwrap();
    out.push(render_panels(&f, dir.join("fig17")).unwrap()[0].clone());
    let sets = [
        WorkPrecisionSet {
            name: "hp-LGR, 3 elements (objective vs 3 × 14 points)".into(),
            time_s: vec![0.5, 1.0, 2.0, 4.0],
            error: vec![1e-2, 1e-3, 1e-4, 1e-6],
            labels: vec!["3×6".into(), "3×8".into(), "3×10".into(), "3×12".into()],
            joined: true,
        },
        WorkPrecisionSet {
            name: "LG, one element per phase (unordered local optima)".into(),
            time_s: vec![0.7, 1.5, 3.0],
            error: vec![3e-2, 2e-4, 5e-5],
            labels: vec!["10".into(), "20".into(), "30".into()],
            joined: false,
        },
    ];
    let f = fig_work_precision_sets(
        "Speed vs accuracy: mesh (error of the objective against the finest mesh)",
        "|φ − φ_ref| / |φ_ref|",
        &sets,
    )
    .unwrap();
    out.push(render(&f, dir.join("sa_mesh")).unwrap()[0].clone());
    let tip: Vec<[f64; 3]> = (0..200)
        .map(|k| {
            let a = 0.03 * k as f64;
            [1.2 * libm::cos(a), 1.2 * libm::sin(a), 0.4]
        })
        .collect();
    let paths = FingerPaths {
        ball_center: [0.0; 3],
        ball_radius: 1.0,
        snapshots: (0..4)
            .map(|k| {
                let p = tip[k * 60];
                vec![[2.0, 0.0, 0.0], [1.8, 0.2, 0.5], [1.5, 0.3, 0.6], p]
            })
            .collect(),
        tip_path: tip.clone(),
        contact_path: tip
            .iter()
            .enumerate()
            .map(|(i, p)| {
                if (50..90).contains(&i) {
                    *p
                } else {
                    [f64::NAN; 3]
                }
            })
            .collect(),
    };
    let f = fig_finger_paths(
        "Fig. 5 counterpart: periodic-cot: finger path",
        &paths,
        &[View::FrontXZ, View::SideYZ, View::Iso],
    )
    .unwrap();
    out.push(render_panels(&f, dir.join("fig5")).unwrap()[0].clone());
    let named = [
        NamedPath {
            name: "robotic finger (periodic-cot): closest point".into(),
            points: tip.clone(),
        },
        NamedPath {
            name: "human finger (periodic-cot-human): closest point".into(),
            points: tip.iter().map(|p| [p[0], p[1], 0.6]).collect(),
        },
    ];
    let f = fig_compare_paths(
        "Fig. 11 counterpart: closest-point paths of the robotic and the human finger (COT)",
        [0.0; 3],
        1.0,
        &named,
        &[View::FrontXZ, View::SideYZ, View::Iso],
    )
    .unwrap();
    out.push(render_panels(&f, dir.join("fig11")).unwrap()[0].clone());
    out
}

#[test]
fn every_text_fits_its_canvas_and_legend_box_as_usvg_lays_it_out() {
    let d = tmp("text-fit");
    let opt = text_fit::options();
    let mut texts = 0;
    for p in all_figures(&d) {
        let svg = std::fs::read_to_string(&p).unwrap();
        let (laid, legends, _) = text_fit::lay_out(&svg, &opt);
        assert!(!legends.is_empty(), "{}: no legend box", p.display());
        texts += laid.len();
        let bad = text_fit::problems(&svg, &opt);
        assert!(bad.is_empty(), "{}:\n{}", p.display(), bad.join("\n"));
    }
    assert!(texts > 300, "only {texts} texts checked");
}

#[test]
fn the_check_finds_text_laid_out_for_another_font_size() {
    // A legend text written 16 % larger than measured (as the SVG was when it named DejaVu
    // Sans at plotters' size, which scales to ascent − descent) must be reported, and so must a
    // title wider than its canvas: the check is not vacuous.
    let d = tmp("text-fit-neg");
    let opt = text_fit::options();
    let mut f = LineFigure::new("t", "x", "y");
    f.series.push(Series::new(
        "a legend entry that is long enough to overflow",
        vec![(0.0, 0.0), (1.0, 1.0)],
    ));
    let p = render(&f, d.join("neg")).unwrap();
    let svg = std::fs::read_to_string(&p[0]).unwrap();
    assert!(text_fit::problems(&svg, &opt).is_empty());
    let line = svg
        .lines()
        .find(|l| l.contains("class=\"legend\""))
        .unwrap();
    let size: f64 = line
        .split("font-size=\"")
        .nth(1)
        .and_then(|s| s.split('"').next())
        .and_then(|s| s.parse().ok())
        .unwrap();
    let bigger = svg.replace(
        line,
        &line.replace(
            &format!("font-size=\"{size}\""),
            &format!("font-size=\"{}\"", size * 1.164),
        ),
    );
    assert_ne!(bigger, svg);
    let bad = text_fit::problems(&bigger, &opt);
    assert!(bad.iter().any(|b| b.contains("leaves its box")), "{bad:?}");
    let wide = svg.replace(">t</text>", &format!(">{}</text>", "W".repeat(80)));
    let bad = text_fit::problems(&wide, &opt);
    assert!(bad.iter().any(|b| b.contains("leaves the")), "{bad:?}");
}

#[test]
fn a_title_longer_than_the_canvas_is_shrunk_or_cut_to_fit() {
    let d = tmp("text-fit-title");
    let opt = text_fit::options();
    let mut f = LineFigure::new("A very long title ".repeat(12), "x [m]", "y [m]");
    f.size = (400, 300);
    f.series
        .push(Series::new("s", vec![(0.0, 0.0), (1.0, 1.0)]));
    let p = render(&f, d.join("long")).unwrap();
    let svg = std::fs::read_to_string(&p[0]).unwrap();
    let bad = text_fit::problems(&svg, &opt);
    assert!(bad.is_empty(), "{bad:?}");
    let (laid, _, _) = text_fit::lay_out(&svg, &opt);
    let title = laid.iter().find(|t| t.class == "panel-title").unwrap();
    assert!(title.text.ends_with('…'), "{}", title.text);
}
