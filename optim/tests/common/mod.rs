//! Shared test problems.
pub mod double_integrator;
