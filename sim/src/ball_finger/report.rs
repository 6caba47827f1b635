//! Derived quantities and run summary of the ball-and-finger system.
//!
//! Output ([`BallFinger::sample_info`], [`BallFinger::report`]): at every stored sample the
//! derived quantities τ, λ (eq. 33 / 37), λ_n (eq. 12), h (eq. 4), σ (eq. 18), ‖Δv‖ (eq. 13),
//! n·v_c (eq. 36) and E = T + U (eq. 22) are recomputed from the model, so the files can be
//! checked against the transition conditions of Sect. 3.1 without re-running the model; events
//! are named by their Fig. 3 transition ([`event_kind`]). τ is the input's at the sample; the
//! state just before an event takes the τ that drove the step ending there, which differs from
//! the input's value after its observations at that time when the input has a memory (a
//! controller's phase and integrators), so that the forces, the power and the energy balance
//! of that last step are those of the motion integrated.
//!
//! # Energy warnings
//! The run summary reports each impact that raises the energy (only Newton's law, eq. 39, can:
//! see bf-model's impact module) and the energy-balance error E(t) − E(t₀) − ∫ P dt of the
//! integration (P of the power balance, eq. 22/25; ∫ P dt by Simpson's rule over each step,
//! with the midpoint state from the step's cubic Hermite interpolant, so that the residual is
//! the integration's and not the quadrature's), as it accumulates over any
//! `BallFingerSettings::energy_window` of simulated time; above its tolerance,
//! `BallFingerSettings::energy_error_rel` times the energy the run moves (the largest kinetic
//! energy T plus the largest ∫ |P| dt over a window), it is a warning (e.g. fixed-step RK4
//! with a step too long for the dynamics). The tolerance is relative so that the check means
//! the same for a scene of any size: the same motion with every mass ×10⁵ has errors ×10⁵.
//!
//! [`SampleInfo`], [`EventInfo`] and [`RunReport`] carry the number of joints N (default 3)
//! for the torque vector τ ∈ ℝᴺ; [`RunSummary`] does not depend on N.

use super::{BallFinger, BallFingerSettings, state_of};
use crate::integrator::{StepEnd, simpson_over_step};
use crate::trajectory::{SampleKind, SimOutput};
use crate::{Input, SimError, SimWarning};
use bf_model::{ImpactLaw, Kernels, Mode, State};
use serde::Serialize;

/// Which of an input's two values at the time of an observation a sample takes
/// ([`Input::tau_before`]): the state just before an event ends the step that led to it, so it
/// takes the τ that drove that step; every other sample (and a chained event's state before,
/// which no step led to) takes the τ after the observations, which drives the next step. A
/// step's end is also a step's start; it takes the latter's τ, whose difference from the
/// former is the input's change over one observation, not an event's.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum Limit {
    /// [`Input::tau_before`].
    Before,
    /// [`Input::tau_in_mode`].
    After,
}

impl Limit {
    /// The side a sample of this kind takes.
    fn of(kind: SampleKind) -> Self {
        if kind == SampleKind::EventPre {
            Limit::Before
        } else {
            Limit::After
        }
    }
}

/// The model evaluated at one state in one mode, for the samples and the steps' midpoints.
struct Evaluated<const N: usize> {
    /// The state.
    state: State<N>,
    /// τ from the input.
    tau: bf_model::VecN<N>,
    /// The contact kinematics.
    kin: bf_model::ContactKinematics<N>,
    /// The mode's accelerations and contact forces.
    acc: bf_model::Accelerations<N>,
    /// P of the power balance (W).
    power: f64,
}

/// Kind of the warning of a failed energy-balance check ([`RunSummary::energy_check_failure`]).
const ENERGY_ERROR: &str = "energy_error";
/// Kind of the warning of a contact held while the ball pulled the finger ([`HeldContact`]).
const HELD_CONTACT: &str = "held_contact";
/// Kind of the warning of a stick held outside the friction cone ([`HeldContact`]).
const HELD_OUTSIDE_CONE: &str = "held_outside_cone";
/// Kind of the warning of an impact whose impulse pulls the finger onto the ball (ι·n < 0).
const PULLING_IMPULSE: &str = "pulling_impulse";
/// Kind of the warning of a sticking impact whose impulse lies outside the static friction cone
/// (eq. 66).
const IMPULSE_OUTSIDE_CONE: &str = "impulse_outside_cone";
/// How far (relative to the impulse) an impulse may be outside its bounds before it is warned
/// of: rounding only.
const IMPULSE_REL_TOL: f64 = 1e-9;

impl<K: Kernels<N>, I: Input, const N: usize> BallFinger<K, I, N> {
    /// Derived quantities at one sample (t, x) in `mode`: τ from the input, λ from the mode's
    /// dynamics (0 in Free, eq. 45), h, σ, ‖Δv‖, n·v_c, the energy and its rate.
    pub fn sample_info(&self, mode: Mode, t: f64, x: &[f64]) -> Result<SampleInfo<N>, SimError> {
        self.sample_eval(Limit::After, mode, t, x)
            .map(|(info, _)| info)
    }

