//! Solution extraction: per-phase times, states at the state points, algebraic variables and
//! controls at the collocation nodes ([`extract`]), and Lagrange interpolation (dense output);
//! [`PhaseValues`] evaluates each element's own polynomials (exact interpolation onto another
//! mesh); its elements (`element_views`) also serve the error estimate
//! ([`super::estimate`]).

use super::nodes::lagrange_basis;
use super::transcription::Transcription;

/// One phase of a solved (or guessed) trajectory.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct PhaseTrajectory {
    /// Start time t_0 of the phase (sum of the previous durations).
    pub t0: f64,
    /// Duration T.
    pub duration: f64,
    /// τ ∈ [−1, 1] of the state points.
    pub state_tau: Vec<f64>,
    /// States at the state points.
    pub x: Vec<Vec<f64>>,
    /// τ of the collocation nodes.
    pub node_tau: Vec<f64>,
    /// Index of each node's state point.
    pub node_state: Vec<usize>,
    /// Quadrature weight of each node on [−1, 1] (∫ f dt ≈ T/2 Σ w_k f_k).
    pub node_weight: Vec<f64>,
    /// Algebraic variables at the nodes.
    pub a: Vec<Vec<f64>>,
    /// Controls at the nodes.
    pub u: Vec<Vec<f64>>,
    /// Element ranges of state points (interpolation support).
    pub elements: Vec<(usize, usize)>,
}

impl PhaseTrajectory {
    /// Checks that the phase's collocation data fit together, so that interpolating them
    /// (a warm start, the dense samples) cannot index out of them: one state row per state
    /// point, each node with its weight, state point, algebraic and control row, rows of one
    /// width each, τ increasing within [−1, 1], and elements of at least two state points
    /// that start at the first, share their end points and end at the last (or, for
    /// Legendre–Gauss, at the one before the phase end), and a finite positive duration. The
    /// error says what does not fit, naming the field.
    pub fn check_shape(&self) -> Result<(), String> {
        // A warm start's phase lengths are its durations; a non-positive one is no phase.
        if !(self.duration.is_finite() && self.duration > 0.0) {
            return Err(format!(
                "`duration` is {}: a phase lasts a finite positive time",
                self.duration
            ));
        }
        let n = self.state_tau.len();
        if n < 2 || self.x.len() != n {
            return Err(format!(
                "{} state points (`state_tau`) and {} state rows (`x`): a phase needs at \
                 least two, one row each",
                n,
                self.x.len()
            ));
        }
        let m = self.node_tau.len();
        for (what, len) in [
            ("node_state", self.node_state.len()),
            ("node_weight", self.node_weight.len()),
            ("a", self.a.len()),
            ("u", self.u.len()),
        ] {
            if len != m {
                return Err(format!(
                    "{m} nodes (`node_tau`) but {len} entries of `{what}`"
                ));
            }
        }
        for (what, rows) in [("x", &self.x), ("a", &self.a), ("u", &self.u)] {
            if let Some(first) = rows.first()
                && let Some(k) = rows.iter().position(|r| r.len() != first.len())
            {
                return Err(format!(
                    "`{what}[{k}]` has {} values, `{what}[0]` {}",
                    rows[k].len(),
                    first.len()
                ));
            }
        }
        if let Some(k) = (1..n).find(|&k| {
            !(self.state_tau[k] > self.state_tau[k - 1] && self.state_tau[k].abs() <= 1.0)
        }) {
            return Err(format!(
                "`state_tau` is not increasing within [-1, 1] at entry {k}"
            ));
        }
        if let Some(k) = self.node_state.iter().position(|&p| p >= n) {
            return Err(format!(
                "`node_state[{k}]` = {} is not one of the {n} state points",
                self.node_state[k]
            ));
        }
        if self.elements.is_empty() {
            return Err("no `elements`: every mesh has at least one".to_string());
        }
        let mut next = 0;
        for (e, &(a, b)) in self.elements.iter().enumerate() {
            if a != next || b < a + 2 || b > n {
                return Err(format!(
                    "`elements[{e}]` = ({a}, {b}) does not continue the elements before it \
                     (it should start at state point {next} and hold at least two of the \
                     {n})"
                ));
            }
            next = b - 1;
        }
        if !(next + 1 == n || next + 2 == n) {
            return Err(format!(
                "the elements end at state point {}, the phase at {}",
                next,
                n - 1
            ));
        }
        Ok(())
    }

