//! The crate's one error type, shared by the interior-point solver ([`crate::ipm`]) and the
//! collocation layer ([`crate::ocp`]): a collocation error is an NLP that cannot be built, and
//! a solver error surfaces through the same `solve_nlp` call, so callers match on one enum.
//! Non-convergence of a solve is *not* an error (it is a [`Status`](crate::ipm::Status) in the
//! returned solution); errors are real breakdowns: invalid problem data, non-finite values
//! where no step can recover, or a failed linear-solver analysis.
//!
//! Variants carry the data (phase, index, lengths, the offending value) rather than text, so
//! callers can act on them; their messages name the same things. A failed factorization is a
//! [`FactorizationError`], with faer's error as its `source()`.

use thiserror::Error;

use crate::terms::{Objective, Scheme, VarRef};

/// Errors of `bf-optim`.
#[derive(Debug, Error, Clone, PartialEq)]
pub enum OptimError {
    /// A vector or pattern had the wrong length.
    #[error("dimension mismatch in {what}: expected {expected}, found {found}")]
    DimensionMismatch {
        /// Which quantity.
        what: &'static str,
        /// Expected length.
        expected: usize,
        /// Actual length.
        found: usize,
    },
    /// A sparsity-pattern entry is out of range, or above the diagonal for the Hessian and
    /// the KKT matrix, or not above the previous row of its column in a KKT pattern
    /// ([`KktSolver::analyse`](crate::ipm::KktSolver::analyse)).
    #[error("invalid sparsity pattern in {what}: entry {index} = ({row}, {col})")]
    InvalidPattern {
        /// `"jacobian"`, `"hessian"` or `"kkt"`.
        what: &'static str,
        /// Triplet index.
        index: usize,
        /// Row of the entry.
        row: usize,
        /// Column of the entry.
        col: usize,
    },
    /// The column pointers of a KKT pattern given to
    /// [`KktSolver::analyse`](crate::ipm::KktSolver::analyse) do not rise from 0 to the
    /// number of row indices.
    #[error(
        "invalid KKT column pointer {index} = {value}: the pointers must rise from 0 to the \
         number of row indices ({entries})"
    )]
    InvalidColumnPointers {
        /// Index of the first pointer out of place.
        index: usize,
        /// Its value.
        value: usize,
        /// Number of row indices.
        entries: usize,
    },
    /// Inconsistent bounds: lower > upper, a NaN, a lower bound at +∞ (≥
    /// [`BOUND_INF`](crate::ipm::BOUND_INF) = 1e19) or an upper bound at −∞ (≤ −1e19).
    #[error("invalid bounds for {what} {index}: [{lower}, {upper}]")]
    InvalidBounds {
        /// `"variable"` or `"constraint"`.
        what: &'static str,
        /// Index.
        index: usize,
        /// Lower bound.
        lower: f64,
        /// Upper bound.
        upper: f64,
    },
    /// An entry of an input vector is out of its range: a non-finite warm-start value, or a
    /// user scaling factor ([`NlpScaling`](crate::ipm::NlpScaling)) that is not positive and
    /// finite.
    #[error("invalid {what} entry {index}: {value} (must be {expected})")]
    InvalidValue {
        /// Which vector (`"warm-start lambda"`, `"constraint scaling"`, …).
        what: &'static str,
        /// Index of the entry (0 for the objective scaling factor).
        index: usize,
        /// The entry.
        value: f64,
        /// What it must be.
        expected: &'static str,
    },
    /// A function or derivative was not finite at the initial point or at an accepted point,
    /// or the Hessian was not finite (no step cut can help; see [`Nlp`](crate::ipm::Nlp)).
    #[error("non-finite {what} at iteration {iter}")]
    NonFinite {
        /// Iteration number.
        iter: usize,
        /// Which quantity.
        what: &'static str,
    },
    /// The sparse factorization could not be set up.
    #[error(transparent)]
    Factorization(#[from] FactorizationError),
    /// A setting is out of its valid range.
    #[error("invalid setting {name}: {msg}")]
    InvalidSetting {
        /// Field name.
        name: &'static str,
        /// Why.
        msg: String,
    },
    /// Fewer than two collocation points per phase (or per element).
    #[error("need at least 2 collocation points, got {points}")]
    TooFewPoints {
        /// The requested number of points.
        points: usize,
    },
    /// A custom mesh was given for a scheme that has no elements (LG, or Radau with 0).
    #[error("a custom mesh needs the Radau scheme with ≥ 1 element, got {scheme:?}")]
    CustomMeshScheme {
        /// The problem's scheme.
        scheme: Scheme,
    },
    /// A mesh specification violates one of its invariants.
    #[error("mesh: {0}")]
    InvalidMesh(MeshDefect),
    /// More meshes (or trajectories) than the problem has phases, or a trajectory list of the
    /// wrong length.
    #[error("{found} {what} for {phases} phases")]
    PhaseCount {
        /// `"meshes"` or `"trajectories"`.
        what: &'static str,
        /// How many were given.
        found: usize,
        /// How many phases the problem has.
        phases: usize,
    },
    /// The problem has no phase.
    #[error("no phases")]
    NoPhases,
    /// The objective refers to a cost state that does not exist (or a ratio of one with itself).
    #[error("objective {objective:?} with {costs} cost states")]
    InvalidObjective {
        /// The objective.
        objective: Objective,
        /// Number of cost states.
        costs: usize,
    },
    /// `cost_bounds` is neither empty nor one entry per cost state.
    #[error("cost_bounds has {found} entries; it needs one per cost state ({costs})")]
    CostBounds {
        /// Number of entries given.
        found: usize,
        /// Number of cost states.
        costs: usize,
    },
    /// A phase's node function, bounds or trajectory is inconsistent.
    #[error("phase {index} (`{name}`): {defect}")]
    Phase {
        /// Index of the phase.
        index: usize,
        /// Name of the phase.
        name: String,
        /// What is wrong.
        defect: PhaseDefect,
    },
    /// A point function is inconsistent.
    #[error("point function `{name}`: {defect}")]
    PointFunction {
        /// Name of the point function.
        name: String,
        /// What is wrong.
        defect: PointDefect,
    },
    /// A bound on a state between the state points ([`crate::ocp::StateBoundBetweenPoints`])
    /// names no state of the transcription, or its bounds or point count are unusable.
    #[error("bound on state {component} of phase {phase} between the state points: {reason}")]
    StateBound {
        /// Phase index as given.
        phase: usize,
        /// State component as given.
        component: usize,
        /// What is wrong.
        reason: &'static str,
    },
    /// The differentiation matrix of a Gauss mesh could not be inverted (too many points).
    #[error("singular Gauss differentiation matrix ({points} collocation points)")]
    SingularDifferentiation {
        /// Number of collocation points of the mesh.
        points: usize,
    },
}