    /// The model at (t, x) in `mode` ([`Evaluated`]).
    fn dynamics_at(
        &self,
        limit: Limit,
        mode: Mode,
        t: f64,
        x: &[f64],
    ) -> Result<Evaluated<N>, SimError> {
        let s = state_of::<N>(x)?;
        let tau = self.input_tau(limit, mode, t, &s)?;
        let kin = self.model.evaluate(&s).map_err(SimError::system)?;
        let acc = self
            .model
            .accelerations(mode, &s, &tau)
            .map_err(SimError::system)?;
        let power = bf_model::energy::power_balance(&kin, self.model.params(), &tau, &acc.force);
        Ok(Evaluated {
            state: s,
            tau,
            kin,
            acc,
            power: power.total,
        })
    }

    /// [`BallFinger::sample_info`] and the state derivative ẋ at the sample, from one
    /// evaluation of the model.
    fn sample_eval(
        &self,
        limit: Limit,
        mode: Mode,
        t: f64,
        x: &[f64],
    ) -> Result<(SampleInfo<N>, Vec<f64>), SimError> {
        let Evaluated {
            state: s,
            tau,
            kin,
            acc,
            power,
        } = self.dynamics_at(limit, mode, t, x)?;
        let e = self.model.energy(&s).map_err(SimError::system)?;
        let mut dx = vec![0.0; x.len()];
        acc.write_state_derivative(&s.qd, &mut dx);
        let info = SampleInfo {
            lambda: acc.force.lambda.into(),
            lambda_n: acc.force.lambda_n,
            sigma: acc.force.sigma,
            power,
            ..SampleInfo::of_state(tau.into(), &kin.contact, &e)
        };
        Ok((info, dx))
    }

    /// The impulse of the impact whose state before the reset is `x_pre` and after it `x_post`
    /// ([`ImpulseInfo`]); `None` if the model cannot be evaluated there.
    fn impulse_at(&self, x_pre: &[f64], x_post: &[f64]) -> Option<ImpulseInfo> {
        // The impact law ran on the event's position as the reset left it (projected onto the
        // surface if it was off it) with the velocities before the reset.
        let mut x = x_pre.to_vec();
        x.get_mut(..N)?.copy_from_slice(x_post.get(..N)?);
        let s = state_of::<N>(&x).ok()?;
        let out = self.model.impact(&s, self.settings.impact_law).ok()?;
        let mu_s = self.model.params().mu_s();
        let tangential = out.impulse_t.norm();
        Some(ImpulseInfo {
            impulse: out.impulse.into(),
            normal: out.impulse_n,
            tangential,
            static_cone_margin: mu_s * out.impulse_n - tangential,
        })
    }

    /// [`BallFinger::sample_info`] that never fails: a sample where the mode's dynamics cannot
    /// be evaluated (e.g. the state a failed run stopped at: a Painlevé configuration, a
    /// singular contact matrix) keeps what the state alone gives (τ, h, ‖Δv‖, n·v_c and the
    /// energies) and gets NaN for the forces and the power; a state the kinematics cannot
    /// evaluate either gets NaN everywhere (`null` in JSON).
    pub fn sample_info_or_nan(&self, mode: Mode, t: f64, x: &[f64]) -> SampleInfo<N> {
        self.info_or_nan(Limit::After, mode, t, x)
    }

    /// [`BallFinger::sample_info_or_nan`] on the given side of the input's observations.
    fn info_or_nan(&self, limit: Limit, mode: Mode, t: f64, x: &[f64]) -> SampleInfo<N> {
        self.sample_eval(limit, mode, t, x)
            .map_or_else(|_| self.kinematic_info(limit, mode, t, x), |(info, _)| info)
    }

    /// The part of [`SampleInfo`] that needs no accelerations (module doc of
    /// [`BallFinger::sample_info_or_nan`]).
    fn kinematic_info(&self, limit: Limit, mode: Mode, t: f64, x: &[f64]) -> SampleInfo<N> {
        let Ok(s) = state_of::<N>(x) else {
            return SampleInfo::NAN;
        };
        let (Ok(kin), Ok(e)) = (self.model.evaluate(&s), self.model.energy(&s)) else {
            return SampleInfo::NAN;
        };
        let tau = self
            .input_tau(limit, mode, t, &s)
            .map_or([f64::NAN; N], Into::into);
        SampleInfo::of_state(tau, &kin.contact, &e)
    }

