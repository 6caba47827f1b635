//! Mode dynamics (paper Sect. 2.4 and 2.6).
//!
//! | symbol | paper |
//! |---|---|
//! | [`free`] | eq. 26a–b, 45: λ = 0 |
//! | [`stick`] | eq. 27–34, 46: λ = Γ⁻¹(G M⁻¹ f + ω × ṙ_c − J̇_c q̇), Γ = G M⁻¹ Gᵀ |
//! | [`slip`] | eq. 20, 35–38, 47: λ = λ_n (n + μ_k t̂), λ_n from d/dt(nᵀ J_c q̇) = 0 |
//! | [`slip_law_residual`] | eq. 38a–b / 47b–c (division-free slip law) |
//! | [`ContactForce`] | λ_n (eq. 12), λ_∥ = T_n λ (eq. 15–17), σ (eq. 18) |
//! | [`ContactMatrices`] | M_f⁻¹ J_cᵀ, W = J_c M_f⁻¹ J_cᵀ, Γ = W + S(r_c) I_b⁻¹ S(r_c)ᵀ (eq. 30–34, 41) |
//! | [`normal_acceleration`] | d/dt(n·v_c) = ṅ·v_c + n·(J̇_c q̇ + J_c q̈) (ḧ for eq. 50) |
//! | [`relative_acceleration`] | d/dt Δv = ω̇ × r_c + ω × ṙ_c − J̇_c q̇ − J_c q̈ |
//!
//! The generalised force vector of eq. 32 is f = [C q̇ + μ_v q̇ + g − τ; ω × I_b ω + D ω]; the
//! gyroscopic term uses the full I_b, so it is exact for a non-isotropic ball.
//!
//! Any number of joints N (const parameter, default 3): M_f is N×N (Cholesky, `Spd`), J_c 3×N,
//! M_f⁻¹ J_cᵀ N×3; the contact-space matrices W and Γ stay 3×3 whatever N is, so the stick and
//! slip laws solve the same 3×3 (or scalar) problems. Γ = W + S(r_c) I_b⁻¹ S(r_c)ᵀ stays
//! invertible for N < 3 as long as the finger can move along the normal (nᵀ W n > 0): the
//! ball's rotation supplies the tangential directions. For N = 3 the generic code is the same
//! arithmetic in the same order as a 3×3-only implementation (the types are identical).

use crate::linalg::{Mat3, MatNx3, Spd, Vec3, VecN, skew};
use crate::settings::TransitionSettings;
use crate::{ContactKinematics, Mode, ModelError, PainleveKind, Params, Result};

/// Contact force λ on the finger (world axes) and its decomposition w.r.t. the normal n.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct ContactForce {
    /// λ (N), force exerted by the ball on the finger.
    pub lambda: Vec3,
    /// λ_n = λ·n (eq. 12); the contact is active for λ_n > 0.
    pub lambda_n: f64,
    /// λ_∥ = T_n λ (eq. 15c): friction force.
    pub lambda_t: Vec3,
    /// σ = μ_s λ_n − |λ_∥| (eq. 18); sticking is valid for σ > 0 (eq. 19).
    pub sigma: f64,
}

impl ContactForce {
    /// Decompose λ w.r.t. the unit normal `n` and compute σ with μ_s.
    pub fn new(lambda: Vec3, n: &Vec3, mu_s: f64) -> Self {
        let lambda_n = lambda.dot(n);
        let lambda_t = lambda - n * lambda_n;
        Self {
            lambda,
            lambda_n,
            lambda_t,
            sigma: mu_s * lambda_n - lambda_t.norm(),
        }
    }
}

/// Accelerations and contact force in one mode.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Accelerations<const N: usize = 3> {
    /// The mode these were computed for.
    pub mode: Mode,
    /// q̈ (rad/s²).
    pub qdd: VecN<N>,
    /// ω̇ (rad/s²).
    pub omega_dot: Vec3,
    /// Contact force (zero in free motion).
    pub force: ContactForce,
}

impl<const N: usize> Accelerations<N> {
    /// Writes ẋ = (q̇, q̈, ω̇) in the flat layout of [`crate::State::write_slice`] into `dx`
    /// (length 2N + 3).
    pub fn write_state_derivative(&self, qd: &VecN<N>, dx: &mut [f64]) {
        dx[..N].copy_from_slice(qd.as_slice());
        dx[N..2 * N].copy_from_slice(self.qdd.as_slice());
        dx[2 * N..2 * N + 3].copy_from_slice(self.omega_dot.as_slice());
    }
}

impl Accelerations<3> {
    /// ẋ = (q̇, q̈, ω̇) in the flat layout of [`crate::State::to_array`].
    pub fn state_derivative(&self, qd: &Vec3) -> [f64; 9] {
        let mut d = [0.0; 9];
        d[0..3].copy_from_slice(qd.as_slice());
        d[3..6].copy_from_slice(self.qdd.as_slice());
        d[6..9].copy_from_slice(self.omega_dot.as_slice());
        d
    }
}

