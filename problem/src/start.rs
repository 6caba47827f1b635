//! [`StartGuess`]: an initial guess given by the caller (constant joint angles, phase
//! durations). The catalogue's guesses ([`crate::catalogue::guess`]) use it and the errors
//! ([`crate::ProblemError::StartGuess`]) carry it, so it sits below both.

use serde::{Deserialize, Serialize};

/// A guess of constant joint angles `q` and phase durations `durations` (the paper's guess is
/// q ≡ [`Q_GUESS`](crate::catalogue::Q_GUESS), every duration 1 s).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct StartGuess {
    /// Joint angles (rad), one per joint.
    pub q: Vec<f64>,
    /// Phase durations (s), one per phase.
    pub durations: Vec<f64>,
}
