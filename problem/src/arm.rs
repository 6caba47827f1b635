//! Point-to-point optimal control of an arm without a ball (`reach-arm`): any scene's serial
//! chain, any number of joints, moved from rest at a start configuration to rest at a target
//! configuration, minimising time plus effort like the catalogue's `reach` (Sect. 4.1):
//!
//! min ∫₀^T (1 + w‖τ‖² + w_a‖q̈‖²) dt  s.t.  M(q) q̈ + C(q, q̇) q̇ + g(q) + μ_v q̇ = τ (eq. 22–24, 26 without
//! the ball), |τ_i| ≤ τ_max,i (the scene's `tau_max`, unbounded where absent),
//! q_min ≤ q ≤ q_max (the scene's joint limits, where given), at rest at both ends:
//! (q, q̇)(0) = (q⁰, 0), τ(0) = g(q⁰), (q, q̇)(T) = (q^f, 0), τ(T) = g(q^f),
//! 0.01 s ≤ T ≤ [`MAX_DURATION`] (or T fixed, [`ArmSettings::duration`]).
//!
//! Rest means q̇ = 0 and q̈ = 0. With q̇ = 0 alone the arm passes through the target with a
//! non-zero acceleration: τ(T) does not hold it there (on the 2-link test arm it was a
//! fraction of g(q^f)), and it swings on. With q̇ = 0, q̈ = 0 is τ = g(q) by the dynamics; so τ
//! is a state (its rate τ̇ the control, determined by the collocation of τ) and both end
//! points fix q, q̇ and τ − g(q) = 0 (g from the scene's `cqd_g_rnea` graph at q̇ = 0), which
//! holds at the end time exactly, not only at the last collocation node (Radau nodes do not
//! include the end of a phase). The torque bounds are state bounds, met at the state points;
//! between them the torque polynomial can overshoot where the optimum is bang-bang (small
//! effort weights; decision records 0014, 0022). So the bound is also imposed between them,
//! through the Bernstein coefficients of each element's torque polynomial
//! ([`ArmSettings::torque_hull`]; bf-optim's [`StateBoundBetweenPoints`] with
//! [`Between::Hull`], linear rows on the state values; decision record 0028): the polynomial
//! lies in their convex hull, so it stays within τ_max everywhere.
//!
//! The small acceleration term (w_a = [`DEFAULT_ACCELERATION_WEIGHT`]) is a regularisation:
//! with time and torque effort alone, a joint of tiny inertia (a wrist: M_ii ≈ 4e-5 kg m² on
//! the PUMA 560) moves at almost no cost, the objective's curvature along its trajectory is
//! about 2w M_ii² ≈ 1e-9, and the interior-point iterates let the wrist flail between its
//! limits (no convergence, re-integration defects of hundreds of rad/s). With w_a the motion
//! is unique; it changes the optimum by a few percent (2-link test arm without torque bounds: J from
//! 141.0 to 144.7).
//!
//! * [`arm_node_function`]: the node function on the bf-codegen graph of the scene — state
//!   x = (q, q̇), algebraic q̈, control τ — with M from `mass_matrix` and C q̇ + g from
//!   `cqd_g_rnea`, the same graphs the emitted `mass_cqd_g` kernel and the ball-and-finger node
//!   functions ([`crate::node`]) are built from; the effort weight w and the runtime parameters
//!   are graph inputs.
//! * [`build_reach_arm`]: the problem ([`ArmBuilt`]) on one Legendre–Gauss–Radau phase.
//!   No node kernels are emitted for arms: the transcription interprets the graphs.
//! * [`ArmSolution`]: the solution record (`solution.json` of `optimize --problem reach-arm`),
//!   with [`arm_solution_at`] building it at an NLP point and [`ArmVerification`] the
//!   re-integration the study layer attaches.
//!
//! Start and target: [`default_start`] is the DH zero configuration (q = 0, the "home" pose of
//! a DH table) moved into the joint limits, or, where no admissible torque holds the arm
//! there, the pose it settles in from there under gravity; [`default_target`] is the start plus
//! [`TARGET_OFFSET_REVOLUTE`] rad on every revolute joint and [`TARGET_OFFSET_PRISMATIC`] m on
//! every prismatic one, moved into the limits.

use bf_codegen::graph::{Graph, Id};
use bf_codegen::nodefn::NodeFunction;
use bf_codegen::robot::SymbolicRobot;
use bf_codegen::{CodegenError, Scene};
use bf_optim::ipm::{Nlp, OutputSettings, Settings, Solution, Status, TerminationSettings};
use bf_optim::ocp::transcription::Between;
use bf_optim::ocp::{
    KernelUse, Objective, Ocp, Phase, PhaseGuess, PhaseTrajectory, PointFunction, Scheme,
    StateBoundBetweenPoints, Transcription, VarRef, extract,
};
use bf_scene::JointType;
use serde::{Deserialize, Serialize};

