//! Pseudospectral transcription of an [`Ocp`] into a sparse [`Nlp`] (paper Sect. 4–5).
//!
//! Per phase with duration T and collocation nodes τ_k (Legendre–Gauss, or Radau per element):
//!
//! ```text
//! Radau     Σ_j D_kj X_j − s_k (T/2) f(X_k, A_k, U_k) = 0        (k = 1..N_c, per element)
//! LG        X_k − X_0 − (T/2) Σ_j A_kj f(X_j, A_j, U_j) = 0       (k = 1..N, A = D₁⁻¹)
//! LG end    X_f − X_0 − Σ_k w_k (T/2) f_k = 0                     (Benson/Garg form)
//! path      g_L + e(t̂_k) ≤ g(X_k, A_k, U_k) ≤ g_U  (e = 0 unless the phase has an EndRamp)
//! costs     c_j − Σ_phases Σ_k w_k s_k (T/2) L_j(X_k, A_k, U_k) = 0   (eq. 51c, c(0) = 0)
//! ```
//! with s_k = 1/K for K Radau elements (1 for LG); in the path row, t̂_k = (τ_k + 1)/2 is the
//! node's normalised time and e the phase's [`EndRamp`](super::EndRamp) on one output
//! (a lower bound that tightens away from the phase's end). The objective is c_j or c_j/c_k (eq. 60), a
//! function of two NLP variables only, so its Hessian stays sparse. Event and linkage
//! constraints (57c–d) are [`PointFunction`](super::PointFunction)s. All nonlinear pieces are [`GraphFn`]s with
//! exact Jacobians and Hessians; the NLP's derivatives are their scattered sums.
//!
//! LG defects in integral form ([`integration_matrix`]): they are the differential defects
//! Σ_j D_kj X_j − (T/2) f_k (D on the support −1, τ_1..τ_N) multiplied by the invertible
//! A = D₁⁻¹, so the NLP has the same solutions and, in exact arithmetic, the same Newton steps.
//! Numerically they differ: the differential rows of one phase carry the O(N²) entries of D
//! (LG-30: row maxima 11 to 322, the largest rows also rescaled by the gradient-based NLP
//! scaling), the integral rows coefficients ±1 and (T/2)·A_kj with max |A_kj| = 0.11 (rows
//! summing to 1 + τ_k) — the form the Gauss quadrature end row already had. With the
//! differential rows the COT problems stalled with LG-30 (δ_w ≈ 1e-2 in every iteration,
//! MaxIterations) and `periodic-qc` only converged with an extra inactive period row; with the
//! integral rows both converge (numbers in BENCHMARKS.md and the root package's tests/ocp_lg.rs).
//! The sparsity is alike: per state component and phase the differential rows have a dense
//! N × (N + 1) block in the states and a diagonal in f, the integral rows two state columns and
//! a dense N × N block in f (plus one duplicate T triplet per node, summed by the solver).
//!
//! Optional linear rows bound a state between its state points (`between`:
//! [`Transcription::bound_states_between_points`]).

use super::block::{GraphFn, KernelUse};
pub use super::mesh::{Colloc, Mesh};
use super::problem::{Objective, Ocp, Scheme, VarRef};
use crate::OptimError;
use crate::error::{FunctionTooLarge, PhaseDefect, PointDefect};
use crate::ipm::{BOUND_INF, Nlp};

mod between;
mod nlp;

pub use between::{
    Between, MAX_ELEVATION, MAX_HULL_DEGREE, MAX_PER_INTERVAL, StateBoundBetweenPoints, hull_rows,
    sample_taus,
};

#[derive(Debug, Clone)]
struct Instance {
    f: usize,
    map: Vec<usize>,
    targets: Vec<Vec<(usize, f64)>>,
}

