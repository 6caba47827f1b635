//! Multi-segment Legendre–Gauss–Radau (LGR) collocation of a d-axis double integrator with
//! optional quadratic drag — the shape of the downstream collocation NLPs: per segment and state
//! component a dense (N × (N+1)) differentiation block.
//!
//! ```text
//! min ∫₀ᵀ Σ_a u_a² dt   s.t.  ṗ_a = v_a,  v̇_a = u_a − c v_a|v_a|,
//!                            p(0) = v(0) = 0,  p_a(T) = d_a,  v(T) = 0
//! ```
//! Segment nodes: the N LGR points τ_0 = −1 < … < τ_{N−1} (roots of P_{N−1} + P_N) plus τ_N = 1;
//! the dynamics are collocated at j = 0..N−1 with the barycentric differentiation matrix and the
//! cost uses the LGR weights (exact to degree 2N−2); adjacent segments share their boundary node.
//! The final node's control enters no equation and gets a tiny cost weight so that it is 0.
//! Without drag the axes decouple and the optimum is `J* = Σ_a 12 d_a² / T³`
//! (`u*_a = 6 d_a (1 − 2t)`, T = 1), which LGR reproduces exactly (polynomial solution).

#![allow(dead_code)]

use bf_optim::ipm::Nlp;

pub struct ChebDoubleIntegrator {
    pub axes: usize,
    pub segments: usize,
    pub order: usize,
    pub distance: Vec<f64>,
    pub drag: f64,
    /// Row-major N × (N+1): rows are collocation nodes 0..N−1.
    diff: Vec<f64>,
    /// Quadrature weight of each global node (already × h/2).
    weight: Vec<f64>,
    tau: Vec<f64>,
}

fn barycentric_diff(x: &[f64]) -> Vec<Vec<f64>> {
    let n = x.len();
    let w: Vec<f64> = (0..n)
        .map(|j| {
            1.0 / (0..n)
                .filter(|&k| k != j)
                .map(|k| x[j] - x[k])
                .product::<f64>()
        })
        .collect();
    let mut d = vec![vec![0.0; n]; n];
    for i in 0..n {
        let mut s = 0.0;
        for j in 0..n {
            if i != j {
                d[i][j] = (w[j] / w[i]) / (x[i] - x[j]);
                s += d[i][j];
            }
        }
        d[i][i] = -s;
    }
    d
}

/// Legendre polynomials P_{n−1}(x), P_n(x) by the three-term recurrence.
fn legendre(n: usize, x: f64) -> (f64, f64) {
    let (mut p0, mut p1) = (1.0, x);
    if n == 0 {
        return (0.0, 1.0);
    }
    for k in 1..n {
        let p2 = ((2 * k + 1) as f64 * x * p1 - k as f64 * p0) / (k + 1) as f64;
        p0 = p1;
        p1 = p2;
    }
    (p0, p1)
}

/// LGR nodes (τ_0 = −1) and weights: Newton on P_{N−1} + P_N from Chebyshev–Radau guesses.
fn lgr(n: usize) -> (Vec<f64>, Vec<f64>) {
    let pi = std::f64::consts::PI;
    let mut x: Vec<f64> = (0..n)
        .map(|j| -libm::cos(2.0 * pi * j as f64 / (2 * n - 1) as f64))
        .collect();
    for xi in x.iter_mut().skip(1) {
        for _ in 0..100 {
            let h = 1e-7;
            let f = |t: f64| {
                let (a, b) = legendre(n, t);
                a + b
            };
            let fx = f(*xi);
            let d = (f(*xi + h) - f(*xi - h)) / (2.0 * h);
            let step = fx / d;
            *xi -= step;
            if step.abs() < 1e-15 {
                break;
            }
        }
    }
    let nn = (n * n) as f64;
    let w = x
        .iter()
        .enumerate()
        .map(|(j, &t)| {
            if j == 0 {
                2.0 / nn
            } else {
                let (pm1, _) = legendre(n, t);
                (1.0 - t) / (nn * pm1 * pm1)
            }
        })
        .collect();
    (x, w)
}

impl ChebDoubleIntegrator {
    pub fn new(axes: usize, segments: usize, order: usize) -> Self {
        let (mut tau, w) = lgr(order);
        tau.push(1.0);
        let d = barycentric_diff(&tau);
        let diff = (0..order).flat_map(|i| d[i].clone()).collect();
        let h = 1.0 / segments as f64;
        let mut weight = vec![0.0; segments * order + 1];
        for s in 0..segments {
            for j in 0..order {
                weight[s * order + j] += 0.5 * h * w[j];
            }
        }
        weight[segments * order] = 1e-3 * weight[0];
        let distance = (0..axes).map(|a| [1.0, 2.0, -1.0, 0.5][a % 4]).collect();
        Self {
            axes,
            segments,
            order,
            distance,
            drag: 0.0,
            diff,
            weight,
            tau,
        }
    }
    pub fn nodes(&self) -> usize {
        self.segments * self.order + 1
    }
    pub fn p(&self, node: usize, a: usize) -> usize {
        3 * self.axes * node + a
    }
    pub fn v(&self, node: usize, a: usize) -> usize {
        3 * self.axes * node + self.axes + a
    }
    pub fn u(&self, node: usize, a: usize) -> usize {
        3 * self.axes * node + 2 * self.axes + a
    }
    pub fn time(&self, node: usize) -> f64 {
        let s = (node / self.order).min(self.segments - 1);
        let j = node - s * self.order;
        let h = 1.0 / self.segments as f64;
        (s as f64 + 0.5 * (self.tau[j] + 1.0)) * h
    }
    pub fn closed_form(&self) -> f64 {
        self.distance.iter().map(|d| 12.0 * d * d).sum()
    }
    fn row(&self, s: usize, j: usize, a: usize, which: usize) -> usize {
        // which: 0 = position defect, 1 = velocity defect
        ((s * self.order + j) * self.axes + a) * 2 + which
    }
}

