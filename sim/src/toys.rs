//! Toy hybrid systems with closed-form solutions, run through the same machinery as the
//! ball–finger model (the diffsol `test_models` idea applied to events).
//!
//! * [`Oscillator`]: x'' = −ω² x, smooth, no guards (order and accuracy checks).
//! * [`CrossingOscillator`]: the same with an `Either` guard x = 0 and identity reset; crossings
//!   at t = (k + ½)π/ω.
//! * [`Pendulum`]: θ'' = −(g/l) sin θ; energy E = ½ l² θ'² − g l cos θ is conserved.
//! * [`BlowUp`]: x' = x², x = 1/(1/x₀ − t), blows up at t = 1/x₀ (failure mid-run).
//! * [`BouncingBall`]: point mass over a plane, y'' = −g − k y' (linear air drag k ≥ 0), impact
//!   guard y (falling), Newton restitution reset v⁺ = −e v⁻ (the 1-D analogue of eq. 39 with
//!   restitution), Resting mode for e = 0 or a post-impact speed below `v_rest`.
//!   For k = 0: impact k+1 at t_{k+1} = t_k + 2 eᵏ u₁ / g, accumulation point
//!   t_∞ = t₁ + 2 e u₁ / (g (1 − e)). **Zeno handling (documented choice):** with
//!   `v_rest = None` and 0 < e < 1 the run approaches t_∞ and must stop with
//!   `SimError::Zeno` (the Zeno guard of the simulator); with `v_rest = Some(v)` the reset
//!   itself handles the accumulation by switching to Resting once e·|v⁻| < v.
//! * [`FrictionBlock`]: block of mass m on a plane with Coulomb friction (μ_s static, μ_k
//!   kinetic) pushed by a tent force F(t) = a t for t ≤ T, F = aT − b(t − T) after: modes Stick /
//!   SlipPos / SlipNeg — the 1-D analogue of the paper's Stick/Slip modes with the
//!   stick → slip condition |F| > μ_s m g (σ ≤ 0, eq. 19) and slip → stick at Δv = 0.
//!   The slip → stick reset always goes to Stick; when |F| > μ_s m g there, Stick's breakaway
//!   guard is already beyond its zero and fires immediately (a chained transition).

use crate::{Guard, HybridSystem, SimError, Transition};

/// Harmonic oscillator x' = v, v' = −ω² x (state `[x, v]`); no guards.
#[derive(Debug, Clone, Copy)]
pub struct Oscillator {
    /// Angular frequency ω (rad/s).
    pub omega: f64,
}

impl HybridSystem for Oscillator {
    type Mode = ();
    fn dim(&self) -> usize {
        2
    }
    fn rhs(&self, _: (), _t: f64, x: &[f64], dx: &mut [f64]) -> Result<(), SimError> {
        dx[0] = x[1];
        dx[1] = -self.omega * self.omega * x[0];
        Ok(())
    }
}

/// Harmonic oscillator with an `Either` guard on x = 0 and an identity reset: from x(0) = 1,
/// v(0) = 0 the events are at t = (k + ½)π/ω.
#[derive(Debug, Clone, Copy)]
pub struct CrossingOscillator {
    /// Angular frequency ω (rad/s).
    pub omega: f64,
}

impl HybridSystem for CrossingOscillator {
    type Mode = ();
    fn dim(&self) -> usize {
        2
    }
    fn rhs(&self, m: (), t: f64, x: &[f64], dx: &mut [f64]) -> Result<(), SimError> {
        Oscillator { omega: self.omega }.rhs(m, t, x, dx)
    }
    fn guards(&self, _: ()) -> Vec<Guard> {
        vec![Guard::either("x=0")]
    }
    fn guard_values(&self, _: (), _: f64, x: &[f64], out: &mut [f64]) -> Result<(), SimError> {
        out[0] = x[0];
        Ok(())
    }
}

/// Planar pendulum θ'' = −(g/l) sin θ (state `[θ, θ']`).
#[derive(Debug, Clone, Copy)]
pub struct Pendulum {
    /// Gravity (m/s²).
    pub g: f64,
    /// Length (m).
    pub l: f64,
}

