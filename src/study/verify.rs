//! Built-in trajectory verification of optimal-control solutions: every phase of a solved
//! problem is re-integrated with the optimal torques by the simulator's adaptive DOPRI5
//! (bf-sim) on the physics of bf-model, and the end-of-phase state defects
//! x_sim(t_f) − x_colloc(t_f) are reported.
//!
//! | item | paper |
//! |---|---|
//! | free phases: q̈, ω̇ from `bf_model::Model::free` | eq. 26 |
//! | stick phases: λ from the index-reduced stick law (`Model::stick`, d/dt Δv = 0) | eq. 29, 33 |
//! | [`PhaseVerification::max_delta_v`]: drift of the stick constraint Δv = 0 | eq. 13–14 |
//! | [`PhaseVerification::min_lambda_n`], [`PhaseVerification::min_sigma`] | eq. 12, 18 |
//! | [`PhaseVerification::min_h`]: penetration check of free phases | eq. 4 |
//! | [`PhaseVerification::node_residual`]: the OCP's dynamics residual at the collocation nodes, evaluated with bf-model's kernels and parameters | eq. 26, 29 |
//! | contact geometry with the smooth saturation of the solution's ε | eq. 58–59 |
//!
//! Conventions:
//! * **Torques between collocation nodes** are the solution's own dense output: in each
//!   collocation element, the Lagrange polynomial through the element's collocation nodes
//!   (what [`PhaseTrajectory::u_at`] evaluates), clamped to |τ_i| ≤ τ_max,i. This is exactly the
//!   function that `OcpSolution::dense` and `torques.csv` sample (100 samples per phase).
//!   The polynomial jumps at element boundaries, so the integrator is restarted at each of them
//!   (no step straddles a discontinuity of the input). Where the optimal torques saturate,
//!   the polynomial overshoots τ_max between the nodes and the clamp changes the torque: this is
//!   then usually the dominant defect (`reach`: ~1e-3–1e-2 clamped vs ~1e-9 with
//!   [`TorqueInterpolant::Polynomial`]); [`PhaseVerification::max_torque_overshoot`] shows it.
//! * **Each phase starts from its own collocated initial state**: the Free → Stick switch
//!   applies the sticking impact law (eq. 40) with the impulse ι from the NLP parameters, and
//!   phase continuity / periodicity are NLP constraints; they are not re-integrated here.
//! * **Stick phases** use the physical stick dynamics (λ from eq. 33), not the collocated λ:
//!   the check is whether the optimal torques *keep* the contact sticking. bf-model refuses
//!   contact queries beyond |h| ≤ tol·r; the OCP allows h ≤ 10⁻⁴ at the touch-down, so the
//!   verification uses [`CONTACT_TOLERANCE`] and reports max |h| instead.
//! * Defects are absolute (rad, rad/s), max over components. A phase whose re-integration
//!   fails (model error, step-size underflow) is reported with `failure` set and NaN defects
//!   (written as `null` in JSON); `Verification::max_defect` is then NaN.

use std::time::Instant;

use bf_model::fixtures::{self, DynKernels};
use bf_model::{ContactVariant, Model, State, TransitionSettings, Vec3};
use bf_optim::ocp::PhaseTrajectory;
use bf_optim::ocp::nodes::lagrange_basis;
use bf_problem::{BuiltProblem, OcpSolution, PhaseMode};
use bf_sim::{Guard, HybridSystem, SimError, SimOutput, SimSettings, Transition};

use super::error::{PhaseDataDefect, StudyError};

pub use bf_problem::solution::records::{PhaseVerification, TorqueInterpolant, Verification};

/// Contact tolerance (fraction of the ball radius) of the stick dynamics during verification.
pub const CONTACT_TOLERANCE: f64 = 0.05;

/// atol = rtol · `ATOL_FACTOR` (states are O(0.1–10) rad, rad/s).
pub const ATOL_FACTOR: f64 = 1e-2;

/// Extra dense-output samples per collocation element for the path checks (h, Δv, λ_n, σ),
/// in addition to the integrator's accepted steps.
pub const SAMPLES_PER_ELEMENT: usize = 16;

