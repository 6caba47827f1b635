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
use crate::{Guard, HybridSystem, Input, SimError, Transition};
use bf_model::dynamics::contact_matrices;
use bf_model::{ImpactLaw, Kernels, Mode, Model, State, Vec3};
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
}

impl Default for BallFingerOptions {
    fn default() -> Self {
        BallFingerOptions {
            impact_law: ImpactLaw::Stick,
            project: true,
            projection_iterations: 3,
            lift_off_speed: 1e-8,
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
            slip_ref: Cell::new([0.0; 3]),
        })
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
    /// dynamics (0 in Free, eq. 45), h, σ, ‖Δv‖, n·v_c and the energy.
    pub fn sample_info(&self, mode: Mode, t: f64, x: &[f64]) -> Result<SampleInfo, SimError> {
        let s = state_of(x)?;
        let tau = self.tau(t, &s)?;
        let kin = self.model.evaluate(&s).map_err(SimError::system)?;
        let acc = self
            .model
            .accelerations(mode, &s, &tau)
            .map_err(SimError::system)?;
        let e = self.model.energy(&s).map_err(SimError::system)?;
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
        let summary = summarize(out, &samples, &events, t0, cpu_seconds);
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
/// eq. 19), `slip_to_stick` (‖Δv‖ ≤ ε, Sect. 3.1).
pub fn event_kind(mode_before: Mode, mode_after: Option<Mode>, guard: &str) -> &'static str {
    match (mode_before, guard) {
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
    /// slip_to_stick, graze).
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
) -> RunSummary {
    let tr = &out.trajectory;
    let kinds = [
        "impact",
        "lift_off",
        "stick_to_slip",
        "slip_to_stick",
        "graze",
    ];
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
        stats: out.stats,
        cpu_seconds,
        real_time_factor: if cpu_seconds > 0.0 {
            elapsed / cpu_seconds
        } else {
            f64::INFINITY
        },
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
            "energy: {:.9} J -> {:.9} J (change {:+.3e} J)",
            self.energy_initial,
            self.energy_final,
            self.energy_final - self.energy_initial
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
            Mode::Slip => vec![
                Guard::falling("lambda_n"),
                Guard::falling("slip_speed"),
                Guard::falling("slip_reversal"),
            ],
        }
    }

    fn guard_values(&self, mode: Mode, t: f64, x: &[f64], out: &mut [f64]) -> Result<(), SimError> {
        let s = state_of(x)?;
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
                let acc = self.model.stick(&s, &tau).map_err(SimError::system)?;
                out[0] = acc.force.lambda_n;
                out[1] = acc.force.sigma;
            }
            Mode::Slip => {
                let tau = self.tau(t, &s)?;
                let kin = self.model.evaluate(&s).map_err(SimError::system)?;
                let acc = bf_model::dynamics::slip(
                    &kin,
                    self.model.params(),
                    &tau,
                    self.model.settings(),
                    None,
                )
                .map_err(SimError::system)?;
                let dv = kin.contact.delta_v;
                out[0] = acc.force.lambda_n;
                out[1] = dv.norm() - self.model.settings().slip_eps;
                let d = Vec3::from(self.slip_ref.get());
                out[2] = if d == Vec3::zeros() {
                    dv.norm()
                } else {
                    dv.dot(&d) - REVERSAL_COS * dv.norm()
                };
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

    fn project(&self, mode: Mode, _t: f64, x: &mut [f64]) -> Result<Option<f64>, SimError> {
        if mode == Mode::Slip {
            // The slip_reversal guard of the next step compares Δv with its direction now.
            let s = state_of(x)?;
            let kin = self.model.evaluate(&s).map_err(SimError::system)?;
            self.set_slip_ref(&kin.contact.delta_v);
        }
        if mode == Mode::Free || !self.options.project {
            return Ok(None);
        }
        let mut s = state_of(x)?;
        let drift = self.project_position(&mut s)?;
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
        if mode == Mode::Slip {
            let kin = self.model.evaluate(&s).map_err(SimError::system)?;
            self.set_slip_ref(&kin.contact.delta_v);
        }
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
