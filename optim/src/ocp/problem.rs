//! Multiphase optimal-control problem description (paper Sect. 4.1–4.2, eq. 51 and 57).
//!
//! A problem is a sequence of [`Phase`]s, each with a prescribed mode (its node function), a
//! free duration T⁽ⁱ⁾ with bounds, differential states x, algebraic node variables a (e.g. q̈,
//! ω̇, λ so that the dynamics is imposed in implicit form), controls u; cost integrands L_j
//! (eq. 51c) accumulated into global cost states c_j(t_f) (eq. 60); static parameters (e.g.
//! the impact impulse ι of eq. 40); and [`PointFunction`]s over phase end points, durations
//! and parameters for the event (57c) and linkage (57d) constraints. [`Scheme`], [`Objective`]
//! and [`VarRef`] are defined in [`crate::terms`], below the errors that name them.

use bf_codegen::graph::{Graph, Id};

pub use crate::terms::{Objective, Scheme, VarRef};

pub use bf_codegen::nodefn::NodeFunction;

/// Event/linkage constraints `lo ≤ e(…) ≤ hi` over end points, durations and parameters.
#[derive(Debug, Clone)]
pub struct PointFunction {
    /// Name (for diagnostics).
    pub name: String,
    /// Expression graph.
    pub graph: Graph,
    /// Graph variable ↔ problem variable.
    pub vars: Vec<(u32, VarRef)>,
    /// Values of other graph inputs.
    pub fixed: Vec<(u32, f64)>,
    /// The constraint expressions.
    pub outputs: Vec<Id>,
    /// Their bounds.
    pub bounds: Vec<(f64, f64)>,
    /// What each row is, for the rows a reader may need told apart (e.g. the impulse cone
    /// among an impact's rows); empty, or shorter than `outputs`, where the function's name
    /// says enough.
    pub row_names: Vec<String>,
}

/// Initial guess of a phase: samples at normalised times s ∈ [0, 1] (ascending), linearly
/// interpolated; one sample means a constant guess.
#[derive(Debug, Clone, PartialEq, Default, serde::Serialize, serde::Deserialize)]
pub struct PhaseGuess {
    /// Normalised sample times.
    pub s: Vec<f64>,
    /// States at the samples.
    pub x: Vec<Vec<f64>>,
    /// Algebraic variables at the samples.
    pub a: Vec<Vec<f64>>,
    /// Controls at the samples.
    pub u: Vec<Vec<f64>>,
    /// Duration.
    pub duration: f64,
}

impl PhaseGuess {
    /// A constant guess.
    pub fn constant(x: Vec<f64>, a: Vec<f64>, u: Vec<f64>, duration: f64) -> Self {
        PhaseGuess {
            s: vec![0.0],
            x: vec![x],
            a: vec![a],
            u: vec![u],
            duration,
        }
    }

    fn interp(s: &[f64], v: &[Vec<f64>], t: f64, n: usize) -> Vec<f64> {
        if v.is_empty() {
            return vec![0.0; n];
        }
        let s = &s[..s.len().min(v.len())];
        let k = s.partition_point(|&x| x <= t);
        let pick = |i: usize| -> Vec<f64> {
            let mut r = v[i].clone();
            r.resize(n, 0.0);
            r
        };
        if k == 0 {
            return pick(0);
        }
        if k >= s.len() {
            return pick(s.len() - 1);
        }
        let (a, b) = (pick(k - 1), pick(k));
        let th = if s[k] > s[k - 1] {
            (t - s[k - 1]) / (s[k] - s[k - 1])
        } else {
            0.0
        };
        a.iter().zip(&b).map(|(a, b)| a + th * (b - a)).collect()
    }

    /// States at normalised time `t` (`n` components).
    pub fn x_at(&self, t: f64, n: usize) -> Vec<f64> {
        Self::interp(&self.s, &self.x, t, n)
    }
    /// Algebraic variables at `t`.
    pub fn a_at(&self, t: f64, n: usize) -> Vec<f64> {
        Self::interp(&self.s, &self.a, t, n)
    }
    /// Controls at `t`.
    pub fn u_at(&self, t: f64, n: usize) -> Vec<f64> {
        Self::interp(&self.s, &self.u, t, n)
    }
}

/// One phase of the multiphase problem.
#[derive(Debug, Clone)]
pub struct Phase {
    /// Name (e.g. "free", "stick").
    pub name: String,
    /// Node function (dynamics, path constraints, cost integrands).
    pub node: NodeFunction,
    /// Bounds of the states (also at the phase end points).
    pub x_bounds: Vec<(f64, f64)>,
    /// Bounds of the algebraic variables.
    pub a_bounds: Vec<(f64, f64)>,
    /// Bounds of the controls.
    pub u_bounds: Vec<(f64, f64)>,
    /// Bounds of the duration.
    pub duration_bounds: (f64, f64),
    /// Collocation points (per phase; per element for Radau see [`Scheme`]).
    pub points: usize,
    /// Initial guess.
    pub guess: PhaseGuess,
    /// A path lower bound that tightens away from the phase's end (`None`: every node has
    /// the node function's bounds).
    pub end_ramp: Option<EndRamp>,
}

/// A lower bound on one path output that depends on the collocation node: at normalised
/// phase time s ∈ [0, 1] the lower bound of path output `index` is its node-function bound
/// plus `clearance` · min(1, (1 − s) / `ramp`). Far from the end the output keeps
/// `clearance` above its bound; over the last `ramp` of the phase the extra bound falls
/// linearly to 0, so that the phase may end on the plain bound (an approach that must stay
/// clear of an obstacle it reaches at its end).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct EndRamp {
    /// Index into the node function's `path`.
    pub index: usize,
    /// Extra lower bound away from the end (≥ 0, in the output's units).
    pub clearance: f64,
    /// Share of the phase over which the extra bound falls to 0, in (0, 1].
    pub ramp: f64,
}

impl EndRamp {
    /// The extra lower bound at normalised phase time `s` ∈ [0, 1].
    pub fn extra(&self, s: f64) -> f64 {
        self.clearance * ((1.0 - s) / self.ramp).clamp(0.0, 1.0)
    }
}

/// A static decision parameter.
#[derive(Debug, Clone, PartialEq)]
pub struct Param {
    /// Name.
    pub name: String,
    /// Lower bound.
    pub lower: f64,
    /// Upper bound.
    pub upper: f64,
    /// Initial guess.
    pub guess: f64,
}

/// A multiphase optimal-control problem (eq. 57).
#[derive(Debug, Clone)]
pub struct Ocp {
    /// Phases in time order.
    pub phases: Vec<Phase>,
    /// Number of cost states.
    pub n_costs: usize,
    /// Static parameters.
    pub params: Vec<Param>,
    /// Event and linkage constraints.
    pub points: Vec<PointFunction>,
    /// Bounds of the cost states c_j(t_f) (empty: unbounded); e.g. a required rotation angle.
    pub cost_bounds: Vec<(f64, f64)>,
    /// Objective.
    pub objective: Objective,
    /// Transcription.
    pub scheme: Scheme,
}