    /// ∫ P dt over the interval of the trajectory `tr` that ends at sample `i` (0 for the first
    /// sample and for an event's jump, the interval that ends at an `EventPost` sample), by
    /// Simpson's rule on the step's Hermite interpolant in the interval's mode
    /// ([`crate::integrator::simpson_over_step`]), so that the balance measures the integration
    /// rather than the quadrature, whose trapezoidal error of order h³ P'' per step dominates
    /// runs of high power (decision record 0078). `slopes` are ẋ at the samples. An interval
    /// whose midpoint cannot be evaluated falls back to the trapezoid.
    fn interval_work(
        &self,
        tr: &crate::Trajectory<Mode>,
        i: usize,
        samples: &[SampleInfo<N>],
        slopes: &[Option<Vec<f64>>],
    ) -> f64 {
        if i == 0 || tr.kind[i] == SampleKind::EventPost {
            return 0.0;
        }
        // The interval (t[i-1], t[i]] was integrated in the mode of its end sample; its start
        // has that mode too, unless it is the state before an event.
        let mode = tr.mode[i];
        let end = |k: usize| {
            Some(StepEnd {
                t: tr.t[k],
                x: &tr.x[k],
                f: slopes[k].as_deref()?,
                g: samples[k].power,
            })
        };
        let simpson = match (end(i - 1), end(i)) {
            (Some(a), Some(b)) if tr.mode[i - 1] == mode => simpson_over_step(a, b, |t, x| {
                self.dynamics_at(Limit::After, mode, t, x)
                    .ok()
                    .map(|e| e.power)
            }),
            _ => None,
        };
        simpson.unwrap_or_else(|| {
            0.5 * (samples[i - 1].power + samples[i].power) * (tr.t[i] - tr.t[i - 1])
        })
    }

    /// Derived quantities at every sample and event of a run, plus its summary. `cpu_seconds`
    /// is the wall time the run took (for the real-time factor).
    pub fn report(&self, out: &SimOutput<Mode>, t0: f64, cpu_seconds: f64) -> RunReport<N> {
        let tr = &out.trajectory;
        let (samples, slopes): (Vec<SampleInfo<N>>, Vec<Option<Vec<f64>>>) = (0..tr.len())
            .map(|i| {
                let limit = Limit::of(tr.kind[i]);
                match self.sample_eval(limit, tr.mode[i], tr.t[i], &tr.x[i]) {
                    Ok((info, dx)) => (info, Some(dx)),
                    Err(_) => (
                        self.kinematic_info(limit, tr.mode[i], tr.t[i], &tr.x[i]),
                        None,
                    ),
                }
            })
            .unzip();
        let events: Vec<EventInfo<N>> = out
            .events
            .iter()
            .map(|e| EventInfo {
                t: e.t,
                kind: event_kind(e.mode_before, e.mode_after, e.guard),
                guard: e.guard,
                mode_before: e.mode_before,
                mode_after: e.mode_after,
                chained: e.chained,
                zeno_fallback: e.zeno_fallback,
                x_pre: e.x_pre.clone(),
                x_post: e.x_post.clone(),
                // A chained event fires from the state the previous reset left, with no step
                // between them: its guard saw the input after that event's observation.
                pre: self.info_or_nan(
                    if e.chained {
                        Limit::After
                    } else {
                        Limit::Before
                    },
                    e.mode_before,
                    e.t,
                    &e.x_pre,
                ),
                post: self.sample_info_or_nan(
                    e.mode_after.unwrap_or(e.mode_before),
                    e.t,
                    &e.x_post,
                ),
                impulse: (e.mode_before == Mode::Free
                    && e.mode_after.is_some_and(|m| m != Mode::Free))
                .then(|| self.impulse_at(&e.x_pre, &e.x_post))
                .flatten(),
            })
            .collect();
        let work: Vec<f64> = (0..tr.len())
            .map(|i| self.interval_work(tr, i, &samples, &slopes))
            .collect();
        // The holds of this run: each began at one of its Zeno fallbacks.
        let holds: Vec<(f64, f64)> = self
            .contact_holds
            .borrow()
            .iter()
            .filter(|&&(a, _)| {
                out.warnings
                    .iter()
                    .any(|w| w.kind == "zeno_fallback" && w.t == a)
            })
            .copied()
            .collect();
        let summary = summarize(
            out,
            &samples,
            &events,
            &work,
            &holds,
            t0,
            cpu_seconds,
            &self.settings,
        );
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

/// Quantities derived from the model at one stored sample (SI units) of a finger with `N`
/// joints (default 3).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct SampleInfo<const N: usize = 3> {
    /// Joint torques τ (N m).
    #[serde(serialize_with = "serialize_array")]
    pub tau: [f64; N],
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
    /// Kinetic energy T = ½ q̇ᵀ M_f q̇ + ½ ωᵀ I_b ω (J, eq. 22); JSON only.
    pub kinetic: f64,
    /// dE/dt = q̇ᵀτ − μ_v‖q̇‖² − D‖ω‖² − λ·Δv of the power balance (W); JSON only.
    pub power: f64,
}

/// Serialises a fixed-size array as a sequence (serde's own array impls stop at 32 and are
/// not generic over the length).
fn serialize_array<S: serde::Serializer, const N: usize>(
    a: &[f64; N],
    s: S,
) -> Result<S::Ok, S::Error> {
    s.collect_seq(a)
}

impl<const N: usize> SampleInfo<N> {
    /// All fields NaN (sample that could not be evaluated).
    pub const NAN: SampleInfo<N> = SampleInfo {
        tau: [f64::NAN; N],
        lambda: [f64::NAN; 3],
        lambda_n: f64::NAN,
        sigma: f64::NAN,
        h: f64::NAN,
        slip_speed: f64::NAN,
        normal_velocity: f64::NAN,
        energy: f64::NAN,
        kinetic: f64::NAN,
        power: f64::NAN,
    };

