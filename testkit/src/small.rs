//! Tiny fixed-size linear algebra, generic over the scalar, for the reference implementation.
//!
//! Everything is written over [`Real`] (= `num_dual::DualNum<Primitive = f64> + Copy`) so the
//! same kinematics code runs on `f64` and on dual numbers; the dual runs give *exact* first
//! derivatives (∂M/∂q, g = ∂U/∂q, J̇ q̇, ṙ_c, ...) without finite-difference error.
//! Homogeneous transforms are plain row-major 4×4 arrays (paper Sect. 2.1: DH frames and the
//! base transform), vectors are `[T; 3]`, rotations `[[T; 3]; 3]` (row-major).

use num_dual::DualNum;

/// Scalar type of the reference: `f64` itself or a `num_dual` number over `f64`.
pub trait Real: DualNum<Primitive = f64> + Copy {}
impl<T: DualNum<Primitive = f64> + Copy> Real for T {}

/// A 3-vector.
pub type V3<T> = [T; 3];
/// A row-major 3×3 matrix.
pub type M3<T> = [[T; 3]; 3];
/// A row-major 4×4 homogeneous transform.
pub type H4<T> = [[T; 4]; 4];

/// Lift an `f64` constant into the scalar type.
#[inline]
pub fn k<T: Real>(x: f64) -> T {
    T::from(x)
}

/// Real (value) part of a scalar.
#[inline]
pub fn re<T: Real>(x: T) -> f64 {
    x.re()
}

/// Zero vector.
pub fn zero3<T: Real>() -> V3<T> {
    [k(0.0); 3]
}

/// Lift an `f64` vector.
pub fn lift3<T: Real>(v: [f64; 3]) -> V3<T> {
    [k(v[0]), k(v[1]), k(v[2])]
}

/// Lift an `f64` matrix.
pub fn lift33<T: Real>(m: [[f64; 3]; 3]) -> M3<T> {
    [lift3(m[0]), lift3(m[1]), lift3(m[2])]
}

/// a + b.
pub fn add<T: Real>(a: V3<T>, b: V3<T>) -> V3<T> {
    [a[0] + b[0], a[1] + b[1], a[2] + b[2]]
}

