//! Arms without a ball: `reach-arm` (bf-problem's [`bf_problem::arm`]) solved, verified and
//! written.
//!
//! * [`solve_reach_arm`]: build and solve the problem with the interior-point solver
//!   (interpreted node functions: no node kernels are emitted for arms).
//! * [`verify_arm`]: re-integration with bf-sim's arm simulator ([`bf_sim::arm::FreeArm`] on
//!   [`bf_model::arm::ArmModel`], compiled kernels when the scene is a compiled one) under the
//!   optimal torques. Like the ball problems' verification, the torques between the nodes are
//!   the solution's own torque polynomial on each collocation element, clamped to τ_max
//!   ([`ElementTorque`]; the optimisation bounds it between the points too, decision record
//!   0028, so the clamp only trims what remains between its samples), and
//!   **every element restarts from its collocated initial state**: the element defects
//!   |x_sim − x_colloc| at the element ends measure the discretisation error of the
//!   collocation, also for an arm whose open-loop motion is unstable (a hanging arm swung up
//!   amplifies any error exponentially). The open-loop replay from the start over the whole
//!   motion is reported beside it ([`ArmVerification::open_loop_end_error`]), not judged.
//!   A solution is verified when the largest element defect is at most
//!   [`VERIFIED_DEFECT`] (rad, rad/s).
//! * [`write_arm_solution`]: `solution.json`, `torques.csv` (the format `simulate --torques`
//!   reads) and `trajectory.csv` (t, q, q̇, τ on the dense grid).

use std::fmt::Write as _;
use std::path::Path;
use std::time::Instant;

use bf_codegen::Scene;
use bf_model::arm::ArmModel;
use bf_optim::ocp::nodes::lagrange_basis;
use bf_optim::ocp::transcription::sample_taus;
use bf_optim::ocp::{PhaseTrajectory, solve_nlp};
use bf_problem::arm::{
    ArmSettings, ArmSolution, ArmVerification, arm_solution_at, build_reach_arm,
};
use bf_sim::arm::{ArmMode, FreeArm};
use bf_sim::{HybridSystem, Input, SimError, SimSettings};

use super::error::PipelineError;
use super::verify::{ATOL_FACTOR, VERIFIED_DEFECT};

/// Builds and solves `reach-arm` on `scene`; `scene_toml` and `scene_params` (the scene file's
/// text and the runtime parameters set on it) are stored for replays.
pub fn solve_reach_arm(
    scene: &Scene,
    settings: &ArmSettings,
    scene_toml: &str,
    scene_params: &[(String, f64)],
) -> Result<ArmSolution, PipelineError> {
    let start = Instant::now();
    let built = build_reach_arm(scene, settings)?;
    let sol = solve_nlp(&built.nlp, &built.solver_settings(), None, None)?;
    Ok(arm_solution_at(
        &built,
        &sol,
        start.elapsed().as_secs_f64(),
        scene_toml,
        scene_params,
    ))
}

/// One solve of [`solve_verified`]: its mesh, status, objective and re-integration defect.
#[derive(Debug, Clone, PartialEq)]
pub struct ArmAttempt {
    /// Collocation points.
    pub points: usize,
    /// Radau elements.
    pub elements: usize,
    /// The solution (with its verification when `rtol` > 0).
    pub solution: ArmSolution,
}

/// Re-solves of `reach-arm` on a mesh with twice the elements by default
/// (`optimize --verify-refinements`): each doubles the problem, so three (8× the elements)
/// rather than the periodic searches' [`super::search::VERIFY_REFINEMENTS`].
pub const ARM_MESH_DOUBLINGS: usize = 3;

