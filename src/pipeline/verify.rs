//! Built-in trajectory verification of optimal-control solutions: the optimal torques are
//! re-integrated by the simulator's adaptive DOPRI5 (bf-sim) on the physics of bf-model, and
//! the re-integrated states are compared with the collocated ones. Decision record:
//! docs/decisions/0005-elementwise-verification.md.
//!
//! | item | paper |
//! |---|---|
//! | free phases: q̈, ω̇ from `bf_model::Model::free` | eq. 26 |
//! | stick phases: λ from the index-reduced stick law (`Model::stick`, d/dt Δv = 0) | eq. 29, 33 |
//! | [`PhaseVerification::max_delta_v`]: drift of the stick constraint Δv = 0 | eq. 13–14 |
//! | [`PhaseVerification::min_lambda_n`], [`PhaseVerification::max_lambda_n`], [`PhaseVerification::min_sigma`] | eq. 12, 18 |
//! | [`cone_failure`]: min σ against ([`CONE_TOLERANCE`] · μ_s + [`CONE_ROUNDING`]) max λ_n ([`cone_allowance`]), part of the verdict | eq. 18–19 |
//! | [`PhaseVerification::min_h`], [`PhaseVerification::smoothing_error`], [`penetration_failure`]: penetration check of free phases, and the smoothing's error in the distance near the ball, part of the verdict | eq. 3–4, 58–59 |
//! | [`PhaseVerification::node_residual`]: the OCP's dynamics residual at the collocation nodes, evaluated with bf-model's kernels and parameters | eq. 26, 29 |
//! | [`ImpactCone`] (`Verification::impacts`): each planned impulse against the friction cone, part of the verdict where the problem imposed it ([`impulse_cone_failure`]), a flag otherwise ([`impulse_cone_warning`], decision record 0087) | eq. 36, 66 |
//! | contact geometry with the smooth saturation of the solution's ε | eq. 58–59 |
//!
//! Three figures per phase, one of them the criterion:
//! * **Element-wise defect** ([`PhaseVerification::defect`], the criterion): every collocation
//!   element is re-integrated alone, from the collocated state at its start, and its end is
//!   compared with the collocated state there (the next element's start, or the phase end) —
//!   multiple shooting with the element boundaries as shooting nodes. A solution is verified
//!   when every element reaches its end and the largest defect is ≤ [`VERIFIED_DEFECT`]: then
//!   the collocated trajectory is a chain of true trajectories of the model under its own
//!   torques with jumps ≤ [`VERIFIED_DEFECT`] at the element boundaries, and the path checks
//!   below hold along these true trajectories. The figure does not grow with the phase
//!   length; a long element on an unstable motion can still amplify its local error, and the
//!   refinement that a failed verification triggers splits such elements
//!   ([`element_errors`], [`super::refine::RefineCriterion::Reintegration`]).
//! * **Collocation-interval defect** ([`PhaseVerification::interval_defect`], informative):
//!   the same from every collocation point to the next. Radau collocation is more accurate
//!   at the element ends than at the interior nodes, so this figure is larger; it bounds the
//!   error of the interior node values that `solution.json` tabulates.
//! * **Open-loop drift** ([`PhaseVerification::open_loop_defect`], informative): one
//!   integration through the whole phase from its collocated initial state, compared at the
//!   phase end. It measures how the phase's motion amplifies small errors (it grows with the
//!   length of a free flight and with how unstable its motion is), i.e. whether the torques
//!   could be played back without feedback; it says nothing about whether the collocated
//!   trajectory solves the dynamics.
//!
//! A plan for the plant (a periodic problem planned with Newton's law) is also run in closed
//! loop by the search (`Verification::execution`, decision record 0048): a plan that the
//! nominal plant does not execute fails the verdict ([`execution_failure`]); one that misses
//! the robustness target on a perturbed plant is verified and graded below the robust ones
//! ([`robustness_miss`], [`is_robust`]). The search runs it only on plans that could still be
//! chosen; one above a verified and robust plan is left unexecuted, and so unverified
//! (`Verification::not_executed`, decision record 0067).
//!
//! Conventions:
//! * **Torques between collocation nodes** are the solution's own dense output: in each
//!   collocation element, the Lagrange polynomial through the element's collocation nodes
//!   (what [`PhaseTrajectory::u_at`] evaluates), clamped to |τ_i| ≤ τ_max,i. This is exactly the
//!   function that `OcpSolution::dense` and `torques.csv` sample (100 samples per phase).
//!   The polynomial jumps at element boundaries, so the integrator is restarted at each of them
//!   (no step straddles a discontinuity of the input). Where the optimal torques saturate,
//!   the polynomial overshoots τ_max between the nodes and the clamp changes the torque;
//!   [`PhaseVerification::max_torque_overshoot`] shows it, and
//!   [`TorqueInterpolant::Polynomial`] integrates the unclamped polynomial instead.
//! * **Each phase starts from its own collocated initial state**: the Free → Stick switch
//!   applies the sticking impact law (eq. 40) with the impulse ι from the NLP parameters, and
//!   phase continuity / periodicity are NLP constraints; they are not re-integrated here.
//! * **Stick phases** use the physical stick dynamics (λ from eq. 33), not the collocated λ:
//!   the check is whether the optimal torques *keep* the contact sticking. bf-model refuses
//!   contact queries beyond |h| ≤ tol·r; the OCP allows h ≤ 10⁻⁴ at the touch-down, so the
//!   verification uses [`CONTACT_TOLERANCE`] and reports max |h| instead.
//! * Defects are absolute (rad, rad/s), max over components: the states are O(0.01–10) rad
//!   and rad/s, so [`VERIFIED_DEFECT`] = 10⁻⁴ is a relative accuracy of about 10⁻⁵–10⁻⁴ on the
//!   largest components, far above the DOPRI5 tolerance (rtol 10⁻¹⁰). An element whose
//!   re-integration fails (model error, step-size underflow) is reported in `failure`, with
//!   NaN defects (written as `null` in JSON); `Verification::max_defect` is then NaN.

use std::time::Instant;

use bf_model::registry;
use bf_model::{ContactVariant, DynKernels, Model, State, TransitionSettings, Vec3, VecN};
use bf_optim::ocp::PhaseTrajectory;
use bf_optim::ocp::nodes::lagrange_basis;
use bf_problem::{BuiltProblem, OcpSolution, PhaseMode};
use bf_sim::{HybridSystem, SimError, SimOutput, SimSettings};

use super::error::{PhaseDataDefect, PipelineError};

use bf_problem::solution::records::ExecutionCheck;
pub use bf_problem::solution::records::{
    ImpactCone, PhaseVerification, TorqueInterpolant, Verification,
};

/// Contact tolerance (fraction of the ball radius) of the stick dynamics during verification.
pub const CONTACT_TOLERANCE: f64 = 0.05;

/// atol = rtol · `ATOL_FACTOR` (states are O(0.1–10) rad, rad/s).
pub const ATOL_FACTOR: f64 = 1e-2;

/// Extra dense-output samples per collocation element for the path checks (h, Δv, λ_n, σ),
/// in addition to the integrator's accepted steps.
pub const SAMPLES_PER_ELEMENT: usize = 16;

/// Settings of [`verify_with`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct VerifySettings {
    /// DOPRI5 relative tolerance, in (0, 0.1].
    pub rtol: f64,
    /// Absolute tolerance (state units); `None`: rtol · [`ATOL_FACTOR`].
    pub atol: Option<f64>,
    /// Torque interpolant.
    pub torque: TorqueInterpolant,
}

impl Default for VerifySettings {
    fn default() -> Self {
        VerifySettings {
            rtol: 1e-10,
            atol: None,
            torque: TorqueInterpolant::Clamped,
        }
    }
}

/// Largest number of joints of a finger the verification re-integrates (one instantiation of
/// the generic model per N = 1..=this, as `simulate` has).
pub const MAX_VERIFY_JOINTS: usize = 7;