use crate::ProblemError;

/// The CLI and `solution.json` name of the problem.
pub const REACH_ARM: &str = "reach-arm";

/// Offset of the default target from the start on a revolute joint (rad).
pub const TARGET_OFFSET_REVOLUTE: f64 = 0.5;

/// Offset of the default target from the start on a prismatic joint (m).
pub const TARGET_OFFSET_PRISMATIC: f64 = 0.05;

/// Upper bound of the motion's duration T (s).
pub const MAX_DURATION: f64 = 20.0;

/// Lower bound of the motion's duration T (s).
pub const MIN_DURATION: f64 = 0.01;

/// Default acceleration weight w_a (s⁴ N⁻² m⁻²-free: per (rad/s²)²).
pub const DEFAULT_ACCELERATION_WEIGHT: f64 = 1e-3;

/// Default [`ArmSettings::torque_hull`] (decision record 0028, BENCHMARKS.md).
pub const DEFAULT_TORQUE_HULL: usize = 2;

/// Samples of the dense output ([`ArmSolution::dense`]).
pub const DENSE_SAMPLES: usize = 201;

/// Settings of [`build_reach_arm`].
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct ArmSettings {
    /// Collocation points of the phase (split over `elements` Radau elements).
    pub points: usize,
    /// Radau elements.
    pub elements: usize,
    /// Start configuration q⁰ (`None`: [`default_start`]).
    pub start: Option<Vec<f64>>,
    /// Target configuration q^f (`None`: [`default_target`]).
    pub target: Option<Vec<f64>>,
    /// Effort weight w of the cost ∫(1 + w‖τ‖² + w_a‖q̈‖²) dt.
    pub effort_weight: f64,
    /// Acceleration weight w_a (see the module docs: it makes the motion of light joints
    /// unique).
    pub acceleration_weight: f64,
    /// A fixed duration T (s) instead of the free one in [[`MIN_DURATION`], [`MAX_DURATION`]].
    pub duration: Option<f64>,
    /// Degree elevation m of the hull bound on the torque polynomials (bf-optim's
    /// [`Between::Hull`]: |τ_i(t)| ≤ τ_max,i everywhere between the state points); 0: the
    /// bound at the state points only (see the module docs).
    pub torque_hull: usize,
    /// Interior-point iteration limit.
    pub max_iter: usize,
    /// Interior-point convergence tolerance.
    pub tol: f64,
    /// Solver log level (0 silent).
    pub print_level: u8,
}

impl Default for ArmSettings {
    fn default() -> Self {
        ArmSettings {
            points: 30,
            elements: 3,
            start: None,
            target: None,
            effort_weight: 1.0,
            acceleration_weight: DEFAULT_ACCELERATION_WEIGHT,
            duration: None,
            torque_hull: DEFAULT_TORQUE_HULL,
            max_iter: 1500,
            tol: 1e-8,
            print_level: 0,
        }
    }
}

/// Joint limits of `scene` as (q_min, q_max), ±∞ where absent.
pub fn joint_limits(scene: &Scene) -> Vec<(f64, f64)> {
    scene
        .links
        .iter()
        .map(|l| {
            (
                l.q_min.unwrap_or(f64::NEG_INFINITY),
                l.q_max.unwrap_or(f64::INFINITY),
            )
        })
        .collect()
}

/// Torque limits τ_max,i of `scene` (∞ where absent).
pub fn torque_limits(scene: &Scene) -> Vec<f64> {
    scene
        .links
        .iter()
        .map(|l| l.tau_max.unwrap_or(f64::INFINITY))
        .collect()
}

/// The default start q⁰: q = 0 moved into the joint limits, where the torque bounds hold
/// the arm there against gravity; otherwise the pose it settles in when let go from there
/// (`settled_pose`: hanging, held by no torque), since `reach-arm` starts at rest and no
/// admissible torque holds q = 0 (the 2-link test arm stretched out horizontally needs
/// 14.2 N m at the shoulder against its 12).
pub fn default_start(scene: &Scene) -> Vec<f64> {
    let zero: Vec<f64> = joint_limits(scene)
        .iter()
        .map(|&(lo, hi)| 0.0f64.clamp(lo, hi))
        .collect();
    let Ok(mut potential) = Potential::new(scene) else {
        // The build reports the scene's model error itself.
        return zero;
    };
    let (_, g) = potential.at(&zero);
    let held = g
        .iter()
        .zip(torque_limits(scene))
        .all(|(g, t)| g.abs() <= t);
    if held {
        zero
    } else {
        settled_pose(scene, &mut potential, zero)
    }
}

