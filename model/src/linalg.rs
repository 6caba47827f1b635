//! Small helpers: skew matrix S(·) (eq. 6), projectors P_n and T_n (eq. 15–17), a symmetric
//! positive definite N×N solve with a conditioning estimate ([`Spd`]: the finger's M_f with N
//! joints, Γ and I_b with N = 3), and array conversions.

use nalgebra::{Matrix3, SMatrix, SVector, Vector3};

/// 3-vector of f64 (world axes unless stated otherwise).
pub type Vec3 = Vector3<f64>;
/// 3×3 matrix of f64.
pub type Mat3 = Matrix3<f64>;
/// Joint-space vector of a finger with `N` joints (q, q̇, τ); [`Vec3`] for N = 3.
pub type VecN<const N: usize> = SVector<f64, N>;
/// N×N joint-space matrix (M_f); [`Mat3`] for N = 3.
pub type MatN<const N: usize> = SMatrix<f64, N, N>;
/// 3×N matrix (the contact Jacobian J_c of eq. 7).
pub type Mat3xN<const N: usize> = SMatrix<f64, 3, N>;
/// N×3 matrix (M_f⁻¹ J_cᵀ).
pub type MatNx3<const N: usize> = SMatrix<f64, N, 3>;

/// Skew-symmetric matrix S(a) with S(a) b = a × b (paper eq. 6).
pub fn skew(a: &Vec3) -> Mat3 {
    Mat3::new(0.0, -a.z, a.y, a.z, 0.0, -a.x, -a.y, a.x, 0.0)
}

/// P_n = n ⊗ n (eq. 16): projection onto the normal.
pub fn normal_projector(n: &Vec3) -> Mat3 {
    n * n.transpose()
}

/// T_n = 1 − P_n (eq. 17): projection onto the tangent plane.
pub fn tangent_projector(n: &Vec3) -> Mat3 {
    Mat3::identity() - normal_projector(n)
}

/// Row-major nested array → matrix (R rows of C entries).
pub(crate) fn mat_from_rows<const R: usize, const C: usize>(
    a: &[[f64; C]; R],
) -> SMatrix<f64, R, C> {
    SMatrix::from_fn(|i, j| a[i][j])
}

/// Cholesky factor of a symmetric positive definite N×N matrix with a cheap reciprocal
/// condition estimate. `None` if not positive definite.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Spd<const N: usize> {
    l: MatN<N>,
    /// Reciprocal condition estimate N / (‖A‖_F ‖A⁻¹‖_F) ∈ (0, 1] (1 for a multiple of the
    /// identity; within a factor N of the 2-norm reciprocal condition number).
    pub rcond: f64,
}

/// The 3×3 factorisation (Γ, I_b, and M_f of a 3-joint finger).
pub(crate) type Spd3 = Spd<3>;

impl<const N: usize> Spd<N> {
    /// Factor `a` (only the lower triangle is read).
    pub fn factor(a: &MatN<N>) -> Option<Self> {
        let mut l = MatN::<N>::zeros();
        for j in 0..N {
            let mut d = a[(j, j)];
            for k in 0..j {
                d -= l[(j, k)] * l[(j, k)];
            }
            if d.is_nan() || d <= 0.0 {
                return None;
            }
            let djj = d.sqrt();
            l[(j, j)] = djj;
            for i in (j + 1)..N {
                let mut s = a[(i, j)];
                for k in 0..j {
                    s -= l[(i, k)] * l[(j, k)];
                }
                l[(i, j)] = s / djj;
            }
        }
        let mut out = Self { l, rcond: 0.0 };
        let inv = out.solve_mat(&MatN::<N>::identity());
        let lower_norm = {
            // ‖A‖_F from the lower triangle only (A is symmetric by contract).
            let mut s = 0.0;
            for i in 0..N {
                for j in 0..N {
                    let v = if j <= i { a[(i, j)] } else { a[(j, i)] };
                    s += v * v;
                }
            }
            s.sqrt()
        };
        out.rcond = N as f64 / (lower_norm * inv.norm());
        if !out.rcond.is_finite() {
            return None;
        }
        Some(out)
    }