/// One collocation element of one phase of an `N`-joint finger as a (single-mode) hybrid
/// system for bf-sim: the torque is the element's control polynomial, clamped to the torque
/// limits.
struct ElementSystem<'a, const N: usize> {
    model: &'a Model<DynKernels<N>, N>,
    /// The same model with the exact contact (the plant's), for [`Touch`].
    exact: &'a Model<DynKernels<N>, N>,
    duration: f64,
    node_tau: Vec<f64>,
    node_u: Vec<[f64; N]>,
    tau_max: [f64; N],
    interp: TorqueInterpolant,
}

impl<const N: usize> ElementSystem<'_, N> {
    /// How far the unclamped polynomial exceeds the torque limits at t (0 inside them).
    fn overshoot(&self, t: f64) -> f64 {
        let s = 2.0 * t / self.duration - 1.0;
        let l = lagrange_basis(&self.node_tau, s);
        (0..N)
            .map(|i| {
                let v: f64 = l.iter().zip(&self.node_u).map(|(w, uk)| w * uk[i]).sum();
                (v.abs() - self.tau_max[i]).max(0.0)
            })
            .fold(0.0, f64::max)
    }

    /// τ(t) at phase-local time t.
    fn torque(&self, t: f64) -> VecN<N> {
        let s = 2.0 * t / self.duration - 1.0;
        let l = lagrange_basis(&self.node_tau, s);
        let mut u = [0.0; N];
        for (i, ui) in u.iter_mut().enumerate() {
            let v: f64 = l.iter().zip(&self.node_u).map(|(w, uk)| w * uk[i]).sum();
            let m = self.tau_max[i];
            // max/min rather than clamp: never panics, whatever the limits are.
            *ui = match self.interp {
                TorqueInterpolant::Clamped => v.max(-m).min(m),
                TorqueInterpolant::Polynomial => v,
            };
        }
        VecN::<N>::from(u)
    }

    /// The exact contact distance h₀ (the plant's, eq. 4 with the exact sat(α) of eq. 3) at
    /// the state `x` (m).
    fn exact_distance(&self, x: &[f64]) -> Result<f64, String> {
        let st = Self::state(x).map_err(|e| e.to_string())?;
        Ok(self
            .exact
            .evaluate(&st)
            .map_err(|e| e.to_string())?
            .contact
            .h)
    }

    fn state(x: &[f64]) -> Result<State<N>, SimError> {
        State::<N>::from_slice(x).ok_or(SimError::DimensionMismatch {
            what: "state",
            expected: State::<N>::DIM,
            found: x.len(),
        })
    }
}

impl<const N: usize> HybridSystem for ElementSystem<'_, N> {
    type Mode = PhaseMode;

    fn dim(&self) -> usize {
        State::<N>::DIM
    }

    fn rhs(&self, mode: PhaseMode, t: f64, x: &[f64], dx: &mut [f64]) -> Result<(), SimError> {
        let st = Self::state(x)?;
        let tau = self.torque(t);
        let acc = match mode {
            PhaseMode::Free => self.model.free(&st, &tau),
            PhaseMode::Stick => self.model.stick(&st, &tau),
        }
        .map_err(SimError::system)?;
        acc.write_state_derivative(&st.qd, dx);
        Ok(())
    }
}

/// max that propagates NaN (`f64::max` drops it, which would hide a failed figure): the fold
/// of every "largest error" that a NaN must fail.
pub fn nan_max(a: f64, b: f64) -> f64 {
    if a.is_nan() || b.is_nan() {
        f64::NAN
    } else {
        a.max(b)
    }
}

/// The bf-model model of `p`'s scene (`N` joints) with the contact `variant` (the smooth
/// contact of the solution's ε, or the exact one for [`Touch`]), after checking that its
/// physical constants are the ones the OCP was built with.
fn verification_model<const N: usize>(
    p: &BuiltProblem,
    variant: ContactVariant,
) -> Result<Model<DynKernels<N>, N>, PipelineError> {
    let settings = TransitionSettings {
        contact_tolerance: CONTACT_TOLERANCE,
        ..TransitionSettings::default()
    };
    let model_err = |source| PipelineError::VerifyModel {
        scene: p.scene.name.clone(),
        source,
    };
    let (kernels, _) = registry::contact_kernels_n::<N>(&p.scene).map_err(model_err)?;
    let model = Model::from_kernels(kernels)
        .map_err(model_err)?
        .with_settings(settings)
        .map_err(model_err)?
        .with_contact_variant(variant)
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
        return Err(PipelineError::ParameterMismatch {
            scene: p.scene.name.clone(),
            model: format!("{pm:?}"),
            ocp: format!("{ph:?}"),
        });
    }
    Ok(model)
}

