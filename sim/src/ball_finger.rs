//! The ball-and-finger hybrid system (paper Sect. 2.6–3, Fig. 2–3) on top of bf-model.
//!
//! State x = (q, q̇, ω) ∈ ℝ⁹ (eq. 44, [`bf_model::State::to_array`] layout), modes
//! [`bf_model::Mode`] = Free / Stick / Slip, joint torques τ(t, q, q̇) from an [`Input`].
//!
//! | mode | vector field | guards (region: valid while g > 0, all `Falling`) |
//! |---|---|---|
//! | Free | eq. 26 | `h` (eq. 50: contact when h crosses 0 or leaves the band h ≥ −tol) |
//! | Stick | eq. 29, λ from eq. 33 | `lambda_n` (λ_n < 0 → Free, eq. 48), `sigma` (σ ≤ 0 → Slip, eq. 19) |
//! | Slip | eq. 37, λ from eq. 38 | `lambda_n` (→ Free), `slip_speed` = ‖Δv‖ − ε (→ Stick, Sect. 3.1) |
//!
//! Resets: Free → impact law of Sect. 2.5 (eq. 39–43, [`ImpactLaw`]); the post-impact ‖Δv⁺‖
//! picks Stick or Slip (Fig. 3's "In-contact" state). Stick → Slip: velocity kick Δv⁺ =
//! `slip_kick` along λ_∥ (so the slip guard does not fire back). Slip → Stick: projection onto
//! Δv = 0 with the sticking impulse (eq. 40–41). Contact → Free: velocities unchanged. When the
//! new mode is already invalid (e.g. λ_n < 0 right after a sticking impact) the simulator chains
//! the next transition at the same instant.
//!
//! Drift control (Sect. 3.1 "we also allow h(q) to drift"): after each accepted step in a
//! contact mode, q is projected back onto h(q) = 0 by Gauss–Newton along ∇h = J_cᵀ n, then the
//! velocities onto the mode's constraint (Stick: Δv = 0 via the sticking impulse; Slip:
//! n·v_c = 0 by the M_f-norm-minimal change of q̇). The reported drift is |h| before projection
//! (m).

use crate::{Guard, HybridSystem, Input, SimError, Transition};
use bf_model::dynamics::contact_matrices;
use bf_model::{ImpactLaw, Kernels, Mode, Model, State, Vec3};

/// Options of the ball-and-finger hybrid system.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BallFingerOptions {
    /// Impact law applied at Free → contact (default: [`ImpactLaw::Stick`]).
    pub impact_law: ImpactLaw,
    /// Project h and the velocity constraint after every accepted contact step (default: true).
    pub project: bool,
    /// Gauss–Newton iterations of the position projection (default: 3).
    pub projection_iterations: usize,
}

impl Default for BallFingerOptions {
    fn default() -> Self {
        BallFingerOptions {
            impact_law: ImpactLaw::Stick,
            project: true,
            projection_iterations: 3,
        }
    }
}

/// The finger–ball [`HybridSystem`]: a bf-model [`Model`] plus a torque [`Input`].
#[derive(Debug, Clone)]
pub struct BallFinger<K: Kernels, I: Input> {
    /// Physics (kernels, parameters, transition tolerances).
    pub model: Model<K>,
    /// Joint torques τ(t, q, q̇).
    pub input: I,
    /// Options.
    pub options: BallFingerOptions,
}

fn state_of(x: &[f64]) -> Result<State, SimError> {
    let a: &[f64; 9] = x.try_into().map_err(|_| SimError::DimensionMismatch {
        what: "ball-finger state",
        expected: 9,
        found: x.len(),
    })?;
    Ok(State::from_array(a))
}

fn write_velocities(x: &mut [f64], qd: &Vec3, omega: &Vec3) {
    x[3..6].copy_from_slice(qd.as_slice());
    x[6..9].copy_from_slice(omega.as_slice());
}

impl<K: Kernels, I: Input> BallFinger<K, I> {
    /// Builds the system; the input must provide 3 torques.
    pub fn new(model: Model<K>, input: I, options: BallFingerOptions) -> Result<Self, SimError> {
        if input.dim() != 3 {
            return Err(SimError::DimensionMismatch {
                what: "torque input",
                expected: 3,
                found: input.dim(),
            });
        }
        Ok(BallFinger {
            model,
            input,
            options,
        })
    }

    fn tau(&self, t: f64, s: &State) -> Result<Vec3, SimError> {
        let mut tau = [0.0; 3];
        self.input
            .tau(t, s.q.as_slice(), s.qd.as_slice(), &mut tau)?;
        Ok(Vec3::from(tau))
    }

    /// Total energy E = T + U at `x` (J).
    pub fn energy(&self, x: &[f64]) -> Result<f64, SimError> {
        let s = state_of(x)?;
        Ok(self.model.energy(&s).map_err(SimError::system)?.total)
    }

    /// Gap h(q) at `x` (m).
    pub fn gap(&self, x: &[f64]) -> Result<f64, SimError> {
        let s = state_of(x)?;
        Ok(self.model.evaluate(&s).map_err(SimError::system)?.contact.h)
    }
}

