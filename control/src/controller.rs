//! [`HybridController`]: the feedback law that executes an optimum in the hybrid model.
//!
//! **Timing by events.** The controller keeps a reference phase and the plant time it began.
//! The plant's impact (Free → Stick/Slip, the h = 0 guard of eq. 50) starts the next contact
//! phase of the reference, its lift-off (λ_n = 0, eq. 48) the next free phase, whatever the
//! clock says; a free phase that lasts longer than planned continues at the planned
//! pre-impact velocity ([`crate::reference`]), so a late plant still approaches the ball as
//! planned and an early one switches to the contact law at once.
//!
//! **Free phases:** computed torque ([`ComputedTorque`], [`InverseDynamics`]):
//! τ = ID(q, q̇, q̈* + K_d (q̇* − q̇) + K_p (q* − q)) + μ_v q̇.
//!
//! **Contact phases (Stick, Slip):** hybrid force/velocity control through the contact force.
//! The force on the finger is commanded as λ_cmd = λ_n,cmd n + λ_∥,cmd:
//! * normal: λ_n,cmd = λ_n*(s) + k_f ∫(λ_n* − λ_n) dt, the integral of the *measured* force
//!   error (what [`bf_sim::Input::observe`] reports after each accepted step), updated
//!   semi-implicitly (ΔI = e Δt / (1 + k_f Δt), stable for any step Δt); after the planned end
//!   of the phase −`lift_off_share` · max λ_n*, so the finger lets go;
//! * tangential: the ball's equation (eq. 29b) I_b ω̇ = −ω × I_b ω − D ω − r_c × λ fixes the
//!   component of λ normal to r_c that gives ω̇_cmd = ω̇* + k_ω (ω* + δ − ω):
//!   λ_∥ = (m × r_c)/‖r_c‖², m = −ω × I_b ω − D ω − I_b ω̇_cmd, then limited to
//!   ‖λ_∥‖ ≤ (1 − margin) μ_s λ_n,cmd (eq. 18–19 with a margin);
//! * the finger's acceleration keeps the contact: from d/dt Δv = ω̇ × r_c + ω × ṙ_c − J̇_c q̇ −
//!   J_c q̈ = −k_s Δv, J_c q̈ = ω̇ × r_c + ω × ṙ_c − J̇_c q̇ + k_s Δv with ω̇ the ball's response
//!   to λ_cmd; in Stick Δv = 0 and this is the sticking constraint (eq. 27–28), after a slip it
//!   drives the relative velocity back to zero (slip recovery);
//! * τ = M q̈ + C q̇ + g + μ_v q̇ − J_cᵀ λ_cmd (eq. 29a solved for τ). On the controller's own
//!   model in Stick, the plant's λ (eq. 33) under this τ is exactly λ_cmd.
//!
//! **Outer loop:** at the end of each period (when the reference wraps to its first phase) the
//! measured mean ω̄ of that period moves the ω offset of the contact phases,
//! δ ← δ + γ (ω̄* − ω̄), with ‖δ‖ ≤ 0.25 ‖ω̄*‖ (anti-windup).
//!
//! **Friction measured:** in Slip the measured force gives the plant's μ_k = ‖λ_∥‖ / λ_n; the
//! controller predicts the kinetic friction with it and scales its μ_s (the friction cone of
//! the margin) by the ratio to the model's μ_k, so a plant with less friction than the model
//! is found out at its first slip.
//!
//! The discrete state (phase, its start, the force integral, δ, the ω integral, μ_k) is recorded
//! with its time at every observation, so τ at an earlier time (the per-sample report written
//! after the run) is recomputed with the state that held then. The controller is for fingers
//! with 3 joints (the paper's and the human finger).

use crate::error::ControlError;
use crate::law::{ComputedTorque, InverseDynamics};
use crate::reference::Reference;
use bf_model::{Kernels, Mat3, Mode, Model, State, Vec3};
use bf_sim::{Input, Measurement, SimError};
use std::cell::RefCell;