fn check_phase_data(
    k: usize,
    tr: &PhaseTrajectory,
    nq: usize,
    nx: usize,
) -> Result<(), PipelineError> {
    let bad = |defect| Err(PipelineError::PhaseData { phase: k, defect });
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
    if tr.u.len() != tr.node_tau.len() || tr.u.iter().any(|u| u.len() != nq) {
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
/// The node's algebraic variables are (q̈, ω̇, λ) with λ in stick phases only.
fn node_residual<const N: usize>(
    model: &Model<DynKernels<N>, N>,
    phase: usize,
    mode: PhaseMode,
    tr: &PhaseTrajectory,
) -> Result<f64, PipelineError> {
    let pm = model.params();
    let mut worst: f64 = 0.0;
    for k in 0..tr.node_tau.len() {
        let x = &tr.x[tr.node_state[k]];
        let a = &tr.a[k];
        let need = if mode == PhaseMode::Stick {
            N + 6
        } else {
            N + 3
        };
        if a.len() < need {
            return Err(PipelineError::PhaseData {
                phase,
                defect: PhaseDataDefect::AlgebraicDimension {
                    found: a.len(),
                    mode,
                    need,
                },
            });
        }
        let st = ElementSystem::<N>::state(x)?;
        let kin = model
            .evaluate(&st)
            .map_err(|source| PipelineError::NodeEvaluation {
                phase,
                node: k,
                source,
            })?;
        let qdd = VecN::<N>::from_column_slice(&a[..N]);
        let wd = Vec3::new(a[N], a[N + 1], a[N + 2]);
        let lam = if mode == PhaseMode::Stick {
            Vec3::new(a[N + 3], a[N + 4], a[N + 5])
        } else {
            Vec3::zeros()
        };
        let tau = VecN::<N>::from_column_slice(&tr.u[k][..N]);
        let c = &kin.contact;
        let rf = kin.m_f * qdd + kin.cqd_g + st.qd * pm.mu_v() - tau - c.j_c.transpose() * lam;
        let ib = pm.ball_inertia();
        let w = &st.omega;
        let rb = ib * wd + w.cross(&(ib * w)) + w * pm.socket_damping() + c.r_c.cross(&lam);
        worst = worst.max(rf.amax()).max(rb.amax());
    }
    Ok(worst)
}

/// Running path checks of one element or phase.
#[derive(Clone, Copy)]
struct PathStats {
    min_h: f64,
    /// [`PhaseVerification::smoothing_error`].
    smoothing_error: f64,
    max_dv: f64,
    min_ln: f64,
    max_ln: f64,
    min_sigma: f64,
    max_abs_h: f64,
    overshoot: f64,
}

impl PathStats {
    fn new() -> Self {
        PathStats {
            min_h: f64::INFINITY,
            smoothing_error: 0.0,
            max_dv: 0.0,
            min_ln: f64::INFINITY,
            max_ln: f64::NEG_INFINITY,
            min_sigma: f64::INFINITY,
            max_abs_h: 0.0,
            overshoot: 0.0,
        }
    }

    fn add<const N: usize>(
        &mut self,
        sys: &ElementSystem<'_, N>,
        mode: PhaseMode,
        t: f64,
        x: &[f64],
    ) -> Result<(), String> {
        let st = ElementSystem::<N>::state(x).map_err(|e| e.to_string())?;
        let kin = sys.model.evaluate(&st).map_err(|e| e.to_string())?;
        let h = kin.contact.h;
        self.overshoot = self.overshoot.max(sys.overshoot(t));
        match mode {
            PhaseMode::Free => {
                self.min_h = self.min_h.min(h);
                // Near the ball the smoothed distance the problem bounds stands in for the
                // plant's exact one; how far apart they are there is the smoothing's error in
                // what the plan asserts.
                let exact = sys.exact_distance(x)?;
                let near = NEAR_BALL * sys.model.params().ball_radius();
                if h.min(exact) <= near {
                    self.smoothing_error = nan_max(self.smoothing_error, (exact - h).abs());
                }
            }
            PhaseMode::Stick => {
                let acc = sys
                    .model
                    .stick(&st, &sys.torque(t))
                    .map_err(|e| e.to_string())?;
                self.max_dv = self.max_dv.max(kin.contact.delta_v.norm());
                self.min_ln = self.min_ln.min(acc.force.lambda_n);
                self.max_ln = self.max_ln.max(acc.force.lambda_n);
                self.min_sigma = self.min_sigma.min(acc.force.sigma);
                self.max_abs_h = self.max_abs_h.max(h.abs());
            }
        }
        Ok(())
    }

    /// Folds the checks of another stretch of the same phase into these.
    fn merge(&mut self, o: &PathStats) {
        self.min_h = self.min_h.min(o.min_h);
        self.smoothing_error = nan_max(self.smoothing_error, o.smoothing_error);
        self.max_dv = self.max_dv.max(o.max_dv);
        self.min_ln = self.min_ln.min(o.min_ln);
        self.max_ln = self.max_ln.max(o.max_ln);
        self.min_sigma = self.min_sigma.min(o.min_sigma);
        self.max_abs_h = self.max_abs_h.max(o.max_abs_h);
        self.overshoot = self.overshoot.max(o.overshoot);
    }

    fn add_output<const N: usize>(
        &mut self,
        sys: &ElementSystem<'_, N>,
        mode: PhaseMode,
        out: &SimOutput<PhaseMode>,
    ) -> Result<(), String> {
        for (t, x) in out.trajectory.t.iter().zip(&out.trajectory.x) {
            self.add(sys, mode, *t, x)?;
        }
        Ok(())
    }
}

/// Distance from the ball, in its radii, beyond which a free path counts as clear of it for the
/// touch check ([`touch_failure`]): the penetration allowance, so that the exact distance's
/// wobble about 0 at a touch-down or lift-off is not read as leaving and touching again.
pub const TOUCH_CLEARANCE: f64 = PENETRATION_TOLERANCE;

/// The first touch of a free phase that ends at an impact by the exact contact distance h₀
/// (the plant's): the first sample with h₀ ≤ 0 after one with h₀ > [`TOUCH_CLEARANCE`]. The
/// phase touches at its end, or, if it grazes the ball on its way, earlier, and a plant with
/// the exact contact strikes the ball then (`track`'s first impact came 0.16 s early on a
/// verified plan). Releases are not tracked: the problems allow their paths h ≥ −10⁻⁴ r
/// (the touch-down and release tolerance), which [`penetration_failure`] checks.
#[derive(Clone, Copy)]
struct Touch {
    /// [`TOUCH_CLEARANCE`] in metres.
    clearance: f64,
    clear: bool,
    first: Option<f64>,
}

impl Touch {
    /// No sample yet, for a ball of radius `radius` (m).
    fn new(radius: f64) -> Touch {
        Touch {
            clearance: TOUCH_CLEARANCE * radius,
            clear: false,
            first: None,
        }
    }

    /// Adds the sample at phase-local time `t` of the state `x` (exact h₀ evaluated only until
    /// the first touch).
    fn add<const N: usize>(
        &mut self,
        sys: &ElementSystem<'_, N>,
        t: f64,
        x: &[f64],
    ) -> Result<(), String> {
        if self.first.is_none() {
            self.add_distance(t, sys.exact_distance(x)?);
        }
        Ok(())
    }

    /// Adds the exact distance `h` (m) at phase-local time `t`, samples in time order.
    fn add_distance(&mut self, t: f64, h: f64) {
        if self.first.is_some() {
            return;
        }
        if h > self.clearance {
            self.clear = true;
        } else if h <= 0.0 && self.clear {
            self.first = Some(t);
        }
    }
}

/// The collocation intervals of element `e` of `tr` on [s_start, s_end] (τ): consecutive
/// state points with their collocated states. Radau elements contain both their boundaries
/// as state points; the last Legendre–Gauss element ends at the phase end, the final state
/// point, which is not in its support range.
fn element_points(
    tr: &PhaseTrajectory,
    (a, b): (usize, usize),
    s_start: f64,
    s_end: f64,
    last: bool,
) -> Vec<(f64, Vec<f64>)> {
    let mut pts: Vec<(f64, Vec<f64>)> = (a..b)
        .filter(|&p| tr.state_tau[p] >= s_start && tr.state_tau[p] <= s_end)
        .map(|p| (tr.state_tau[p], tr.x[p].clone()))
        .collect();
    if pts.first().is_none_or(|(t, _)| *t > s_start) {
        pts.insert(0, (s_start, tr.x_at(s_start)));
    }
    if pts.last().is_some_and(|(t, _)| *t < s_end) {
        let x = if last {
            tr.x[tr.x.len() - 1].clone()
        } else {
            tr.x_at(s_end)
        };
        pts.push((s_end, x));
    }
    pts
}

/// Componentwise |x − y| as the max over the q, q̇ and ω parts of the state of an
/// `nq`-joint finger (NaN propagates).
fn part_defects(nq: usize, x: &[f64], y: &[f64]) -> [f64; 3] {
    let mut d = [0.0f64; 3];
    for (i, (xi, yi)) in x.iter().zip(y).enumerate() {
        let part = (i / nq).min(2);
        d[part] = nan_max(d[part], (xi - yi).abs());
    }
    d
}

/// One DOPRI5 run of `sys` from (t0, x0) to t1: the output (the partial one if it failed)
/// and why it failed.
fn integrate<const N: usize>(
    sys: &ElementSystem<'_, N>,
    settings: SimSettings,
    mode: PhaseMode,
    t0: f64,
    x0: &[f64],
    t1: f64,
) -> (SimOutput<PhaseMode>, Option<String>) {
    // The system goes to the simulator as a trait object, so one compiled copy of the simulator
    // serves every joint count (the virtual calls cost nothing beside the kernels they make).
    let sys: &dyn HybridSystem<Mode = PhaseMode> = sys;
    match bf_sim::simulate(sys, settings, mode, t0, x0, t1) {
        Ok(out) => (out, None),
        Err(fail) => {
            let msg = fail.to_string();
            (fail.partial, Some(msg))
        }
    }
}

/// max_i |x_end,i − x_i| of a run that reached its end (steps are recorded, so its last
/// sample is the end state); NaN if it failed.
fn end_defect(nq: usize, out: &SimOutput<PhaseMode>, err: &Option<String>, x: &[f64]) -> [f64; 3] {
    match (err, out.trajectory.x.last()) {
        (None, Some(xe)) => part_defects(nq, xe, x),
        _ => [f64::NAN; 3],
    }
}

fn verify_phase<const N: usize>(
    model: &Model<DynKernels<N>, N>,
    exact: &Model<DynKernels<N>, N>,
    tau_max: [f64; N],
    k: usize,
    mode: PhaseMode,
    tr: &PhaseTrajectory,
    rtol: f64,
    atol: f64,
    interp: TorqueInterpolant,
    ends_at_impact: bool,
    radius: f64,
) -> Result<PhaseVerification, PipelineError> {
    let big_t = tr.duration;
    // The first and last state points are τ = −1 and +1 in both schemes (LG: the final state
    // is the quadrature variable, which interpolation of the element would miss).
    let x_start = tr.x[0].clone();
    let x_colloc_end = tr.x[tr.x.len() - 1].clone();
    let node_residual = node_residual(model, k, mode, tr)?;
    let time = |s: f64| 0.5 * (s + 1.0) * big_t;
    let mut stats = PathStats::new();
    let mut touch = Touch::new(radius);
    let (mut steps, mut rejected, mut rhs) = (0, 0, 0);
    let mut failure: Option<(f64, String)> = None;
    let mut parts = [0.0f64; 3];
    let mut element_defects = Vec::with_capacity(tr.elements.len());
    let mut element_min_h = Vec::with_capacity(tr.elements.len());
    let mut element_min_sigma = Vec::with_capacity(tr.elements.len());
    let mut interval_defect = 0.0f64;
    let mut x_open = x_start.clone();
    let mut open_loop_failure = None;
    let mut s_prev = -1.0;
    let ne = tr.elements.len();
    for (e, &(a, b)) in tr.elements.iter().enumerate() {
        let last = e + 1 == ne;
        let s_end = if last { 1.0 } else { tr.state_tau[b - 1] };
        let s_start = s_prev;
        let (ta, tb) = (time(s_start), time(s_end));
        s_prev = s_end;
        if tb <= ta {
            element_defects.push(0.0);
            element_min_h.push(f64::NAN);
            element_min_sigma.push(f64::NAN);
            continue;
        }
        let ks: Vec<usize> = (0..tr.node_tau.len())
            .filter(|&j| (a..b).contains(&tr.node_state[j]))
            .collect();
        if ks.is_empty() {
            return Err(PipelineError::PhaseData {
                phase: k,
                defect: PhaseDataDefect::EmptyElement(e),
            });
        }
        let sys = ElementSystem {
            model,
            exact,
            duration: big_t,
            node_tau: ks.iter().map(|&j| tr.node_tau[j]).collect(),
            node_u: ks
                .iter()
                .map(|&j| std::array::from_fn(|i| tr.u[j][i]))
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
        let pts = element_points(tr, (a, b), s_start, s_end, last);
        let (x_a, x_b) = (&pts[0].1, &pts[pts.len() - 1].1);
        // The verification: the element alone, from its collocated start state, with the path
        // checks along it.
        let (out, err) = integrate(&sys, settings.clone(), mode, ta, x_a, tb);
        steps += out.stats.accepted_steps;
        rejected += out.stats.rejected_steps;
        rhs += out.stats.rhs_evals;
        // The path checks of this element alone (min h, min σ for the refinement), then
        // folded into the phase's.
        let mut el = PathStats::new();
        let mut path = el.add_output(&sys, mode, &out);
        if ends_at_impact && path.is_ok() {
            path = out
                .trajectory
                .t
                .iter()
                .zip(&out.trajectory.x)
                .try_for_each(|(t, x)| touch.add(&sys, *t, x));
        }
        let measured = err.is_none() && path.is_ok();
        element_min_h.push(if measured { el.min_h } else { f64::NAN });
        element_min_sigma.push(if measured { el.min_sigma } else { f64::NAN });
        stats.merge(&el);
        let d = end_defect(N, &out, &err, x_b);
        match err.or(path.err()) {
            Some(msg) => {
                failure.get_or_insert((out.t_final, format!("element {e}: {msg}")));
                element_defects.push(f64::NAN);
            }
            None => {
                for (p, di) in parts.iter_mut().zip(d) {
                    *p = nan_max(*p, di);
                }
                element_defects.push(d.into_iter().fold(0.0, nan_max));
            }
        }
        let plain = SimSettings {
            output_dt: None,
            ..settings
        };
        // Informative: every collocation interval from its collocated start state ...
        for w in pts.windows(2) {
            let ((s0, x0), (s1, x1)) = (&w[0], &w[1]);
            let (t0, t1) = (time(*s0), time(*s1));
            if t1 > t0 {
                let (out, err) = integrate(&sys, plain.clone(), mode, t0, x0, t1);
                let d = end_defect(N, &out, &err, x1);
                interval_defect = d.into_iter().fold(interval_defect, nan_max);
            }
        }
        // ... and the open-loop replay, one integration through the whole phase.
        if open_loop_failure.is_none() {
            let (out, err) = integrate(&sys, plain, mode, ta, &x_open, tb);
            match (err, out.trajectory.x.last()) {
                (None, Some(xl)) => x_open.clone_from(xl),
                (err, _) => {
                    open_loop_failure = Some(format!(
                        "element {e}: {}",
                        err.unwrap_or_else(|| "no state".into())
                    ));
                }
            }
        }
    }
    let failed = failure.is_some();
    let [dq, dqd, dw] = parts.map(|v| if failed { f64::NAN } else { v });
    let open_loop_defect = if open_loop_failure.is_some() {
        f64::NAN
    } else {
        part_defects(N, &x_open, &x_colloc_end)
            .into_iter()
            .fold(0.0, nan_max)
    };
    let (t_reached, failure) = match failure {
        Some((t, msg)) => (t, Some(msg)),
        None => (big_t, None),
    };
    let stick = mode == PhaseMode::Stick;
    let finite_or_none = |v: f64, on: bool| (on && v.is_finite()).then_some(v);
    Ok(PhaseVerification {
        phase: k,
        mode,
        duration: big_t,
        t_reached,
        failure,
        defect: nan_max(nan_max(dq, dqd), dw),
        defect_q: dq,
        defect_qd: dqd,
        defect_omega: dw,
        element_defects,
        interval_defect,
        open_loop_defect,
        open_loop_failure,
        x_start,
        x_end: x_open,
        x_colloc_end,
        steps,
        rejected_steps: rejected,
        rhs_evals: rhs,
        rtol,
        atol,
        node_residual,
        max_torque_overshoot: stats.overshoot,
        min_h: finite_or_none(stats.min_h, !stick),
        element_min_h: if stick { Vec::new() } else { element_min_h },
        first_touch: touch.first,
        smoothing_error: finite_or_none(stats.smoothing_error, !stick && !failed),
        max_delta_v: finite_or_none(stats.max_dv, stick),
        min_lambda_n: finite_or_none(stats.min_ln, stick),
        max_lambda_n: finite_or_none(stats.max_ln, stick),
        min_sigma: finite_or_none(stats.min_sigma, stick),
        element_min_sigma: if stick { element_min_sigma } else { Vec::new() },
        max_abs_h: finite_or_none(stats.max_abs_h, stick),
    })
}

/// Largest element-wise re-integration defect (state units) at which a solution counts as
/// verified: above it, the collocation solution does not describe what the hybrid model does
/// with its torques, and every place that shows the solution flags it.
pub const VERIFIED_DEFECT: f64 = 1e-4;

/// Penetration the re-integrated path may show, in radii of the ball
/// ([`Verification::radius`]; 0.1 mm on the paper's ball of 1 m): the problem's own
/// allowance h ≥ −10⁻⁴ r at the touch-down and release (the tolerance on h of the periodic
/// problems in bf-problem's catalogue). The optimum satisfies its distance bounds at the collocation nodes only, and
/// the re-integration follows the model within [`VERIFIED_DEFECT`], so min h is reported
/// against this, not against 0.
pub const PENETRATION_TOLERANCE: f64 = 1e-4;

/// Distance from the ball, in its radii, within which a free path's smoothed and exact contact
/// distances are compared ([`PhaseVerification::smoothing_error`]): 1 cm on the paper's ball,
/// a hundred penetration allowances. Farther away the two may differ (the smoothing rounds
/// the link's ends) without a plant touching the ball.
pub const NEAR_BALL: f64 = 1e-2;

/// Friction-cone margin the re-integrated stick phases may show, as a fraction of the cone's
/// size μ_s max λ_n of the phase: the optimum satisfies σ = μ_s λ_n − ‖λ_∥‖ ≥ 0 (eq. 18) at
/// its collocation nodes only; between them the torques are interpolated and the
/// re-integration computes λ from the stick law (eq. 33) on a state that is off the collocated
/// one by up to [`VERIFIED_DEFECT`]. Margins down to −1 % of the cone pass; a lower one
/// fails the verification ([`path_failure`]).
pub const CONE_TOLERANCE: f64 = 0.01;

/// The rounding a friction-cone margin may show whatever μ_s, as a fraction of the normal
/// force (or impulse): with μ_s = 0 the cone is the normal direction alone, and the tangential
/// force an accurate solve leaves is its rounding, not a slip.
pub const CONE_ROUNDING: f64 = 1e-6;

/// Whether `sol` carries a re-integration that reached the end of every element with an
/// element-wise defect of at most [`VERIFIED_DEFECT`] and no path check outside its
/// allowance ([`path_failure`]).
pub fn is_verified(sol: &OcpSolution) -> bool {
    sol.verification.as_ref().is_some_and(passes)
}

/// The verdict of a verification record: completed, defect ≤ [`VERIFIED_DEFECT`], path
/// checks within their allowances and, where one ran, the plan executed in closed loop
/// ([`execution_failure`]).
pub fn passes(v: &Verification) -> bool {
    v.completed()
        && v.max_defect.is_finite()
        && v.max_defect <= VERIFIED_DEFECT
        && verdict_failure(v).is_none()
}

/// Why the verification record `v` does not pass ([`passes`]), as a phrase for the places that
/// show an unverified solution (`optimize`'s error, the reports): the verdict's own failure
/// ([`verdict_failure`]) where every element reached its end within [`VERIFIED_DEFECT`],
/// otherwise the defect against the tolerance and whether a phase stopped short. `None` when
/// it passes.
pub fn unverified_reason(v: &Verification) -> Option<String> {
    if passes(v) {
        return None;
    }
    Some(match verdict_failure(v) {
        Some(why) if v.passes(VERIFIED_DEFECT) => why,
        _ => format!(
            "its re-integration defect {:.3e} exceeds {VERIFIED_DEFECT:e}{}",
            v.max_defect,
            if v.completed() {
                ""
            } else {
                " (a phase could not be re-integrated to its end)"
            }
        ),
    })
}

/// Why `v` fails its verdict other than by its defects: the first path check outside its
/// allowance ([`path_failure`]), else a closed-loop execution that failed
/// ([`execution_failure`]), else a closed-loop execution that the search did not run because
/// the plan could not have been chosen ([`Verification::not_executed`]).
pub fn verdict_failure(v: &Verification) -> Option<String> {
    path_failure(v)
        .or_else(|| impulse_cone_failure(v))
        .or_else(|| execution_failure(v))
        .or_else(|| {
            v.not_executed
                .as_ref()
                .map(|why| format!("not run in closed loop: {why}"))
        })
}

/// The failure of `v`'s closed-loop execution on the nominal plant
/// ([`Verification::execution`]), as a sentence naming the controller and the error, if one
/// ran and failed.
pub fn execution_failure(v: &Verification) -> Option<String> {
    closed_loop(v, |e| e.failure.as_ref()).map(|s| format!("executed {s}"))
}

/// "in closed loop (C controller, Newton's impact law): WHY" for the reason `why` picks from
/// `v`'s closed-loop check, if one ran and `why` gives a reason.
fn closed_loop(
    v: &Verification,
    why: impl Fn(&ExecutionCheck) -> Option<&String>,
) -> Option<String> {
    let e = v.execution.as_ref()?;
    let why = why(e)?;
    Some(format!(
        "in closed loop ({} controller, Newton's impact law): {why}",
        e.controller
    ))
}

/// The robustness miss of `v`'s closed-loop execution: a perturbed plant of the robustness
/// table beyond its target, as a sentence naming the controller and the plant, if the
/// perturbed plants ran and one missed. It does not fail the verdict ([`passes`]): the plan
/// is executed on the plant it was planned for, and what the miss measures is the
/// controller's margin against model error (the low `periodic-cot` plans are executed within
/// 0.2 % on the nominal plant and missed by 100 % and more with 50 % more socket damping).
/// The search ranks such a plan below every verified plan that meets the target (decision
/// record 0048), and `optimize` flags it.
pub fn robustness_miss(v: &Verification) -> Option<String> {
    closed_loop(v, |e| e.robustness_failure.as_ref())
}

/// Whether `v` records a robustness miss ([`robustness_miss`], without its sentence).
fn misses_robustness(v: &Verification) -> bool {
    v.execution
        .as_ref()
        .is_some_and(|e| e.robustness_failure.is_some())
}

/// Whether `sol` is verified ([`is_verified`]) and, where the perturbed plants ran, meets the
/// robustness target on every one ([`robustness_miss`]).
pub fn is_robust(sol: &OcpSolution) -> bool {
    is_verified(sol) && !sol.verification.as_ref().is_some_and(misses_robustness)
}

/// The first path check of `v` outside its allowance, as a sentence naming the phase, the
/// quantity, its value and the allowance: a free phase that penetrates the ball
/// ([`penetration_failure`]), else a stick phase that slips ([`cone_failure`]). The
/// collocation imposes both bounds at its nodes only; between them a path can break them
/// although every node and every element end agree with the model, so the element-wise
/// defect alone would call such an optimum verified.
pub fn path_failure(v: &Verification) -> Option<String> {
    penetration_failure(v)
        .or_else(|| touch_failure(v))
        .or_else(|| cone_failure(v))
}

/// How far the worst path check of `v` is outside its allowance, in units of the allowance:
/// the deepest penetration of a free phase over [`PENETRATION_TOLERANCE`] and the lowest cone
/// margin of a stick phase over its [`cone_allowance`] (as −min h / tol and −min σ /
/// allowance), 0 when no path check goes below zero; above 1 exactly when [`path_failure`]
/// names a failure of a check that a finer mesh changes. The refinement ([`super::search`])
/// stops refining a candidate whose only failure is a path check that a refinement did not
/// bring closer. The smoothing's error ([`PhaseVerification::smoothing_error`]) is left out:
/// it measures the smoothing ε, not the mesh.
pub fn path_excess(v: &Verification) -> f64 {
    let touch = v
        .phases
        .iter()
        .filter_map(touch_lead)
        .map(|(lead, allowance)| lead / allowance)
        .fold(0.0, f64::max);
    excess_of(
        v.phases
            .iter()
            .filter(|p| p.mode == PhaseMode::Free)
            .filter_map(|p| p.min_h),
        PENETRATION_TOLERANCE * v.radius,
        worst_cone_margin(v),
    )
    .max(touch)
}

/// How long before the end of its free phase a plant with the exact contact would touch the
/// ball (s) may be, as a fraction of the phase's duration: a plan whose path only touches at
/// its impact has no touch at all along its re-integration ([`PhaseVerification::first_touch`]
/// is `None` on every default optimum), a path that grazes the ball on its way touches
/// 2–30 % of the phase early (BENCHMARKS.md, "Plans that graze the ball").
pub const TOUCH_LEAD_TOLERANCE: f64 = 0.01;

/// The lead of `p`'s first touch ([`PhaseVerification::first_touch`]) before the phase's
/// end and its allowance ([`TOUCH_LEAD_TOLERANCE`] · duration), both in s, for a free phase
/// that touches.
fn touch_lead(p: &PhaseVerification) -> Option<(f64, f64)> {
    let t = p.first_touch.filter(|_| p.mode == PhaseMode::Free)?;
    let allowance = TOUCH_LEAD_TOLERANCE * p.duration;
    Some(((p.duration - t).max(0.0), allowance.max(f64::MIN_POSITIVE)))
}

/// The first free phase of `v` whose path touches the ball by the exact contact (the plant's)
/// more than [`TOUCH_LEAD_TOLERANCE`] of its duration before its end, as a sentence naming the
/// phase, the time and the allowance: the smoothed contact (eq. 58–59) keeps such a path a
/// few µm clear of the ball, so its nodes and its min h pass, but a plant strikes the ball
/// there instead of at the planned impact.
pub fn touch_failure(v: &Verification) -> Option<String> {
    v.phases.iter().find_map(|p| {
        let (lead, allowance) = touch_lead(p)?;
        (lead > allowance).then(|| {
            format!(
                "phase {} (free): the path touches the ball with the exact contact (the \
                 plant's) at t = {:.4} s, {lead:.4} s before the phase ends (allowance {:.0} % \
                 of its {:.4} s)",
                p.phase + 1,
                p.duration - lead,
                100.0 * TOUCH_LEAD_TOLERANCE,
                p.duration
            )
        })
    })
}

/// [`path_excess`] of the free phases' min h `min_h` against the penetration allowance `tol`
/// (m) and of the worst cone margin `cone`.
fn excess_of(min_h: impl Iterator<Item = f64>, tol: f64, cone: Option<ConeMargin>) -> f64 {
    let pen = min_h.map(|h| -h / tol).fold(0.0, f64::max);
    let cone = cone.map_or(0.0, |m| -m.relative());
    pen.max(cone).max(0.0)
}

/// The first free phase of `v` whose re-integrated path penetrates the ball deeper than
/// [`PENETRATION_TOLERANCE`] radii (min h < −10⁻⁴ r), as a sentence naming the phase, min h
/// and the allowance: a long free phase that grazes the ball can sag into it between its nodes.
/// A free phase is also judged by the smoothing's error in the distance near the ball
/// ([`PhaseVerification::smoothing_error`], against the same allowance): with a coarse
/// smoothing ε the smoothed distance the problem bounds can keep a path clear of a ball that
/// the plant's finger, with the exact contact, enters.
pub fn penetration_failure(v: &Verification) -> Option<String> {
    let tol = PENETRATION_TOLERANCE * v.radius;
    v.phases.iter().find_map(|p| {
        if p.mode != PhaseMode::Free {
            return None;
        }
        if let Some(h) = p.min_h.filter(|&h| h < -tol) {
            return Some(format!(
                "phase {} (free): the re-integrated path penetrates the ball, min h = {h:.3e} m \
                 below the allowance -{tol:e} m",
                p.phase + 1
            ));
        }
        smoothing_failure_of(p, tol)
    })
}

/// The first free phase of `v` whose smoothing error near the ball
/// ([`PhaseVerification::smoothing_error`]) exceeds the penetration allowance, as a sentence:
/// the part of [`penetration_failure`] that no finer mesh changes, since it measures the
/// smoothing ε.
pub fn smoothing_failure(v: &Verification) -> Option<String> {
    let tol = PENETRATION_TOLERANCE * v.radius;
    v.phases
        .iter()
        .filter(|p| p.mode == PhaseMode::Free)
        .find_map(|p| smoothing_failure_of(p, tol))
}

fn smoothing_failure_of(p: &PhaseVerification, tol: f64) -> Option<String> {
    let e = p.smoothing_error.filter(|&e| e > tol)?;
    Some(format!(
        "phase {} (free): near the ball the exact contact distance (the plant's) differs from \
         the smoothed one the problem bounds by {e:.3e} m, more than the allowance {tol:e} m: \
         the smoothing ε is too coarse for this path (a smaller --epsilon)",
        p.phase + 1
    ))
}

/// The friction-cone margin of one re-integrated stick phase against its allowance.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ConeMargin {
    /// Phase index, 0-based (text for readers counts phases from 1).
    pub phase: usize,
    /// min σ = μ_s λ_n − ‖λ_∥‖ along the phase's re-integration (N).
    pub min_sigma: f64,
    /// The margin the phase may show: min σ ≥ −`allowance` passes (N).
    pub allowance: f64,
}

impl ConeMargin {
    /// Whether min σ is within the allowance.
    pub fn within(&self) -> bool {
        self.min_sigma >= -self.allowance
    }

    /// min σ in units of the allowance (< −1: outside it); the order in which phases are
    /// worse.
    fn relative(&self) -> f64 {
        if self.allowance > 0.0 {
            self.min_sigma / self.allowance
        } else if self.min_sigma >= 0.0 {
            0.0
        } else {
            f64::NEG_INFINITY
        }
    }
}

/// ([`CONE_TOLERANCE`] · μ_s + [`CONE_ROUNDING`]) · max λ_n (N): the margin σ a stick phase
/// whose re-integrated normal force peaks at `max_lambda_n` may show (0 if the force never
/// pushes); of an impulse, with its normal part ι·n for `max_lambda_n` (N s).
pub fn cone_allowance(mu_s: f64, max_lambda_n: f64) -> f64 {
    (CONE_TOLERANCE * mu_s + CONE_ROUNDING) * max_lambda_n.max(0.0)
}

/// The cone margin of every stick phase of `v` that has one (the record holds μ_s, and the
/// phase min σ and max λ_n; older files hold neither), in phase order.
pub fn cone_margins(v: &Verification) -> Vec<ConeMargin> {
    if !v.mu_s.is_finite() {
        return Vec::new();
    }
    v.phases
        .iter()
        .filter(|p| p.mode == PhaseMode::Stick)
        .filter_map(|p| {
            Some(ConeMargin {
                phase: p.phase,
                min_sigma: p.min_sigma?,
                allowance: cone_allowance(v.mu_s, p.max_lambda_n?),
            })
        })
        .collect()
}

/// The stick phase of `v` whose margin is lowest relative to its allowance (the first of
/// equals): outside its allowance iff some phase is.
pub fn worst_cone_margin(v: &Verification) -> Option<ConeMargin> {
    cone_margins(v)
        .into_iter()
        .reduce(|a, b| if b.relative() < a.relative() { b } else { a })
}

/// The stick phase of `v` that slips most beyond its allowance ([`worst_cone_margin`]), as a
/// sentence naming the phase, min σ and the allowance: between the nodes the interpolated
/// torques can push the contact force out of the friction cone (eq. 18), which the
/// collocation bounds at its nodes only.
pub fn cone_failure(v: &Verification) -> Option<String> {
    let m = worst_cone_margin(v)?;
    (!m.within()).then(|| {
        format!(
            "phase {} (stick): the re-integrated contact force leaves the friction cone, min σ = \
             {:.3e} N below the allowance -{:.3e} N (({CONE_TOLERANCE} μ_s + {CONE_ROUNDING:e}) · max λ_n)",
            m.phase + 1,
            m.min_sigma,
            m.allowance
        )
    })
}

/// An element error of the refinement for a path check outside its allowance: the excess
/// `value` (> `allowance` > 0, in the check's units) as a multiple of the allowance times
/// [`VERIFIED_DEFECT`] (state units), so that such an element is refined like one whose
/// defect exceeds the verification's tolerance by that factor (more nodes impose the bound,
/// h ≥ −10⁻⁴ r or σ ≥ 0, at more points along it). A zero allowance counts as
/// [`FAILED_ELEMENT_ERROR`].
fn excess_error(value: f64, allowance: f64) -> f64 {
    if allowance > 0.0 {
        VERIFIED_DEFECT * value / allowance
    } else {
        FAILED_ELEMENT_ERROR
    }
}

/// Element error of the refinement for an element whose re-integration failed (state
/// units): large enough that the ph rule splits the element, finite so that it does.
pub const FAILED_ELEMENT_ERROR: f64 = 1.0;

/// The element-wise defects of `sol` ([`verify`] at `rtol`) per phase and element, as the
/// element errors of a mesh refinement ([`super::refine::RefineCriterion::Reintegration`]);
/// an element whose re-integration failed counts as [`FAILED_ELEMENT_ERROR`], one whose free
/// path penetrates the ball deeper than [`PENETRATION_TOLERANCE`] or whose stick path leaves
/// the friction cone by more than its phase's [`cone_allowance`] at least as its
/// `excess_error`.
pub fn element_errors(
    p: &BuiltProblem,
    sol: &OcpSolution,
    rtol: f64,
) -> Result<Vec<Vec<f64>>, PipelineError> {
    let v = verify(p, sol, rtol)?;
    Ok(record_element_errors(&v))
}

/// The element errors of [`element_errors`] from the verification record `v`: per phase and
/// element, the element defect, raised where the element's min h or min σ is outside its
/// allowance (`excess_error`), [`FAILED_ELEMENT_ERROR`] where the element failed.
pub fn record_element_errors(v: &Verification) -> Vec<Vec<f64>> {
    let margins = cone_margins(v);
    v.phases
        .iter()
        .map(|ph| {
            let at = |xs: &[f64], e: usize| xs.get(e).copied().unwrap_or(f64::INFINITY);
            let cone = margins
                .iter()
                .find(|m| m.phase == ph.phase)
                .map_or(f64::INFINITY, |m| m.allowance);
            ph.element_defects
                .iter()
                .enumerate()
                .map(|(e, &d)| {
                    if d.is_nan() {
                        return FAILED_ELEMENT_ERROR;
                    }
                    let h = at(&ph.element_min_h, e);
                    let sigma = at(&ph.element_min_sigma, e);
                    let mut err = d;
                    if h < -PENETRATION_TOLERANCE {
                        err = err.max(excess_error(-h, PENETRATION_TOLERANCE));
                    }
                    if cone.is_finite() && sigma < -cone {
                        err = err.max(excess_error(-sigma, cone));
                    }
                    err
                })
                .collect()
        })
        .collect()
}

/// [`verify_with`] at `rtol` with atol = rtol · [`ATOL_FACTOR`] and the clamped torque
/// interpolant of the dense output / `torques.csv`.
pub fn verify(
    p: &BuiltProblem,
    sol: &OcpSolution,
    rtol: f64,
) -> Result<Verification, PipelineError> {
    verify_with(
        p,
        sol,
        &VerifySettings {
            rtol,
            ..VerifySettings::default()
        },
    )
}

/// Re-integrates every collocation element of `sol` (a solution of `p`) from its collocated
/// start state with the solution's torques, by DOPRI5 on bf-model's free / stick dynamics
/// with the smooth contact of ε = `sol.epsilon`, and reports the element-wise defects and
/// path checks, and the collocation-interval and open-loop figures (see the module docs).
///
/// Errors: tolerances out of range (rtol ∉ (0, 0.1], atol ≤ 0); a solution that does not
/// match `p` (phase count, modes, ε, dimensions); non-finite solution data; a scene without a
/// bf-model counterpart or whose constants differ from the OCP's. A re-integration that breaks
/// down part-way is *not* an error: it is reported in that phase's `failure` (an element) or
/// `open_loop_failure`.
pub fn verify_with(
    p: &BuiltProblem,
    sol: &OcpSolution,
    opt: &VerifySettings,
) -> Result<Verification, PipelineError> {
    let start = Instant::now();
    let rtol = opt.rtol;
    if !(bf_sim::MIN_RTOL..=bf_sim::MAX_RTOL).contains(&rtol) {
        return Err(PipelineError::InvalidOption {
            name: "verification rtol",
            value: rtol,
            expected: "in [1e-14, 0.1] (bf_sim::MIN_RTOL to MAX_RTOL)",
        });
    }
    let atol = opt.atol.unwrap_or(rtol * ATOL_FACTOR);
    if !(atol.is_finite() && atol > 0.0) {
        return Err(PipelineError::InvalidOption {
            name: "verification atol",
            value: atol,
            expected: "finite and > 0",
        });
    }
    if sol.raw.len() != p.modes.len() || sol.modes != p.modes {
        return Err(PipelineError::ModeMismatch {
            solution: sol.modes.clone(),
            problem: p.modes.clone(),
        });
    }
    let eps = sol.epsilon;
    if !(eps.is_finite() && eps > 0.0) || (eps - p.epsilon).abs() > 1e-12 * p.epsilon.abs() {
        return Err(PipelineError::EpsilonMismatch {
            solution: eps,
            problem: p.epsilon,
        });
    }
    let (phases, impacts) = match p.physics.nq {
        1 => verify_phases::<1>(p, sol, opt, atol)?,
        2 => verify_phases::<2>(p, sol, opt, atol)?,
        3 => verify_phases::<3>(p, sol, opt, atol)?,
        4 => verify_phases::<4>(p, sol, opt, atol)?,
        5 => verify_phases::<5>(p, sol, opt, atol)?,
        6 => verify_phases::<6>(p, sol, opt, atol)?,
        7 => verify_phases::<7>(p, sol, opt, atol)?,
        joints => {
            return Err(PipelineError::VerifyJoints {
                scene: p.scene.name.clone(),
                joints,
                max: MAX_VERIFY_JOINTS,
            });
        }
    };
    let fold = |f: &dyn Fn(&PhaseVerification) -> f64| phases.iter().map(f).fold(0.0, nan_max);
    let max_defect = fold(&|p| p.defect);
    let max_interval_defect = fold(&|p| p.interval_defect);
    let max_open_loop_defect = fold(&|p| p.open_loop_defect);
    let max_node_residual = fold(&|p| p.node_residual);
    let mut v = Verification {
        tolerance: VERIFIED_DEFECT,
        verified: false,
        problem: sol.problem.clone(),
        scene: p.scene.name.clone(),
        epsilon: eps,
        torque: opt.torque,
        rtol,
        atol,
        max_defect,
        max_interval_defect,
        max_open_loop_defect,
        max_node_residual,
        mu_s: p.physics.mu_s,
        radius: p.physics.radius,
        phases,
        seconds: start.elapsed().as_secs_f64(),
        execution: None,
        not_executed: None,
        impacts,
    };
    v.verified = passes(&v);
    Ok(v)
}

/// The phase verifications and the impacts' cone records of [`verify_with`] for a finger of
/// `N` joints (tolerances, modes and ε checked by the caller).
fn verify_phases<const N: usize>(
    p: &BuiltProblem,
    sol: &OcpSolution,
    opt: &VerifySettings,
    atol: f64,
) -> Result<(Vec<PhaseVerification>, Vec<ImpactCone>), PipelineError> {
    let eps = sol.epsilon;
    let model = verification_model::<N>(p, ContactVariant::Smooth(eps))?;
    let exact = verification_model::<N>(p, ContactVariant::Exact)?;
    let mut tau_max = [f64::INFINITY; N];
    for (t, m) in tau_max.iter_mut().zip(&p.physics.tau_max) {
        if !m.is_nan() {
            *t = m.abs();
        }
    }
    let mut phases = Vec::with_capacity(sol.raw.len());
    for (k, tr) in sol.raw.iter().enumerate() {
        check_phase_data(k, tr, N, State::<N>::DIM)?;
        phases.push(verify_phase(
            &model,
            &exact,
            tau_max,
            k,
            sol.modes[k],
            tr,
            opt.rtol,
            atol,
            opt.torque,
            // A free phase before a stick phase ends at an impact; its path must reach the
            // ball there only ([`Touch`]). A release may come back within the problem's
            // allowance h ≥ −10⁻⁴ r, which the penetration check holds it to.
            sol.modes[k] == PhaseMode::Free && sol.modes.get(k + 1) == Some(&PhaseMode::Stick),
            p.physics.radius,
        )?);
    }
    let impacts = impact_cones(&model, p, sol)?;
    Ok((phases, impacts))
}

/// The cone record ([`ImpactCone`]) of every free → stick switch of `sol`: the plan's impulse ι
/// (its NLP parameters, three per impact in phase order) against the contact normal n of
/// `model` at the stick phase's collocated first configuration, where the impact happens.
fn impact_cones<const N: usize>(
    model: &Model<DynKernels<N>, N>,
    p: &BuiltProblem,
    sol: &OcpSolution,
) -> Result<Vec<ImpactCone>, PipelineError> {
    let switches = (0..sol.modes.len().saturating_sub(1))
        .filter(|&k| sol.modes[k] == PhaseMode::Free && sol.modes[k + 1] == PhaseMode::Stick);
    let mut impacts = Vec::new();
    // The state at the first (`first`) or last point of phase `k`.
    let state = |k: usize, first: bool| {
        let xs = &sol.raw[k].x;
        let x = if first { xs.first() } else { xs.last() };
        x.and_then(|x| State::<N>::from_slice(x))
            .ok_or(PipelineError::Unrecomputable(format!(
                "phase {} has no {} state of {} values",
                k + 1,
                if first { "first" } else { "last" },
                State::<N>::DIM
            )))
    };
    for (k, iota) in switches.zip(sol.impulse.chunks_exact(3)) {
        let (pre, x) = (state(k, false)?, state(k + 1, true)?);
        let geometry = |x: &State<N>| {
            model
                .evaluate(x)
                .map(|k| k.contact)
                .map_err(|source| PipelineError::VerifyModel {
                    scene: p.scene.name.clone(),
                    source,
                })
        };
        let n = geometry(&x)?.n;
        let impact_speed = -geometry(&pre)?.normal_velocity();
        let impulse = [iota[0], iota[1], iota[2]];
        let normal = impulse[0] * n[0] + impulse[1] * n[1] + impulse[2] * n[2];
        let tangential = (0..3)
            .map(|i| (impulse[i] - normal * n[i]).powi(2))
            .sum::<f64>()
            .sqrt();
        impacts.push(ImpactCone {
            phase: k,
            impulse,
            normal,
            tangential,
            margin: p.physics.mu_s * normal - tangential,
            impact_speed,
            imposed: p.settings.impulse_cone,
        });
    }
    Ok(impacts)
}

/// Whether the impulse of the impact `c` leaves the friction cone of `mu_s` (eq. 66): its
/// margin μ_s ι·n − ‖ι_∥‖ below −[`cone_allowance`] of ι·n, the allowance of the stick
/// phases' forces. One test for the verdict of an imposed cone ([`impulse_cone_failure`]),
/// the flag of an unimposed one ([`impulse_cone_warning`]) and the report's table.
pub fn outside_impulse_cone(mu_s: f64, c: &ImpactCone) -> bool {
    c.margin < -cone_allowance(mu_s, c.normal)
}

/// The first impact of `v` that imposed the impulse cone (eq. 66) and leaves it
/// ([`outside_impulse_cone`]), as a sentence naming the phase, the margin and the allowance.
/// The cone is a point constraint of the NLP, so only an inaccurate solve breaks it.
pub fn impulse_cone_failure(v: &Verification) -> Option<String> {
    v.impacts
        .iter()
        .find(|c| c.imposed && outside_impulse_cone(v.mu_s, c))
        .map(|c| {
            format!(
                "the impact at the end of phase {} leaves the impulse cone it imposed (eq. 66): \
                 mu_s iota.n - |iota_t| = {:.3e} N s below the allowance -{:.3e} N s",
                c.phase + 1,
                c.margin,
                cone_allowance(v.mu_s, c.normal)
            )
        })
}

/// The first impact of `v` whose impulse needs more static friction than μ_s (eq. 66) and
/// whose problem did not impose the cone, as a sentence for the places that show the plan
/// (a flag, not a failure of the verdict: the paper's problems leave the cone out, Sect. 7).
pub fn impulse_cone_warning(v: &Verification) -> Option<String> {
    v.impacts
        .iter()
        .find(|c| !c.imposed && outside_impulse_cone(v.mu_s, c))
        .map(|c| {
            format!(
                "the impact at the end of phase {} needs static friction {} against mu_s = {} \
                 (|iota_t| / iota.n, eq. 66): a real contact would slip there; \
                 `optimize --impulse-cone` imposes the cone",
                c.phase + 1,
                fmt_friction(c.friction_needed()),
                v.mu_s
            )
        })
}

/// A friction coefficient as text: three significant digits, `inf` when no friction holds.
fn fmt_friction(mu: f64) -> String {
    if mu.is_finite() {
        format!("{mu:.3}")
    } else {
        "inf (the impulse does not push)".into()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The path-check excess is above 1 exactly when a path check fails by the verdict's own
    /// rules (min h below −[`PENETRATION_TOLERANCE`], or a cone margin outside its allowance),
    /// scales with the violation, and is 0 when nothing goes below zero.
    #[test]
    fn path_excess_is_above_one_exactly_when_a_path_check_fails() {
        let tol = PENETRATION_TOLERANCE;
        for h in [1e-3, 0.0, -0.5 * tol, -tol, -1.01 * tol, -3.0 * tol] {
            for (sigma, allowance) in [
                (0.1, 1e-3),
                (-0.5e-3, 1e-3),
                (-1e-3, 1e-3),
                (-2e-3, 1e-3),
                (-1e-6, 0.0),
                (0.0, 0.0),
            ] {
                let m = ConeMargin {
                    phase: 1,
                    min_sigma: sigma,
                    allowance,
                };
                let e = excess_of([h, 1e-2].into_iter(), tol, Some(m));
                let fails = h < -tol || !m.within();
                assert_eq!(
                    e > 1.0,
                    fails,
                    "h {h}, sigma {sigma}, allowance {allowance}: {e}"
                );
                assert!(e >= 0.0);
                if h <= 0.0 && allowance > 0.0 {
                    let want = (-h / tol).max(-sigma / allowance).max(0.0);
                    assert!((e - want).abs() <= 1e-12 * want.max(1.0), "{e} {want}");
                }
            }
        }
        assert_eq!(excess_of(std::iter::empty(), tol, None), 0.0);
    }

    /// The first touch of the exact distance h₀(t) sampled at 1 ms over a 1 s free phase.
    fn first_touch(h: impl Fn(f64) -> f64) -> Option<f64> {
        let mut touch = Touch::new(1.0);
        for k in 0..=1000 {
            let t = k as f64 * 1e-3;
            touch.add_distance(t, h(t));
        }
        touch.first
    }

    /// A free phase that starts at a lift-off (h₀ slightly negative, as the smoothing leaves
    /// it) and rises, or ends at an impact from above, has no touch before its end; one that
    /// grazes the ball on its way (h₀ dips to 0 and rises again) touches at the dip, and one
    /// that skims along the ball before its impact touches where it first reaches it; a dip
    /// that stays above 0 is no touch. The lead of the touch before the end decides the
    /// verdict ([`touch_failure`]).
    #[test]
    fn a_touch_is_where_the_exact_distance_first_reaches_the_ball_after_leaving_it() {
        let c = TOUCH_CLEARANCE;
        // Lift-off at t = 0 from h₀ = −10 µm, rising at 0.1 m/s: no touch.
        assert_eq!(first_touch(|t| -1e-5 + 0.1 * t), None);
        // An impact at t = 1 s at 0.1 m/s, reaching h₀ = 0 at 0.9999 s: a touch within the
        // last sample.
        let end = first_touch(|t| 0.1 * (1.0 - t) - 1e-5).unwrap();
        assert!(end > 0.999 - 1e-12 && end <= 1.0, "{end}");
        // A graze at t = 0.4 s (h₀ = 1 mm (t − 0.4)² / 0.01 − 1 µm), then away, then an
        // impact: the touch is at the graze.
        let graze = |t: f64| 1e-3 * (t - 0.4f64).powi(2) / 0.01 - 1e-6;
        let g = first_touch(|t| graze(t).min(0.1 * (1.0 - t))).unwrap();
        assert!((g - 0.4).abs() < 0.011, "{g}");
        // The same dip staying 0.5 clearances above the ball (its minimum 49 µm), then the
        // approach ending 1 mm short: no touch.
        assert_eq!(
            first_touch(|t| (graze(t) + 0.5 * c).min(0.1 * (1.0 - t) + 1e-3)),
            None
        );
        // The same dip 0.5 clearances lower reaches the ball: a touch where it first does,
        // 0.1 (t − 0.4)² = 0.5 c + 1 µm, within one sample.
        let low = first_touch(|t| (graze(t) - 0.5 * c).min(0.1 * (1.0 - t) + 1e-3)).unwrap();
        let reach = 0.4 - ((0.5 * c + 1e-6) / 0.1f64).sqrt();
        assert!(low >= reach && low < reach + 1e-3, "{low} vs {reach}");
        // Skimming at h₀ = 0 from 0.8 s to the impact: the touch is at 0.8 s.
        let s = first_touch(|t| if t < 0.8 { 0.5 * (0.8 - t) } else { 0.0 }).unwrap();
        assert!((s - 0.8).abs() < 1.5e-3, "{s}");
    }
}
