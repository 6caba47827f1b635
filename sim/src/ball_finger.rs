//! The ball-and-finger hybrid system (paper Sect. 2.6–3, Fig. 2–3) on top of bf-model.
//!
//! State x = (q, q̇, ω) ∈ ℝ⁹ (eq. 44, [`bf_model::State::to_array`] layout), modes
//! [`bf_model::Mode`] = Free / Stick / Slip, joint torques τ(t, q, q̇) from an [`Input`].
//!
//! | mode | vector field | guards (region: valid while g > 0, all `Falling`) |
//! |---|---|---|
//! | Free | eq. 26 | `h` (eq. 50: contact when h crosses 0 or leaves the band h ≥ −tol) |
//! | Stick | eq. 29, λ from eq. 33 | `lambda_n` (λ_n < 0 → Free, eq. 48), `sigma` (σ ≤ 0 → Slip, eq. 19) |
//! | Slip | eq. 37, λ from eq. 38 | `lambda_n` (→ Free), `slip_speed` = ‖Δv‖ − ε (→ Stick, Sect. 3.1), `slip_reversal` = Δv·d₀ − ½‖Δv‖ (Δv turned > 60° within a step: it passed ‖Δv‖ ≈ 0, → Stick) |
//! | Stick, Slip | | `alpha_tip` = α, `alpha_base` = α + ℓ (either direction): the kinks of sat(α), eq. 3 (see below) |
//!
//! Resets: Free → impact law of Sect. 2.5 (eq. 39–43, [`ImpactLaw`]); the post-impact ‖Δv⁺‖
//! picks Stick or Slip (Fig. 3's "In-contact" state). Stick → Slip: velocity kick Δv⁺ =
//! `slip_kick` along λ_∥ (so the slip guard does not fire back). Slip → Stick: projection onto
//! Δv = 0 with the sticking impulse (eq. 40–41). Contact → Free: q back onto h = 0 and a tiny
//! normal impulse sets n·v_c⁺ = `lift_off_speed` (1e-8 m/s) so the h guard does not chatter at
//! λ_n = 0. An h crossing in Free while n·v_c > 0 (interpolation error at a graze) puts q back
//! on h = 0 and stays Free instead of applying an impact to a separating finger. When the
//! new mode is already invalid (e.g. λ_n < 0 right after a sticking impact) the simulator chains
//! the next transition at the same instant.
//!
//! # Non-smooth points of the contact geometry
//! The finger's last link is the segment from joint 3 to the fingertip p_e (Sect. 2.2); the
//! potential contact point p_c = p_e + sat(α) e_x3 (eq. 3) has two kinks, α = 0 (p_c reaches the
//! fingertip: the contact passes between the link's side and its end point) and α = −ℓ (p_c
//! reaches the link's base, joint 3; ℓ = a₃). At both, h (eq. 4, the distance to a convex set,
//! C¹ away from it), n (eq. 11), J_c (eq. 7) and v_c (eq. 6) are continuous, so at h = 0 the
//! conditions h = 0 (eq. 8) and n·v_c = 0 (eq. 10) hold on both sides and no impulse is needed.
//! But d sat(α)/dt jumps between α̇ and 0, so ṙ_c and J̇_c q̇ in the bias of eq. 33 and in the
//! normal-constraint acceleration of eq. 36–38 jump: λ and the accelerations are discontinuous
//! there. Hence in Stick and Slip the guards `alpha_tip` and `alpha_base` locate the crossing on
//! the dense output (event kind `kink`) and the reset keeps state and mode: the contact
//! persists on the other part of the link (the end point or the side), and whether it persists
//! beyond that instant is decided by the new geometry's λ_n (eq. 48: λ_n < 0 lifts off at once,
//! e.g. when the tip's path curves away from the ball) and σ (eq. 19: Stick → Slip), which the
//! simulator checks right after the reset (chained transitions). Free motion needs no kink
//! events: its vector field does not involve the contact and its guard h is C¹. The only other
//! non-smooth point, |r_c| = 0 (n undefined), cannot occur near contact (|r_c| = r + h).
//! Besides, a trial step whose stage or end state leaves the contact band |h| ≤
//! `contact_tolerance`·r is rejected and retried shorter ([`SimError::OutsideDomain`]), so a
//! step cannot jump out of the contact modes' domain.
//!
//! # Zeno fallback
//! More than `SimSettings::zeno_max_events` events within `zeno_window` (an accumulation of
//! events, e.g. the contact point chattering at a kink, or impact / lift-off or stick / slip
//! chatter) calls [`HybridSystem::zeno_fallback`], which ends the cascade for
//! `BallFingerOptions::zeno_hold_time` seconds and is reported as a `zeno_fallback` warning:
//! * only kink events: the kink guards are suspended (the mode continues; the error control
//!   shortens the steps across the kink);
//! * otherwise: the contact is made sticking (q projected onto h = 0, velocities onto Δv = 0 by
//!   the sticking impulse of eq. 40–41, which never adds energy) and held in Stick regardless of
//!   λ_n and σ (the lift-off and stick → slip guards are suspended; the sticking force does no
//!   work). When the hold ends the guards take over again.
//!
//! # Energy warnings
//! The run summary reports each impact that raises the energy (only Newton's law, eq. 39, can:
//! see bf-model's impact module) and the energy-balance error E(t) − E(t₀) − ∫ P dt of the
//! integration (P of the power balance, eq. 22/25); above `BallFingerOptions::energy_error_tol`
//! it is a warning (e.g. fixed-step RK4 with a step too long for the dynamics).
//!
//! Drift control (Sect. 3.1 "we also allow h(q) to drift"): after each accepted step in a
//! contact mode, q is projected back onto h(q) = 0 by Gauss–Newton along ∇h = J_cᵀ n, then the
//! velocities onto the mode's constraint (Stick: Δv = 0 via the sticking impulse; Slip:
//! n·v_c = 0 by the M_f-norm-minimal change of q̇). The reported drift is |h| before projection
//! (m).
//!
//! Output ([`BallFinger::sample_info`], [`BallFinger::report`]): at every stored sample the
//! derived quantities τ, λ (eq. 33 / 37), λ_n (eq. 12), h (eq. 4), σ (eq. 18), ‖Δv‖ (eq. 13),
//! n·v_c (eq. 36) and E = T + U (eq. 22) are recomputed from the model, so the files can be
//! checked against the transition conditions of Sect. 3.1 without re-running the model; events
//! are named by their Fig. 3 transition ([`event_kind`]).