    /// What the state gives without accelerations: τ, h, ‖Δv‖, n·v_c and the energies, with
    /// the forces and the power NaN.
    fn of_state(
        tau: [f64; N],
        c: &bf_model::ContactGeometry<N>,
        e: &bf_model::energy::Energy,
    ) -> Self {
        SampleInfo {
            tau,
            h: c.h,
            slip_speed: c.delta_v.norm(),
            normal_velocity: c.normal_velocity(),
            energy: e.total,
            kinetic: e.kinetic_finger + e.kinetic_ball,
            ..SampleInfo::NAN
        }
    }
}

/// One event of the log with the derived quantities before and after the reset.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct EventInfo<const N: usize = 3> {
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
    /// Whether the Zeno fallback replaced the guard's transition: `mode_after` is the mode it
    /// held (`kind` still names the transition the guard asked for).
    pub zeno_fallback: bool,
    /// State (q, q̇, ω) before the reset.
    pub x_pre: Vec<f64>,
    /// State after the reset.
    pub x_post: Vec<f64>,
    /// Derived quantities before the reset (in `mode_before`).
    pub pre: SampleInfo<N>,
    /// Derived quantities after the reset (in `mode_after`).
    pub post: SampleInfo<N>,
    /// At an impact, the impulse the law gave the finger ([`ImpulseInfo`]); `None` (JSON
    /// `null`) at other events.
    pub impulse: Option<ImpulseInfo>,
}

/// The impulse of an impact (eq. 39–43), recomputed by the run's impact law from the state it
/// was applied to: the event's position (after the projection onto h = 0, if any) with its
/// pre-impact velocities, so it is the impulse the run applied, bit for bit.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct ImpulseInfo {
    /// ι on the finger (N s, world axes).
    pub impulse: [f64; 3],
    /// ι·n (N s): positive when the ball pushes the finger away, as a contact can.
    pub normal: f64,
    /// ‖ι_∥‖ (N s).
    pub tangential: f64,
    /// μ_s ι·n − ‖ι_∥‖ (N s, eq. 66): non-negative when static friction can hold the impulse
    /// without slipping.
    pub static_cone_margin: f64,
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
    /// Whether the contact steps were projected onto h = 0 and n·v_c = 0
    /// (`BallFingerSettings::project`); without it the drift is only what `max_contact_gap`
    /// and `max_normal_velocity` show, and `max_drift`, `final_drift` are 0.
    pub projected: bool,
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
    /// Largest energy gain E⁺ − E⁻ over the impacts (J); > 0 only for Newton's law (eq. 39),
    /// which does not guarantee dissipation. 0 when no impact raised the energy (a run whose
    /// impacts all dissipate, or without impacts).
    pub max_impact_energy_gain: f64,
    /// The energy-balance error of the integration that the run is checked on (J): the largest
    /// change of the residual E(t) − E(t₀) − ∫ P dt − Σ ΔE_events over any
    /// `BallFingerSettings::energy_window` of simulated time (P from the power balance,
    /// ∫ P dt by Simpson's rule over each step, `BallFinger::interval_work`; jumps at events
    /// excluded). For a run no longer than the window it is the largest |residual| from t₀,
    /// [`energy_drift`](Self::energy_drift).
    pub energy_error: f64,
    /// The largest |E(t) − E(t₀) − ∫ P dt − Σ ΔE_events| over the whole run (J): the
    /// residual from t₀, which can grow with the run's length.
    pub energy_drift: f64,
    /// What [`energy_error`](Self::energy_error) is checked against (J):
    /// `BallFingerSettings::energy_error_rel` times the energy the run moves (its largest
    /// kinetic energy plus the largest ∫ |P| dt over a window), plus the rounding of E.
    pub energy_tolerance: f64,
    /// Conditions that qualify the result: `energy_raising_impact` (one per impact raising E by
    /// more than `BallFingerSettings::impact_energy_tol`), `energy_error` (energy-balance error
    /// above [`energy_tolerance`](Self::energy_tolerance)), `pulling_impulse` (an impact
    /// whose impulse pulls the finger onto the ball, ι·n < 0), `impulse_outside_cone` (a
    /// sticking impact whose impulse static friction cannot hold, eq. 66), `held_contact`
    /// (contact kept with λ_n < 0: only the Zeno fallback does), `held_outside_cone` (stick
    /// kept with σ < 0, likewise), `zeno_fallback` (see the module docs).
    pub warnings: Vec<SimWarning>,
    /// The sticking contacts the Zeno fallback held regardless of λ_n and σ, as [start, end]
    /// (s, the end at most `t_final`): the intervals where `held_contact` and
    /// `held_outside_cone` judge both ends of a step.
    pub contact_holds: Vec<[f64; 2]>,
    /// Accepted steps, rejected steps, vector-field evaluations.
    pub stats: crate::SimStats,
    /// Wall-clock time of the run (s).
    pub cpu_seconds: f64,
    /// Simulated time / wall-clock time.
    pub real_time_factor: f64,
    /// Which model kernels ran (`"compiled"` or `"interpreted"`), when the caller says so
    /// (the CLI does); omitted from `summary.json` otherwise.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub kernels: Option<String>,
}

