//! Hock–Schittkowski test problems (W. Hock, K. Schittkowski, "Test Examples for Nonlinear
//! Programming Codes", Lecture Notes in Economics and Mathematical Systems 187, Springer 1981).
//! Each problem records the published starting point, bounds, optimal objective `f*` and (where
//! the book gives it) the optimal point `x*`, so the transcription can be checked independently
//! of the solver (`f(x*) ≈ f*`, `x*` feasible).
//!
//! Constraints are written as in the book: `g(x) ≥ 0` (inequality) or `g(x) = 0` (equality).

#![allow(dead_code)]

pub mod dual;

use bf_optim::ipm::{Nlp, NlpScaling, Settings, Solution, Status};
use dual::D;

const INF: f64 = f64::INFINITY;

/// One HS problem with dense derivative patterns evaluated by hyper-dual numbers.
pub struct Hs {
    pub name: &'static str,
    pub tags: &'static str,
    pub x0: Vec<f64>,
    pub xl: Vec<f64>,
    pub xu: Vec<f64>,
    /// Number of equality constraints (the first `neq` of `g`); the rest are `g ≥ 0`.
    pub neq: usize,
    pub m: usize,
    pub f: fn(&[D]) -> D,
    pub g: fn(&[D]) -> Vec<D>,
    pub fstar: f64,
    pub xstar: Option<Vec<f64>>,
}

fn lift(x: &[f64]) -> Vec<D> {
    x.iter().map(|&v| D::cst(v)).collect()
}

impl Hs {
    fn n(&self) -> usize {
        self.x0.len()
    }
    pub fn f_val(&self, x: &[f64]) -> f64 {
        (self.f)(&lift(x)).a
    }
    pub fn g_val(&self, x: &[f64]) -> Vec<f64> {
        (self.g)(&lift(x)).iter().map(|d| d.a).collect()
    }
    /// Max violation of bounds and constraints at x.
    pub fn violation(&self, x: &[f64]) -> f64 {
        let mut v = 0.0f64;
        for j in 0..self.n() {
            v = v.max(self.xl[j] - x[j]).max(x[j] - self.xu[j]);
        }
        for (i, gi) in self.g_val(x).into_iter().enumerate() {
            v = v.max(if i < self.neq { gi.abs() } else { -gi });
        }
        v
    }
}

impl Nlp for Hs {
    fn num_variables(&self) -> usize {
        self.n()
    }
    fn num_constraints(&self) -> usize {
        self.m
    }
    fn variable_bounds(&self, lower: &mut [f64], upper: &mut [f64]) {
        lower.copy_from_slice(&self.xl);
        upper.copy_from_slice(&self.xu);
    }
    fn constraint_bounds(&self, lower: &mut [f64], upper: &mut [f64]) {
        for i in 0..self.m {
            lower[i] = 0.0;
            upper[i] = if i < self.neq { 0.0 } else { INF };
        }
    }
    fn initial_point(&self, x: &mut [f64]) {
        x.copy_from_slice(&self.x0);
    }
    fn objective(&self, x: &[f64]) -> f64 {
        self.f_val(x)
    }
    fn gradient(&self, x: &[f64], grad: &mut [f64]) {
        let mut xd = lift(x);
        for j in 0..self.n() {
            xd[j].b = 1.0;
            grad[j] = (self.f)(&xd).b;
            xd[j].b = 0.0;
        }
    }
    fn constraints(&self, x: &[f64], g: &mut [f64]) {
        for (i, v) in self.g_val(x).into_iter().enumerate() {
            g[i] = v;
        }
    }
    fn jacobian_structure(&self) -> Vec<(usize, usize)> {
        let mut s = Vec::new();
        for i in 0..self.m {
            for j in 0..self.n() {
                s.push((i, j));
            }
        }
        s
    }
    fn jacobian_values(&self, x: &[f64], values: &mut [f64]) {
        let n = self.n();
        let mut xd = lift(x);
        for j in 0..n {
            xd[j].b = 1.0;
            let g = (self.g)(&xd);
            for i in 0..self.m {
                values[i * n + j] = g[i].b;
            }
            xd[j].b = 0.0;
        }
    }
    fn hessian_structure(&self) -> Vec<(usize, usize)> {
        let mut s = Vec::new();
        for i in 0..self.n() {
            for j in 0..=i {
                s.push((i, j));
            }
        }
        s
    }
    fn hessian_values(&self, x: &[f64], obj_factor: f64, lambda: &[f64], values: &mut [f64]) {
        let mut xd = lift(x);
        let mut k = 0;
        for i in 0..self.n() {
            for j in 0..=i {
                xd[i].b = 1.0;
                xd[j].c = 1.0;
                let mut v = obj_factor * (self.f)(&xd).d;
                if self.m > 0 {
                    let g = (self.g)(&xd);
                    for (l, gl) in g.iter().enumerate() {
                        v += lambda[l] * gl.d;
                    }
                }
                values[k] = v;
                k += 1;
                xd[i].b = 0.0;
                xd[j].c = 0.0;
            }
        }
    }
}