/// Gains of the contact law (module doc).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ContactGains {
    /// k_ω (1/s): rate at which ω follows ω* + δ.
    pub omega_rate: f64,
    /// k_f (1/s): integral gain of the normal-force loop.
    pub force_integral: f64,
    /// k_s (1/s): rate at which a relative velocity Δv (slip) is driven to zero.
    pub slip_rate: f64,
    /// The commanded λ_n may rise up to this multiple of the phase's largest λ_n* to keep the
    /// tangential force ω needs inside the friction cone.
    pub force_boost: f64,
    /// a_s (m/s²): constant part of the deceleration of a slip's relative velocity.
    pub slip_decel: f64,
    /// Share of μ_s λ_n kept free: ‖λ_∥‖ ≤ (1 − margin) μ_s λ_n, in [0, 1).
    pub friction_margin: f64,
    /// After the planned end of a contact phase the commanded λ_n is minus this share of the
    /// phase's largest λ_n*, so the finger lifts off.
    pub lift_off_share: f64,
}

/// All gains of the [`HybridController`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct HybridGains {
    /// Free phases.
    pub free: ComputedTorque,
    /// Contact phases.
    pub contact: ContactGains,
    /// γ of the outer loop (share of the period's mean ω error corrected per period), in
    /// [0, 1].
    pub outer: f64,
}

impl Default for HybridGains {
    /// ω_n = 20 rad/s, ζ = 1 (the free phases of the optima last 0.1–9 s, so errors decay in
    /// a fraction of a phase); k_ω = 100/s (the contact phases of the optima last 26 ms and more), λ_n boost up to 3 × max λ_n*, k_f = 300/s (the loop must settle within a 26 ms stick phase), k_s = 100/s, a_s = 5 m/s²; a friction margin of 20 %
    /// (a plant with μ 20 % below the model still sticks); lift-off share 5 %; γ = 0.5.
    fn default() -> Self {
        HybridGains {
            free: ComputedTorque {
                omega_n: 20.0,
                zeta: 1.0,
            },
            contact: ContactGains {
                omega_rate: 100.0,
                force_boost: 3.0,
                force_integral: 300.0,
                slip_rate: 100.0,
                slip_decel: 20.0,
                friction_margin: 0.2,
                lift_off_share: 0.05,
            },
            outer: 0.5,
        }
    }
}

impl HybridGains {
    /// Checks every gain (finite, in range); the error names it.
    pub fn validate(&self) -> Result<(), ControlError> {
        ComputedTorque::new(self.free.omega_n, self.free.zeta)?;
        let c = &self.contact;
        for (name, value) in [
            ("omega_rate", c.omega_rate),
            ("force_integral", c.force_integral),
            ("slip_rate", c.slip_rate),
            ("slip_decel", c.slip_decel),
            ("force_boost", c.force_boost),
            ("lift_off_share", c.lift_off_share),
        ] {
            if !(value.is_finite() && value >= 0.0) {
                return Err(ControlError::Gain {
                    name,
                    value,
                    condition: "a finite non-negative value",
                });
            }
        }
        if !(0.0..1.0).contains(&c.friction_margin) {
            return Err(ControlError::Gain {
                name: "friction_margin",
                value: c.friction_margin,
                condition: "a value in [0, 1)",
            });
        }
        if !(0.0..=1.0).contains(&self.outer) {
            return Err(ControlError::Gain {
                name: "outer",
                value: self.outer,
                condition: "a value in [0, 1]",
            });
        }
        Ok(())
    }
}

/// Largest ‖δ‖ of the outer loop, as a share of ‖ω̄*‖.
const OFFSET_LIMIT: f64 = 0.25;

/// The discrete state of the controller from time `t` on.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Discrete {
    t: f64,
    mode: Mode,
    phase: usize,
    start: f64,
    force_int: f64,
    omega_offset: [f64; 3],
    omega_int: [f64; 3],
    omega_last: [f64; 3],
    period_start: f64,
    periods: usize,
    slips: usize,
    /// μ_k measured in the last slip (|λ_∥| / λ_n); the model's μ_k before any slip.
    mu_k: f64,
}