/// The potential energy V(q) and its gradient, the gravity torques g(q), of a scene.
struct Potential {
    tape: bf_codegen::interp::Tape,
    vars: Vec<f64>,
    q_vars: Vec<usize>,
}

impl Potential {
    fn new(scene: &Scene) -> Result<Self, CodegenError> {
        let mut model = SymbolicRobot::new(scene)?;
        let lay = model.layout;
        let v = model.potential();
        let g = model.gravity();
        let outs: Vec<Id> = std::iter::once(v).chain(g).collect();
        model.check_size("the gravity torques", bf_codegen::robot::PROBLEM_ADVICE)?;
        let tape = bf_codegen::interp::Tape::new(&model.g, &outs);
        let mut vars = vec![0.0; lay.n_vars()];
        for (i, p) in model.params.iter().enumerate() {
            vars[lay.param(i) as usize] = p.1;
        }
        let q_vars = (0..model.nq()).map(|i| lay.q(i) as usize).collect();
        Ok(Potential { tape, vars, q_vars })
    }

    /// (V(q), g(q)).
    fn at(&mut self, q: &[f64]) -> (f64, Vec<f64>) {
        for (&v, &x) in self.q_vars.iter().zip(q) {
            self.vars[v] = x;
        }
        let out: Vec<f64> = self.tape.eval(&self.vars);
        (out[0], out[1..].to_vec())
    }
}

/// The pose reached from `q` by descending the potential energy over the revolute joints
/// within their limits (projected gradient steps of at most 0.1 rad, halved until V
/// decreases): where the arm comes to rest when let go, a local minimum of V at which gravity
/// needs no torque (or a joint limit takes it). Prismatic joints stay: along gravity an
/// unlimited slide has no rest pose.
fn settled_pose(scene: &Scene, potential: &mut Potential, mut q: Vec<f64>) -> Vec<f64> {
    let limits = joint_limits(scene);
    let revolute: Vec<bool> = scene
        .links
        .iter()
        .map(|l| l.joint == JointType::Revolute)
        .collect();
    let project = |q: &mut [f64]| {
        for (x, &(lo, hi)) in q.iter_mut().zip(&limits) {
            *x = x.clamp(lo, hi);
        }
    };
    let (mut v, mut g) = potential.at(&q);
    let mut step: f64 = 0.1;
    for _ in 0..10_000 {
        let gmax = g
            .iter()
            .zip(&revolute)
            .filter(|(_, r)| **r)
            .map(|(g, _)| g.abs())
            .fold(0.0, f64::max);
        if !(gmax.is_finite() && gmax > 0.0) || step < 1e-12 {
            break;
        }
        let mut trial = q.clone();
        for ((x, gi), r) in trial.iter_mut().zip(&g).zip(&revolute) {
            if *r {
                *x -= step * gi / gmax;
            }
        }
        project(&mut trial);
        let (vt, gt) = potential.at(&trial);
        if vt < v && trial != q {
            (q, v, g) = (trial, vt, gt);
            step = (2.0 * step).min(0.1);
        } else {
            step *= 0.5;
        }
    }
    q
}

/// The default target: `start` plus the fixed offsets of the module docs, moved into the joint
/// limits (downwards where the upper limit leaves no room).
pub fn default_target(scene: &Scene, start: &[f64]) -> Vec<f64> {
    scene
        .links
        .iter()
        .zip(joint_limits(scene))
        .zip(start)
        .map(|((l, (lo, hi)), &s)| {
            let d = if l.joint == JointType::Prismatic {
                TARGET_OFFSET_PRISMATIC
            } else {
                TARGET_OFFSET_REVOLUTE
            };
            if s + d <= hi { s + d } else { (s - d).max(lo) }
        })
        .collect()
}

/// Graph variables of the arm's node function.
#[derive(Debug, Clone)]
pub struct ArmNodeVars {
    /// The state: q, q̇, then τ.
    pub x: Vec<u32>,
    /// q̈ (the algebraic variables).
    pub qdd: Vec<u32>,
    /// τ (the last third of the state).
    pub tau: Vec<u32>,
    /// τ̇ (the controls).
    pub tau_rate: Vec<u32>,
    /// T.
    pub duration: u32,
}