/// Options of [`verify_with`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct VerifyOptions {
    /// DOPRI5 relative tolerance, in (0, 0.1].
    pub rtol: f64,
    /// Absolute tolerance (state units); `None`: rtol · [`ATOL_FACTOR`].
    pub atol: Option<f64>,
    /// Torque interpolant.
    pub torque: TorqueInterpolant,
}

impl Default for VerifyOptions {
    fn default() -> Self {
        VerifyOptions {
            rtol: 1e-10,
            atol: None,
            torque: TorqueInterpolant::Clamped,
        }
    }
}

/// One collocation element of one phase as a (single-mode) hybrid system for bf-sim: the
/// torque is the element's control polynomial, clamped to the torque limits.
struct ElementSystem<'a> {
    model: &'a Model<DynKernels>,
    duration: f64,
    node_tau: Vec<f64>,
    node_u: Vec<[f64; 3]>,
    tau_max: [f64; 3],
    interp: TorqueInterpolant,
}

impl ElementSystem<'_> {
    /// How far the unclamped polynomial exceeds the torque limits at t (0 inside them).
    fn overshoot(&self, t: f64) -> f64 {
        let s = 2.0 * t / self.duration - 1.0;
        let l = lagrange_basis(&self.node_tau, s);
        (0..3)
            .map(|i| {
                let v: f64 = l.iter().zip(&self.node_u).map(|(w, uk)| w * uk[i]).sum();
                (v.abs() - self.tau_max[i]).max(0.0)
            })
            .fold(0.0, f64::max)
    }

    /// τ(t) at phase-local time t.
    fn torque(&self, t: f64) -> Vec3 {
        let s = 2.0 * t / self.duration - 1.0;
        let l = lagrange_basis(&self.node_tau, s);
        let mut u = [0.0; 3];
        for (i, ui) in u.iter_mut().enumerate() {
            let v: f64 = l.iter().zip(&self.node_u).map(|(w, uk)| w * uk[i]).sum();
            let m = self.tau_max[i];
            // max/min rather than clamp: never panics, whatever the limits are.
            *ui = match self.interp {
                TorqueInterpolant::Clamped => v.max(-m).min(m),
                TorqueInterpolant::Polynomial => v,
            };
        }
        Vec3::new(u[0], u[1], u[2])
    }

    fn state(x: &[f64]) -> Result<State, SimError> {
        let a: &[f64; 9] = x.try_into().map_err(|_| SimError::DimensionMismatch {
            what: "state",
            expected: 9,
            found: x.len(),
        })?;
        Ok(State::from_array(a))
    }
}

impl HybridSystem for ElementSystem<'_> {
    type Mode = PhaseMode;

    fn dim(&self) -> usize {
        9
    }

    fn rhs(&self, mode: PhaseMode, t: f64, x: &[f64], dx: &mut [f64]) -> Result<(), SimError> {
        let st = Self::state(x)?;
        let tau = self.torque(t);
        let acc = match mode {
            PhaseMode::Free => self.model.free(&st, &tau),
            PhaseMode::Stick => self.model.stick(&st, &tau),
        }
        .map_err(SimError::system)?;
        dx.copy_from_slice(&acc.state_derivative(&st.qd));
        Ok(())
    }

    fn guards(&self, _mode: PhaseMode) -> Vec<Guard> {
        Vec::new()
    }

    fn guard_values(&self, _: PhaseMode, _: f64, _: &[f64], _: &mut [f64]) -> Result<(), SimError> {
        Ok(())
    }

    fn reset(
        &self,
        mode: PhaseMode,
        _: usize,
        _: f64,
        _: &mut [f64],
    ) -> Result<Transition<PhaseMode>, SimError> {
        Ok(Transition::To(mode))
    }
}

/// max that propagates NaN (f64::max ignores it).
fn nan_max(a: f64, b: f64) -> f64 {
    if a.is_nan() || b.is_nan() {
        f64::NAN
    } else {
        a.max(b)
    }
}

