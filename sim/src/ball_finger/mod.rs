//! The ball-and-finger hybrid system (paper Sect. 2.6–3, Fig. 2–3) on top of bf-model.
//!
//! State x = (q, q̇, ω) ∈ ℝ^(2N+3) for a finger with N joints (eq. 44,
//! [`bf_model::State::write_slice`] layout; ℝ⁹ for the paper's N = 3), modes
//! [`bf_model::Mode`] = Free / Stick / Slip, joint torques τ(t, q, q̇) from an [`Input`] with N
//! components. [`BallFinger`] takes N as a const parameter with default 3, like bf-model's
//! [`Model`]: `BallFinger<PaperKernels, I>` is the paper's system, and for N = 3 the generic
//! code runs exactly the arithmetic of a 3-joint-only implementation. The step-to-event
//! machinery ([`crate::Simulator`]) works on slices and needs no change for other N.
//!
//! This file holds [`BallFinger`]: construction (with the length ℓ = a_N of the contact link,
//! the lower limit of sat(α) in eq. 3), the energy E = T + U (eq. 22), the gap h (eq. 4) and
//! the Gauss–Newton projection of q onto h(q) = 0 used by the drift control. The other files:
//! * `settings` — [`BallFingerSettings`].
//! * `hybrid` — the [`HybridSystem`](crate::HybridSystem) implementation: vector fields, guards
//!   and resets of the modes (eq. 19, 26–43, 48–50), the kinks of sat(α) (eq. 3), the Zeno
//!   fallback and the drift control (Sect. 3.1).
//! * `report` — derived per-sample quantities, event kinds, run summary and energy warnings
//!   ([`BallFinger::report`], [`RunSummary`]).
//! * `files` — the output files of a run ([`RunReport::write_dir`]).

mod files;
mod hybrid;
mod report;
mod settings;

pub use report::{EventInfo, ImpulseInfo, RunReport, RunSummary, SampleInfo, event_kind};
pub use settings::BallFingerSettings;

use crate::{Input, SimError};
use bf_model::{Kernels, Mode, Model, ModelError, State, Vec3, VecN};
use std::cell::{Cell, RefCell};

/// The finger–ball [`HybridSystem`](crate::HybridSystem) of a finger with `N` joints (default
/// 3): a bf-model [`Model`] plus a torque [`Input`].
#[derive(Debug, Clone)]
pub struct BallFinger<K: Kernels<N>, I: Input, const N: usize = 3> {
    /// Physics (kernels, parameters, transition tolerances).
    pub model: Model<K, N>,
    /// Joint torques τ(t, q, q̇).
    pub input: I,
    /// Settings.
    pub settings: BallFingerSettings,
    /// Unit slip direction Δv/‖Δv‖ at the start of the current Slip step (zero: unknown), for
    /// the `slip_reversal` guard; updated by the resets into Slip and after every accepted
    /// Slip step (`project`).
    slip_ref: Cell<[f64; 3]>,
    /// The fixed step of the integrator (s; `None` for an adaptive one), the horizon of the
    /// `slip_stop` guard ([`crate::HybridSystem::fixed_step`]).
    fixed_step: Cell<Option<f64>>,
    /// Length ℓ = a_N of the contact link (m), the lower limit of sat(α) in eq. 3.
    link_length: f64,
    /// Guards suspended by the Zeno fallback, and until when.
    hold: Cell<Hold>,
    /// Every sticking contact the Zeno fallback held, as (start, until) (s): the one mechanism
    /// that keeps a contact against λ_n ≥ 0 or σ ≥ 0, which the report judges by it.
    contact_holds: RefCell<Vec<(f64, f64)>>,
}

/// Guards suspended by the Zeno fallback until `until` (s).
#[derive(Debug, Clone, Copy, PartialEq)]
struct Hold {
    until: f64,
    /// The kink guards `alpha_tip`, `alpha_base`.
    kinks: bool,
    /// The contact-mode guards `lambda_n`, `sigma`, `slip_speed`, `slip_reversal`,
    /// `slip_stop`.
    contact: bool,
}

impl Hold {
    const NONE: Hold = Hold {
        until: f64::NEG_INFINITY,
        kinks: false,
        contact: false,
    };
}

