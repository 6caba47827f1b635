//! The solution of a ball-and-finger problem as `solution.json` stores it ([`OcpSolution`]):
//! status, objective φ = c₁/c₂ or c₁ (eq. 60), phase durations, the trajectory at the
//! collocation points and on a dense grid ([`Samples`], with h eq. 4, σ eq. 18 and α eq. 2),
//! the raw collocation data for warm starts, and the records of how it was found
//! ([`records`]). [`solution_at`] builds it at an NLP point; [`warm_initial_point`]
//! interpolates one onto another mesh.

pub mod records;

use bf_optim::ipm::{Counters, Nlp, Status, Timing, WarmStart};
use bf_optim::ocp::trajectory::values_at;
use bf_optim::ocp::{PhaseTrajectory, Scheme, extract};
use serde::{Deserialize, Serialize};

use crate::ProblemError;
use crate::catalogue::BuiltProblem;
use crate::node::PhaseMode;
use crate::points::Diagnostics;
use records::{RefineReport, StrategyReport, Verification};

/// Trajectory samples (at the collocation state points or on a dense grid).
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
pub struct Samples {
    /// Time (s).
    pub t: Vec<f64>,
    /// Phase index of each sample.
    pub phase: Vec<usize>,
    /// Joint angles.
    pub q: Vec<Vec<f64>>,
    /// Joint rates.
    pub qd: Vec<Vec<f64>>,
    /// Ball angular velocity.
    pub omega: Vec<Vec<f64>>,
    /// Torques.
    pub tau: Vec<Vec<f64>>,
    /// Contact force λ (zero in free phases).
    pub lambda: Vec<Vec<f64>>,
    /// Distance h (eq. 4).
    pub h: Vec<f64>,
    /// Slip margin σ = μ_s λ_n − ‖λ_∥‖ (eq. 18; zero in free phases).
    pub sigma: Vec<f64>,
    /// α (eq. 2).
    pub alpha: Vec<f64>,
}

/// A solution of a problem; serialises to `solution.json`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct OcpSolution {
    /// Problem name.
    pub problem: String,
    /// Solver status.
    pub status: Status,
    /// Objective φ.
    pub objective: f64,
    /// Cost states c_1(t_f), c_2(t_f).
    pub c1: f64,
    /// Second cost state.
    pub c2: f64,
    /// Phase modes.
    pub modes: Vec<PhaseMode>,
    /// Phase durations (s).
    pub phase_durations: Vec<f64>,
    /// Total duration (period for the periodic problems).
    pub period: f64,
    /// Mean ω over [0, t_f] (quadrature).
    pub mean_omega: [f64; 3],
    /// Impact impulse ι (if any).
    pub impulse: Vec<f64>,
    /// Interior-point iterations (all continuation stages).
    pub iterations: usize,
    /// Wall time of the solve (s, all stages).
    pub solve_seconds: f64,
    /// Strategy stages run: (description, status, iterations).
    pub stages: Vec<(String, Status, usize)>,
    /// Final constraint violation.
    pub constraint_violation: f64,
    /// Final dual infeasibility.
    pub dual_infeasibility: f64,
    /// Solver time breakdown of the final stage.
    pub timing: Timing,
    /// Solver counters of the final stage.
    pub counters: Counters,
    /// NLP size: variables, constraints.
    pub nlp_size: (usize, usize),
    /// Collocation points per phase and scheme.
    pub points: usize,
    /// Scheme.
    pub scheme: Scheme,
    /// ε of the smooth saturation.
    pub epsilon: f64,
    /// Values at the state points.
    pub nodes: Samples,
    /// Dense interpolation (100 samples per phase).
    pub dense: Samples,
    /// Raw per-phase collocation data (warm starts, interpolation).
    pub raw: Vec<PhaseTrajectory>,
    /// Static parameters.
    pub params: Vec<f64>,
    /// Primal-dual point of the final NLP (for an exact warm start on the same mesh; stored
    /// in solution.json so that `--warm-start` is exact when the mesh is unchanged).
    #[serde(default)]
    pub nlp_warm: Option<WarmStart>,
    /// How the solution was found: every stage or start with its status and objective.
    #[serde(default)]
    pub strategy: Option<StrategyReport>,
    /// Adaptive mesh refinement that produced this solution (`optimize --refine TOL`); its
    /// `mesh` is the final mesh (`points`/`scheme` above are the starting mesh's).
    #[serde(default)]
    pub refinement: Option<RefineReport>,
    /// Re-integration of each phase with the optimal torques (the study layer's verification).
    #[serde(default)]
    pub verification: Option<Verification>,
    /// The scene the problem was posed on (its `name`).
    #[serde(default)]
    pub scene: String,
    /// Which kernels evaluated the phase node functions: `"compiled"` (every phase on an
    /// emitted node kernel), `"interpreted"` (none) or `"mixed"`.
    #[serde(default)]
    pub kernels: String,
}

