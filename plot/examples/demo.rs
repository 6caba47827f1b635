//! Renders a few demo figures to the directory given as first argument (default `out/plot-demo`).
use bf_plot::*;
fn main() -> Result<(), PlotError> {
    let dir = std::env::args()
        .nth(1)
        .unwrap_or_else(|| "out/plot-demo".into());
    let dir = std::path::Path::new(&dir);
    let r = render_report(&sat::fig4_saturation(&[0.01, 0.1], 801), dir.join("fig4"))?;
    println!("{:?}", r);
    let mut f = LineFigure::new("Eight series", "t [s]", "y [-]");
    for k in 0..8 {
        f.series.push(Series::new(
            format!("series {k}"),
            (0..200)
                .map(|i| {
                    let t = i as f64 * 0.05;
                    (t, libm::sin(t + k as f64 * 0.4) * (1.0 + 0.1 * k as f64))
                })
                .collect(),
        ));
    }
    f.vertical_markers = vec![
        (2.0, "impact".into()),
        (2.3, "lift-off".into()),
        (7.0, "t_f".into()),
    ];
    f.hlines.push(HLine {
        y: 1.6,
        label: "limit".into(),
        colour: Colour::Auto,
        fit: true,
    });
    f.bands.push(Band {
        x0: 2.0,
        x1: 2.3,
        label: "contact".into(),
        colour: Colour::Auto,
    });
    println!("{:?}", render(&f, dir.join("eight"))?);

    // A kernel-variant comparison: unrelated points (one per kernel), labelled.
    let kernels = ["mass_matrix", "cqd_g", "cqd_g_rnea", "mass_cqd_g"];
    let sets: Vec<paper::WorkPrecisionSet> = ["plain", "FMA", "f32", "runtime params"]
        .iter()
        .enumerate()
        .map(|(v, name)| paper::WorkPrecisionSet {
            name: name.to_string(),
            time_s: (0..4)
                .map(|k| 1e-9 * (40.0 + 35.0 * k as f64) * (1.0 + 0.15 * v as f64))
                .collect(),
            error: (0..4)
                .map(|k| {
                    if v == 2 {
                        1e-7 * (1.0 + k as f64)
                    } else {
                        1.1e-16 * (1.0 + 0.7 * k as f64 + 0.3 * v as f64)
                    }
                })
                .collect(),
            labels: kernels.iter().map(|k| k.to_string()).collect(),
            joined: false,
        })
        .collect();
    let f = paper::fig_work_precision_sets(
        "Kernels: error vs time per call",
        "max ‖y − y_dd‖∞ / ‖y_dd‖∞",
        &sets,
    )?;
    println!("{:?}", render(&f, dir.join("kernels"))?);
    Ok(())
}