/// [`solve_reach_arm`] then [`verify_arm`] at `rtol` (0: no verification, one solve); an
/// unverified optimum is solved again on a mesh with twice the elements and points (the
/// same points per element), up to `refinements` times: where the torque bounds are active
/// the optimal torques have corners, which the element polynomials resolve only on short
/// elements. A solve that did not converge ends the attempts: a finer mesh resolves an
/// optimum better, it does not make an unreachable target reachable (a target of 1e6 rad
/// took four meshes and two minutes to fail). Returns every attempt, the last one being the
/// answer.
///
/// `optimize --problem reach-arm` uses [`ARM_MESH_DOUBLINGS`] unless told otherwise.
pub fn solve_verified(
    scene: &Scene,
    settings: &ArmSettings,
    rtol: f64,
    refinements: usize,
    scene_toml: &str,
    scene_params: &[(String, f64)],
) -> Result<Vec<ArmAttempt>, PipelineError> {
    let mut attempts = Vec::new();
    let mut s = settings.clone();
    loop {
        let mut sol = solve_reach_arm(scene, &s, scene_toml, scene_params)?;
        if rtol > 0.0 {
            sol.verification = Some(verify_arm(&sol, rtol)?);
        }
        let done =
            rtol == 0.0 || is_verified(&sol) || !sol.converged() || attempts.len() >= refinements;
        attempts.push(ArmAttempt {
            points: s.points,
            elements: s.elements,
            solution: sol,
        });
        if done {
            return Ok(attempts);
        }
        s.points *= 2;
        s.elements *= 2;
    }
}

/// The scene an arm solution was posed on, parsed from its stored text with its runtime
/// parameters.
pub fn scene_of(sol: &ArmSolution) -> Result<Scene, PipelineError> {
    let mut scene = Scene::from_toml_str(&sol.scene_toml, &sol.scene).map_err(|source| {
        bf_problem::ProblemError::Scene {
            scene: sol.scene.clone(),
            source,
        }
    })?;
    bf_model::registry::set_parameters(&mut scene, &sol.scene_params).map_err(|e| {
        PipelineError::Arm {
            message: format!("scene `{}`: {e}", sol.scene),
        }
    })?;
    Ok(scene)
}

/// The torque of one collocation element: τ is a state of `reach-arm` (bf_problem::arm), so
/// this is the element's state polynomial of τ, the Lagrange interpolation through its state
/// points (both ends included), in time, clamped to |τ_i| ≤ τ_max,i: a drive delivers no
/// more, so the verification and `simulate --init` replay what a real arm would do, and the
/// clamp's effect (where the polynomial overshoots between the points) is part of the
/// re-integration defect instead of a torque no drive has.
#[derive(Debug, Clone)]
pub struct ElementTorque {
    t0: f64,
    duration: f64,
    taus: Vec<f64>,
    values: Vec<Vec<f64>>,
    limits: Vec<f64>,
}

/// τ_max per joint of an arm solution, ∞ where it has none.
pub fn torque_limits(sol: &ArmSolution) -> Vec<f64> {
    sol.tau_max
        .iter()
        .map(|t| t.map_or(f64::INFINITY, f64::abs))
        .collect()
}

impl ElementTorque {
    /// The torque of element `e` of `tr`, an arm of `n` joints (state (q, q̇, τ)) with the
    /// torque limits `limits` (∞ where none; missing entries count as none).
    pub fn new(tr: &PhaseTrajectory, e: usize, n: usize, limits: &[f64]) -> Self {
        let (a, b) = tr.elements[e];
        ElementTorque {
            t0: tr.t0,
            duration: tr.duration,
            taus: tr.state_tau[a..b].to_vec(),
            values: tr.x[a..b]
                .iter()
                .map(|x| x[2 * n..3 * n].to_vec())
                .collect(),
            limits: (0..n)
                .map(|i| limits.get(i).copied().unwrap_or(f64::INFINITY))
                .collect(),
        }
    }

    /// The unclamped polynomial at time `t`.
    pub fn polynomial_at(&self, t: f64, out: &mut [f64]) {
        let s = 2.0 * (t - self.t0) / self.duration - 1.0;
        let l = lagrange_basis(&self.taus, s);
        for (i, o) in out.iter_mut().enumerate() {
            *o = self.values.iter().zip(&l).map(|(v, w)| w * v[i]).sum();
        }
    }

    /// τ at time `t`: the polynomial clamped to the limits.
    pub fn at(&self, t: f64, out: &mut [f64]) {
        self.polynomial_at(t, out);
        for (o, &m) in out.iter_mut().zip(&self.limits) {
            // max/min rather than clamp: never panics, whatever the limits are.
            *o = o.max(-m).min(m);
        }
    }
}