/// The node function of the arm: state x = (q, q̇, τ), algebraic q̈, control τ̇,
/// ẋ = (q̇, q̈, τ̇), path rows (M q̈ + C q̇ + g + μ_v q̇ − τ)_i / M_ii(q_ref)
/// = 0 (one per joint), cost integrands (1 + w‖τ‖² + w_a‖q̈‖², 1). The constant row scale 1/M_ii at the
/// reference configuration `q_ref` changes no solution; it balances the rows of joints whose
/// inertias differ by orders of magnitude (PUMA 560: 3 kg m² at the shoulder, 4e-5 kg m² at
/// the flange), without which the interior-point iterates of the light joints wander. Builds
/// deep graphs: call it on a thread with a large stack for long chains (as
/// [`build_reach_arm`] does).
pub fn arm_node_function(
    scene: &Scene,
    effort_weight: f64,
    acceleration_weight: f64,
    q_ref: &[f64],
) -> Result<(NodeFunction, ArmNodeVars), CodegenError> {
    let mut model = SymbolicRobot::new(scene)?;
    let nq = model.nq();
    let lay = model.layout;
    let mut fixed: Vec<(u32, f64)> = model
        .params
        .iter()
        .enumerate()
        .map(|(i, p)| (lay.param(i), p.1))
        .collect();
    let base = lay.n_vars() as u32;
    let n = nq as u32;
    let qdd_v: Vec<u32> = (base..base + n).collect();
    let tau_v: Vec<u32> = (base + n..base + 2 * n).collect();
    let rate_v: Vec<u32> = (base + 2 * n..base + 3 * n).collect();
    let xv: Vec<u32> = (0..nq)
        .map(|i| lay.q(i))
        .chain((0..nq).map(|i| lay.qd(i)))
        .chain(tau_v.iter().copied())
        .collect();
    let t_v = base + 3 * n;
    let w_v = t_v + 1;
    let wa_v = t_v + 2;
    fixed.push((w_v, effort_weight));
    fixed.push((wa_v, acceleration_weight));
    let mu_v = scene.friction.as_ref().map_or(0.0, |f| f.mu_v);
    let mass = model.mass_matrix();
    let bias = model.cqd_g_rnea();
    let mut at_ref = vec![0.0; lay.n_vars()];
    for (i, &q) in q_ref.iter().enumerate().take(nq) {
        at_ref[lay.q(i) as usize] = q;
    }
    for &(v, x) in &fixed {
        if let Some(slot) = at_ref.get_mut(v as usize) {
            *slot = x;
        }
    }
    let diag: Vec<Id> = (0..nq).map(|i| mass[i][i]).collect();
    let m_ref = bf_codegen::interp::eval::<f64>(&model.g, &diag, &at_ref);
    let g: &mut Graph = &mut model.g;
    let qd: Vec<Id> = xv[nq..2 * nq].iter().map(|&v| g.var(v)).collect();
    let qdd: Vec<Id> = qdd_v.iter().map(|&v| g.var(v)).collect();
    let tau: Vec<Id> = tau_v.iter().map(|&v| g.var(v)).collect();
    let rate: Vec<Id> = rate_v.iter().map(|&v| g.var(v)).collect();
    let muv = g.constant(mu_v);
    let mut path = Vec::with_capacity(nq);
    for i in 0..nq {
        let mq = g.dot(&mass[i], &qdd);
        let mut r = g.add(mq, bias[i]);
        if mu_v != 0.0 {
            let fr = g.mul(muv, qd[i]);
            r = g.add(r, fr);
        }
        let r = g.sub(r, tau[i]);
        let m = m_ref[i];
        path.push(if m.is_finite() && m > 0.0 {
            let k = g.constant(1.0 / m);
            g.mul(k, r)
        } else {
            r
        });
    }
    let sq: Vec<Id> = tau.iter().map(|&t| g.square(t)).collect();
    let tt = g.sum(&sq);
    let w = g.var(w_v);
    let wt = g.mul(w, tt);
    let one = g.one();
    let aa: Vec<Id> = qdd.iter().map(|&a| g.square(a)).collect();
    let aa = g.sum(&aa);
    let wa = g.var(wa_v);
    let waa = g.mul(wa, aa);
    let c1 = g.add(one, wt);
    let c1 = g.add(c1, waa);
    let mut xdot = qd.clone();
    xdot.extend(&qdd);
    xdot.extend(&rate);
    let nf = NodeFunction {
        graph: std::mem::take(&mut model.g),
        x: xv.clone(),
        a: qdd_v.clone(),
        u: rate_v.clone(),
        duration: t_v,
        fixed,
        xdot,
        path_bounds: vec![(0.0, 0.0); nq],
        path,
        costs: vec![c1, one],
    };
    Ok((
        nf,
        ArmNodeVars {
            x: xv,
            qdd: qdd_v,
            tau: tau_v,
            tau_rate: rate_v,
            duration: t_v,
        },
    ))
}

