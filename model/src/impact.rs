//! Impact laws (paper Sect. 2.5), all with coefficient of restitution 0, so every law ensures
//! n·J_c q̇⁺ = 0. The impulse ι acts on the finger (world axes); the ball receives −ι at r_c:
//! M_f (q̇⁺ − q̇⁻) = J_cᵀ ι (eq. 40a), I_b (ω⁺ − ω⁻) = −r_c × ι (eq. 40b), hence
//! Δv⁺ = Δv⁻ − Γ ι with Γ = G M⁻¹ Gᵀ and the kinetic energy
//! T⁺ = T⁻ − ι·Δv⁻ + ½ ιᵀ Γ ι.
//!
//! | law | paper | how it is solved |
//! |---|---|---|
//! | [`ImpactLaw::Newton`] | eq. 39 | J_c q̇⁺ = T_n J_c q̇⁻ solved for q̇⁺ (J_c square), ω unchanged |
//! | [`ImpactLaw::Stick`] | eq. 40–41 | Γ ι = Δv⁻ |
//! | [`ImpactLaw::MaxDissipation`] | eq. 42 | exact convex SOCP: interior (= sticking impulse if it lies in the cone) or cone boundary by a monotone dual 1-D root find (nested 1-D secular equation) |
//! | [`ImpactLaw::MinRelativeVelocity`] | eq. 43 | closed form: Δv⁺(μ) is a linear-fractional curve, one stationary point |
//! | [`ImpactLaw::NormalImpulse`] | text after eq. 39 | frictionless: ι = ι_n n, ι_n = −n·v_c⁻ / nᵀ W n |
//!
//! Note on eq. 39: the paper says the Newton impulse is perpendicular to the ball and leaves ω
//! unchanged. Keeping the tangential velocity J_c q̇ exactly (eq. 39) in general needs a finger
//! impulse ι = J_c⁻ᵀ M_f (q̇⁺ − q̇⁻) that is *not* perpendicular to n (unless W n ∥ n,
//! W = J_c M_f⁻¹ J_cᵀ), and it need not dissipate energy. We implement eq. 39 literally (ω
//! unchanged, the reported ι is the finger impulse) and document the disagreement: on random
//! approach states of the paper scene it raises the kinetic energy in about 1 case in 6 (by up
//! to ~36 %), and ι is up to ~80° away from n. [`ImpactLaw::NormalImpulse`] is the physically
//! consistent reading of the sentence after eq. 39 (impulse perpendicular to the ball, so ω is
//! unchanged because r_c ∥ n): it always dissipates, but changes the tangential velocity by
//! T_n W n ι_n. It is not in [`ImpactLaw::ALL`] (the paper's four laws).
//!
//! Any number of joints N (default 3): every law works on the 3×3 contact-space matrices W and
//! Γ, so only Newton's law depends on N. Eq. 39 fixes all three components of J_c q̇⁺: for
//! N = 3 it is solved with J_c⁻¹ as above; for N > 3 the solution set is an affine subspace
//! and we take the q̇⁺ closest to q̇⁻ in the kinetic-energy (M_f) norm, q̇⁺ = q̇⁻ + M_f⁻¹ J_cᵀ ι
//! with W ι = −n (n·v_c⁻) (needs W = J_c M_f⁻¹ J_cᵀ nonsingular, i.e. J_c of rank 3).
//!
//! Rank-deficient J_c (N < 3, or a singular posture of any N: W or J_c below
//! `singular_rcond`): the contact point cannot move in every direction, so eq. 39 (normal
//! velocity zero *and* tangential velocity kept) has in general no solution. Restitution 0,
//! n·J_c q̇⁺ = 0, is what the impact must achieve; of the finger velocities that achieve it we
//! take the one closest to q̇⁻ in the kinetic-energy norm (Gauss's least constraint):
//! q̇⁺ = q̇⁻ + M_f⁻¹ J_cᵀ n ι_n, ι_n = −n·v_c⁻ / nᵀ W n, the impulse along n that
//! [`ImpactLaw::NormalImpulse`] applies, ω unchanged as eq. 39 says. It loses
//! ½ (n·v_c⁻)² / nᵀ W n of kinetic energy, never gains. Only a finger that cannot move its
//! contact point along n at all (nᵀ W n ≈ 0) is refused (`SingularContact`); the other laws
//! work on Γ, which the ball's rotation keeps regular for N < 3.

