//! bf-testkit: independent reference implementations, used by tests and by
//! `ball-finger verify appendix` (the paper's appendix checked against them); never by the
//! simulation or optimisation code.
//!
//! * [`reference`](mod@reference): kinematics, Lagrangian dynamics (eq. 22–24, 76), gravity (eq. 72 with the
//!   docs/parameters.md sign), contact geometry (eq. 2–13, 33, 58–59) for any scene, with exact
//!   derivatives from dual numbers; and a recursive Newton–Euler inverse dynamics.
//! * [`appendix`]: the paper's Appendix A (eq. 67–71) and Appendix B (eq. 72–79) transcribed
//!   literally, plus the corrected forms (see docs/appendix-errata.md).
//! * [`small`]: generic fixed-size linear algebra used by both.
//! * [`urdf_tree`]: spatial-algebra RNEA, CRBA and forward kinematics on a URDF's whole tree,
//!   read by its own XML reader (the check of the URDF import, eq. 22).

pub mod appendix;
pub mod error;
pub mod reference;
pub mod small;
pub mod urdf_tree;

pub use error::TestkitError;
pub use reference::{ContactKind, Pose, RefBall, RefContact, RefLink, Reference};

#[cfg(test)]
mod appendix_tests;
#[cfg(test)]
mod reference_tests;
