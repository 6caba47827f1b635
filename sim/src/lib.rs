//! bf-sim: the hybrid simulator of the ball-and-finger project (paper Sect. 3, Fig. 2–3).
//!
//! The paper's model is a hybrid, variable-index DAE (eq. 44–47) with mode transitions at
//! zero crossings of guard functions (eq. 48–50, λ_n < 0, σ ≤ 0, ‖Δv‖ ≤ ε) and reset maps given
//! by impact laws (eq. 39–43). This crate is the generic machinery, independent of the finger:
//!
//! * [`HybridSystem`] — modes, vector field, guards with [`Direction`], resets that pick the
//!   next mode ([`Transition`]), optional projection (drift control) and validity check.
//! * [`integrator`] — adaptive Dormand–Prince 5(4) with PI control and dense output, fixed-step
//!   RK4 with Hermite dense output (our own: `docs/decisions/0003-own-integrators.md`).
//! * [`events`] — guard bracketing on sub-sampled dense output, Illinois root finding, direction
//!   filters, guards starting on their surface after a reset.
//! * [`Simulator`] — the step-to-event loop (`step() -> Result<StopReason, SimError>`,
//!   `apply_reset()`), Zeno and chain limits; [`simulate`] runs it and returns either a
//!   [`SimOutput`] or a [`SimFailure`] that keeps the partial trajectory.
//! * [`trajectory`] — [`Trajectory`], [`EventRecord`], JSON/CSV writers (atomic).
//! * [`input`] — [`Input`] torques τ(t, q, q̇): [`TorqueSeries`] (CSV/JSON) and [`PdController`];
//!   feedback laws that need the contact mode, ω and the measured contact force override
//!   [`Input::tau_in_mode`] and [`Input::observe`] ([`Measurement`]), as bf-control does.
//! * [`toys`] — systems with closed-form event times used by tests and benches.
//! * [`ball_finger`] — the finger–ball model of bf-model as a [`HybridSystem`], with the derived
//!   per-sample quantities (τ, λ, h, σ, ‖Δv‖, E), event kinds, run summary and output files.
//! * [`arm`] — free motion of an arm with any number of joints and no ball (M q̈ = τ − C q̇ −
//!   g − μ_v q̇), its energy balance and output files.
//! * [`work_precision`](mod@work_precision) — error against a tight reference versus CPU time (DOPRI5 rtol and RK4
//!   step ladders).
//!
//! ```
//! use bf_sim::{simulate, SimSettings, toys::{BouncingBall, BallMode}};
//! let ball = BouncingBall { g: 9.81, e: 0.5, drag: 0.0, v_rest: None };
//! let out = simulate(&ball, SimSettings::default(), BallMode::Flight, 0.0, &[1.0, 0.0], 1.0)
//!     .expect("runs");
//! let t1 = (2.0f64 / 9.81).sqrt(); // first impact from 1 m
//! assert!((out.events[0].t - t1).abs() < 1e-10);
//! ```

pub mod arm;
pub mod ball_finger;
pub mod error;
pub mod events;
pub mod input;
pub mod integrator;
pub mod settings;
pub mod simulator;
pub mod system;
pub mod toys;
pub mod trajectory;
pub mod work_precision;

pub use error::SimError;
pub use input::{Input, Measurement, PdController, TorqueSeries, TrackingPd};
pub use settings::{
    MAX_ATOL, MAX_RTOL, MIN_RTOL, Method, SimSettings, atol_out_of_range, rtol_out_of_range,
};
pub use simulator::{SimFailure, Simulator, StopReason, simulate, simulate_until};
pub use system::{Direction, Guard, HybridSystem, Transition};
pub use trajectory::{EventRecord, SampleKind, SimOutput, SimStats, SimWarning, Trajectory, shown};
pub use work_precision::{WorkPrecisionRow, format_table, work_precision};
