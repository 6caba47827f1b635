//! Custom hp-Radau meshes and the collocation error estimate used for mesh refinement
//! (paper Sect. 5: the transcription of eq. 57; the estimate follows Patterson, Hager & Rao,
//! "A ph mesh refinement method for optimal control", OCAM 36 (2015), and Darby, Hager & Rao,
//! OCAM 32 (2011)).
//!
//! * [`MeshSpec`]: element boundaries in τ ∈ [−1, 1] and the number N_e of Legendre–Gauss–Radau
//!   points per element (the state polynomial of element e has degree N_e); serialisable so a
//!   refined mesh can be stored with a solution.
//! * [`Mesh::radau_custom`]: the collocation mesh of a [`MeshSpec`] (defects of eq. 58 with the
//!   element scale s_e = h_e / 2).
//! * [`collocation_errors`]: per element, the relative difference between the state polynomial
//!   X̂ and its re-integration X̃(s_j) = X̂(s_0) + (h_e/2)(T/2) ∫ f(X̂, A*, Û) at N_e + 1 fresh
//!   LGR points (PHR 2015 eq. 25–27). The dynamics is implicit here (ẋ = f(x, a) with
//!   r(x, a, u) = 0, e.g. eq. 26 and 29 with q̈, ω̇, λ as algebraic variables a): at each
//!   extra point the interpolated Â is corrected to the minimum-norm A* with r(X̂, A*, Û) = 0
//!   (Gauss–Newton), so that the estimate measures the dynamics defect between the nodes. The
//!   residuals of equality path constraints that depend on the states only (e.g. the stick
//!   constraint Δv = 0, eq. 14) are added as absolute errors.
//! * [`MeshSpec::refined`]: the ph rule of PHR 2015: an element with error e > tol gets
//!   P = ⌈log_N(e / tol)⌉ more points if N + P ≤ N_max, else it is split into
//!   max(2, ⌈(N + P) / N_min⌉) equal elements of N_min points.

use serde::{Deserialize, Serialize};

use super::block::GraphFn;
use super::nodes::{differentiation_matrix, lagrange_basis, legendre_gauss, legendre_gauss_radau};
use super::problem::{Ocp, Scheme};
use super::trajectory::PhaseTrajectory;
use super::transcription::{Colloc, Mesh};
use crate::OptimError;
use crate::error::{MeshDefect, PhaseDefect};

/// An hp-Radau mesh of one phase.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct MeshSpec {
    /// Element boundaries in τ: strictly increasing, first −1, last +1 (one more than
    /// `degrees`).
    pub breaks: Vec<f64>,
    /// LGR points per element (≥ 2); the state polynomial of the element has this degree.
    pub degrees: Vec<usize>,
}

/// Limits of the ph refinement rule ([`MeshSpec::refined`]).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct HpRule {
    /// Points per element after a split (≥ 2).
    pub n_min: usize,
    /// Largest number of points per element reached by raising the degree.
    pub n_max: usize,
}

impl Default for HpRule {
    fn default() -> Self {
        HpRule {
            n_min: 4,
            n_max: 12,
        }
    }
}

impl MeshSpec {
    /// `elements` equal elements of `degree` points each.
    pub fn uniform(elements: usize, degree: usize) -> Result<MeshSpec, OptimError> {
        let k = elements as f64;
        let s = MeshSpec {
            breaks: (0..=elements).map(|e| -1.0 + 2.0 * e as f64 / k).collect(),
            degrees: vec![degree; elements],
        };
        s.validate()?;
        Ok(s)
    }

    /// The mesh [`Mesh::new`] builds for a Radau `scheme` with `points` per phase
    /// (`points.div_ceil(elements).max(2)` points in each of the equal elements).
    pub fn from_scheme(scheme: Scheme, points: usize) -> Result<MeshSpec, OptimError> {
        match scheme {
            Scheme::Radau { elements } if elements > 0 => {
                Self::uniform(elements, points.div_ceil(elements).max(2))
            }
            scheme => Err(OptimError::CustomMeshScheme { scheme }),
        }
    }

