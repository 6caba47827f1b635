//! The state x = (q, q̇, ω) of eq. 44 (x^T = (q^T, dq^T, ω^T)) and the three modes of Sect. 2.6.
//!
//! [`State`] is generic over the number of joints `N` (default 3, the paper's finger): q and q̇
//! are [`VecN<N>`](crate::VecN) (= [`Vec3`] for N = 3), ω is always 3-D. The flat layout
//! (q, q̇, ω) has 2N + 3 entries ([`State::write_slice`], [`State::from_slice`]); for N = 3 the
//! fixed-size [`State::to_array`] / [`State::from_array`] give the same 9 numbers.

use crate::linalg::{Vec3, VecN};
use crate::{ModelError, Result};

/// Discrete mode of the hybrid system (Sect. 2.6, Fig. 2–3), defined in bf-scene.
pub use bf_scene::Mode;

/// State x = (q, q̇, ω) of a finger with `N` joints: joint angles (rad), joint rates (rad/s),
/// ball angular velocity (rad/s, world axes).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct State<const N: usize = 3> {
    /// Joint angles q.
    pub q: VecN<N>,
    /// Joint velocities q̇.
    pub qd: VecN<N>,
    /// Ball angular velocity ω.
    pub omega: Vec3,
}

impl<const N: usize> State<N> {
    /// Build a state.
    pub fn new(q: VecN<N>, qd: VecN<N>, omega: Vec3) -> Self {
        Self { q, qd, omega }
    }

    /// Length 2N + 3 of the flat layout (q, q̇, ω).
    pub const DIM: usize = bf_scene::state_len(N);

    /// Writes the flat layout (q, q̇, ω) into `x` (length [`State::DIM`]).
    pub fn write_slice(&self, x: &mut [f64]) {
        x[..N].copy_from_slice(self.q.as_slice());
        x[N..2 * N].copy_from_slice(self.qd.as_slice());
        x[2 * N..2 * N + 3].copy_from_slice(self.omega.as_slice());
    }

    /// The flat layout (q, q̇, ω) as a vector.
    pub fn to_vec(&self) -> Vec<f64> {
        let mut x = vec![0.0; Self::DIM];
        self.write_slice(&mut x);
        x
    }

    /// Inverse of [`State::write_slice`]; `None` unless `x` has [`State::DIM`] entries.
    pub fn from_slice(x: &[f64]) -> Option<Self> {
        (x.len() == Self::DIM).then(|| Self {
            q: VecN::<N>::from_column_slice(&x[..N]),
            qd: VecN::<N>::from_column_slice(&x[N..2 * N]),
            omega: Vec3::from_column_slice(&x[2 * N..]),
        })
    }

    /// Error unless every component is finite.
    pub fn check_finite(&self) -> Result<()> {
        if self
            .q
            .iter()
            .chain(self.qd.iter())
            .chain(self.omega.iter())
            .all(|v| v.is_finite())
        {
            Ok(())
        } else {
            Err(ModelError::NonFinite { what: "state" })
        }
    }
}

impl State<3> {
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

    #[test]
    fn slice_layout_of_two_joints() {
        let x = State::<2>::new(
            VecN::<2>::new(1., 2.),
            VecN::<2>::new(3., 4.),
            Vec3::new(5., 6., 7.),
        );
        assert_eq!(State::<2>::DIM, 7);
        assert_eq!(x.to_vec(), vec![1., 2., 3., 4., 5., 6., 7.]);
        assert_eq!(State::<2>::from_slice(&x.to_vec()), Some(x));
        assert_eq!(State::<2>::from_slice(&[0.0; 9]), None);
    }
}
