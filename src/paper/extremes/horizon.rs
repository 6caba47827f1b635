//! Probe 8, a long horizon (eq. 26 and the energy of eq. 22): the paper finger in free motion
//! without damping or torque for 10 s or 100 s, DOPRI5 at rtol 1e-6 … 1e-10: energy drift
//! relative to the kinetic energy exchanged, CPU time, and a bounded step count.

use std::f64::consts::PI;
use std::time::Instant;

use anyhow::{anyhow, bail};
use bf_model::{Mode, State};
use bf_sim::ball_finger::{BallFinger, BallFingerSettings};
use bf_sim::{PdController, SimSettings, simulate};

use super::report::{ExtremesRow, Rows};

/// Free motion over a long horizon (probe 8).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct HorizonRun {
    /// Horizon (s).
    pub t_end: f64,
    /// DOPRI5 rtol (atol = rtol/100).
    pub rtol: f64,
    /// max_t |E(t) − E(0)| / max_t T(t): energy drift relative to the kinetic energy exchanged
    /// (independent of the potential's datum).
    pub drift: f64,
    /// |E(t_end) − E(0)| / max_t T(t).
    pub final_drift: f64,
    /// Accepted steps.
    pub steps: usize,
    /// Events (must be 0: the finger never reaches the ball).
    pub events: usize,
    /// CPU (wall) seconds.
    pub cpu_seconds: f64,
}

/// Initial state of the long-horizon run: the paper finger hanging below its base (q₁ = π puts
/// link 1 along −z), swinging with all three joints; it stays ≥ 1 m away from the ball.
pub const HORIZON_X0: [f64; 9] = [PI + 0.4, 0.5, -0.4, 0.0, 0.8, -0.5, 0.0, 0.0, 0.0];

/// Probe 8: paper finger with μ_v = D = 0 and zero torque, DOPRI5 at `rtol` for `t_end` s.
pub fn long_horizon(t_end: f64, rtol: f64) -> anyhow::Result<HorizonRun> {
    let base = bf_model::fixtures::paper_scene()?;
    let params = base.params().with_viscous(0.0, 0.0)?;
    let model = base.with_params(params);
    let input = PdController::new(vec![0.0; 3], vec![0.0; 3], vec![0.0; 3])?;
    let sys = BallFinger::new(model, input, BallFingerSettings::default())?;
    let settings = SimSettings {
        rtol,
        atol: rtol * 1e-2,
        // bounded: ~100× what DOPRI5 needs at rtol 1e-10 for this motion
        max_steps: 2_000_000,
        ..SimSettings::default()
    };
    let start = Instant::now();
    let out = simulate(
        &sys as &dyn bf_sim::HybridSystem<Mode = Mode>,
        settings,
        Mode::Free,
        0.0,
        &HORIZON_X0,
        t_end,
    )
    .map_err(|f| anyhow!("simulation failed at t = {}: {}", f.t, f.error))?;
    let cpu_seconds = start.elapsed().as_secs_f64();
    let e0 = sys.energy(&HORIZON_X0)?;
    let mut max_dev: f64 = 0.0;
    let mut max_kin: f64 = 0.0;
    let mut last = 0.0;
    for x in &out.trajectory.x {
        let s = State::from_array(x.as_slice().try_into()?);
        let e = sys.model.energy(&s)?;
        if !e.total.is_finite() {
            bail!("NaN energy on the trajectory");
        }
        max_dev = max_dev.max((e.total - e0).abs());
        max_kin = max_kin.max(e.kinetic_finger);
        last = (e.total - e0).abs();
    }
    if (out.t_final - t_end).abs() > 1e-9 * t_end {
        bail!("run stopped at t = {} before t_end = {t_end}", out.t_final);
    }
    Ok(HorizonRun {
        t_end,
        rtol,
        drift: max_dev / max_kin,
        final_drift: last / max_kin,
        steps: out.stats.accepted_steps,
        events: out.stats.events,
        cpu_seconds,
    })
}

/// The report rows of probe 8 over `t_end` s.
pub(super) fn report(t_end: f64, rows: &mut Vec<ExtremesRow>) {
    for &rtol in &[1e-6, 1e-8, 1e-10] {
        let t = Instant::now();
        let mut r = Rows::new("long horizon (free, μ_v = D = τ = 0)");
        let par = format!("{t_end} s, rtol {rtol:e}");
        match long_horizon(t_end, rtol) {
            Ok(h) => {
                r.num(&par, "max |ΔE| / max T", h.drift, rtol);
                r.num(&par, "accepted steps", h.steps as f64, 0.0);
                r.num(&par, "CPU s", h.cpu_seconds, 0.0);
                if h.events != 0 {
                    r.fail(
                        &par,
                        format!("{} events: the finger reached the ball", h.events),
                    );
                }
            }
            Err(e) => r.fail(&par, format!("{e:#}")),
        }
        r.finish(t, rows);
    }
}
