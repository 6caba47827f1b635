//! Free motion of a robot arm with any number of joints and no ball (`bf_model::arm`):
//! M(q) q̈ = τ − C(q, q̇) q̇ − g(q) − μ_v q̇ as a [`HybridSystem`] with one mode and no guards,
//! state x = [q; q̇] (length 2 NQ), torques from any [`Input`] (time series, PD controller).
//!
//! [`FreeArm::report`] derives per-sample torques and energies and the run summary: the energy
//! balance error max |E(t) − E(t₀) − ∫ P dt| with P = τ·q̇ − μ_v |q̇|² (Simpson's rule over each
//! step, the midpoint from the step's interpolant), which vanishes for the exact solution up to
//! the integration's error, and its check against
//! [`ENERGY_ERROR_REL`] times the energy the run moves (an arm's energies span orders of
//! magnitude, so the tolerance is relative, as the ball-and-finger system's is;
//! [`ArmSummary::energy_check_failure`]); [`ArmReport::write_dir`] writes `trajectory.csv`
//! (t, q, q̇, τ, E) and `summary.json`.

use std::fmt::Write as _;
use std::path::Path;

use bf_model::arm::ArmModel;
use serde::Serialize;

use crate::integrator::{StepEnd, simpson_over_step};
use crate::trajectory::write_atomic;
use crate::{HybridSystem, Input, SimError, SimOutput, SimStats};

/// The energy-balance tolerance of an arm run relative to the energy it moves: the largest
/// kinetic energy ½ q̇ᵀ M q̇ over the samples plus ∫ |P| dt (the work of the torques and the
/// friction, either sign). A run above it has an integration too coarse for its dynamics.
/// 1e-3 is some 100 times what DOPRI5 leaves at its default tolerance; the ball-and-finger
/// system's check uses the same share by default (`BallFingerSettings::energy_error_rel`).
pub const ENERGY_ERROR_REL: f64 = 1e-3;

/// The part of the tolerance that does not scale with the motion, relative to the largest
/// |E| of the run: rounding of E itself, for a run that barely moves.
const ENERGY_ROUNDING_REL: f64 = 1e-9;

/// The energy-balance tolerance of a run that moves `kinetic` (its largest kinetic energy) and
/// `flow` (∫ |P| dt) with the largest |E| `largest`: `rel` times the energy moved, plus the
/// rounding of E. One rule for the arm and the ball-and-finger system.
pub(crate) fn balance_tolerance(rel: f64, kinetic: f64, flow: f64, largest: f64) -> f64 {
    rel * (kinetic + flow) + ENERGY_ROUNDING_REL * largest.max(1.0)
}

/// The single mode of [`FreeArm`].
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ArmMode {
    /// Unconstrained joint-space motion.
    Free,
}

/// An arm driven by joint torques (see the module docs).
#[derive(Debug, Clone)]
pub struct FreeArm<I: Input> {
    /// The arm's dynamics.
    pub model: ArmModel,
    /// The joint torques.
    pub input: I,
}

fn system_err(e: impl std::fmt::Display) -> SimError {
    SimError::System { msg: e.to_string() }
}

impl<I: Input> FreeArm<I> {
    /// The arm with `input`; the input must have one torque per joint.
    pub fn new(model: ArmModel, input: I) -> Result<Self, SimError> {
        if input.dim() != model.nq() {
            return Err(SimError::DimensionMismatch {
                what: "torque input",
                expected: model.nq(),
                found: input.dim(),
            });
        }
        Ok(FreeArm { model, input })
    }

    fn tau(&self, t: f64, x: &[f64]) -> Result<Vec<f64>, SimError> {
        let n = self.model.nq();
        let mut tau = vec![0.0; n];
        self.input.tau(t, &x[..n], &x[n..], &mut tau)?;
        Ok(tau)
    }