/// Torques of the open-loop replay: the control polynomial of the element containing t (the
/// interpolant the collocation solved for; `simulate --init` replays with it too).
#[derive(Debug, Clone)]
pub struct PhaseTorque {
    /// (end time, polynomial) per element.
    elements: Vec<(f64, ElementTorque)>,
    n: usize,
}

impl PhaseTorque {
    /// The torques of `tr`, an arm of `n` joints with the torque limits `limits`
    /// ([`ElementTorque::new`]).
    pub fn new(tr: &PhaseTrajectory, n: usize, limits: &[f64]) -> Self {
        let elements = (0..tr.elements.len())
            .map(|e| {
                let end = tr.time(tr.state_tau[tr.elements[e].1 - 1]);
                (end, ElementTorque::new(tr, e, n, limits))
            })
            .collect();
        PhaseTorque { elements, n }
    }

    /// The end of the last element (s): past it [`Input::tau`] holds the torque there.
    pub fn end(&self) -> Option<f64> {
        self.elements.last().map(|(end, _)| *end)
    }
}

impl Input for PhaseTorque {
    fn dim(&self) -> usize {
        self.n
    }
    fn tau(&self, t: f64, _: &[f64], _: &[f64], out: &mut [f64]) -> Result<(), SimError> {
        // The last polynomial extrapolated past the solution's end is no torque of it.
        let t = self.end().map_or(t, |end| t.min(end));
        let k = self
            .elements
            .iter()
            .position(|(end, _)| t <= *end)
            .unwrap_or(self.elements.len().saturating_sub(1));
        if let Some((_, p)) = self.elements.get(k) {
            p.at(t, out);
        }
        Ok(())
    }
}

/// One element's polynomial as an [`Input`].
struct OneElement(ElementTorque, usize);

impl Input for OneElement {
    fn dim(&self) -> usize {
        self.1
    }
    fn tau(&self, t: f64, _: &[f64], _: &[f64], out: &mut [f64]) -> Result<(), SimError> {
        self.0.at(t, out);
        Ok(())
    }
}

fn max_abs_diff(a: &[f64], b: &[f64]) -> f64 {
    a.iter()
        .zip(b)
        .map(|(x, y)| (x - y).abs())
        .fold(0.0, f64::max)
}

/// Points inside every interval between state points at which [`verify_arm`] evaluates the
/// torque polynomials for [`ArmVerification::max_torque_overshoot`] (beside the state points):
/// where the optimisation bounds the torque at the state points and through the Bernstein hull
/// of each element ([`bf_problem::arm::ArmSettings::torque_hull`]), so that an overshoot the
/// hull would not have excluded is seen.
pub const OVERSHOOT_SAMPLES: usize = 16;

