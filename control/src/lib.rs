//! bf-control: feedback that executes an optimum of the ball-and-finger problem in the hybrid
//! model (the controller the paper's Sect. 7 asks for; its Sect. 6.2 shows the open loop
//! drifting).
//!
//! | module | what | paper |
//! |---|---|---|
//! | [`law`] | [`ComputedTorque`]: q̈_cmd = q̈* + K_d (q̇* − q̇) + K_p (q* − q), K_p = ω_n², K_d = 2ζω_n, and the generated inverse dynamics τ = ID(q, q̇, q̈) + μ_v q̇ ([`InverseDynamics`]) | eq. 24, 26a |
//! | [`reference`](mod@reference) | [`Reference`]: the optimum phase by phase (q*, q̇*, q̈*, ω*, ω̇*, λ*, the contact point r_c* and the gap h*), indexed by the time since the phase began; h* inverted for the re-timed approach | Sect. 4, eq. 3, 4, 26, 29 |
//! | [`controller`] | [`HybridController`]: a bf-sim [`Input`](bf_sim::Input) that starts each phase at the plant's event (impact h = 0, lift-off), computed torque in free phases (the approach to an impact indexed by the measured gap h), hybrid force/velocity control in contact (λ_n regulated, ω tracked, ‖λ_∥‖ ≤ (1 − margin) μ_s λ_n, relative velocity Δv driven to zero after a slip), a per-period outer loop on the mean ω, and re-planning at each lift-off through a [`Replanner`] | eq. 12–19, 29–33, 39, 48 |
//! | [`error`] | [`ControlError`] | — |
//! | [`metrics`] | per-period figures of a run: mean ω, its error against the optimum, contact, stick and slip time, max |τ| | eq. 61 (mean ω) |
//!
//! The reference and the controller are generic in the finger's joint count N (`Reference<N>`,
//! `HybridController<K, N>`, both 3 by default); the controller refuses N < 3 (its contact law
//! commands a 3-D force through the joints). Its free law's inverse dynamics is a scene's
//! generated kernel, or the model's M q̈ + C q̇ + g for scenes without one.
//!
//! Why a crate of its own above bf-sim and not a module of it: docs/decisions/0012-control-layer.md.

pub mod controller;
pub mod error;
pub mod law;
pub mod metrics;
pub mod reference;

pub use controller::{Clearance, ContactGains, HybridController, HybridGains, Replanner};
pub use error::ControlError;
pub use law::{ComputedTorque, InverseDynamics};
pub use metrics::{
    MAX_PERIOD_RATIO, MIN_FLIGHT, MIN_PERIOD_RATIO, PeriodMetrics, PeriodStarts, period_metrics,
};
pub use reference::{Reference, ReferencePhase};