use crate::trajectory::{SampleKind, SimOutput, write_atomic};
use crate::{Guard, HybridSystem, Input, SimError, SimWarning, Transition};
use bf_model::dynamics::contact_matrices;
use bf_model::{ImpactLaw, Kernels, Mode, Model, ModelError, State, Vec3};
use serde::Serialize;
use std::cell::Cell;
use std::path::Path;

/// The `slip_reversal` guard fires when Δv turns by more than arccos(0.5) = 60° from its
/// direction at the start of the step: in continuous slip the direction of Δv changes slowly
/// unless ‖Δv‖ passes (close to) zero, which is the Slip → Stick condition of Sect. 3.1. It
/// catches the zero passage that the ‖Δv‖ ≤ ε guard misses when a step jumps over the ε-ball
/// (loose tolerances, fixed-step RK4).
const REVERSAL_COS: f64 = 0.5;

/// Options of the ball-and-finger hybrid system.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BallFingerOptions {
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
    /// valid; it does not act on the ball (r_c ∥ n) and changes the energy by O(1e-18) J.
    /// 0 disables it.
    pub lift_off_speed: f64,
    /// How long the Zeno fallback holds its regularisation (s): suspended kink guards, or a
    /// sticking contact held regardless of λ_n and σ (see the module docs) (default: 1e-2).
    pub zeno_hold_time: f64,
    /// An impact that raises the energy E by more than this (J) is reported as an
    /// `energy_raising_impact` warning; only Newton's law (eq. 39) can do so (default: 1e-9).
    pub impact_energy_tol: f64,
    /// A run whose energy-balance error (the largest |E(t) − E(t₀) − ∫ P dt − Σ ΔE_events|,
    /// P = dE/dt of the power balance, trapezoidal rule over the samples) exceeds this (J) gets an
    /// `energy_error` warning: the step is too long for the dynamics (e.g. fixed-step RK4 with a
    /// large step) (default: 1e-3).
    pub energy_error_tol: f64,
}

