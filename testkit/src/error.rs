//! The error type of bf-testkit.

/// Errors of the reference implementation (bad scene data, missing ball, singular matrices).
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum TestkitError {
    /// The scene cannot be turned into a reference model (e.g. an unknown rotation axis).
    #[error("invalid scene: {0}")]
    InvalidScene(String),
    /// A contact quantity was requested for a scene without `[ball]`.
    #[error("the scene has no ball, contact quantities are undefined")]
    NoBall,
    /// `set_param` got a name the reference does not know.
    #[error("unknown parameter name `{0}`")]
    UnknownParameter(String),
    /// The mass matrix could not be factorised (not SPD / not finite).
    #[error("mass matrix is not symmetric positive definite at this state")]
    SingularMassMatrix,
}