/// Matrices of the contact problem at one configuration.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ContactMatrices<const N: usize = 3> {
    /// M_f⁻¹ J_cᵀ (N×3).
    pub minv_jct: MatNx3<N>,
    /// W = J_c M_f⁻¹ J_cᵀ (finger part of Γ; the inverse mass seen at the contact point).
    pub w: Mat3,
    /// Γ = G M⁻¹ Gᵀ = W + S(r_c) I_b⁻¹ S(r_c)ᵀ (eq. 33; the matrix of eq. 41).
    pub gamma: Mat3,
    /// nᵀ W n: normal inverse mass. Γ is singular iff this vanishes (I_b SPD).
    pub n_w_n: f64,
}

/// Cholesky of M_f, with typed errors.
pub(crate) fn factor_mass<const N: usize>(kin: &ContactKinematics<N>) -> Result<Spd<N>> {
    kin.check_finite()?;
    let m = &kin.m_f;
    let asym = (m - m.transpose()).amax();
    if asym > 1e-9 * m.amax() {
        return Err(ModelError::MassMatrixNotPositiveDefinite);
    }
    Spd::factor(m)
        .filter(|c| c.rcond > 1e-14)
        .ok_or(ModelError::MassMatrixNotPositiveDefinite)
}

/// Error unless |h| ≤ contact tolerance.
pub(crate) fn require_contact<const N: usize>(
    kin: &ContactKinematics<N>,
    params: &Params,
    settings: &TransitionSettings,
) -> Result<()> {
    let tol = settings.contact_tolerance * params.ball_radius();
    if kin.contact.h.abs() <= tol {
        Ok(())
    } else {
        Err(ModelError::NotInContact {
            h: kin.contact.h,
            tolerance: tol,
        })
    }
}

/// Compute W, Γ and M_f⁻¹ J_cᵀ; also returns the M_f factorisation.
pub(crate) fn matrices_with_mass<const N: usize>(
    kin: &ContactKinematics<N>,
    params: &Params,
) -> Result<(ContactMatrices<N>, Spd<N>)> {
    let chol = factor_mass(kin)?;
    let jc = &kin.contact.j_c;
    let minv_jct = chol.solve_mat(&jc.transpose());
    let w = jc * minv_jct;
    let w = (w + w.transpose()) * 0.5;
    let s = skew(&kin.contact.r_c);
    let gamma = w + s * params.ball_inertia_inv() * s.transpose();
    let gamma = (gamma + gamma.transpose()) * 0.5;
    let n = &kin.contact.n;
    let n_w_n = n.dot(&(w * n));
    Ok((
        ContactMatrices {
            minv_jct,
            w,
            gamma,
            n_w_n,
        },
        chol,
    ))
}

/// Contact matrices (W, Γ, M_f⁻¹ J_cᵀ) at the configuration of `kin`.
pub fn contact_matrices<const N: usize>(
    kin: &ContactKinematics<N>,
    params: &Params,
) -> Result<ContactMatrices<N>> {
    matrices_with_mass(kin, params).map(|(m, _)| m)
}

/// Factor Γ, or `SingularContact` when its reciprocal condition is below the threshold.
pub(crate) fn factor_gamma<const N: usize>(
    mats: &ContactMatrices<N>,
    settings: &TransitionSettings,
) -> Result<Spd<3>> {
    match Spd::factor(&mats.gamma) {
        Some(c) if c.rcond > settings.singular_rcond => Ok(c),
        Some(c) => Err(ModelError::SingularContact { rcond: c.rcond }),
        None => Err(ModelError::SingularContact { rcond: 0.0 }),
    }
}

/// Error unless nᵀ W n is a safe fraction of ‖W‖ (the normal direction is controllable).
pub(crate) fn require_normal_mobility<const N: usize>(
    mats: &ContactMatrices<N>,
    settings: &TransitionSettings,
) -> Result<()> {
    let scale = mats.w.norm();
    let rc = if scale > 0.0 { mats.n_w_n / scale } else { 0.0 };
    if rc.is_finite() && rc > settings.singular_rcond {
        Ok(())
    } else {
        Err(ModelError::SingularContact { rcond: rc.max(0.0) })
    }
}

/// Joint-space generalised force without contact, f_q = C q̇ + μ_v q̇ + g − τ (eq. 32, top).
fn f_finger<const N: usize>(kin: &ContactKinematics<N>, params: &Params, tau: &VecN<N>) -> VecN<N> {
    kin.cqd_g + kin.state.qd * params.mu_v() - tau
}

