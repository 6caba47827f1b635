//! The joint torques of a `ball-finger simulate` run ([`CliInput`]): an open-loop series
//! (`--torques`, Sect. 6.2), a joint-space PD controller (`--pd`), a solution's torques with PD
//! tracking of its trajectory (`--pd-track`, Sect. 7, `paper::openloop::tracking_input`), or
//! none.

use crate::cli::SimulateArgs;
use crate::errors::bail_usage;
use crate::io::parse_list;
use anyhow::{Context, Result, bail};
use bf_sim::{Input, PdController, SimError, TorqueSeries, TrackingPd};

/// Joint torques of a CLI run: a time series, a PD controller, or none (τ = 0).
#[derive(Debug, Clone)]
pub enum CliInput {
    /// Open-loop torques τ(t) (`--torques`).
    Series(TorqueSeries),
    /// τ = kp (target − q) − kd q̇ (`--pd`).
    Pd(PdController),
    /// A solution's torques with PD tracking of its trajectory (`--init` with `--pd-track`).
    Tracking(TrackingPd),
    /// Unactuated joints of a finger with this many joints.
    Zero(usize),
    /// Unactuated joints of an arm with this many joints.
    Arm(usize),
    /// An arm solution's torques replayed with its own control polynomials (`--init`), the
    /// interpolant its collocation and verification use: a linear interpolation of its dense
    /// samples ends measurably off the target (1.7e-4 rad on the 2-link test arm).
    Replay(crate::pipeline::arm::PhaseTorque),
}

impl CliInput {
    /// The last time of a `--torques` series or of a replayed arm solution (s): past it the
    /// input holds its last torque, and `simulate` ends its run there unless `--t-end` says
    /// otherwise or it is not after the start (a one-row series is a constant torque, held
    /// over the default run).
    pub fn series_end(&self) -> Option<f64> {
        match self {
            CliInput::Series(s) => s.times().last().copied(),
            CliInput::Replay(p) => p.end(),
            _ => None,
        }
    }
}

impl Input for CliInput {
    fn dim(&self) -> usize {
        match self {
            CliInput::Series(s) => s.dim(),
            CliInput::Pd(p) => p.dim(),
            CliInput::Tracking(p) => p.dim(),
            CliInput::Zero(n) => *n,
            CliInput::Arm(n) => *n,
            CliInput::Replay(p) => p.dim(),
        }
    }
    fn tau(&self, t: f64, q: &[f64], qd: &[f64], out: &mut [f64]) -> Result<(), SimError> {
        match self {
            CliInput::Series(s) => s.tau(t, q, qd, out),
            CliInput::Pd(p) => p.tau(t, q, qd, out),
            CliInput::Tracking(p) => p.tau(t, q, qd, out),
            CliInput::Replay(p) => p.tau(t, q, qd, out),
            CliInput::Zero(_) | CliInput::Arm(_) => {
                out.fill(0.0);
                Ok(())
            }
        }
    }
}

/// The `--pd` controller of `n` joints: target angles `target` (the `--pd` text) and
/// `--pd-gains`, one (kp, kd) pair for all joints or kp₁..kpₙ, kd₁..kdₙ.
pub(super) fn pd_controller(args: &SimulateArgs, target: &str, n: usize) -> Result<PdController> {
    let target = parse_list("--pd", target, Some(n))?;
    let g = parse_list("--pd-gains", &args.pd_gains, None)?;
    let (kp, kd) = match g.len() {
        2 => (vec![g[0]; n], vec![g[1]; n]),
        k if k == 2 * n => (g[..n].to_vec(), g[n..].to_vec()),
        k => bail_usage!(
            "--pd-gains: expected 2 values (kp,kd) or {} (kp1..{n},kd1..{n}), got {k}",
            2 * n
        ),
    };
    // A negative gain feeds the error back with the wrong sign: the joint runs away from the
    // target (exponentially for kp < 0, with growing oscillation for kd < 0) until the run
    // hits its sample limit. Refused before the run.
    for (name, gains) in [("kp", &kp), ("kd", &kd)] {
        if let Some((i, v)) = gains.iter().enumerate().find(|(_, v)| **v < 0.0) {
            bail_usage!(
                "--pd-gains {}: {name} of joint {} is {v}; gains must be >= 0 (a negative gain \
                 destabilises the joint)",
                args.pd_gains,
                i + 1
            );
        }
    }
    Ok(PdController::new(kp, kd, target)?)
}

