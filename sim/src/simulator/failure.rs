//! [`SimFailure`], a failed run that keeps the partial trajectory, and [`simulate`], the
//! one-call wrapper of [`Simulator::new`] + [`Simulator::run`] (paper Sect. 3.2, Fig. 3).

use super::Simulator;
use crate::trajectory::{SimOutput, SimStats, Trajectory, events_csv, output_json, write_atomic};
use crate::{HybridSystem, SimError, SimSettings};
use std::fmt::Debug;
use std::path::Path;

/// A failed run: the error, where it happened, and everything computed before it.
#[derive(Debug)]
pub struct SimFailure<M> {
    /// The error that stopped the run.
    pub error: SimError,
    /// Time at which the run stopped.
    pub t: f64,
    /// Mode at that time (`None` if the run could not even start).
    pub mode: Option<M>,
    /// Trajectory, events and statistics up to the failure.
    pub partial: SimOutput<M>,
}

impl<M: Debug> std::fmt::Display for SimFailure<M> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "simulation failed at t = {} ({} samples, {} events kept): {}",
            self.t,
            self.partial.trajectory.len(),
            self.partial.events.len(),
            self.error
        )
    }
}

/// The message already states [`SimFailure::error`], so the chain continues with that error's
/// own source (an error chain would otherwise print it twice).
impl<M: Debug> std::error::Error for SimFailure<M> {
    fn source(&self) -> Option<&(dyn std::error::Error + 'static)> {
        std::error::Error::source(&self.error)
    }
}

impl<M: Debug> SimFailure<M> {
    /// Writes the partial trajectory, events and the error message as JSON (same layout as
    /// [`SimOutput::write_json`] plus `"error"`).
    pub fn write_json(&self, path: &Path) -> Result<(), SimError> {
        let p = &self.partial;
        let bytes = output_json(
            &p.trajectory,
            &p.events,
            p.stats,
            p.t_final,
            &p.mode_final,
            p.terminated,
            &p.warnings,
            Some(self.error.to_string()),
        )?;
        write_atomic(path, &bytes)
    }

    /// Writes the partial event log as CSV.
    pub fn write_events_csv(&self, path: &Path) -> Result<(), SimError> {
        write_atomic(path, &events_csv(&self.partial.events)?)
    }
}

/// Convenience wrapper: [`Simulator::new`] + [`Simulator::run`]. A setup error (bad settings,
/// NaN initial state, `t_end <= t0`, ...) is returned as a failure with an empty trajectory.
pub fn simulate<S: HybridSystem + ?Sized>(
    sys: &S,
    settings: SimSettings,
    mode0: S::Mode,
    t0: f64,
    x0: &[f64],
    t_end: f64,
) -> Result<SimOutput<S::Mode>, Box<SimFailure<S::Mode>>> {
    simulate_until(sys, settings, mode0, t0, x0, t_end, |_| false)
}

/// [`simulate`] with [`Simulator::run_until`]: the run ends early, without error, once
/// `until` says so (asked with the trajectory recorded so far after every step and event).
pub fn simulate_until<S: HybridSystem + ?Sized>(
    sys: &S,
    settings: SimSettings,
    mode0: S::Mode,
    t0: f64,
    x0: &[f64],
    t_end: f64,
    mut until: impl FnMut(&Trajectory<S::Mode>) -> bool,
) -> Result<SimOutput<S::Mode>, Box<SimFailure<S::Mode>>> {
    match Simulator::new(sys, settings, mode0, t0, x0, t_end) {
        Ok(sim) => sim.run_until(|s| until(s.trajectory())),
        Err(error) => Err(Box::new(SimFailure {
            error,
            t: t0,
            mode: Some(mode0),
            partial: SimOutput {
                trajectory: Trajectory::default(),
                events: Vec::new(),
                stats: SimStats::default(),
                t_final: t0,
                mode_final: mode0,
                terminated: false,
                warnings: Vec::new(),
            },
        })),
    }
}