/// Ball generalised force f_b = ω × I_b ω + D ω (eq. 32, bottom).
fn f_ball<const N: usize>(kin: &ContactKinematics<N>, params: &Params) -> Vec3 {
    let w = &kin.state.omega;
    w.cross(&(params.ball_inertia() * w)) + w * params.socket_damping()
}

fn check_tau<const N: usize>(tau: &VecN<N>) -> Result<()> {
    if tau.iter().all(|v| v.is_finite()) {
        Ok(())
    } else {
        Err(ModelError::NonFinite { what: "torque" })
    }
}

/// Accelerations for a given contact force λ on the finger (eq. 29 / 31 / 44):
/// q̈ = M_f⁻¹(τ − C q̇ − μ_v q̇ − g + J_cᵀ λ), ω̇ = I_b⁻¹(−ω × I_b ω − D ω − r_c × λ).
pub fn accelerations_with_force<const N: usize>(
    kin: &ContactKinematics<N>,
    params: &Params,
    tau: &VecN<N>,
    lambda: &Vec3,
) -> Result<(VecN<N>, Vec3)> {
    check_tau(tau)?;
    let chol = factor_mass(kin)?;
    Ok(accel_from_force(kin, params, tau, lambda, &chol))
}

fn accel_from_force<const N: usize>(
    kin: &ContactKinematics<N>,
    params: &Params,
    tau: &VecN<N>,
    lambda: &Vec3,
    chol: &Spd<N>,
) -> (VecN<N>, Vec3) {
    let qdd = chol.solve(&(kin.contact.j_c.transpose() * lambda - f_finger(kin, params, tau)));
    let omega_dot =
        params.ball_inertia_inv() * (-f_ball(kin, params) - kin.contact.r_c.cross(lambda));
    (qdd, omega_dot)
}

/// Free motion (eq. 26): λ = 0. Needs no contact (h is ignored).
pub fn free<const N: usize>(
    kin: &ContactKinematics<N>,
    params: &Params,
    tau: &VecN<N>,
) -> Result<Accelerations<N>> {
    let (qdd, omega_dot) = accelerations_with_force(kin, params, tau, &Vec3::zeros())?;
    Ok(Accelerations {
        mode: Mode::Free,
        qdd,
        omega_dot,
        force: ContactForce::default(),
    })
}

/// Sticking (eq. 29, 33): λ from d/dt(G [q̇; ω]) = 0, i.e.
/// Γ λ = G M⁻¹ f − Ġ [q̇; ω] = J_c M_f⁻¹ f_q + r_c × (I_b⁻¹ f_b) − J̇_c q̇ − ṙ_c × ω.
///
/// Errors: `NotInContact` if |h| is beyond the tolerance, `SingularContact` if Γ is singular.
/// The sign of λ_n and σ are reported, not enforced (validity is the caller's business,
/// see [`crate::transitions`]).
pub fn stick<const N: usize>(
    kin: &ContactKinematics<N>,
    params: &Params,
    tau: &VecN<N>,
    settings: &TransitionSettings,
) -> Result<Accelerations<N>> {
    check_tau(tau)?;
    require_contact(kin, params, settings)?;
    let (mats, chol) = matrices_with_mass(kin, params)?;
    let gchol = factor_gamma(&mats, settings)?;
    let c = &kin.contact;
    let fq = f_finger(kin, params, tau);
    let fb = f_ball(kin, params);
    let rhs = c.j_c * chol.solve(&fq) + c.r_c.cross(&(params.ball_inertia_inv() * fb))
        - c.jc_dot_qd
        - c.rc_dot.cross(&kin.state.omega);
    let lambda = gchol.solve(&rhs);
    let (qdd, omega_dot) = accel_from_force(kin, params, tau, &lambda, &chol);
    Ok(Accelerations {
        mode: Mode::Stick,
        qdd,
        omega_dot,
        force: ContactForce::new(lambda, &c.n, params.mu_s()),
    })
}

/// Unit slip direction t̂ = T_n Δv / |T_n Δv|, or the normalised tangential part of `hint` when
/// |T_n Δv| ≤ `settings.slip_direction_tol` (eq. 20 is undefined at Δv = 0; at the onset of
/// slip the direction of the sticking friction force λ_∥ is the natural hint, Sect. 2.4.2).
pub fn slip_direction<const N: usize>(
    kin: &ContactKinematics<N>,
    settings: &TransitionSettings,
    hint: Option<&Vec3>,
) -> Result<Vec3> {
    let n = &kin.contact.n;
    let dv_t = kin.contact.delta_v - n * n.dot(&kin.contact.delta_v);
    let speed = dv_t.norm();
    if speed > settings.slip_direction_tol {
        return Ok(dv_t / speed);
    }
    if let Some(h) = hint {
        let ht = h - n * n.dot(h);
        let hn = ht.norm();
        if hn.is_finite() && hn > 0.0 {
            return Ok(ht / hn);
        }
    }
    Err(ModelError::UndefinedSlipDirection {
        tangential_speed: speed,
    })
}

