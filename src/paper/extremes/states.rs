//! Fixed probe states and contact states of the paper scene shared by several probes: the
//! q, q̇, ω of the kernel probes, a configuration touching the ball (h = 0, eq. 4), states that
//! slip with a chosen Δv (eq. 13), and the torque that presses a static finger onto the ball
//! with a known force (so that a stick has the exact answer λ = f n, eq. 33).

use anyhow::bail;
use bf_model::{ContactKinematics, Model, PaperKernels, State, Vec3};

/// Direction of q for the |q| sweep (all joints large, different magnitudes and signs).
pub const Q_DIR: [f64; 3] = [0.7, -0.45, 0.9];
/// q̇ used by the kernel-accuracy probe (rad/s).
pub const QD_PROBE: [f64; 3] = [0.3, -0.2, 0.5];
/// Ball angular velocity used by the kernel probes (rad/s).
pub const OMEGA_PROBE: [f64; 3] = [0.1, 0.2, 2.2];

/// Torque that holds the finger against gravity and C q̇ and presses it onto the ball with
/// force `f` (N) along −n at the contact point: τ = C q̇ + g − J_cᵀ n f. In a static stick this
/// gives λ = f n exactly (q̈ = 0, ω̇ = 0 since r_c ∥ n).
pub fn press_torque(kin: &ContactKinematics, f: f64) -> Vec3 {
    kin.cqd_g - kin.contact.j_c.transpose() * kin.contact.n * f
}

/// A configuration of the paper finger touching the ball (|h| < 1e-14 m) with line contact
/// (−l < α < 0), found by M_f-metric Newton steps on h from (0.1, 1.3, 1.2).
pub fn paper_contact_configuration() -> anyhow::Result<Vec3> {
    let model = bf_model::fixtures::paper_scene()?;
    let mut q = Vec3::new(0.1, 1.3, 1.2);
    for _ in 0..50 {
        let x = State::new(q, Vec3::zeros(), Vec3::zeros());
        let kin = model.evaluate(&x)?;
        if kin.contact.h.abs() < 1e-14 {
            return Ok(q);
        }
        q += model.project_configuration(&x)?;
    }
    bail!("Newton on h(q) = 0 did not converge in 50 steps")
}

/// State at contact configuration `q` with q̇ = 0 and ω chosen so that Δv = `s` · `t_hat`
/// (t_hat unit and tangential: ω = s (r_c × t̂)/|r_c|², so ω × r_c = s t̂).
pub(super) fn state_with_slip(
    model: &Model<PaperKernels>,
    q: Vec3,
    t_hat: &Vec3,
    s: f64,
) -> anyhow::Result<State> {
    let kin = model.evaluate(&State::new(q, Vec3::zeros(), Vec3::zeros()))?;
    let rc = kin.contact.r_c;
    let w = rc.cross(t_hat) * (s / rc.norm_squared());
    Ok(State::new(q, Vec3::zeros(), w))
}

/// A unit tangent at the contact of configuration `q` (normal n): T_n applied to world y.
pub(super) fn some_tangent(model: &Model<PaperKernels>, q: Vec3) -> anyhow::Result<Vec3> {
    let kin = model.evaluate(&State::new(q, Vec3::zeros(), Vec3::zeros()))?;
    let n = kin.contact.n;
    let e = Vec3::new(0.3, 1.0, -0.2);
    Ok((e - n * n.dot(&e)).normalize())
}