/// The bf-model model of `p`'s scene with the smooth contact of ε, after checking that its
/// physical constants are the ones the OCP was built with.
fn verification_model(p: &BuiltProblem, eps: f64) -> Result<Model<DynKernels>, StudyError> {
    let settings = TransitionSettings {
        contact_tolerance: CONTACT_TOLERANCE,
        ..TransitionSettings::default()
    };
    let model_err = |source| StudyError::VerifyModel {
        scene: p.scene.name.clone(),
        source,
    };
    let (model, _) = fixtures::model_for_scene(&p.scene).map_err(model_err)?;
    let model = model
        .with_settings(settings)
        .map_err(model_err)?
        .with_contact_variant(ContactVariant::Smooth(eps))
        .map_err(model_err)?;
    let pm = model.params();
    let ph = &p.physics;
    let close = |a: f64, b: f64| (a - b).abs() <= 1e-12 * a.abs().max(b.abs()).max(1e-300);
    let mut same = close(pm.mu_v(), ph.mu_v)
        && close(pm.socket_damping(), ph.damping)
        && close(pm.ball_radius(), ph.radius)
        && close(pm.mu_s(), ph.mu_s);
    for i in 0..3 {
        for j in 0..3 {
            same &= (pm.ball_inertia()[(i, j)] - ph.ib[i][j]).abs()
                <= 1e-12 * ph.ib[i][i].abs().max(1e-300);
        }
    }
    if !same {
        return Err(StudyError::ParameterMismatch {
            scene: p.scene.name.clone(),
            model: format!("{pm:?}"),
            ocp: format!("{ph:?}"),
        });
    }
    Ok(model)
}

fn check_phase_data(k: usize, tr: &PhaseTrajectory, nx: usize) -> Result<(), StudyError> {
    let bad = |defect| Err(StudyError::PhaseData { phase: k, defect });
    if !(tr.duration.is_finite() && tr.duration > 0.0) {
        return bad(PhaseDataDefect::Duration(tr.duration));
    }
    if tr.x.is_empty() || tr.x.iter().any(|x| x.len() != nx) {
        return bad(PhaseDataDefect::StateDimension);
    }
    if tr.state_tau.len() != tr.x.len() || tr.node_state.len() != tr.node_tau.len() {
        return bad(PhaseDataDefect::Inconsistent);
    }
    if tr.state_tau.first() != Some(&-1.0) || tr.state_tau.last() != Some(&1.0) {
        return bad(PhaseDataDefect::Span);
    }
    if tr.u.len() != tr.node_tau.len() || tr.u.iter().any(|u| u.len() != 3) {
        return bad(PhaseDataDefect::ControlDimension);
    }
    if tr.a.len() != tr.node_tau.len() {
        return bad(PhaseDataDefect::AlgebraicCount);
    }
    if tr.elements.is_empty()
        || tr
            .elements
            .iter()
            .any(|&(a, b)| a >= b || b > tr.state_tau.len())
    {
        return bad(PhaseDataDefect::ElementRanges);
    }
    let finite = |v: &[Vec<f64>]| v.iter().flatten().all(|x| x.is_finite());
    let times_finite = tr
        .state_tau
        .iter()
        .chain(&tr.node_tau)
        .all(|t| t.is_finite());
    if !(finite(&tr.x) && finite(&tr.u) && finite(&tr.a) && times_finite) {
        return bad(PhaseDataDefect::NonFinite);
    }
    Ok(())
}

/// Max |residual| of eq. 26 / 29 at the collocation nodes of `tr`, with bf-model's kernels.
fn node_residual(
    model: &Model<DynKernels>,
    phase: usize,
    mode: PhaseMode,
    tr: &PhaseTrajectory,
) -> Result<f64, StudyError> {
    let pm = model.params();
    let mut worst: f64 = 0.0;
    for k in 0..tr.node_tau.len() {
        let x = &tr.x[tr.node_state[k]];
        let a = &tr.a[k];
        let need = if mode == PhaseMode::Stick { 9 } else { 6 };
        if a.len() < need {
            return Err(StudyError::PhaseData {
                phase,
                defect: PhaseDataDefect::AlgebraicDimension {
                    found: a.len(),
                    mode,
                    need,
                },
            });
        }
        let st = ElementSystem::state(x)?;
        let kin = model
            .evaluate(&st)
            .map_err(|source| StudyError::NodeEvaluation {
                phase,
                node: k,
                source,
            })?;
        let qdd = Vec3::new(a[0], a[1], a[2]);
        let wd = Vec3::new(a[3], a[4], a[5]);
        let lam = if mode == PhaseMode::Stick {
            Vec3::new(a[6], a[7], a[8])
        } else {
            Vec3::zeros()
        };
        let tau = Vec3::new(tr.u[k][0], tr.u[k][1], tr.u[k][2]);
        let c = &kin.contact;
        let rf = kin.m_f * qdd + kin.cqd_g + st.qd * pm.mu_v() - tau - c.j_c.transpose() * lam;
        let ib = pm.ball_inertia();
        let w = &st.omega;
        let rb = ib * wd + w.cross(&(ib * w)) + w * pm.socket_damping() + c.r_c.cross(&lam);
        worst = worst.max(rf.amax()).max(rb.amax());
    }
    Ok(worst)
}