impl Default for BallFingerOptions {
    fn default() -> Self {
        BallFingerOptions {
            impact_law: ImpactLaw::Stick,
            project: true,
            projection_iterations: 3,
            lift_off_speed: 1e-8,
            zeno_hold_time: 1e-2,
            impact_energy_tol: 1e-9,
            energy_error_tol: 1e-3,
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
    /// Unit slip direction Δv/‖Δv‖ at the start of the current Slip step (zero: unknown), for
    /// the `slip_reversal` guard; updated by the resets into Slip and after every accepted
    /// Slip step (`project`).
    slip_ref: Cell<[f64; 3]>,
    /// Length ℓ = a₃ of the contact link (m), the lower limit of sat(α) in eq. 3.
    link_length: f64,
    /// Guards suspended by the Zeno fallback, and until when.
    hold: Cell<Hold>,
}

/// Guards suspended by the Zeno fallback until `until` (s).
#[derive(Debug, Clone, Copy, PartialEq)]
struct Hold {
    until: f64,
    /// The kink guards `alpha_tip`, `alpha_base`.
    kinks: bool,
    /// The contact-mode guards `lambda_n`, `sigma`, `slip_speed`, `slip_reversal`.
    contact: bool,
}

impl Hold {
    const NONE: Hold = Hold {
        until: f64::NEG_INFINITY,
        kinks: false,
        contact: false,
    };
}

/// Value of a guard suspended by the Zeno fallback: constant and on the valid side, so it
/// neither fires nor masks; when the hold ends the true value takes over (a crossing there is an
/// ordinary event).
const HELD_GUARD: f64 = 1.0;

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

/// Length ℓ of the contact link from the contact kernel. With a revolute last joint, advancing q₃
/// by π reverses e_x3 about z₂ while p₂ (joint 3) stays, and α = (o_b − p₂ − d₃ z₂)·e_x3 − ℓ
/// (eq. 2 with p_e = p₂ + d₃ z₂ + ℓ e_x3), so α(q) + α(q + π e₃) = −2ℓ. Checked at two
/// configurations and, for the exact saturation, against sat(α) = −ℓ where α < −ℓ.
fn contact_link_length<K: Kernels>(model: &Model<K>) -> Result<f64, SimError> {
    let alpha = |q: Vec3| -> Result<(f64, f64), SimError> {
        let c = model
            .evaluate(&State::new(q, Vec3::zeros(), Vec3::zeros()))
            .map_err(SimError::system)?
            .contact;
        Ok((c.alpha, c.sat_alpha))
    };
    let pi = std::f64::consts::PI;
    let mut lengths = Vec::new();
    for q in [Vec3::new(0.0, 0.0, 0.0), Vec3::new(0.3, -0.7, 1.1)] {
        let (a0, s0) = alpha(q)?;
        let (a1, s1) = alpha(q + Vec3::new(0.0, 0.0, pi))?;
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
        let link_length = contact_link_length(&model)?;
        Ok(BallFinger {
            model,
            input,
            options,
            slip_ref: Cell::new([0.0; 3]),
            link_length,
            hold: Cell::new(Hold::NONE),
        })
    }

    /// Length ℓ of the contact link (m): the α at which sat(α) of eq. 3 saturates at −ℓ.
    pub fn link_length(&self) -> f64 {
        self.link_length
    }

    /// Maps a model error at a trial state: far from contact is outside the contact modes'
    /// domain (the step is retried shorter), everything else is a system error.
    fn model_err(mode: Mode, t: f64) -> impl Fn(ModelError) -> SimError {
        move |e| match e {
            ModelError::NotInContact { .. } => SimError::OutsideDomain {
                t,
                mode: format!("{mode:?}"),
                msg: e.to_string(),
            },
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
    fn project_position(&self, s: &mut State) -> Result<Option<f64>, SimError> {
        let mut drift = None;
        for _ in 0..self.options.projection_iterations {
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

    /// Derived quantities at one sample (t, x) in `mode`: τ from the input, λ from the mode's
    /// dynamics (0 in Free, eq. 45), h, σ, ‖Δv‖, n·v_c, the energy and its rate.
    pub fn sample_info(&self, mode: Mode, t: f64, x: &[f64]) -> Result<SampleInfo, SimError> {
        let s = state_of(x)?;
        let tau = self.tau(t, &s)?;
        let kin = self.model.evaluate(&s).map_err(SimError::system)?;
        let acc = self
            .model
            .accelerations(mode, &s, &tau)
            .map_err(SimError::system)?;
        let e = self.model.energy(&s).map_err(SimError::system)?;
        let power = bf_model::energy::power_balance(&kin, self.model.params(), &tau, &acc.force);
        let c = &kin.contact;
        Ok(SampleInfo {
            tau: tau.into(),
            lambda: acc.force.lambda.into(),
            lambda_n: acc.force.lambda_n,
            sigma: acc.force.sigma,
            h: c.h,
            slip_speed: c.delta_v.norm(),
            normal_velocity: c.normal_velocity(),
            energy: e.total,
            power: power.total,
        })
    }

    /// [`BallFinger::sample_info`] that never fails: a sample where the model cannot be
    /// evaluated (e.g. the state a failed run stopped at) gets NaN fields (`null` in JSON).
    pub fn sample_info_or_nan(&self, mode: Mode, t: f64, x: &[f64]) -> SampleInfo {
        self.sample_info(mode, t, x).unwrap_or(SampleInfo::NAN)
    }

    /// Derived quantities at every sample and event of a run, plus its summary. `cpu_seconds`
    /// is the wall time the run took (for the real-time factor).
    pub fn report(&self, out: &SimOutput<Mode>, t0: f64, cpu_seconds: f64) -> RunReport {
        let tr = &out.trajectory;
        let samples: Vec<SampleInfo> = (0..tr.len())
            .map(|i| self.sample_info_or_nan(tr.mode[i], tr.t[i], &tr.x[i]))
            .collect();
        let events: Vec<EventInfo> = out
            .events
            .iter()
            .map(|e| EventInfo {
                t: e.t,
                kind: event_kind(e.mode_before, e.mode_after, e.guard),
                guard: e.guard,
                mode_before: e.mode_before,
                mode_after: e.mode_after,
                chained: e.chained,
                x_pre: e.x_pre.clone(),
                x_post: e.x_post.clone(),
                pre: self.sample_info_or_nan(e.mode_before, e.t, &e.x_pre),
                post: self.sample_info_or_nan(
                    e.mode_after.unwrap_or(e.mode_before),
                    e.t,
                    &e.x_post,
                ),
            })
            .collect();
        let summary = summarize(out, &samples, &events, t0, cpu_seconds, &self.options);
        RunReport {
            samples,
            events,
            summary,
        }
    }
}

/// Name of a Fig. 3 transition from the mode it leaves and the guard that fired:
/// `impact` (Free, h = 0, eq. 50), `graze` (h crossed zero on the interpolant while separating:
/// q put back on the surface, still Free), `lift_off` (λ_n < 0, eq. 48), `stick_to_slip` (σ ≤ 0,
/// eq. 19), `slip_to_stick` (‖Δv‖ ≤ ε, Sect. 3.1); and `kink` (the contact point passed a kink of
/// sat(α), eq. 3: same mode before and after).
pub fn event_kind(mode_before: Mode, mode_after: Option<Mode>, guard: &str) -> &'static str {
    match (mode_before, guard) {
        (_, "alpha_tip" | "alpha_base") => "kink",
        (Mode::Free, _) if mode_after == Some(Mode::Free) => "graze",
        (Mode::Free, _) => "impact",
        (_, "lambda_n") => "lift_off",
        (Mode::Stick, _) => "stick_to_slip",
        (Mode::Slip, _) => "slip_to_stick",
    }
}

/// Quantities derived from the model at one stored sample (SI units).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct SampleInfo {
    /// Joint torques τ (N m).
    pub tau: [f64; 3],
    /// Contact force on the finger λ, world axes (N); 0 in Free.
    pub lambda: [f64; 3],
    /// Normal force λ_n = λ·n (N, eq. 12).
    pub lambda_n: f64,
    /// Friction margin σ = μ_s λ_n − ‖λ_∥‖ (N, eq. 18); 0 in Free.
    pub sigma: f64,
    /// Gap h (m, eq. 4); negative = penetration.
    pub h: f64,
    /// Relative slip speed ‖Δv‖ (m/s, eq. 13).
    pub slip_speed: f64,
    /// Normal velocity n·v_c = ḣ (m/s, eq. 36).
    pub normal_velocity: f64,
    /// Total energy E = T + U (J, eq. 22).
    pub energy: f64,
    /// dE/dt = q̇ᵀτ − μ_v‖q̇‖² − D‖ω‖² − λ·Δv of the power balance (W); JSON only.
    pub power: f64,
}

impl SampleInfo {
    /// All fields NaN (sample that could not be evaluated).
    pub const NAN: SampleInfo = SampleInfo {
        tau: [f64::NAN; 3],
        lambda: [f64::NAN; 3],
        lambda_n: f64::NAN,
        sigma: f64::NAN,
        h: f64::NAN,
        slip_speed: f64::NAN,
        normal_velocity: f64::NAN,
        energy: f64::NAN,
        power: f64::NAN,
    };
}

/// One event of the log with the derived quantities before and after the reset.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct EventInfo {
    /// Event time (s).
    pub t: f64,
    /// Fig. 3 transition name ([`event_kind`]).
    pub kind: &'static str,
    /// Guard that fired (`h`, `lambda_n`, `sigma`, `slip_speed`).
    pub guard: &'static str,
    /// Mode before.
    pub mode_before: Mode,
    /// Mode after (`None`: terminated).
    pub mode_after: Option<Mode>,
    /// Whether it fired at the same instant as the previous event (chained).
    pub chained: bool,
    /// State (q, q̇, ω) before the reset.
    pub x_pre: Vec<f64>,
    /// State after the reset.
    pub x_post: Vec<f64>,
    /// Derived quantities before the reset (in `mode_before`).
    pub pre: SampleInfo,
    /// Derived quantities after the reset (in `mode_after`).
    pub post: SampleInfo,
}

/// Summary of a run (printed by the CLI, written as `summary.json`).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct RunSummary {
    /// Start time (s).
    pub t0: f64,
    /// Time reached (s).
    pub t_final: f64,
    /// Mode at `t_final`.
    pub mode_final: Mode,
    /// Number of events of each kind, in a fixed order (impact, lift_off, stick_to_slip,
    /// slip_to_stick, graze, kink).
    pub event_counts: Vec<(&'static str, usize)>,
    /// Share of the simulated time spent in Free, Stick, Slip (sums to 1).
    pub mode_time_share: [(Mode, f64); 3],
    /// Largest penetration max(−h, 0) over all samples (m).
    pub max_penetration: f64,
    /// Largest contact drift |h| removed by the projection (m, before projection).
    pub max_drift: f64,
    /// Drift |h| removed at the last projected step (m); 0 if the run never projected.
    pub final_drift: f64,
    /// Largest |h| over contact-mode samples as stored (after projection, if any) (m).
    pub max_contact_gap: f64,
    /// Largest |n·v_c| over contact-mode samples as stored (m/s): velocity-constraint drift.
    pub max_normal_velocity: f64,
    /// Energy at the first and last sample (J).
    pub energy_initial: f64,
    /// Energy at the last sample (J).
    pub energy_final: f64,
    /// Largest energy change E⁺ − E⁻ over the impacts (J); > 0 only for Newton's law (eq. 39),
    /// which does not guarantee dissipation. 0 without impacts.
    pub max_impact_energy_gain: f64,
    /// Largest |E(t) − E(t₀) − ∫ P dt − Σ ΔE_events| over the samples (J): the energy-balance
    /// error of the integration (P from the power balance, trapezoidal rule between samples;
    /// jumps at events excluded).
    pub energy_error: f64,
    /// Conditions that qualify the result: `energy_raising_impact` (one per impact raising E by
    /// more than `BallFingerOptions::impact_energy_tol`), `energy_error` (energy-balance error
    /// above `BallFingerOptions::energy_error_tol`), `zeno_fallback` (see the module docs).
    pub warnings: Vec<SimWarning>,
    /// Accepted steps, rejected steps, vector-field evaluations.
    pub stats: crate::SimStats,
    /// Wall-clock time of the run (s).
    pub cpu_seconds: f64,
    /// Simulated time / wall-clock time.
    pub real_time_factor: f64,
}

fn summarize(
    out: &SimOutput<Mode>,
    samples: &[SampleInfo],
    events: &[EventInfo],
    t0: f64,
    cpu_seconds: f64,
    options: &BallFingerOptions,
) -> RunSummary {
    let tr = &out.trajectory;
    let kinds = [
        "impact",
        "lift_off",
        "stick_to_slip",
        "slip_to_stick",
        "graze",
        "kink",
    ];
    let mut warnings = Vec::new();
    let mut max_impact_energy_gain = 0.0f64;
    for e in events.iter().filter(|e| e.kind == "impact") {
        let gain = e.post.energy - e.pre.energy;
        if gain.is_finite() {
            max_impact_energy_gain = max_impact_energy_gain.max(gain);
        }
        if gain > options.impact_energy_tol {
            warnings.push(SimWarning {
                t: e.t,
                kind: "energy_raising_impact",
                message: format!(
                    "{} impact raised the energy by {gain:+.3e} J",
                    options.impact_law.name()
                ),
            });
        }
    }
    let (energy_error, t_error) = energy_balance_error(tr, samples);
    warnings.extend(out.warnings.iter().cloned());
    if energy_error > options.energy_error_tol {
        warnings.push(SimWarning {
            t: t_error,
            kind: "energy_error",
            message: format!(
                "energy-balance error {energy_error:.3e} J exceeds {:e} J: the integration \
                 step is too long for the dynamics",
                options.energy_error_tol
            ),
        });
    }
    warnings.sort_by(|a, b| a.t.total_cmp(&b.t));
    let event_counts = kinds
        .iter()
        .map(|&k| (k, events.iter().filter(|e| e.kind == k).count()))
        .collect();
    let mut time = [0.0f64; 3];
    let idx = |m: Mode| match m {
        Mode::Free => 0,
        Mode::Stick => 1,
        Mode::Slip => 2,
    };
    for i in 1..tr.len() {
        // The interval (t[i-1], t[i]] belongs to the mode in which it was integrated.
        time[idx(tr.mode[i])] += tr.t[i] - tr.t[i - 1];
    }
    let total: f64 = time.iter().sum();
    let share = |k: usize| if total > 0.0 { time[k] / total } else { 0.0 };
    let contact = |i: &usize| tr.mode[*i] != Mode::Free;
    let max_penetration = samples
        .iter()
        .map(|s| -s.h)
        .filter(|v| v.is_finite())
        .fold(0.0, f64::max);
    let max_contact_gap = (0..tr.len())
        .filter(contact)
        .map(|i| samples[i].h.abs())
        .filter(|v| v.is_finite())
        .fold(0.0, f64::max);
    let max_normal_velocity = (0..tr.len())
        .filter(contact)
        .map(|i| samples[i].normal_velocity.abs())
        .filter(|v| v.is_finite())
        .fold(0.0, f64::max);
    let final_drift = (0..tr.len())
        .rev()
        .find(|&i| tr.kind[i] == SampleKind::Step && tr.drift[i].is_some())
        .and_then(|i| tr.drift[i])
        .unwrap_or(0.0);
    let elapsed = out.t_final - t0;
    RunSummary {
        t0,
        t_final: out.t_final,
        mode_final: out.mode_final,
        event_counts,
        mode_time_share: [
            (Mode::Free, share(0)),
            (Mode::Stick, share(1)),
            (Mode::Slip, share(2)),
        ],
        max_penetration,
        max_drift: out.stats.max_drift,
        final_drift,
        max_contact_gap,
        max_normal_velocity,
        energy_initial: samples.first().map_or(f64::NAN, |s| s.energy),
        energy_final: samples.last().map_or(f64::NAN, |s| s.energy),
        max_impact_energy_gain,
        energy_error,
        warnings,
        stats: out.stats,
        cpu_seconds,
        real_time_factor: if cpu_seconds > 0.0 {
            elapsed / cpu_seconds
        } else {
            f64::INFINITY
        },
    }
}

/// Largest |E(t) − E(t₀) − ∫ P dt| over the samples, with the jumps at events (the interval
/// ending at an `EventPost` sample) left out, and the time where it occurs. Non-finite samples
/// (a failed run's last state) are skipped.
fn energy_balance_error(tr: &crate::Trajectory<Mode>, samples: &[SampleInfo]) -> (f64, f64) {
    let mut residual = 0.0f64;
    let mut worst = (0.0f64, tr.t.first().copied().unwrap_or(0.0));
    for i in 1..tr.len() {
        if tr.kind[i] == SampleKind::EventPost {
            continue;
        }
        let (a, b) = (&samples[i - 1], &samples[i]);
        let step = (b.energy - a.energy) - 0.5 * (a.power + b.power) * (tr.t[i] - tr.t[i - 1]);
        if !step.is_finite() {
            continue;
        }
        residual += step;
        if residual.abs() > worst.0 {
            worst = (residual.abs(), tr.t[i]);
        }
    }
    worst
}

impl RunSummary {
    /// One line per kind of warning (count, worst case, what to do), for the CLI.
    pub fn warning_lines(&self) -> Vec<String> {
        let mut lines = Vec::new();
        let of = |kind: &'static str| self.warnings.iter().filter(move |w| w.kind == kind);
        let n = of("energy_raising_impact").count();
        if n > 0 {
            lines.push(format!(
                "{n} impact(s) raised the energy, largest {:+.3e} J: Newton's law (eq. 39) does \
                 not guarantee dissipation (stick, max-dissipation and min-slip do)",
                self.max_impact_energy_gain
            ));
        }
        for w in of("energy_error") {
            lines.push(format!("t = {} s: {}", w.t, w.message));
        }
        let z: Vec<&SimWarning> = of("zeno_fallback").collect();
        if let Some(w) = z.first() {
            lines.push(format!(
                "{} Zeno fallback(s), first at t = {} s: {}",
                z.len(),
                w.t,
                w.message
            ));
        }
        lines
    }
}

impl std::fmt::Display for RunSummary {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        writeln!(
            f,
            "simulated t = {} .. {} s, final mode {:?}",
            self.t0, self.t_final, self.mode_final
        )?;
        let ev: Vec<String> = self
            .event_counts
            .iter()
            .map(|(k, n)| format!("{k} {n}"))
            .collect();
        writeln!(f, "events: {} ({})", self.stats.events, ev.join(", "))?;
        let sh: Vec<String> = self
            .mode_time_share
            .iter()
            .map(|(m, s)| format!("{m:?} {:.1}%", 100.0 * s))
            .collect();
        writeln!(f, "time in modes: {}", sh.join(", "))?;
        writeln!(f, "max penetration: {:.3e} m", self.max_penetration)?;
        writeln!(
            f,
            "contact drift |h| before projection: max {:.3e} m, final {:.3e} m; after: max |h| {:.3e} m, max |n.v_c| {:.3e} m/s",
            self.max_drift, self.final_drift, self.max_contact_gap, self.max_normal_velocity
        )?;
        writeln!(
            f,
            "energy: {:.9} J -> {:.9} J (change {:+.3e} J); balance error {:.3e} J",
            self.energy_initial,
            self.energy_final,
            self.energy_final - self.energy_initial,
            self.energy_error
        )?;
        writeln!(
            f,
            "steps: {} accepted, {} rejected, {} rhs evaluations",
            self.stats.accepted_steps, self.stats.rejected_steps, self.stats.rhs_evals
        )?;
        write!(
            f,
            "cpu time: {:.3} ms, real-time factor {:.0}x",
            1e3 * self.cpu_seconds,
            self.real_time_factor
        )
    }
}

/// Everything derived from one ball-and-finger run ([`BallFinger::report`]).
#[derive(Debug, Clone, PartialEq)]
pub struct RunReport {
    /// Derived quantities per trajectory sample (same indices as the trajectory).
    pub samples: Vec<SampleInfo>,
    /// Event log with derived quantities.
    pub events: Vec<EventInfo>,
    /// Summary.
    pub summary: RunSummary,
}

const TRAJ_HEADER: [&str; 25] = [
    "t", "mode", "kind", "q1", "q2", "q3", "qd1", "qd2", "qd3", "omega1", "omega2", "omega3",
    "tau1", "tau2", "tau3", "lambda1", "lambda2", "lambda3", "lambda_n", "h", "sigma", "dv",
    "hdot", "energy", "drift",
];

fn csv_err(what: &'static str) -> impl Fn(csv::Error) -> SimError {
    move |e| SimError::Serialize {
        what,
        msg: e.to_string(),
    }
}

fn f(v: f64) -> String {
    format!("{v:?}")
}

fn info_fields(s: &SampleInfo) -> Vec<String> {
    let mut r: Vec<String> = s.tau.iter().chain(&s.lambda).map(|&v| f(v)).collect();
    r.extend(
        [
            s.lambda_n,
            s.h,
            s.sigma,
            s.slip_speed,
            s.normal_velocity,
            s.energy,
        ]
        .map(f),
    );
    r
}

#[derive(Serialize)]
struct TrajectoryJson<'a> {
    t: &'a [f64],
    mode: &'a [Mode],
    kind: &'a [SampleKind],
    x: &'a [Vec<f64>],
    drift: &'a [Option<f64>],
    derived: &'a [SampleInfo],
}

#[derive(Serialize)]
struct EventsJson<'a> {
    events: &'a [EventInfo],
}