/// Variable and row offsets of one phase.
#[derive(Debug, Clone, PartialEq)]
pub struct PhaseLayout {
    /// Mesh.
    pub mesh: Mesh,
    /// Number of states, algebraic variables, controls.
    pub nx: usize,
    /// Algebraic variables per node.
    pub na: usize,
    /// Controls per node.
    pub nu: usize,
    /// First state variable (point-major: point p, component i at `x0 + p nx + i`).
    pub x0: usize,
    /// First algebraic variable (node-major).
    pub a0: usize,
    /// First control (node-major).
    pub u0: usize,
    /// Duration variable.
    pub t: usize,
}

impl PhaseLayout {
    /// Index of state component `i` at state point `p`.
    pub fn x(&self, p: usize, i: usize) -> usize {
        self.x0 + p * self.nx + i
    }
    /// Index of algebraic variable `i` at node `k`.
    pub fn a(&self, k: usize, i: usize) -> usize {
        self.a0 + k * self.na + i
    }
    /// Index of control `i` at node `k`.
    pub fn u(&self, k: usize, i: usize) -> usize {
        self.u0 + k * self.nu + i
    }
}

/// The transcribed NLP.
#[derive(Debug, Clone)]
pub struct Transcription {
    /// Per-phase layout.
    pub phases: Vec<PhaseLayout>,
    /// First parameter variable.
    pub p0: usize,
    /// First cost-state variable.
    pub c0: usize,
    /// Objective.
    pub objective: Objective,
    n: usize,
    m: usize,
    xl: Vec<f64>,
    xu: Vec<f64>,
    gl: Vec<f64>,
    gu: Vec<f64>,
    x_init: Vec<f64>,
    linear: Vec<(usize, usize, f64)>,
    fns: Vec<GraphFn>,
    inst: Vec<Instance>,
    jac_pattern: Vec<(usize, usize)>,
    hess_pattern: Vec<(usize, usize)>,
    /// Row names by range, for diagnostics.
    pub row_blocks: Vec<(String, std::ops::Range<usize>)>,
    /// Whether runs of four consecutive collocation nodes of a node function with batched
    /// kernels are evaluated in one batched call (default: on). The values are bitwise the
    /// same either way; off evaluates every node by itself (to time both).
    pub batch_nodes: bool,
}

/// The LG integration matrix A = D₁⁻¹, where D₁ = (D_kj), k, j = 1..N, is the Gauss
/// differentiation matrix without its column of the non-collocated X₀ (`mesh.colloc[k].drow`).
/// Since Σ_j D_kj = 0, A D₀ = −1, so A applied to the differential defects
/// Σ_j D_kj X_j − (T/2) f_k gives the integral defects X_k − X₀ − (T/2) Σ_j A_kj f_j (see the
/// module docs). Gauss–Jordan elimination with partial pivoting (N ≤ a few hundred).
pub fn integration_matrix(mesh: &Mesh) -> Result<Vec<Vec<f64>>, OptimError> {
    let n = mesh.colloc.len();
    // Augmented [D₁ | I].
    let mut m = vec![vec![0.0; 2 * n]; n];
    for (k, c) in mesh.colloc.iter().enumerate() {
        for &(sp, d) in &c.drow {
            if (1..=n).contains(&sp) {
                m[k][sp - 1] = d;
            }
        }
        m[k][n + k] = 1.0;
    }
    for col in 0..n {
        let piv = (col..n)
            .max_by(|&a, &b| m[a][col].abs().total_cmp(&m[b][col].abs()))
            .unwrap_or(col);
        let p = m[piv][col];
        if p.abs() <= 1e-300 || !p.is_finite() {
            return Err(OptimError::SingularDifferentiation { points: n });
        }
        m.swap(col, piv);
        m[col].iter_mut().for_each(|v| *v /= p);
        let pivot_row = m[col].clone();
        for (r, row) in m.iter_mut().enumerate() {
            let f = row[col];
            if r != col && f != 0.0 {
                for (v, pv) in row.iter_mut().zip(&pivot_row) {
                    *v -= f * pv;
                }
            }
        }
    }
    Ok(m.into_iter().map(|row| row[n..].to_vec()).collect())
}