/// Running path checks of one phase.
#[derive(Default)]
struct PathStats {
    min_h: f64,
    max_dv: f64,
    min_ln: f64,
    min_sigma: f64,
    max_abs_h: f64,
    overshoot: f64,
}

impl PathStats {
    fn new() -> Self {
        PathStats {
            min_h: f64::INFINITY,
            max_dv: 0.0,
            min_ln: f64::INFINITY,
            min_sigma: f64::INFINITY,
            max_abs_h: 0.0,
            overshoot: 0.0,
        }
    }

    fn add(
        &mut self,
        sys: &ElementSystem,
        mode: PhaseMode,
        t: f64,
        x: &[f64],
    ) -> Result<(), String> {
        let st = ElementSystem::state(x).map_err(|e| e.to_string())?;
        let kin = sys.model.evaluate(&st).map_err(|e| e.to_string())?;
        let h = kin.contact.h;
        self.overshoot = self.overshoot.max(sys.overshoot(t));
        match mode {
            PhaseMode::Free => self.min_h = self.min_h.min(h),
            PhaseMode::Stick => {
                let acc = sys
                    .model
                    .stick(&st, &sys.torque(t))
                    .map_err(|e| e.to_string())?;
                self.max_dv = self.max_dv.max(kin.contact.delta_v.norm());
                self.min_ln = self.min_ln.min(acc.force.lambda_n);
                self.min_sigma = self.min_sigma.min(acc.force.sigma);
                self.max_abs_h = self.max_abs_h.max(h.abs());
            }
        }
        Ok(())
    }

    fn add_output(
        &mut self,
        sys: &ElementSystem,
        mode: PhaseMode,
        out: &SimOutput<PhaseMode>,
    ) -> Result<(), String> {
        for (t, x) in out.trajectory.t.iter().zip(&out.trajectory.x) {
            self.add(sys, mode, *t, x)?;
        }
        Ok(())
    }
}