/// Why the KKT factorization (or the external solver) could not be set up.
#[derive(Debug, Error, Clone, PartialEq)]
pub enum FactorizationError {
    /// faer's symbolic analysis of the KKT pattern failed (index overflow, allocation).
    #[error("KKT factorization: symbolic analysis failed")]
    SymbolicAnalysis(#[source] faer::sparse::FaerError),
    /// The multifrontal analysis cannot index the KKT's fronts (the matrix is too large for
    /// its index types).
    #[error("KKT factorization: multifrontal analysis: KKT too large")]
    TooLarge,
    /// The workspace of the numeric factorization and solve could not be allocated.
    #[error("KKT factorization: out of memory for the KKT workspace")]
    OutOfMemory,
    /// Ipopt rejected the problem at creation; the `Debug` text of its `CreateError`, kept as
    /// text so the enum does not depend on the optional `ipopt` feature.
    #[error("KKT factorization: ipopt: {0}")]
    Ipopt(String),
}

/// What is wrong with a [`MeshSpec`](crate::ocp::MeshSpec).
#[derive(Debug, Error, Clone, PartialEq)]
pub enum MeshDefect {
    /// `breaks` must have one entry more than `degrees`, and there must be an element.
    #[error("{breaks} breaks for {elements} elements")]
    BreakCount {
        /// Number of breaks.
        breaks: usize,
        /// Number of elements (degrees).
        elements: usize,
    },
    /// The breaks do not span [−1, 1].
    #[error("breaks must start at −1 and end at +1, got {first} … {last}")]
    Span {
        /// First break.
        first: f64,
        /// Last break.
        last: f64,
    },
    /// The breaks are not strictly increasing (or not finite).
    #[error("breaks must be strictly increasing (element {element})")]
    NotIncreasing {
        /// First element whose end is not above its start.
        element: usize,
    },
    /// An element degree outside 2..=64.
    #[error("element {element} has degree {degree}, outside 2..=64")]
    Degree {
        /// The element.
        element: usize,
        /// Its degree.
        degree: usize,
    },
}

/// A node or point function whose exact derivatives would exceed its graph's node limit
/// ([`bf_codegen::graph::Graph::limit`]): the defect of [`PhaseDefect::GraphTooLarge`] and
/// [`PointDefect::GraphTooLarge`].
#[derive(Debug, Error, Clone, PartialEq)]
#[error(
    "the {function} function and its exact derivatives would hold more than {limit} graph nodes; \
     raise the limit with --max-graph-nodes if the machine has the memory (about {} bytes a \
     node)",
    bf_codegen::BYTES_PER_NODE
)]
pub struct FunctionTooLarge {
    /// `"node"` or `"point"`.
    pub function: &'static str,
    /// The graph's node limit.
    pub limit: usize,
}