use crate::dynamics::{ContactMatrices, factor_gamma, matrices_with_mass, require_contact};
use crate::linalg::{Mat3, MatN, Spd, Vec3, VecN, tangent_basis};
use crate::settings::TransitionSettings;
use crate::{ContactKinematics, Mode, ModelError, Params, Result};

/// Which impact law to apply (Sect. 2.5). Serialised / parsed in snake_case
/// (`"newton"`, `"stick"`, `"max_dissipation"`, `"min_relative_velocity"`, `"normal_impulse"`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ImpactLaw {
    /// Newton's law, restitution 0 (eq. 39).
    Newton,
    /// Sticking impact, Δv⁺ = 0 (eq. 40–41).
    Stick,
    /// Slipping by maximum dissipation (eq. 42).
    MaxDissipation,
    /// Slipping by minimum post-impact relative velocity (eq. 43).
    MinRelativeVelocity,
    /// Frictionless inelastic impact: ι = ι_n n with n·J_c q̇⁺ = 0; ω is unchanged (r_c ∥ n).
    /// The energy-consistent reading of the text after eq. 39 (see the module docs).
    NormalImpulse,
}

impl ImpactLaw {
    /// The paper's four laws, in paper order.
    pub const ALL: [ImpactLaw; 4] = [
        Self::Newton,
        Self::Stick,
        Self::MaxDissipation,
        Self::MinRelativeVelocity,
    ];

    /// snake_case name (as in scene / CLI options).
    pub fn name(self) -> &'static str {
        match self {
            Self::Newton => "newton",
            Self::Stick => "stick",
            Self::MaxDissipation => "max_dissipation",
            Self::MinRelativeVelocity => "min_relative_velocity",
            Self::NormalImpulse => "normal_impulse",
        }
    }
}

impl std::str::FromStr for ImpactLaw {
    type Err = ModelError;

    fn from_str(s: &str) -> Result<Self> {
        [
            Self::Newton,
            Self::Stick,
            Self::MaxDissipation,
            Self::MinRelativeVelocity,
            Self::NormalImpulse,
        ]
        .into_iter()
        .find(|l| l.name() == s)
        .ok_or_else(|| ModelError::UnknownName {
            what: "impact law",
            name: s.to_string(),
            expected: "newton, stick, max_dissipation, min_relative_velocity, normal_impulse",
        })
    }
}

/// Result of an impact.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ImpactOutcome<const N: usize = 3> {
    /// The law that produced it.
    pub law: ImpactLaw,
    /// q̇⁺.
    pub qd: VecN<N>,
    /// ω⁺.
    pub omega: Vec3,
    /// ι (N s), impulse on the finger.
    pub impulse: Vec3,
    /// ι_n = ι·n.
    pub impulse_n: f64,
    /// ι_∥ = T_n ι.
    pub impulse_t: Vec3,
    /// Δv⁺ = ω⁺ × r_c − J_c q̇⁺.
    pub delta_v: Vec3,
    /// Post-impact mode: `Stick` if |Δv⁺| ≤ `slip_eps`, else `Slip`.
    pub mode: Mode,
    /// T⁺ − T⁻ (J), kinetic energy change of finger + ball.
    pub kinetic_energy_change: f64,
    /// |ι_∥| ≤ μ_s ι_n (eq. 66): friction can support the impulse without slipping.
    pub within_static_cone: bool,
}