fn clean_bound(v: f64, lower: bool) -> f64 {
    if v.is_nan() {
        if lower { -BOUND_INF } else { BOUND_INF }
    } else {
        v
    }
}

impl Transcription {
    /// Transcribes `ocp`.
    pub fn new(ocp: &Ocp) -> Result<Transcription, OptimError> {
        Self::with_meshes(ocp, &[])
    }

    /// Transcribes `ocp` with a custom hp-Radau mesh for phase i where `meshes[i]` is given
    /// (needs the Radau scheme); other phases use `ocp.scheme` and their `points`.
    pub fn with_meshes(
        ocp: &Ocp,
        meshes: &[Option<super::mesh::MeshSpec>],
    ) -> Result<Transcription, OptimError> {
        Self::with_kernels(ocp, meshes, KernelUse::Never)
    }

    /// [`Transcription::with_meshes`] with the phase node functions on emitted kernels where
    /// `kernels` has them; with [`KernelUse::Require`] a phase node function without an
    /// emitted kernel (its graphs changed since the kernels were emitted, or its shape was
    /// never emitted) is an error.
    pub fn with_kernels(
        ocp: &Ocp,
        meshes: &[Option<super::mesh::MeshSpec>],
        kernels: KernelUse,
    ) -> Result<Transcription, OptimError> {
        if meshes.len() > ocp.phases.len() {
            return Err(OptimError::PhaseCount {
                what: "meshes",
                found: meshes.len(),
                phases: ocp.phases.len(),
            });
        }
        if ocp.scheme == Scheme::Lg && meshes.iter().any(Option::is_some) {
            return Err(OptimError::CustomMeshScheme { scheme: ocp.scheme });
        }
        if ocp.phases.is_empty() {
            return Err(OptimError::NoPhases);
        }
        let nc = ocp.n_costs;
        match ocp.objective {
            Objective::Cost(j) if j < nc => {}
            Objective::Ratio(j, k) if j < nc && k < nc && j != k => {}
            objective => {
                return Err(OptimError::InvalidObjective {
                    objective,
                    costs: nc,
                });
            }
        }
        let mut n = 0;
        let mut layouts = Vec::new();
        for (pi, ph) in ocp.phases.iter().enumerate() {
            let nd = &ph.node;
            let (nx, na, nu) = (nd.x.len(), nd.a.len(), nd.u.len());
            let bad = |defect| OptimError::Phase {
                index: pi,
                name: ph.name.clone(),
                defect,
            };
            if nd.xdot.len() != nx {
                return Err(bad(PhaseDefect::XdotLength {
                    found: nd.xdot.len(),
                    states: nx,
                }));
            }
            if nd.costs.len() != nc {
                return Err(bad(PhaseDefect::CostCount {
                    found: nd.costs.len(),
                    costs: nc,
                }));
            }
            for (which, found, expected) in [
                ("path_bounds", nd.path_bounds.len(), nd.path.len()),
                ("x_bounds", ph.x_bounds.len(), nx),
                ("a_bounds", ph.a_bounds.len(), na),
                ("u_bounds", ph.u_bounds.len(), nu),
            ] {
                if found != expected {
                    return Err(bad(PhaseDefect::BoundsLength {
                        which,
                        found,
                        expected,
                    }));
                }
            }
            if let Some(r) = ph.end_ramp
                && !(r.index < nd.path.len()
                    && r.clearance.is_finite()
                    && r.clearance >= 0.0
                    && r.ramp > 0.0
                    && r.ramp <= 1.0)
            {
                return Err(bad(PhaseDefect::EndRamp {
                    index: r.index,
                    outputs: nd.path.len(),
                    clearance: r.clearance,
                    ramp: r.ramp,
                }));
            }
            let mesh = match meshes.get(pi) {
                Some(Some(spec)) => Mesh::from_spec(spec)?,
                _ => Mesh::new(ocp.scheme, ph.points)?,
            };
            let ns = mesh.n_state_points();
            let ncol = mesh.colloc.len();
            let x0 = n;
            let a0 = x0 + ns * nx;
            let u0 = a0 + ncol * na;
            let t = u0 + ncol * nu;
            n = t + 1;
            layouts.push(PhaseLayout {
                mesh,
                nx,
                na,
                nu,
                x0,
                a0,
                u0,
                t,
            });
        }
        let p0 = n;
        n += ocp.params.len();
        let c0 = n;
        n += nc;

        // Variable bounds and initial point.
        let mut xl = vec![-BOUND_INF; n];
        let mut xu = vec![BOUND_INF; n];
        let mut x_init = vec![0.0; n];
        for (ph, l) in ocp.phases.iter().zip(&layouts) {
            let g = &ph.guess;
            for (p, &tau) in l.mesh.state_tau.iter().enumerate() {
                let s = 0.5 * (tau + 1.0);
                let xg = g.x_at(s, l.nx);
                for i in 0..l.nx {
                    xl[l.x(p, i)] = clean_bound(ph.x_bounds[i].0, true);
                    xu[l.x(p, i)] = clean_bound(ph.x_bounds[i].1, false);
                    x_init[l.x(p, i)] = xg[i];
                }
            }
            for (k, c) in l.mesh.colloc.iter().enumerate() {
                let s = 0.5 * (c.tau + 1.0);
                let ag = g.a_at(s, l.na);
                let ug = g.u_at(s, l.nu);
                for i in 0..l.na {
                    xl[l.a(k, i)] = clean_bound(ph.a_bounds[i].0, true);
                    xu[l.a(k, i)] = clean_bound(ph.a_bounds[i].1, false);
                    x_init[l.a(k, i)] = ag[i];
                }
                for i in 0..l.nu {
                    xl[l.u(k, i)] = clean_bound(ph.u_bounds[i].0, true);
                    xu[l.u(k, i)] = clean_bound(ph.u_bounds[i].1, false);
                    x_init[l.u(k, i)] = ug[i];
                }
            }
            xl[l.t] = ph.duration_bounds.0;
            xu[l.t] = ph.duration_bounds.1;
            x_init[l.t] = g.duration;
        }
        if !ocp.cost_bounds.is_empty() {
            if ocp.cost_bounds.len() != nc {
                return Err(OptimError::CostBounds {
                    found: ocp.cost_bounds.len(),
                    costs: nc,
                });
            }
            for (j, b) in ocp.cost_bounds.iter().enumerate() {
                xl[c0 + j] = clean_bound(b.0, true);
                xu[c0 + j] = clean_bound(b.1, false);
            }
        }
        for (i, p) in ocp.params.iter().enumerate() {
            xl[p0 + i] = p.lower;
            xu[p0 + i] = p.upper;
            x_init[p0 + i] = p.guess;
        }

        // Rows.
        let mut m = 0;
        let mut gl = Vec::new();
        let mut gu = Vec::new();
        let mut linear = Vec::new();
        let mut fns = Vec::new();
        let mut inst = Vec::new();
        let mut row_blocks = Vec::new();
        let cost_row0 = {
            // cost rows are placed first so their index is known while scanning phases.
            for j in 0..nc {
                gl.push(0.0);
                gu.push(0.0);
                linear.push((j, c0 + j, 1.0));
            }
            m += nc;
            row_blocks.push(("cost states".to_string(), 0..nc));
            0
        };
        for (pi, (ph, l)) in ocp.phases.iter().zip(&layouts).enumerate() {
            let nd = &ph.node;
            // (T/2) ẋ, path rows, (T/2) L: the outputs node kernels are emitted from, so that
            // the lookup finds them by fingerprint.
            let mut col = nd.collocation();
            let n_path = nd.path.len();
            let f = GraphFn::with_backend(
                &mut col.graph,
                &col.outputs,
                &col.locals,
                &nd.fixed,
                kernels,
            );
            if col.graph.exceeded() {
                return Err(OptimError::Phase {
                    index: pi,
                    name: ph.name.clone(),
                    defect: PhaseDefect::GraphTooLarge(FunctionTooLarge {
                        function: "node",
                        limit: col.graph.limit(),
                    }),
                });
            }
            if matches!(kernels, KernelUse::Require(_)) && f.kernel_name().is_none() {
                return Err(OptimError::Phase {
                    index: pi,
                    name: ph.name.clone(),
                    defect: PhaseDefect::NoKernel,
                });
            }
            let fid = fns.len();
            fns.push(f);
            let ncol = l.mesh.colloc.len();
            let def0 = m;
            m += ncol * l.nx;
            for _ in 0..ncol * l.nx {
                gl.push(0.0);
                gu.push(0.0);
            }
            row_blocks.push((format!("phase {pi} ({}) defects", ph.name), def0..m));
            let end0 = m;
            if l.mesh.gauss_end {
                m += l.nx;
                let last = l.mesh.n_state_points() - 1;
                for i in 0..l.nx {
                    gl.push(0.0);
                    gu.push(0.0);
                    linear.push((end0 + i, l.x(last, i), 1.0));
                    linear.push((end0 + i, l.x(0, i), -1.0));
                }
                row_blocks.push((format!("phase {pi} ({}) quadrature end", ph.name), end0..m));
            }
            let path0 = m;
            m += ncol * n_path;
            for c in &l.mesh.colloc {
                for (j, b) in nd.path_bounds.iter().enumerate() {
                    let lower = match ph.end_ramp {
                        Some(r) if r.index == j => b.0 + r.extra(0.5 * (c.tau + 1.0)),
                        _ => b.0,
                    };
                    gl.push(clean_bound(lower, true));
                    gu.push(clean_bound(b.1, false));
                }
            }
            row_blocks.push((format!("phase {pi} ({}) path", ph.name), path0..m));
            // LG: integral-form defects (module docs); Radau: differential form per element.
            let integ = if l.mesh.gauss_end {
                Some(integration_matrix(&l.mesh)?)
            } else {
                None
            };
            for (k, c) in l.mesh.colloc.iter().enumerate() {
                for i in 0..l.nx {
                    if integ.is_some() {
                        linear.push((def0 + k * l.nx + i, l.x(c.state_point, i), 1.0));
                        linear.push((def0 + k * l.nx + i, l.x(0, i), -1.0));
                        continue;
                    }
                    for &(sp, dv) in &c.drow {
                        if dv != 0.0 {
                            linear.push((def0 + k * l.nx + i, l.x(sp, i), dv));
                        }
                    }
                }
                let mut map = Vec::new();
                for i in 0..l.nx {
                    map.push(l.x(c.state_point, i));
                }
                for i in 0..l.na {
                    map.push(l.a(k, i));
                }
                for i in 0..l.nu {
                    map.push(l.u(k, i));
                }
                map.push(l.t);
                let mut targets = Vec::new();
                for i in 0..l.nx {
                    let mut t = match &integ {
                        Some(a) => (0..ncol)
                            .map(|r| (def0 + r * l.nx + i, -c.scale * a[r][k]))
                            .filter(|e| e.1 != 0.0)
                            .collect(),
                        None => vec![(def0 + k * l.nx + i, -c.scale)],
                    };
                    if l.mesh.gauss_end {
                        t.push((end0 + i, -c.weight));
                    }
                    targets.push(t);
                }
                for i in 0..n_path {
                    targets.push(vec![(path0 + k * n_path + i, 1.0)]);
                }
                for j in 0..nc {
                    targets.push(vec![(cost_row0 + j, -c.weight)]);
                }
                inst.push(Instance {
                    f: fid,
                    map,
                    targets,
                });
            }
        }
        for pf in &ocp.points {
            let bad = |defect| OptimError::PointFunction {
                name: pf.name.clone(),
                defect,
            };
            if pf.outputs.len() != pf.bounds.len() {
                return Err(bad(PointDefect::BoundsLength {
                    outputs: pf.outputs.len(),
                    bounds: pf.bounds.len(),
                }));
            }
            let mut map = Vec::new();
            for &(_, r) in &pf.vars {
                let idx = match r {
                    VarRef::Initial { phase, i } | VarRef::Final { phase, i } => {
                        let l = layouts
                            .get(phase)
                            .filter(|l| i < l.nx)
                            .ok_or_else(|| bad(PointDefect::BadReference(r)))?;
                        if matches!(r, VarRef::Initial { .. }) {
                            l.x(0, i)
                        } else {
                            l.x(l.mesh.n_state_points() - 1, i)
                        }
                    }
                    VarRef::Duration(p) => layouts
                        .get(p)
                        .map(|l| l.t)
                        .ok_or_else(|| bad(PointDefect::BadReference(r)))?,
                    VarRef::Param(i) => {
                        if i >= ocp.params.len() {
                            return Err(bad(PointDefect::BadReference(r)));
                        }
                        p0 + i
                    }
                };
                map.push(idx);
            }
            let mut sorted = map.clone();
            sorted.sort_unstable();
            if sorted.windows(2).any(|w| w[0] == w[1]) {
                return Err(bad(PointDefect::ReadsTwice));
            }
            let mut graph = pf.graph.clone();
            let locals: Vec<u32> = pf.vars.iter().map(|v| v.0).collect();
            let f = GraphFn::new(&mut graph, &pf.outputs, &locals, &pf.fixed);
            if graph.exceeded() {
                return Err(bad(PointDefect::GraphTooLarge(FunctionTooLarge {
                    function: "point",
                    limit: graph.limit(),
                })));
            }
            let r0 = m;
            let targets = (0..pf.outputs.len()).map(|i| vec![(r0 + i, 1.0)]).collect();
            for b in &pf.bounds {
                gl.push(clean_bound(b.0, true));
                gu.push(clean_bound(b.1, false));
            }
            m += pf.outputs.len();
            row_blocks.push((pf.name.clone(), r0..m));
            inst.push(Instance {
                f: fns.len(),
                map,
                targets,
            });
            fns.push(f);
        }

        let mut jac_pattern: Vec<(usize, usize)> = linear.iter().map(|&(r, c, _)| (r, c)).collect();
        let mut hess_pattern = Vec::new();
        for it in &inst {
            let f = &fns[it.f];
            for &(o, lv) in f.jacobian_pattern() {
                for &(r, _) in &it.targets[o] {
                    jac_pattern.push((r, it.map[lv]));
                }
            }
            for &(i, j) in f.hessian_pattern() {
                let (a, b) = (it.map[i], it.map[j]);
                hess_pattern.push((a.max(b), a.min(b)));
            }
        }
        match ocp.objective {
            Objective::Cost(_) => {}
            Objective::Ratio(j, k) => {
                let (a, b) = (c0 + j, c0 + k);
                hess_pattern.push((a.max(b), a.min(b)));
                hess_pattern.push((c0 + k, c0 + k));
            }
        }
        let mut tr = Transcription {
            phases: layouts,
            p0,
            c0,
            objective: ocp.objective,
            n,
            m,
            xl,
            xu,
            gl,
            gu,
            x_init,
            linear,
            fns,
            inst,
            jac_pattern,
            hess_pattern,
            row_blocks,
            batch_nodes: true,
        };
        tr.init_cost_states();
        Ok(tr)
    }

