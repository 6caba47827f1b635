//! ball-finger: the command implementations behind the `ball-finger` binary, shared with the
//! integration tests in `tests/` and the benchmarks in `benches/`.
//!
//! The pipeline (docs/architecture.md): a scene file (`scenes/*.toml`, DH table of paper
//! Table 1 plus inertias) → `bf-codegen` (symbolic kinematics/dynamics, Appendix A/B and
//! eq. 22–33) → `bf-generated` (flat kernels) → `bf-model` (Sect. 2–3 physics) → `bf-sim`
//! (hybrid simulation, Fig. 3); `bf-problem` (the Sect. 4 optimal-control problem) on
//! `bf-optim` (collocation and interior point) → [`pipeline`] (solve policy, strategies,
//! refinement, verification, solution files) → [`paper`] (the paper's experiments and reports)
//! → `commands`.

pub mod cli;
pub mod commands;
pub mod errors;
pub mod io;
pub mod names;
pub mod paper;
pub mod pipeline;
pub mod progress;
