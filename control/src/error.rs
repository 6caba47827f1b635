//! [`ControlError`], the error of every module of the crate (below them all, so that no
//! module imports another for its error type).

use bf_model::ModelError;

/// Errors of the control layer; each names what is wrong and the value.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum ControlError {
    /// A gain out of range.
    #[error("gain {name} = {value}: expected {condition}")]
    Gain {
        /// Gain name.
        name: &'static str,
        /// Its value.
        value: f64,
        /// What it must be.
        condition: &'static str,
    },
    /// The controller's scene cannot be used.
    #[error("scene `{scene}` {msg}")]
    Scene {
        /// Scene name.
        scene: String,
        /// What is wrong.
        msg: String,
    },
    /// A slice of the wrong length.
    #[error("{what}: expected {expected} values, found {found}")]
    Dimension {
        /// What was passed.
        what: &'static str,
        /// Expected length.
        expected: usize,
        /// Found length.
        found: usize,
    },
    /// The reference trajectory is unusable.
    #[error("reference trajectory: {msg}")]
    Reference {
        /// What is wrong.
        msg: String,
    },
    /// The contact Jacobian J_c cannot be inverted (the finger cannot move its contact point
    /// freely, e.g. stretched).
    #[error("contact law at t = {t} s: the contact Jacobian J_c is singular")]
    SingularJacobian {
        /// Time (s).
        t: f64,
    },
    /// A model evaluation failed.
    #[error(transparent)]
    Model(#[from] ModelError),
}
