//! The crate's error type. Non-convergence of a solve is *not* an error (it is a
//! [`Status`](crate::ipm::Status) in the returned solution); errors are real breakdowns: invalid
//! problem data, non-finite values where no step can recover, or a failed linear-solver analysis.

use thiserror::Error;

/// Errors of `bf-optim`.
#[derive(Debug, Error, Clone, PartialEq)]
pub enum OptimError {
    /// A vector or pattern had the wrong length.
    #[error("dimension mismatch in {what}: expected {expected}, found {found}")]
    DimensionMismatch {
        /// Which quantity.
        what: &'static str,
        /// Expected length.
        expected: usize,
        /// Actual length.
        found: usize,
    },
    /// A sparsity-pattern entry is out of range (or above the diagonal for the Hessian).
    #[error("invalid sparsity pattern in {what}: entry {index} = ({row}, {col})")]
    InvalidPattern {
        /// `"jacobian"` or `"hessian"`.
        what: &'static str,
        /// Triplet index.
        index: usize,
        /// Row of the entry.
        row: usize,
        /// Column of the entry.
        col: usize,
    },
    /// Inconsistent bounds (lower > upper, or NaN).
    #[error("invalid bounds for {what} {index}: [{lower}, {upper}]")]
    InvalidBounds {
        /// `"variable"` or `"constraint"`.
        what: &'static str,
        /// Index.
        index: usize,
        /// Lower bound.
        lower: f64,
        /// Upper bound.
        upper: f64,
    },
    /// A function or derivative was not finite at an accepted point (no step cut can help).
    #[error("non-finite {what} at iteration {iter}")]
    NonFinite {
        /// Iteration number.
        iter: usize,
        /// Which quantity.
        what: &'static str,
    },
    /// The sparse factorization could not be set up.
    #[error("KKT factorization: {0}")]
    Factorization(String),
    /// A setting is out of its valid range.
    #[error("invalid setting {name}: {msg}")]
    InvalidSetting {
        /// Field name.
        name: &'static str,
        /// Why.
        msg: String,
    },
}
