//! The `HybridSystem` trait: the model → sim boundary (paper Sect. 3, Fig. 2–3).
//!
//! A hybrid system is a set of discrete modes (Free / Stick / Slip for the ball and finger,
//! eq. 45–47), a continuous state x with a mode-dependent vector field ẋ = f(mode, t, x) (eq. 44
//! with λ from eq. 45–47), per-mode guard functions g_i(mode, t, x) whose zero crossings are the
//! transition conditions (eq. 50, λ_n < 0, σ ≤ 0, ‖Δv‖ ≤ ε), and reset maps (the impact laws,
//! eq. 39–43) that give the post-transition mode and state.
//!
//! * A reset returns the *next mode*, chosen from the state: an impact can go to Stick or Slip
//!   depending on Δv⁺ (Fig. 3's "In-contact" pseudo-state).
//! * A reset may land in a state where a directional guard of the new mode is already past its
//!   zero (e.g. Stick with σ < 0). The simulator then fires that guard immediately at the same
//!   time instant: transitions chain, bounded by `SimSettings::max_chained_events`.
//! * `project` is the constraint-drift hook of the simulator (`docs/architecture.md`): it may pull the state back onto
//!   h = 0 / the stick constraint after each accepted step and returns the drift it removed.
//! * A state outside a mode's domain (e.g. a contact mode far from contact) is reported as
//!   [`SimError::OutsideDomain`]; inside a trial step it rejects the step, which is retried
//!   shorter, instead of ending the run.
//! * `zeno_fallback` lets a system end an accumulation of events (Zeno behaviour, chattering)
//!   by a documented regularisation instead of the default [`SimError::Zeno`].
//! * `fixed_step` tells the system the step of a fixed-step method before every step, so a
//!   guard can see a transition that one such step cannot resolve (the ball and finger's
//!   `slip_stop`: the slip's stop, Sect. 3.1, decision record 0088).

use crate::SimError;
use std::fmt::Debug;

/// Which zero crossings of a guard trigger its transition.
///
/// Directional guards are *region* guards, like the paper's transition conditions (eq. 50,
/// λ_n < 0, σ ≤ 0): the mode is valid while s·g > 0 (s = +1 for `Falling`, −1 for `Rising`)
/// and the transition fires when the state leaves that region — by a crossing during a step,
/// by starting beyond `guard_zero_tol` on the triggered side right after a reset (chained
/// transition), or by sliding out of the ±`guard_zero_tol` band into the triggered side after
/// starting on the surface (eq. 50's "h = ḣ = 0 ∧ ḧ < 0"). A reset must therefore leave the
/// state in the valid region of the guards of the mode it returns (or on their surface);
/// use `Either` for pure crossing detectors (counters, Poincaré sections).
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub enum Direction {
    /// g goes from < 0 to ≥ 0. The "triggered side" is g > 0.
    Rising,
    /// g goes from > 0 to ≤ 0 (e.g. h for impact, eq. 50). The "triggered side" is g < 0.
    Falling,
    /// Any sign change. There is no triggered side, so such a guard never fires immediately
    /// after a reset.
    Either,
}

/// Static description of one guard of a mode.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Guard {
    /// Name used in the event log (`"impact"`, `"lambda_n"`, `"sigma"`, ...).
    pub name: &'static str,
    /// Crossing direction that triggers the transition.
    pub direction: Direction,
}

impl Guard {
    /// A guard triggering when g goes from positive to ≤ 0.
    pub const fn falling(name: &'static str) -> Self {
        Guard {
            name,
            direction: Direction::Falling,
        }
    }
    /// A guard triggering when g goes from negative to ≥ 0.
    pub const fn rising(name: &'static str) -> Self {
        Guard {
            name,
            direction: Direction::Rising,
        }
    }
    /// A guard triggering on any sign change.
    pub const fn either(name: &'static str) -> Self {
        Guard {
            name,
            direction: Direction::Either,
        }
    }
}

/// Outcome of a reset map.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Transition<M> {
    /// Continue in this mode from the (possibly modified) state.
    To(M),
    /// Stop the simulation here (e.g. the finger left the workspace); the run ends successfully
    /// with `StopReason::Terminated`.
    Terminate,
}