/// A transcribed `reach-arm` problem.
#[derive(Debug, Clone)]
pub struct ArmBuilt {
    /// The scene.
    pub scene: Scene,
    /// Start configuration q⁰.
    pub start: Vec<f64>,
    /// Target configuration q^f.
    pub target: Vec<f64>,
    /// Torque limits used (∞ = none).
    pub tau_max: Vec<f64>,
    /// The problem.
    pub ocp: Ocp,
    /// Its transcription (interpreted node functions).
    pub nlp: Transcription,
    /// Settings used.
    pub settings: ArmSettings,
}

impl ArmBuilt {
    /// Number of joints.
    pub fn nq(&self) -> usize {
        self.start.len()
    }

    /// Interior-point settings of the solve.
    pub fn solver_settings(&self) -> Settings {
        Settings {
            termination: TerminationSettings {
                tol: self.settings.tol,
                max_iter: self.settings.max_iter,
                ..Default::default()
            },
            output: OutputSettings {
                print_level: self.settings.print_level,
            },
            ..Settings::default()
        }
    }
}

fn arm_err(scene: &Scene, message: String) -> ProblemError {
    ProblemError::Arm {
        scene: scene.name.clone(),
        message,
    }
}

/// Checks a configuration given in the settings (`what`: "start" or "target"): one finite
/// value per joint, inside the joint limits. Public so that a caller can name its own option
/// for the same check before posing the problem.
pub fn check_configuration(scene: &Scene, what: &str, q: &[f64]) -> Result<(), ProblemError> {
    let nq = scene.links.len();
    if q.len() != nq {
        return Err(arm_err(
            scene,
            format!("the {what} has {} values, the arm {nq} joints", q.len()),
        ));
    }
    for (i, (&v, (lo, hi))) in q.iter().zip(joint_limits(scene)).enumerate() {
        if !v.is_finite() {
            return Err(arm_err(
                scene,
                format!("the {what}'s joint {} is not finite ({v})", i + 1),
            ));
        }
        // The kernels' sine and cosine are defined within ±2²⁰ rad only.
        if scene.links[i].joint == JointType::Revolute && v.abs() > bf_scene::MAX_ANGLE {
            return Err(arm_err(
                scene,
                format!(
                    "the {what}'s joint {} = {v:e} rad is beyond ±2²⁰ = ±{} rad, where the \
                     kernels' sine and cosine are defined; give the angle modulo 2π",
                    i + 1,
                    bf_scene::MAX_ANGLE
                ),
            ));
        }
        if v < lo || v > hi {
            return Err(arm_err(
                scene,
                format!(
                    "the {what}'s joint {} = {v} is outside the joint limits [{lo}, {hi}]",
                    i + 1
                ),
            ));
        }
    }
    Ok(())
}

/// Rest at `q` at the start (`initial`) or end of the phase: q fixed, q̇ = 0 and
/// τ − (C q̇ + g)(q, q̇) = 0, i.e. τ = g(q) where q̇ = 0 (so q̈ = 0 by the dynamics).
fn rest_at(
    scene: &Scene,
    q: &[f64],
    initial: bool,
    name: &str,
) -> Result<PointFunction, CodegenError> {
    let mut model = SymbolicRobot::new(scene)?;
    let nq = model.nq();
    let lay = model.layout;
    let bias = model.cqd_g_rnea();
    let fixed: Vec<(u32, f64)> = model
        .params
        .iter()
        .enumerate()
        .map(|(i, p)| (lay.param(i), p.1))
        .collect();
    let base = lay.n_vars() as u32;
    let g = &mut model.g;
    let at = |i: usize| {
        if initial {
            VarRef::Initial { phase: 0, i }
        } else {
            VarRef::Final { phase: 0, i }
        }
    };
    let mut vars = Vec::with_capacity(3 * nq);
    let mut outputs = Vec::with_capacity(3 * nq);
    let mut bounds = Vec::with_capacity(3 * nq);
    for (i, &qi) in q.iter().enumerate().take(nq) {
        vars.push((lay.q(i), at(i)));
        outputs.push(g.var(lay.q(i)));
        bounds.push((qi, qi));
    }
    for i in 0..nq {
        vars.push((lay.qd(i), at(nq + i)));
        outputs.push(g.var(lay.qd(i)));
        bounds.push((0.0, 0.0));
    }
    for (i, &b) in bias.iter().enumerate() {
        let v = base + i as u32;
        vars.push((v, at(2 * nq + i)));
        let tau = g.var(v);
        outputs.push(g.sub(tau, b));
        bounds.push((0.0, 0.0));
    }
    Ok(PointFunction {
        name: name.into(),
        graph: std::mem::take(&mut model.g),
        vars,
        fixed,
        outputs,
        bounds,
        row_names: Vec::new(),
    })
}

/// Duration of the initial guess (s).
pub const GUESS_DURATION: f64 = 1.0;

/// Samples of the initial guess.
const GUESS_SAMPLES: usize = 21;