    /// Time of normalised τ.
    pub fn time(&self, tau: f64) -> f64 {
        self.t0 + 0.5 * (tau + 1.0) * self.duration
    }

    fn element_of(&self, tau: f64) -> (usize, usize) {
        for &(a, b) in &self.elements {
            if tau <= self.state_tau[b - 1] {
                return (a, b);
            }
        }
        *self.elements.last().unwrap_or(&(0, self.state_tau.len()))
    }

    /// State at τ (Lagrange interpolation within the element).
    pub fn x_at(&self, tau: f64) -> Vec<f64> {
        let (a, b) = self.element_of(tau);
        let l = lagrange_basis(&self.state_tau[a..b], tau);
        let nx = self.x.first().map_or(0, |v| v.len());
        (0..nx)
            .map(|i| (a..b).zip(&l).map(|(p, w)| w * self.x[p][i]).sum())
            .collect()
    }

    fn node_interp(&self, v: &[Vec<f64>], tau: f64) -> Vec<f64> {
        let (a, b) = self.element_of(tau);
        let ks: Vec<usize> = (0..self.node_tau.len())
            .filter(|&k| (a..b).contains(&self.node_state[k]))
            .collect();
        let taus: Vec<f64> = ks.iter().map(|&k| self.node_tau[k]).collect();
        let l = lagrange_basis(&taus, tau);
        let n = v.first().map_or(0, |r| r.len());
        (0..n)
            .map(|i| ks.iter().zip(&l).map(|(&k, w)| w * v[k][i]).sum())
            .collect()
    }

    /// Controls at τ (polynomial through the element's collocation nodes).
    pub fn u_at(&self, tau: f64) -> Vec<f64> {
        self.node_interp(&self.u, tau)
    }

    /// Algebraic variables at τ.
    pub fn a_at(&self, tau: f64) -> Vec<f64> {
        self.node_interp(&self.a, tau)
    }
}

/// Splits the NLP vector `x` into phase trajectories.
///
/// # Panics
///
/// If `x` is shorter than the transcription's number of variables
/// ([`Nlp::num_variables`](crate::ipm::Nlp::num_variables) of `tr`), as a
/// [`Solution::x`](crate::ipm::Solution::x) of a solve of `tr` never is.
pub fn extract(tr: &Transcription, x: &[f64]) -> Vec<PhaseTrajectory> {
    let mut t0 = 0.0;
    let mut out = Vec::new();
    for l in &tr.phases {
        let duration = x[l.t];
        let ns = l.mesh.n_state_points();
        let xs = (0..ns)
            .map(|p| (0..l.nx).map(|i| x[l.x(p, i)]).collect())
            .collect();
        let nk = l.mesh.colloc.len();
        let a = (0..nk)
            .map(|k| (0..l.na).map(|i| x[l.a(k, i)]).collect())
            .collect();
        let u = (0..nk)
            .map(|k| (0..l.nu).map(|i| x[l.u(k, i)]).collect())
            .collect();
        out.push(PhaseTrajectory {
            t0,
            duration,
            state_tau: l.mesh.state_tau.clone(),
            x: xs,
            node_tau: l.mesh.colloc.iter().map(|c| c.tau).collect(),
            node_state: l.mesh.colloc.iter().map(|c| c.state_point).collect(),
            node_weight: l.mesh.colloc.iter().map(|c| c.weight).collect(),
            a,
            u,
            elements: l.mesh.elements.iter().map(|r| (r.start, r.end)).collect(),
        });
        t0 += duration;
    }
    out
}

/// One element of a solved phase: its τ interval, state support points and own nodes.
pub(super) struct ElementView {
    pub(super) ta: f64,
    pub(super) tb: f64,
    pub(super) states: std::ops::Range<usize>,
    pub(super) nodes: Vec<usize>,
}

