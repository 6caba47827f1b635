//! Model-wide tolerances: [`TransitionSettings`].
//!
//! One home for every tolerance of the physics layer, shared by the mode dynamics
//! ([`crate::dynamics`]: contact band of eq. 8, singular Γ of eq. 33, Painlevé margin of
//! Sect. 7), the impact laws ([`crate::impact`]: separating contacts, eq. 39–43) and the
//! transition predicates ([`crate::transitions`]: the tolerances that replace the equalities of
//! eq. 48–50 and ‖Δv‖ = 0, Sect. 3.1). It depends on nothing but the error type, so those three
//! modules import it without importing each other.

use crate::{ModelError, Result};

/// Tolerances of the physics layer and of the transition predicates. Deserialisable with
/// missing fields taking their defaults.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct TransitionSettings {
    /// Contact-mode queries (stick, slip, impacts) accept |h| ≤ `contact_tolerance` · r and
    /// return `NotInContact` otherwise. Dimensionless, a fraction of the ball radius r; allows the
    /// drift of h in contact modes (Sect. 3.1). (default: 1e-3)
    pub contact_tolerance: f64,
    /// |h| ≤ `h_eps` · r counts as h = 0 in eq. 50. Dimensionless. (default: 1e-9)
    pub h_eps: f64,
    /// |ḣ| ≤ `hdot_eps` counts as ḣ = 0 in eq. 50; impacts with n·v_c > `hdot_eps` are refused
    /// as separating (m/s). (default: 1e-9)
    pub hdot_eps: f64,
    /// ε of Sect. 3.1: Slip→Stick needs ‖Δv‖ ≤ ε; a post-impact ‖Δv⁺‖ ≤ ε counts as sticking
    /// (m/s). (default: 1e-6)
    pub slip_eps: f64,
    /// ‖Δv‖ set by the Stick→Slip velocity update (m/s); must exceed `slip_eps` so that the
    /// Slip→Stick condition does not fire immediately. (default: 2e-6)
    pub slip_kick: f64,
    /// Below this ‖Δv_∥‖ the slip direction of eq. 20 is undefined and a hint is needed (m/s).
    /// (default: 1e-12)
    pub slip_direction_tol: f64,
    /// Reciprocal-condition threshold below which Γ (eq. 33), nᵀ W n relative to ‖W‖ or J_c
    /// count as singular. Dimensionless. (default: 1e-10)
    pub singular_rcond: f64,
    /// Slip is reported as a Painlevé paradox when the effective normal inverse mass
    /// nᵀ W (n + μ_k t̂) ≤ `painleve_margin` · nᵀ W n. Dimensionless. (default: 1e-9)
    pub painleve_margin: f64,
}

impl Default for TransitionSettings {
    fn default() -> Self {
        Self {
            contact_tolerance: 1e-3,
            h_eps: 1e-9,
            hdot_eps: 1e-9,
            slip_eps: 1e-6,
            slip_kick: 2e-6,
            slip_direction_tol: 1e-12,
            singular_rcond: 1e-10,
            painleve_margin: 1e-9,
        }
    }
}

impl TransitionSettings {
    /// Error naming the first field that is negative, NaN, or (for `slip_kick`) not above
    /// `slip_eps`.
    pub fn validate(&self) -> Result<()> {
        let fields: [(&'static str, f64); 8] = [
            ("contact_tolerance", self.contact_tolerance),
            ("h_eps", self.h_eps),
            ("hdot_eps", self.hdot_eps),
            ("slip_eps", self.slip_eps),
            ("slip_kick", self.slip_kick),
            ("slip_direction_tol", self.slip_direction_tol),
            ("singular_rcond", self.singular_rcond),
            ("painleve_margin", self.painleve_margin),
        ];
        for (name, value) in fields {
            if !value.is_finite() || value < 0.0 {
                return Err(ModelError::InvalidParameter {
                    name,
                    value,
                    reason: "tolerance must be finite and >= 0",
                });
            }
        }
        if self.slip_kick <= self.slip_eps {
            return Err(ModelError::InvalidParameter {
                name: "slip_kick",
                value: self.slip_kick,
                reason: "must be > slip_eps",
            });
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn default_settings_valid_and_bad_rejected() {
        let s = TransitionSettings::default();
        assert!(s.validate().is_ok());
        let bad = TransitionSettings {
            slip_eps: f64::NAN,
            ..s
        };
        let e = bad.validate().unwrap_err();
        assert!(e.to_string().contains("slip_eps"), "{e}");
        let bad = TransitionSettings {
            slip_kick: s.slip_eps,
            ..s
        };
        assert!(
            bad.validate()
                .unwrap_err()
                .to_string()
                .contains("slip_kick")
        );
        let bad = TransitionSettings {
            contact_tolerance: -1.0,
            ..s
        };
        assert!(bad.validate().is_err());
    }
}
