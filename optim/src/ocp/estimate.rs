//! The collocation error estimate used for mesh refinement (paper Sect. 5; Patterson, Hager &
//! Rao, "A ph mesh refinement method for optimal control", OCAM 36 (2015), and Darby, Hager &
//! Rao, OCAM 32 (2011)).
//!
//! [`collocation_errors`]: per element, the relative difference between the state polynomial
//! X̂ and its re-integration X̃(s_j) = X̂(s_0) + (h_e/2)(T/2) ∫ f(X̂, A*, Û) at N_e + 1 fresh LGR
//! points (PHR 2015 eq. 25–27). The dynamics is implicit here (ẋ = f(x, a) with r(x, a, u) = 0,
//! e.g. eq. 26 and 29 with q̈, ω̇, λ as algebraic variables a): at each extra point the
//! interpolated Â is corrected to the minimum-norm A* with r(X̂, A*, Û) = 0 (Gauss–Newton), so
//! that the estimate measures the dynamics defect between the nodes. The residuals of equality
//! path constraints that depend on the states only (e.g. the stick constraint Δv = 0, eq. 14)
//! are added as absolute errors. The elements and their polynomials are the solved
//! trajectory's ([`super::trajectory`]); [`MeshSpec::refined`](super::MeshSpec::refined) turns
//! the errors into the next mesh.

use super::block::GraphFn;
use super::nodes::{lagrange_basis, legendre_gauss, legendre_gauss_radau};
use super::problem::Ocp;
use super::trajectory::{PhaseTrajectory, element_values, element_views};
use crate::OptimError;
use crate::error::PhaseDefect;

/// Solves the small dense symmetric positive definite system `a y = b` by Cholesky; `false` if
/// `a` is not numerically positive definite.
fn cholesky_solve(a: &mut [Vec<f64>], b: &mut [f64]) -> bool {
    let n = b.len();
    for j in 0..n {
        let mut d = a[j][j];
        for k in 0..j {
            d -= a[j][k] * a[j][k];
        }
        if d.is_nan() || d <= 0.0 {
            return false;
        }
        let d = d.sqrt();
        a[j][j] = d;
        for i in j + 1..n {
            let mut s = a[i][j];
            for k in 0..j {
                s -= a[i][k] * a[j][k];
            }
            a[i][j] = s / d;
        }
    }
    for i in 0..n {
        let mut s = b[i];
        for k in 0..i {
            s -= a[i][k] * b[k];
        }
        b[i] = s / a[i][i];
    }
    for i in (0..n).rev() {
        let mut s = b[i];
        for k in i + 1..n {
            s -= a[k][i] * b[k];
        }
        b[i] = s / a[i][i];
    }
    b.iter().all(|v| v.is_finite())
}

/// The node function of one phase compiled for the estimate: outputs ẋ and the equality path
/// constraints; rows that depend on a (solved for A*) and rows of the states only.
struct PhaseEval {
    f: GraphFn,
    nx: usize,
    na: usize,
    nu: usize,
    /// Output index of each a-dependent equality row, with its value.
    alg_rows: Vec<(usize, f64)>,
    /// Output index of each state-only equality row, with its value.
    state_rows: Vec<(usize, f64)>,
}