fn summarize<const N: usize>(
    out: &SimOutput<Mode>,
    samples: &[SampleInfo<N>],
    events: &[EventInfo<N>],
    work: &[f64],
    holds: &[(f64, f64)],
    t0: f64,
    cpu_seconds: f64,
    settings: &BallFingerSettings,
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
        if gain > settings.impact_energy_tol {
            warnings.push(SimWarning {
                t: e.t,
                kind: "energy_raising_impact",
                message: format!(
                    "{} impact raised the energy by {gain:+.3e} J",
                    settings.impact_law.name()
                ),
            });
        }
    }
    for e in events {
        let Some(imp) = e.impulse else { continue };
        // Relative to the impulse, so that rounding of a tangential impulse does not count.
        let tol = IMPULSE_REL_TOL * imp.tangential.max(imp.normal.abs());
        let law = settings.impact_law.name();
        if imp.normal < -tol {
            warnings.push(SimWarning {
                t: e.t,
                kind: PULLING_IMPULSE,
                message: format!(
                    "the {law} impact pulls the finger onto the ball (ι·n = {:.3e} N s < 0), \
                     which no contact can: the law's impulse is not physical here",
                    imp.normal
                ),
            });
        } else if settings.impact_law == ImpactLaw::Stick && imp.static_cone_margin < -tol {
            warnings.push(SimWarning {
                t: e.t,
                kind: IMPULSE_OUTSIDE_CONE,
                message: format!(
                    "the sticking impulse needs ‖ι_∥‖ = {:.3e} N s of friction, more than \
                     μ_s ι·n = {:.3e} N s (eq. 66): a real finger would slip at this impact \
                     (max-dissipation keeps the impulse in the cone)",
                    imp.tangential,
                    imp.tangential + imp.static_cone_margin
                ),
            });
        }
    }
    let residual = balance_residual(tr, samples, work);
    let energy_drift = residual.iter().fold(0.0f64, |m, r| m.max(r.abs()));
    let (energy_error, t_error) =
        window_error(&tr.t[..residual.len()], &residual, settings.energy_window);
    let energy_tolerance = energy_tolerance(tr, samples, work, settings);
    warnings.extend(out.warnings.iter().cloned());
    // A NaN error is not within.
    if energy_error > energy_tolerance || energy_error.is_nan() {
        let span = if t_error - t0 > settings.energy_window {
            format!(
                "over the {} s up to t = {t_error} s",
                settings.energy_window
            )
        } else {
            format!("from t = {t0} s")
        };
        warnings.push(SimWarning {
            t: t_error,
            kind: ENERGY_ERROR,
            message: format!(
                "energy-balance error {energy_error:.3e} J {span} exceeds {energy_tolerance:.3e} \
                 J ({:e} of the energy the run moves): the integration is too coarse for the \
                 dynamics (its step too long, or its tolerance too loose)",
                settings.energy_error_rel
            ),
        });
    }
    warnings.extend(held_contact(tr, samples, holds).warnings());
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
        projected: settings.project,
        max_drift: out.stats.max_drift,
        final_drift,
        max_contact_gap,
        max_normal_velocity,
        energy_initial: samples.first().map_or(f64::NAN, |s| s.energy),
        energy_final: samples.last().map_or(f64::NAN, |s| s.energy),
        max_impact_energy_gain,
        energy_error,
        energy_drift,
        energy_tolerance,
        warnings,
        contact_holds: holds
            .iter()
            .map(|&(a, b)| [a, b.min(out.t_final)])
            .collect(),
        stats: out.stats,
        cpu_seconds,
        real_time_factor: if cpu_seconds > 0.0 {
            elapsed / cpu_seconds
        } else {
            f64::INFINITY
        },
        kernels: None,
    }
}

/// The energy-balance residual E(t) − E(t₀) − ∫ P dt at each sample, `work[i]`
/// being ∫ P dt over the interval that ends at sample i (`BallFinger::interval_work`), with the
/// jumps at events (the interval ending at an `EventPost` sample) left out. A non-finite
/// interval (a failed run's last state) adds nothing.
fn balance_residual<const N: usize>(
    tr: &crate::Trajectory<Mode>,
    samples: &[SampleInfo<N>],
    work: &[f64],
) -> Vec<f64> {
    let n = tr.len().min(samples.len()).min(work.len());
    let mut residual = Vec::with_capacity(n);
    let mut sum = 0.0f64;
    for i in 0..n {
        if i > 0 && tr.kind[i] != SampleKind::EventPost {
            let step = (samples[i].energy - samples[i - 1].energy) - work[i];
            if step.is_finite() {
                sum += step;
            }
        }
        residual.push(sum);
    }
    residual
}