/// Kinetic energy ½ q̇ᵀ M_f q̇ + ½ ωᵀ I_b ω.
fn kinetic<const N: usize>(m_f: &MatN<N>, ib: &Mat3, qd: &VecN<N>, w: &Vec3) -> f64 {
    0.5 * qd.dot(&(m_f * qd)) + 0.5 * w.dot(&(ib * w))
}

fn outcome<const N: usize>(
    law: ImpactLaw,
    kin: &ContactKinematics<N>,
    params: &Params,
    settings: &TransitionSettings,
    qd: VecN<N>,
    omega: Vec3,
    impulse: Vec3,
) -> ImpactOutcome<N> {
    let c = &kin.contact;
    let n = &c.n;
    let delta_v = omega.cross(&c.r_c) - c.j_c * qd;
    let impulse_n = impulse.dot(n);
    let impulse_t = impulse - n * impulse_n;
    let t0 = kinetic(
        &kin.m_f,
        params.ball_inertia(),
        &kin.state.qd,
        &kin.state.omega,
    );
    let t1 = kinetic(&kin.m_f, params.ball_inertia(), &qd, &omega);
    ImpactOutcome {
        law,
        qd,
        omega,
        impulse,
        impulse_n,
        impulse_t,
        delta_v,
        mode: if delta_v.norm() <= settings.slip_eps {
            Mode::Stick
        } else {
            Mode::Slip
        },
        kinetic_energy_change: t1 - t0,
        within_static_cone: impulse_t.norm() <= params.mu_s() * impulse_n,
    }
}

/// Apply the impulse ι: q̇⁺ = q̇⁻ + M_f⁻¹ J_cᵀ ι, ω⁺ = ω⁻ − I_b⁻¹ (r_c × ι).
fn apply_impulse<const N: usize>(
    kin: &ContactKinematics<N>,
    params: &Params,
    mats: &ContactMatrices<N>,
    iota: &Vec3,
) -> (VecN<N>, Vec3) {
    let qd = kin.state.qd + mats.minv_jct * iota;
    let omega = kin.state.omega - params.ball_inertia_inv() * kin.contact.r_c.cross(iota);
    (qd, omega)
}

/// Apply `law` at a contact state (|h| within tolerance, n·v_c⁻ ≤ `hdot_eps`).
///
/// Errors: `NotInContact`, `Separating`, `SingularContact` (Γ singular / nᵀ W n ≈ 0),
/// `SingularContactJacobian` (Newton only), `NoConvergence` (max dissipation, not expected).
pub fn impact<const N: usize>(
    kin: &ContactKinematics<N>,
    params: &Params,
    law: ImpactLaw,
    settings: &TransitionSettings,
) -> Result<ImpactOutcome<N>> {
    require_contact(kin, params, settings)?;
    let vn = kin.contact.normal_velocity();
    if vn > settings.hdot_eps {
        return Err(ModelError::Separating {
            normal_velocity: vn,
        });
    }
    let (mats, _) = matrices_with_mass(kin, params)?;
    match law {
        ImpactLaw::Newton => newton(kin, params, &mats, settings),
        ImpactLaw::Stick => {
            let iota = stick_impulse(kin, &mats, settings)?;
            let (qd, w) = apply_impulse(kin, params, &mats, &iota);
            Ok(outcome(law, kin, params, settings, qd, w, iota))
        }
        ImpactLaw::MaxDissipation => {
            crate::dynamics::require_normal_mobility(&mats, settings)?;
            let iota = max_dissipation_impulse(kin, params, &mats)?;
            let (qd, w) = apply_impulse(kin, params, &mats, &iota);
            Ok(outcome(law, kin, params, settings, qd, w, iota))
        }
        ImpactLaw::MinRelativeVelocity => {
            crate::dynamics::require_normal_mobility(&mats, settings)?;
            let iota = min_relative_velocity_impulse(kin, params, &mats, settings)?;
            let (qd, w) = apply_impulse(kin, params, &mats, &iota);
            Ok(outcome(law, kin, params, settings, qd, w, iota))
        }
        ImpactLaw::NormalImpulse => {
            crate::dynamics::require_normal_mobility(&mats, settings)?;
            let n = kin.contact.n;
            let iota = n * (-vn / mats.n_w_n);
            let (qd, w) = apply_impulse(kin, params, &mats, &iota);
            Ok(outcome(law, kin, params, settings, qd, w, iota))
        }
    }
}