/// A phase switch of the controller: plant time, reference phase entered, and the mode
/// transition that caused it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PhaseSwitch {
    /// Plant time (s).
    pub t: f64,
    /// The reference phase entered.
    pub phase: usize,
    /// The plant's mode before the event.
    pub from: Mode,
    /// The plant's mode after it.
    pub to: Mode,
}

/// The hybrid controller (module doc); a bf-sim [`Input`] for 3 joints.
#[derive(Debug)]
pub struct HybridController<K: Kernels<3>> {
    model: Model<K, 3>,
    id: InverseDynamics,
    reference: Reference,
    gains: HybridGains,
    /// max λ_n* of each phase (N): the scale of the lift-off command.
    lambda_scale: Vec<f64>,
    history: RefCell<Vec<Discrete>>,
    switches: RefCell<Vec<PhaseSwitch>>,
}

impl<K: Kernels<3>> HybridController<K> {
    /// The controller on `model` (its own model of the plant: the optimum's scene) with the
    /// inverse dynamics `id` of the same scene, tracking `reference` from its first phase,
    /// which begins at plant time `t0` with the plant's initial state `x0` (q, q̇, ω).
    pub fn new(
        model: Model<K, 3>,
        id: InverseDynamics,
        reference: Reference,
        gains: HybridGains,
        t0: f64,
        x0: &[f64],
    ) -> Result<Self, ControlError> {
        gains.validate()?;
        if id.nq() != 3 {
            return Err(ControlError::Dimension {
                what: "inverse dynamics joints",
                expected: 3,
                found: id.nq(),
            });
        }
        if x0.len() != 9 || x0.iter().any(|v| !v.is_finite()) || !t0.is_finite() {
            return Err(ControlError::Dimension {
                what: "finite initial state (q, qd, omega)",
                expected: 9,
                found: x0.iter().filter(|v| v.is_finite()).count(),
            });
        }
        let lambda_scale = reference
            .phases
            .iter()
            .map(|p| {
                p.lambda
                    .iter()
                    .map(|l| Vec3::from(*l).norm())
                    .fold(0.0, f64::max)
            })
            .collect();
        let mode = if reference.phases[0].contact {
            Mode::Stick
        } else {
            Mode::Free
        };
        let omega = [x0[6], x0[7], x0[8]];
        let d = Discrete {
            t: t0,
            mode,
            phase: 0,
            start: t0,
            force_int: 0.0,
            omega_offset: [0.0; 3],
            omega_int: [0.0; 3],
            omega_last: omega,
            period_start: t0,
            periods: 0,
            slips: 0,
            mu_k: model.params().mu_k(),
        };
        Ok(HybridController {
            model,
            id,
            reference,
            gains,
            lambda_scale,
            history: RefCell::new(vec![d]),
            switches: RefCell::new(Vec::new()),
        })
    }

    /// The reference tracked.
    pub fn reference(&self) -> &Reference {
        &self.reference
    }

    /// The phase switches so far, in time order.
    pub fn switches(&self) -> Vec<PhaseSwitch> {
        self.switches.borrow().clone()
    }

    /// Periods completed so far (the reference wrapped to its first phase).
    pub fn periods(&self) -> usize {
        self.last().periods
    }

    /// Stick → Slip transitions seen so far.
    pub fn slips(&self) -> usize {
        self.last().slips
    }

    /// The outer loop's current ω offset δ (rad/s).
    pub fn omega_offset(&self) -> [f64; 3] {
        self.last().omega_offset
    }

    fn last(&self) -> Discrete {
        let h = self.history.borrow();
        h[h.len() - 1]
    }

