//! Minimum-energy rest-to-rest double integrator, trapezoidal collocation:
//!
//! ```text
//! min ∫₀ᵀ u² dt   s.t.  ṗ = v,  v̇ = u,  p(0) = v(0) = 0,  p(T) = d,  v(T) = 0
//! ```
//! Closed form: `u*(t) = 6d/T² (1 − 2t/T)`, `J* = 12 d²/T³`; costates `λ_p = −24 d/T³`,
//! `λ_v = −2u*`. Variables per node k = 0..N: `(p_k, v_k, u_k)`; defects per interval:
//! `p_{k+1} − p_k − h/2 (v_k + v_{k+1}) = 0`, `v_{k+1} − v_k − h/2 (u_k + u_{k+1}) = 0`;
//! objective `Σ h/2 (u_k² + u_{k+1}²)`. Boundary values are fixed variables (x_L = x_U).
//! An optional control bound `u ≤ u_max` and a nonlinear drag term `v̇ = u − c_d v|v|` make a
//! harder variant (no closed form).

#![allow(dead_code)]

use bf_optim::ipm::Nlp;

pub struct DoubleIntegrator {
    pub n_int: usize,
    pub t_final: f64,
    pub distance: f64,
    pub u_max: f64,
    pub drag: f64,
}

impl DoubleIntegrator {
    pub fn new(n_int: usize) -> Self {
        Self {
            n_int,
            t_final: 1.0,
            distance: 1.0,
            u_max: f64::INFINITY,
            drag: 0.0,
        }
    }
    fn h(&self) -> f64 {
        self.t_final / self.n_int as f64
    }
    pub fn p(k: usize) -> usize {
        3 * k
    }
    pub fn v(k: usize) -> usize {
        3 * k + 1
    }
    pub fn u(k: usize) -> usize {
        3 * k + 2
    }
    /// Acceleration a(v, u) = u − c v|v| and its partials.
    fn acc(&self, v: f64, u: f64) -> (f64, f64, f64) {
        (u - self.drag * v * v.abs(), -2.0 * self.drag * v.abs(), 1.0)
    }
}

impl Nlp for DoubleIntegrator {
    fn num_variables(&self) -> usize {
        3 * (self.n_int + 1)
    }
    fn num_constraints(&self) -> usize {
        2 * self.n_int
    }
    fn variable_bounds(&self, lower: &mut [f64], upper: &mut [f64]) {
        lower.fill(f64::NEG_INFINITY);
        upper.fill(f64::INFINITY);
        for k in 0..=self.n_int {
            upper[Self::u(k)] = self.u_max;
        }
        let n = self.n_int;
        for (i, val) in [
            (Self::p(0), 0.0),
            (Self::v(0), 0.0),
            (Self::p(n), self.distance),
            (Self::v(n), 0.0),
        ] {
            lower[i] = val;
            upper[i] = val;
        }
    }
    fn constraint_bounds(&self, lower: &mut [f64], upper: &mut [f64]) {
        lower.fill(0.0);
        upper.fill(0.0);
    }
    fn initial_point(&self, x: &mut [f64]) {
        // straight-line position guess, zero velocity and control
        for k in 0..=self.n_int {
            let t = k as f64 / self.n_int as f64;
            x[Self::p(k)] = self.distance * t;
            x[Self::v(k)] = 0.0;
            x[Self::u(k)] = 0.0;
        }
    }
    fn objective(&self, x: &[f64]) -> f64 {
        let h = self.h();
        (0..self.n_int)
            .map(|k| 0.5 * h * (x[Self::u(k)].powi(2) + x[Self::u(k + 1)].powi(2)))
            .sum()
    }
    fn gradient(&self, x: &[f64], grad: &mut [f64]) {
        let h = self.h();
        grad.fill(0.0);
        for k in 0..self.n_int {
            grad[Self::u(k)] += h * x[Self::u(k)];
            grad[Self::u(k + 1)] += h * x[Self::u(k + 1)];
        }
    }
    fn constraints(&self, x: &[f64], g: &mut [f64]) {
        let h = self.h();
        for k in 0..self.n_int {
            let (a0, _, _) = self.acc(x[Self::v(k)], x[Self::u(k)]);
            let (a1, _, _) = self.acc(x[Self::v(k + 1)], x[Self::u(k + 1)]);
            g[2 * k] =
                x[Self::p(k + 1)] - x[Self::p(k)] - 0.5 * h * (x[Self::v(k)] + x[Self::v(k + 1)]);
            g[2 * k + 1] = x[Self::v(k + 1)] - x[Self::v(k)] - 0.5 * h * (a0 + a1);
        }
    }
    fn jacobian_structure(&self) -> Vec<(usize, usize)> {
        let mut s = Vec::with_capacity(10 * self.n_int);
        for k in 0..self.n_int {
            let (r0, r1) = (2 * k, 2 * k + 1);
            s.extend_from_slice(&[
                (r0, Self::p(k)),
                (r0, Self::p(k + 1)),
                (r0, Self::v(k)),
                (r0, Self::v(k + 1)),
                (r1, Self::v(k)),
                (r1, Self::v(k + 1)),
                (r1, Self::u(k)),
                (r1, Self::u(k + 1)),
            ]);
        }
        s
    }
    fn jacobian_values(&self, x: &[f64], v: &mut [f64]) {
        let h = self.h();
        for k in 0..self.n_int {
            let (_, av0, au0) = self.acc(x[Self::v(k)], x[Self::u(k)]);
            let (_, av1, au1) = self.acc(x[Self::v(k + 1)], x[Self::u(k + 1)]);
            let o = 8 * k;
            v[o] = -1.0;
            v[o + 1] = 1.0;
            v[o + 2] = -0.5 * h;
            v[o + 3] = -0.5 * h;
            v[o + 4] = -1.0 - 0.5 * h * av0;
            v[o + 5] = 1.0 - 0.5 * h * av1;
            v[o + 6] = -0.5 * h * au0;
            v[o + 7] = -0.5 * h * au1;
        }
    }
    fn hessian_structure(&self) -> Vec<(usize, usize)> {
        // diagonal in u (objective) and in v (drag term)
        let mut s = Vec::with_capacity(2 * (self.n_int + 1));
        for k in 0..=self.n_int {
            s.push((Self::u(k), Self::u(k)));
            s.push((Self::v(k), Self::v(k)));
        }
        s
    }
    fn hessian_values(&self, x: &[f64], obj_factor: f64, lambda: &[f64], values: &mut [f64]) {
        let h = self.h();
        for k in 0..=self.n_int {
            let w = if k == 0 || k == self.n_int { 0.5 } else { 1.0 };
            values[2 * k] = obj_factor * 2.0 * h * w;
            // d²a/dv² = −2c sign(v); v-defect rows k−1 and k both contain a(v_k) with factor −h/2
            let avv = -2.0 * self.drag * x[Self::v(k)].signum();
            let mut lam = 0.0;
            if k > 0 {
                lam += lambda[2 * (k - 1) + 1];
            }
            if k < self.n_int {
                lam += lambda[2 * k + 1];
            }
            values[2 * k + 1] = -0.5 * h * avv * lam;
        }
    }
}
