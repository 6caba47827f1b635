//! Small numerics shared by the probes: the normwise relative error every row reports (its
//! maxima NaN-propagating, [`crate::pipeline::verify::nan_max`], so a NaN can never hide behind
//! `f64::max`), and the spectra of 3×3 matrices (SPD checks of M, eq. 22a; rank of J_c, eq. 7).

use crate::pipeline::verify::nan_max;

use bf_model::Mat3;

/// Normwise relative error max|a − b| / max|b| (b is the reference); NaN anywhere gives NaN.
pub fn rel_err(a: &[f64], b: &[f64]) -> f64 {
    let num = a
        .iter()
        .zip(b)
        .map(|(x, y)| (x - y).abs())
        .fold(0.0, nan_max);
    let den = b.iter().map(|y| y.abs()).fold(0.0, nan_max);
    if num == 0.0 { 0.0 } else { num / den }
}

pub(super) fn all_finite(v: &[f64]) -> bool {
    v.iter().all(|x| x.is_finite())
}

fn mat_rows(m: &[f64]) -> Mat3 {
    Mat3::from_row_slice(m)
}

/// Eigenvalues of the symmetric part of a 3×3 row-major matrix, ascending.
pub(super) fn sym_eigenvalues(m: &[f64]) -> [f64; 3] {
    let a = mat_rows(m);
    let a = (a + a.transpose()) * 0.5;
    let mut e: Vec<f64> = a.symmetric_eigenvalues().iter().copied().collect();
    e.sort_by(f64::total_cmp);
    [e[0], e[1], e[2]]
}

/// Singular values of a 3×3 matrix, ascending.
pub(super) fn singular_values(m: &Mat3) -> [f64; 3] {
    let mut s: Vec<f64> = m.singular_values().iter().copied().collect();
    s.sort_by(f64::total_cmp);
    [s[0], s[1], s[2]]
}

pub(super) fn flat3(m: &[[f64; 3]; 3]) -> Vec<f64> {
    m.iter().flatten().copied().collect()
}