    /// The discrete state in force at time `t` in plant mode `mode`: the last one recorded at
    /// or before `t`; of several recorded at `t` itself (an event: pre- and post-transition),
    /// the latest one with that mode.
    fn state_at(&self, t: f64, mode: Mode) -> Discrete {
        let h = self.history.borrow();
        let k = h.partition_point(|e| e.t <= t).max(1);
        let mut i = k - 1;
        while i > 0 && h[i].t == t && h[i].mode != mode && h[i - 1].t == t {
            i -= 1;
        }
        h[i]
    }

    /// τ in `mode` at time `t` and state (q, q̇, ω) with the discrete state `d`.
    fn law(
        &self,
        d: &Discrete,
        mode: Mode,
        t: f64,
        x: &State<3>,
        out: &mut [f64; 3],
    ) -> Result<(), ControlError> {
        let (phase, start) = self.timed_phase(d.phase, d.start, t);
        let ph = &self.reference.phases[phase];
        let s = t - start;
        let r = ph.at(s);
        if mode == Mode::Free || !ph.contact {
            let mut qdd = [0.0; 3];
            self.gains.free.acceleration(
                x.q.as_slice(),
                x.qd.as_slice(),
                &r.q,
                &r.qd,
                &r.qdd,
                &mut qdd,
            );
            return self.id.torque(x.q.as_slice(), x.qd.as_slice(), &qdd, out);
        }
        let g = &self.gains.contact;
        let p = self.model.params();
        let kin = self.model.evaluate(x)?;
        let c = &kin.contact;
        let n = c.n;
        let planned_end = s > ph.duration;
        let mut lambda_n = if planned_end {
            -g.lift_off_share * self.lambda_scale[phase]
        } else {
            Vec3::from(r.lambda).dot(&n) + g.force_integral * d.force_int
        };
        let omega = x.omega;
        let target = Vec3::from(r.omega) + Vec3::from(d.omega_offset);
        let omega_dot_cmd = Vec3::from(r.omega_dot) + (target - omega) * g.omega_rate;
        let ib: &Mat3 = p.ball_inertia();
        let f_b = omega.cross(&(ib * omega)) + omega * p.socket_damping();
        let m = -f_b - ib * omega_dot_cmd;
        let rc = c.r_c;
        let perp = m.cross(&rc) / rc.norm_squared();
        let mut lambda_t = perp - n * n.dot(&perp);
        // The friction measured in a slip scales the static coefficient the margin is taken
        // from (a plant with less friction than the model is found out at its first slip).
        let mu_s = if p.mu_k() > 0.0 {
            p.mu_s() * (d.mu_k / p.mu_k()).min(1.0)
        } else {
            p.mu_s()
        };
        let grip = (1.0 - g.friction_margin) * mu_s;
        if !planned_end {
            // Press harder when the tangential force ω needs exceeds the friction cone with
            // its margin, up to `force_boost` times the phase's largest planned force.
            let needed = lambda_t.norm() / grip;
            lambda_n = lambda_n.max(needed.min(g.force_boost * self.lambda_scale[phase]));
        }
        let cap = grip * lambda_n.max(0.0);
        let lt = lambda_t.norm();
        if lt > cap {
            lambda_t *= if lt > 0.0 { cap / lt } else { 0.0 };
        }
        // In Slip the plant's friction is kinetic, λ = λ_n (n + μ_k t̂) (eq. 20, 37): the
        // tangential force is not the controller's to choose, so it is predicted, and the
        // finger's tangential acceleration instead drives Δv to zero.
        let slip_dir = match mode {
            Mode::Slip => {
                bf_model::dynamics::slip_direction(&kin, self.model.settings(), None).ok()
            }
            _ => None,
        };
        let lambda = match slip_dir {
            Some(t_hat) => (n + t_hat * d.mu_k) * lambda_n,
            None => n * lambda_n + lambda_t,
        };
        let omega_dot = p.ball_inertia_inv() * (-f_b - rc.cross(&lambda));
        let dv = c.delta_v - n * n.dot(&c.delta_v);
        let dv_norm = dv.norm();
        // Δv̇ = −k_s Δv − a_s Δv/‖Δv‖: exponential plus a constant deceleration, so a slip
        // ends in finite time (the Slip → Stick guard ‖Δv‖ ≤ ε).
        // Only in Slip: in Stick Δv is zero up to rounding (the simulator projects onto it),
        // and Δv/‖Δv‖ of rounding noise would be a random unit vector.
        let mut dv_dot = Vec3::zeros();
        if slip_dir.is_some() && dv_norm > 0.0 {
            dv_dot = -dv * (g.slip_rate + g.slip_decel / dv_norm);
        }
        let stick_acc = omega_dot.cross(&rc) + omega.cross(&c.rc_dot) - c.jc_dot_qd - dv_dot;
        // The normal part keeps n·v_c = 0 (the derivative of eq. 36, as the slip law does).
        let normal = -(c.n_dot().dot(&c.v_c) + n.dot(&c.jc_dot_qd));
        let a_c = stick_acc - n * n.dot(&stick_acc) + n * normal;
        let qdd = c
            .j_c
            .lu()
            .solve(&a_c)
            .filter(|v| v.iter().all(|x| x.is_finite()))
            .ok_or(ControlError::SingularJacobian { t })?;
        let tau = kin.m_f * qdd + kin.cqd_g + x.qd * p.mu_v() - c.j_c.transpose() * lambda;
        out.copy_from_slice(tau.as_slice());
        Ok(())
    }