/// The initial guess: the quintic rest-to-rest motion q(s) = q⁰ + (q^f − q⁰)(10s³ − 15s⁴ +
/// 6s⁵), s = t/T (q̇ = q̈ = 0 at both ends), with the torques of inverse dynamics along it
/// (τ = M q̈ + C q̇ + g + μ_v q̇ on the scene's graphs; τ = g at both ends) and τ̇ by central
/// differences, so that the guess satisfies the dynamics and the boundary conditions.
pub fn rest_to_rest_guess(
    scene: &Scene,
    start: &[f64],
    target: &[f64],
    duration: f64,
) -> Result<PhaseGuess, CodegenError> {
    let mut model = SymbolicRobot::new(scene)?;
    let nq = model.nq();
    let lay = model.layout;
    let mass = model.mass_matrix();
    let bias = model.cqd_g_rnea();
    let outs: Vec<Id> = mass.iter().flatten().chain(&bias).copied().collect();
    model.check_size(
        "the guess's inverse dynamics",
        bf_codegen::robot::PROBLEM_ADVICE,
    )?;
    let tape = bf_codegen::interp::Tape::new(&model.g, &outs);
    let mu_v = scene.friction.as_ref().map_or(0.0, |f| f.mu_v);
    let mut vars = vec![0.0; lay.n_vars()];
    for (i, p) in model.params.iter().enumerate() {
        vars[lay.param(i) as usize] = p.1;
    }
    let mut guess = PhaseGuess {
        duration,
        ..PhaseGuess::default()
    };
    for k in 0..GUESS_SAMPLES {
        let s = k as f64 / (GUESS_SAMPLES - 1) as f64;
        let (s2, s3) = (s * s, s * s * s);
        let (p, dp, ddp) = (
            s3 * (10.0 - 15.0 * s + 6.0 * s2),
            30.0 * s2 * (1.0 - s) * (1.0 - s) / duration,
            60.0 * s * (1.0 - 3.0 * s + 2.0 * s2) / duration.powi(2),
        );
        let d: Vec<f64> = start.iter().zip(target).map(|(a, b)| b - a).collect();
        let q: Vec<f64> = start.iter().zip(&d).map(|(a, d)| a + d * p).collect();
        let qd: Vec<f64> = d.iter().map(|d| d * dp).collect();
        let qdd: Vec<f64> = d.iter().map(|d| d * ddp).collect();
        for i in 0..nq {
            vars[lay.q(i) as usize] = q[i];
            vars[lay.qd(i) as usize] = qd[i];
        }
        let out: Vec<f64> = tape.eval(&vars);
        let tau: Vec<f64> = (0..nq)
            .map(|i| {
                let mq: f64 = (0..nq).map(|j| out[i * nq + j] * qdd[j]).sum();
                mq + out[nq * nq + i] + mu_v * qd[i]
            })
            .collect();
        guess.s.push(s);
        guess.x.push(q.into_iter().chain(qd).chain(tau).collect());
        guess.a.push(qdd);
    }
    let taus: Vec<&[f64]> = guess.x.iter().map(|x| &x[2 * nq..]).collect();
    let h = duration / (GUESS_SAMPLES - 1) as f64;
    for k in 0..GUESS_SAMPLES {
        let (lo, hi) = (k.saturating_sub(1), (k + 1).min(GUESS_SAMPLES - 1));
        let dt = (hi - lo) as f64 * h;
        guess
            .u
            .push((0..nq).map(|i| (taus[hi][i] - taus[lo][i]) / dt).collect());
    }
    Ok(guess)
}

/// Builds `reach-arm` on `scene` (any serial chain; a ball, if any, is ignored) from the
/// guess of [`rest_to_rest_guess`]. Runs on a helper thread with a large
/// stack (deep graphs of long chains).
pub fn build_reach_arm(scene: &Scene, settings: &ArmSettings) -> Result<ArmBuilt, ProblemError> {
    std::thread::scope(|s| {
        std::thread::Builder::new()
            .stack_size(256 << 20)
            .spawn_scoped(s, || build_inner(scene, settings))
            .map_err(ProblemError::BuildThread)?
            .join()
            .map_err(|_| ProblemError::BuildPanicked)?
    })
}

