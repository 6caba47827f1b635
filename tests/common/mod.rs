//! Helpers shared by the integration tests of the problem library.
pub mod fd;
pub mod kkt;