/// An HS problem with its objective multiplied by `obj` and its constraints by `con` (neither
/// moves the minimiser), and the first gradient entry then multiplied by `grad0` (1: exact
/// derivatives; any other value: a deliberately wrong gradient for the derivative checker);
/// `scaling` is what [`Nlp::scaling`] returns (used with `ScalingMethod::User`).
pub struct Transformed {
    pub hs: Hs,
    pub obj: f64,
    pub con: f64,
    pub grad0: f64,
    pub scaling: Option<NlpScaling>,
}

impl Transformed {
    /// `hs` unchanged (every factor 1, no user scaling); set the fields to transform it.
    pub fn new(hs: Hs) -> Self {
        Transformed {
            hs,
            obj: 1.0,
            con: 1.0,
            grad0: 1.0,
            scaling: None,
        }
    }
}

impl Nlp for Transformed {
    fn num_variables(&self) -> usize {
        self.hs.num_variables()
    }
    fn num_constraints(&self) -> usize {
        self.hs.num_constraints()
    }
    fn variable_bounds(&self, l: &mut [f64], u: &mut [f64]) {
        self.hs.variable_bounds(l, u)
    }
    fn constraint_bounds(&self, l: &mut [f64], u: &mut [f64]) {
        self.hs.constraint_bounds(l, u)
    }
    fn initial_point(&self, x: &mut [f64]) {
        self.hs.initial_point(x)
    }
    fn objective(&self, x: &[f64]) -> f64 {
        self.obj * self.hs.objective(x)
    }
    fn gradient(&self, x: &[f64], g: &mut [f64]) {
        self.hs.gradient(x, g);
        g.iter_mut().for_each(|v| *v *= self.obj);
        g[0] *= self.grad0;
    }
    fn constraints(&self, x: &[f64], g: &mut [f64]) {
        self.hs.constraints(x, g);
        g.iter_mut().for_each(|v| *v *= self.con);
    }
    fn jacobian_structure(&self) -> Vec<(usize, usize)> {
        self.hs.jacobian_structure()
    }
    fn jacobian_values(&self, x: &[f64], v: &mut [f64]) {
        self.hs.jacobian_values(x, v);
        v.iter_mut().for_each(|e| *e *= self.con);
    }
    fn hessian_structure(&self) -> Vec<(usize, usize)> {
        self.hs.hessian_structure()
    }
    fn hessian_values(&self, x: &[f64], s: f64, l: &[f64], v: &mut [f64]) {
        let l: Vec<f64> = l.iter().map(|v| v * self.con).collect();
        self.hs.hessian_values(x, s * self.obj, &l, v)
    }
    fn scaling(&self) -> Option<NlpScaling> {
        self.scaling.clone()
    }
}

fn none(_: &[D]) -> Vec<D> {
    Vec::new()
}

fn rosen(x: &[D]) -> D {
    100.0 * (x[1] - x[0] * x[0]).powi(2) + (1.0 - x[0]).powi(2)
}

macro_rules! hs {
    ($name:expr, $tags:expr, x0 = $x0:expr, xl = $xl:expr, xu = $xu:expr, neq = $neq:expr, m = $m:expr,
     f = $f:expr, g = $g:expr, fstar = $fs:expr, xstar = $xs:expr) => {
        Hs {
            name: $name,
            tags: $tags,
            x0: $x0.to_vec(),
            xl: $xl.to_vec(),
            xu: $xu.to_vec(),
            neq: $neq,
            m: $m,
            f: $f,
            g: $g,
            fstar: $fs,
            xstar: $xs,
        }
    };
}

// The problem lists (declared after the `hs!` macro, which they use).
mod set_a;
mod set_b;

/// All transcribed problems.
pub fn all() -> Vec<Hs> {
    let mut v = set_a::list();
    v.extend(set_b::list());
    v
}

