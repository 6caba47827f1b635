//! Collocation problems with closed-form optima, for tests of this crate and of the layers
//! built on it (the collocation counterpart of bf-sim's `toys`).
//!
//! * [`double_integrator_phase`]: ṗ = v, v̇ = u with the cost integrands [u², 1]; with
//!   [`rest_to_rest`] (p, v from (0, 0) to (1, 0)) over a fixed unit horizon the optimum is the
//!   cubic p* = 3t² − 2t³, u* = 6 − 12t, ∫u² = 12, which lies in every collocation space of
//!   degree ≥ 3 (so the transcription must reproduce it to round-off).
//! * [`brachistochrone`]: minimum time from rest at the origin to (1, 0.6) under g = 9.81,
//!   whose optimum is the cycloid ([`cycloid_time`]); smooth but not polynomial, so errors
//!   decay spectrally in the number of points.
//!
//! Both come in an `implicit` form with an algebraic variable a = v̇ and the equality path
//! constraint a − f = 0, the form of the ball-and-finger node functions (eq. 26, 29).

use bf_codegen::graph::{Graph, Id};

use super::problem::{
    NodeFunction, Objective, Ocp, Phase, PhaseGuess, PointFunction, Scheme, VarRef,
};

/// "No bound" for the toys' variables (the transcription treats |b| ≥ 1e19 as infinite).
const INF: f64 = 1e20;

/// Gravity of the brachistochrone, m/s².
const G: f64 = 9.81;

/// End point of the brachistochrone, (x, y) with y pointing down.
const TARGET: (f64, f64) = (1.0, 0.6);

/// The node function with states `0..nx`, control `nx`, duration variable `nx + 1` and the
/// rates `xdot` (in terms of those variables); `implicit`: the last rate f becomes the
/// algebraic variable a = `nx + 2` with the equality path constraint a − f = 0.
fn node_function(
    mut g: Graph,
    nx: u32,
    mut xdot: Vec<Id>,
    implicit: bool,
    costs: Vec<Id>,
) -> NodeFunction {
    let (a, path) = match xdot.pop() {
        Some(f) if implicit => {
            let a = g.var(nx + 2);
            let r = g.sub(a, f);
            xdot.push(a);
            (vec![nx + 2], vec![r])
        }
        last => {
            xdot.extend(last);
            (vec![], vec![])
        }
    };
    NodeFunction {
        graph: g,
        x: (0..nx).collect(),
        a,
        u: vec![nx],
        duration: nx + 1,
        fixed: vec![],
        xdot,
        path_bounds: vec![(0.0, 0.0); path.len()],
        path,
        costs,
    }
}

/// A point function `"boundary"` that fixes state components at the start of phase `first`
/// (`(i, value)` in `initial`) and at the end of phase `last` (`terminal`).
pub fn fixed_ends(
    first: usize,
    initial: &[(usize, f64)],
    last: usize,
    terminal: &[(usize, f64)],
) -> PointFunction {
    let mut graph = Graph::new();
    let starts = initial
        .iter()
        .map(|&(i, v)| (VarRef::Initial { phase: first, i }, v));
    let ends = terminal
        .iter()
        .map(|&(i, v)| (VarRef::Final { phase: last, i }, v));
    let (mut vars, mut outputs, mut bounds) = (Vec::new(), Vec::new(), Vec::new());
    for (k, (r, v)) in starts.chain(ends).enumerate() {
        vars.push((k as u32, r));
        outputs.push(graph.var(k as u32));
        bounds.push((v, v));
    }
    PointFunction {
        name: "boundary".into(),
        graph,
        vars,
        fixed: vec![],
        outputs,
        bounds,
        row_names: Vec::new(),
    }
}

/// The double integrator ṗ = v, v̇ = u (states `[p, v]`, control `u`) with the cost integrands
/// `[u², 1]` on `points` collocation points, the duration in `duration_bounds` starting from
/// `duration_guess`; `implicit`: v̇ = a with a − u = 0.
pub fn double_integrator_phase(
    points: usize,
    implicit: bool,
    duration_bounds: (f64, f64),
    duration_guess: f64,
) -> Phase {
    let mut g = Graph::new();
    let (v, u) = (g.var(1), g.var(2));
    let u2 = g.square(u);
    let one = g.one();
    let node = node_function(g, 2, vec![v, u], implicit, vec![u2, one]);
    let na = node.a.len();
    Phase {
        name: "di".into(),
        node,
        x_bounds: vec![(-INF, INF); 2],
        a_bounds: vec![(-INF, INF); na],
        u_bounds: vec![(-INF, INF)],
        duration_bounds,
        points,
        guess: PhaseGuess::constant(vec![0.0, 0.0], vec![0.0; na], vec![0.0], duration_guess),
        end_ramp: None,
    }
}

