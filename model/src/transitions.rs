//! Mode validity and transitions (paper Sect. 3.1, eq. 48–50, Fig. 2–3).
//!
//! | function | paper |
//! |---|---|
//! | [`free_to_contact`] | eq. 50: h < 0 ∨ (h = 0 ∧ ḣ < 0) ∨ (h = ḣ = 0 ∧ ḧ < 0) |
//! | [`stick_to_slip`] | σ ≤ 0 (eq. 18–19) |
//! | [`slip_to_stick`] | ‖Δv‖ ≤ ε ∧ d‖Δv‖/dt < 0 |
//! | [`contact_to_free`] | λ_n < 0 (eq. 48) |
//! | [`slip_to_stick_update`] | velocities projected onto Δv = 0 with the sticking impulse (eq. 40–41) |
//! | [`stick_to_slip_update`] | minimal (M-norm) velocity change giving Δv⁺ = `slip_kick` · λ_∥/‖λ_∥‖ |
//! | [`check`] | first transition that fires in a given mode |
//! | [`guards`] | continuous guard functions (h/r, λ_n, σ, ‖Δv‖ − ε) for event location by root finding |
//! | [`project_configuration`] | drift control of h (eq. 8): M_f-metric Newton step Δq = −h M_f⁻¹ J_cᵀ n / nᵀ W n |
//! | [`project_velocity`] | drift control of eq. 46 (Stick: Δv = 0) or eq. 36 (Slip: n·v_c = 0) by the M-norm-closest velocities |
//!
//! Every function is generic over the number of joints N (default 3).
//!
//! Equalities are replaced by tolerances ([`TransitionSettings`], defined in
//! [`crate::settings`]) as Sect. 3.1 prescribes.

use crate::dynamics::{
    Accelerations, ContactForce, factor_gamma, matrices_with_mass, normal_acceleration,
    relative_acceleration, require_contact,
};
use crate::impact::{ImpactOutcome, apply_given_impulse, project_stick};
use crate::{ContactKinematics, Mode, ModelError, Params, Result};

/// The tolerances live in [`crate::settings`]; re-exported here under their old path.
pub use crate::settings::TransitionSettings;

/// A transition that fires (Fig. 2).
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Transition {
    /// Free → in contact: apply an impact law (eq. 50).
    Impact,
    /// Stick → Slip (σ ≤ 0).
    StickToSlip,
    /// Slip → Stick (‖Δv‖ ≤ ε, decreasing).
    SlipToStick,
    /// Stick/Slip → Free (λ_n < 0).
    ContactToFree,
}

/// Eq. 50 with tolerances. `free` must be the free-mode accelerations at `kin` (ḧ needs q̈).
pub fn free_to_contact<const N: usize>(
    kin: &ContactKinematics<N>,
    params: &Params,
    free: &Accelerations<N>,
    settings: &TransitionSettings,
) -> bool {
    let c = &kin.contact;
    let h_tol = settings.h_eps * params.ball_radius();
    if c.h < -h_tol {
        return true;
    }
    if c.h.abs() > h_tol {
        return false;
    }
    if c.h_dot < -settings.hdot_eps {
        return true;
    }
    c.h_dot.abs() <= settings.hdot_eps && normal_acceleration(kin, &free.qdd) < 0.0
}

/// Stick → Slip: σ ≤ 0 (static friction cannot hold, eq. 19). Requires λ_n ≥ 0 (otherwise
/// [`contact_to_free`] applies).
pub fn stick_to_slip(force: &ContactForce) -> bool {
    force.lambda_n >= 0.0 && force.sigma <= 0.0
}

/// Slip → Stick: ‖Δv‖ ≤ ε and d‖Δv‖/dt < 0 (Δv·Δv̇ < 0), or Δv = 0 exactly.
pub fn slip_to_stick<const N: usize>(
    kin: &ContactKinematics<N>,
    slip: &Accelerations<N>,
    settings: &TransitionSettings,
) -> bool {
    let dv = kin.contact.delta_v;
    let s = dv.norm();
    if s > settings.slip_eps {
        return false;
    }
    s == 0.0 || dv.dot(&relative_acceleration(kin, &slip.qdd, &slip.omega_dot)) < 0.0
}

/// Contact → Free: λ_n < 0 (eq. 48 would be violated).
pub fn contact_to_free(force: &ContactForce) -> bool {
    force.lambda_n < 0.0
}

/// The first transition that fires from `mode` given the accelerations computed in that mode
/// (priority: ContactToFree before StickToSlip / SlipToStick).
pub fn check<const N: usize>(
    mode: Mode,
    kin: &ContactKinematics<N>,
    params: &Params,
    acc: &Accelerations<N>,
    settings: &TransitionSettings,
) -> Option<Transition> {
    match mode {
        Mode::Free => free_to_contact(kin, params, acc, settings).then_some(Transition::Impact),
        Mode::Stick => {
            if contact_to_free(&acc.force) {
                Some(Transition::ContactToFree)
            } else if stick_to_slip(&acc.force) {
                Some(Transition::StickToSlip)
            } else {
                None
            }
        }
        Mode::Slip => {
            if contact_to_free(&acc.force) {
                Some(Transition::ContactToFree)
            } else if slip_to_stick(kin, acc, settings) {
                Some(Transition::SlipToStick)
            } else {
                None
            }
        }
    }
}

/// A scalar guard: `transition` fires when `value` crosses zero from above (value ≤ 0).
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Guard {
    /// The transition this guard triggers.
    pub transition: Transition,
    /// Guard value; positive while the current mode is valid.
    pub value: f64,
}