fn state_of<const N: usize>(x: &[f64]) -> Result<State<N>, SimError> {
    State::from_slice(x).ok_or(SimError::DimensionMismatch {
        what: "ball-finger state",
        expected: State::<N>::DIM,
        found: x.len(),
    })
}

fn write_velocities<const N: usize>(x: &mut [f64], qd: &VecN<N>, omega: &Vec3) {
    x[N..2 * N].copy_from_slice(qd.as_slice());
    x[2 * N..2 * N + 3].copy_from_slice(omega.as_slice());
}

/// Joint angles of the second configuration at which the contact link length is measured
/// (the first is q = 0); entries beyond the list are 0.
const PROBE_Q: [f64; 7] = [0.3, -0.7, 1.1, 0.5, -0.4, 0.9, 0.2];

/// Length ℓ of the contact link from the contact kernel. With a revolute last joint, advancing
/// q_N by π reverses e_xN about z_{N−1} while p_{N−1} (joint N) stays, and
/// α = (o_b − p_{N−1} − d_N z_{N−1})·e_xN − ℓ (eq. 2 with p_e = p_{N−1} + d_N z_{N−1} + ℓ e_xN),
/// so α(q) + α(q + π e_N) = −2ℓ. Checked at two configurations and, for the exact saturation,
/// against sat(α) = −ℓ where α < −ℓ.
fn contact_link_length<K: Kernels<N>, const N: usize>(
    model: &Model<K, N>,
) -> Result<f64, SimError> {
    let alpha = |q: VecN<N>| -> Result<(f64, f64), SimError> {
        let c = model
            .evaluate(&State::new(q, VecN::<N>::zeros(), Vec3::zeros()))
            .map_err(SimError::system)?
            .contact;
        Ok((c.alpha, c.sat_alpha))
    };
    let pi = std::f64::consts::PI;
    let mut turn = VecN::<N>::zeros();
    turn[N - 1] = pi;
    let probe = VecN::<N>::from_fn(|i, _| PROBE_Q.get(i).copied().unwrap_or(0.0));
    let mut lengths = Vec::new();
    // Where the ball's centre lies on the contact link's line the contact normal is undefined
    // and the kernel's geometry not finite: such a configuration is passed over for another.
    let mut singular = None;
    let mut failed = 0;
    for q in [VecN::<N>::zeros(), probe, -probe, 0.5 * probe, 1.7 * probe] {
        if lengths.len() == 2 {
            break;
        }
        let (a0, s0, a1, s1) = match (alpha(q), alpha(q + turn)) {
            (Ok((a0, s0)), Ok((a1, s1))) => (a0, s0, a1, s1),
            (Err(e), _) | (_, Err(e)) => {
                singular = Some(e);
                failed += 1;
                continue;
            }
        };
        let l = -0.5 * (a0 + a1);
        // The side with α < −ℓ has sat(α) = −ℓ for the exact saturation.
        let (a_low, s_low) = if a0 < a1 { (a0, s0) } else { (a1, s1) };
        let exact = model.contact_variant() == bf_model::ContactVariant::Exact;
        let tol = 1e-9 * (1.0 + l.abs());
        if exact && a_low < -l - tol && (s_low + l).abs() > tol {
            return Err(contact_link_error(l, "sat(alpha) does not saturate at -l"));
        }
        lengths.push(l);
    }
    if lengths.len() < 2 {
        let why = singular.map_or_else(String::new, |e| format!(" ({e})"));
        return Err(contact_link_error(
            f64::NAN,
            &format!(
                "the contact kernel is not finite at {failed} of the 5 configurations \
                 tried{why}"
            ),
        ));
    }
    let l = lengths[0];
    if !(l.is_finite() && l > 0.0) || (lengths[1] - l).abs() > 1e-9 * (1.0 + l) {
        return Err(contact_link_error(
            l,
            "alpha(q) + alpha(q + pi e3) is not the same -2 l at two configurations",
        ));
    }
    Ok(l)
}

fn contact_link_error(l: f64, why: &str) -> SimError {
    SimError::System {
        msg: format!(
            "cannot determine the contact link length from the contact kernel (got {l}): {why}; \
             the ball-finger simulator needs a revolute last joint carrying the contact link"
        ),
    }
}