impl Pendulum {
    /// Energy per unit mass, ½ l² θ'² − g l cos θ (J/kg).
    pub fn energy(&self, x: &[f64]) -> f64 {
        0.5 * self.l * self.l * x[1] * x[1] - self.g * self.l * libm::cos(x[0])
    }
}

impl HybridSystem for Pendulum {
    type Mode = ();
    fn dim(&self) -> usize {
        2
    }
    fn rhs(&self, _: (), _t: f64, x: &[f64], dx: &mut [f64]) -> Result<(), SimError> {
        dx[0] = x[1];
        dx[1] = -self.g / self.l * libm::sin(x[0]);
        Ok(())
    }
}

/// x' = x² (state `[x]`); finite-time blow-up at t = 1/x₀ for x₀ > 0.
#[derive(Debug, Clone, Copy)]
pub struct BlowUp;

impl HybridSystem for BlowUp {
    type Mode = ();
    fn dim(&self) -> usize {
        1
    }
    fn rhs(&self, _: (), _t: f64, x: &[f64], dx: &mut [f64]) -> Result<(), SimError> {
        dx[0] = x[0] * x[0];
        Ok(())
    }
}

/// Modes of [`BouncingBall`].
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum BallMode {
    /// Ballistic flight, guard y ↓ 0.
    Flight,
    /// At rest on the plane (y = v = 0), no guards.
    Resting,
}

/// Point mass falling onto the plane y = 0 (state `[y, v]`); see the module docs.
#[derive(Debug, Clone, Copy)]
pub struct BouncingBall {
    /// Gravity g (m/s²).
    pub g: f64,
    /// Coefficient of restitution e ∈ [0, 1].
    pub e: f64,
    /// Linear drag coefficient k ≥ 0 (1/s): v' = −g − k v.
    pub drag: f64,
    /// Post-impact speed below which the ball comes to rest (`None`: never, except e = 0).
    pub v_rest: Option<f64>,
}

impl HybridSystem for BouncingBall {
    type Mode = BallMode;
    fn dim(&self) -> usize {
        2
    }
    fn rhs(&self, mode: BallMode, _t: f64, x: &[f64], dx: &mut [f64]) -> Result<(), SimError> {
        match mode {
            BallMode::Flight => {
                dx[0] = x[1];
                dx[1] = -self.g - self.drag * x[1];
            }
            BallMode::Resting => {
                dx[0] = 0.0;
                dx[1] = 0.0;
            }
        }
        Ok(())
    }
    fn guards(&self, mode: BallMode) -> Vec<Guard> {
        match mode {
            BallMode::Flight => vec![Guard::falling("impact")],
            BallMode::Resting => Vec::new(),
        }
    }
    fn guard_values(
        &self,
        mode: BallMode,
        _t: f64,
        x: &[f64],
        out: &mut [f64],
    ) -> Result<(), SimError> {
        if mode == BallMode::Flight {
            out[0] = x[0];
        }
        Ok(())
    }
    fn reset(
        &self,
        mode: BallMode,
        _guard: usize,
        _t: f64,
        x: &mut [f64],
    ) -> Result<Transition<BallMode>, SimError> {
        debug_assert_eq!(mode, BallMode::Flight);
        // Leaves the state exactly on g = 0: the case diffsol 0.18 mishandled.
        x[0] = 0.0;
        let v_post = -self.e * x[1];
        if self.e == 0.0 || self.v_rest.is_some_and(|vr| v_post.abs() < vr) {
            x[1] = 0.0;
            Ok(Transition::To(BallMode::Resting))
        } else {
            x[1] = v_post;
            Ok(Transition::To(BallMode::Flight))
        }
    }
}

