//! Multiphase optimal control by pseudospectral collocation (paper Sect. 4–5).
//!
//! The collocation modules form one chain, each using only those before it:
//!
//! * [`nodes`]: Legendre–Gauss / Gauss–Radau nodes, weights, differentiation matrices;
//! * [`mesh`]: the collocation mesh of a phase (LG, uniform or custom hp-Radau) and the ph
//!   refinement rule;
//! * [`transcription`]: the sparse NLP handed to the interior-point solver ([`crate::ipm`]);
//! * [`trajectory`]: extraction and interpolation of the solution;
//! * [`estimate`]: the collocation error estimate of a solution, per element.
//!
//! Beside the chain, used by it: [`problem`], the multiphase problem (eq. 57): phases, node
//! functions, point functions; [`block`], graph functions with exact Jacobians and Hessians
//! (bf-codegen `diff`), on emitted kernels handed in by the caller or interpreted. [`toys`]:
//! problems with closed-form optima (double integrator, brachistochrone) for tests.

pub mod block;
pub mod estimate;
pub mod mesh;
pub mod nodes;
pub mod problem;
pub mod toys;
pub mod trajectory;
pub mod transcription;

/// The expression graph in which node and point functions are written (bf-codegen's), so a
/// user of this crate builds problems without naming the generator crate.
pub use bf_codegen::graph::{Graph, Id};
pub use block::{GraphFn, KernelLookup, KernelUse, NodeKernel, NodeKernelFn, NodeKernelX4, Part};
pub use estimate::collocation_errors;
pub use mesh::{HpRule, Mesh, MeshSpec};
pub use problem::{
    EndRamp, NodeFunction, Objective, Ocp, Param, Phase, PhaseGuess, PointFunction, Scheme, VarRef,
};
pub use trajectory::{PhaseTrajectory, extract};
pub use transcription::{PhaseLayout, StateBoundBetweenPoints, Transcription};

use crate::OptimError;
use crate::ipm::{IterationInfo, Settings, Solution, WarmStart, solve_with};

/// Solves the transcribed problem with the interior-point solver (optional primal-dual warm
/// start and per-iteration callback; return `false` from it to stop).
pub fn solve_nlp(
    tr: &Transcription,
    settings: &Settings,
    warm: Option<&WarmStart>,
    callback: Option<&mut dyn FnMut(&IterationInfo) -> bool>,
) -> Result<Solution, OptimError> {
    solve_with(tr, settings, warm, callback)
}
