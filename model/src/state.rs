//! The state x = (q, q̇, ω) of eq. 44 (x^T = (q^T, dq^T, ω^T)) and the three modes of Sect. 2.6.

use crate::linalg::Vec3;
use crate::{ModelError, Result};

/// Discrete mode of the hybrid system (Sect. 2.6, Fig. 2–3), defined in bf-scene.
pub use bf_scene::Mode;

/// State x = (q, q̇, ω): joint angles (rad), joint rates (rad/s), ball angular velocity
/// (rad/s, world axes).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct State {
    /// Joint angles q.
    pub q: Vec3,
    /// Joint velocities q̇.
    pub qd: Vec3,
    /// Ball angular velocity ω.
    pub omega: Vec3,
}

impl State {
    /// Build a state.
    pub fn new(q: Vec3, qd: Vec3, omega: Vec3) -> Self {
        Self { q, qd, omega }
    }

    /// Flat layout (q, q̇, ω) as used by integrators.
    pub fn to_array(&self) -> [f64; 9] {
        let mut x = [0.0; 9];
        x[0..3].copy_from_slice(self.q.as_slice());
        x[3..6].copy_from_slice(self.qd.as_slice());
        x[6..9].copy_from_slice(self.omega.as_slice());
        x
    }

    /// Inverse of [`State::to_array`].
    pub fn from_array(x: &[f64; 9]) -> Self {
        Self {
            q: Vec3::new(x[0], x[1], x[2]),
            qd: Vec3::new(x[3], x[4], x[5]),
            omega: Vec3::new(x[6], x[7], x[8]),
        }
    }

    /// Error unless every component is finite.
    pub fn check_finite(&self) -> Result<()> {
        if self.to_array().iter().all(|v| v.is_finite()) {
            Ok(())
        } else {
            Err(ModelError::NonFinite { what: "state" })
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn array_roundtrip_and_finite_check() {
        let x = State::new(
            Vec3::new(1., 2., 3.),
            Vec3::new(4., 5., 6.),
            Vec3::new(7., 8., 9.),
        );
        let a = x.to_array();
        assert_eq!(a, [1., 2., 3., 4., 5., 6., 7., 8., 9.]);
        assert_eq!(State::from_array(&a), x);
        assert!(x.check_finite().is_ok());
        let mut y = x;
        y.omega.y = f64::NAN;
        assert_eq!(
            y.check_finite(),
            Err(ModelError::NonFinite { what: "state" })
        );
    }
}
