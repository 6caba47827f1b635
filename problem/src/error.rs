//! [`ProblemError`]: the one error enum of bf-problem. Variants carry the scene, setting or
//! value concerned; an error of a layer below (a scene file, the symbolic model, the
//! collocation layer) is the typed [`source`](std::error::Error::source), and a message never
//! repeats its source's text.

use bf_codegen::CodegenError;
use bf_codegen::spec::SpecError;
use bf_optim::OptimError;

use crate::id::Problem;
use crate::start::StartGuess;

/// Everything that can go wrong while building a problem or its solution record.
#[derive(Debug, thiserror::Error)]
pub enum ProblemError {
    /// A name that is not a [`Problem`].
    #[error("unknown problem `{name}`; known problems: {names}", names = Problem::names())]
    UnknownProblem {
        /// The name given.
        name: String,
    },
    /// The scene a problem is posed on is not among the generated scenes.
    #[error("unknown scene `{scene}`")]
    UnknownScene {
        /// The scene name.
        scene: String,
    },
    /// The scene's text does not load.
    #[error("scene `{scene}` does not load")]
    Scene {
        /// The scene name.
        scene: String,
        /// Why.
        #[source]
        source: SpecError,
    },
    /// The symbolic model of the scene (physics, node functions, contact) cannot be built.
    #[error("cannot build the model of scene `{scene}`")]
    Model {
        /// The scene name.
        scene: String,
        /// Why.
        #[source]
        source: CodegenError,
    },
    /// A numeric problem setting is outside its valid range.
    #[error("{name} must be {expected}, got {value}")]
    InvalidSetting {
        /// The setting: the [`ProblemSettings`](crate::ProblemSettings) field (`epsilon`,
        /// `approach_clearance`, `min_stick`, …) where it is one.
        name: &'static str,
        /// Its value.
        value: f64,
        /// The valid range, as the message says it (`positive`).
        expected: &'static str,
    },
    /// The period bounds (problem defaults intersected with the setting) are empty.
    #[error("period bounds [{lower}, {upper}] are empty or not finite")]
    PeriodBounds {
        /// Lower bound, s.
        lower: f64,
        /// Upper bound, s.
        upper: f64,
    },
    /// A start guess does not fit the problem.
    #[error(
        "start guess needs {joints} finite joint angles and {phases} positive durations, got \
         {guess:?}"
    )]
    StartGuess {
        /// Joints of the scene.
        joints: usize,
        /// Phases of the problem.
        phases: usize,
        /// The guess given.
        guess: StartGuess,
    },
    /// The scene's finger has no contact configuration on the family of configurations the
    /// initial guesses of a finger other than the paper's 3-joint one are derived from.
    #[error(
        "scene `{scene}` ({joints} joints): no contact configuration for the initial guess: \
         {reason}"
    )]
    NoContactConfiguration {
        /// The scene name.
        scene: String,
        /// Its joints.
        joints: usize,
        /// What the search found (values of h and the configurations tried).
        reason: String,
    },
    /// A re-plan from a lift-off state that cannot be posed (catalogue `replan`): a state of
    /// the wrong length or with a non-finite value, a problem or solution that is not periodic.
    #[error("re-plan: {msg}")]
    Replan {
        /// What is wrong, naming the state, component or problem.
        msg: String,
    },
    /// A warm start from a solution with a different number of phases.
    #[error("warm start has {found} phases, the problem {expected}")]
    WarmStartPhases {
        /// Phases of the warm-start solution.
        found: usize,
        /// Phases of the problem.
        expected: usize,
    },
    /// A warm start whose collocation data of one phase do not fit together or do not fit the
    /// problem's phase (other state, algebraic or control widths).
    #[error("warm start: raw[{phase}]: {reason}")]
    WarmStartShape {
        /// The phase.
        phase: usize,
        /// What does not fit.
        reason: String,
    },
    /// An arm problem (`reach-arm`) cannot be posed on the scene as configured.
    #[error("scene `{scene}`: {message}")]
    Arm {
        /// The scene name.
        scene: String,
        /// What is wrong (the value and the bound it breaks).
        message: String,
    },
    /// The thread that builds a problem could not be started.
    #[error("cannot spawn the problem build thread")]
    BuildThread(#[source] std::io::Error),
    /// Building the problem panicked (a bug, reported instead of aborting the caller).
    #[error("the problem build panicked")]
    BuildPanicked,
    /// The collocation layer rejected the problem (or its solver failed).
    #[error(transparent)]
    Optim(#[from] OptimError),
}

impl ProblemError {
    /// [`ProblemError::Model`] of the scene `scene`, for `map_err`.
    pub(crate) fn model(scene: &str) -> impl FnOnce(CodegenError) -> ProblemError + '_ {
        move |source| ProblemError::Model {
            scene: scene.to_string(),
            source,
        }
    }
}