/// Where a run's contact broke the model's own conditions (λ_n ≥ 0 in contact, eq. 48; σ ≥ 0
/// in Stick, eq. 19), as only the Zeno fallback lets it: its guards switch the mode at those
/// bounds otherwise, up to the event location's rounding.
#[derive(Debug, Clone, Copy, PartialEq)]
struct HeldContact {
    /// The smallest λ_n over the samples that begin a step in contact and the ends of the
    /// steps inside a contact hold (N; +∞ without).
    min_lambda_n: f64,
    /// The smallest σ over the samples that begin a step in Stick and the ends of the Stick
    /// steps inside a contact hold (N; +∞ without).
    min_sigma: f64,
    /// The time spent in contact with λ_n < 0 (s), and when it first was.
    pulling: (f64, Option<f64>),
    /// The time spent sticking with σ < 0 but λ_n ≥ 0 (s), and when it first was.
    outside_cone: (f64, Option<f64>),
}

/// How far (relative to the run's largest contact force) λ_n or σ may fall below zero at a
/// contact sample before the contact counts as held against the model: the event location's
/// rounding.
const HELD_FORCE_REL_TOL: f64 = 1e-6;

impl HeldContact {
    /// The warnings of a held contact: `held_contact` where the finger was kept on the ball
    /// while the ball pulled it (λ_n < 0: it would have left; the run's contact there is not
    /// the model's), `held_outside_cone` where it was kept sticking with too little friction
    /// (σ < 0: it would have slipped, by as much as the chatter the fallback stopped).
    fn warnings(&self) -> Vec<SimWarning> {
        let mut out = Vec::new();
        if let (time, Some(t)) = self.pulling {
            out.push(SimWarning {
                t,
                kind: HELD_CONTACT,
                message: format!(
                    "the Zeno fallback kept the finger on the ball for {time:.4} s while the \
                     ball pulled it (λ_n down to {:.3e} N; a contact needs λ_n ≥ 0, eq. 48): \
                     the finger would have left, so the run's contact there is not the \
                     model's physics",
                    self.min_lambda_n
                ),
            });
        }
        if let (time, Some(t)) = self.outside_cone {
            out.push(SimWarning {
                t,
                kind: HELD_OUTSIDE_CONE,
                message: format!(
                    "the Zeno fallback kept the finger sticking for {time:.4} s with too little \
                     friction (σ down to {:.3e} N; sticking needs σ ≥ 0, eq. 19): it would have \
                     slipped there",
                    self.min_sigma
                ),
            });
        }
        out
    }
}

/// The contact of a run kept against the model (module doc of [`HeldContact`]). `holds` are
/// the run's contact holds (start, until) by the Zeno fallback: a step that overlaps one was
/// integrated with the contact guards suspended and has no sample inside, so both its ends
/// count. Outside them a step's end may be the pre-sample of the very event whose guard ended
/// it (the sliver step after an impact whose λ_n < 0 lifts off at once), so only its start
/// counts.
fn held_contact<const N: usize>(
    tr: &crate::Trajectory<Mode>,
    samples: &[SampleInfo<N>],
    holds: &[(f64, f64)],
) -> HeldContact {
    let n = tr.len().min(samples.len());
    let contact = |i: usize| tr.mode[i] != Mode::Free;
    let scale = (0..n)
        .filter(|&i| contact(i))
        .map(|i| samples[i].lambda.iter().map(|v| v * v).sum::<f64>().sqrt())
        .filter(|v| v.is_finite())
        .fold(0.0, f64::max);
    let tol = HELD_FORCE_REL_TOL * scale;
    let mut held = HeldContact {
        min_lambda_n: f64::INFINITY,
        min_sigma: f64::INFINITY,
        pulling: (0.0, None),
        outside_cone: (0.0, None),
    };
    // The samples that begin an interval integrated in contact: a contact sample that an
    // event leaves at once (an impact whose post-impact λ_n < 0 lifts off in the same instant)
    // is the guard doing its work, not a held contact.
    let integrated =
        |i: usize| contact(i) && i + 1 < n && tr.mode[i + 1] == tr.mode[i] && tr.t[i + 1] > tr.t[i];
    let in_hold = |i: usize| holds.iter().any(|&(a, b)| tr.t[i] < b && tr.t[i + 1] > a);
    for i in (0..n).filter(|&i| integrated(i)) {
        let stick = tr.mode[i] == Mode::Stick;
        let (s, end) = (&samples[i], &samples[i + 1]);
        let (mut lambda_n, mut sigma) = (s.lambda_n, if stick { s.sigma } else { f64::INFINITY });
        if in_hold(i) {
            lambda_n = lambda_n.min(end.lambda_n);
            if stick {
                sigma = sigma.min(end.sigma);
            }
        }
        held.min_lambda_n = held.min_lambda_n.min(lambda_n);
        held.min_sigma = held.min_sigma.min(sigma);
        let slot = if lambda_n < -tol {
            &mut held.pulling
        } else if sigma < -tol {
            &mut held.outside_cone
        } else {
            continue;
        };
        let dt = tr.t[i + 1] - tr.t[i];
        slot.0 += dt;
        slot.1.get_or_insert(tr.t[i]);
    }
    held
}