    /// The free phase in force at time `t` when free phase `phase` began at `start`: two free
    /// phases in a row (the optimum's period may begin in the middle of the flight) are joined
    /// by time, as no event separates them. Other phases are returned as they are.
    fn timed_phase(&self, mut phase: usize, mut start: f64, t: f64) -> (usize, f64) {
        let phases = &self.reference.phases;
        for _ in 0..phases.len() {
            let next = (phase + 1) % phases.len();
            let ph = &phases[phase];
            if ph.contact || phases[next].contact || t - start <= ph.duration {
                break;
            }
            start += ph.duration;
            phase = next;
        }
        (phase, start)
    }

    /// [`HybridController::timed_phase`] applied to `d` at time `t`, ending the period when
    /// the reference wraps to its first phase.
    fn advance_timed(&self, d: &mut Discrete, t: f64) {
        let (phase, start) = self.timed_phase(d.phase, d.start, t);
        if phase != d.phase {
            if phase < d.phase {
                self.end_period(d, start);
            }
            d.phase = phase;
            d.start = start;
        }
    }

    /// Moves `d` to the next reference phase whose contact flag is `contact`, starting at `t`;
    /// wrapping past the last phase ends a period (outer loop).
    fn advance(&self, d: &mut Discrete, t: f64, contact: bool) {
        let np = self.reference.phases.len();
        let mut next = d.phase;
        for _ in 0..np {
            next = (next + 1) % np;
            if next == 0 {
                self.end_period(d, t);
            }
            if self.reference.phases[next].contact == contact {
                break;
            }
        }
        d.phase = next;
        d.start = t;
        d.force_int = 0.0;
    }

    fn end_period(&self, d: &mut Discrete, t: f64) {
        let len = t - d.period_start;
        if len > 0.0 {
            for i in 0..3 {
                let mean = d.omega_int[i] / len;
                d.omega_offset[i] += self.gains.outer * (self.reference.mean_omega[i] - mean);
            }
            // Anti-windup: a plant that cannot reach the optimum's ω must not drive the offset
            // (and with it the contact forces) without bound.
            let limit = OFFSET_LIMIT * Vec3::from(self.reference.mean_omega).norm();
            let norm = Vec3::from(d.omega_offset).norm();
            if norm > limit {
                d.omega_offset = d.omega_offset.map(|v| v * limit / norm);
            }
        }
        d.omega_int = [0.0; 3];
        d.period_start = t;
        d.periods += 1;
    }
}

fn to_sim(e: ControlError) -> SimError {
    SimError::system(e)
}