impl OcpSolution {
    /// The torques as `t [s],tau1 [N m],...,tauN [N m]` CSV (sim/README.md): dense samples with strictly
    /// increasing times (a sample equal in time to the previous one, at a phase boundary, is
    /// dropped), full precision.
    pub fn torques_csv(&self) -> String {
        let nq = self.dense.tau.first().map_or(0, |v| v.len());
        let mut s = String::from("t [s]");
        for i in 1..=nq {
            s.push_str(&format!(",tau{i} [N m]"));
        }
        s.push('\n');
        let mut last = f64::NEG_INFINITY;
        for (k, &t) in self.dense.t.iter().enumerate() {
            if t <= last || !t.is_finite() {
                continue;
            }
            last = t;
            s.push_str(&format!("{t:?}"));
            for v in &self.dense.tau[k] {
                s.push_str(&format!(",{v:?}"));
            }
            s.push('\n');
        }
        s
    }
}

fn samples(p: &BuiltProblem, diag: &Diagnostics, traj: &[PhaseTrajectory], dense: bool) -> Samples {
    let nq = p.physics.nq;
    let mut s = Samples::default();
    for (pi, tr) in traj.iter().enumerate() {
        let taus: Vec<f64> = if dense {
            (0..100).map(|k| -1.0 + 2.0 * k as f64 / 99.0).collect()
        } else {
            tr.state_tau.clone()
        };
        for (k, &tau) in taus.iter().enumerate() {
            let x = if dense { tr.x_at(tau) } else { tr.x[k].clone() };
            // Interpolated controls may overshoot the bounds between nodes: clamp to |τ| ≤ τ_max.
            let u: Vec<f64> = tr
                .u_at(tau)
                .iter()
                .zip(&p.physics.tau_max)
                .map(|(u, m)| u.clamp(-m, *m))
                .collect();
            let a = tr.a_at(tau);
            let lam = if p.modes[pi] == PhaseMode::Stick && a.len() >= nq + 6 {
                a[nq + 3..nq + 6].to_vec()
            } else {
                vec![0.0; 3]
            };
            let c = diag.eval(&x);
            let ln: f64 = lam.iter().zip(&c.n).map(|(a, b)| a * b).sum();
            let par: Vec<f64> = (0..3).map(|i| lam[i] - ln * c.n[i]).collect();
            let sigma = if p.modes[pi] == PhaseMode::Stick {
                p.physics.mu_s * ln - par.iter().map(|v| v * v).sum::<f64>().sqrt()
            } else {
                0.0
            };
            s.t.push(tr.time(tau));
            s.phase.push(pi);
            s.q.push(x[..nq].to_vec());
            s.qd.push(x[nq..2 * nq].to_vec());
            s.omega.push(x[2 * nq..2 * nq + 3].to_vec());
            s.tau.push(u);
            s.lambda.push(lam);
            s.h.push(c.h);
            s.sigma.push(sigma);
            s.alpha.push(c.alpha);
        }
    }
    s
}