/// Re-integrates `sol` on its scene (see the module docs) with DOPRI5 at `rtol`
/// (atol = rtol · [`ATOL_FACTOR`]).
pub fn verify_arm(sol: &ArmSolution, rtol: f64) -> Result<ArmVerification, PipelineError> {
    let scene = scene_of(sol)?;
    let (model, _) = ArmModel::from_scene(&scene).map_err(|e| PipelineError::Arm {
        message: format!("scene `{}`: {e}", scene.name),
    })?;
    let tr = &sol.raw;
    let n = model.nq();
    let limits = torque_limits(sol);
    let settings = SimSettings {
        rtol,
        atol: rtol * ATOL_FACTOR,
        h_max: (tr.duration / 10.0).max(1e-6),
        ..SimSettings::default()
    };
    let mut node_residual: f64 = 0.0;
    for k in 0..tr.node_tau.len() {
        // The state is (q, q̇, τ), the algebraic variables q̈ (bf_problem::arm).
        let x = &tr.x[tr.node_state[k]];
        match model.accelerations(&x[..n], &x[n..2 * n], &x[2 * n..3 * n]) {
            Ok(qdd) => node_residual = node_residual.max(max_abs_diff(&qdd, &tr.a[k])),
            Err(_) => node_residual = f64::NAN,
        }
    }
    let mut element_defects = Vec::new();
    let mut failure = None;
    let mut overshoot: f64 = 0.0;
    for (e, &(a, b)) in tr.elements.iter().enumerate() {
        let poly = ElementTorque::new(tr, e, n, &limits);
        let (t0, t1) = (tr.time(tr.state_tau[a]), tr.time(tr.state_tau[b - 1]));
        let mut tau = vec![0.0; n];
        let support = &tr.state_tau[a..b];
        let samples = sample_taus(support, OVERSHOOT_SAMPLES);
        for &s in support.iter().chain(&samples) {
            poly.polynomial_at(tr.time(s), &mut tau);
            for (v, m) in tau.iter().zip(&sol.tau_max) {
                if let Some(m) = m {
                    overshoot = overshoot.max(v.abs() - m);
                }
            }
        }
        let sys = FreeArm::new(model.clone(), OneElement(poly, n))?;
        match bf_sim::simulate(
            &sys as &dyn HybridSystem<Mode = ArmMode>,
            settings.clone(),
            ArmMode::Free,
            t0,
            &tr.x[a][..2 * n],
            t1,
        ) {
            Ok(out) => {
                let end = out.trajectory.x.last().map_or(&tr.x[a], |x| x);
                element_defects.push(max_abs_diff(end, &tr.x[b - 1][..2 * n]));
            }
            Err(f) => {
                failure.get_or_insert(format!("element {e}: at t = {} s: {}", f.t, f.error));
                element_defects.push(f64::NAN);
            }
        }
    }
    let max_defect = if element_defects.iter().any(|d| d.is_nan()) {
        f64::NAN
    } else {
        element_defects.iter().copied().fold(0.0, f64::max)
    };
    let x_final: Vec<f64> = sol
        .target
        .iter()
        .copied()
        .chain(std::iter::repeat_n(0.0, n))
        .collect();
    let x0: Vec<f64> = tr.x.first().map_or(vec![], |x| x[..2 * n].to_vec());
    let sys = FreeArm::new(model, PhaseTorque::new(tr, n, &limits))?;
    let t_end = tr.t0 + tr.duration;
    let open_loop_end_error = match bf_sim::simulate(
        &sys as &dyn HybridSystem<Mode = ArmMode>,
        settings,
        ArmMode::Free,
        tr.t0,
        &x0,
        t_end,
    ) {
        Ok(out) => out
            .trajectory
            .x
            .last()
            .map_or(f64::NAN, |x| max_abs_diff(x, &x_final)),
        Err(_) => f64::NAN,
    };
    Ok(ArmVerification {
        rtol,
        element_defects,
        max_defect,
        open_loop_end_error,
        max_torque_overshoot: overshoot.max(0.0),
        node_residual,
        failure,
    })
}

/// Whether `sol` converged and its verification passes [`VERIFIED_DEFECT`].
pub fn is_verified(sol: &ArmSolution) -> bool {
    sol.converged()
        && sol
            .verification
            .as_ref()
            .is_some_and(|v| v.max_defect <= VERIFIED_DEFECT)
}

/// Why `sol` counts as failed (not converged, or re-integrated and not verified), if it does:
/// a solution that was not re-integrated (`--verify-rtol 0`) is no failure, as for the
/// finger (`optimize`'s exit status), and its file says `verified: false`.
pub fn failure_of(sol: &ArmSolution) -> Option<String> {
    if !sol.converged() {
        return Some(format!(
            "the solver did not converge ({})",
            crate::names::name(&sol.status)
        ));
    }
    match &sol.verification {
        None => None,
        Some(v) if !is_verified(sol) => Some(format!(
            "the solution is unverified: its re-integration defect {:.3e} exceeds {:e}{}",
            v.max_defect,
            VERIFIED_DEFECT,
            v.failure
                .as_ref()
                .map(|f| format!(" ({f})"))
                .unwrap_or_default()
        )),
        Some(_) => None,
    }
}