impl<K: Kernels<N>, I: Input, const N: usize> BallFinger<K, I, N> {
    /// Builds the system; the input must provide N torques.
    pub fn new(
        model: Model<K, N>,
        input: I,
        settings: BallFingerSettings,
    ) -> Result<Self, SimError> {
        if input.dim() != N {
            return Err(SimError::DimensionMismatch {
                what: "torque input",
                expected: N,
                found: input.dim(),
            });
        }
        let link_length = contact_link_length(&model)?;
        Ok(BallFinger {
            model,
            input,
            settings,
            slip_ref: Cell::new([0.0; 3]),
            fixed_step: Cell::new(None),
            link_length,
            hold: Cell::new(Hold::NONE),
            contact_holds: RefCell::new(Vec::new()),
        })
    }

    /// Length ℓ of the contact link (m): the α at which sat(α) of eq. 3 saturates at −ℓ.
    pub fn link_length(&self) -> f64 {
        self.link_length
    }

    /// Maps a model error at a trial state: far from contact is outside the contact modes'
    /// domain, and so is a slip whose normal force has no unique solution (Painlevé, eq. 37):
    /// the step is retried shorter. A trial stage past the end of a slip has Δv reversed and
    /// with it the friction direction t̂ (eq. 20), and with a large μ_k that alone makes
    /// nᵀ W (n + μ_k t̂) negative; a shorter step ends before the slip stops, where the
    /// `slip_speed` guard takes over. A paradox on the trajectory itself still ends the run
    /// (no step short enough avoids it). Everything else is a system error.
    fn model_err(mode: Mode, t: f64) -> impl Fn(ModelError) -> SimError {
        move |e| match e {
            ModelError::NotInContact { .. } | ModelError::Painleve { .. } => {
                SimError::OutsideDomain {
                    t,
                    mode: format!("{mode:?}"),
                    msg: e.to_string(),
                }
            }
            e => SimError::system(e),
        }
    }

    fn set_slip_ref(&self, dv: &Vec3) {
        let n = dv.norm();
        let d = if n > 0.0 && n.is_finite() {
            dv / n
        } else {
            Vec3::zeros()
        };
        self.slip_ref.set(d.into());
    }

    /// Gauss–Newton steps of q along ∇h = J_cᵀ n onto h(q) = 0; returns |h| before.
    fn project_position(&self, s: &mut State<N>) -> Result<Option<f64>, SimError> {
        let mut drift = None;
        for _ in 0..self.settings.projection_iterations {
            let kin = self.model.evaluate(s).map_err(SimError::system)?;
            let c = &kin.contact;
            drift.get_or_insert(c.h.abs());
            let grad = c.j_c.transpose() * c.n;
            let g2 = grad.norm_squared();
            if c.h == 0.0 || g2 < 1e-24 {
                break;
            }
            s.q -= grad * (c.h / g2);
        }
        Ok(drift)
    }

    fn tau(&self, mode: Mode, t: f64, s: &State<N>) -> Result<VecN<N>, SimError> {
        self.input_tau(report::Limit::After, mode, t, s)
    }

    /// τ at (t, s) in `mode`, on the given side of the input's observations at `t`.
    fn input_tau(
        &self,
        limit: report::Limit,
        mode: Mode,
        t: f64,
        s: &State<N>,
    ) -> Result<VecN<N>, SimError> {
        let mut tau = [0.0; N];
        let x = (s.q.as_slice(), s.qd.as_slice(), s.omega.as_slice());
        match limit {
            report::Limit::After => self.input.tau_in_mode(mode, t, x.0, x.1, x.2, &mut tau),
            report::Limit::Before => self.input.tau_before(mode, t, x.0, x.1, x.2, &mut tau),
        }?;
        Ok(VecN::<N>::from(tau))
    }

    /// Total energy E = T + U at `x` (J).
    pub fn energy(&self, x: &[f64]) -> Result<f64, SimError> {
        let s = state_of::<N>(x)?;
        Ok(self.model.energy(&s).map_err(SimError::system)?.total)
    }

    /// Gap h(q) at `x` (m).
    pub fn gap(&self, x: &[f64]) -> Result<f64, SimError> {
        let s = state_of::<N>(x)?;
        Ok(self.model.evaluate(&s).map_err(SimError::system)?.contact.h)
    }
}
