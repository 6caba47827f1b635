//! Helpers shared by bf-plot's integration tests (and the `finger_paths` example): a fresh
//! temporary directory, a time grid, time series from closures, a rotation about z, and finger
//! snapshots whose links fold back on themselves in the side view.

#![allow(dead_code)]

#[path = "../../../tests/common/tempdir.rs"]
mod tempdir;
pub use tempdir::TempDir;

use bf_plot::paper::TimeSeries;

/// A fresh, empty temporary directory for one test (process id and `name` keep runs apart),
/// removed with its contents when the returned guard is dropped ([`TempDir`]).
pub fn tmp(name: &str) -> TempDir {
    let d = std::env::temp_dir().join(format!("bf-plot-test-{}-{name}", std::process::id()));
    TempDir::fresh(d)
}

/// `n` equally spaced times from 0 to `t1`.
pub fn grid(n: usize, t1: f64) -> Vec<f64> {
    (0..n).map(|i| t1 * i as f64 / (n - 1) as f64).collect()
}

/// One series per closure in `f`, sampled at `t`, named `names`.
pub fn ts(t: &[f64], f: &[&dyn Fn(f64) -> f64], names: &[&str]) -> TimeSeries {
    TimeSeries {
        t: t.to_vec(),
        values: f
            .iter()
            .map(|g| t.iter().map(|&x| g(x)).collect())
            .collect(),
        names: names.iter().map(|s| s.to_string()).collect(),
    }
}

/// The rotation by `a` about z (row-major).
pub fn rot_z(a: f64) -> [[f64; 3]; 3] {
    let (s, c) = libm::sincos(a);
    [[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]]
}

/// Finger snapshots (base, joints, tip) with the base (2, 0, 0), which projects to (0, 0) in the
/// y–z view, and first links that point almost exactly back along the second one: polylines
/// turning by almost 180° (hairpins) in the side view.
pub fn hairpin_snapshots() -> Vec<Vec<[f64; 3]>> {
    vec![
        vec![
            [2.0, 0.0, 0.0],
            [2.0, -0.6, 0.66],
            [1.5, -0.5, 0.55],
            [0.8, -0.95, 1.05],
        ],
        vec![
            [2.0, 0.0, 0.0],
            [2.0, 0.0, 1.0],
            [1.2, 0.6, 0.9],
            [0.3, 0.9, 1.1],
        ],
        vec![
            [2.0, 0.0, 0.0],
            [1.9, 0.62, 0.5],
            [1.4, 0.0, 0.01],
            [0.9, 0.55, 0.45],
        ],
        vec![
            [2.0, 0.0, 0.0],
            [2.0, 0.8, 0.55],
            [1.0, 1.3, 0.85],
            [1.5, 0.71, 0.49],
        ],
    ]
}

/// `n` points of a closed fingertip path around the hairpin snapshots.
pub fn hairpin_tip_path(n: usize) -> Vec<[f64; 3]> {
    (0..n)
        .map(|k| {
            let t = k as f64 * std::f64::consts::TAU / (n - 1) as f64;
            [
                0.6 + 0.3 * libm::cos(t),
                0.9 * libm::sin(t),
                0.8 + 0.3 * libm::sin(2.0 * t),
            ]
        })
        .collect()
}