fn verify_phase(
    model: &Model<DynKernels>,
    tau_max: [f64; 3],
    k: usize,
    mode: PhaseMode,
    tr: &PhaseTrajectory,
    rtol: f64,
    atol: f64,
    interp: TorqueInterpolant,
) -> Result<PhaseVerification, StudyError> {
    let big_t = tr.duration;
    // The first and last state points are τ = −1 and +1 in both schemes (LG: the final state
    // is the quadrature variable, which interpolation of the element would miss).
    let x_start = tr.x[0].clone();
    let x_colloc_end = tr.x[tr.x.len() - 1].clone();
    let node_residual = node_residual(model, k, mode, tr)?;
    let mut x = x_start.clone();
    let mut stats = PathStats::new();
    let (mut steps, mut rejected, mut rhs) = (0, 0, 0);
    let mut failure = None;
    let mut t_reached = 0.0;
    let mut s_prev = -1.0;
    let mut element_defect = 0.0;
    let ne = tr.elements.len();
    for (e, &(a, b)) in tr.elements.iter().enumerate() {
        let s_end = if e + 1 == ne {
            1.0
        } else {
            tr.state_tau[b - 1]
        };
        let s_start = s_prev;
        let (ta, tb) = (0.5 * (s_start + 1.0) * big_t, 0.5 * (s_end + 1.0) * big_t);
        s_prev = s_end;
        if tb <= ta {
            continue;
        }
        let ks: Vec<usize> = (0..tr.node_tau.len())
            .filter(|&j| (a..b).contains(&tr.node_state[j]))
            .collect();
        if ks.is_empty() {
            return Err(StudyError::PhaseData {
                phase: k,
                defect: PhaseDataDefect::EmptyElement(e),
            });
        }
        let sys = ElementSystem {
            model,
            duration: big_t,
            node_tau: ks.iter().map(|&j| tr.node_tau[j]).collect(),
            node_u: ks
                .iter()
                .map(|&j| [tr.u[j][0], tr.u[j][1], tr.u[j][2]])
                .collect(),
            tau_max,
            interp,
        };
        let settings = SimSettings {
            rtol,
            atol,
            h_max: tb - ta,
            output_dt: Some((tb - ta) / SAMPLES_PER_ELEMENT as f64),
            record_steps: true,
            ..SimSettings::default()
        };
        // Steps are recorded: the last sample is then the state at tb.
        let local = SimSettings {
            output_dt: None,
            ..settings.clone()
        };
        let xa = if e == 0 {
            x_start.clone()
        } else {
            tr.x_at(s_start)
        };
        let xb = if e + 1 == ne {
            x_colloc_end.clone()
        } else {
            tr.x_at(s_end)
        };
        element_defect = match bf_sim::simulate(&sys, local, mode, ta, &xa, tb) {
            Ok(out) if out.trajectory.x.last().is_some() => {
                let xe = &out.trajectory.x[out.trajectory.x.len() - 1];
                let d = (0..xb.len())
                    .map(|i| (xe[i] - xb[i]).abs())
                    .fold(0.0, nan_max);
                nan_max(element_defect, d)
            }
            _ => f64::NAN,
        };
        let (out, err) = match bf_sim::simulate(&sys, settings, mode, ta, &x, tb) {
            Ok(out) => (out, None),
            Err(fail) => {
                let msg = fail.to_string();
                (fail.partial, Some(msg))
            }
        };
        steps += out.stats.accepted_steps;
        rejected += out.stats.rejected_steps;
        rhs += out.stats.rhs_evals;
        if let Some(xl) = out.trajectory.x.last() {
            x.clone_from(xl);
            t_reached = out.t_final;
        }
        let path = stats.add_output(&sys, mode, &out);
        if let Some(msg) = err.or(path.err()) {
            failure = Some(format!("element {e}: {msg}"));
            break;
        }
    }
    let nq = 3;
    let part = |r: std::ops::Range<usize>| -> f64 {
        if failure.is_some() {
            return f64::NAN;
        }
        r.map(|i| (x[i] - x_colloc_end[i]).abs()).fold(0.0, nan_max)
    };
    let (dq, dqd, dw) = (part(0..nq), part(nq..2 * nq), part(2 * nq..2 * nq + 3));
    let stick = mode == PhaseMode::Stick;
    let finite_or_none = |v: f64, on: bool| (on && v.is_finite()).then_some(v);
    Ok(PhaseVerification {
        phase: k,
        mode,
        duration: big_t,
        t_reached,
        failure,
        defect: dq.max(dqd).max(dw),
        defect_q: dq,
        defect_qd: dqd,
        defect_omega: dw,
        element_defect,
        x_start,
        x_end: x,
        x_colloc_end,
        steps,
        rejected_steps: rejected,
        rhs_evals: rhs,
        rtol,
        atol,
        node_residual,
        max_torque_overshoot: stats.overshoot,
        min_h: finite_or_none(stats.min_h, !stick),
        max_delta_v: finite_or_none(stats.max_dv, stick),
        min_lambda_n: finite_or_none(stats.min_ln, stick),
        min_sigma: finite_or_none(stats.min_sigma, stick),
        max_abs_h: finite_or_none(stats.max_abs_h, stick),
    })
}

/// Largest re-integration defect (end-of-phase state error, state units) at which a solution
/// counts as verified: above it, the collocation solution does not describe what the hybrid
/// model does with its torques, and every place that shows the solution flags it.
pub const VERIFIED_DEFECT: f64 = 1e-4;