/// One solve of `settings` per problem and objective factor (1, 1e8, 1e12, the scalings of
/// the scale-invariance tests): (name, factor, solution).
pub fn sweep_scaled_objectives(settings: &Settings) -> Vec<(&'static str, f64, Solution)> {
    let mut out = Vec::new();
    for (i, name) in all().iter().map(|p| p.name).enumerate() {
        for obj in [1.0, 1e8, 1e12] {
            let t = Transformed {
                obj,
                ..Transformed::new(all().into_iter().nth(i).unwrap())
            };
            out.push((name, obj, bf_optim::ipm::solve(&t, settings).unwrap()));
        }
    }
    out
}

/// Asserts that two [`sweep_scaled_objectives`] runs end every problem with the same status
/// and the same objective (to 1e-6 of `max(|f|, factor)`); `what` names the difference of
/// `b`'s settings in the messages.
pub fn assert_same_results(
    a: &[(&'static str, f64, Solution)],
    b: &[(&'static str, f64, Solution)],
    what: &str,
) {
    for ((name, obj, x), (_, _, y)) in a.iter().zip(b) {
        assert_eq!(y.status, x.status, "{name} × {obj:e} {what}: {y:?}");
        assert_same_objective(name, *obj, x, y, what);
    }
}

/// `y` ends at `x`'s objective to 1e-6 of `max(|f|, obj)` (problem `name` with its objective
/// multiplied by `obj`).
fn assert_same_objective(name: &str, obj: f64, x: &Solution, y: &Solution, what: &str) {
    let scale = x.objective.abs().max(obj);
    assert!(
        (y.objective - x.objective).abs() <= 1e-6 * scale,
        "{name} × {obj:e}: objective {} {what}, {} without",
        y.objective,
        x.objective
    );
}

/// Asserts that two [`sweep_scaled_objectives`] runs end every problem with the same status,
/// every `Solved` one at the same objective (to 1e-6 of `max(|f|, factor)`), and every other
/// one no farther than `slack` times `a`'s distance from the published optimum: an Acceptable
/// end (HS013, whose optimum is not a KKT point) is only as exact as the acceptable
/// tolerances. `what` names the difference of `b`'s settings in the messages.
pub fn assert_same_optima(
    a: &[(&'static str, f64, Solution)],
    b: &[(&'static str, f64, Solution)],
    what: &str,
    slack: f64,
) {
    let fstar: Vec<f64> = all().iter().map(|p| p.fstar).collect();
    for (i, ((name, obj, x), (_, _, y))) in a.iter().zip(b).enumerate() {
        assert_eq!(y.status, x.status, "{name} × {obj:e} {what}: {y:?}");
        if x.status == Status::Solved {
            assert_same_objective(name, *obj, x, y, what);
        } else {
            let f = obj * fstar[i / 3];
            assert!(
                (y.objective - f).abs() <= slack * (x.objective - f).abs(),
                "{name} × {obj:e}: {} {what}, {} without, f* {f}",
                y.objective,
                x.objective
            );
        }
    }
}

/// Heading of the section of `optim/HS_RESULTS.md` written by the `hs_scaling` test.
pub const SCALING_HEADING: &str = "## Scale invariance";

fn results_path() -> &'static str {
    concat!(env!("CARGO_MANIFEST_DIR"), "/HS_RESULTS.md")
}

/// Replaces the part of `optim/HS_RESULTS.md` from `heading` on (appended if absent) by
/// `text`, keeping what precedes it.
pub fn write_results_section(heading: &str, text: &str) {
    let old = std::fs::read_to_string(results_path()).unwrap_or_default();
    let head = match old.find(heading) {
        Some(i) => &old[..i],
        None => &old,
    };
    std::fs::write(results_path(), format!("{}\n\n{text}", head.trim_end())).unwrap();
}

/// `optim/HS_RESULTS.md` split at [`SCALING_HEADING`]: the part before it (the whole file if
/// that section is absent) and the section itself (empty then).
pub fn results_parts() -> (String, String) {
    let old = std::fs::read_to_string(results_path()).unwrap_or_default();
    let i = old.find(SCALING_HEADING).unwrap_or(old.len());
    (old[..i].to_string(), old[i..].to_string())
}

/// Replaces the part of `optim/HS_RESULTS.md` before [`SCALING_HEADING`] (the whole file if
/// that section is absent) by `text`.
pub fn write_results_head(text: &str) {
    let (_, tail) = results_parts();
    let sep = if tail.is_empty() { "" } else { "\n" };
    std::fs::write(results_path(), format!("{text}{sep}{tail}")).unwrap();
}
