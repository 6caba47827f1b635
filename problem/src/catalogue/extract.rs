//! Between a transcribed problem ([`BuiltProblem`]) and its solution record ([`OcpSolution`]):
//! [`solution_at`] builds the record at an NLP point (durations, mean ω, the samples of
//! [`Samples`] with h eq. 4, σ eq. 18 and α eq. 2); [`warm_initial_point`] sets a problem's
//! initial point from a record on another mesh; [`node_kernel_source`] says whether the node
//! functions ran on emitted kernels.

use bf_optim::ipm::{Counters, Nlp, Status, Timing};
use bf_optim::ocp::trajectory::PhaseValues;
use bf_optim::ocp::{PhaseTrajectory, extract};

use super::BuiltProblem;
use crate::ProblemError;
use crate::node::PhaseMode;
use crate::points::Diagnostics;
use crate::solution::{OcpSolution, Samples};

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

/// The period's mean ball angular velocity ω̄ = (1/T) ∫ ω dt over the phases `traj` of a
/// finger with `nq` joints (ω the states 2nq … 2nq + 2), by each phase's collocation
/// quadrature: the `mean_omega` of [`solution_at`], which `track` measures every period
/// against. NaN where the data lack those states (an edited file).
pub fn mean_omega(traj: &[PhaseTrajectory], nq: usize) -> [f64; 3] {
    let period: f64 = traj.iter().map(|t| t.duration).sum();
    let mut mean = [0.0; 3];
    for tr in traj {
        for (k, &sp) in tr.node_state.iter().enumerate() {
            let w = tr.node_weight.get(k).copied().unwrap_or(f64::NAN);
            for (i, m) in mean.iter_mut().enumerate() {
                let omega = tr.x.get(sp).and_then(|r| r.get(2 * nq + i));
                *m += 0.5 * tr.duration * w * omega.copied().unwrap_or(f64::NAN);
            }
        }
    }
    if period > 0.0 {
        mean.iter_mut().for_each(|v| *v /= period);
    }
    mean
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
    let mean = mean_omega(&traj, nq);
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
        // The caller knows the file text (`bf_scene::Scene` keeps no source text).
        scene_toml: String::new(),
        scene_params: Vec::new(),
        active_bounds: None,
        search_settings: None,
        impact_law: p.settings.impact_law,
        cone_margin: p.settings.cone_margin,
        impulse_cone: p.settings.impulse_cone,
        torque_margin: p.settings.torque_margin,
        approach_clearance: p.settings.approach_clearance,
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
    for (phase, (l, raw)) in p.nlp.phases.iter().zip(&prev.raw).enumerate() {
        let shape = |reason: String| ProblemError::WarmStartShape { phase, reason };
        raw.check_shape().map_err(shape)?;
        for (what, rows, n) in [
            ("x", &raw.x, l.nx),
            ("a", &raw.a, l.na),
            ("u", &raw.u, l.nu),
        ] {
            if let Some(r) = rows.first().filter(|r| r.len() != n) {
                return Err(shape(format!(
                    "its rows of `{what}` have {} values, the problem's phase {n}",
                    r.len()
                )));
            }
        }
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
        let raw_values = PhaseValues::new(raw);
        for (pt, &tau) in l.mesh.state_tau.iter().enumerate() {
            let [xv, _, _] = raw_values.at(tau);
            put(&mut x, &|i| l.x(pt, i), &xv, l.nx);
        }
        for (k, c) in l.mesh.colloc.iter().enumerate() {
            let [_, a, u] = raw_values.at(c.tau);
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