fn build_inner(scene: &Scene, settings: &ArmSettings) -> Result<ArmBuilt, ProblemError> {
    let nq = scene.links.len();
    for (name, value) in [
        ("effort weight", settings.effort_weight),
        ("acceleration weight", settings.acceleration_weight),
    ] {
        if !(value.is_finite() && value >= 0.0) {
            return Err(ProblemError::InvalidSetting {
                name,
                value,
                expected: "finite and non-negative",
            });
        }
    }
    if settings.elements == 0 || settings.points < 2 * settings.elements {
        return Err(arm_err(
            scene,
            format!(
                "{} points on {} elements: need at least 1 element and 2 points per element",
                settings.points, settings.elements
            ),
        ));
    }
    let start = settings
        .start
        .clone()
        .unwrap_or_else(|| default_start(scene));
    check_configuration(scene, "start", &start)?;
    let target = settings
        .target
        .clone()
        .unwrap_or_else(|| default_target(scene, &start));
    check_configuration(scene, "target", &target)?;
    let (node, _) = arm_node_function(
        scene,
        settings.effort_weight,
        settings.acceleration_weight,
        &start,
    )
    .map_err(ProblemError::model(&scene.name))?;
    let tau_max = torque_limits(scene);
    let mut x_bounds = joint_limits(scene);
    x_bounds.extend(vec![(f64::NEG_INFINITY, f64::INFINITY); nq]);
    x_bounds.extend(tau_max.iter().map(|&t| (-t, t)));
    let duration_bounds = match settings.duration {
        Some(t) if (MIN_DURATION..=MAX_DURATION).contains(&t) => (t, t),
        Some(t) => {
            return Err(ProblemError::InvalidSetting {
                name: "duration",
                value: t,
                expected: "in [0.01, 20] s",
            });
        }
        None => (MIN_DURATION, MAX_DURATION),
    };
    let guess = rest_to_rest_guess(
        scene,
        &start,
        &target,
        settings.duration.unwrap_or(GUESS_DURATION),
    )
    .map_err(ProblemError::model(&scene.name))?;
    let phase = Phase {
        name: "free".into(),
        node,
        x_bounds,
        a_bounds: vec![(f64::NEG_INFINITY, f64::INFINITY); nq],
        u_bounds: vec![(f64::NEG_INFINITY, f64::INFINITY); nq],
        duration_bounds,
        points: settings.points,
        guess,
        end_ramp: None,
    };
    let ocp = Ocp {
        phases: vec![phase],
        n_costs: 2,
        params: vec![],
        points: vec![
            rest_at(scene, &start, true, "rest at the start")
                .map_err(ProblemError::model(&scene.name))?,
            rest_at(scene, &target, false, "rest at the target")
                .map_err(ProblemError::model(&scene.name))?,
        ],
        cost_bounds: vec![],
        objective: Objective::Cost(0),
        scheme: Scheme::Radau {
            elements: settings.elements,
        },
    };
    let mut nlp = Transcription::with_kernels(&ocp, &[], KernelUse::Never)?;
    if settings.torque_hull > 0 {
        let between: Vec<StateBoundBetweenPoints> = tau_max
            .iter()
            .enumerate()
            .filter(|(_, t)| t.is_finite())
            .map(|(i, &t)| StateBoundBetweenPoints {
                phase: 0,
                component: 2 * nq + i,
                lower: -t,
                upper: t,
                how: Between::Hull(settings.torque_hull),
            })
            .collect();
        nlp.bound_states_between_points(&between)?;
    }
    Ok(ArmBuilt {
        scene: scene.clone(),
        start,
        target,
        tau_max,
        ocp,
        nlp,
        settings: settings.clone(),
    })
}

/// Arm trajectory samples.
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
pub struct ArmSamples {
    /// Time (s).
    pub t: Vec<f64>,
    /// Joint positions (rad; m for prismatic joints).
    pub q: Vec<Vec<f64>>,
    /// Joint velocities.
    pub qd: Vec<Vec<f64>>,
    /// Joint torques (N m; N for prismatic joints).
    pub tau: Vec<Vec<f64>>,
}

/// Re-integration of an arm solution (the study layer's verification).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ArmVerification {
    /// Relative tolerance of the integrator.
    pub rtol: f64,
    /// Per collocation element, max over the state components of |x_sim − x_colloc| at the
    /// element's end, each element started from its collocated initial state.
    pub element_defects: Vec<f64>,
    /// Max of `element_defects` (NaN if an element could not be integrated).
    pub max_defect: f64,
    /// The open-loop replay from the start over the whole motion (no restarts): max over the
    /// components of |x_sim(T) − (q^f, 0)|. Informational: an unstable arm amplifies the
    /// discretisation error, so this is not the verdict.
    pub open_loop_end_error: f64,
    /// Largest excess of the interpolated torque polynomial over τ_max between the nodes.
    pub max_torque_overshoot: f64,
    /// max over the collocation nodes of |q̈_colloc − q̈(q, q̇, τ)|, q̈ from the simulator's
    /// model (M q̈ = τ − C q̇ − g − μ_v q̇): the node function and the simulator agree when it
    /// is at the solver's tolerance.
    pub node_residual: f64,
    /// Why an integration failed, if one did.
    pub failure: Option<String>,
}

