//! The crate's error type: every physical or numerical failure of Sect. 2–3 and 7 is a typed
//! variant (singular Γ of eq. 33, Painlevé for the slip normal force of eq. 37, no contact for
//! queries that need h = 0, eq. 8), so callers never see NaN.

use std::fmt;
use std::sync::Arc;

use thiserror::Error;

/// Which kind of Painlevé failure (paper Sect. 7) the slip normal force exhibits.
///
/// With the normal constraint acceleration a(λ_n) = a_free + k λ_n (k = effective inverse mass
/// including the kinetic-friction direction), the complementarity conditions (48) at acceleration
/// level have: no solution when k ≤ 0 and a_free < 0, two solutions (free and in contact) when
/// k ≤ 0 and a_free ≥ 0.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum PainleveKind {
    /// No consistent contact force exists (k ≤ 0, a_free < 0).
    Inconsistent,
    /// More than one consistent solution exists (k ≤ 0, a_free ≥ 0).
    NonUnique,
}

/// Errors of bf-model.
#[derive(Debug, Clone, PartialEq, Error)]
pub enum ModelError {
    /// A physical parameter is out of range (negative friction, zero radius, NaN, ...).
    #[error("invalid parameter `{name}` = {value}: {reason}")]
    InvalidParameter {
        /// Parameter name, e.g. `"mu_k"`.
        name: &'static str,
        /// The offending value (or a representative entry).
        value: f64,
        /// What is required.
        reason: &'static str,
    },
    /// A state, torque or kernel output contains NaN or ±inf.
    #[error("non-finite {what}")]
    NonFinite {
        /// What was non-finite, e.g. `"state"`, `"torque"`, `"mass matrix"`.
        what: &'static str,
    },
    /// The kernel parameter vector has the wrong length.
    #[error("kernel parameter vector has length {got}, scene `{scene}` expects {expected}")]
    ParameterCount {
        /// Scene name.
        scene: &'static str,
        /// Expected length (the scene's NP).
        expected: usize,
        /// Supplied length.
        got: usize,
    },
    /// The scene cannot be used as a model (missing ball / friction section, unknown constant, ...).
    #[error("scene `{scene}`: {message}")]
    Scene {
        /// Scene name.
        scene: String,
        /// Explanation.
        message: String,
    },
    /// The scene text a kernel set carries is not a valid scene file.
    #[error("scene `{scene}`: its text is not a valid scene file")]
    SceneText {
        /// Scene name.
        scene: String,
        /// The scene file's error.
        #[source]
        source: Shared<bf_scene::SpecError>,
    },
    /// bf-codegen cannot build the kernel graphs of a scene (interpreted kernels).
    #[error("scene `{scene}`: cannot build its kernel graphs")]
    Graphs {
        /// Scene name.
        scene: String,
        /// The generator's error.
        #[source]
        source: Shared<bf_codegen::CodegenError>,
    },
    /// The helper thread that builds a scene's kernel graphs could not be started.
    #[error("scene `{scene}`: cannot spawn a thread to build its kernel graphs")]
    Thread {
        /// Scene name.
        scene: String,
        /// The operating system's error.
        #[source]
        source: Shared<std::io::Error>,
    },
    /// A name given as a compiled contact scene is none of them.
    #[error("not a compiled contact scene: {0}")]
    NotCompiled(bf_scene::UnknownScene),
    /// A contact-mode quantity was requested at a state that is not in contact.
    #[error("not in contact: h = {h:e} m, |h| must be <= {tolerance:e} m")]
    NotInContact {
        /// Signed distance h (eq. 4).
        h: f64,
        /// Accepted |h| (see `TransitionSettings::contact_tolerance`).
        tolerance: f64,
    },
    /// An impact law was applied while the finger separates from the ball (n·v_c > 0).
    #[error("impact requested while separating: n·v_c = {normal_velocity:e} m/s > 0")]
    Separating {
        /// n·J_c q̇⁻ (eq. 36).
        normal_velocity: f64,
    },
    /// The finger mass matrix M_f(q) is not symmetric positive definite.
    #[error("finger mass matrix is not positive definite")]
    MassMatrixNotPositiveDefinite,
    /// Γ = G M⁻¹ Gᵀ (eq. 33) is singular: the finger cannot move along the contact normal
    /// (Jᵀ_c n ≈ 0), e.g. a stretched finger touching along its own axis.
    #[error("singular contact: Γ = G M⁻¹ Gᵀ is (nearly) singular, reciprocal condition {rcond:e}")]
    SingularContact {
        /// Estimate of the reciprocal condition number of Γ (or of nᵀ J_c M_f⁻¹ J_cᵀ n relative to
        /// ‖J_c M_f⁻¹ J_cᵀ‖).
        rcond: f64,
    },
    /// J_c is singular, so Newton's law (eq. 39) cannot be solved for q̇⁺.
    #[error(
        "contact Jacobian J_c is singular (reciprocal condition {rcond:e}); eq. 39 has no unique q̇⁺"
    )]
    SingularContactJacobian {
        /// Reciprocal condition estimate of J_c.
        rcond: f64,
    },
    /// Painlevé paradox in slip (Sect. 7): the effective normal inverse mass
    /// nᵀ J_c M_f⁻¹ J_cᵀ (n + μ_k t̂) is not positive.
    #[error(
        "Painlevé paradox ({kind:?}): slip normal inverse mass {effective_inverse_mass:e} <= 0, \
         free normal acceleration {free_normal_acceleration:e}"
    )]
    Painleve {
        /// No solution or several solutions.
        kind: PainleveKind,
        /// nᵀ J_c M_f⁻¹ J_cᵀ (n + μ_k t̂).
        effective_inverse_mass: f64,
        /// Normal constraint acceleration with λ = 0.
        free_normal_acceleration: f64,
    },
    /// Slip requested with (almost) zero tangential relative velocity and no direction hint
    /// (eq. 20 undefined).
    #[error("slip direction undefined: |Δv_∥| = {tangential_speed:e} m/s and no direction hint")]
    UndefinedSlipDirection {
        /// |T_n Δv|.
        tangential_speed: f64,
    },
    /// A name (impact law, scene, ...) that is not known.
    #[error("unknown {what} `{name}`; expected one of: {expected}")]
    UnknownName {
        /// What kind of name.
        what: &'static str,
        /// The name given.
        name: String,
        /// The accepted names.
        expected: &'static str,
    },
    /// An iterative solve (maximum-dissipation impact, eq. 42) did not converge.
    #[error("{what} did not converge")]
    NoConvergence {
        /// Which solve.
        what: &'static str,
    },
}

/// An error of another library held by a [`ModelError`] variant as its `source()`, behind an
/// `Arc` so that `ModelError` stays `Clone`; two are equal when their messages are (the wrapped
/// errors are not comparable). Displays as the wrapped error and forwards its `source()`.
#[derive(Debug)]
pub struct Shared<E>(pub Arc<E>);

impl<E> Shared<E> {
    /// Wraps `e`.
    pub fn new(e: E) -> Self {
        Shared(Arc::new(e))
    }
}

impl<E> Clone for Shared<E> {
    fn clone(&self) -> Self {
        Shared(Arc::clone(&self.0))
    }
}

impl<E: fmt::Display> PartialEq for Shared<E> {
    fn eq(&self, other: &Self) -> bool {
        Arc::ptr_eq(&self.0, &other.0) || self.0.to_string() == other.0.to_string()
    }
}

impl<E: fmt::Display> fmt::Display for Shared<E> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        self.0.fmt(f)
    }
}

impl<E: std::error::Error> std::error::Error for Shared<E> {
    fn source(&self) -> Option<&(dyn std::error::Error + 'static)> {
        self.0.source()
    }
}