impl<K: Kernels, I: Input> HybridSystem for BallFinger<K, I> {
    type Mode = Mode;

    fn dim(&self) -> usize {
        9
    }

    fn rhs(&self, mode: Mode, t: f64, x: &[f64], dx: &mut [f64]) -> Result<(), SimError> {
        let s = state_of(x)?;
        let tau = self.tau(t, &s)?;
        let acc = self
            .model
            .accelerations(mode, &s, &tau)
            .map_err(SimError::system)?;
        dx.copy_from_slice(&acc.state_derivative(&s.qd));
        Ok(())
    }

    fn guards(&self, mode: Mode) -> Vec<Guard> {
        match mode {
            Mode::Free => vec![Guard::falling("h")],
            Mode::Stick => vec![Guard::falling("lambda_n"), Guard::falling("sigma")],
            Mode::Slip => vec![Guard::falling("lambda_n"), Guard::falling("slip_speed")],
        }
    }

    fn guard_values(&self, mode: Mode, t: f64, x: &[f64], out: &mut [f64]) -> Result<(), SimError> {
        let s = state_of(x)?;
        match mode {
            Mode::Free => {
                out[0] = self.model.evaluate(&s).map_err(SimError::system)?.contact.h;
            }
            Mode::Stick => {
                let tau = self.tau(t, &s)?;
                let acc = self.model.stick(&s, &tau).map_err(SimError::system)?;
                out[0] = acc.force.lambda_n;
                out[1] = acc.force.sigma;
            }
            Mode::Slip => {
                let tau = self.tau(t, &s)?;
                let kin = self.model.evaluate(&s).map_err(SimError::system)?;
                let acc = self.model.slip(&s, &tau, None).map_err(SimError::system)?;
                out[0] = acc.force.lambda_n;
                out[1] = kin.contact.delta_v.norm() - self.model.settings().slip_eps;
            }
        }
        Ok(())
    }

    fn reset(
        &self,
        mode: Mode,
        guard: usize,
        t: f64,
        x: &mut [f64],
    ) -> Result<Transition<Mode>, SimError> {
        let s = state_of(x)?;
        let next = match (mode, guard) {
            (Mode::Free, _) => {
                let out = self
                    .model
                    .impact(&s, self.options.impact_law)
                    .map_err(SimError::system)?;
                write_velocities(x, &out.qd, &out.omega);
                out.mode
            }
            (Mode::Stick | Mode::Slip, 0) => Mode::Free,
            (Mode::Stick, _) => {
                let tau = self.tau(t, &s)?;
                let acc = self.model.stick(&s, &tau).map_err(SimError::system)?;
                let out = self
                    .model
                    .stick_to_slip_update(&s, &acc.force)
                    .map_err(SimError::system)?;
                write_velocities(x, &out.qd, &out.omega);
                Mode::Slip
            }
            (Mode::Slip, _) => {
                let out = self
                    .model
                    .slip_to_stick_update(&s)
                    .map_err(SimError::system)?;
                write_velocities(x, &out.qd, &out.omega);
                Mode::Stick
            }
        };
        Ok(Transition::To(next))
    }

    fn project(&self, mode: Mode, _t: f64, x: &mut [f64]) -> Result<Option<f64>, SimError> {
        if mode == Mode::Free || !self.options.project {
            return Ok(None);
        }
        let mut s = state_of(x)?;
        let mut drift = None;
        for _ in 0..self.options.projection_iterations {
            let kin = self.model.evaluate(&s).map_err(SimError::system)?;
            let c = &kin.contact;
            drift.get_or_insert(c.h.abs());
            let grad = c.j_c.transpose() * c.n;
            let g2 = grad.norm_squared();
            if c.h == 0.0 || g2 < 1e-24 {
                break;
            }
            s.q -= grad * (c.h / g2);
        }
        match mode {
            Mode::Stick => {
                let out = self
                    .model
                    .slip_to_stick_update(&s)
                    .map_err(SimError::system)?;
                s.qd = out.qd;
                s.omega = out.omega;
            }
            Mode::Slip => {
                let kin = self.model.evaluate(&s).map_err(SimError::system)?;
                let mats = contact_matrices(&kin, self.model.params()).map_err(SimError::system)?;
                let n = kin.contact.n;
                let vn = n.dot(&kin.contact.v_c);
                if mats.n_w_n > 0.0 {
                    s.qd -= mats.minv_jct * n * (vn / mats.n_w_n);
                }
            }
            Mode::Free => {}
        }
        x.copy_from_slice(&s.to_array());
        Ok(drift)
    }

    fn check_valid(&self, mode: Mode, t: f64, x: &[f64]) -> Result<(), SimError> {
        if mode == Mode::Free {
            return Ok(());
        }
        let h = self.gap(x)?;
        let tol = self.model.settings().contact_tolerance * self.model.params().ball_radius();
        if h.abs() > tol {
            return Err(SimError::InvalidState {
                t,
                mode: format!("{mode:?}"),
                msg: format!("contact drift |h| = {:e} m exceeds {tol:e} m", h.abs()),
            });
        }
        Ok(())
    }
}
