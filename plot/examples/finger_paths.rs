//! Renders a finger-path figure (front, side, isometric) whose side view contains links that
//! fold back on themselves, as in the periodic-qc scenario, to the directory given as first
//! argument (default `out/plot-demo`). Used to inspect the clipping / thick-line fix by eye.
use bf_plot::scene3d::{FingerPaths, View, fig_finger_paths};
use bf_plot::{PlotError, render_panels};

// The hairpin snapshots are the ones bf-plot's rendering test checks.
#[path = "../tests/common/mod.rs"]
mod common;
use common::{hairpin_snapshots, hairpin_tip_path};

fn main() -> Result<(), PlotError> {
    let dir = std::env::args()
        .nth(1)
        .unwrap_or_else(|| "out/plot-demo".into());
    let dir = std::path::Path::new(&dir);
    // Base (2, 0, 0) projects to (0, 0) in the y–z view; several first links there point
    // almost exactly back along the second one.
    let mut snapshots = hairpin_snapshots();
    snapshots.push(vec![
        [2.0, 0.0, 0.0],
        [2.0, 0.7, 0.6],
        [2.0, 0.71, 0.61],
        [1.2, -0.3, 1.2],
    ]);
    let tip_path = hairpin_tip_path(600);
    // In contact (on the unit sphere) for the middle third of the path.
    let contact_path = tip_path
        .iter()
        .enumerate()
        .map(|(k, p)| {
            let n = (p[0] * p[0] + p[1] * p[1] + p[2] * p[2]).sqrt();
            if (200..400).contains(&k) {
                p.map(|v| v / n)
            } else {
                [f64::NAN; 3]
            }
        })
        .collect();
    let data = FingerPaths {
        ball_center: [0.0; 3],
        ball_radius: 1.0,
        snapshots,
        tip_path,
        contact_path,
    };
    let fig = fig_finger_paths(
        "hairpin links: finger path",
        &data,
        &[View::FrontXZ, View::SideYZ, View::Iso],
    )?;
    println!("{:?}", render_panels(&fig, dir.join("finger_paths"))?);
    Ok(())
}