impl BouncingBall {
    /// Time of flight τ > 0 until y = 0 from (y₀ ≥ 0, v₀) and the impact velocity, in closed
    /// form for k = 0 and by a safeguarded Newton iteration on the closed-form y(τ) for k > 0:
    /// y(τ) = y₀ + (v₀ + g/k)(1 − e^{−kτ})/k − gτ/k, v(τ) = (v₀ + g/k)e^{−kτ} − g/k.
    pub fn flight(&self, y0: f64, v0: f64) -> (f64, f64) {
        let g = self.g;
        let k = self.drag;
        if k == 0.0 {
            let u = (v0 * v0 + 2.0 * g * y0).sqrt();
            return ((v0 + u) / g, -u);
        }
        let vinf = g / k;
        let y = |tau: f64| y0 + (v0 + vinf) * (1.0 - libm::exp(-k * tau)) / k - vinf * tau;
        let v = |tau: f64| (v0 + vinf) * libm::exp(-k * tau) - vinf;
        // Bracket: y > 0 just after the apex time, y < 0 eventually (terminal velocity).
        let t_apex = if v0 > 0.0 {
            libm::log(1.0 + v0 / vinf) / k
        } else {
            0.0
        };
        let mut lo = t_apex;
        let mut hi = t_apex.max(1e-3);
        while y(hi) > 0.0 {
            hi *= 2.0;
        }
        let mut tau = hi;
        for _ in 0..200 {
            let yt = y(tau);
            if yt > 0.0 {
                lo = tau;
            } else {
                hi = tau;
            }
            let mut next = tau - yt / v(tau);
            if !(next > lo && next < hi) {
                next = 0.5 * (lo + hi);
            }
            if (next - tau).abs() <= 1e-16 * tau.abs() {
                tau = next;
                break;
            }
            tau = next;
        }
        (tau, v(tau))
    }

    /// Reference impact times and post-impact velocities of the first `n` impacts from
    /// (y₀, v₀) at t = 0 (ignores `v_rest`; e = 0 gives a single impact).
    pub fn reference_impacts(&self, y0: f64, v0: f64, n: usize) -> Vec<(f64, f64)> {
        let mut out = Vec::new();
        let (mut t, mut y, mut v) = (0.0, y0, v0);
        for _ in 0..n {
            let (tau, vi) = self.flight(y, v);
            t += tau;
            y = 0.0;
            v = -self.e * vi;
            out.push((t, v));
            if self.e == 0.0 {
                break;
            }
        }
        out
    }

    /// Accumulation time t_∞ = t₁ + 2 e u₁ / (g (1 − e)) of the impacts without drag, from
    /// (y₀, v₀) at t = 0, 0 ≤ e < 1.
    pub fn accumulation_time(&self, y0: f64, v0: f64) -> f64 {
        let u1 = (v0 * v0 + 2.0 * self.g * y0).sqrt();
        let t1 = (v0 + u1) / self.g;
        t1 + 2.0 * self.e * u1 / (self.g * (1.0 - self.e))
    }
}

/// Modes of [`FrictionBlock`].
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum BlockMode {
    /// v = 0, static friction balances F; guard |F| − μ_s m g ↑ 0.
    Stick,
    /// v > 0, kinetic friction −μ_k m g; guard v ↓ 0.
    SlipPos,
    /// v < 0, kinetic friction +μ_k m g; guard v ↑ 0.
    SlipNeg,
}

/// Block on a frictional plane under the tent force F(t) (state `[x, v]`); see the module docs.
#[derive(Debug, Clone, Copy)]
pub struct FrictionBlock {
    /// Mass m (kg).
    pub m: f64,
    /// Gravity g (m/s²).
    pub g: f64,
    /// Static friction coefficient μ_s.
    pub mu_s: f64,
    /// Kinetic friction coefficient μ_k ≤ μ_s.
    pub mu_k: f64,
    /// Force ramp-up rate a > 0 (N/s).
    pub a: f64,
    /// Time T of the force peak (s).
    pub t_peak: f64,
    /// Force ramp-down rate b > 0 after T (N/s).
    pub b: f64,
}

/// Closed-form events of [`FrictionBlock`] from rest at x = 0 (see
/// [`FrictionBlock::reference`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BlockReference {
    /// Stick → SlipPos breakaway time t₁ = μ_s m g / a.
    pub t1: f64,
    /// SlipPos → Stick time t₂ (v returns to 0).
    pub t2: f64,
    /// Position at t₂.
    pub x2: f64,
    /// Whether |F(t₂)| > μ_s m g, i.e. Stick is left immediately for SlipNeg at t₂ (chain).
    pub chained_at_t2: bool,
    /// Stick → SlipNeg time t₃ = T + (aT + μ_s m g)/b (equals t₂ when chained).
    pub t3: f64,
}