    /// Checks the invariants documented on the fields.
    pub fn validate(&self) -> Result<(), OptimError> {
        let bad = |d: MeshDefect| Err(OptimError::InvalidMesh(d));
        if self.degrees.is_empty() || self.breaks.len() != self.degrees.len() + 1 {
            return bad(MeshDefect::BreakCount {
                breaks: self.breaks.len(),
                elements: self.degrees.len(),
            });
        }
        let (first, last) = (self.breaks[0], self.breaks[self.breaks.len() - 1]);
        if first != -1.0 || last != 1.0 {
            return bad(MeshDefect::Span { first, last });
        }
        if let Some(element) = self
            .breaks
            .windows(2)
            .position(|w| w[1].partial_cmp(&w[0]) != Some(std::cmp::Ordering::Greater))
        {
            return bad(MeshDefect::NotIncreasing { element });
        }
        let mut degrees = self.degrees.iter().enumerate();
        if let Some((element, &degree)) = degrees.find(|&(_, &d)| !(2..=64).contains(&d)) {
            return bad(MeshDefect::Degree { element, degree });
        }
        Ok(())
    }

    /// Number of elements.
    pub fn n_elements(&self) -> usize {
        self.degrees.len()
    }

    /// Number of collocation points.
    pub fn n_points(&self) -> usize {
        self.degrees.iter().sum()
    }

    /// The mesh after one ph refinement step with element errors `errors` (one per element):
    /// elements with error ≤ `tol` (or a non-finite error, which no refinement can fix) are
    /// kept, the others get more points or are split (see the module docs). Returns `self`
    /// unchanged when every error is ≤ `tol`.
    pub fn refined(&self, errors: &[f64], tol: f64, rule: HpRule) -> MeshSpec {
        let n_min = rule.n_min.max(2);
        let n_max = rule.n_max.max(n_min);
        let mut breaks = vec![self.breaks[0]];
        let mut degrees = Vec::new();
        for (e, &n) in self.degrees.iter().enumerate() {
            let (a, b) = (self.breaks[e], self.breaks[e + 1]);
            let err = errors.get(e).copied().unwrap_or(0.0);
            if err.is_nan() || err <= tol || !err.is_finite() || tol <= 0.0 {
                breaks.push(b);
                degrees.push(n);
                continue;
            }
            let p = ((err / tol).ln() / (n as f64).ln()).ceil().max(1.0) as usize;
            if n + p <= n_max {
                breaks.push(b);
                degrees.push(n + p);
            } else {
                let parts = (n + p).div_ceil(n_min).max(2);
                for j in 1..=parts {
                    breaks.push(if j == parts {
                        b
                    } else {
                        a + (b - a) * j as f64 / parts as f64
                    });
                    degrees.push(n_min);
                }
            }
        }
        MeshSpec { breaks, degrees }
    }
}

impl Mesh {
    /// The Radau mesh with element boundaries `breaks` (τ, from −1 to +1) and `degrees[e]` LGR
    /// points in element e (the element's start included, its end excluded; the phase end is
    /// the last state point).
    pub fn radau_custom(breaks: &[f64], degrees: &[usize]) -> Result<Mesh, OptimError> {
        let spec = MeshSpec {
            breaks: breaks.to_vec(),
            degrees: degrees.to_vec(),
        };
        spec.validate()?;
        let mut state_tau = Vec::new();
        let mut colloc = Vec::new();
        let mut ranges = Vec::new();
        for (e, &n) in degrees.iter().enumerate() {
            let (t, w) = legendre_gauss_radau(n);
            let mut sup = t.clone();
            sup.push(1.0);
            let d = differentiation_matrix(&sup);
            let half = 0.5 * (breaks[e + 1] - breaks[e]);
            let base = state_tau.len();
            for j in 0..n {
                let tau = breaks[e] + (t[j] + 1.0) * half;
                state_tau.push(tau);
                colloc.push(Colloc {
                    state_point: base + j,
                    tau,
                    scale: half,
                    weight: w[j] * half,
                    drow: (0..=n).map(|i| (base + i, d[j][i])).collect(),
                });
            }
            ranges.push(base..base + n + 1);
        }
        state_tau.push(1.0);
        Ok(Mesh {
            state_tau,
            colloc,
            gauss_end: false,
            elements: ranges,
        })
    }