    /// Sets the cost-state entries of the initial point to the quadrature of their integrands
    /// along the guess (consistent c(t_f)); a ratio's denominator that vanishes there is set to
    /// 1 so that the objective is finite at the start.
    fn init_cost_states(&mut self) {
        let nc = self.n - self.c0;
        for j in 0..nc {
            self.x_init[self.c0 + j] = 0.0;
        }
        let mut g = vec![0.0; self.m];
        self.constraints(&self.x_init.clone(), &mut g);
        for j in 0..nc {
            let v = -g[j];
            self.x_init[self.c0 + j] = if v.is_finite() { v } else { 0.0 };
        }
        if let Objective::Ratio(_, k) = self.objective
            && self.x_init[self.c0 + k].abs() < 1e-8
        {
            self.x_init[self.c0 + k] = 1.0;
        }
    }

    fn locals(&self, it: &Instance, x: &[f64]) -> Vec<f64> {
        it.map.iter().map(|&i| x[i]).collect()
    }

    /// Replaces the initial point (e.g. for a warm start); length `n`.
    pub fn set_initial_point(&mut self, x: &[f64]) -> Result<(), OptimError> {
        if x.len() != self.n {
            return Err(OptimError::DimensionMismatch {
                what: "initial point",
                expected: self.n,
                found: x.len(),
            });
        }
        self.x_init.copy_from_slice(x);
        Ok(())
    }

