//! Energy and power balance of finger + ball (eq. 22, 25, 44).
//!
//! E = ½ q̇ᵀ M_f q̇ + U_f(q) + ½ ωᵀ I_b ω (the ball centre is fixed, so its potential is
//! constant and omitted). With Ṁ_f − 2C skew (Christoffel C) and g = ∂U/∂q, along any mode
//! dE/dt = q̇ᵀτ − μ_v ‖q̇‖² − D ‖ω‖² − λ·Δv,
//! where −λ·Δv = q̇ᵀ J_cᵀ λ − ωᵀ (r_c × λ) is the power of the contact force: 0 when sticking
//! (Δv = 0), −μ_k λ_n ‖Δv‖ ≤ 0 when slipping (eq. 20), 0 in free motion. The gyroscopic term
//! does no work (ω·(ω × I_b ω) = 0) for any I_b. Generic over the number of joints N.

use crate::dynamics::ContactForce;
use crate::{ContactKinematics, Params, VecN};

/// Energy of the system at one state (J).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Energy {
    /// ½ q̇ᵀ M_f q̇.
    pub kinetic_finger: f64,
    /// ½ ωᵀ I_b ω.
    pub kinetic_ball: f64,
    /// U_f(q) (eq. 22b).
    pub potential: f64,
    /// Sum of the three.
    pub total: f64,
}

/// E at the state of `kin`.
pub fn energy<const N: usize>(kin: &ContactKinematics<N>, params: &Params) -> Energy {
    let qd = &kin.state.qd;
    let w = &kin.state.omega;
    let kinetic_finger = 0.5 * qd.dot(&(kin.m_f * qd));
    let kinetic_ball = 0.5 * w.dot(&(params.ball_inertia() * w));
    Energy {
        kinetic_finger,
        kinetic_ball,
        potential: kin.potential,
        total: kinetic_finger + kinetic_ball + kin.potential,
    }
}

/// Terms of dE/dt (W).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PowerBalance {
    /// Actuator power q̇ᵀ τ.
    pub input: f64,
    /// Joint viscous dissipation μ_v ‖q̇‖² (≥ 0, subtracted).
    pub joint_viscous: f64,
    /// Socket dissipation D ‖ω‖² (≥ 0, subtracted).
    pub socket: f64,
    /// Friction slip dissipation λ·Δv (≥ 0 for kinetic friction, subtracted; 0 when sticking).
    pub slip: f64,
    /// dE/dt = input − joint_viscous − socket − slip.
    pub total: f64,
}

/// Power balance at `kin` with torque `tau` and contact force `force` (zero in free motion).
pub fn power_balance<const N: usize>(
    kin: &ContactKinematics<N>,
    params: &Params,
    tau: &VecN<N>,
    force: &ContactForce,
) -> PowerBalance {
    let qd = &kin.state.qd;
    let w = &kin.state.omega;
    let input = qd.dot(tau);
    let joint_viscous = params.mu_v() * qd.norm_squared();
    let socket = params.socket_damping() * w.norm_squared();
    let slip = force.lambda.dot(&kin.contact.delta_v);
    PowerBalance {
        input,
        joint_viscous,
        socket,
        slip,
        total: input - joint_viscous - socket - slip,
    }
}
