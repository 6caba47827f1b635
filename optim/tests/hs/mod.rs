//! Hock–Schittkowski test problems (W. Hock, K. Schittkowski, "Test Examples for Nonlinear
//! Programming Codes", Lecture Notes in Economics and Mathematical Systems 187, Springer 1981).
//! Each problem records the published starting point, bounds, optimal objective `f*` and (where
//! the book gives it) the optimal point `x*`, so the transcription can be checked independently
//! of the solver (`f(x*) ≈ f*`, `x*` feasible).
//!
//! Constraints are written as in the book: `g(x) ≥ 0` (inequality) or `g(x) = 0` (equality).

#![allow(dead_code)]

pub mod dual;

use bf_optim::ipm::Nlp;
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

/// All transcribed problems.
pub fn all() -> Vec<Hs> {
    let s2 = 2f64.sqrt();
    let s3 = 3f64.sqrt();
    let pi = std::f64::consts::PI;
    vec![
        hs!(
            "HS001",
            "bounds, rosenbrock",
            x0 = [-2.0, 1.0],
            xl = [-INF, -1.5],
            xu = [INF, INF],
            neq = 0,
            m = 0,
            f = rosen,
            g = none,
            fstar = 0.0,
            xstar = Some(vec![1.0, 1.0])
        ),
        hs!(
            "HS002",
            "active bound",
            x0 = [-2.0, 1.0],
            xl = [-INF, 1.5],
            xu = [INF, INF],
            neq = 0,
            m = 0,
            f = rosen,
            g = none,
            fstar = 0.0504261879,
            xstar = Some(vec![1.224370749, 1.5])
        ),
        hs!(
            "HS003",
            "active bound, ill-conditioned",
            x0 = [10.0, 1.0],
            xl = [-INF, 0.0],
            xu = [INF, INF],
            neq = 0,
            m = 0,
            f = |x| x[1] + 1e-5 * (x[1] - x[0]).powi(2),
            g = none,
            fstar = 0.0,
            xstar = Some(vec![0.0, 0.0])
        ),
        hs!(
            "HS004",
            "active bounds",
            x0 = [1.125, 0.125],
            xl = [1.0, 0.0],
            xu = [INF, INF],
            neq = 0,
            m = 0,
            f = |x| (x[0] + 1.0).powi(3) / 3.0 + x[1],
            g = none,
            fstar = 8.0 / 3.0,
            xstar = Some(vec![1.0, 0.0])
        ),
        hs!(
            "HS005",
            "non-convex, bounds",
            x0 = [0.0, 0.0],
            xl = [-1.5, -3.0],
            xu = [4.0, 3.0],
            neq = 0,
            m = 0,
            f = |x| (x[0] + x[1]).sin() + (x[0] - x[1]).powi(2) - 1.5 * x[0] + 2.5 * x[1] + 1.0,
            g = none,
            fstar = -0.5 * s3 - pi / 3.0,
            xstar = Some(vec![0.5 - pi / 3.0, -0.5 - pi / 3.0])
        ),
        hs!(
            "HS006",
            "equality",
            x0 = [-1.2, 1.0],
            xl = [-INF; 2],
            xu = [INF; 2],
            neq = 1,
            m = 1,
            f = |x| (1.0 - x[0]).powi(2),
            g = |x| vec![10.0 * (x[1] - x[0] * x[0])],
            fstar = 0.0,
            xstar = Some(vec![1.0, 1.0])
        ),
        hs!(
            "HS007",
            "equality, non-convex",
            x0 = [2.0, 2.0],
            xl = [-INF; 2],
            xu = [INF; 2],
            neq = 1,
            m = 1,
            f = |x| (1.0 + x[0] * x[0]).ln() - x[1],
            g = |x| vec![(1.0 + x[0] * x[0]).powi(2) + x[1] * x[1] - 4.0],
            fstar = -s3,
            xstar = Some(vec![0.0, s3])
        ),
        hs!(
            "HS008",
            "constant objective, feasibility",
            x0 = [2.0, 1.0],
            xl = [-INF; 2],
            xu = [INF; 2],
            neq = 2,
            m = 2,
            f = |_x| D::cst(-1.0),
            g = |x| vec![x[0] * x[0] + x[1] * x[1] - 25.0, x[0] * x[1] - 9.0],
            fstar = -1.0,
            xstar = None
        ),
        hs!(
            "HS009",
            "non-convex, periodic",
            x0 = [0.0, 0.0],
            xl = [-INF; 2],
            xu = [INF; 2],
            neq = 1,
            m = 1,
            f = |x| (std::f64::consts::PI * x[0] / 12.0).sin()
                * (std::f64::consts::PI * x[1] / 16.0).cos(),
            g = |x| vec![4.0 * x[0] - 3.0 * x[1]],
            fstar = -0.5,
            xstar = Some(vec![-3.0, -4.0])
        ),
        hs!(
            "HS010",
            "inequality, linear objective",
            x0 = [-10.0, 10.0],
            xl = [-INF; 2],
            xu = [INF; 2],
            neq = 0,
            m = 1,
            f = |x| x[0] - x[1],
            g = |x| vec![-3.0 * x[0] * x[0] + 2.0 * x[0] * x[1] - x[1] * x[1] + 1.0],
            fstar = -1.0,
            xstar = Some(vec![0.0, 1.0])
        ),
        hs!(
            "HS011",
            "inequality",
            x0 = [4.9, 0.1],
            xl = [-INF; 2],
            xu = [INF; 2],
            neq = 0,
            m = 1,
            f = |x| (x[0] - 5.0).powi(2) + x[1] * x[1] - 25.0,
            g = |x| vec![-x[0] * x[0] + x[1]],
            fstar = -8.498464223,
            xstar = Some(vec![1.234772892632396, 1.524664093087327])
        ),
        hs!(
            "HS012",
            "inequality",
            x0 = [0.0, 0.0],
            xl = [-INF; 2],
            xu = [INF; 2],
            neq = 0,
            m = 1,
            f = |x| 0.5 * x[0] * x[0] + x[1] * x[1] - x[0] * x[1] - 7.0 * x[0] - 7.0 * x[1],
            g = |x| vec![25.0 - 4.0 * x[0] * x[0] - x[1] * x[1]],
            fstar = -30.0,
            xstar = Some(vec![2.0, 3.0])
        ),
        hs!(
            "HS013",
            "degenerate (no constraint qualification)",
            x0 = [-2.0, -2.0],
            xl = [0.0, 0.0],
            xu = [INF, INF],
            neq = 0,
            m = 1,
            f = |x| (x[0] - 2.0).powi(2) + x[1] * x[1],
            g = |x| vec![(1.0 - x[0]).powi(3) - x[1]],
            fstar = 1.0,
            xstar = Some(vec![1.0, 0.0])
        ),
        hs!(
            "HS014",
            "mixed",
            x0 = [2.0, 2.0],
            xl = [-INF; 2],
            xu = [INF; 2],
            neq = 1,
            m = 2,
            f = |x| (x[0] - 2.0).powi(2) + (x[1] - 1.0).powi(2),
            g = |x| vec![
                x[0] - 2.0 * x[1] + 1.0,
                -0.25 * x[0] * x[0] - x[1] * x[1] + 1.0
            ],
            fstar = 9.0 - 2.875 * 7f64.sqrt(),
            xstar = Some(vec![0.5 * (7f64.sqrt() - 1.0), 0.25 * (7f64.sqrt() + 1.0)])
        ),
        hs!(
            "HS015",
            "non-convex, active bound",
            x0 = [-2.0, 1.0],
            xl = [-INF, -INF],
            xu = [0.5, INF],
            neq = 0,
            m = 2,
            f = rosen,
            g = |x| vec![x[0] * x[1] - 1.0, x[0] + x[1] * x[1]],
            fstar = 306.5,
            xstar = Some(vec![0.5, 2.0])
        ),
        hs!(
            "HS016",
            "non-convex, bounds",
            x0 = [-2.0, 1.0],
            xl = [-0.5, -INF],
            xu = [0.5, 1.0],
            neq = 0,
            m = 2,
            f = rosen,
            g = |x| vec![x[0] + x[1] * x[1], x[0] * x[0] + x[1]],
            fstar = 0.25,
            xstar = Some(vec![0.5, 0.25])
        ),
        hs!(
            "HS017",
            "non-convex, degenerate",
            x0 = [-2.0, 1.0],
            xl = [-0.5, -INF],
            xu = [0.5, 1.0],
            neq = 0,
            m = 2,
            f = rosen,
            g = |x| vec![x[1] * x[1] - x[0], x[0] * x[0] - x[1]],
            fstar = 1.0,
            xstar = Some(vec![0.0, 0.0])
        ),
        hs!(
            "HS018",
            "non-convex",
            x0 = [2.0, 2.0],
            xl = [2.0, 0.0],
            xu = [50.0, 50.0],
            neq = 0,
            m = 2,
            f = |x| 0.01 * x[0] * x[0] + x[1] * x[1],
            g = |x| vec![x[0] * x[1] - 25.0, x[0] * x[0] + x[1] * x[1] - 25.0],
            fstar = 5.0,
            xstar = Some(vec![250f64.sqrt(), 2.5f64.sqrt()])
        ),
        hs!(
            "HS019",
            "non-convex",
            x0 = [20.1, 5.84],
            xl = [13.0, 0.0],
            xu = [100.0, 100.0],
            neq = 0,
            m = 2,
            f = |x| (x[0] - 10.0).powi(3) + (x[1] - 20.0).powi(3),
            g = |x| vec![
                (x[0] - 5.0).powi(2) + (x[1] - 5.0).powi(2) - 100.0,
                -(x[1] - 5.0).powi(2) - (x[0] - 6.0).powi(2) + 82.81
            ],
            fstar = -6961.81381,
            xstar = Some(vec![14.095, 0.84296079])
        ),
        hs!(
            "HS020",
            "non-convex",
            x0 = [-2.0, 1.0],
            xl = [-0.5, -INF],
            xu = [0.5, INF],
            neq = 0,
            m = 3,
            f = rosen,
            g = |x| vec![
                x[0] + x[1] * x[1],
                x[0] * x[0] + x[1],
                x[0] * x[0] + x[1] * x[1] - 1.0
            ],
            fstar = 81.5 - 25.0 * s3,
            xstar = Some(vec![0.5, 0.5 * s3])
        ),
        hs!(
            "HS021",
            "infeasible start, active bound",
            x0 = [-1.0, -1.0],
            xl = [2.0, -50.0],
            xu = [50.0, 50.0],
            neq = 0,
            m = 1,
            f = |x| 0.01 * x[0] * x[0] + x[1] * x[1] - 100.0,
            g = |x| vec![10.0 * x[0] - x[1] - 10.0],
            fstar = -99.96,
            xstar = Some(vec![2.0, 0.0])
        ),
        hs!(
            "HS022",
            "inequality",
            x0 = [2.0, 2.0],
            xl = [-INF; 2],
            xu = [INF; 2],
            neq = 0,
            m = 2,
            f = |x| (x[0] - 2.0).powi(2) + (x[1] - 1.0).powi(2),
            g = |x| vec![-x[0] - x[1] + 2.0, -x[0] * x[0] + x[1]],
            fstar = 1.0,
            xstar = Some(vec![1.0, 1.0])
        ),
        hs!(
            "HS023",
            "non-convex",
            x0 = [3.0, 1.0],
            xl = [-50.0; 2],
            xu = [50.0; 2],
            neq = 0,
            m = 5,
            f = |x| x[0] * x[0] + x[1] * x[1],
            g = |x| vec![
                x[0] + x[1] - 1.0,
                x[0] * x[0] + x[1] * x[1] - 1.0,
                9.0 * x[0] * x[0] + x[1] * x[1] - 9.0,
                x[0] * x[0] - x[1],
                x[1] * x[1] - x[0],
            ],
            fstar = 2.0,
            xstar = Some(vec![1.0, 1.0])
        ),
        hs!(
            "HS024",
            "non-convex, linear constraints",
            x0 = [1.0, 0.5],
            xl = [0.0, 0.0],
            xu = [INF, INF],
            neq = 0,
            m = 3,
            f = |x| ((x[0] - 3.0).powi(2) - 9.0) * x[1].powi(3) / (27.0 * 3f64.sqrt()),
            g = |x| {
                let r = 3f64.sqrt();
                vec![x[0] / r - x[1], x[0] + r * x[1], -x[0] - r * x[1] + 6.0]
            },
            fstar = -1.0,
            xstar = Some(vec![3.0, s3])
        ),
        hs!(
            "HS026",
            "equality, singular Hessian at x*",
            x0 = [-2.6, 2.0, 2.0],
            xl = [-INF; 3],
            xu = [INF; 3],
            neq = 1,
            m = 1,
            f = |x| (x[0] - x[1]).powi(2) + (x[1] - x[2]).powi(4),
            g = |x| vec![(1.0 + x[1] * x[1]) * x[0] + x[2].powi(4) - 3.0],
            fstar = 0.0,
            xstar = Some(vec![1.0, 1.0, 1.0])
        ),
        hs!(
            "HS027",
            "equality",
            x0 = [2.0, 2.0, 2.0],
            xl = [-INF; 3],
            xu = [INF; 3],
            neq = 1,
            m = 1,
            f = |x| 0.01 * (x[0] - 1.0).powi(2) + (x[1] - x[0] * x[0]).powi(2),
            g = |x| vec![x[0] + x[2] * x[2] + 1.0],
            fstar = 0.04,
            xstar = Some(vec![-1.0, 1.0, 0.0])
        ),
        hs!(
            "HS028",
            "equality QP",
            x0 = [-4.0, 1.0, 1.0],
            xl = [-INF; 3],
            xu = [INF; 3],
            neq = 1,
            m = 1,
            f = |x| (x[0] + x[1]).powi(2) + (x[1] + x[2]).powi(2),
            g = |x| vec![x[0] + 2.0 * x[1] + 3.0 * x[2] - 1.0],
            fstar = 0.0,
            xstar = Some(vec![0.5, -0.5, 0.5])
        ),
        hs!(
            "HS029",
            "non-convex",
            x0 = [1.0, 1.0, 1.0],
            xl = [-INF; 3],
            xu = [INF; 3],
            neq = 0,
            m = 1,
            f = |x| -x[0] * x[1] * x[2],
            g = |x| vec![-x[0] * x[0] - 2.0 * x[1] * x[1] - 4.0 * x[2] * x[2] + 48.0],
            fstar = -16.0 * s2,
            xstar = Some(vec![4.0, 2.0 * s2, 2.0])
        ),
        hs!(
            "HS030",
            "active bound",
            x0 = [1.0, 1.0, 1.0],
            xl = [1.0, -10.0, -10.0],
            xu = [10.0; 3],
            neq = 0,
            m = 1,
            f = |x| x[0] * x[0] + x[1] * x[1] + x[2] * x[2],
            g = |x| vec![x[0] * x[0] + x[1] * x[1] - 1.0],
            fstar = 1.0,
            xstar = Some(vec![1.0, 0.0, 0.0])
        ),
        hs!(
            "HS031",
            "non-convex constraint",
            x0 = [1.0, 1.0, 1.0],
            xl = [-10.0, 1.0, -10.0],
            xu = [10.0, 10.0, 1.0],
            neq = 0,
            m = 1,
            f = |x| 9.0 * x[0] * x[0] + x[1] * x[1] + 9.0 * x[2] * x[2],
            g = |x| vec![x[0] * x[1] - 1.0],
            fstar = 6.0,
            xstar = Some(vec![1.0 / s3, s3, 0.0])
        ),
        hs!(
            "HS032",
            "active bounds",
            x0 = [0.1, 0.7, 0.2],
            xl = [0.0; 3],
            xu = [INF; 3],
            neq = 1,
            m = 2,
            f = |x| (x[0] + 3.0 * x[1] + x[2]).powi(2) + 4.0 * (x[0] - x[1]).powi(2),
            g = |x| vec![
                1.0 - x[0] - x[1] - x[2],
                6.0 * x[1] + 4.0 * x[2] - x[0].powi(3) - 3.0
            ],
            fstar = 1.0,
            xstar = Some(vec![0.0, 0.0, 1.0])
        ),
        hs!(
            "HS033",
            "non-convex, active bound",
            x0 = [0.0, 0.0, 3.0],
            xl = [0.0; 3],
            xu = [INF, INF, 5.0],
            neq = 0,
            m = 2,
            f = |x| (x[0] - 1.0) * (x[0] - 2.0) * (x[0] - 3.0) + x[2],
            g = |x| vec![
                x[2] * x[2] - x[1] * x[1] - x[0] * x[0],
                x[0] * x[0] + x[1] * x[1] + x[2] * x[2] - 4.0
            ],
            fstar = s2 - 6.0,
            xstar = Some(vec![0.0, s2, s2])
        ),
        hs!(
            "HS034",
            "exponential constraints",
            x0 = [0.0, 1.05, 2.9],
            xl = [0.0; 3],
            xu = [100.0, 100.0, 10.0],
            neq = 0,
            m = 2,
            f = |x| -x[0],
            g = |x| vec![x[1] - x[0].exp(), x[2] - x[1].exp()],
            fstar = -(10f64.ln().ln()),
            xstar = Some(vec![10f64.ln().ln(), 10f64.ln(), 10.0])
        ),
        hs!(
            "HS035",
            "convex QP",
            x0 = [0.5, 0.5, 0.5],
            xl = [0.0; 3],
            xu = [INF; 3],
            neq = 0,
            m = 1,
            f = |x| 9.0 - 8.0 * x[0] - 6.0 * x[1] - 4.0 * x[2]
                + 2.0 * x[0] * x[0]
                + 2.0 * x[1] * x[1]
                + x[2] * x[2]
                + 2.0 * x[0] * x[1]
                + 2.0 * x[0] * x[2],
            g = |x| vec![3.0 - x[0] - x[1] - 2.0 * x[2]],
            fstar = 1.0 / 9.0,
            xstar = Some(vec![4.0 / 3.0, 7.0 / 9.0, 4.0 / 9.0])
        ),
        hs!(
            "HS036",
            "active bounds",
            x0 = [10.0, 10.0, 10.0],
            xl = [0.0; 3],
            xu = [20.0, 11.0, 42.0],
            neq = 0,
            m = 1,
            f = |x| -x[0] * x[1] * x[2],
            g = |x| vec![72.0 - x[0] - 2.0 * x[1] - 2.0 * x[2]],
            fstar = -3300.0,
            xstar = Some(vec![20.0, 11.0, 15.0])
        ),
        hs!(
            "HS037",
            "non-convex",
            x0 = [10.0, 10.0, 10.0],
            xl = [0.0; 3],
            xu = [42.0; 3],
            neq = 0,
            m = 2,
            f = |x| -x[0] * x[1] * x[2],
            g = |x| vec![
                72.0 - x[0] - 2.0 * x[1] - 2.0 * x[2],
                x[0] + 2.0 * x[1] + 2.0 * x[2]
            ],
            fstar = -3456.0,
            xstar = Some(vec![24.0, 12.0, 12.0])
        ),
        hs!(
            "HS038",
            "Wood function, bounds",
            x0 = [-3.0, -1.0, -3.0, -1.0],
            xl = [-10.0; 4],
            xu = [10.0; 4],
            neq = 0,
            m = 0,
            f = |x| 100.0 * (x[1] - x[0] * x[0]).powi(2)
                + (1.0 - x[0]).powi(2)
                + 90.0 * (x[3] - x[2] * x[2]).powi(2)
                + (1.0 - x[2]).powi(2)
                + 10.1 * ((x[1] - 1.0).powi(2) + (x[3] - 1.0).powi(2))
                + 19.8 * (x[1] - 1.0) * (x[3] - 1.0),
            g = none,
            fstar = 0.0,
            xstar = Some(vec![1.0; 4])
        ),
        hs!(
            "HS039",
            "equality, linear objective",
            x0 = [2.0; 4],
            xl = [-INF; 4],
            xu = [INF; 4],
            neq = 2,
            m = 2,
            f = |x| -x[0],
            g = |x| vec![
                x[1] - x[0].powi(3) - x[2] * x[2],
                x[0] * x[0] - x[1] - x[3] * x[3]
            ],
            fstar = -1.0,
            xstar = Some(vec![1.0, 1.0, 0.0, 0.0])
        ),
        hs!(
            "HS040",
            "equality, non-convex",
            x0 = [0.8; 4],
            xl = [-INF; 4],
            xu = [INF; 4],
            neq = 3,
            m = 3,
            f = |x| -x[0] * x[1] * x[2] * x[3],
            g = |x| vec![
                x[0].powi(3) + x[1] * x[1] - 1.0,
                x[0] * x[0] * x[3] - x[2],
                x[3] * x[3] - x[1]
            ],
            fstar = -0.25,
            xstar = Some(vec![
                2f64.powf(-1.0 / 3.0),
                2f64.powf(-0.5),
                2f64.powf(-11.0 / 12.0),
                2f64.powf(-0.25)
            ])
        ),
        hs!(
            "HS041",
            "active bounds",
            x0 = [2.0; 4],
            xl = [0.0; 4],
            xu = [1.0, 1.0, 1.0, 2.0],
            neq = 1,
            m = 1,
            f = |x| 2.0 - x[0] * x[1] * x[2],
            g = |x| vec![x[0] + 2.0 * x[1] + 2.0 * x[2] - x[3]],
            fstar = 52.0 / 27.0,
            xstar = Some(vec![2.0 / 3.0, 1.0 / 3.0, 1.0 / 3.0, 2.0])
        ),
        hs!(
            "HS042",
            "equality",
            x0 = [1.0; 4],
            xl = [-INF; 4],
            xu = [INF; 4],
            neq = 2,
            m = 2,
            f = |x| (x[0] - 1.0).powi(2)
                + (x[1] - 2.0).powi(2)
                + (x[2] - 3.0).powi(2)
                + (x[3] - 4.0).powi(2),
            g = |x| vec![x[0] - 2.0, x[2] * x[2] + x[3] * x[3] - 2.0],
            fstar = 28.0 - 10.0 * s2,
            xstar = Some(vec![2.0, 2.0, 0.6 * s2, 0.8 * s2])
        ),
        hs!(
            "HS043",
            "Rosen-Suzuki",
            x0 = [0.0; 4],
            xl = [-INF; 4],
            xu = [INF; 4],
            neq = 0,
            m = 3,
            f = |x| x[0] * x[0] + x[1] * x[1] + 2.0 * x[2] * x[2] + x[3] * x[3]
                - 5.0 * x[0]
                - 5.0 * x[1]
                - 21.0 * x[2]
                + 7.0 * x[3],
            g = |x| vec![
                8.0 - x[0] * x[0] - x[1] * x[1] - x[2] * x[2] - x[3] * x[3] - x[0] + x[1] - x[2]
                    + x[3],
                10.0 - x[0] * x[0] - 2.0 * x[1] * x[1] - x[2] * x[2] - 2.0 * x[3] * x[3]
                    + x[0]
                    + x[3],
                5.0 - 2.0 * x[0] * x[0] - x[1] * x[1] - x[2] * x[2] - 2.0 * x[0] + x[1] + x[3],
            ],
            fstar = -44.0,
            xstar = Some(vec![0.0, 1.0, 2.0, -1.0])
        ),
        hs!(
            "HS044",
            "non-convex QP, vertex solution",
            x0 = [0.0; 4],
            xl = [0.0; 4],
            xu = [INF; 4],
            neq = 0,
            m = 6,
            f = |x| x[0] - x[1] - x[2] - x[0] * x[2] + x[0] * x[3] + x[1] * x[2] - x[1] * x[3],
            g = |x| vec![
                8.0 - x[0] - 2.0 * x[1],
                12.0 - 4.0 * x[0] - x[1],
                12.0 - 3.0 * x[0] - 4.0 * x[1],
                8.0 - 2.0 * x[2] - x[3],
                8.0 - x[2] - 2.0 * x[3],
                5.0 - x[2] - x[3],
            ],
            fstar = -15.0,
            xstar = Some(vec![0.0, 3.0, 0.0, 4.0])
        ),
        hs!(
            "HS045",
            "all bounds active",
            x0 = [2.0; 5],
            xl = [0.0; 5],
            xu = [1.0, 2.0, 3.0, 4.0, 5.0],
            neq = 0,
            m = 0,
            f = |x| 2.0 - x[0] * x[1] * x[2] * x[3] * x[4] / 120.0,
            g = none,
            fstar = 1.0,
            xstar = Some(vec![1.0, 2.0, 3.0, 4.0, 5.0])
        ),
        hs!(
            "HS046",
            "equality, degenerate minimum",
            x0 = [0.5 * s2, 1.75, 0.5, 2.0, 2.0],
            xl = [-INF; 5],
            xu = [INF; 5],
            neq = 2,
            m = 2,
            f = |x| (x[0] - x[1]).powi(2)
                + (x[2] - 1.0).powi(2)
                + (x[3] - 1.0).powi(4)
                + (x[4] - 1.0).powi(6),
            g = |x| vec![
                x[0] * x[0] * x[3] + (x[3] - x[4]).sin() - 1.0,
                x[1] + x[2].powi(4) * x[3] * x[3] - 2.0
            ],
            fstar = 0.0,
            xstar = Some(vec![1.0; 5])
        ),
        hs!(
            "HS048",
            "linear equalities",
            x0 = [3.0, 5.0, -3.0, 2.0, -2.0],
            xl = [-INF; 5],
            xu = [INF; 5],
            neq = 2,
            m = 2,
            f = |x| (x[0] - 1.0).powi(2) + (x[1] - x[2]).powi(2) + (x[3] - x[4]).powi(2),
            g = |x| vec![
                x[0] + x[1] + x[2] + x[3] + x[4] - 5.0,
                x[2] - 2.0 * (x[3] + x[4]) + 3.0
            ],
            fstar = 0.0,
            xstar = Some(vec![1.0; 5])
        ),
        hs!(
            "HS049",
            "linear equalities, high-order objective",
            x0 = [10.0, 7.0, 2.0, -3.0, 0.8],
            xl = [-INF; 5],
            xu = [INF; 5],
            neq = 2,
            m = 2,
            f = |x| (x[0] - x[1]).powi(2)
                + (x[2] - 1.0).powi(2)
                + (x[3] - 1.0).powi(4)
                + (x[4] - 1.0).powi(6),
            g = |x| vec![
                x[0] + x[1] + x[2] + 4.0 * x[3] - 7.0,
                x[2] + 5.0 * x[4] - 6.0
            ],
            fstar = 0.0,
            xstar = Some(vec![1.0; 5])
        ),
        hs!(
            "HS050",
            "linear equalities",
            x0 = [35.0, -31.0, 11.0, 5.0, -5.0],
            xl = [-INF; 5],
            xu = [INF; 5],
            neq = 3,
            m = 3,
            f = |x| (x[0] - x[1]).powi(2)
                + (x[1] - x[2]).powi(2)
                + (x[2] - x[3]).powi(4)
                + (x[3] - x[4]).powi(2),
            g = |x| vec![
                x[0] + 2.0 * x[1] + 3.0 * x[2] - 6.0,
                x[1] + 2.0 * x[2] + 3.0 * x[3] - 6.0,
                x[2] + 2.0 * x[3] + 3.0 * x[4] - 6.0,
            ],
            fstar = 0.0,
            xstar = Some(vec![1.0; 5])
        ),
        hs!(
            "HS051",
            "equality QP",
            x0 = [2.5, 0.5, 2.0, -1.0, 0.5],
            xl = [-INF; 5],
            xu = [INF; 5],
            neq = 3,
            m = 3,
            f = |x| (x[0] - x[1]).powi(2)
                + (x[1] + x[2] - 2.0).powi(2)
                + (x[3] - 1.0).powi(2)
                + (x[4] - 1.0).powi(2),
            g = |x| vec![
                x[0] + 3.0 * x[1] - 4.0,
                x[2] + x[3] - 2.0 * x[4],
                x[1] - x[4]
            ],
            fstar = 0.0,
            xstar = Some(vec![1.0; 5])
        ),
        hs!(
            "HS052",
            "equality QP",
            x0 = [2.0; 5],
            xl = [-INF; 5],
            xu = [INF; 5],
            neq = 3,
            m = 3,
            f = |x| (4.0 * x[0] - x[1]).powi(2)
                + (x[1] + x[2] - 2.0).powi(2)
                + (x[3] - 1.0).powi(2)
                + (x[4] - 1.0).powi(2),
            g = |x| vec![x[0] + 3.0 * x[1], x[2] + x[3] - 2.0 * x[4], x[1] - x[4]],
            fstar = 1859.0 / 349.0,
            xstar = Some(vec![
                -33.0 / 349.0,
                11.0 / 349.0,
                180.0 / 349.0,
                -158.0 / 349.0,
                11.0 / 349.0
            ])
        ),
        hs!(
            "HS053",
            "equality QP with bounds",
            x0 = [2.0; 5],
            xl = [-10.0; 5],
            xu = [10.0; 5],
            neq = 3,
            m = 3,
            f = |x| (x[0] - x[1]).powi(2)
                + (x[1] + x[2] - 2.0).powi(2)
                + (x[3] - 1.0).powi(2)
                + (x[4] - 1.0).powi(2),
            g = |x| vec![x[0] + 3.0 * x[1], x[2] + x[3] - 2.0 * x[4], x[1] - x[4]],
            fstar = 176.0 / 43.0,
            xstar = Some(vec![
                -33.0 / 43.0,
                11.0 / 43.0,
                27.0 / 43.0,
                -5.0 / 43.0,
                11.0 / 43.0
            ])
        ),
        hs!(
            "HS060",
            "equality",
            x0 = [2.0; 3],
            xl = [-10.0; 3],
            xu = [10.0; 3],
            neq = 1,
            m = 1,
            f = |x| (x[0] - 1.0).powi(2) + (x[0] - x[1]).powi(2) + (x[1] - x[2]).powi(4),
            g = |x| vec![x[0] * (1.0 + x[1] * x[1]) + x[2].powi(4) - 4.0 - 3.0 * 2f64.sqrt()],
            fstar = 0.03256820025,
            xstar = Some(vec![1.104859024, 1.196674194, 1.535262257])
        ),
        hs!(
            "HS061",
            "equality",
            x0 = [0.0; 3],
            xl = [-INF; 3],
            xu = [INF; 3],
            neq = 2,
            m = 2,
            f = |x| 4.0 * x[0] * x[0] + 2.0 * x[1] * x[1] + 2.0 * x[2] * x[2] - 33.0 * x[0]
                + 16.0 * x[1]
                - 24.0 * x[2],
            g = |x| vec![
                3.0 * x[0] - 2.0 * x[1] * x[1] - 7.0,
                4.0 * x[0] - x[2] * x[2] - 11.0
            ],
            fstar = -143.6461422,
            xstar = Some(vec![5.326770157, -2.118998639, 3.210464239])
        ),
        hs!(
            "HS063",
            "equality, bounds",
            x0 = [2.0; 3],
            xl = [0.0; 3],
            xu = [INF; 3],
            neq = 2,
            m = 2,
            f = |x| 1000.0
                - x[0] * x[0]
                - 2.0 * x[1] * x[1]
                - x[2] * x[2]
                - x[0] * x[1]
                - x[0] * x[2],
            g = |x| vec![
                8.0 * x[0] + 14.0 * x[1] + 7.0 * x[2] - 56.0,
                x[0] * x[0] + x[1] * x[1] + x[2] * x[2] - 25.0
            ],
            fstar = 961.7151721,
            xstar = Some(vec![3.512118414, 0.2169881741, 3.552174034])
        ),
        hs!(
            "HS064",
            "badly scaled",
            x0 = [1.0; 3],
            xl = [1e-5; 3],
            xu = [INF; 3],
            neq = 0,
            m = 1,
            f = |x| 5.0 * x[0]
                + 50000.0 / x[0]
                + 20.0 * x[1]
                + 72000.0 / x[1]
                + 10.0 * x[2]
                + 144000.0 / x[2],
            g = |x| vec![1.0 - 4.0 / x[0] - 32.0 / x[1] - 120.0 / x[2]],
            fstar = 6299.842428,
            xstar = Some(vec![108.7347175, 85.12613942, 204.3247078])
        ),
        hs!(
            "HS065",
            "inequality, bounds",
            x0 = [-5.0, 5.0, 0.0],
            xl = [-4.5, -4.5, -5.0],
            xu = [4.5, 4.5, 5.0],
            neq = 0,
            m = 1,
            f = |x| (x[0] - x[1]).powi(2)
                + (x[0] + x[1] - 10.0).powi(2) / 9.0
                + (x[2] - 5.0).powi(2),
            g = |x| vec![48.0 - x[0] * x[0] - x[1] * x[1] - x[2] * x[2]],
            fstar = 0.9535288567,
            xstar = Some(vec![3.650461821, 3.65046168, 4.6204170507])
        ),
        hs!(
            "HS066",
            "exponential constraints",
            x0 = [0.0, 1.05, 2.9],
            xl = [0.0; 3],
            xu = [100.0, 100.0, 10.0],
            neq = 0,
            m = 2,
            f = |x| 0.2 * x[2] - 0.8 * x[0],
            g = |x| vec![x[1] - x[0].exp(), x[2] - x[1].exp()],
            fstar = 0.5181632741,
            xstar = Some(vec![0.1841264879, 1.202167873, 3.327322322])
        ),
        hs!(
            "HS071",
            "Ipopt's example",
            x0 = [1.0, 5.0, 5.0, 1.0],
            xl = [1.0; 4],
            xu = [5.0; 4],
            neq = 1,
            m = 2,
            f = |x| x[0] * x[3] * (x[0] + x[1] + x[2]) + x[2],
            g = |x| vec![
                x[0] * x[0] + x[1] * x[1] + x[2] * x[2] + x[3] * x[3] - 40.0,
                x[0] * x[1] * x[2] * x[3] - 25.0,
            ],
            fstar = 17.0140173,
            xstar = Some(vec![1.0, 4.7429994, 3.8211503, 1.3794082])
        ),
        hs!(
            "HS076",
            "convex QP",
            x0 = [0.5; 4],
            xl = [0.0; 4],
            xu = [INF; 4],
            neq = 0,
            m = 3,
            f = |x| x[0] * x[0] + 0.5 * x[1] * x[1] + x[2] * x[2] + 0.5 * x[3] * x[3] - x[0] * x[2]
                + x[2] * x[3]
                - x[0]
                - 3.0 * x[1]
                + x[2]
                - x[3],
            g = |x| vec![
                5.0 - x[0] - 2.0 * x[1] - x[2] - x[3],
                4.0 - 3.0 * x[0] - x[1] - 2.0 * x[2] + x[3],
                x[1] + 4.0 * x[2] - 1.5,
            ],
            fstar = -4.681818181,
            xstar = Some(vec![0.2727273, 2.090909, 0.0, 0.5454545])
        ),
        hs!(
            "HS077",
            "equality",
            x0 = [2.0; 5],
            xl = [-INF; 5],
            xu = [INF; 5],
            neq = 2,
            m = 2,
            f = |x| (x[0] - 1.0).powi(2)
                + (x[0] - x[1]).powi(2)
                + (x[2] - 1.0).powi(2)
                + (x[3] - 1.0).powi(4)
                + (x[4] - 1.0).powi(6),
            g = |x| vec![
                x[0] * x[0] * x[3] + (x[3] - x[4]).sin() - 2.0 * 2f64.sqrt(),
                x[1] + x[2].powi(4) * x[3] * x[3] - 8.0 - 2f64.sqrt(),
            ],
            fstar = 0.24150513,
            xstar = Some(vec![1.166172, 1.182111, 1.380257, 1.506036, 0.6109203])
        ),
        hs!(
            "HS078",
            "equality, non-convex",
            x0 = [-2.0, 1.5, 2.0, -1.0, -1.0],
            xl = [-INF; 5],
            xu = [INF; 5],
            neq = 3,
            m = 3,
            f = |x| x[0] * x[1] * x[2] * x[3] * x[4],
            g = |x| vec![
                x[0] * x[0] + x[1] * x[1] + x[2] * x[2] + x[3] * x[3] + x[4] * x[4] - 10.0,
                x[1] * x[2] - 5.0 * x[3] * x[4],
                x[0].powi(3) + x[1].powi(3) + 1.0,
            ],
            fstar = -2.919700,
            xstar = Some(vec![-1.717142, 1.595708, 1.827248, -0.7636429, -0.7636435])
        ),
        hs!(
            "HS079",
            "equality",
            x0 = [2.0; 5],
            xl = [-INF; 5],
            xu = [INF; 5],
            neq = 3,
            m = 3,
            f = |x| (x[0] - 1.0).powi(2)
                + (x[0] - x[1]).powi(2)
                + (x[1] - x[2]).powi(2)
                + (x[2] - x[3]).powi(4)
                + (x[3] - x[4]).powi(4),
            g = |x| {
                let r = 2f64.sqrt();
                vec![
                    x[0] + x[1] * x[1] + x[2].powi(3) - 2.0 - 3.0 * r,
                    x[1] - x[2] * x[2] + x[3] + 2.0 - 2.0 * r,
                    x[0] * x[4] - 2.0,
                ]
            },
            fstar = 0.0787768209,
            xstar = Some(vec![1.191127, 1.362603, 1.472818, 1.635017, 1.679081])
        ),
        hs!(
            "HS080",
            "equality, exponential",
            x0 = [-2.0, 2.0, 2.0, -1.0, -1.0],
            xl = [-2.3, -2.3, -3.2, -3.2, -3.2],
            xu = [2.3, 2.3, 3.2, 3.2, 3.2],
            neq = 3,
            m = 3,
            f = |x| (x[0] * x[1] * x[2] * x[3] * x[4]).exp(),
            g = |x| vec![
                x[0] * x[0] + x[1] * x[1] + x[2] * x[2] + x[3] * x[3] + x[4] * x[4] - 10.0,
                x[1] * x[2] - 5.0 * x[3] * x[4],
                x[0].powi(3) + x[1].powi(3) + 1.0,
            ],
            fstar = 0.0539498478,
            xstar = Some(vec![-1.717143, 1.595709, 1.827247, -0.7636413, -0.7636450])
        ),
        hs!(
            "HS081",
            "equality, exponential",
            x0 = [-2.0, 2.0, 2.0, -1.0, -1.0],
            xl = [-2.3, -2.3, -3.2, -3.2, -3.2],
            xu = [2.3, 2.3, 3.2, 3.2, 3.2],
            neq = 3,
            m = 3,
            f = |x| (x[0] * x[1] * x[2] * x[3] * x[4]).exp()
                - 0.5 * (x[0].powi(3) + x[1].powi(3) + 1.0).powi(2),
            g = |x| vec![
                x[0] * x[0] + x[1] * x[1] + x[2] * x[2] + x[3] * x[3] + x[4] * x[4] - 10.0,
                x[1] * x[2] - 5.0 * x[3] * x[4],
                x[0].powi(3) + x[1].powi(3) + 1.0,
            ],
            fstar = 0.0539498478,
            xstar = Some(vec![-1.717143, 1.595709, 1.827247, -0.7636413, -0.7636450])
        ),
        hs!(
            "HS100",
            "non-convex, 7 variables",
            x0 = [1.0, 2.0, 0.0, 4.0, 0.0, 1.0, 1.0],
            xl = [-INF; 7],
            xu = [INF; 7],
            neq = 0,
            m = 4,
            f = |x| (x[0] - 10.0).powi(2)
                + 5.0 * (x[1] - 12.0).powi(2)
                + x[2].powi(4)
                + 3.0 * (x[3] - 11.0).powi(2)
                + 10.0 * x[4].powi(6)
                + 7.0 * x[5] * x[5]
                + x[6].powi(4)
                - 4.0 * x[5] * x[6]
                - 10.0 * x[5]
                - 8.0 * x[6],
            g = |x| vec![
                127.0
                    - 2.0 * x[0] * x[0]
                    - 3.0 * x[1].powi(4)
                    - x[2]
                    - 4.0 * x[3] * x[3]
                    - 5.0 * x[4],
                282.0 - 7.0 * x[0] - 3.0 * x[1] - 10.0 * x[2] * x[2] - x[3] + x[4],
                196.0 - 23.0 * x[0] - x[1] * x[1] - 6.0 * x[5] * x[5] + 8.0 * x[6],
                -4.0 * x[0] * x[0] - x[1] * x[1] + 3.0 * x[0] * x[1]
                    - 2.0 * x[2] * x[2]
                    - 5.0 * x[5]
                    + 11.0 * x[6],
            ],
            fstar = 680.6300573,
            xstar = Some(vec![
                2.330499, 1.951372, -0.4775414, 4.365726, -0.6244870, 1.038131, 1.594227
            ])
        ),
        hs!(
            "HS113",
            "convex, 10 variables, 8 inequalities",
            x0 = [2.0, 3.0, 5.0, 5.0, 1.0, 2.0, 7.0, 3.0, 6.0, 10.0],
            xl = [-INF; 10],
            xu = [INF; 10],
            neq = 0,
            m = 8,
            f = |x| x[0] * x[0] + x[1] * x[1] + x[0] * x[1] - 14.0 * x[0] - 16.0 * x[1]
                + (x[2] - 10.0).powi(2)
                + 4.0 * (x[3] - 5.0).powi(2)
                + (x[4] - 3.0).powi(2)
                + 2.0 * (x[5] - 1.0).powi(2)
                + 5.0 * x[6] * x[6]
                + 7.0 * (x[7] - 11.0).powi(2)
                + 2.0 * (x[8] - 10.0).powi(2)
                + (x[9] - 7.0).powi(2)
                + 45.0,
            g = |x| vec![
                105.0 - 4.0 * x[0] - 5.0 * x[1] + 3.0 * x[6] - 9.0 * x[7],
                -10.0 * x[0] + 8.0 * x[1] + 17.0 * x[6] - 2.0 * x[7],
                8.0 * x[0] - 2.0 * x[1] - 5.0 * x[8] + 2.0 * x[9] + 12.0,
                -3.0 * (x[0] - 2.0).powi(2) - 4.0 * (x[1] - 3.0).powi(2) - 2.0 * x[2] * x[2]
                    + 7.0 * x[3]
                    + 120.0,
                -5.0 * x[0] * x[0] - 8.0 * x[1] - (x[2] - 6.0).powi(2) + 2.0 * x[3] + 40.0,
                -0.5 * (x[0] - 8.0).powi(2) - 2.0 * (x[1] - 4.0).powi(2) - 3.0 * x[4] * x[4]
                    + x[5]
                    + 30.0,
                -x[0] * x[0] - 2.0 * (x[1] - 2.0).powi(2) + 2.0 * x[0] * x[1] - 14.0 * x[4]
                    + 6.0 * x[5],
                3.0 * x[0] - 6.0 * x[1] - 12.0 * (x[8] - 8.0).powi(2) + 7.0 * x[9],
            ],
            fstar = 24.3062091,
            xstar = Some(vec![
                2.171996, 2.363683, 8.773926, 5.095984, 0.9906548, 1.430574, 1.321644, 9.828726,
                8.280092, 8.375927
            ])
        ),
    ]
}