    /// The current initial point.
    pub fn initial(&self) -> &[f64] {
        &self.x_init
    }

    /// Constraint bounds (lower, upper).
    pub fn row_bounds(&self) -> (&[f64], &[f64]) {
        (&self.gl, &self.gu)
    }

    /// Variable bounds (lower, upper).
    pub fn var_bounds(&self) -> (&[f64], &[f64]) {
        (&self.xl, &self.xu)
    }

    /// Largest violation of the constraint bounds at `x`, and the row where it occurs.
    pub fn max_violation(&self, x: &[f64]) -> (f64, usize) {
        let mut g = vec![0.0; self.m];
        self.constraints(x, &mut g);
        let mut worst = (0.0, 0);
        for r in 0..self.m {
            let v = (self.gl[r] - g[r]).max(g[r] - self.gu[r]).max(0.0);
            if v > worst.0 || v.is_nan() {
                worst = (v, r);
            }
        }
        worst
    }

    /// The compiled node function of every phase (phase order), e.g. to see whether it runs
    /// on an emitted kernel ([`GraphFn::kernel_name`]).
    pub fn phase_functions(&self) -> &[GraphFn] {
        // The phases' node functions are compiled first, one per phase, before the point
        // functions.
        &self.fns[..self.phases.len()]
    }

