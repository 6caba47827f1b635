//! bf-optim: the optimisation layer of ball-finger.
//!
//! * [`ipm`]: a sparse primal-dual interior-point NLP solver in the style of Wächter & Biegler
//!   (2006) — Ipopt's algorithm — on faer's sparse LDLᵀ. It solves the collocation NLPs of the
//!   paper's trajectory optimisation (Sect. 4); the collocation layer (`ocp`) and the concrete
//!   problems (`problems`) are built on top of it.
//! * [`OptimError`]: the crate's error enum.

pub mod error;
pub mod ipm;
pub mod ocp;
pub mod problems;

pub use error::OptimError;