    /// [`Mesh::radau_custom`] of a [`MeshSpec`].
    pub fn from_spec(spec: &MeshSpec) -> Result<Mesh, OptimError> {
        Self::radau_custom(&spec.breaks, &spec.degrees)
    }
}

/// One element of a solved phase: its τ interval, state support points and own nodes.
struct ElementView {
    ta: f64,
    tb: f64,
    states: std::ops::Range<usize>,
    nodes: Vec<usize>,
}

/// The elements of `tr` with their own nodes. A node belongs to the last element whose state
/// points contain its state point: a Radau element's last support point is the next element's
/// first node (hp-Radau) or the phase end (no node), while the support points of a
/// Legendre–Gauss element are the phase start and all its Gauss nodes, the last of them
/// included. The element ends at its last support point unless that point is one of its own
/// nodes (Legendre–Gauss); then it ends at the next state point (the phase end).
fn element_views(tr: &PhaseTrajectory) -> Vec<ElementView> {
    let elements: Vec<(usize, usize)> = tr
        .elements
        .iter()
        .copied()
        .filter(|&(a, b)| b >= a + 2 && b <= tr.state_tau.len())
        .collect();
    let owner = |p: usize| elements.iter().rposition(|&(a, b)| (a..b).contains(&p));
    elements
        .iter()
        .enumerate()
        .map(|(e, &(a, b))| {
            let nodes: Vec<usize> = (0..tr.node_tau.len())
                .filter(|&k| owner(tr.node_state[k]) == Some(e))
                .collect();
            let last_is_own_node = nodes.iter().any(|&k| tr.node_state[k] == b - 1);
            let end = if last_is_own_node && b < tr.state_tau.len() {
                b
            } else {
                b - 1
            };
            ElementView {
                ta: tr.state_tau[a],
                tb: tr.state_tau[end],
                states: a..b,
                nodes,
            }
        })
        .collect()
}

/// Evaluates a phase's state polynomial, algebraic variables and controls inside one element.
fn interp_rows(tau_sup: &[f64], rows: &[&[f64]], t: f64) -> Vec<f64> {
    let n = rows.first().map_or(0, |r| r.len());
    if tau_sup.is_empty() {
        return vec![0.0; n];
    }
    let l = lagrange_basis(tau_sup, t);
    (0..n)
        .map(|i| rows.iter().zip(&l).map(|(r, w)| w * r[i]).sum())
        .collect()
}

/// State, algebraic variables and controls of `tr` at τ ∈ element `ev` (the element's own
/// polynomials, also at its end points).
fn element_values(tr: &PhaseTrajectory, ev: &ElementView, t: f64) -> [Vec<f64>; 3] {
    let xs: Vec<&[f64]> = ev.states.clone().map(|p| tr.x[p].as_slice()).collect();
    let x = interp_rows(&tr.state_tau[ev.states.clone()], &xs, t);
    let nt: Vec<f64> = ev.nodes.iter().map(|&k| tr.node_tau[k]).collect();
    let a_rows: Vec<&[f64]> = ev.nodes.iter().map(|&k| tr.a[k].as_slice()).collect();
    let u_rows: Vec<&[f64]> = ev.nodes.iter().map(|&k| tr.u[k].as_slice()).collect();
    [
        x,
        interp_rows(&nt, &a_rows, t),
        interp_rows(&nt, &u_rows, t),
    ]
}

/// The values of `tr` at τ, each quantity from the element that contains τ in the half-open
/// sense [start, end) (the last element also owns τ = 1). Used to interpolate a solution onto
/// another mesh exactly (a warm start).
pub fn values_at(tr: &PhaseTrajectory, tau: f64) -> [Vec<f64>; 3] {
    let ev = element_views(tr);
    let idx = ev
        .iter()
        .position(|e| tau < e.tb)
        .unwrap_or(ev.len().saturating_sub(1));
    match ev.get(idx) {
        Some(e) => element_values(tr, e, tau),
        None => [vec![], vec![], vec![]],
    }
}

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