/// The tolerance of the energy-balance error of a run (`RunSummary::energy_tolerance`):
/// `settings.energy_error_rel` times the largest kinetic energy of its samples plus the largest
/// ∫ |P| dt over a window (Σ |∫ P dt| over the steps, the windows of [`window_error`]), plus
/// the rounding of E, relative to its largest |E|, for a run that barely moves. Samples that
/// could not be evaluated (NaN) are left out.
fn energy_tolerance<const N: usize>(
    tr: &crate::Trajectory<Mode>,
    samples: &[SampleInfo<N>],
    work: &[f64],
    settings: &BallFingerSettings,
) -> f64 {
    let finite_max =
        |v: &mut dyn Iterator<Item = f64>| v.filter(|x| x.is_finite()).fold(0.0f64, f64::max);
    let kinetic = finite_max(&mut samples.iter().map(|s| s.kinetic));
    let largest = finite_max(&mut samples.iter().map(|s| s.energy.abs()));
    let n = tr.len().min(work.len());
    let mut flow = Vec::with_capacity(n);
    let mut sum = 0.0f64;
    for w in &work[..n] {
        if w.is_finite() {
            sum += w.abs();
        }
        flow.push(sum);
    }
    let (window_flow, _) = window_error(&tr.t[..n], &flow, settings.energy_window);
    crate::arm::balance_tolerance(settings.energy_error_rel, kinetic, window_flow, largest)
}

/// The largest change of the residual `r` (sampled at the non-decreasing times `t`) over a
/// trailing `window`, and the time where it ends: at sample i, |r(tᵢ) − r(tⱼ)| with j the last
/// sample at or before tᵢ − `window`, or |r(tᵢ)| while there is none (r = 0 before t₀). With a
/// window at least as long as the run it is the largest |r| from t₀.
fn window_error(t: &[f64], r: &[f64], window: f64) -> (f64, f64) {
    let mut worst = (0.0f64, t.first().copied().unwrap_or(0.0));
    let mut base: Option<usize> = None;
    for i in 0..t.len().min(r.len()) {
        // The times are non-decreasing, so the base only moves forward.
        loop {
            let next = base.map_or(0, |j| j + 1);
            if next < i && t[next] <= t[i] - window {
                base = Some(next);
            } else {
                break;
            }
        }
        let e = (r[i] - base.map_or(0.0, |j| r[j])).abs();
        if e > worst.0 {
            worst = (e, t[i]);
        }
    }
    worst
}

impl RunSummary {
    /// The warning of a failed energy-balance check (the balance error above
    /// [`RunSummary::energy_tolerance`]): the one warning that says the run's own accuracy
    /// check failed, rather than something the model did (an impact that raised the energy, a
    /// Zeno fallback).
    pub fn energy_check_failure(&self) -> Option<&SimWarning> {
        self.warnings.iter().find(|w| w.kind == ENERGY_ERROR)
    }

    /// The warning of a contact held while the ball pulled the finger (λ_n < 0 over steps of
    /// the run, which only the Zeno fallback allows): the finger would have left, so the
    /// run's contact there is the regularisation's, not the model's physics.
    pub fn held_contact(&self) -> Option<&SimWarning> {
        self.warnings.iter().find(|w| w.kind == HELD_CONTACT)
    }

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
        for w in of(ENERGY_ERROR) {
            lines.push(format!("t = {} s: {}", crate::shown(w.t), w.message));
        }
        for kind in [PULLING_IMPULSE, IMPULSE_OUTSIDE_CONE] {
            let w: Vec<&SimWarning> = of(kind).collect();
            if let Some(first) = w.first() {
                lines.push(format!(
                    "{} impact(s) with {kind}, first at t = {} s: {}",
                    w.len(),
                    first.t,
                    first.message
                ));
            }
        }
        for w in of(HELD_CONTACT).chain(of(HELD_OUTSIDE_CONE)) {
            lines.push(format!("t = {} s: {}", crate::shown(w.t), w.message));
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
        // Kinds a caller added (e.g. the CLI's `torques_held`), one line each.
        let summarised = [
            "energy_raising_impact",
            ENERGY_ERROR,
            PULLING_IMPULSE,
            IMPULSE_OUTSIDE_CONE,
            HELD_CONTACT,
            HELD_OUTSIDE_CONE,
            "zeno_fallback",
        ];
        for w in self
            .warnings
            .iter()
            .filter(|w| !summarised.contains(&w.kind))
        {
            lines.push(format!("t = {} s: {}", crate::shown(w.t), w.message));
        }
        lines
    }
}