/// a − b.
pub fn sub<T: Real>(a: V3<T>, b: V3<T>) -> V3<T> {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

/// s · a.
pub fn scale<T: Real>(s: T, a: V3<T>) -> V3<T> {
    [s * a[0], s * a[1], s * a[2]]
}

/// a · b.
pub fn dot<T: Real>(a: V3<T>, b: V3<T>) -> T {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

/// a × b.
pub fn cross<T: Real>(a: V3<T>, b: V3<T>) -> V3<T> {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

/// Euclidean norm.
pub fn norm<T: Real>(a: V3<T>) -> T {
    dot(a, a).sqrt()
}

/// m v.
pub fn matvec<T: Real>(m: &M3<T>, v: V3<T>) -> V3<T> {
    [dot(m[0], v), dot(m[1], v), dot(m[2], v)]
}

/// a b (3×3).
pub fn matmul<T: Real>(a: &M3<T>, b: &M3<T>) -> M3<T> {
    let mut out = [[k(0.0); 3]; 3];
    for i in 0..3 {
        for j in 0..3 {
            out[i][j] = a[i][0] * b[0][j] + a[i][1] * b[1][j] + a[i][2] * b[2][j];
        }
    }
    out
}

/// mᵀ.
pub fn transpose<T: Real>(m: &M3<T>) -> M3<T> {
    let mut out = *m;
    for i in 0..3 {
        for j in 0..3 {
            out[i][j] = m[j][i];
        }
    }
    out
}

/// Column `j` of a 3×3 matrix.
pub fn col<T: Real>(m: &M3<T>, j: usize) -> V3<T> {
    [m[0][j], m[1][j], m[2][j]]
}

/// 4×4 identity.
pub fn eye4<T: Real>() -> H4<T> {
    let mut out = [[k(0.0); 4]; 4];
    for (i, row) in out.iter_mut().enumerate() {
        row[i] = k(1.0);
    }
    out
}

/// a b (4×4).
pub fn mul4<T: Real>(a: &H4<T>, b: &H4<T>) -> H4<T> {
    let mut out = [[k(0.0); 4]; 4];
    for i in 0..4 {
        for j in 0..4 {
            let mut s = a[i][0] * b[0][j];
            for l in 1..4 {
                s += a[i][l] * b[l][j];
            }
            out[i][j] = s;
        }
    }
    out
}

/// Homogeneous transform from a rotation and a translation.
pub fn h_from<T: Real>(r: &M3<T>, t: V3<T>) -> H4<T> {
    let mut out = eye4();
    for i in 0..3 {
        for j in 0..3 {
            out[i][j] = r[i][j];
        }
        out[i][3] = t[i];
    }
    out
}

/// Rotation block of a homogeneous transform.
pub fn h_rot<T: Real>(h: &H4<T>) -> M3<T> {
    [
        [h[0][0], h[0][1], h[0][2]],
        [h[1][0], h[1][1], h[1][2]],
        [h[2][0], h[2][1], h[2][2]],
    ]
}

/// Translation of a homogeneous transform.
pub fn h_pos<T: Real>(h: &H4<T>) -> V3<T> {
    [h[0][3], h[1][3], h[2][3]]
}

/// Elementary rotation about z given (sin, cos).
pub fn rot_z<T: Real>(s: T, c: T) -> H4<T> {
    let mut h = eye4();
    h[0][0] = c;
    h[0][1] = -s;
    h[1][0] = s;
    h[1][1] = c;
    h
}

/// Elementary rotation about x given (sin, cos).
pub fn rot_x<T: Real>(s: T, c: T) -> H4<T> {
    let mut h = eye4();
    h[1][1] = c;
    h[1][2] = -s;
    h[2][1] = s;
    h[2][2] = c;
    h
}

/// Elementary translation along x.
pub fn trans_x<T: Real>(a: T) -> H4<T> {
    let mut h = eye4();
    h[0][3] = a;
    h
}

/// Elementary translation along z.
pub fn trans_z<T: Real>(d: T) -> H4<T> {
    let mut h = eye4();
    h[2][3] = d;
    h
}

/// (sin, cos) of a constant angle, exact (0, ±1) at multiples of π/2 so that e.g. α = π/2
/// yields the exact zeros the generator folds; other angles use the libm values.
pub fn sin_cos_const(x: f64) -> (f64, f64) {
    let quarter = x / std::f64::consts::FRAC_PI_2;
    let kq = quarter.round();
    if (quarter - kq).abs() <= 4.0 * f64::EPSILON * quarter.abs().max(1.0) {
        match (kq as i64).rem_euclid(4) {
            0 => (0.0, 1.0),
            1 => (1.0, 0.0),
            2 => (0.0, -1.0),
            _ => (-1.0, 0.0),
        }
    } else {
        libm::sincos(x)
    }
}

/// Elementary rotation matrix about a principal axis (0 = x, 1 = y, 2 = z), in f64.
pub fn axis_rotation(axis: usize, angle: f64) -> [[f64; 3]; 3] {
    let (s, c) = sin_cos_const(angle);
    match axis {
        0 => [[1.0, 0.0, 0.0], [0.0, c, -s], [0.0, s, c]],
        1 => [[c, 0.0, s], [0.0, 1.0, 0.0], [-s, 0.0, c]],
        _ => [[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]],
    }
}

/// Solves the 3×3 system m x = b by Cramer's rule (for the small, well-conditioned mass
/// matrices of the tests; no pivoting).
pub fn solve3<T: Real>(m: &M3<T>, b: &V3<T>) -> V3<T> {
    let det = |a: &M3<T>| {
        a[0][0] * (a[1][1] * a[2][2] - a[1][2] * a[2][1])
            - a[0][1] * (a[1][0] * a[2][2] - a[1][2] * a[2][0])
            + a[0][2] * (a[1][0] * a[2][1] - a[1][1] * a[2][0])
    };
    let d = det(m);
    let mut x = zero3();
    for c in 0..3 {
        let mut a = *m;
        for r in 0..3 {
            a[r][c] = b[r];
        }
        x[c] = det(&a) / d;
    }
    x
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn exact_quarter_turns_and_generic_angles() {
        assert_eq!(sin_cos_const(std::f64::consts::FRAC_PI_2), (1.0, 0.0));
        assert_eq!(sin_cos_const(-std::f64::consts::FRAC_PI_2), (-1.0, 0.0));
        assert_eq!(sin_cos_const(std::f64::consts::PI), (0.0, -1.0));
        assert_eq!(sin_cos_const(0.0), (0.0, 1.0));
        let (s, c) = sin_cos_const(0.3);
        assert_eq!((s, c), libm::sincos(0.3f64));
    }

    #[test]
    fn axis_rotation_matches_right_hand_rule() {
        // R_y(-π/2) of docs/parameters.md: [[0,0,-1],[0,1,0],[1,0,0]].
        let r = axis_rotation(1, -std::f64::consts::FRAC_PI_2);
        assert_eq!(r, [[0.0, 0.0, -1.0], [0.0, 1.0, 0.0], [1.0, 0.0, 0.0]]);
        // R_z(θ) e_x = (cos θ, sin θ, 0) and cross product e_x × e_y = e_z.
        let rz = axis_rotation(2, 0.7);
        let v = matvec(&rz, [1.0, 0.0, 0.0]);
        assert!(
            (v[0] - libm::cos(0.7f64)).abs() < 1e-15 && (v[1] - libm::sin(0.7f64)).abs() < 1e-15
        );
        assert_eq!(cross([1.0, 0.0, 0.0], [0.0, 1.0, 0.0]), [0.0, 0.0, 1.0]);
    }

    #[test]
    fn solve3_recovers_the_solution_of_a_symmetric_positive_definite_system() {
        let m: M3<f64> = [[2.0, 0.3, -0.1], [0.3, 1.5, 0.2], [-0.1, 0.2, 0.8]];
        let want: V3<f64> = [0.4, -1.2, 2.5];
        let x = solve3(&m, &matvec(&m, want));
        for i in 0..3 {
            assert!((x[i] - want[i]).abs() < 1e-14, "{x:?} vs {want:?}");
        }
    }
}