impl<K: Kernels<3>> Input for HybridController<K> {
    fn dim(&self) -> usize {
        3
    }

    fn tau(&self, t: f64, q: &[f64], qd: &[f64], out: &mut [f64]) -> Result<(), SimError> {
        // Without the ball's state the controller assumes free motion.
        self.tau_in_mode(Mode::Free, t, q, qd, &[0.0; 3], out)
    }

    fn tau_in_mode(
        &self,
        mode: Mode,
        t: f64,
        q: &[f64],
        qd: &[f64],
        omega: &[f64],
        out: &mut [f64],
    ) -> Result<(), SimError> {
        let len_err = |what, found| SimError::DimensionMismatch {
            what,
            expected: 3,
            found,
        };
        let q: [f64; 3] = q.try_into().map_err(|_| len_err("q", q.len()))?;
        let qd: [f64; 3] = qd.try_into().map_err(|_| len_err("qd", qd.len()))?;
        let w: [f64; 3] = omega
            .try_into()
            .map_err(|_| len_err("omega", omega.len()))?;
        let out: &mut [f64; 3] = out.try_into().map_err(|_| len_err("torque output", 3))?;
        let d = self.state_at(t, mode);
        let x = State::new(q.into(), qd.into(), w.into());
        self.law(&d, mode, t, &x, out).map_err(to_sim)
    }

    fn wants_force(&self) -> bool {
        true
    }

    fn observe(&self, m: &Measurement<'_>) {
        let mut h = self.history.borrow_mut();
        // A step whose end was measured and then rejected (its projected state failed the
        // validity check) is retried shorter: forget what was recorded after the retry's time.
        while h.len() > 1 && h[h.len() - 1].t > m.t {
            h.pop();
        }
        self.switches.borrow_mut().retain(|s| s.t <= m.t);
        let mut d = h[h.len() - 1];
        let Some(omega) = m.x.get(6..9).and_then(|w| <[f64; 3]>::try_from(w).ok()) else {
            return;
        };
        let dt = m.t - d.t;
        for i in 0..3 {
            d.omega_int[i] += 0.5 * (d.omega_last[i] + omega[i]) * dt;
        }
        d.omega_last = omega;
        self.advance_timed(&mut d, m.t);
        match m.from {
            None => {
                let ph = &self.reference.phases[d.phase];
                if let (Some(lambda), true) = (m.lambda, m.mode != Mode::Free)
                    && let Some(s) = State::<3>::from_slice(m.x)
                    && let Ok(kin) = self.model.evaluate(&s)
                {
                    let n = kin.contact.n;
                    let lambda = Vec3::from(lambda);
                    let lambda_n = lambda.dot(&n);
                    if m.mode == Mode::Slip && lambda_n > 0.0 {
                        let mu = (lambda - n * lambda_n).norm() / lambda_n;
                        if mu.is_finite() && mu > 0.0 {
                            d.mu_k = mu;
                        }
                    }
                    let err = ph.lambda_n(m.t - d.start, &n) - lambda_n;
                    let kf = self.gains.contact.force_integral;
                    if ph.contact && err.is_finite() && dt > 0.0 && m.t - d.start <= ph.duration {
                        d.force_int += err * dt / (1.0 + kf * dt);
                    }
                }
            }
            Some(from) => {
                let was_contact = from != Mode::Free;
                let is_contact = m.mode != Mode::Free;
                if was_contact != is_contact {
                    let in_contact_phase = self.reference.phases[d.phase].contact;
                    if in_contact_phase != is_contact {
                        self.advance(&mut d, m.t, is_contact);
                    }
                    self.switches.borrow_mut().push(PhaseSwitch {
                        t: m.t,
                        phase: d.phase,
                        from,
                        to: m.mode,
                    });
                } else if from == Mode::Stick && m.mode == Mode::Slip {
                    d.slips += 1;
                }
            }
        }
        d.t = m.t;
        d.mode = m.mode;
        h.push(d);
    }
}