/// Sticking impulse ι = Γ⁻¹ Δv⁻ (eq. 41).
fn stick_impulse<const N: usize>(
    kin: &ContactKinematics<N>,
    mats: &ContactMatrices<N>,
    settings: &TransitionSettings,
) -> Result<Vec3> {
    let g = factor_gamma(mats, settings)?;
    Ok(g.solve(&kin.contact.delta_v))
}

/// Velocity projection onto Δv = 0 with the sticking impulse (eq. 40–41), without the
/// approach / separation check (used at Slip→Stick, where n·v_c ≈ 0).
pub(crate) fn project_stick<const N: usize>(
    kin: &ContactKinematics<N>,
    params: &Params,
    settings: &TransitionSettings,
) -> Result<ImpactOutcome<N>> {
    require_contact(kin, params, settings)?;
    let (mats, _) = matrices_with_mass(kin, params)?;
    let iota = stick_impulse(kin, &mats, settings)?;
    let (qd, w) = apply_impulse(kin, params, &mats, &iota);
    Ok(outcome(
        ImpactLaw::Stick,
        kin,
        params,
        settings,
        qd,
        w,
        iota,
    ))
}

/// Apply a given impulse ι at a contact state (used for the Stick→Slip velocity update).
pub(crate) fn apply_given_impulse<const N: usize>(
    kin: &ContactKinematics<N>,
    params: &Params,
    settings: &TransitionSettings,
    iota: &Vec3,
) -> Result<ImpactOutcome<N>> {
    let (mats, _) = matrices_with_mass(kin, params)?;
    let (qd, w) = apply_impulse(kin, params, &mats, iota);
    Ok(outcome(
        ImpactLaw::Stick,
        kin,
        params,
        settings,
        qd,
        w,
        *iota,
    ))
}

/// Newton (eq. 39): J_c q̇⁺ = T_n J_c q̇⁻, ω⁺ = ω⁻ (see the module docs for N ≠ 3).
fn newton<const N: usize>(
    kin: &ContactKinematics<N>,
    params: &Params,
    mats: &ContactMatrices<N>,
    settings: &TransitionSettings,
) -> Result<ImpactOutcome<N>> {
    let c = &kin.contact;
    if N != 3 {
        let Some(w) = Spd::factor(&mats.w).filter(|f| N > 3 && f.rcond > settings.singular_rcond)
        else {
            return newton_rank_deficient(kin, params, mats, settings);
        };
        let iota = w.solve(&(c.n * -c.n.dot(&c.v_c)));
        let qd = kin.state.qd + mats.minv_jct * iota;
        return Ok(outcome(
            ImpactLaw::Newton,
            kin,
            params,
            settings,
            qd,
            kin.state.omega,
            iota,
        ));
    }
    // N = 3: J_c is square; the copies below are exact (same numbers, 3×3 types).
    let jc = Mat3::from_column_slice(c.j_c.as_slice());
    let m_f = Mat3::from_column_slice(kin.m_f.as_slice());
    let qd_minus = Vec3::from_column_slice(kin.state.qd.as_slice());
    let Some(inv) = jc.try_inverse() else {
        return newton_rank_deficient(kin, params, mats, settings);
    };
    let rcond = 1.0 / (jc.norm() * inv.norm());
    if rcond.is_nan() || rcond <= settings.singular_rcond {
        return newton_rank_deficient(kin, params, mats, settings);
    }
    let target = c.v_c - c.n * c.n.dot(&c.v_c);
    // One step of iterative refinement keeps n·J_c q̇⁺ at round-off level for moderate κ(J_c).
    let mut qd = inv * target;
    qd += inv * (target - jc * qd);
    let dq = qd - qd_minus;
    let iota = inv.transpose() * (m_f * dq);
    Ok(outcome(
        ImpactLaw::Newton,
        kin,
        params,
        settings,
        VecN::<N>::from_column_slice(qd.as_slice()),
        kin.state.omega,
        iota,
    ))
}