fn units(scene: &Scene, i: usize) -> (&'static str, &'static str, &'static str) {
    if scene
        .links
        .get(i)
        .is_some_and(|l| l.joint == bf_codegen::spec::JointType::Prismatic)
    {
        ("m", "m/s", "N")
    } else {
        ("rad", "rad/s", "N m")
    }
}

/// `torques.csv` (`t [s],tau1 [N m],..`, N for a prismatic joint: the header of the ball
/// problems' file, the format `simulate --torques` reads) and `trajectory.csv`
/// (`t [s],q1 [rad],..,qd1 [rad/s],..,tau1 [N m],..`) of the dense samples.
pub fn arm_csvs(sol: &ArmSolution, scene: &Scene) -> (String, String) {
    let n = sol.start.len();
    let d = &sol.dense;
    let mut torques = String::from("t [s]");
    for i in 0..n {
        let _ = write!(torques, ",tau{} [{}]", i + 1, units(scene, i).2);
    }
    torques.push('\n');
    let mut traj = String::from("t [s]");
    for (k, stem) in ["q", "qd", "tau"].iter().enumerate() {
        for i in 0..n {
            let u = units(scene, i);
            let unit = [u.0, u.1, u.2][k];
            let _ = write!(traj, ",{stem}{} [{unit}]", i + 1);
        }
    }
    traj.push('\n');
    for k in 0..d.t.len() {
        let _ = write!(torques, "{:e}", d.t[k]);
        for v in &d.tau[k] {
            let _ = write!(torques, ",{v:e}");
        }
        torques.push('\n');
        let _ = write!(traj, "{:e}", d.t[k]);
        for v in d.q[k].iter().chain(&d.qd[k]).chain(&d.tau[k]) {
            let _ = write!(traj, ",{v:e}");
        }
        traj.push('\n');
    }
    (torques, traj)
}

/// Writes `solution.json`, `torques.csv` and `trajectory.csv` of `sol` into `dir`, through
/// the solution files' one writer ([`super::solution_io::write_file`]). `solution.json`
/// carries the schema of the ball problems' files: `schema_version` and a top-level
/// `verified` (docs/files.md).
pub fn write_arm_solution(sol: &ArmSolution, dir: &Path) -> Result<(), PipelineError> {
    let scene = scene_of(sol)?;
    let (torques, traj) = arm_csvs(sol, &scene);
    let serial = |e: serde_json::Error| PipelineError::Arm {
        message: format!("cannot serialise the solution: {e}"),
    };
    let mut doc = serde_json::to_value(sol).map_err(serial)?;
    if let serde_json::Value::Object(m) = &mut doc {
        m.insert(
            "schema_version".into(),
            super::solution_io::SCHEMA_VERSION.into(),
        );
        m.insert("verified".into(), is_verified(sol).into());
    }
    let json = serde_json::to_string_pretty(&doc).map_err(serial)?;
    for (name, text) in [
        ("solution.json", json.as_str()),
        ("torques.csv", &torques),
        ("trajectory.csv", &traj),
    ] {
        super::solution_io::write_file(&dir.join(name), text.as_bytes())?;
    }
    Ok(())
}

/// Whether the solution document `doc` is an arm's (`optimize --problem reach-arm`): the
/// commands that take a finger's solution name it instead of failing on its missing fields.
pub fn is_arm_solution(doc: &serde_json::Value) -> bool {
    doc.get("problem").and_then(|p| p.as_str()) == Some(bf_problem::arm::REACH_ARM)
}

/// Reads an arm `solution.json`.
pub fn read_arm_solution(path: &Path) -> Result<ArmSolution, PipelineError> {
    let text = bf_codegen::spec::read_input_text(path).map_err(|e| PipelineError::Arm {
        message: format!("{}: cannot read: {e}", path.display()),
    })?;
    let doc: serde_json::Value = crate::io::json_value(&text).map_err(|e| PipelineError::Arm {
        message: format!("{}: not valid JSON: {e}", path.display()),
    })?;
    // Files written before arm solutions had a schema version have the same fields.
    super::solution_io::check_schema_version(&doc, path)?;
    serde_json::from_value(doc).map_err(|e| PipelineError::Arm {
        message: format!("{}: not an arm solution: {e}", path.display()),
    })
}
