//! `SimError`: the one error enum of bf-sim.
//!
//! Variants carry the context needed to act on them (time `t`, mode name, guard name, file and
//! line). A failed *run* is reported as [`crate::SimFailure`], which wraps a `SimError` together
//! with the partial trajectory computed before the failure.

use std::path::PathBuf;

/// Everything that can go wrong while setting up or running a hybrid simulation.
#[derive(Debug, thiserror::Error)]
pub enum SimError {
    /// A setting or argument is out of its valid range (e.g. `t_end <= t0`, `rtol <= 0`).
    #[error("invalid setting `{name}`: {msg}")]
    InvalidSetting {
        /// Name of the offending field or argument.
        name: &'static str,
        /// What is wrong with it.
        msg: String,
    },
    /// A state vector has the wrong length for the system.
    #[error("dimension mismatch for {what}: expected {expected}, found {found}")]
    DimensionMismatch {
        /// Which vector.
        what: &'static str,
        /// Length the system declares.
        expected: usize,
        /// Length that was passed.
        found: usize,
    },
    /// A NaN or infinity appeared in the state, the vector field or a guard, and step-size
    /// reduction could not get rid of it.
    #[error("non-finite value in {what} at t = {t} (mode {mode})")]
    NonFinite {
        /// Where it appeared (`initial state`, `vector field`, `guard <name>`, ...).
        what: String,
        /// Time at which it appeared.
        t: f64,
        /// Mode at that time (`Debug` form).
        mode: String,
    },
    /// The adaptive controller wanted a step below `h_min`.
    #[error("step size {h:e} below h_min at t = {t} (mode {mode})")]
    StepSizeTooSmall {
        /// Time of the failed step.
        t: f64,
        /// Rejected step size.
        h: f64,
        /// Mode at that time.
        mode: String,
    },
    /// More than `max_steps` accepted + rejected steps.
    #[error("step limit {max_steps} reached at t = {t} (mode {mode})")]
    MaxSteps {
        /// Time reached.
        t: f64,
        /// The limit from the settings.
        max_steps: usize,
        /// Mode at that time.
        mode: String,
    },
    /// More than `zeno_max_events` events inside a window of `zeno_window` seconds: the run
    /// approaches an accumulation point (Zeno behaviour) or chatters between modes.
    #[error(
        "Zeno/chattering: {count} events within the Zeno window ending at t = {t} (mode {mode})"
    )]
    Zeno {
        /// Time of the event that exceeded the limit.
        t: f64,
        /// Mode before that event.
        mode: String,
        /// Number of events counted in the window.
        count: usize,
    },
    /// More than `max_chained_events` instantaneous transitions at one time instant: the resets
    /// keep landing in states that immediately trigger another transition.
    #[error("{count} chained instantaneous transitions at t = {t} (mode {mode}); reset loop")]
    ChainLimit {
        /// Time instant of the chain.
        t: f64,
        /// Mode the chain got to.
        mode: String,
        /// Number of chained transitions.
        count: usize,
    },
    /// The system's per-mode validity check failed (e.g. constraint drift too large).
    #[error("state invalid for mode {mode} at t = {t}: {msg}")]
    InvalidState {
        /// Time of the check.
        t: f64,
        /// Mode being checked.
        mode: String,
        /// System-provided explanation.
        msg: String,
    },
    /// A trial state lies outside the domain where the current mode's vector field, guards or
    /// validity check are defined (e.g. a contact mode evaluated with |h| beyond the contact
    /// band). Raised by systems for states that a shorter step avoids: inside a step the
    /// simulator rejects the step and retries it shorter, so this ends a run only when raised at
    /// the initial state or by a reset, when the retried step would fall below `h_min`, or when
    /// the trajectory itself runs into the boundary (`SimSettings::max_domain_creep`
    /// consecutive accepted steps each needed a domain rejection).
    #[error("state outside the domain of mode {mode} at t = {t}: {msg}")]
    OutsideDomain {
        /// Time of the evaluation.
        t: f64,
        /// Mode being evaluated.
        mode: String,
        /// System-provided explanation.
        msg: String,
    },
    /// An error raised by the system implementation (vector field, guards, reset, projection),
    /// e.g. a singular contact matrix in the ball–finger model.
    #[error("system error: {msg}")]
    System {
        /// System-provided explanation, including the underlying error.
        msg: String,
    },
    /// An input file could not be read, or an output file not written.
    #[error(transparent)]
    Io(#[from] bf_output::FileError),
    /// An input file (torque series, ...) is malformed.
    #[error("{}{}: {msg}", path.display(), line.map(|l| format!(":{l}")).unwrap_or_default())]
    Parse {
        /// File concerned (`<memory>` for in-memory data).
        path: PathBuf,
        /// 1-based line (CSV) if known.
        line: Option<usize>,
        /// What is wrong.
        msg: String,
    },
    /// Serialising an output failed.
    #[error("cannot serialise {what}")]
    Serialize {
        /// What was being written.
        what: &'static str,
        /// The serialiser's error (csv or serde_json).
        #[source]
        source: Box<dyn std::error::Error + Send + Sync>,
    },
}

impl SimError {
    /// Whether a shorter step can avoid this error: [`SimError::OutsideDomain`] raised inside a
    /// trial step rejects the step instead of ending the run.
    pub fn is_step_rejectable(&self) -> bool {
        matches!(self, SimError::OutsideDomain { .. })
    }

    /// Wraps any error of a system implementation as [`SimError::System`]; the intended use is
    /// `model_call().map_err(SimError::system)?` inside a [`crate::HybridSystem`] impl.
    pub fn system<E: std::fmt::Display>(e: E) -> Self {
        SimError::System { msg: e.to_string() }
    }
}