/// Newton's law where J_c is rank-deficient (see the module docs): the normal velocity is
/// removed by the impulse along n with the least change of kinetic energy, ω unchanged.
fn newton_rank_deficient<const N: usize>(
    kin: &ContactKinematics<N>,
    params: &Params,
    mats: &ContactMatrices<N>,
    settings: &TransitionSettings,
) -> Result<ImpactOutcome<N>> {
    crate::dynamics::require_normal_mobility(mats, settings)?;
    let n = kin.contact.n;
    let iota = n * (-kin.contact.normal_velocity() / mats.n_w_n);
    let qd = kin.state.qd + mats.minv_jct * iota;
    Ok(outcome(
        ImpactLaw::Newton,
        kin,
        params,
        settings,
        qd,
        kin.state.omega,
        iota,
    ))
}

/// Frame (n, t1, t2) as columns.
fn contact_frame(n: &Vec3) -> Mat3 {
    let (t1, t2) = tangent_basis(n);
    Mat3::from_columns(&[*n, t1, t2])
}

/// Maximum-dissipation impulse (eq. 42): minimise T⁺(ι) = T⁻ − ι·Δv⁻ + ½ ιᵀΓι subject to
/// nᵀ Γ ι = n·Δv⁻ (⇔ n·J_c q̇⁺ = 0, eq. 42d) and |ι_∥| ≤ μ_k ι_n (eq. 42e).
///
/// In the frame (n, t1, t2) the equality eliminates ι_n, leaving a strictly convex 2-D problem
/// min ½ xᵀA x − bᵀx s.t. |x| + k·x ≤ c (x = ι_∥). If the unconstrained minimiser (the
/// sticking impulse) is feasible it is the answer; otherwise the dual function's derivative
/// φ(γ) = |x(γ)| + k·x(γ) − c is non-increasing in the multiplier γ ≥ 0 and is bracketed and
/// solved to round-off; x(γ) itself solves the secular equation s |(A + sI)⁻¹ w| = γ
/// (w = b − γ k), monotone in s.
fn max_dissipation_impulse<const N: usize>(
    kin: &ContactKinematics<N>,
    params: &Params,
    mats: &ContactMatrices<N>,
) -> Result<Vec3> {
    let n = kin.contact.n;
    let r = contact_frame(&n);
    let gp = r.transpose() * mats.gamma * r;
    let dvp = r.transpose() * kin.contact.delta_v;
    let gnn = gp[(0, 0)];
    let g = nalgebra::Vector2::new(gp[(0, 1)], gp[(0, 2)]);
    // ι_n ≥ 0 needs n·Δv⁻ ≥ 0; within the grazing tolerance clamp to exactly 0.
    let a0 = dvp[0].max(0.0) / gnn;
    // ι' = z0 + Z x
    let mut z = nalgebra::Matrix3x2::zeros();
    z[(0, 0)] = -g[0] / gnn;
    z[(0, 1)] = -g[1] / gnn;
    z[(1, 0)] = 1.0;
    z[(2, 1)] = 1.0;
    let z0 = Vec3::new(a0, 0.0, 0.0);
    let dvp_c = Vec3::new(a0 * gnn, dvp[1], dvp[2]);
    let a = z.transpose() * gp * z;
    let a = (a + a.transpose()) * 0.5;
    let b = z.transpose() * (dvp_c - gp * z0);
    let mu = params.mu_k();
    let k = g * (mu / gnn);
    let c = mu * a0;
    let x = if mu == 0.0 {
        nalgebra::Vector2::zeros()
    } else {
        solve_cone_qp(&a, &b, &k, c)?
    };
    let iota_p = z0 + z * x;
    Ok(r * iota_p)
}

