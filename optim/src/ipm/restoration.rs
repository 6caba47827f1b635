//! Feasibility-restoration problem (Wächter & Biegler 2006, Sect. 3.3, eq. (30)):
//!
//! ```text
//! min_{x,p,n}  ρ Σ (p_i + n_i) + ζ/2 ‖D_R (x − x_R)‖²      ζ = √μ, D_R = diag(min(1, 1/|x_R|))
//! s.t.         c(x) − p + n = 0,   x_L ≤ x ≤ x_U,   p, n ≥ 0
//! ```
//!
//! solved by the same interior-point core. [`StdProblem::early_stop`] returns true as soon as the
//! `x` part is acceptable to the outer filter and reduces the outer infeasibility `θ = ‖c‖₁` by
//! the factor κ_resto (W&B "return to the regular iteration" test).

use super::stdform::StdProblem;

/// What the restoration needs from the outer iteration to decide when to return.
pub(crate) struct OuterInfo {
    pub xl: Vec<f64>,
    pub xu: Vec<f64>,
    pub lo: Vec<usize>,
    pub up: Vec<usize>,
    pub damp: Vec<f64>,
    pub kappa_d: f64,
    pub mu: f64,
    pub filter: Vec<(f64, f64)>,
    pub theta_ref: f64,
    pub kappa_resto: f64,
    pub tol: f64,
}

/// The restoration NLP in standard form over `(x, p, n)`.
pub(crate) struct RestorationProblem<'a> {
    orig: &'a mut dyn StdProblem,
    n0: usize,
    m: usize,
    x_ref: Vec<f64>,
    dr2: Vec<f64>,
    rho: f64,
    zeta: f64,
    xl: Vec<f64>,
    xu: Vec<f64>,
    jac_pat: Vec<(usize, usize)>,
    hess_pat: Vec<(usize, usize)>,
    n_orig_jac: usize,
    n_orig_hess: usize,
    outer: OuterInfo,
    c_buf: Vec<f64>,
}

impl<'a> RestorationProblem<'a> {
    pub fn new(
        orig: &'a mut dyn StdProblem,
        x_ref: Vec<f64>,
        rho: f64,
        zeta: f64,
        outer: OuterInfo,
    ) -> Self {
        let n0 = orig.n();
        let m = orig.m();
        let mut xl = outer.xl.clone();
        let mut xu = outer.xu.clone();
        xl.extend(std::iter::repeat_n(0.0, 2 * m));
        xu.extend(std::iter::repeat_n(f64::INFINITY, 2 * m));
        let mut jac_pat = orig.jac_pattern().to_vec();
        let n_orig_jac = jac_pat.len();
        for i in 0..m {
            jac_pat.push((i, n0 + i));
            jac_pat.push((i, n0 + m + i));
        }
        let mut hess_pat = orig.hess_pattern().to_vec();
        let n_orig_hess = hess_pat.len();
        for j in 0..n0 {
            hess_pat.push((j, j));
        }
        let dr2 = x_ref
            .iter()
            .map(|v| (1.0f64).min(1.0 / v.abs()).powi(2))
            .collect();
        Self {
            orig,
            n0,
            m,
            x_ref,
            dr2,
            rho,
            zeta,
            xl,
            xu,
            jac_pat,
            hess_pat,
            n_orig_jac,
            n_orig_hess,
            outer,
            c_buf: vec![0.0; m],
        }
    }
}

impl StdProblem for RestorationProblem<'_> {
    fn n(&self) -> usize {
        self.n0 + 2 * self.m
    }
    fn m(&self) -> usize {
        self.m
    }
    fn x_lower(&self) -> &[f64] {
        &self.xl
    }
    fn x_upper(&self) -> &[f64] {
        &self.xu
    }
    fn jac_pattern(&self) -> &[(usize, usize)] {
        &self.jac_pat
    }
    fn hess_pattern(&self) -> &[(usize, usize)] {
        &self.hess_pat
    }
    fn eval_f(&mut self, w: &[f64]) -> f64 {
        let pn: f64 = w[self.n0..].iter().sum();
        let mut prox = 0.0;
        for j in 0..self.n0 {
            let d = w[j] - self.x_ref[j];
            prox += self.dr2[j] * d * d;
        }
        self.rho * pn + 0.5 * self.zeta * prox
    }
    fn eval_grad(&mut self, w: &[f64], g: &mut [f64]) {
        for j in 0..self.n0 {
            g[j] = self.zeta * self.dr2[j] * (w[j] - self.x_ref[j]);
        }
        g[self.n0..].iter_mut().for_each(|v| *v = self.rho);
    }
    fn eval_c(&mut self, w: &[f64], c: &mut [f64]) {
        self.orig.eval_c(&w[..self.n0], c);
        for i in 0..self.m {
            c[i] += -w[self.n0 + i] + w[self.n0 + self.m + i];
        }
    }
    fn eval_jac(&mut self, w: &[f64], v: &mut [f64]) {
        self.orig.eval_jac(&w[..self.n0], &mut v[..self.n_orig_jac]);
        for i in 0..self.m {
            v[self.n_orig_jac + 2 * i] = -1.0;
            v[self.n_orig_jac + 2 * i + 1] = 1.0;
        }
    }
    fn eval_hess(&mut self, w: &[f64], obj_factor: f64, y: &[f64], v: &mut [f64]) {
        self.orig
            .eval_hess(&w[..self.n0], 0.0, y, &mut v[..self.n_orig_hess]);
        for j in 0..self.n0 {
            v[self.n_orig_hess + j] = obj_factor * self.zeta * self.dr2[j];
        }
    }
    fn early_stop(&mut self, w: &[f64]) -> bool {
        let o = &self.outer;
        let x = &w[..self.n0];
        let mut phi = 0.0;
        for &j in &o.lo {
            let s = x[j] - o.xl[j];
            if s <= 0.0 {
                return false;
            }
            phi -= o.mu * libm::log(s);
        }
        for &j in &o.up {
            let s = o.xu[j] - x[j];
            if s <= 0.0 {
                return false;
            }
            phi -= o.mu * libm::log(s);
        }
        let kd = o.kappa_d * o.mu;
        for j in 0..self.n0 {
            if o.damp[j] > 0.0 {
                phi += kd * (x[j] - o.xl[j]);
            } else if o.damp[j] < 0.0 {
                phi += kd * (o.xu[j] - x[j]);
            }
        }
        let mut c = std::mem::take(&mut self.c_buf);
        self.orig.eval_c(x, &mut c);
        let theta: f64 = c.iter().map(|v| v.abs()).sum();
        self.c_buf = c;
        if !theta.is_finite() {
            return false;
        }
        let reduced = theta <= o.kappa_resto * o.theta_ref || theta <= 0.1 * o.tol;
        if !reduced {
            return false;
        }
        let f = self.orig.eval_f(x);
        phi += f;
        if !phi.is_finite() {
            return false;
        }
        self.outer
            .filter
            .iter()
            .all(|&(ft, fp)| theta < ft || phi < fp)
    }
    fn scales(&self) -> (f64, Option<&[f64]>) {
        (1.0, None)
    }
}