impl std::fmt::Display for RunSummary {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        writeln!(
            f,
            "simulated t = {} .. {} s, final mode {}",
            crate::shown(self.t0),
            crate::shown(self.t_final),
            mode_name(self.mode_final)
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
            .map(|(m, s)| format!("{} {:.1}%", mode_name(*m), 100.0 * s))
            .collect();
        writeln!(f, "time in modes: {}", sh.join(", "))?;
        writeln!(f, "max penetration: {:.3e} m", self.max_penetration)?;
        if self.projected {
            writeln!(
                f,
                "contact drift |h| before projection: max {:.3e} m, final {:.3e} m; after: max \
                 |h| {:.3e} m, max |n.v_c| {:.3e} m/s",
                self.max_drift, self.final_drift, self.max_contact_gap, self.max_normal_velocity
            )?;
        } else {
            writeln!(
                f,
                "contact drift, not projected (--no-projection): max |h| {:.3e} m, max |n.v_c| \
                 {:.3e} m/s",
                self.max_contact_gap, self.max_normal_velocity
            )?;
        }
        writeln!(
            f,
            "energy: {:.9} J -> {:.9} J (change {:+.3e} J); balance error {:.3e} J of {:.3e} J \
             allowed (drift over the run {:.3e} J)",
            self.energy_initial,
            self.energy_final,
            self.energy_final - self.energy_initial,
            self.energy_error,
            self.energy_tolerance,
            self.energy_drift
        )?;
        writeln!(
            f,
            "steps: {} accepted, {} rejected, {} rhs evaluations",
            self.stats.accepted_steps, self.stats.rejected_steps, self.stats.rhs_evals
        )?;
        write!(
            f,
            "wall time: {:.3} ms, real-time factor {:.0}x",
            1e3 * self.cpu_seconds,
            self.real_time_factor
        )
    }
}

/// Everything derived from one ball-and-finger run ([`BallFinger::report`]).
#[derive(Debug, Clone, PartialEq)]
pub struct RunReport<const N: usize = 3> {
    /// Derived quantities per trajectory sample (same indices as the trajectory).
    pub samples: Vec<SampleInfo<N>>,
    /// Event log with derived quantities.
    pub events: Vec<EventInfo<N>>,
    /// Summary.
    pub summary: RunSummary,
}

/// The mode as written in every file: its serde name (lowercase), as in the JSON files.
pub(super) fn mode_name(m: Mode) -> &'static str {
    match m {
        Mode::Free => "free",
        Mode::Stick => "stick",
        Mode::Slip => "slip",
    }
}

#[cfg(test)]
mod tests {
    use super::window_error;

    /// A residual that drifts at a constant rate d: over a window W the check sees d·W, where
    /// it started (at t₀) it sees d·t, whatever the run's length.
    #[test]
    fn a_steady_drift_is_checked_per_window() {
        let d = 1e-4;
        let t: Vec<f64> = (0..=4000).map(|k| 0.01 * k as f64).collect();
        let r: Vec<f64> = t.iter().map(|t| -d * t).collect();
        // The window reaches back to a sample, so it spans W to W plus one sample interval.
        let (e, at) = window_error(&t, &r, 10.0);
        assert!(e >= d * 10.0 - 1e-12 && e <= d * 10.01 + 1e-12, "{e}");
        assert!(at >= 10.0, "{at}");
        let (e, at) = window_error(&t, &r, f64::INFINITY);
        assert!((e - d * 40.0).abs() <= 1e-12, "{e}");
        assert_eq!(at, 40.0);
        // Within the first window, the check is the residual from t₀.
        let (e, _) = window_error(&t[..=500], &r[..=500], 10.0);
        assert!((e - d * 5.0).abs() <= 1e-12, "{e}");
    }

    /// A jump of the residual (a badly integrated event) is seen at its full size by every
    /// window that holds it, however long the run goes on after it, and a jump that comes
    /// back within a window is seen as well.
    #[test]
    fn a_jump_is_checked_whatever_follows() {
        let t: Vec<f64> = (0..=10_000).map(|k| 0.01 * k as f64).collect();
        let jump = |t: f64| if t >= 37.0 { 2e-3 } else { 0.0 };
        let r: Vec<f64> = t.iter().map(|&t| jump(t)).collect();
        let (e, at) = window_error(&t, &r, 10.0);
        assert_eq!(e, 2e-3);
        assert!((at - 37.0).abs() < 1e-9, "{at}");
        let spike: Vec<f64> = t
            .iter()
            .map(|&t| if (37.0..37.5).contains(&t) { 2e-3 } else { 0.0 })
            .collect();
        assert_eq!(window_error(&t, &spike, 10.0).0, 2e-3);
    }
}