/// Jacobi eigen-decomposition of a symmetric 2×2 matrix: (eigenvalues, rotation Q) with
/// A = Q diag(λ) Qᵀ.
fn sym_eig2(a: &nalgebra::Matrix2<f64>) -> ([f64; 2], nalgebra::Matrix2<f64>) {
    let (p, q, s) = (a[(0, 0)], a[(0, 1)], a[(1, 1)]);
    let th = 0.5 * libm::atan2(2.0 * q, p - s);
    let (sn, cs) = libm::sincos(th);
    let l1 = p * cs * cs + 2.0 * q * sn * cs + s * sn * sn;
    let l2 = p * sn * sn - 2.0 * q * sn * cs + s * cs * cs;
    ([l1, l2], nalgebra::Matrix2::new(cs, -sn, sn, cs))
}

/// min ½ xᵀA x − bᵀx + γ |x| + γ k·x over x ∈ R² (A SPD): the inner problem of the dual.
fn inner_min(
    eig: &([f64; 2], nalgebra::Matrix2<f64>),
    b: &nalgebra::Vector2<f64>,
    k: &nalgebra::Vector2<f64>,
    gamma: f64,
) -> nalgebra::Vector2<f64> {
    let w = b - k * gamma;
    let wn = w.norm();
    if wn <= gamma {
        return nalgebra::Vector2::zeros();
    }
    let (lam, q) = eig;
    let wt = q.transpose() * w;
    // g(s) = s |(Λ + sI)⁻¹ w̃| increases from 0 to |w|; solve g(s) = γ.
    let g_and_d = |s: f64| {
        let mut g2 = 0.0;
        let mut dg2 = 0.0;
        for i in 0..2 {
            let f = s / (lam[i] + s);
            g2 += wt[i] * wt[i] * f * f;
            dg2 += 2.0 * wt[i] * wt[i] * f * lam[i] / (lam[i] + s).powi(2);
        }
        let g = g2.sqrt();
        (g, if g > 0.0 { dg2 / (2.0 * g) } else { 0.0 })
    };
    let lmin = lam[0].min(lam[1]);
    let lmax = lam[0].max(lam[1]);
    let mut lo = gamma * lmin / (wn - gamma);
    let mut hi = gamma * lmax / (wn - gamma);
    let mut s = 0.5 * (lo + hi);
    for _ in 0..200 {
        let (g, dg) = g_and_d(s);
        let r = g - gamma;
        if r.abs() <= 2.0 * f64::EPSILON * gamma {
            break;
        }
        if r > 0.0 {
            hi = s;
        } else {
            lo = s;
        }
        if hi - lo <= 4.0 * f64::EPSILON * hi {
            break;
        }
        let newton = if dg > 0.0 { s - r / dg } else { f64::NAN };
        s = if newton > lo && newton < hi {
            newton
        } else {
            0.5 * (lo + hi)
        };
    }
    let xt = nalgebra::Vector2::new(wt[0] / (lam[0] + s), wt[1] / (lam[1] + s));
    q * xt
}