/// The elements of `tr` with their own nodes. A node belongs to the last element whose state
/// points contain its state point: a Radau element's last support point is the next element's
/// first node (hp-Radau) or the phase end (no node), while the support points of a
/// Legendre–Gauss element are the phase start and all its Gauss nodes, the last of them
/// included. The element ends at its last support point unless that point is one of its own
/// nodes (Legendre–Gauss); then it ends at the next state point (the phase end).
pub(super) fn element_views(tr: &PhaseTrajectory) -> Vec<ElementView> {
    let elements = usable_elements(tr);
    // The owner of each state point: the last element that contains it (later elements
    // overwrite earlier ones), found once rather than per node and element.
    let mut owner: Vec<Option<usize>> = vec![None; tr.state_tau.len()];
    for (e, &(a, b)) in elements.iter().enumerate() {
        owner[a..b].iter_mut().for_each(|o| *o = Some(e));
    }
    let mut nodes: Vec<Vec<usize>> = vec![Vec::new(); elements.len()];
    for (k, &p) in tr.node_state.iter().enumerate().take(tr.node_tau.len()) {
        if let Some(&Some(e)) = owner.get(p) {
            nodes[e].push(k);
        }
    }
    elements
        .iter()
        .zip(nodes)
        .map(|(&(a, b), nodes)| {
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

/// The elements of `tr` that can carry a polynomial: at least two state points, all of them
/// in the phase.
fn usable_elements(tr: &PhaseTrajectory) -> Vec<(usize, usize)> {
    tr.elements
        .iter()
        .copied()
        .filter(|&(a, b)| b >= a + 2 && b <= tr.state_tau.len())
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
pub(super) fn element_values(tr: &PhaseTrajectory, ev: &ElementView, t: f64) -> [Vec<f64>; 3] {
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

/// The values of a phase at any τ, each quantity from the element that contains τ in the
/// half-open sense [start, end) (the last element also owns τ = 1): a solution interpolated
/// onto another mesh exactly (a warm start). The elements and their own nodes are found once,
/// since a warm start onto a mesh of hundreds of points evaluates the phase at every point.
pub struct PhaseValues<'a> {
    tr: &'a PhaseTrajectory,
    views: Vec<ElementView>,
}

impl<'a> PhaseValues<'a> {
    /// The elements of `tr`.
    pub fn new(tr: &'a PhaseTrajectory) -> Self {
        PhaseValues {
            tr,
            views: element_views(tr),
        }
    }

    /// State, algebraic variables and controls at τ.
    pub fn at(&self, tau: f64) -> [Vec<f64>; 3] {
        let ev = &self.views;
        let idx = ev
            .iter()
            .position(|e| tau < e.tb)
            .unwrap_or(ev.len().saturating_sub(1));
        match ev.get(idx) {
            Some(e) => element_values(self.tr, e, tau),
            None => [vec![], vec![], vec![]],
        }
    }
}

#[cfg(test)]
mod tests {
    use super::{PhaseTrajectory, PhaseValues, element_views, usable_elements};
    use crate::ocp::Scheme;
    use crate::ocp::mesh::{Mesh, MeshSpec};

    /// The quadratic every quantity of the test phase follows: a state, algebraic variables and
    /// controls sampled from it are interpolated exactly by any element of at least three
    /// support points.
    fn f(t: f64) -> Vec<f64> {
        vec![1.0 + t, 2.0 * t * t - 0.5, 0.25 - t * t + 3.0 * t]
    }

    /// A phase on `mesh` whose states, algebraic variables and controls are `f` at its points
    /// (the algebraic variables and controls shifted, so each quantity is a different curve).
    fn phase(mesh: &Mesh) -> PhaseTrajectory {
        PhaseTrajectory {
            t0: 0.0,
            duration: 1.0,
            state_tau: mesh.state_tau.clone(),
            x: mesh.state_tau.iter().map(|&t| f(t)).collect(),
            node_tau: mesh.colloc.iter().map(|c| c.tau).collect(),
            node_state: mesh.colloc.iter().map(|c| c.state_point).collect(),
            node_weight: mesh.colloc.iter().map(|c| c.weight).collect(),
            a: mesh.colloc.iter().map(|c| f(c.tau + 0.5)).collect(),
            u: mesh.colloc.iter().map(|c| f(-c.tau)).collect(),
            elements: mesh.elements.iter().map(|r| (r.start, r.end)).collect(),
        }
    }

    /// The elements' own nodes as first written: each node given to the last element whose
    /// state points contain its state point, searched per element and node.
    fn nodes_by_search(tr: &PhaseTrajectory) -> Vec<Vec<usize>> {
        let elements = usable_elements(tr);
        let owner = |p: usize| elements.iter().rposition(|&(a, b)| (a..b).contains(&p));
        (0..elements.len())
            .map(|e| {
                (0..tr.node_tau.len())
                    .filter(|&k| owner(tr.node_state[k]) == Some(e))
                    .collect()
            })
            .collect()
    }

    /// The elements' own nodes found in one pass are those of the per-node search, on
    /// hp-Radau (a node on every element's first point, none at the phase end),
    /// Legendre–Gauss (one element, the phase end a state point of its own) and a refined
    /// non-uniform Radau mesh; and [`PhaseValues`] reproduces the quadratics the phase was
    /// sampled from at 201 points of [−1, 1], element ends included.
    #[test]
    fn one_pass_element_nodes_match_the_search() {
        let refined = MeshSpec::uniform(4, 3).unwrap().refined(
            &[1.0, 1e-9, 1.0, 1e-9],
            1e-3,
            Default::default(),
        );
        let meshes = [
            Mesh::new(Scheme::Radau { elements: 3 }, 10).unwrap(),
            Mesh::new(Scheme::Lg, 12).unwrap(),
            Mesh::from_spec(&refined).unwrap(),
        ];
        for mesh in &meshes {
            let tr = phase(mesh);
            let views = element_views(&tr);
            let want = nodes_by_search(&tr);
            assert_eq!(views.len(), want.len());
            for (v, w) in views.iter().zip(&want) {
                assert_eq!(&v.nodes, w);
            }
            let pv = PhaseValues::new(&tr);
            for i in 0..=200 {
                let t = -1.0 + 2.0 * i as f64 / 200.0;
                let [x, a, u] = pv.at(t);
                for (got, want) in [(x, f(t)), (a, f(t + 0.5)), (u, f(-t))] {
                    for (g, w) in got.iter().zip(&want) {
                        assert!((g - w).abs() <= 1e-12, "τ {t}: {got:?} against {want:?}");
                    }
                    assert_eq!(got.len(), 3);
                }
            }
        }
    }

    /// The phases of every scheme pass [`PhaseTrajectory::check_shape`], and each kind of edit
    /// that would make their interpolation index out of the data is named.
    #[test]
    fn check_shape_accepts_every_scheme_and_names_what_does_not_fit() {
        let meshes = [
            Mesh::new(Scheme::Radau { elements: 3 }, 10).unwrap(),
            Mesh::new(Scheme::Lg, 12).unwrap(),
        ];
        for mesh in &meshes {
            let tr = phase(mesh);
            assert_eq!(tr.check_shape(), Ok(()));
            type Edit = fn(&mut PhaseTrajectory);
            let edits: [(Edit, &str); 7] = [
                (
                    |t| {
                        t.x.pop();
                    },
                    "state rows",
                ),
                (
                    |t| {
                        t.u.pop();
                    },
                    "entries of `u`",
                ),
                (
                    |t| {
                        t.x[1].pop();
                    },
                    "`x[1]` has 2 values",
                ),
                (|t| t.node_state[0] = 999, "`node_state[0]` = 999"),
                (
                    |t| {
                        t.elements.remove(0);
                    },
                    "elements",
                ),
                (|t| t.state_tau.swap(1, 2), "`state_tau` is not increasing"),
                (|t| t.duration = -0.5, "`duration` is -0.5"),
            ];
            for (edit, needle) in edits {
                let mut bad = tr.clone();
                edit(&mut bad);
                let e = bad.check_shape().unwrap_err();
                assert!(e.contains(needle), "{e} lacks {needle:?}");
            }
        }
    }
}