    /// Torques, energy and power at every sample of `out`, and the summary of the run.
    pub fn report(
        &self,
        out: &SimOutput<ArmMode>,
        cpu_seconds: f64,
    ) -> Result<ArmReport, SimError> {
        let n = self.model.nq();
        let tr = &out.trajectory;
        let mut samples = Vec::with_capacity(tr.len());
        let mut kinetic_max = 0.0f64;
        // ẋ at each sample, for the Hermite midpoints of the balance's quadrature.
        let mut slopes = Vec::with_capacity(tr.len());
        for (&t, x) in tr.t.iter().zip(&tr.x) {
            let mut f = vec![0.0; x.len()];
            slopes.push(self.rhs(ArmMode::Free, t, x, &mut f).ok().map(|()| f));
            let tau = self.tau(t, x)?;
            let energy = self.model.energy(&x[..n], &x[n..]).map_err(system_err)?;
            let potential = self.model.potential(&x[..n]).map_err(system_err)?;
            kinetic_max = kinetic_max.max(energy - potential);
            let power = self.model.power(&x[n..], &tau);
            samples.push(ArmSample {
                t,
                q: x[..n].to_vec(),
                qd: x[n..].to_vec(),
                tau,
                energy,
                power,
            });
        }
        let (mut work, mut flow, mut energy_error) = (0.0, 0.0, 0.0f64);
        for (i, w) in samples.windows(2).enumerate() {
            let dt = w[1].t - w[0].t;
            // Simpson's rule on the step's Hermite interpolant, as the ball-and-finger
            // balance takes it (decision record 0078): the trapezoid's error dominates runs of
            // high power; it stays the fallback where the midpoint cannot be evaluated.
            let end = |k: usize| {
                Some(StepEnd {
                    t: samples[k].t,
                    x: &tr.x[k],
                    f: slopes[k].as_deref()?,
                    g: samples[k].power,
                })
            };
            let simpson = end(i).zip(end(i + 1)).and_then(|(a, b)| {
                simpson_over_step(a, b, |t, x| {
                    let tau = self.tau(t, x).ok()?;
                    Some(self.model.power(&x[n..], &tau))
                })
            });
            work += simpson.unwrap_or(0.5 * (w[0].power + w[1].power) * dt);
            flow += 0.5 * (w[0].power.abs() + w[1].power.abs()) * dt;
            let e0 = samples[0].energy;
            energy_error = energy_error.max((w[1].energy - e0 - work).abs());
        }
        let largest = samples.iter().fold(0.0f64, |m, s| m.max(s.energy.abs()));
        let energy_tolerance = balance_tolerance(ENERGY_ERROR_REL, kinetic_max, flow, largest);
        let summary = ArmSummary {
            scene: self.model.name().to_string(),
            kernels: None,
            joints: n,
            prismatic: self.model.prismatic().to_vec(),
            t_final: out.t_final,
            energy_initial: samples.first().map_or(f64::NAN, |s| s.energy),
            energy_final: samples.last().map_or(f64::NAN, |s| s.energy),
            work,
            energy_error,
            energy_tolerance,
            stats: out.stats,
            cpu_seconds,
            warnings: Vec::new(),
        };
        Ok(ArmReport { samples, summary })
    }
}

impl<I: Input> HybridSystem for FreeArm<I> {
    type Mode = ArmMode;
    fn dim(&self) -> usize {
        2 * self.model.nq()
    }
    fn rhs(&self, _: ArmMode, t: f64, x: &[f64], dx: &mut [f64]) -> Result<(), SimError> {
        let n = self.model.nq();
        let tau = self.tau(t, x)?;
        let qdd = self
            .model
            .accelerations(&x[..n], &x[n..], &tau)
            .map_err(system_err)?;
        dx[..n].copy_from_slice(&x[n..]);
        dx[n..].copy_from_slice(&qdd);
        Ok(())
    }
}

/// Derived quantities at one sample.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ArmSample {
    /// Time (s).
    pub t: f64,
    /// Joint angles (rad).
    pub q: Vec<f64>,
    /// Joint velocities (rad/s).
    pub qd: Vec<f64>,
    /// Joint torques (N m).
    pub tau: Vec<f64>,
    /// Energy ½ q̇ᵀ M q̇ + U (J).
    pub energy: f64,
    /// Power τ·q̇ − μ_v |q̇|² (W).
    pub power: f64,
}