/// Builds the [`OcpSolution`] of `p` at the NLP point `x`.
pub fn solution_at(
    p: &BuiltProblem,
    x: &[f64],
    status: Status,
) -> Result<OcpSolution, ProblemError> {
    let diag = Diagnostics::new(&p.scene, p.epsilon)?;
    let traj = extract(&p.nlp, x);
    let nq = p.physics.nq;
    let period: f64 = traj.iter().map(|t| t.duration).sum();
    let mut mean = [0.0; 3];
    for tr in &traj {
        for (k, &sp) in tr.node_state.iter().enumerate() {
            for i in 0..3 {
                mean[i] += 0.5 * tr.duration * tr.node_weight[k] * tr.x[sp][2 * nq + i];
            }
        }
    }
    if period > 0.0 {
        mean.iter_mut().for_each(|v| *v /= period);
    }
    let c0 = p.nlp.c0;
    let np = p.ocp.params.len();
    let (viol, _) = p.nlp.max_violation(x);
    Ok(OcpSolution {
        problem: p.name.clone(),
        status,
        objective: Nlp::objective(&p.nlp, x),
        c1: x[c0],
        c2: x[c0 + 1],
        modes: p.modes.clone(),
        phase_durations: traj.iter().map(|t| t.duration).collect(),
        period,
        mean_omega: mean,
        impulse: x[p.nlp.p0..p.nlp.p0 + np].to_vec(),
        iterations: 0,
        solve_seconds: 0.0,
        stages: vec![],
        constraint_violation: viol,
        dual_infeasibility: f64::NAN,
        timing: Timing::default(),
        counters: Counters::default(),
        nlp_size: (Nlp::num_variables(&p.nlp), Nlp::num_constraints(&p.nlp)),
        points: p.settings.points,
        scheme: p.settings.scheme,
        epsilon: p.epsilon,
        nodes: samples(p, &diag, &traj, false),
        dense: samples(p, &diag, &traj, true),
        raw: traj,
        params: x[p.nlp.p0..p.nlp.p0 + np].to_vec(),
        nlp_warm: None,
        strategy: None,
        refinement: None,
        verification: None,
        scene: p.scene.name.clone(),
        kernels: node_kernel_source(p).to_string(),
    })
}

/// `"compiled"`, `"interpreted"` or `"mixed"`: whether the phase node functions of `p` run on
/// emitted kernels.
pub fn node_kernel_source(p: &BuiltProblem) -> &'static str {
    let fns = p.nlp.phase_functions();
    let compiled = fns.iter().filter(|f| f.kernel_name().is_some()).count();
    if compiled == fns.len() {
        "compiled"
    } else if compiled == 0 {
        "interpreted"
    } else {
        "mixed"
    }
}

/// Sets the initial point of `p` to `prev` interpolated exactly (element polynomials) onto
/// `p`'s mesh: states, algebraic variables, controls, durations, parameters and cost states.
pub fn warm_initial_point(p: &mut BuiltProblem, prev: &OcpSolution) -> Result<(), ProblemError> {
    if prev.raw.len() != p.nlp.phases.len() {
        return Err(ProblemError::WarmStartPhases {
            found: prev.raw.len(),
            expected: p.nlp.phases.len(),
        });
    }
    let mut x = p.nlp.initial().to_vec();
    for (l, raw) in p.nlp.phases.iter().zip(&prev.raw) {
        let put = |x: &mut Vec<f64>, idx: &dyn Fn(usize) -> usize, v: &[f64], n: usize| {
            for (i, &val) in v.iter().enumerate().take(n) {
                if val.is_finite() {
                    x[idx(i)] = val;
                }
            }
        };
        for (pt, &tau) in l.mesh.state_tau.iter().enumerate() {
            let [xv, _, _] = values_at(raw, tau);
            put(&mut x, &|i| l.x(pt, i), &xv, l.nx);
        }
        for (k, c) in l.mesh.colloc.iter().enumerate() {
            let [_, a, u] = values_at(raw, c.tau);
            put(&mut x, &|i| l.a(k, i), &a, l.na);
            put(&mut x, &|i| l.u(k, i), &u, l.nu);
        }
        if raw.duration.is_finite() {
            x[l.t] = raw.duration;
        }
    }
    let np = p.ocp.params.len();
    for (i, &v) in prev.params.iter().enumerate().take(np) {
        x[p.nlp.p0 + i] = v;
    }
    for (j, &v) in [prev.c1, prev.c2].iter().enumerate().take(p.ocp.n_costs) {
        if v.is_finite() {
            x[p.nlp.c0 + j] = v;
        }
    }
    Ok(p.nlp.set_initial_point(&x)?)
}
