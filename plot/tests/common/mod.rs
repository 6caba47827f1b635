//! Helpers shared by bf-plot's integration tests: a fresh temporary directory, a time grid,
//! time series from closures, and a rotation about z.

#![allow(dead_code)]

use std::path::PathBuf;

use bf_plot::paper::TimeSeries;

/// A fresh, empty temporary directory for one test (process id and `name` keep runs apart).
pub fn tmp(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("bf-plot-test-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
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
    let (s, c) = a.sin_cos();
    [[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]]
}