/// Rest to rest over `nphases` double-integrator phases: (p, v) = (0, 0) at the start of the
/// first phase, (1, 0) at the end of the last, and continuity of (p, v) between phases.
pub fn rest_to_rest(nphases: usize) -> Vec<PointFunction> {
    let last = nphases - 1;
    let mut pts = vec![fixed_ends(
        0,
        &[(0, 0.0), (1, 0.0)],
        last,
        &[(0, 1.0), (1, 0.0)],
    )];
    for p in 1..nphases {
        let mut g = Graph::new();
        let (a0, a1, b0, b1) = (g.var(0), g.var(1), g.var(2), g.var(3));
        let d0 = g.sub(a0, b0);
        let d1 = g.sub(a1, b1);
        pts.push(PointFunction {
            name: format!("link {p}"),
            graph: g,
            vars: vec![
                (0, VarRef::Final { phase: p - 1, i: 0 }),
                (1, VarRef::Final { phase: p - 1, i: 1 }),
                (2, VarRef::Initial { phase: p, i: 0 }),
                (3, VarRef::Initial { phase: p, i: 1 }),
            ],
            fixed: vec![],
            outputs: vec![d0, d1],
            bounds: vec![(0.0, 0.0); 2],
            row_names: Vec::new(),
        });
    }
    pts
}

/// Rest-to-rest double integrator on [0, 1], min ∫u² (J* = 12), one phase of 8 points on one
/// Radau element.
pub fn double_integrator(implicit: bool) -> Ocp {
    Ocp {
        phases: vec![double_integrator_phase(8, implicit, (1.0, 1.0), 1.0)],
        n_costs: 2,
        params: vec![],
        points: rest_to_rest(1),
        cost_bounds: vec![],
        objective: Objective::Cost(0),
        scheme: Scheme::Radau { elements: 1 },
    }
}

/// Minimum-time brachistochrone from rest at the origin to (1, 0.6), g = 9.81 (y down):
/// ẋ = v sin u, ẏ = v cos u, v̇ = g cos u (states `[x, y, v]`, control `u`, cost integrand 1),
/// on `points` collocation points of `scheme`; `implicit`: v̇ = a with a − g cos u = 0.
pub fn brachistochrone(implicit: bool, scheme: Scheme, points: usize) -> Ocp {
    let mut g = Graph::new();
    let (v, u) = (g.var(2), g.var(3));
    let (s, c) = (g.sin(u), g.cos(u));
    let xd = g.mul(v, s);
    let yd = g.mul(v, c);
    let gc = g.constant(G);
    let vd = g.mul(gc, c);
    let one = g.one();
    let node = node_function(g, 3, vec![xd, yd, vd], implicit, vec![one]);
    let na = node.a.len();
    let phase = Phase {
        name: "b".into(),
        node,
        x_bounds: vec![(-10.0, 10.0); 3],
        a_bounds: vec![(-INF, INF); na],
        u_bounds: vec![(-0.5, 3.5)],
        duration_bounds: (0.01, 5.0),
        points,
        guess: PhaseGuess {
            s: vec![0.0, 1.0],
            x: vec![vec![0.0; 3], vec![TARGET.0, TARGET.1, 3.0]],
            a: vec![vec![0.0; na]],
            u: vec![vec![1.0]],
            duration: 0.5,
        },
        end_ramp: None,
    };
    Ocp {
        phases: vec![phase],
        n_costs: 1,
        params: vec![],
        points: vec![fixed_ends(
            0,
            &[(0, 0.0), (1, 0.0), (2, 0.0)],
            0,
            &[(0, TARGET.0), (1, TARGET.1)],
        )],
        cost_bounds: vec![],
        objective: Objective::Cost(0),
        scheme,
    }
}

/// Optimal time of [`brachistochrone`]: the cycloid x = R(φ − sin φ), y = R(1 − cos φ)
/// through (1, 0.6) (φ_f by bisection of (φ − sin φ)/(1 − cos φ) = 1/0.6), T = φ_f √(R/g).
pub fn cycloid_time() -> f64 {
    let f = |p: f64| (p - libm::sin(p)) / (1.0 - libm::cos(p)) - TARGET.0 / TARGET.1;
    let (mut lo, mut hi) = (1e-3, 2.0 * std::f64::consts::PI - 1e-3);
    for _ in 0..200 {
        let mid = 0.5 * (lo + hi);
        if f(mid) > 0.0 { hi = mid } else { lo = mid }
    }
    let phi = 0.5 * (lo + hi);
    let r = TARGET.1 / (1.0 - libm::cos(phi));
    phi * (r / G).sqrt()
}
