//! Settings of the ball-and-finger hybrid system ([`BallFingerSettings`]): the impact law of
//! Free → contact (Sect. 2.5, eq. 39–43), the drift projection (Sect. 3.1), the lift-off
//! speed, the Zeno hold time and the tolerances of the energy warnings.

use bf_model::ImpactLaw;

/// Settings of the ball-and-finger hybrid system.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BallFingerSettings {
    /// Impact law applied at Free → contact (default: [`ImpactLaw::Stick`]).
    pub impact_law: ImpactLaw,
    /// Project h and the velocity constraint after every accepted contact step (default: true).
    pub project: bool,
    /// Gauss–Newton iterations of the position projection (default: 3).
    pub projection_iterations: usize,
    /// Normal separation speed n·v_c⁺ (m/s) set by the contact → Free reset when the finger
    /// is not already separating (default: 1e-8). At lift-off λ_n = 0 and ḣ = 0, so the free
    /// ḧ is itself ≈ 0 and integration noise in ḣ (~1e-12) can turn the h guard around at once
    /// (lift-off / impact chatter). Like the slip kick of Sect. 3.1 ("update q̇ and ω such that
    /// the required condition is satisfied"), a tiny normal impulse along n makes the new mode
    /// valid; it does not act on the ball (r_c ∥ n) and by itself changes the energy by
    /// O(1e-18) J. The reset also projects q onto h = 0, which moves the energy by the drift it
    /// removes (measured 1.8e-10 J at the default tolerances, 1.5e-5 J at rtol 1e-3); the
    /// energy balance counts every reset's jump. 0 disables it.
    pub lift_off_speed: f64,
    /// How long the Zeno fallback holds its regularisation (s): suspended kink guards, or a
    /// sticking contact held regardless of λ_n and σ (see the module docs) (default: 1e-2).
    pub zeno_hold_time: f64,
    /// An impact that raises the energy E by more than this (J) is reported as an
    /// `energy_raising_impact` warning; only Newton's law (eq. 39) can do so (default: 1e-9).
    pub impact_energy_tol: f64,
    /// A run whose energy-balance error (the residual E(t) − E(t₀) − ∫ P dt − Σ ΔE_events,
    /// P = dE/dt of the power balance, Simpson's rule over each step, as it accumulates
    /// over any [`energy_window`](Self::energy_window) of simulated time) exceeds this share
    /// of the energy the run moves (its largest kinetic energy plus the largest ∫ |P| dt over
    /// a window; `RunSummary::energy_tolerance`) gets an `energy_error` warning: the
    /// integration is too coarse for the dynamics (e.g. fixed-step RK4 with a large step, or
    /// a loose tolerance). Relative, so that a scene's size does not decide the verdict
    /// (default: [`crate::arm::ENERGY_ERROR_REL`], 1e-3, as for an arm).
    pub energy_error_rel: f64,
    /// The span of simulated time (s) over which the balance error is held to
    /// [`energy_error_rel`](Self::energy_error_rel): at every sample, the residual accumulated
    /// since the last sample at least this long before (since t₀ within the first span). A run
    /// this long or shorter is checked from t₀ as a whole; a longer one is held to the same
    /// accuracy per span, since even an accurate integration accumulates a residual in
    /// proportion to its length (default: 10, the length of a default `simulate` run;
    /// `f64::INFINITY` checks every run from t₀).
    pub energy_window: f64,
}

impl Default for BallFingerSettings {
    fn default() -> Self {
        BallFingerSettings {
            impact_law: ImpactLaw::Stick,
            project: true,
            projection_iterations: 3,
            lift_off_speed: 1e-8,
            zeno_hold_time: 1e-2,
            impact_energy_tol: 1e-9,
            energy_error_rel: crate::arm::ENERGY_ERROR_REL,
            energy_window: 10.0,
        }
    }
}