/// Slipping (eq. 37, 20): λ = λ_n (n + μ_k t̂) with t̂ from [`slip_direction`], λ_n from the
/// normal constraint d/dt(nᵀ J_c q̇) = 0 (derivative of eq. 36):
/// a_free + k λ_n = 0 with k = nᵀ W (n + μ_k t̂), a_free = ṅ·v_c + n·J̇_c q̇ − nᵀ J_c M_f⁻¹ f_q.
///
/// Errors: `NotInContact`, `SingularContact` (nᵀ W n ≈ 0), `UndefinedSlipDirection`, and
/// `Painleve` when k ≤ `painleve_margin`·nᵀ W n (Sect. 7: no or several solutions).
pub fn slip<const N: usize>(
    kin: &ContactKinematics<N>,
    params: &Params,
    tau: &VecN<N>,
    settings: &TransitionSettings,
    direction_hint: Option<&Vec3>,
) -> Result<Accelerations<N>> {
    check_tau(tau)?;
    require_contact(kin, params, settings)?;
    let (mats, chol) = matrices_with_mass(kin, params)?;
    require_normal_mobility(&mats, settings)?;
    let t_hat = slip_direction(kin, settings, direction_hint)?;
    let c = &kin.contact;
    let n = &c.n;
    let d = n + t_hat * params.mu_k();
    let k = n.dot(&(mats.w * d));
    let a_free = c.n_dot().dot(&c.v_c) + n.dot(&c.jc_dot_qd)
        - n.dot(&(c.j_c * chol.solve(&f_finger(kin, params, tau))));
    if k.is_nan() || k <= settings.painleve_margin * mats.n_w_n {
        let kind = if a_free < 0.0 {
            PainleveKind::Inconsistent
        } else {
            PainleveKind::NonUnique
        };
        return Err(ModelError::Painleve {
            kind,
            effective_inverse_mass: k,
            free_normal_acceleration: a_free,
        });
    }
    let lambda_n = -a_free / k;
    let lambda = d * lambda_n;
    let (qdd, omega_dot) = accel_from_force(kin, params, tau, &lambda, &chol);
    Ok(Accelerations {
        mode: Mode::Slip,
        qdd,
        omega_dot,
        force: ContactForce::new(lambda, n, params.mu_s()),
    })
}

/// Residual of the division-free slip law (eq. 38a–b, 47b–c):
/// [λ·Δv − |Δv| μ_k λ·n,  (n × Δv)·λ]. Zero for the λ of [`slip`] (with Δv tangential), and
/// well defined (→ 0) as Δv → 0.
pub fn slip_law_residual(lambda: &Vec3, n: &Vec3, delta_v: &Vec3, mu_k: f64) -> [f64; 2] {
    [
        lambda.dot(delta_v) - delta_v.norm() * mu_k * lambda.dot(n),
        n.cross(delta_v).dot(lambda),
    ]
}

/// Dispatch on the mode: [`free`], [`stick`] or [`slip`] (slip without a direction hint).
pub fn accelerations<const N: usize>(
    mode: Mode,
    kin: &ContactKinematics<N>,
    params: &Params,
    tau: &VecN<N>,
    settings: &TransitionSettings,
) -> Result<Accelerations<N>> {
    match mode {
        Mode::Free => free(kin, params, tau),
        Mode::Stick => stick(kin, params, tau, settings),
        Mode::Slip => slip(kin, params, tau, settings, None),
    }
}

/// Normal constraint acceleration d/dt(n·v_c) = ṅ·v_c + n·(J̇_c q̇ + J_c q̈).
///
/// With the exact saturation n·ṙ_c ≡ n·v_c (eq. 1: n ⟂ e_x3 inside the segment, ṡat = 0 at its
/// ends), so this is ḧ, the quantity of eq. 50; it vanishes in stick and slip.
pub fn normal_acceleration<const N: usize>(kin: &ContactKinematics<N>, qdd: &VecN<N>) -> f64 {
    let c = &kin.contact;
    c.n_dot().dot(&c.v_c) + c.n.dot(&(c.jc_dot_qd + c.j_c * qdd))
}

/// d/dt Δv = ω̇ × r_c + ω × ṙ_c − J̇_c q̇ − J_c q̈ (time derivative of eq. 13).
pub fn relative_acceleration<const N: usize>(
    kin: &ContactKinematics<N>,
    qdd: &VecN<N>,
    omega_dot: &Vec3,
) -> Vec3 {
    let c = &kin.contact;
    omega_dot.cross(&c.r_c) + kin.state.omega.cross(&c.rc_dot) - c.jc_dot_qd - c.j_c * qdd
}