impl RunReport {
    /// Writes `trajectory.csv` / `trajectory.json` (t, mode, kind, q, q̇, ω, τ, λ, λ_n, h, σ,
    /// ‖Δv‖ (`dv`), n·v_c (`hdot`), E, drift per sample), `events.csv` / `events.json`
    /// (time, kind, guard, modes, pre/post state and derived quantities) and `summary.json`
    /// into `dir` (created if missing), each atomically. `error` (a failed run) is added to
    /// the summary.
    pub fn write_dir(
        &self,
        dir: &Path,
        out: &SimOutput<Mode>,
        error: Option<&str>,
    ) -> Result<(), SimError> {
        std::fs::create_dir_all(dir).map_err(|source| SimError::Io {
            path: dir.to_path_buf(),
            source,
        })?;
        let tr = &out.trajectory;
        // Trajectory CSV.
        let mut w = csv::Writer::from_writer(Vec::new());
        w.write_record(TRAJ_HEADER)
            .map_err(csv_err("trajectory CSV"))?;
        for i in 0..tr.len() {
            let mut rec = vec![
                f(tr.t[i]),
                format!("{:?}", tr.mode[i]),
                format!("{:?}", tr.kind[i]),
            ];
            rec.extend(tr.x[i].iter().map(|&v| f(v)));
            rec.extend(info_fields(&self.samples[i]));
            rec.push(tr.drift[i].map(f).unwrap_or_default());
            w.write_record(&rec).map_err(csv_err("trajectory CSV"))?;
        }
        let bytes = w.into_inner().map_err(|e| SimError::Serialize {
            what: "trajectory CSV",
            msg: e.to_string(),
        })?;
        write_atomic(&dir.join("trajectory.csv"), &bytes)?;
        let tj = TrajectoryJson {
            t: &tr.t,
            mode: &tr.mode,
            kind: &tr.kind,
            x: &tr.x,
            drift: &tr.drift,
            derived: &self.samples,
        };
        write_atomic(&dir.join("trajectory.json"), &json("trajectory JSON", &tj)?)?;
        // Events.
        let mut w = csv::Writer::from_writer(Vec::new());
        let mut header: Vec<String> =
            ["t", "kind", "guard", "mode_before", "mode_after", "chained"]
                .map(String::from)
                .to_vec();
        for side in ["pre", "post"] {
            for c in &TRAJ_HEADER[3..24] {
                header.push(format!("{side}_{c}"));
            }
        }
        w.write_record(&header).map_err(csv_err("event CSV"))?;
        for e in &self.events {
            let mut rec = vec![
                f(e.t),
                e.kind.to_string(),
                e.guard.to_string(),
                format!("{:?}", e.mode_before),
                e.mode_after
                    .map_or_else(|| "Terminate".to_string(), |m| format!("{m:?}")),
                e.chained.to_string(),
            ];
            rec.extend(e.x_pre.iter().map(|&v| f(v)));
            rec.extend(info_fields(&e.pre));
            rec.extend(e.x_post.iter().map(|&v| f(v)));
            rec.extend(info_fields(&e.post));
            w.write_record(&rec).map_err(csv_err("event CSV"))?;
        }
        let bytes = w.into_inner().map_err(|e| SimError::Serialize {
            what: "event CSV",
            msg: e.to_string(),
        })?;
        write_atomic(&dir.join("events.csv"), &bytes)?;
        write_atomic(
            &dir.join("events.json"),
            &json(
                "events JSON",
                &EventsJson {
                    events: &self.events,
                },
            )?,
        )?;
        #[derive(Serialize)]
        struct SummaryJson<'a> {
            #[serde(flatten)]
            summary: &'a RunSummary,
            error: Option<&'a str>,
        }
        write_atomic(
            &dir.join("summary.json"),
            &json(
                "summary JSON",
                &SummaryJson {
                    summary: &self.summary,
                    error,
                },
            )?,
        )
    }
}

