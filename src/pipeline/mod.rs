//! The solve pipeline: everything that builds, solves, searches, refines, verifies and files an
//! optimal-control problem of bf-problem on the engines below it. It knows nothing of the
//! paper's experiments ([`crate::paper`] builds on it), so another problem of the catalogue, or
//! a new one, reuses it whole.
//!
//! * [`solve`](mod@solve): the solve-and-retry policy (interior-point settings, dual-regularization
//!   retry, geometric-guess fallback) and primal-dual warm starts;
//! * [`strategy`]: continuation and multi-start searches for good local optima (Sect. 7);
//! * [`search`]: the seeded multi-start search with re-integration and refinement of each end
//!   point;
//! * [`global`]: the global search (sampling, monotonic basin hopping, polishing) over any
//!   [`global::Landscape`];
//! * [`reshape`]: the reshaping moves of the global search (phase-duration bounds);
//! * [`refine`]: adaptive hp mesh refinement (Sect. 5);
//! * [`verify`]: re-integration of the optimal torques with the simulator (bf-sim);
//! * [`bounds`]: the bounds an optimum sits on (eq. 60–65);
//! * [`solution_io`]: `solution.json` and `torques.csv`;
//! * [`arm`]: `reach-arm` on arms without a ball: solve, per-element re-integration, files;
//! * [`error`]: [`PipelineError`], the one error type of the layer.
//!
//! [`build`] builds a catalogue problem on the scenes and node kernels of bf-generated
//! ([`GENERATED`]); it requires every phase node function to run on an emitted kernel, so a
//! graph that changed without its kernels being re-emitted is an error, not a slow solve.

pub mod arm;
pub mod bounds;
pub mod error;
pub mod global;
pub mod refine;
pub mod reshape;
pub mod search;
pub mod solution_io;
pub mod solve;
pub mod strategy;
pub mod verify;

use bf_optim::ocp::{KernelUse, NodeKernel};
use bf_problem::{BuiltProblem, Generated, Problem, ProblemSettings};

pub use bf_problem::OcpSolution;

pub use error::PipelineError;
pub use solution_io::SolutionIo;
pub use solve::{solve, solve_warm, solver_settings, warm_settings};

/// The emitted node kernel of bf-generated with this structural fingerprint, as bf-optim's
/// collocation takes it.
pub fn node_kernel(fingerprint: u128) -> Option<NodeKernel> {
    bf_generated::node_kernel(fingerprint).map(|k| NodeKernel {
        name: k.name,
        n_out: k.n_out,
        n_local: k.n_local,
        n_fixed: k.n_fixed,
        jacobian_pattern: k.jacobian_pattern,
        hessian_pattern: k.hessian_pattern,
        value: k.value,
        jacobian: k.jacobian,
        hessian: k.hessian,
        x4: k.x4.map(|b| bf_optim::ocp::NodeKernelX4 {
            value: b.value,
            jacobian: b.jacobian,
            hessian: b.hessian,
        }),
    })
}

/// The scenes and node kernels of bf-generated, kernels required.
pub const GENERATED: Generated = Generated {
    scene_toml: bf_generated::scene_toml,
    kernels: KernelUse::Require(node_kernel),
};

/// Builds `problem` with `settings` on [`GENERATED`].
pub fn build(problem: Problem, settings: &ProblemSettings) -> Result<BuiltProblem, PipelineError> {
    Ok(bf_problem::build(problem, settings, &GENERATED)?)
}