impl PhaseEval {
    fn new(ph: &super::problem::Phase) -> PhaseEval {
        let nd = &ph.node;
        let mut graph = nd.graph.clone();
        let mut outputs = nd.xdot.clone();
        let mut eq = Vec::new();
        for (i, (&id, &(lo, hi))) in nd.path.iter().zip(&nd.path_bounds).enumerate() {
            if lo == hi && lo.is_finite() {
                eq.push((i, lo));
                outputs.push(id);
            }
        }
        let mut locals = nd.x.clone();
        locals.extend(&nd.a);
        locals.extend(&nd.u);
        locals.push(nd.duration);
        let f = GraphFn::new(&mut graph, &outputs, &locals, &nd.fixed);
        let (nx, na, nu) = (nd.x.len(), nd.a.len(), nd.u.len());
        let mut depends_on_a = vec![false; outputs.len()];
        for &(o, l) in f.jacobian_pattern() {
            if (nx..nx + na).contains(&l) {
                depends_on_a[o] = true;
            }
        }
        let (mut alg_rows, mut state_rows) = (Vec::new(), Vec::new());
        for (k, &(_, v)) in eq.iter().enumerate() {
            let o = nx + k;
            if depends_on_a[o] {
                alg_rows.push((o, v));
            } else {
                state_rows.push((o, v));
            }
        }
        PhaseEval {
            f,
            nx,
            na,
            nu,
            alg_rows,
            state_rows,
        }
    }

    /// ẋ at (x, a, u) after correcting a to the minimum-norm solution of the a-dependent
    /// equality rows (Gauss–Newton from the interpolated a); also the largest state-only
    /// equality residual.
    fn xdot(&self, x: &[f64], a: &[f64], u: &[f64], duration: f64) -> (Vec<f64>, f64) {
        let mut loc: Vec<f64> = x.iter().chain(a).chain(u).copied().collect();
        loc.push(duration);
        let m = self.alg_rows.len();
        if m > 0 && self.na > 0 {
            let row_of: std::collections::BTreeMap<usize, usize> = self
                .alg_rows
                .iter()
                .enumerate()
                .map(|(r, &(o, _))| (o, r))
                .collect();
            for _ in 0..8 {
                let y = self.f.eval(&loc);
                let r: Vec<f64> = self.alg_rows.iter().map(|&(o, v)| y[o] - v).collect();
                let rn = r.iter().fold(0.0f64, |s, v| s.max(v.abs()));
                if !rn.is_finite() || rn < 1e-13 {
                    break;
                }
                let mut j = vec![vec![0.0; self.na]; m];
                for (&(o, l), v) in self.f.jacobian_pattern().iter().zip(self.f.jacobian(&loc)) {
                    if let Some(&ri) = row_of.get(&o)
                        && (self.nx..self.nx + self.na).contains(&l)
                    {
                        j[ri][l - self.nx] = v;
                    }
                }
                let mut jj = vec![vec![0.0; m]; m];
                let mut diag_max = 0.0f64;
                for p in 0..m {
                    for q in 0..=p {
                        let s: f64 = (0..self.na).map(|c| j[p][c] * j[q][c]).sum();
                        jj[p][q] = s;
                        jj[q][p] = s;
                    }
                    diag_max = diag_max.max(jj[p][p]);
                }
                // A tiny Levenberg term keeps rank-deficient rows (more rows than unknowns)
                // solvable in the least-squares sense.
                for (p, row) in jj.iter_mut().enumerate() {
                    row[p] += 1e-12 * diag_max + 1e-300;
                }
                let mut yv = r.clone();
                if !cholesky_solve(&mut jj, &mut yv) {
                    break;
                }
                for c in 0..self.na {
                    let d: f64 = (0..m).map(|p| j[p][c] * yv[p]).sum();
                    loc[self.nx + c] -= d;
                }
            }
        }
        let y = self.f.eval(&loc);
        let sres = self
            .state_rows
            .iter()
            .fold(0.0f64, |s, &(o, v)| s.max((y[o] - v).abs()));
        (y[..self.nx].to_vec(), sres)
    }
}