/// The `--torques` series at `path` for a scene `name` with `n` joints: one column per joint.
pub(super) fn series(path: &std::path::Path, name: &str, n: usize) -> Result<CliInput> {
    let s =
        TorqueSeries::from_path(path).with_context(|| format!("--torques {}", path.display()))?;
    if s.dim() != n {
        bail!(
            "--torques {}: scene `{name}` has {n} joints, the torque series has {} columns",
            path.display(),
            s.dim()
        );
    }
    Ok(CliInput::Series(s))
}

/// The joint torques of a run of the finger of scene `name` with `n` joints.
pub fn input(args: &SimulateArgs, name: &str, n: usize) -> Result<CliInput> {
    if let Some(path) = &args.torques {
        return series(path, name, n);
    }
    if let Some(gains) = &args.pd_track {
        return tracking(args, gains).map(CliInput::Tracking);
    }
    if let Some(target) = &args.pd {
        return pd_controller(args, target, n).map(CliInput::Pd);
    }
    Ok(CliInput::Zero(n))
}

/// Most periods of a solution `--pd-track` repeats (its series hold every dense sample of
/// every period).
pub const MAX_TRACKED_PERIODS: f64 = 10_000.0;

/// `--pd-track KP,KD`: the solution of `--init` repeated over `--t-end` with PD tracking.
fn tracking(args: &SimulateArgs, gains: &str) -> Result<TrackingPd> {
    use crate::pipeline::SolutionIo as _;
    let g = parse_list("--pd-track", gains, Some(2))?;
    // As for `--pd-gains`: a negative gain runs the joint away from its reference.
    for (name, v) in [("kp", g[0]), ("kd", g[1])] {
        if v < 0.0 {
            bail_usage!(
                "--pd-track {gains}: {name} is {v}; gains must be >= 0 (a negative gain \
                 destabilises the joint)"
            );
        }
    }
    let Some(path) = &args.init else {
        bail_usage!("--pd-track needs --init SOLUTION (a solution.json of `optimize`)");
    };
    let sol = bf_problem::OcpSolution::read_json(path)
        // Every error of the reader names the file it is about.
        .context("--pd-track: reading the solution")?;
    if sol.dense.t.len() < 2 || !(sol.period.is_finite() && sol.period > 0.0) {
        bail!(
            "--pd-track: {} has no trajectory to track (period {} s, {} dense samples)",
            path.display(),
            sol.period,
            sol.dense.t.len()
        );
    }
    let periods = (args.t_end() / sol.period).ceil().max(1.0);
    if periods.is_nan() || periods > MAX_TRACKED_PERIODS {
        bail_usage!(
            "--pd-track: --t-end {} s is {periods} periods of {} s of {}, more than {}",
            args.t_end(),
            sol.period,
            path.display(),
            MAX_TRACKED_PERIODS
        );
    }
    let pd = crate::paper::openloop::PdTrack {
        kp: g[0],
        kd: g[1],
        during_contact: args.pd_track_contact,
    };
    crate::paper::openloop::tracking_input(&sol, periods as usize, &pd)
        .with_context(|| format!("--pd-track {gains}"))
}

/// Largest |τ| of a torque series at its knots (N m).
pub(super) fn max_torque(s: &TorqueSeries) -> f64 {
    let mut tau = vec![0.0; s.dim()];
    s.times().iter().fold(0.0, |m, &t| {
        s.eval(t, &mut tau);
        tau.iter().fold(m, |m, v| m.max(v.abs()))
    })
}