/// Whether `sol` carries a re-integration that reached the end of every phase with a defect of
/// at most [`VERIFIED_DEFECT`].
pub fn is_verified(sol: &OcpSolution) -> bool {
    sol.verification.as_ref().is_some_and(|v| {
        v.completed() && v.max_defect.is_finite() && v.max_defect <= VERIFIED_DEFECT
    })
}

/// [`verify_with`] at `rtol` with atol = rtol · [`ATOL_FACTOR`] and the clamped torque
/// interpolant of the dense output / `torques.csv`.
pub fn verify(p: &BuiltProblem, sol: &OcpSolution, rtol: f64) -> Result<Verification, StudyError> {
    verify_with(
        p,
        sol,
        &VerifyOptions {
            rtol,
            ..VerifyOptions::default()
        },
    )
}

/// Re-integrates every phase of `sol` (a solution of `p`) from its collocated initial state
/// with the solution's torques, by DOPRI5 on bf-model's free / stick dynamics with the smooth
/// contact of ε = `sol.epsilon`, and reports the end-of-phase state defects and path checks
/// (see the module docs).
///
/// Errors: tolerances out of range (rtol ∉ (0, 0.1], atol ≤ 0); a solution that does not
/// match `p` (phase count, modes, ε, dimensions); non-finite solution data; a scene without a
/// bf-model counterpart or whose constants differ from the OCP's. A re-integration that breaks
/// down part-way is *not* an error: it is reported in that phase's `failure`.
pub fn verify_with(
    p: &BuiltProblem,
    sol: &OcpSolution,
    opt: &VerifyOptions,
) -> Result<Verification, StudyError> {
    let start = Instant::now();
    let rtol = opt.rtol;
    if !(rtol.is_finite() && rtol > 0.0 && rtol <= 0.1) {
        return Err(StudyError::InvalidOption {
            name: "verification rtol",
            value: rtol,
            expected: "in (0, 0.1]",
        });
    }
    let atol = opt.atol.unwrap_or(rtol * ATOL_FACTOR);
    if !(atol.is_finite() && atol > 0.0) {
        return Err(StudyError::InvalidOption {
            name: "verification atol",
            value: atol,
            expected: "finite and > 0",
        });
    }
    if p.physics.nq != 3 {
        return Err(StudyError::VerifyJoints {
            scene: p.scene.name.clone(),
            joints: p.physics.nq,
        });
    }
    if sol.raw.len() != p.modes.len() || sol.modes != p.modes {
        return Err(StudyError::ModeMismatch {
            solution: sol.modes.clone(),
            problem: p.modes.clone(),
        });
    }
    let eps = sol.epsilon;
    if !(eps.is_finite() && eps > 0.0) || (eps - p.epsilon).abs() > 1e-12 * p.epsilon.abs() {
        return Err(StudyError::EpsilonMismatch {
            solution: eps,
            problem: p.epsilon,
        });
    }
    let model = verification_model(p, eps)?;
    let mut tau_max = [f64::INFINITY; 3];
    for (t, m) in tau_max.iter_mut().zip(&p.physics.tau_max) {
        if !m.is_nan() {
            *t = m.abs();
        }
    }
    let mut phases = Vec::with_capacity(sol.raw.len());
    for (k, tr) in sol.raw.iter().enumerate() {
        check_phase_data(k, tr, 9)?;
        phases.push(verify_phase(
            &model,
            tau_max,
            k,
            sol.modes[k],
            tr,
            rtol,
            atol,
            opt.torque,
        )?);
    }
    let fold = |f: &dyn Fn(&PhaseVerification) -> f64| phases.iter().map(f).fold(0.0, nan_max);
    let max_defect = fold(&|p| p.defect);
    let max_node_residual = fold(&|p| p.node_residual);
    let completed = phases.iter().all(|p| p.failure.is_none());
    Ok(Verification {
        tolerance: VERIFIED_DEFECT,
        verified: completed && max_defect.is_finite() && max_defect <= VERIFIED_DEFECT,
        problem: sol.problem.clone(),
        scene: p.scene.name.clone(),
        epsilon: eps,
        torque: opt.torque,
        rtol,
        atol,
        max_defect,
        max_node_residual,
        phases,
        seconds: start.elapsed().as_secs_f64(),
    })
}