fn json<T: Serialize>(what: &'static str, v: &T) -> Result<Vec<u8>, SimError> {
    serde_json::to_vec_pretty(v).map_err(|e| SimError::Serialize {
        what,
        msg: e.to_string(),
    })
}

/// Guards of the contact modes besides their transitions: the kinks of sat(α) (eq. 3).
const KINK_GUARDS: [Guard; 2] = [Guard::either("alpha_tip"), Guard::either("alpha_base")];

impl<K: Kernels, I: Input> BallFinger<K, I> {
    /// Values of the kink guards at contact geometry `c`: α (m; 0 where p_c reaches the
    /// fingertip p_e) and α + ℓ (m; 0 where p_c reaches the link's base, joint 3).
    fn kink_values(&self, c: &bf_model::ContactGeometry, t: f64, out: &mut [f64]) {
        let hold = self.hold.get();
        if hold.kinks && t < hold.until {
            out.fill(HELD_GUARD);
        } else {
            out[0] = c.alpha;
            out[1] = c.alpha + self.link_length;
        }
    }

    /// Whether the contact-mode transition guards are held by the Zeno fallback at `t`.
    fn contact_held(&self, t: f64) -> bool {
        let hold = self.hold.get();
        hold.contact && t < hold.until
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
            .map_err(Self::model_err(mode, t))?;
        dx.copy_from_slice(&acc.state_derivative(&s.qd));
        Ok(())
    }

