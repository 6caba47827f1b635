//! `SimSettings`: integrator, event-location and output settings (all SI, time in seconds).
//!
//! The Zeno guard and the chain limit implement the "allow a small violation, but terminate" stance
//! of the paper's Sect. 3.1: transition times are approximated to `event_tol`, and accumulating
//! transitions are either ended by the system's documented fallback
//! (`HybridSystem::zeno_fallback`, reported as a warning) or stopped with a clear error instead
//! of looping forever.

use crate::SimError;

/// Which Runge–Kutta scheme advances the continuous state.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Method {
    /// Adaptive Dormand–Prince 5(4) with PI step-size control and Hairer's 4th-order continuous
    /// extension (dense output). Uses `rtol`, `atol`, `h_init`, `h_min`, `h_max`.
    Dopri5,
    /// Classic fixed-step RK4 with step `h` (seconds) and a cubic Hermite dense output. The last
    /// step before `t_end` and the step after an event are shortened / restarted, so events are
    /// still located by root finding on the interpolant.
    Rk4 {
        /// Fixed step size in seconds (> 0).
        h: f64,
    },
}

/// The largest relative tolerance [`SimSettings::validate`] accepts: 10 % per step.
pub const MAX_RTOL: f64 = 0.1;

/// The smallest relative tolerance [`SimSettings::validate`] accepts: about 50 times the f64
/// rounding unit (2.2e-16). Below it the embedded error estimate measures the rounding of the
/// stages, not their truncation, and the step size drifts down to `h_min` or the sample limit.
pub const MIN_RTOL: f64 = 1e-14;

/// The largest absolute tolerance [`SimSettings::validate`] accepts: 0.1 (rad, rad/s) per step,
/// as [`MAX_RTOL`] is 10 %; beyond it the error control no longer bounds the steps, and the
/// states of the finger are of order 1.
pub const MAX_ATOL: f64 = 0.1;

/// Why a positive absolute tolerance `atol` is above [`MAX_ATOL`], or `None`: the one statement
/// of the bound, for [`SimSettings::validate`] and `simulate --atol`.
pub fn atol_out_of_range(atol: f64) -> Option<String> {
    (atol > MAX_ATOL).then(|| {
        format!(
            "must be at most {MAX_ATOL} (an absolute error of 0.1 rad or rad/s per step, beyond \
             which the step-size control no longer measures anything), got {}",
            crate::shown(atol)
        )
    })
}

/// Why a positive relative tolerance `rtol` is outside [[`MIN_RTOL`], [`MAX_RTOL`]] ("must be at
/// least …, got …" with the reason), or `None` within it: the one statement of the range, for
/// [`SimSettings::validate`] and the command lines that name their option.
pub fn rtol_out_of_range(rtol: f64) -> Option<String> {
    if rtol < MIN_RTOL {
        Some(format!(
            "must be at least {MIN_RTOL:e} (about 50 times the f64 rounding unit, below which the \
             error estimate measures rounding), got {}",
            crate::shown(rtol)
        ))
    } else if rtol > MAX_RTOL {
        Some(format!(
            "must be at most {MAX_RTOL} (a relative error of 10 % per step, beyond which the \
             step-size control no longer measures anything), got {}",
            crate::shown(rtol)
        ))
    } else {
        None
    }
}

