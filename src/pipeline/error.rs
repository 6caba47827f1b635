//! [`PipelineError`]: the one error enum of the solve pipeline. The engines' errors pass through
//! unchanged ([`ProblemError`], [`OptimError`], [`SimError`]); the study's own variants name
//! the file, option or solution concerned, and keep an underlying error as the typed
//! [`source`](std::error::Error::source) instead of repeating its text. Where the whole cause
//! chain belongs in one line of text (records, warnings), use [`crate::errors::chain`].

use std::path::PathBuf;

use bf_optim::OptimError;
use bf_problem::solution::records::Strategy;
use bf_problem::{PhaseMode, ProblemError};
use bf_sim::SimError;

/// Everything that can go wrong in the solve pipeline.
#[derive(Debug, thiserror::Error)]
pub enum PipelineError {
    /// Building the problem failed.
    #[error(transparent)]
    Problem(#[from] ProblemError),
    /// The collocation layer or the NLP solver failed.
    #[error(transparent)]
    Optim(#[from] OptimError),
    /// The simulator rejected a verification state.
    #[error(transparent)]
    Sim(#[from] SimError),
    /// A file could not be read or written.
    #[error(transparent)]
    Io(#[from] bf_output::FileError),
    /// A solution file could not be serialised or parsed.
    #[error("{op} {}", path.display())]
    Json {
        /// What was attempted (`cannot serialise the solution for`, `cannot parse`).
        op: &'static str,
        /// The file.
        path: PathBuf,
        /// Why.
        #[source]
        source: serde_json::Error,
    },
    /// A solution file's content is not a solution of a known schema.
    #[error("{}: {reason}", path.display())]
    SolutionFile {
        /// The file.
        path: PathBuf,
        /// What is wrong with it.
        reason: String,
    },
    /// A solution cannot be recomputed from its own data (no scene text or primal point, or
    /// a point that does not fit the problem it names).
    #[error("{0}")]
    Unrecomputable(String),
    /// An arm solution (`reach-arm`) cannot be verified, read or written.
    #[error("{message}")]
    Arm {
        /// What failed, naming the scene or file.
        message: String,
    },
    /// A numeric option is outside its valid range.
    #[error("{name} must be {expected}, got {value}")]
    InvalidOption {
        /// The option.
        name: &'static str,
        /// Its value.
        value: f64,
        /// The valid range, as the message says it.
        expected: &'static str,
    },
    /// A multi-start search with zero starts.
    #[error("multi-start needs at least one start")]
    NoStarts,
    /// Mesh refinement of a Legendre–Gauss transcription.
    #[error("mesh refinement needs the Radau scheme")]
    RefineNeedsRadau,
    /// Every chain of a strategy failed; `stages` lists each failed stage with its cause.
    #[error("every {strategy} solve failed: {}", stages.join("; "))]
    AllChainsFailed {
        /// The strategy.
        strategy: Strategy,
        /// `chain: stage (cause)` of every stage.
        stages: Vec<String>,
    },
    /// A broken invariant of the study code itself (a bug, reported instead of a panic).
    #[error("internal: {0}")]
    Internal(&'static str),
    /// The bf-model model used for the verification cannot be set up.
    #[error("verification model of scene `{scene}`")]
    VerifyModel {
        /// The scene.
        scene: String,
        /// Why.
        #[source]
        source: bf_model::ModelError,
    },
    /// bf-model cannot evaluate a collocation node of the solution to verify.
    #[error("verification: phase {} node {} cannot be evaluated", .phase + 1, .node + 1)]
    NodeEvaluation {
        /// The phase, 0-based (the message counts from 1).
        phase: usize,
        /// The node within the phase, 0-based (the message counts from 1).
        node: usize,
        /// Why.
        #[source]
        source: bf_model::ModelError,
    },
    /// The verification model's physical constants differ from the ones the OCP was built with.
    #[error("bf-model parameters of scene `{scene}` differ from the OCP's: {model} vs {ocp}")]
    ParameterMismatch {
        /// The scene.
        scene: String,
        /// bf-model's parameters (`Debug` form).
        model: String,
        /// The OCP's physics (`Debug` form).
        ocp: String,
    },
    /// Verification of a scene whose finger has more joints than the verification runs.
    #[error("verification re-integrates fingers with 1 to {max} joints, `{scene}` has {joints}")]
    VerifyJoints {
        /// The scene.
        scene: String,
        /// Its joints.
        joints: usize,
        /// The most joints the verification runs (`verify::MAX_VERIFY_JOINTS`).
        max: usize,
    },
    /// The solution to verify has other phase modes than the problem.
    #[error(
        "verification: the solution has modes [{}], the problem [{}]",
        crate::names::names(solution),
        crate::names::names(problem)
    )]
    ModeMismatch {
        /// Modes of the solution.
        solution: Vec<PhaseMode>,
        /// Modes of the problem.
        problem: Vec<PhaseMode>,
    },
    /// The solution to verify was computed with another smoothing ε.
    #[error("verification: solution eps {solution} does not match the problem's {problem}")]
    EpsilonMismatch {
        /// ε of the solution.
        solution: f64,
        /// ε of the problem.
        problem: f64,
    },
    /// A phase trajectory of the solution to verify is inconsistent.
    #[error("verification: phase {} has {defect}", .phase + 1)]
    PhaseData {
        /// The phase, 0-based (the message counts from 1).
        phase: usize,
        /// What is wrong.
        defect: PhaseDataDefect,
    },
}

/// What is wrong with a phase trajectory handed to the verification.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum PhaseDataDefect {
    /// A duration that is not finite and positive.
    #[error("duration {0}")]
    Duration(f64),
    /// States of the wrong dimension (or none).
    #[error("states of the wrong dimension")]
    StateDimension,
    /// State points and nodes do not match.
    #[error("inconsistent state points / nodes")]
    Inconsistent,
    /// State points that do not span [−1, 1].
    #[error("state points not spanning [-1, 1]")]
    Span,
    /// Controls of the wrong dimension.
    #[error("controls of the wrong dimension")]
    ControlDimension,
    /// Not one vector of algebraic variables per node.
    #[error("algebraic variables of the wrong count")]
    AlgebraicCount,
    /// Element ranges that are empty, reversed or beyond the state points.
    #[error("invalid element ranges")]
    ElementRanges,
    /// A NaN or infinity in the states, controls, algebraic variables or times.
    #[error("non-finite values")]
    NonFinite,
    /// Too few algebraic variables at a node of `mode`.
    #[error(
        "{found} algebraic variables at a {} node, need {need}",
        crate::names::name(mode)
    )]
    AlgebraicDimension {
        /// Algebraic variables at the node.
        found: usize,
        /// The phase's mode.
        mode: PhaseMode,
        /// How many the mode needs.
        need: usize,
    },
    /// An element without collocation nodes.
    #[error("element {0} with no collocation nodes")]
    EmptyElement(usize),
}
