//! bf-optim: the optimisation layer of ball-finger.
//!
//! * [`ipm`]: a sparse primal-dual interior-point NLP solver in the style of Wächter & Biegler
//!   (2006) — Ipopt's algorithm — on faer's sparse LDLᵀ. It solves the collocation NLPs of the
//!   paper's trajectory optimisation (Sect. 4);
//! * [`ocp`]: multiphase optimal control by pseudospectral collocation on top of it. Generic:
//!   the ball-and-finger problems live in bf-problem, and emitted node kernels come in through
//!   a lookup argument ([`ocp::KernelUse`]).
//! * [`OptimError`]: the crate's error enum, at the bottom with the problem terms it names
//!   ([`terms`]: [`ocp::Scheme`], [`ocp::Objective`], [`ocp::VarRef`]).

pub mod error;
pub mod ipm;
pub mod ocp;
pub mod terms;

pub use error::{FactorizationError, OptimError};