/// Strictly convex 2-D QP over {|x| + k·x ≤ c} (c ≥ 0), exact up to round-off.
fn solve_cone_qp(
    a: &nalgebra::Matrix2<f64>,
    b: &nalgebra::Vector2<f64>,
    k: &nalgebra::Vector2<f64>,
    c: f64,
) -> Result<nalgebra::Vector2<f64>> {
    let phi_of = |x: &nalgebra::Vector2<f64>| x.norm() + k.dot(x) - c;
    let chol = a
        .cholesky()
        .ok_or(ModelError::SingularContact { rcond: 0.0 })?;
    let xu = chol.solve(b);
    let scale = xu.norm().max(c);
    if phi_of(&xu) <= 1e-14 * scale {
        return Ok(xu);
    }
    let eig = sym_eig2(a);
    // Bracket the multiplier: φ(0) > 0; grow γ until φ(γ) ≤ 0.
    let mut lo = 0.0;
    let mut hi = b.norm().max(f64::MIN_POSITIVE);
    let mut x_hi = inner_min(&eig, b, k, hi);
    let mut f_hi = phi_of(&x_hi);
    let mut grow = 0;
    while f_hi > 0.0 {
        lo = hi;
        hi *= 2.0;
        x_hi = inner_min(&eig, b, k, hi);
        f_hi = phi_of(&x_hi);
        grow += 1;
        if grow > 2000 {
            return Err(ModelError::NoConvergence {
                what: "max-dissipation impact multiplier bracket",
            });
        }
    }
    let mut f_lo = phi_of(&inner_min(&eig, b, k, lo));
    // Illinois regula falsi on the monotone φ; keep the feasible end (φ ≤ 0). `f_lo`/`f_hi`
    // are the (possibly halved) Illinois weights, `true_hi` the true φ at `hi`.
    let mut true_hi = f_hi;
    let mut side = 0i8;
    for _ in 0..300 {
        if hi - lo <= 8.0 * f64::EPSILON * hi || true_hi.abs() <= 1e-15 * scale {
            return Ok(x_hi);
        }
        let mut g = (lo * f_hi - hi * f_lo) / (f_hi - f_lo);
        if !(g > lo && g < hi) {
            g = 0.5 * (lo + hi);
        }
        let xg = inner_min(&eig, b, k, g);
        let fg = phi_of(&xg);
        if fg > 0.0 {
            lo = g;
            f_lo = fg;
            if side == 1 {
                f_hi *= 0.5;
            }
            side = 1;
        } else {
            hi = g;
            f_hi = fg;
            true_hi = fg;
            x_hi = xg;
            if side == -1 {
                f_lo *= 0.5;
            }
            side = -1;
        }
    }
    Ok(x_hi)
}

