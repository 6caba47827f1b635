//! The layout of the ball-and-finger state x = (q, q̇, ω) of paper eq. 44, which the model, the
//! simulator, the optimal-control problem and the generator's variable layout share: the
//! joint angles q and velocities q̇ of a finger with nq joints, then the ball's angular
//! velocity ω (3 components, world axes).

/// Length 2 nq + 3 of the state x = (q, q̇, ω) (eq. 44) of a finger with `nq` joints.
pub const fn state_len(nq: usize) -> usize {
    2 * nq + 3
}