/// Integration matrix of the LGR points `s` (plus the end point +1): row j holds
/// ∫_{−1}^{σ_j} ℓ_l(σ) dσ for σ_j = s_1, …, s_{M−1}, +1 (the integral to s_0 = −1 is 0).
fn integration_matrix(s: &[f64]) -> Vec<Vec<f64>> {
    let m = s.len();
    let (g, gw) = legendre_gauss(m + 1);
    let mut ends: Vec<f64> = s[1..].to_vec();
    ends.push(1.0);
    ends.iter()
        .map(|&b| {
            let half = 0.5 * (b + 1.0);
            let mut row = vec![0.0; m];
            for (gk, wk) in g.iter().zip(&gw) {
                let l = lagrange_basis(s, -1.0 + (gk + 1.0) * half);
                for (r, v) in row.iter_mut().zip(l) {
                    *r += wk * half * v;
                }
            }
            row
        })
        .collect()
}

/// Collocation error estimate of every element of every phase of a solved `ocp` (see the
/// module docs): per phase, per element, the largest over the state components and N_e + 1
/// fresh LGR points of |X̃ − X̂| / (1 + max_p |X_p|) (max over the phase's state points), or the
/// residual of a state-only equality path constraint if larger.
pub fn collocation_errors(
    ocp: &Ocp,
    traj: &[PhaseTrajectory],
) -> Result<Vec<Vec<f64>>, OptimError> {
    if traj.len() != ocp.phases.len() {
        return Err(OptimError::PhaseCount {
            what: "trajectories",
            found: traj.len(),
            phases: ocp.phases.len(),
        });
    }
    let mut out = Vec::new();
    for (index, (ph, tr)) in ocp.phases.iter().zip(traj).enumerate() {
        let ev = PhaseEval::new(ph);
        let dims_ok = tr.x.iter().all(|v| v.len() == ev.nx)
            && tr.a.iter().all(|v| v.len() == ev.na)
            && tr.u.iter().all(|v| v.len() == ev.nu)
            && tr.node_state.len() == tr.node_tau.len()
            && tr.a.len() == tr.node_tau.len()
            && tr.u.len() == tr.node_tau.len()
            && tr.x.len() == tr.state_tau.len()
            && tr.node_state.iter().all(|&p| p < tr.x.len());
        if !dims_ok {
            return Err(OptimError::Phase {
                index,
                name: ph.name.clone(),
                defect: PhaseDefect::TrajectoryShape,
            });
        }
        let scale: Vec<f64> = (0..ev.nx)
            .map(|i| 1.0 + tr.x.iter().fold(0.0f64, |m, x| m.max(x[i].abs())))
            .collect();
        let mut errs = Vec::new();
        for e in element_views(tr) {
            let n = e.states.len() - 1;
            let (s, _) = legendre_gauss_radau(n + 1);
            let im = integration_matrix(&s);
            let half = 0.5 * (e.tb - e.ta);
            let tau_of = |sv: f64| e.ta + (sv + 1.0) * half;
            let mut fs = Vec::new();
            let mut xs = Vec::new();
            let mut worst = 0.0f64;
            for &sv in &s {
                let [x, a, u] = element_values(tr, &e, tau_of(sv));
                let (f, sres) = ev.xdot(&x, &a, &u, tr.duration);
                let r = sres / (1.0 + x.iter().fold(0.0f64, |m, v| m.max(v.abs())));
                worst = if r.is_nan() { f64::NAN } else { worst.max(r) };
                fs.push(f);
                xs.push(x);
            }
            let [x_end, _, _] = element_values(tr, &e, e.tb);
            let c = half * 0.5 * tr.duration;
            for (j, row) in im.iter().enumerate() {
                let xhat = if j + 1 < s.len() { &xs[j + 1] } else { &x_end };
                for i in 0..ev.nx {
                    let integ: f64 = row.iter().zip(&fs).map(|(w, f)| w * f[i]).sum();
                    let xt = xs[0][i] + c * integ;
                    let d = (xt - xhat[i]).abs() / scale[i];
                    // NaN marks a broken solution: keep it visible.
                    worst = if d.is_nan() || worst.is_nan() {
                        f64::NAN
                    } else {
                        worst.max(d)
                    };
                }
            }
            errs.push(worst);
        }
        out.push(errs);
    }
    Ok(out)
}