/// Summary of a free-motion run (`summary.json`).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ArmSummary {
    /// Scene name.
    pub scene: String,
    /// Which kernels ran (`"compiled"` / `"interpreted"`), when the caller says so.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub kernels: Option<String>,
    /// Number of joints.
    pub joints: usize,
    /// Which joints are prismatic (q in m, q̇ in m/s, τ a force in N); the others are
    /// revolute (rad, rad/s, N m).
    pub prismatic: Vec<bool>,
    /// Time reached (s).
    pub t_final: f64,
    /// Energy at the first sample (J).
    pub energy_initial: f64,
    /// Energy at the last sample (J).
    pub energy_final: f64,
    /// ∫ P dt over the run (J, Simpson's rule over each step).
    pub work: f64,
    /// max |E(t) − E(t₀) − ∫ P dt| over the samples (J).
    pub energy_error: f64,
    /// What `energy_error` is checked against (J): [`ENERGY_ERROR_REL`] times the largest
    /// kinetic energy plus ∫ |P| dt, and the rounding of E.
    pub energy_tolerance: f64,
    /// Step counters.
    pub stats: SimStats,
    /// Wall-clock time (s).
    pub cpu_seconds: f64,
    /// Conditions that qualify the run, added by the caller (e.g. `torques_held`: the run went
    /// on past the end of its torque series, holding its last torque); the CLI prints them on
    /// stderr.
    pub warnings: Vec<crate::SimWarning>,
}

impl ArmSummary {
    /// Why the run failed its energy check, if it did: its balance error is above
    /// [`energy_tolerance`](Self::energy_tolerance) (or not a number), so its integration was
    /// too coarse for the dynamics.
    pub fn energy_check_failure(&self) -> Option<String> {
        let within = self.energy_error <= self.energy_tolerance;
        // A NaN error is not within.
        (!within).then(|| {
            format!(
                "energy-balance error {:.3e} J exceeds {:.3e} J ({:e} of the energy the run \
                 moves): the integration is too coarse for the dynamics (its step too long, or \
                 its tolerance too loose)",
                self.energy_error, self.energy_tolerance, ENERGY_ERROR_REL
            )
        })
    }
}

impl std::fmt::Display for ArmSummary {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        writeln!(
            f,
            "free motion of `{}` ({} joints), t = 0 .. {} s",
            self.scene, self.joints, self.t_final
        )?;
        writeln!(
            f,
            "energy: {:.9} J -> {:.9} J, work of torques and friction {:.3e} J; balance error \
             {:.3e} J (tolerance {:.3e} J)",
            self.energy_initial,
            self.energy_final,
            self.work,
            self.energy_error,
            self.energy_tolerance
        )?;
        write!(
            f,
            "steps: {} accepted, {} rejected; wall time {:.3} ms",
            self.stats.accepted_steps,
            self.stats.rejected_steps,
            1e3 * self.cpu_seconds
        )
    }
}

/// Samples and summary of a free-motion run.
#[derive(Debug, Clone, PartialEq)]
pub struct ArmReport {
    /// One entry per trajectory sample.
    pub samples: Vec<ArmSample>,
    /// The summary.
    pub summary: ArmSummary,
}

impl ArmReport {
    /// Writes `trajectory.csv` (`t [s],q1 [rad]..,qd1 [rad/s]..,tau1 [N m]..,energy [J]`, with
    /// m, m/s and N for prismatic joints) and `summary.json` (with `error` when the run failed)
    /// into `dir`.
    pub fn write_dir(&self, dir: &Path, error: Option<&str>) -> Result<(), SimError> {
        let n = self.summary.joints;
        let prismatic = |i: usize| self.summary.prismatic.get(i).copied().unwrap_or(false);
        let mut csv = String::from("t [s]");
        for (stem, revolute, linear) in [
            ("q", "rad", "m"),
            ("qd", "rad/s", "m/s"),
            ("tau", "N m", "N"),
        ] {
            for i in 0..n {
                let unit = if prismatic(i) { linear } else { revolute };
                let _ = write!(csv, ",{stem}{} [{unit}]", i + 1);
            }
        }
        csv.push_str(",energy [J]\n");
        for s in &self.samples {
            let _ = write!(csv, "{:e}", s.t);
            for v in s.q.iter().chain(&s.qd).chain(&s.tau) {
                let _ = write!(csv, ",{v:e}");
            }
            let _ = writeln!(csv, ",{:e}", s.energy);
        }
        write_atomic(&dir.join("trajectory.csv"), csv.as_bytes())?;
        let mut summary = serde_json::to_value(&self.summary).map_err(system_err)?;
        if let (Some(e), Some(o)) = (error, summary.as_object_mut()) {
            o.insert("error".into(), e.into());
        }
        let text = serde_json::to_string_pretty(&summary).map_err(system_err)?;
        write_atomic(&dir.join("summary.json"), text.as_bytes())
    }
}