impl Nlp for ChebDoubleIntegrator {
    fn num_variables(&self) -> usize {
        3 * self.axes * self.nodes()
    }
    fn num_constraints(&self) -> usize {
        2 * self.axes * self.segments * self.order
    }
    fn variable_bounds(&self, lower: &mut [f64], upper: &mut [f64]) {
        lower.fill(f64::NEG_INFINITY);
        upper.fill(f64::INFINITY);
        let last = self.nodes() - 1;
        for a in 0..self.axes {
            for (i, val) in [
                (self.p(0, a), 0.0),
                (self.v(0, a), 0.0),
                (self.p(last, a), self.distance[a]),
                (self.v(last, a), 0.0),
            ] {
                lower[i] = val;
                upper[i] = val;
            }
        }
    }
    fn constraint_bounds(&self, lower: &mut [f64], upper: &mut [f64]) {
        lower.fill(0.0);
        upper.fill(0.0);
    }
    fn initial_point(&self, x: &mut [f64]) {
        x.fill(0.0);
        for node in 0..self.nodes() {
            let t = self.time(node);
            for a in 0..self.axes {
                x[self.p(node, a)] = self.distance[a] * t;
            }
        }
    }
    fn objective(&self, x: &[f64]) -> f64 {
        let mut f = 0.0;
        for node in 0..self.nodes() {
            for a in 0..self.axes {
                f += self.weight[node] * x[self.u(node, a)].powi(2);
            }
        }
        f
    }
    fn gradient(&self, x: &[f64], grad: &mut [f64]) {
        grad.fill(0.0);
        for node in 0..self.nodes() {
            for a in 0..self.axes {
                grad[self.u(node, a)] = 2.0 * self.weight[node] * x[self.u(node, a)];
            }
        }
    }
    fn constraints(&self, x: &[f64], g: &mut [f64]) {
        let n = self.order;
        let h2 = 0.5 / self.segments as f64;
        for s in 0..self.segments {
            for j in 0..n {
                let drow = &self.diff[j * (n + 1)..(j + 1) * (n + 1)];
                let node = s * n + j;
                for a in 0..self.axes {
                    let (mut dp, mut dv) = (0.0, 0.0);
                    for k in 0..=n {
                        dp += drow[k] * x[self.p(s * n + k, a)];
                        dv += drow[k] * x[self.v(s * n + k, a)];
                    }
                    let v = x[self.v(node, a)];
                    let acc = x[self.u(node, a)] - self.drag * v * v.abs();
                    g[self.row(s, j, a, 0)] = dp - h2 * v;
                    g[self.row(s, j, a, 1)] = dv - h2 * acc;
                }
            }
        }
    }
    fn jacobian_structure(&self) -> Vec<(usize, usize)> {
        let n = self.order;
        let mut st = Vec::new();
        for s in 0..self.segments {
            for j in 0..n {
                let node = s * n + j;
                for a in 0..self.axes {
                    let (r0, r1) = (self.row(s, j, a, 0), self.row(s, j, a, 1));
                    for k in 0..=n {
                        st.push((r0, self.p(s * n + k, a)));
                    }
                    st.push((r0, self.v(node, a)));
                    for k in 0..=n {
                        st.push((r1, self.v(s * n + k, a)));
                    }
                    st.push((r1, self.u(node, a)));
                }
            }
        }
        st
    }
    fn jacobian_values(&self, x: &[f64], vals: &mut [f64]) {
        let n = self.order;
        let h2 = 0.5 / self.segments as f64;
        let mut o = 0;
        for s in 0..self.segments {
            for j in 0..n {
                let drow = &self.diff[j * (n + 1)..(j + 1) * (n + 1)];
                let node = s * n + j;
                for a in 0..self.axes {
                    vals[o..o + n + 1].copy_from_slice(drow);
                    o += n + 1;
                    vals[o] = -h2;
                    o += 1;
                    vals[o..o + n + 1].copy_from_slice(drow);
                    // the v-defect also depends on v(node) through the drag term
                    let v = x[self.v(node, a)];
                    vals[o + j] += h2 * self.drag * 2.0 * v.abs();
                    o += n + 1;
                    vals[o] = -h2;
                    o += 1;
                }
            }
        }
    }
    fn hessian_structure(&self) -> Vec<(usize, usize)> {
        let mut st = Vec::new();
        for node in 0..self.nodes() {
            for a in 0..self.axes {
                st.push((self.u(node, a), self.u(node, a)));
                st.push((self.v(node, a), self.v(node, a)));
            }
        }
        st
    }
    fn hessian_values(&self, x: &[f64], obj_factor: f64, lambda: &[f64], vals: &mut [f64]) {
        let n = self.order;
        let h2 = 0.5 / self.segments as f64;
        vals.fill(0.0);
        for node in 0..self.nodes() {
            for a in 0..self.axes {
                let k = 2 * (node * self.axes + a);
                vals[k] = 2.0 * obj_factor * self.weight[node];
                if node < self.segments * n {
                    // collocated in the segment that owns it as node j ≤ N − 1
                    let s = node / n;
                    let j = node - s * n;
                    let v = x[self.v(node, a)];
                    vals[k + 1] = lambda[self.row(s, j, a, 1)] * h2 * self.drag * 2.0 * v.signum();
                }
            }
        }
    }
}