    /// Replaces the bounds of the rows of the block `name` (a point function's name, see
    /// [`Transcription::row_blocks`]), e.g. the fixed value of an initial state that is
    /// re-solved from several values without transcribing the problem again. Errors when no
    /// block has that name, `bounds` has another length than the block, or a bound is NaN or
    /// its lower end above its upper.
    pub fn set_block_bounds(
        &mut self,
        name: &str,
        bounds: &[(f64, f64)],
    ) -> Result<(), OptimError> {
        let rows = self
            .row_blocks
            .iter()
            .find(|b| b.0 == name)
            .map(|b| b.1.clone())
            .unwrap_or(0..0);
        if rows.len() != bounds.len() || rows.is_empty() {
            return Err(OptimError::DimensionMismatch {
                what: "bounds of the named row block",
                expected: rows.len(),
                found: bounds.len(),
            });
        }
        for (row, &(lo, hi)) in rows.zip(bounds) {
            if lo.is_nan() || hi.is_nan() || lo > hi {
                return Err(OptimError::InvalidBounds {
                    what: "constraint",
                    index: row,
                    lower: lo,
                    upper: hi,
                });
            }
            self.gl[row] = clean_bound(lo, true);
            self.gu[row] = clean_bound(hi, false);
        }
        Ok(())
    }

    /// Name of the block that contains `row`.
    pub fn row_name(&self, row: usize) -> &str {
        self.row_blocks
            .iter()
            .find(|b| b.1.contains(&row))
            .map(|b| b.0.as_str())
            .unwrap_or("?")
    }
}