/// Settings of a simulation run. Every field is public; [`SimSettings::default`] documents the
/// defaults and [`SimSettings::validate`] checks ranges.
#[derive(Debug, Clone, PartialEq)]
pub struct SimSettings {
    /// Integration scheme (default: [`Method::Dopri5`]).
    pub method: Method,
    /// Relative tolerance of the DOPRI5 error test (default: 1e-8).
    pub rtol: f64,
    /// Absolute tolerance of the DOPRI5 error test, in state units (default: 1e-10).
    pub atol: f64,
    /// Initial step size in seconds; `None` selects it automatically from the vector field
    /// (Hairer–Nørsett–Wanner's starting-step heuristic) (default: `None`).
    pub h_init: Option<f64>,
    /// Smallest allowed step in seconds; a smaller request is [`SimError::StepSizeTooSmall`]
    /// (default: 1e-14).
    pub h_min: f64,
    /// Largest allowed step in seconds (default: 0.1). Also bounds how long a guard excursion
    /// can hide between the sub-samples of one step.
    pub h_max: f64,
    /// Maximum number of attempted steps (accepted + rejected) per run (default: 1_000_000).
    pub max_steps: usize,
    /// Absolute tolerance on event times in seconds: a located event time is within this of the
    /// true zero of the guard on the dense output, on the crossed side (default: 1e-12).
    pub event_tol: f64,
    /// Number of equal sub-intervals per step on which guard signs are sampled, so a double
    /// crossing inside one step is seen (default: 4).
    pub event_subdivisions: usize,
    /// Guard values with |g| <= this are "on the surface" right after a reset or at the start;
    /// such guards are neither retriggered nor lose their next genuine crossing (default: 1e-9).
    pub guard_zero_tol: f64,
    /// Zeno guard: more than this many events within `zeno_window` seconds calls the system's
    /// `HybridSystem::zeno_fallback`, and without one is [`SimError::Zeno`] (default: 100).
    pub zeno_max_events: usize,
    /// Zeno guard window in seconds (default: 1e-3).
    pub zeno_window: f64,
    /// Maximum number of instantaneous transitions chained at one time instant before
    /// [`SimError::ChainLimit`] (default: 16).
    pub max_chained_events: usize,
    /// A trial step that leaves the mode's domain ([`SimError::OutsideDomain`]) is rejected and
    /// retried shorter; when this many consecutive accepted steps each needed such a rejection,
    /// the trajectory itself runs into the domain boundary (the steps creep towards it), and the
    /// run stops with that error (default: 32).
    pub max_domain_creep: usize,
    /// Record a sample at every accepted step (default: true).
    pub record_steps: bool,
    /// Additionally record samples on the uniform grid t0 + k·dt via dense output (default:
    /// `None`).
    pub output_dt: Option<f64>,
}

impl Default for SimSettings {
    fn default() -> Self {
        SimSettings {
            method: Method::Dopri5,
            rtol: 1e-8,
            atol: 1e-10,
            h_init: None,
            h_min: 1e-14,
            h_max: 0.1,
            max_steps: 1_000_000,
            event_tol: 1e-12,
            event_subdivisions: 4,
            guard_zero_tol: 1e-9,
            zeno_max_events: 100,
            zeno_window: 1e-3,
            max_chained_events: 16,
            max_domain_creep: 32,
            record_steps: true,
            output_dt: None,
        }
    }
}

impl SimSettings {
    /// Checks that every field is in range; returns the first violation as
    /// [`SimError::InvalidSetting`].
    pub fn validate(&self) -> Result<(), SimError> {
        fn pos(name: &'static str, v: f64) -> Result<(), SimError> {
            if v.is_finite() && v > 0.0 {
                Ok(())
            } else {
                Err(SimError::InvalidSetting {
                    name,
                    msg: format!("must be finite and > 0, got {v}"),
                })
            }
        }
        pos("rtol", self.rtol)?;
        if let Some(msg) = rtol_out_of_range(self.rtol) {
            return Err(SimError::InvalidSetting { name: "rtol", msg });
        }
        pos("atol", self.atol)?;
        if let Some(msg) = atol_out_of_range(self.atol) {
            return Err(SimError::InvalidSetting { name: "atol", msg });
        }
        pos("h_min", self.h_min)?;
        pos("h_max", self.h_max)?;
        if let Some(h) = self.h_init {
            pos("h_init", h)?;
        }
        if let Method::Rk4 { h } = self.method {
            pos("method.h", h)?;
        }
        if self.h_min > self.h_max {
            return Err(SimError::InvalidSetting {
                name: "h_min",
                msg: format!("h_min {} > h_max {}", self.h_min, self.h_max),
            });
        }
        pos("event_tol", self.event_tol)?;
        pos("guard_zero_tol", self.guard_zero_tol)?;
        pos("zeno_window", self.zeno_window)?;
        if let Some(dt) = self.output_dt {
            pos("output_dt", dt)?;
        }
        let nonzero = |name: &'static str, v: usize| {
            if v == 0 {
                Err(SimError::InvalidSetting {
                    name,
                    msg: "must be >= 1".into(),
                })
            } else {
                Ok(())
            }
        };
        nonzero("max_steps", self.max_steps)?;
        nonzero("event_subdivisions", self.event_subdivisions)?;
        nonzero("zeno_max_events", self.zeno_max_events)?;
        nonzero("max_chained_events", self.max_chained_events)?;
        nonzero("max_domain_creep", self.max_domain_creep)?;
        Ok(())
    }
}
