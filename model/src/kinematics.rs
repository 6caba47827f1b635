//! Evaluated kinematics at one state: the inputs of every physics function.
//!
//! | field | paper |
//! |---|---|
//! | `m_f` | M_f(q), eq. 22a / 24 |
//! | `cqd_g` | C(q, q̇) q̇ + g(q), eq. 24 (Christoffel C, g = ∂U/∂q) |
//! | `potential` | U_f(q), eq. 22b |
//! | `contact.alpha`, `sat_alpha`, `p_c`, `r_c` | eq. 2–3 |
//! | `contact.h`, `h_dot` | eq. 4 and its time derivative n·ṙ_c |
//! | `contact.n` | eq. 11 |
//! | `contact.j_c`, `v_c` | eq. 6–7 |
//! | `contact.delta_v` | eq. 13 |
//! | `contact.rc_dot`, `jc_dot_qd` | ṙ_c and J̇_c q̇ in the bias of eq. 33 |
//!
//! Both structs are generic over the number of joints `N` (default 3): M_f is N×N, C q̇ + g an
//! N-vector and J_c 3×N; every other contact quantity lives in world space (3-D).

use crate::linalg::{Mat3xN, MatN, Vec3, VecN, mat_from_rows};
use crate::{ModelError, Result, State};

/// Contact geometry of eq. 2–13 at one state (a copy of the generated `Contact` struct with
/// nalgebra types). λ-free: it depends on (q, q̇, ω) only.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ContactGeometry<const N: usize = 3> {
    /// α = (o_b − p_e)·e_x3 (eq. 2).
    pub alpha: f64,
    /// sat(α) (exact or smooth, eq. 3 / 58–59).
    pub sat_alpha: f64,
    /// Closest point of the last link to the ball, p_c (eq. 3).
    pub p_c: Vec3,
    /// r_c = p_c − o_b.
    pub r_c: Vec3,
    /// Signed distance h = |r_c| − r (eq. 4).
    pub h: f64,
    /// Outward normal n = r_c/|r_c| (eq. 11).
    pub n: Vec3,
    /// Contact Jacobian J_c (eq. 7), 3×NQ.
    pub j_c: Mat3xN<N>,
    /// v_c = J_c q̇ (eq. 6).
    pub v_c: Vec3,
    /// Δv = ω × r_c − v_c (eq. 13).
    pub delta_v: Vec3,
    /// ḣ = n·ṙ_c.
    pub h_dot: f64,
    /// ṙ_c (includes d sat(α)/dt).
    pub rc_dot: Vec3,
    /// J̇_c q̇ (includes d sat(α)/dt), eq. 33.
    pub jc_dot_qd: Vec3,
}

impl<const N: usize> Default for ContactGeometry<N> {
    fn default() -> Self {
        Self {
            alpha: 0.0,
            sat_alpha: 0.0,
            p_c: Vec3::zeros(),
            r_c: Vec3::zeros(),
            h: 0.0,
            n: Vec3::zeros(),
            j_c: Mat3xN::<N>::zeros(),
            v_c: Vec3::zeros(),
            delta_v: Vec3::zeros(),
            h_dot: 0.0,
            rc_dot: Vec3::zeros(),
            jc_dot_qd: Vec3::zeros(),
        }
    }
}

impl<const N: usize> ContactGeometry<N> {
    /// Fill from the row-major arrays of a generated `Contact` struct.
    pub fn from_arrays(
        alpha: f64,
        sat_alpha: f64,
        p_c: &[f64; 3],
        r_c: &[f64; 3],
        h: f64,
        n: &[f64; 3],
        j_c: &[[f64; N]; 3],
        v_c: &[f64; 3],
        delta_v: &[f64; 3],
        h_dot: f64,
        rc_dot: &[f64; 3],
        jc_dot_qd: &[f64; 3],
    ) -> Self {
        let v = |a: &[f64; 3]| Vec3::new(a[0], a[1], a[2]);
        Self {
            alpha,
            sat_alpha,
            p_c: v(p_c),
            r_c: v(r_c),
            h,
            n: v(n),
            j_c: mat_from_rows(j_c),
            v_c: v(v_c),
            delta_v: v(delta_v),
            h_dot,
            rc_dot: v(rc_dot),
            jc_dot_qd: v(jc_dot_qd),
        }
    }

    /// Whether every field is finite.
    pub fn is_finite(&self) -> bool {
        [self.alpha, self.sat_alpha, self.h, self.h_dot]
            .iter()
            .all(|v| v.is_finite())
            && [
                self.p_c,
                self.r_c,
                self.n,
                self.v_c,
                self.delta_v,
                self.rc_dot,
                self.jc_dot_qd,
            ]
            .iter()
            .all(|v| v.iter().all(|x| x.is_finite()))
            && self.j_c.iter().all(|x| x.is_finite())
    }

    /// n·v_c = nᵀ J_c q̇ (eq. 36): the normal velocity of the finger at the contact point.
    pub fn normal_velocity(&self) -> f64 {
        self.n.dot(&self.v_c)
    }

    /// ṅ = T_n ṙ_c / |r_c|.
    pub fn n_dot(&self) -> Vec3 {
        let rn = self.r_c.norm();
        (self.rc_dot - self.n * self.n.dot(&self.rc_dot)) / rn
    }
}

/// Everything the physics needs at one state x = (q, q̇, ω).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ContactKinematics<const N: usize = 3> {
    /// The state at which the kernels were evaluated.
    pub state: State<N>,
    /// Finger mass matrix M_f(q).
    pub m_f: MatN<N>,
    /// C(q, q̇) q̇ + g(q) (without μ_v q̇).
    pub cqd_g: VecN<N>,
    /// Finger potential energy U_f(q) (J).
    pub potential: f64,
    /// Contact geometry.
    pub contact: ContactGeometry<N>,
}

impl<const N: usize> ContactKinematics<N> {
    /// Error if any kernel output is NaN/inf (a non-finite state gives NonFinite "state").
    pub fn check_finite(&self) -> Result<()> {
        self.state.check_finite()?;
        if !self.m_f.iter().all(|v| v.is_finite()) {
            return Err(ModelError::NonFinite {
                what: "mass matrix",
            });
        }
        if !self.cqd_g.iter().all(|v| v.is_finite()) || !self.potential.is_finite() {
            return Err(ModelError::NonFinite {
                what: "C qd + g or potential",
            });
        }
        if !self.contact.is_finite() {
            return Err(ModelError::NonFinite {
                what: "contact geometry",
            });
        }
        Ok(())
    }
}