/// The solution of `reach-arm`; serialises to `solution.json`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ArmSolution {
    /// Problem name ([`REACH_ARM`]).
    pub problem: String,
    /// The scene's `name`.
    pub scene: String,
    /// The scene file's text as read (so the solution replays without the file).
    pub scene_toml: String,
    /// Runtime parameters set on the command line (name, value).
    pub scene_params: Vec<(String, f64)>,
    /// Which kernels evaluated the node function (always `"interpreted"`: no node kernels are
    /// emitted for arms).
    pub kernels: String,
    /// Solver status.
    pub status: Status,
    /// Objective ∫(1 + w‖τ‖² + w_a‖q̈‖²) dt.
    pub objective: f64,
    /// Effort weight w.
    pub effort_weight: f64,
    /// Acceleration weight w_a.
    pub acceleration_weight: f64,
    /// Duration T (s).
    pub duration: f64,
    /// Start configuration.
    pub start: Vec<f64>,
    /// Target configuration.
    pub target: Vec<f64>,
    /// Torque limits (`null` = none).
    pub tau_max: Vec<Option<f64>>,
    /// Interior-point iterations.
    pub iterations: usize,
    /// Wall time of the solve (s).
    pub solve_seconds: f64,
    /// Final constraint violation.
    pub constraint_violation: f64,
    /// Final dual infeasibility.
    pub dual_infeasibility: f64,
    /// NLP size: variables, constraints.
    pub nlp_size: (usize, usize),
    /// Collocation points and Radau elements.
    pub points: usize,
    /// Degree elevation of the hull bound on the torques ([`ArmSettings::torque_hull`];
    /// absent in older files: 0, bounds at the state points only).
    #[serde(default)]
    pub torque_hull: usize,
    /// Radau elements.
    pub elements: usize,
    /// Values at the collocation state points.
    pub nodes: ArmSamples,
    /// [`DENSE_SAMPLES`] equally spaced samples of the collocation polynomials.
    pub dense: ArmSamples,
    /// Raw collocation data.
    pub raw: PhaseTrajectory,
    /// Re-integration with the optimal torques.
    #[serde(default)]
    pub verification: Option<ArmVerification>,
}

impl ArmSolution {
    /// Whether the solver converged (Solved or Acceptable).
    pub fn converged(&self) -> bool {
        self.status.is_success()
    }
}

fn samples_at(tr: &PhaseTrajectory, taus: &[f64], nq: usize) -> ArmSamples {
    let mut s = ArmSamples::default();
    for &tau in taus {
        let x = tr.x_at(tau);
        s.t.push(tr.time(tau));
        s.q.push(x[..nq].to_vec());
        s.qd.push(x[nq..2 * nq].to_vec());
        s.tau.push(x[2 * nq..3 * nq].to_vec());
    }
    s
}

/// The solution record of `p` at the solver result `sol` (`seconds`: wall time of the solve;
/// `scene_toml`, `scene_params`: the scene as given, for replays).
pub fn arm_solution_at(
    p: &ArmBuilt,
    sol: &Solution,
    seconds: f64,
    scene_toml: &str,
    scene_params: &[(String, f64)],
) -> ArmSolution {
    let nq = p.nq();
    let raw = extract(&p.nlp, &sol.x).remove(0);
    let nodes = samples_at(&raw, &raw.state_tau, nq);
    let dense_tau: Vec<f64> = (0..DENSE_SAMPLES)
        .map(|k| -1.0 + 2.0 * k as f64 / (DENSE_SAMPLES - 1) as f64)
        .collect();
    let dense = samples_at(&raw, &dense_tau, nq);
    let size = (Nlp::num_variables(&p.nlp), Nlp::num_constraints(&p.nlp));
    ArmSolution {
        problem: REACH_ARM.into(),
        scene: p.scene.name.clone(),
        scene_toml: scene_toml.into(),
        scene_params: scene_params.to_vec(),
        kernels: "interpreted".into(),
        status: sol.status,
        objective: sol.objective,
        effort_weight: p.settings.effort_weight,
        acceleration_weight: p.settings.acceleration_weight,
        duration: raw.duration,
        start: p.start.clone(),
        target: p.target.clone(),
        tau_max: p
            .tau_max
            .iter()
            .map(|&t| t.is_finite().then_some(t))
            .collect(),
        iterations: sol.iterations,
        solve_seconds: seconds,
        constraint_violation: sol.constraint_violation,
        dual_infeasibility: sol.dual_infeasibility,
        nlp_size: size,
        points: p.settings.points,
        torque_hull: p.settings.torque_hull,
        elements: p.settings.elements,
        nodes,
        dense,
        raw,
        verification: None,
    }
}