impl FrictionBlock {
    /// Applied force F(t) (N).
    pub fn force(&self, t: f64) -> f64 {
        if t <= self.t_peak {
            self.a * t
        } else {
            self.a * self.t_peak - self.b * (t - self.t_peak)
        }
    }

    /// Closed-form event times from x = v = 0 at t = 0 in Stick; requires a T > μ_s m g.
    /// Slip phase: m v' = F − μ_k m g, integrated piecewise (quadratic v, cubic x), v(t₂) = 0 from
    /// the quadratic formula.
    pub fn reference(&self) -> BlockReference {
        let (m, a, b, tp) = (self.m, self.a, self.b, self.t_peak);
        let cs = self.mu_s * m * self.g;
        let ck = self.mu_k * m * self.g;
        let t1 = cs / a;
        assert!(t1 < tp, "reference() needs a·T > μ_s m g");
        let v_t = (a * (tp * tp - t1 * t1) / 2.0 - ck * (tp - t1)) / m;
        let x_t = (a * (tp.powi(3) / 6.0 - t1 * t1 * tp / 2.0 + t1.powi(3) / 3.0)
            - ck * (tp - t1).powi(2) / 2.0)
            / m;
        let p = a * tp - ck;
        let tau = (p + (p * p + 2.0 * b * m * v_t).sqrt()) / b;
        let t2 = tp + tau;
        let x2 = x_t + v_t * tau + (p * tau * tau / 2.0 - b * tau.powi(3) / 6.0) / m;
        let f2 = a * tp - b * tau;
        let chained = f2.abs() > cs;
        let t3 = if chained { t2 } else { tp + (a * tp + cs) / b };
        BlockReference {
            t1,
            t2,
            x2,
            chained_at_t2: chained,
            t3,
        }
    }
}

impl HybridSystem for FrictionBlock {
    type Mode = BlockMode;
    fn dim(&self) -> usize {
        2
    }
    fn rhs(&self, mode: BlockMode, t: f64, x: &[f64], dx: &mut [f64]) -> Result<(), SimError> {
        let fk = self.mu_k * self.m * self.g;
        match mode {
            BlockMode::Stick => {
                dx[0] = 0.0;
                dx[1] = 0.0;
            }
            BlockMode::SlipPos => {
                dx[0] = x[1];
                dx[1] = (self.force(t) - fk) / self.m;
            }
            BlockMode::SlipNeg => {
                dx[0] = x[1];
                dx[1] = (self.force(t) + fk) / self.m;
            }
        }
        Ok(())
    }
    fn guards(&self, mode: BlockMode) -> Vec<Guard> {
        match mode {
            BlockMode::Stick => vec![Guard::rising("breakaway")],
            BlockMode::SlipPos => vec![Guard::falling("v=0")],
            BlockMode::SlipNeg => vec![Guard::rising("v=0")],
        }
    }
    fn guard_values(
        &self,
        mode: BlockMode,
        t: f64,
        x: &[f64],
        out: &mut [f64],
    ) -> Result<(), SimError> {
        out[0] = match mode {
            BlockMode::Stick => self.force(t).abs() - self.mu_s * self.m * self.g,
            BlockMode::SlipPos | BlockMode::SlipNeg => x[1],
        };
        Ok(())
    }
    fn reset(
        &self,
        mode: BlockMode,
        _guard: usize,
        t: f64,
        x: &mut [f64],
    ) -> Result<Transition<BlockMode>, SimError> {
        x[1] = 0.0;
        Ok(Transition::To(match mode {
            BlockMode::Stick => {
                if self.force(t) > 0.0 {
                    BlockMode::SlipPos
                } else {
                    BlockMode::SlipNeg
                }
            }
            BlockMode::SlipPos | BlockMode::SlipNeg => BlockMode::Stick,
        }))
    }
    fn check_valid(&self, mode: BlockMode, t: f64, x: &[f64]) -> Result<(), SimError> {
        if mode == BlockMode::Stick && x[1] != 0.0 {
            return Err(SimError::InvalidState {
                t,
                mode: format!("{mode:?}"),
                msg: format!("stick with v = {}", x[1]),
            });
        }
        Ok(())
    }
}
