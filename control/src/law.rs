//! The computed-torque law of the free phases.
//!
//! * [`ComputedTorque`]: the commanded acceleration q̈_cmd = q̈* + K_d (q̇* − q̇) + K_p (q* − q)
//!   with K_p = ω_n², K_d = 2ζω_n on every joint. With τ = ID(q, q̇, q̈_cmd) on an exact model
//!   the closed loop is q̈ = q̈_cmd, so every joint's error e = q* − q obeys
//!   ë + 2ζω_n ė + ω_n² e = 0: the gains are a natural frequency (rad/s) and a damping ratio,
//!   independent of the link inertias (unlike fixed N m/rad PD gains).
//! * [`InverseDynamics`]: the generated kernel `inverse_dynamics` of a compiled scene,
//!   τ = M q̈ + C q̇ + g (eq. 24, Newton–Euler), plus the joints' viscous friction μ_v q̇ of
//!   eq. 26a, so that ID inverts the free-motion dynamics the simulator integrates; or, for a
//!   scene without that kernel (a user's scene on interpreted kernels), the same sum formed
//!   from the controller's model, M(q) q̈ + (C q̇ + g)(q, q̇) + μ_v q̇
//!   ([`InverseDynamics::from_model`]), which the controller evaluates itself.

use crate::error::ControlError;
use bf_generated::EvalIntoFn;

/// Gains of [`ComputedTorque`]: natural frequency ω_n (rad/s) and damping ratio ζ.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ComputedTorque {
    /// ω_n (rad/s), positive.
    pub omega_n: f64,
    /// ζ, non-negative.
    pub zeta: f64,
}

impl ComputedTorque {
    /// Checks ω_n > 0 and ζ ≥ 0, both finite.
    pub fn new(omega_n: f64, zeta: f64) -> Result<Self, ControlError> {
        if !(omega_n.is_finite() && omega_n > 0.0) {
            return Err(ControlError::Gain {
                name: "omega_n",
                value: omega_n,
                condition: "a positive finite natural frequency (rad/s)",
            });
        }
        if !(zeta.is_finite() && zeta >= 0.0) {
            return Err(ControlError::Gain {
                name: "zeta",
                value: zeta,
                condition: "a non-negative finite damping ratio",
            });
        }
        Ok(ComputedTorque { omega_n, zeta })
    }

    /// K_p = ω_n² (1/s²).
    pub fn kp(&self) -> f64 {
        self.omega_n * self.omega_n
    }

    /// K_d = 2ζω_n (1/s).
    pub fn kd(&self) -> f64 {
        2.0 * self.zeta * self.omega_n
    }

    /// Writes q̈_cmd = q̈* + K_d (q̇* − q̇) + K_p (q* − q) into `out` (all slices of one length).
    pub fn acceleration(
        &self,
        q: &[f64],
        qd: &[f64],
        q_ref: &[f64],
        qd_ref: &[f64],
        qdd_ref: &[f64],
        out: &mut [f64],
    ) {
        let (kp, kd) = (self.kp(), self.kd());
        for i in 0..out.len() {
            out[i] = qdd_ref[i] + kd * (qd_ref[i] - qd[i]) + kp * (q_ref[i] - q[i]);
        }
    }
}

/// The inverse dynamics plus viscous joint friction, τ = M(q) q̈ + C(q, q̇) q̇ + g(q) + μ_v q̇:
/// the generated kernel of a compiled scene ([`InverseDynamics::compiled`]), or the model's
/// M and C q̇ + g ([`InverseDynamics::from_model`]).
#[derive(Debug, Clone)]
pub struct InverseDynamics {
    /// The generated kernel (function, index, runtime parameter values); `None`: the model's.
    kernel: Option<(EvalIntoFn, usize, Vec<f64>)>,
    mu_v: f64,
    nq: usize,
}

impl InverseDynamics {
    /// The kernel of the compiled scene `scene` with runtime parameter values `params` and
    /// viscous friction `mu_v` (N m s/rad). Errors if the scene is not compiled in or emits no
    /// `inverse_dynamics`, or the parameter count differs.
    pub fn compiled(scene: &str, params: &[f64], mu_v: f64) -> Result<Self, ControlError> {
        let entry = bf_generated::scene(scene).ok_or_else(|| ControlError::Scene {
            scene: scene.to_string(),
            msg: "is not a compiled scene (the controller needs its inverse-dynamics kernel)"
                .into(),
        })?;
        let kernel = entry
            .kernel_index("inverse_dynamics")
            .ok_or_else(|| ControlError::Scene {
                scene: scene.to_string(),
                msg: "emits no inverse_dynamics kernel".into(),
            })?;
        if params.len() != entry.param_names.len() {
            return Err(ControlError::Scene {
                scene: scene.to_string(),
                msg: format!(
                    "{} runtime parameter values for {} parameters",
                    params.len(),
                    entry.param_names.len()
                ),
            });
        }
        Ok(InverseDynamics {
            kernel: Some((entry.eval_into, kernel, params.to_vec())),
            mu_v,
            nq: entry.nq,
        })
    }

    /// The inverse dynamics of a finger with `nq` joints formed from the controller's own
    /// model: τ = M(q) q̈ + (C q̇ + g)(q, q̇) + μ_v q̇ with M and C q̇ + g from the model's
    /// kernels (`mass_cqd_g`), for a scene that emits no `inverse_dynamics` kernel. The same
    /// torque as the kernel's to rounding (eq. 24 and eq. 26a are one equation), at the cost
    /// of one evaluation of the model. Only the [`crate::HybridController`] can evaluate it
    /// ([`InverseDynamics::torque`] errors): it holds the model.
    pub fn from_model(nq: usize, mu_v: f64) -> Self {
        InverseDynamics {
            kernel: None,
            mu_v,
            nq,
        }
    }

    /// Whether τ comes from a generated kernel (otherwise from the controller's model).
    pub fn is_compiled(&self) -> bool {
        self.kernel.is_some()
    }

    /// Number of joints.
    pub fn nq(&self) -> usize {
        self.nq
    }

    /// The viscous joint friction μ_v (N m s/rad) added to the inverse dynamics.
    pub fn mu_v(&self) -> f64 {
        self.mu_v
    }

    /// Writes τ = ID(q, q̇, q̈) + μ_v q̇ into `out`; an error for [`InverseDynamics::from_model`],
    /// which has no kernel to evaluate.
    pub fn torque(
        &self,
        q: &[f64],
        qd: &[f64],
        qdd: &[f64],
        out: &mut [f64],
    ) -> Result<(), ControlError> {
        let Some((eval, kernel, params)) = &self.kernel else {
            return Err(ControlError::Scene {
                scene: "(the controller's model)".into(),
                msg: "has no inverse-dynamics kernel: the controller forms M q̈ + C q̇ + g \
                      from its model"
                    .into(),
            });
        };
        let written = eval(*kernel, q, qd, &[0.0; 3], 0.0, qdd, params, out);
        if written != Some(self.nq) || out.len() != self.nq {
            return Err(ControlError::Dimension {
                what: "inverse dynamics",
                expected: self.nq,
                found: out.len().min(q.len()).min(qd.len()).min(qdd.len()),
            });
        }
        for i in 0..self.nq {
            out[i] += self.mu_v * qd[i];
        }
        Ok(())
    }
}