    fn guards(&self, mode: Mode) -> Vec<Guard> {
        let mut g = match mode {
            Mode::Free => return vec![Guard::falling("h")],
            Mode::Stick => vec![Guard::falling("lambda_n"), Guard::falling("sigma")],
            Mode::Slip => vec![
                Guard::falling("lambda_n"),
                Guard::falling("slip_speed"),
                Guard::falling("slip_reversal"),
            ],
        };
        g.extend(KINK_GUARDS);
        g
    }

    fn guard_values(&self, mode: Mode, t: f64, x: &[f64], out: &mut [f64]) -> Result<(), SimError> {
        let s = state_of(x)?;
        let err = Self::model_err(mode, t);
        match mode {
            Mode::Free => {
                // Only the contact kernel is needed for h (no mass matrix).
                s.check_finite().map_err(SimError::system)?;
                let c = self.model.kernels().contact(
                    &s.q.into(),
                    &s.qd.into(),
                    &s.omega.into(),
                    self.model.contact_variant(),
                );
                out[0] = c.h;
            }
            Mode::Stick => {
                let tau = self.tau(t, &s)?;
                let kin = self.model.evaluate(&s).map_err(&err)?;
                let acc = bf_model::dynamics::stick(
                    &kin,
                    self.model.params(),
                    &tau,
                    self.model.settings(),
                )
                .map_err(&err)?;
                if self.contact_held(t) {
                    out[..2].fill(HELD_GUARD);
                } else {
                    out[0] = acc.force.lambda_n;
                    out[1] = acc.force.sigma;
                }
                self.kink_values(&kin.contact, t, &mut out[2..]);
            }
            Mode::Slip => {
                let tau = self.tau(t, &s)?;
                let kin = self.model.evaluate(&s).map_err(&err)?;
                let acc = bf_model::dynamics::slip(
                    &kin,
                    self.model.params(),
                    &tau,
                    self.model.settings(),
                    None,
                )
                .map_err(&err)?;
                let dv = kin.contact.delta_v;
                if self.contact_held(t) {
                    out[..3].fill(HELD_GUARD);
                } else {
                    out[0] = acc.force.lambda_n;
                    out[1] = dv.norm() - self.model.settings().slip_eps;
                    let d = Vec3::from(self.slip_ref.get());
                    out[2] = if d == Vec3::zeros() {
                        dv.norm()
                    } else {
                        dv.dot(&d) - REVERSAL_COS * dv.norm()
                    };
                }
                self.kink_values(&kin.contact, t, &mut out[3..]);
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
        let name = self.guards(mode).get(guard).map_or("", |g| g.name);
        if KINK_GUARDS.iter().any(|g| g.name == name) {
            // The contact point passed a kink of sat(α): h, n, J_c and the velocities are
            // continuous there, so the contact persists in the same mode; the new geometry's
            // λ_n and σ are checked at once by the mode's guards (chained transition).
            return Ok(Transition::To(mode));
        }
        let next = match (mode, guard) {
            (Mode::Free, _) => {
                let kin = self.model.evaluate(&s).map_err(SimError::system)?;
                if kin.contact.normal_velocity() > self.model.settings().hdot_eps {
                    // h crossed zero on the interpolant while the finger separates (n·v_c > 0):
                    // a grazing touch seen through interpolation error, not an impact. Put q
                    // back on the surface and continue in Free; the guard then sees h rise.
                    let mut s = s;
                    self.project_position(&mut s)?;
                    x[0..3].copy_from_slice(s.q.as_slice());
                    return Ok(Transition::To(Mode::Free));
                }
                let mut s = s;
                let tol =
                    self.model.settings().contact_tolerance * self.model.params().ball_radius();
                if kin.contact.h.abs() > tol {
                    // The located event state lies beyond the contact band (an interpolant far
                    // from the solution, e.g. a fixed step far too long): apply the impact law
                    // on the surface h = 0 instead of refusing it.
                    self.project_position(&mut s)?;
                    x[0..3].copy_from_slice(s.q.as_slice());
                }
                let out = self
                    .model
                    .impact(&s, self.options.impact_law)
                    .map_err(SimError::system)?;
                write_velocities(x, &out.qd, &out.omega);
                self.set_slip_ref(&out.delta_v);
                out.mode
            }
            (Mode::Stick | Mode::Slip, 0) => {
                // Leave the contact from the surface (the contact mode let h drift), so the
                // Free mode's h guard starts on its surface and sees the departure.
                let mut s = s;
                if self.options.project {
                    self.project_position(&mut s)?;
                    x[0..3].copy_from_slice(s.q.as_slice());
                }
                let sep = self.options.lift_off_speed;
                if sep > 0.0 {
                    let kin = self.model.evaluate(&s).map_err(SimError::system)?;
                    let vn = kin.contact.normal_velocity();
                    if vn < sep {
                        let mats = contact_matrices(&kin, self.model.params())
                            .map_err(SimError::system)?;
                        if mats.n_w_n > 0.0 {
                            let qd =
                                s.qd + mats.minv_jct * kin.contact.n * ((sep - vn) / mats.n_w_n);
                            x[3..6].copy_from_slice(qd.as_slice());
                        }
                    }
                }
                Mode::Free
            }
            (Mode::Stick, _) => {
                let tau = self.tau(t, &s)?;
                let acc = self.model.stick(&s, &tau).map_err(SimError::system)?;
                let out = self
                    .model
                    .stick_to_slip_update(&s, &acc.force)
                    .map_err(SimError::system)?;
                write_velocities(x, &out.qd, &out.omega);
                self.set_slip_ref(&out.delta_v);
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

    fn project(&self, mode: Mode, t: f64, x: &mut [f64]) -> Result<Option<f64>, SimError> {
        let err = Self::model_err(mode, t);
        if mode == Mode::Slip {
            // The slip_reversal guard of the next step compares Δv with its direction now.
            let s = state_of(x)?;
            let kin = self.model.evaluate(&s).map_err(&err)?;
            self.set_slip_ref(&kin.contact.delta_v);
        }
        if mode == Mode::Free || !self.options.project {
            return Ok(None);
        }
        let mut s = state_of(x)?;
        let drift = self.project_position(&mut s)?;
        match mode {
            Mode::Stick => {
                let out = self.model.slip_to_stick_update(&s).map_err(&err)?;
                s.qd = out.qd;
                s.omega = out.omega;
            }
            Mode::Slip => {
                let kin = self.model.evaluate(&s).map_err(&err)?;
                let mats = contact_matrices(&kin, self.model.params()).map_err(&err)?;
                let n = kin.contact.n;
                let vn = n.dot(&kin.contact.v_c);
                if mats.n_w_n > 0.0 {
                    s.qd -= mats.minv_jct * n * (vn / mats.n_w_n);
                }
            }
            Mode::Free => {}
        }
        x.copy_from_slice(&s.to_array());
        if mode == Mode::Slip {
            let kin = self.model.evaluate(&s).map_err(&err)?;
            self.set_slip_ref(&kin.contact.delta_v);
        }
        Ok(drift)
    }

    fn zeno_fallback(
        &self,
        mode: Mode,
        t: f64,
        x: &mut [f64],
        recent: &[(&'static str, Mode)],
    ) -> Result<Option<(Mode, String)>, SimError> {
        let is_kink = |g: &str| KINK_GUARDS.iter().any(|k| k.name == g);
        let kinks = recent.iter().any(|(g, _)| is_kink(g));
        let hold = self.options.zeno_hold_time;
        let mut names: Vec<(&str, usize)> = Vec::new();
        for (g, _) in recent {
            match names.iter_mut().find(|(n, _)| n == g) {
                Some((_, c)) => *c += 1,
                None => names.push((g, 1)),
            }
        }
        let names: Vec<String> = names.iter().map(|(n, c)| format!("{n} {c}")).collect();
        let names = names.join(", ");
        if mode != Mode::Free && recent.iter().all(|(g, _)| is_kink(g)) {
            self.hold.set(Hold {
                until: t + hold,
                kinks: true,
                contact: false,
            });
            return Ok(Some((
                mode,
                format!(
                    "the contact point chatters across a kink of sat(alpha) (eq. 3; {names}): \
                     kink events suspended for {hold} s, steps across the kink are shortened \
                     by the error control"
                ),
            )));
        }
        // Chatter between contact and free motion or between stick and slip: hold a sticking
        // contact (Δv = 0 by the dissipative sticking projection, eq. 40–41).
        let mut s = state_of(x)?;
        let tol = self.model.settings().contact_tolerance * self.model.params().ball_radius();
        if self.gap(x)?.abs() > tol {
            return Ok(None);
        }
        self.project_position(&mut s)?;
        let out = self
            .model
            .slip_to_stick_update(&s)
            .map_err(SimError::system)?;
        s.qd = out.qd;
        s.omega = out.omega;
        x.copy_from_slice(&s.to_array());
        self.hold.set(Hold {
            until: t + hold,
            kinks,
            contact: true,
        });
        Ok(Some((
            Mode::Stick,
            format!(
                "mode chatter ({names}): sticking contact held for {hold} s regardless of \
                 lambda_n and sigma (eq. 48, 19)"
            ),
        )))
    }

    fn check_valid(&self, mode: Mode, t: f64, x: &[f64]) -> Result<(), SimError> {
        if mode == Mode::Free {
            return Ok(());
        }
        let h = self.gap(x)?;
        let tol = self.model.settings().contact_tolerance * self.model.params().ball_radius();
        if h.abs() > tol {
            // Outside the contact modes' domain: a trial step ending here is retried shorter.
            return Err(SimError::OutsideDomain {
                t,
                mode: format!("{mode:?}"),
                msg: format!("contact drift |h| = {:e} m exceeds {tol:e} m", h.abs()),
            });
        }
        Ok(())
    }
}