/// A hybrid dynamical system with modes, vector fields, guards and resets.
///
/// All methods take `&self`: per-call scratch memory must live in the implementation (e.g. a
/// `RefCell`) or be allocated; the simulator never calls them concurrently.
pub trait HybridSystem {
    /// Discrete mode. `Debug` gives the name written to trajectories and errors.
    type Mode: Copy + PartialEq + Debug;

    /// Dimension n of the continuous state x.
    fn dim(&self) -> usize;

    /// Vector field: writes ẋ = f(mode, t, x) into `dx` (length n).
    fn rhs(&self, mode: Self::Mode, t: f64, x: &[f64], dx: &mut [f64]) -> Result<(), SimError>;

    /// The guards active in `mode`, in a fixed order (the index is the guard id passed to
    /// [`HybridSystem::guard_values`] and [`HybridSystem::reset`]). Default: none (a plain
    /// ODE; then the defaults of `guard_values` and `reset` are never called).
    fn guards(&self, _mode: Self::Mode) -> Vec<Guard> {
        Vec::new()
    }

    /// Writes g_i(mode, t, x) for every guard of `mode` into `out` (length = `guards(mode).len()`).
    /// Evaluated together because guards usually share work (contact forces λ, eq. 33).
    /// Default: writes nothing (for systems without guards).
    fn guard_values(
        &self,
        _mode: Self::Mode,
        _t: f64,
        _x: &[f64],
        _out: &mut [f64],
    ) -> Result<(), SimError> {
        Ok(())
    }

    /// Reset map of guard `guard` of `mode` at the event time `t`: modifies `x` in place
    /// (length n) and returns the next mode (or termination). Default: the identity (same
    /// mode, `x` unchanged), e.g. for pure crossing detectors.
    fn reset(
        &self,
        mode: Self::Mode,
        _guard: usize,
        _t: f64,
        _x: &mut [f64],
    ) -> Result<Transition<Self::Mode>, SimError> {
        Ok(Transition::To(mode))
    }

    /// Optional drift control after every accepted step and before every reset: may project `x`
    /// back onto the mode's constraint manifold. Returns the drift measured *before* projection
    /// (`None` if the mode has nothing to project). Default: no projection.
    fn project(&self, _mode: Self::Mode, _t: f64, _x: &mut [f64]) -> Result<Option<f64>, SimError> {
        Ok(None)
    }

    /// The length of the steps the simulator takes from now on when its method cannot shorten
    /// them (fixed-step RK4: `Some(h)`), or `None` for an adaptive method; called before every
    /// step. A system whose guard must see a transition that happens inside one such step
    /// (where the iteration cannot resolve it) can use it. Default: ignored.
    fn fixed_step(&self, _h: Option<f64>) {}

    /// Optional validity check of `x` in `mode`, called on the (projected) end of every trial
    /// step and after every reset. After a trial step [`SimError::OutsideDomain`] rejects the
    /// step, which is retried shorter; any other `Err` (typically [`SimError::InvalidState`]),
    /// or one after a reset, stops the run with the partial trajectory. Default: always valid.
    fn check_valid(&self, _mode: Self::Mode, _t: f64, _x: &[f64]) -> Result<(), SimError> {
        Ok(())
    }

    /// Zeno fallback, called when more than `SimSettings::zeno_max_events` events fell within
    /// `SimSettings::zeno_window`, right after the reset of the last one: `mode` and `x` are
    /// the post-reset mode and state, `recent` the guard name and mode before each event of
    /// the window, oldest first. A system that can end the cascade (e.g. by suspending a
    /// chattering guard for a while, or by choosing another mode) may modify `x` and returns the
    /// mode to continue in with a one-line description of what it did; the simulator records it
    /// as a `zeno_fallback` [`crate::SimWarning`], clears the window and continues. `Ok(None)`
    /// (the default) stops the run with [`SimError::Zeno`].
    fn zeno_fallback(
        &self,
        _mode: Self::Mode,
        _t: f64,
        _x: &mut [f64],
        _recent: &[(&'static str, Self::Mode)],
    ) -> Result<Option<(Self::Mode, String)>, SimError> {
        Ok(None)
    }
}
