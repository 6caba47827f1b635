//! Helpers shared by the integration tests of the problem library.
pub mod kkt;