/// Continuous guard functions of `mode` for event location (Sect. 3.1: "the solver has to
/// pinpoint when the transition condition becomes satisfied with equality"):
/// Free: h / r (Impact; the ḣ, ḧ parts of eq. 50 matter only at h = 0, see
/// [`free_to_contact`]); Stick: λ_n (ContactToFree), σ (StickToSlip); Slip: λ_n
/// (ContactToFree), ‖Δv‖ − ε (SlipToStick; crossing downwards implies d‖Δv‖/dt < 0).
pub fn guards<const N: usize>(
    mode: Mode,
    kin: &ContactKinematics<N>,
    params: &Params,
    acc: &Accelerations<N>,
    settings: &TransitionSettings,
) -> [Option<Guard>; 2] {
    let g = |transition, value| Some(Guard { transition, value });
    match mode {
        Mode::Free => [
            g(Transition::Impact, kin.contact.h / params.ball_radius()),
            None,
        ],
        Mode::Stick => [
            g(Transition::ContactToFree, acc.force.lambda_n),
            g(Transition::StickToSlip, acc.force.sigma),
        ],
        Mode::Slip => [
            g(Transition::ContactToFree, acc.force.lambda_n),
            g(
                Transition::SlipToStick,
                kin.contact.delta_v.norm() - settings.slip_eps,
            ),
        ],
    }
}

/// Slip → Stick reset: project (q̇, ω) onto Δv = 0 with the sticking impulse ι = Γ⁻¹ Δv
/// (eq. 40–41); the M-norm-closest consistent velocities. Also removes a drifted n·v_c.
pub fn slip_to_stick_update<const N: usize>(
    kin: &ContactKinematics<N>,
    params: &Params,
    settings: &TransitionSettings,
) -> Result<ImpactOutcome<N>> {
    project_stick(kin, params, settings)
}

/// Stick → Slip reset: at the end of sticking Δv ≈ 0 and eq. 20 is undefined, so set
/// Δv⁺ = `slip_kick` · t̂ with t̂ = λ_∥/‖λ_∥‖ (the friction direction continues), by the
/// impulse ι = Γ⁻¹(Δv⁻ − Δv⁺) (minimal change in the kinetic-energy norm). n·v_c⁺ = 0.
pub fn stick_to_slip_update<const N: usize>(
    kin: &ContactKinematics<N>,
    params: &Params,
    stick_force: &ContactForce,
    settings: &TransitionSettings,
) -> Result<ImpactOutcome<N>> {
    require_contact(kin, params, settings)?;
    let n = kin.contact.n;
    let lt = stick_force.lambda_t - n * n.dot(&stick_force.lambda_t);
    let s = lt.norm();
    if !(s.is_finite() && s > 0.0) {
        return Err(ModelError::UndefinedSlipDirection {
            tangential_speed: 0.0,
        });
    }
    let target = lt * (settings.slip_kick / s);
    let (mats, _) = matrices_with_mass(kin, params)?;
    let g = factor_gamma(&mats, settings)?;
    let iota = g.solve(&(kin.contact.delta_v - target));
    let mut out = apply_given_impulse(kin, params, settings, &iota)?;
    out.mode = Mode::Slip;
    Ok(out)
}

/// One Newton step of h(q) = 0 that is smallest in the M_f metric:
/// Δq = −h M_f⁻¹ J_cᵀ n / (nᵀ J_c M_f⁻¹ J_cᵀ n) (∇h = J_cᵀ n with the exact sat). Returns Δq;
/// h(q + Δq) = O(h²). Use to control the drift of h in contact modes (Sect. 3.1).
pub fn project_configuration<const N: usize>(
    kin: &ContactKinematics<N>,
    params: &Params,
    settings: &TransitionSettings,
) -> Result<crate::VecN<N>> {
    let (mats, _) = matrices_with_mass(kin, params)?;
    crate::dynamics::require_normal_mobility(&mats, settings)?;
    Ok(mats.minv_jct * kin.contact.n * (-kin.contact.h / mats.n_w_n))
}

/// Velocities made consistent with `mode` by the M-norm-closest change: Stick → Δv = 0
/// (sticking impulse, eq. 41); Slip → n·v_c = 0 (normal impulse ι = −n (n·v_c)/nᵀ W n, ω
/// unchanged); Free → unchanged (zero impulse).
pub fn project_velocity<const N: usize>(
    mode: Mode,
    kin: &ContactKinematics<N>,
    params: &Params,
    settings: &TransitionSettings,
) -> Result<ImpactOutcome<N>> {
    match mode {
        Mode::Free => apply_given_impulse(kin, params, settings, &crate::Vec3::zeros()),
        Mode::Stick => project_stick(kin, params, settings),
        Mode::Slip => {
            require_contact(kin, params, settings)?;
            let (mats, _) = matrices_with_mass(kin, params)?;
            crate::dynamics::require_normal_mobility(&mats, settings)?;
            let n = kin.contact.n;
            let iota = n * (-kin.contact.normal_velocity() / mats.n_w_n);
            let mut out = apply_given_impulse(kin, params, settings, &iota)?;
            out.mode = Mode::Slip;
            Ok(out)
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn force_predicates() {
        let n = crate::Vec3::z();
        let f = ContactForce::new(crate::Vec3::new(0.5, 0.0, 1.0), &n, 0.8);
        assert!(!stick_to_slip(&f) && !contact_to_free(&f));
        let f = ContactForce::new(crate::Vec3::new(0.9, 0.0, 1.0), &n, 0.8);
        assert!(stick_to_slip(&f));
        let f = ContactForce::new(crate::Vec3::new(0.0, 0.0, -1.0), &n, 0.8);
        assert!(contact_to_free(&f) && !stick_to_slip(&f));
    }
}