    /// Solve A x = b.
    pub fn solve(&self, b: &VecN<N>) -> VecN<N> {
        let l = &self.l;
        let mut y = VecN::<N>::zeros();
        for i in 0..N {
            let mut s = b[i];
            for k in 0..i {
                s -= l[(i, k)] * y[k];
            }
            y[i] = s / l[(i, i)];
        }
        let mut x = VecN::<N>::zeros();
        for i in (0..N).rev() {
            let mut s = y[i];
            for k in (i + 1)..N {
                s -= l[(k, i)] * x[k];
            }
            x[i] = s / l[(i, i)];
        }
        x
    }

    /// A⁻¹ B column by column.
    pub fn solve_mat<const C: usize>(&self, b: &SMatrix<f64, N, C>) -> SMatrix<f64, N, C> {
        let mut out = SMatrix::<f64, N, C>::zeros();
        for c in 0..C {
            let col = self.solve(&b.column(c).into_owned());
            out.set_column(c, &col);
        }
        out
    }
}

/// An orthonormal basis (t1, t2) of the plane orthogonal to the unit vector `n`.
pub(crate) fn tangent_basis(n: &Vec3) -> (Vec3, Vec3) {
    // Cross with the axis least aligned with n for a well-conditioned first tangent.
    let a = if n.x.abs() <= n.y.abs() && n.x.abs() <= n.z.abs() {
        Vec3::x()
    } else if n.y.abs() <= n.z.abs() {
        Vec3::y()
    } else {
        Vec3::z()
    };
    let t1 = n.cross(&a).normalize();
    let t2 = n.cross(&t1);
    (t1, t2)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn skew_is_cross_product() {
        let a = Vec3::new(0.3, -1.2, 2.0);
        let b = Vec3::new(-0.7, 0.4, 1.1);
        assert!((skew(&a) * b - a.cross(&b)).norm() < 1e-15);
    }

    #[test]
    fn projectors_decompose() {
        let n = Vec3::new(1.0, 2.0, -2.0) / 3.0;
        let f = Vec3::new(0.5, -0.1, 0.9);
        let perp = normal_projector(&n) * f;
        let par = tangent_projector(&n) * f;
        assert!((perp + par - f).norm() < 1e-15);
        assert!(par.dot(&n).abs() < 1e-15);
        // eq. 15c: f_∥ = −n × (n × f)
        assert!((par + n.cross(&n.cross(&f))).norm() < 1e-15);
    }

    #[test]
    fn cholesky_solves_and_rejects_indefinite() {
        let a = Mat3::new(4.0, 1.0, 0.5, 1.0, 3.0, -0.2, 0.5, -0.2, 2.0);
        let f = Spd3::factor(&a).unwrap();
        let b = Vec3::new(1.0, -2.0, 0.3);
        assert!((a * f.solve(&b) - b).norm() < 1e-14);
        let bad = Mat3::new(1.0, 2.0, 0.0, 2.0, 1.0, 0.0, 0.0, 0.0, 1.0);
        assert!(Spd3::factor(&bad).is_none());
    }

    #[test]
    fn tangent_basis_orthonormal() {
        for n in [
            Vec3::x(),
            Vec3::new(0.3, -0.4, 0.866).normalize(),
            -Vec3::z(),
        ] {
            let (t1, t2) = tangent_basis(&n);
            assert!(t1.dot(&n).abs() < 1e-15 && t2.dot(&n).abs() < 1e-15);
            assert!(t1.dot(&t2).abs() < 1e-15);
            assert!((t1.norm() - 1.0).abs() < 1e-15 && (t2.norm() - 1.0).abs() < 1e-15);
        }
    }
}
