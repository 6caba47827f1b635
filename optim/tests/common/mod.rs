//! Shared test problems.
pub mod cheb;
pub mod double_integrator;