/// What is wrong with a [`Phase`](crate::ocp::Phase) (or its trajectory).
#[derive(Debug, Error, Clone, PartialEq)]
pub enum PhaseDefect {
    /// The node function's derivatives would exceed its graph's node limit.
    #[error(transparent)]
    GraphTooLarge(FunctionTooLarge),
    /// `xdot` must have one entry per state.
    #[error("xdot has {found} entries for {states} states")]
    XdotLength {
        /// Entries of `xdot`.
        found: usize,
        /// Number of states.
        states: usize,
    },
    /// One cost integrand per cost state is required.
    #[error("{found} cost integrands for {costs} cost states")]
    CostCount {
        /// Integrands of the node function.
        found: usize,
        /// Cost states of the problem.
        costs: usize,
    },
    /// A bounds vector has the wrong length.
    #[error("{which} has {found} entries, expected {expected}")]
    BoundsLength {
        /// `"path_bounds"`, `"x_bounds"`, `"a_bounds"` or `"u_bounds"`.
        which: &'static str,
        /// Its length.
        found: usize,
        /// The length the node function needs.
        expected: usize,
    },
    /// An [`crate::ocp::EndRamp`] outside its ranges.
    #[error(
        "end ramp on path output {index} of {outputs}: clearance {clearance} (finite, ≥ 0) \
         and ramp {ramp} (in (0, 1]) out of range"
    )]
    EndRamp {
        /// The path output it bounds.
        index: usize,
        /// Number of path outputs.
        outputs: usize,
        /// Its clearance.
        clearance: f64,
        /// Its ramp.
        ramp: f64,
    },
    /// Emitted kernels are required but none has the structure of the node function.
    #[error(
        "no emitted node kernel has the structure of its node function (the graphs changed \
         since the kernels were emitted, or this phase shape is not emitted)"
    )]
    NoKernel,
    /// A trajectory does not match the node function's dimensions.
    #[error("trajectory does not match the node function")]
    TrajectoryShape,
}

/// What is wrong with a [`PointFunction`](crate::ocp::PointFunction).
#[derive(Debug, Error, Clone, PartialEq)]
pub enum PointDefect {
    /// The point function's derivatives would exceed its graph's node limit.
    #[error(transparent)]
    GraphTooLarge(FunctionTooLarge),
    /// `bounds` must have one entry per output.
    #[error("{bounds} bounds for {outputs} outputs")]
    BoundsLength {
        /// Number of outputs.
        outputs: usize,
        /// Number of bounds.
        bounds: usize,
    },
    /// A variable reference names a phase, state or parameter that does not exist.
    #[error("bad reference {0:?}")]
    BadReference(VarRef),
    /// The same NLP variable is read twice.
    #[error("reads a variable twice")]
    ReadsTwice,
}