/// Minimum-relative-velocity impulse (eq. 43): ι(μ) = ι_n (n + μ d̂), d̂ = Δv_∥⁻/|Δv_∥⁻|,
/// ι_n = n·Δv⁻ / nᵀΓ(n + μ d̂) from eq. 43d, μ ∈ [0, μ_k] (43f closed at 0: the infimum is
/// attained there). Δv⁺(μ) = (c0 + μ c1)/(Γ_nn + μ Γ_nd) has exactly one stationary point of
/// |Δv⁺|², so the minimum is at μ = 0, μ_k or that point. When |Δv_∥⁻| ≈ 0 the direction of
/// the sticking impulse's tangential part is used (documented fallback; then Δv⁺ = 0 if
/// reachable within μ_k).
fn min_relative_velocity_impulse<const N: usize>(
    kin: &ContactKinematics<N>,
    params: &Params,
    mats: &ContactMatrices<N>,
    settings: &TransitionSettings,
) -> Result<Vec3> {
    let n = kin.contact.n;
    let dv = kin.contact.delta_v;
    let dv_n = n.dot(&dv).max(0.0);
    let dv_t = dv - n * n.dot(&dv);
    let gam = &mats.gamma;
    let d = if dv_t.norm() > settings.slip_direction_tol {
        dv_t.normalize()
    } else {
        let is = stick_impulse(kin, mats, settings)?;
        let it = is - n * n.dot(&is);
        if it.norm() > 1e-300 {
            it.normalize()
        } else {
            tangent_basis(&n).0
        }
    };
    let gn = gam * n;
    let gd = gam * d;
    let g_nn = n.dot(&gn);
    let g_nd = n.dot(&gd);
    let den = |m: f64| g_nn + m * g_nd;
    let c0 = dv * g_nn - gn * dv_n;
    let c1 = dv * g_nd - gd * dv_n;
    let f = |m: f64| (c0 + c1 * m).norm_squared() / den(m).powi(2);
    // Admissible μ: [0, μ_k] where the normal impulse stays positive and finite.
    let mu_hi = if g_nd < 0.0 {
        params.mu_k().min(0.999_999 * g_nn / -g_nd)
    } else {
        params.mu_k()
    };
    let mut best = (0.0, f(0.0));
    let mut consider = |m: f64| {
        if m.is_finite() && (0.0..=mu_hi).contains(&m) && den(m) > 0.0 {
            let v = f(m);
            if v < best.1 {
                best = (m, v);
            }
        }
    };
    consider(mu_hi);
    let denom = c1.norm_squared() * g_nn - g_nd * c0.dot(&c1);
    if denom != 0.0 {
        consider((g_nd * c0.norm_squared() - g_nn * c0.dot(&c1)) / denom);
    }
    let m = best.0;
    let iota_n = dv_n / den(m);
    Ok((n + d * m) * iota_n)
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::{Matrix2, Vector2};

    /// Brute-force min over a dense polar grid of the feasible region, refined locally.
    fn brute(a: &Matrix2<f64>, b: &Vector2<f64>, k: &Vector2<f64>, c: f64) -> (f64, Vector2<f64>) {
        let obj = |x: &Vector2<f64>| 0.5 * x.dot(&(a * x)) - b.dot(x);
        let mut best = (obj(&Vector2::zeros()), Vector2::zeros());
        for i in 0..720 {
            let th = i as f64 / 720.0 * std::f64::consts::TAU;
            let e = Vector2::new(libm::cos(th), libm::sin(th));
            let den = 1.0 + k.dot(&e);
            if den <= 0.0 {
                continue;
            }
            let rmax = c / den;
            for j in 1..=400 {
                let x = e * (rmax * j as f64 / 400.0);
                let v = obj(&x);
                if v < best.0 {
                    best = (v, x);
                }
            }
        }
        best
    }

    #[test]
    fn cone_qp_matches_brute_force() {
        use rand::{Rng, SeedableRng};
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(7);
        let mut n_boundary = 0;
        for _ in 0..40 {
            let l = Matrix2::new(
                rng.random_range(0.2..2.0),
                0.0,
                rng.random_range(-1.0..1.0),
                rng.random_range(0.2..2.0),
            );
            let a = l * l.transpose();
            let b = Vector2::new(rng.random_range(-3.0..3.0), rng.random_range(-3.0..3.0));
            let k = Vector2::new(rng.random_range(-0.6..0.6), rng.random_range(-0.6..0.6));
            let c = rng.random_range(0.05..1.0);
            let x = solve_cone_qp(&a, &b, &k, c).unwrap();
            let obj = |x: &Vector2<f64>| 0.5 * x.dot(&(a * x)) - b.dot(x);
            assert!(x.norm() + k.dot(&x) <= c * (1.0 + 1e-12), "infeasible");
            let (bv, bx) = brute(&a, &b, &k, c);
            assert!(
                obj(&x) <= bv + 1e-9 * (1.0 + bv.abs()),
                "{} vs brute {} at {bx}",
                obj(&x),
                bv
            );
            // The brute force is only approximately optimal: mine must not be much better
            // than the grid either (it would mean infeasibility).
            assert!(obj(&x) >= bv - 1e-3 * (1.0 + bv.abs()));
            if x.norm() + k.dot(&x) > c * (1.0 - 1e-9) {
                n_boundary += 1;
            }
        }
        assert!(
            n_boundary > 10,
            "test must exercise the boundary case ({n_boundary})"
        );
    }
}

#[cfg(test)]
mod name_tests {
    use super::*;

    #[test]
    fn names_roundtrip_and_unknown_is_error() {
        for law in [ImpactLaw::NormalImpulse]
            .iter()
            .chain(ImpactLaw::ALL.iter())
        {
            assert_eq!(law.name().parse::<ImpactLaw>().unwrap(), *law);
        }
        let e = "bounce".parse::<ImpactLaw>().unwrap_err();
        assert!(e.to_string().contains("unknown impact law `bounce`"), "{e}");
    }
}
