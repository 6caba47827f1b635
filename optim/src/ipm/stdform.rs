//! The internal standard form the algorithm works on,
//!
//! ```text
//! min f(x)   s.t.   c(x) = 0,   x_L ≤ x ≤ x_U          (Wächter & Biegler 2006, eq. (1))
//! ```
//!
//! and [`Reformulated`], which maps a user [`Nlp`] to it:
//! * fixed variables (`x_L = x_U`) are removed (Ipopt's `fixed_variable_treatment = make_parameter`);
//! * each inequality row `g_L ≤ g_i(x) ≤ g_U` gets a slack `s`: `c_i = σ_i g_i(x) − s`,
//!   `σ_i g_L ≤ s ≤ σ_i g_U`; equality rows become `c_i = σ_i (g_i(x) − g_L)`;
//! * the objective is scaled by `σ_f` and each row by `σ_i` (gradient-based or user scaling).

use super::nlp::{BOUND_INF, Nlp};
use super::settings::{ScalingMethod, Settings};
use crate::error::OptimError;

/// An equality-constrained, bound-constrained NLP in internal (scaled) variables.
pub(crate) trait StdProblem {
    /// Number of variables.
    fn n(&self) -> usize;
    /// Number of equality constraints.
    fn m(&self) -> usize;
    /// Lower bounds (−∞ allowed).
    fn x_lower(&self) -> &[f64];
    /// Upper bounds (+∞ allowed).
    fn x_upper(&self) -> &[f64];
    /// Jacobian triplet pattern.
    fn jac_pattern(&self) -> &[(usize, usize)];
    /// Hessian lower-triangle triplet pattern.
    fn hess_pattern(&self) -> &[(usize, usize)];
    /// Objective.
    fn eval_f(&mut self, x: &[f64]) -> f64;
    /// Gradient.
    fn eval_grad(&mut self, x: &[f64], g: &mut [f64]);
    /// Constraints.
    fn eval_c(&mut self, x: &[f64], c: &mut [f64]);
    /// Jacobian values.
    fn eval_jac(&mut self, x: &[f64], v: &mut [f64]);
    /// Hessian of `σ f + yᵀ c`.
    fn eval_hess(&mut self, x: &[f64], obj_factor: f64, y: &[f64], v: &mut [f64]);
    /// Restoration hook: true when the outer problem accepts this point.
    fn early_stop(&mut self, _x: &[f64]) -> bool {
        false
    }
    /// Objective factor and row factors to report unscaled errors.
    fn scales(&self) -> (f64, Option<&[f64]>) {
        (1.0, None)
    }
    /// Number of leading variables that are the problem's own (the rest are slacks of
    /// inequality rows, bounded whenever those are).
    fn n_own(&self) -> usize {
        self.n()
    }
}

/// User NLP → standard form (see module docs).
pub(crate) struct Reformulated<'a> {
    nlp: &'a dyn Nlp,
    pub n_user: usize,
    pub m_user: usize,
    pub x_l_user: Vec<f64>,
    pub x_u_user: Vec<f64>,
    pub g_l: Vec<f64>,
    pub g_u: Vec<f64>,
    /// internal index → user index, for free variables.
    pub free: Vec<usize>,
    /// user index → internal index (usize::MAX if fixed).
    pub inv: Vec<usize>,
    /// row → slack internal index (usize::MAX for equalities).
    pub slack: Vec<usize>,
    pub obj_scale: f64,
    pub con_scale: Vec<f64>,
    xl: Vec<f64>,
    xu: Vec<f64>,
    jac_pat: Vec<(usize, usize)>,
    /// For the first `jac_src.len()` internal entries: index into the user values.
    jac_src: Vec<usize>,
    user_jac_pat: Vec<(usize, usize)>,
    hess_pat: Vec<(usize, usize)>,
    hess_src: Vec<usize>,
    user_hess_len: usize,
    // scratch
    xu_full: Vec<f64>,
    g_buf: Vec<f64>,
    grad_buf: Vec<f64>,
    jac_buf: Vec<f64>,
    hess_buf: Vec<f64>,
    lam_buf: Vec<f64>,
}

fn is_inf(v: f64) -> bool {
    v.abs() >= BOUND_INF
}

impl<'a> Reformulated<'a> {
    /// Validates the user problem and builds the reformulation (scaling computed at `x0`).
    pub fn new(nlp: &'a dyn Nlp, settings: &Settings, x0: &[f64]) -> Result<Self, OptimError> {
        let n = nlp.num_variables();
        let m = nlp.num_constraints();
        if x0.len() != n {
            return Err(OptimError::DimensionMismatch {
                what: "initial point",
                expected: n,
                found: x0.len(),
            });
        }
        let mut x_l = vec![0.0; n];
        let mut x_u = vec![0.0; n];
        nlp.variable_bounds(&mut x_l, &mut x_u);
        let mut g_l = vec![0.0; m];
        let mut g_u = vec![0.0; m];
        nlp.constraint_bounds(&mut g_l, &mut g_u);
        for j in 0..n {
            if x_l[j].is_nan()
                || x_u[j].is_nan()
                || x_l[j] > x_u[j]
                || x_l[j] >= BOUND_INF
                || x_u[j] <= -BOUND_INF
            {
                return Err(OptimError::InvalidBounds {
                    what: "variable",
                    index: j,
                    lower: x_l[j],
                    upper: x_u[j],
                });
            }
            if is_inf(x_l[j]) {
                x_l[j] = f64::NEG_INFINITY;
            }
            if is_inf(x_u[j]) {
                x_u[j] = f64::INFINITY;
            }
        }
        for i in 0..m {
            if g_l[i].is_nan()
                || g_u[i].is_nan()
                || g_l[i] > g_u[i]
                || g_l[i] >= BOUND_INF
                || g_u[i] <= -BOUND_INF
            {
                return Err(OptimError::InvalidBounds {
                    what: "constraint",
                    index: i,
                    lower: g_l[i],
                    upper: g_u[i],
                });
            }
            if is_inf(g_l[i]) {
                g_l[i] = f64::NEG_INFINITY;
            }
            if is_inf(g_u[i]) {
                g_u[i] = f64::INFINITY;
            }
        }
        let user_jac_pat = nlp.jacobian_structure();
        for (k, &(r, c)) in user_jac_pat.iter().enumerate() {
            if r >= m || c >= n {
                return Err(OptimError::InvalidPattern {
                    what: "jacobian",
                    index: k,
                    row: r,
                    col: c,
                });
            }
        }
        let user_hess_pat = nlp.hessian_structure();
        for (k, &(r, c)) in user_hess_pat.iter().enumerate() {
            if r >= n || c >= n || r < c {
                return Err(OptimError::InvalidPattern {
                    what: "hessian",
                    index: k,
                    row: r,
                    col: c,
                });
            }
        }
        let mut free = Vec::new();
        let mut inv = vec![usize::MAX; n];
        for j in 0..n {
            if x_l[j] != x_u[j] {
                inv[j] = free.len();
                free.push(j);
            }
        }
        let nf = free.len();
        let mut slack = vec![usize::MAX; m];
        let mut ns = 0;
        for i in 0..m {
            if g_l[i] != g_u[i] {
                slack[i] = nf + ns;
                ns += 1;
            }
        }
        // Scaling at the initial point clamped into the bounds.
        let mut xs: Vec<f64> = (0..n).map(|j| x0[j].clamp(x_l[j], x_u[j])).collect();
        xs.iter_mut().zip(x0).for_each(|(v, &o)| {
            if v.is_nan() {
                *v = o;
            }
        });
        let (mut obj_scale, mut con_scale) = (1.0, vec![1.0; m]);
        match settings.scaling.method {
            ScalingMethod::None => {}
            ScalingMethod::User => {
                if let Some(s) = nlp.scaling() {
                    if s.constraints.len() != m {
                        return Err(OptimError::DimensionMismatch {
                            what: "constraint scaling",
                            expected: m,
                            found: s.constraints.len(),
                        });
                    }
                    // A factor that is not positive and finite is a mistake of the caller, as a
                    // wrong length is: no factor stands in for it.
                    let factors = std::iter::once(("objective scaling", 0, s.objective)).chain(
                        s.constraints
                            .iter()
                            .enumerate()
                            .map(|(i, &v)| ("constraint scaling", i, v)),
                    );
                    for (what, index, value) in factors {
                        if !(value > 0.0 && value.is_finite()) {
                            return Err(OptimError::InvalidValue {
                                what,
                                index,
                                value,
                                expected: "positive and finite",
                            });
                        }
                    }
                    obj_scale = s.objective;
                    con_scale.copy_from_slice(&s.constraints);
                }
            }
            ScalingMethod::GradientBased => {
                let gmax = settings.scaling.scaling_max_gradient;
                let mut grad = vec![0.0; n];
                nlp.gradient(&xs, &mut grad);
                let gn = grad.iter().fold(0.0f64, |a, v| a.max(v.abs()));
                // Outside [scaling_min_gradient, scaling_max_gradient] the objective is
                // brought to the gradient target `scaling_max_gradient`, from above (Ipopt,
                // but without its floor) or from below, so that an objective c·f with such a
                // gradient is scaled to the same internal objective whatever c: its iterates
                // and the meaning of the absolute tolerances do not depend on c.
                if gn.is_finite()
                    && (gn > gmax || (gn > 0.0 && gn < settings.scaling.scaling_min_gradient))
                {
                    obj_scale = gmax / gn;
                }
                let mut jv = vec![0.0; user_jac_pat.len()];
                nlp.jacobian_values(&xs, &mut jv);
                let mut rmax = vec![0.0f64; m];
                for (k, &(r, _)) in user_jac_pat.iter().enumerate() {
                    rmax[r] = rmax[r].max(jv[k].abs());
                }
                for i in 0..m {
                    if rmax[i].is_finite() && rmax[i] > gmax {
                        con_scale[i] = (gmax / rmax[i]).max(1e-8);
                    }
                }
            }
        }
        obj_scale *= settings.scaling.obj_scaling_factor;
        let mut xl = Vec::with_capacity(nf + ns);
        let mut xu = Vec::with_capacity(nf + ns);
        for &j in &free {
            xl.push(x_l[j]);
            xu.push(x_u[j]);
        }
        for i in 0..m {
            if slack[i] != usize::MAX {
                xl.push(con_scale[i] * g_l[i]);
                xu.push(con_scale[i] * g_u[i]);
            }
        }
        let mut jac_pat = Vec::new();
        let mut jac_src = Vec::new();
        for (k, &(r, c)) in user_jac_pat.iter().enumerate() {
            if inv[c] != usize::MAX {
                jac_pat.push((r, inv[c]));
                jac_src.push(k);
            }
        }
        for i in 0..m {
            if slack[i] != usize::MAX {
                jac_pat.push((i, slack[i]));
            }
        }
        let mut hess_pat = Vec::new();
        let mut hess_src = Vec::new();
        for (k, &(r, c)) in user_hess_pat.iter().enumerate() {
            if inv[r] != usize::MAX && inv[c] != usize::MAX {
                hess_pat.push((inv[r], inv[c]));
                hess_src.push(k);
            }
        }
        let mut xu_full = xs.clone();
        for j in 0..n {
            if inv[j] == usize::MAX {
                xu_full[j] = x_l[j];
            }
        }
        Ok(Self {
            nlp,
            n_user: n,
            m_user: m,
            x_l_user: x_l,
            x_u_user: x_u,
            g_l,
            g_u,
            free,
            inv,
            slack,
            obj_scale,
            con_scale,
            xl,
            xu,
            jac_pat,
            jac_src,
            user_jac_pat: user_jac_pat.clone(),
            hess_pat,
            hess_src,
            user_hess_len: user_hess_pat.len(),
            xu_full,
            g_buf: vec![0.0; m],
            grad_buf: vec![0.0; n],
            jac_buf: vec![0.0; user_jac_pat.len()],
            hess_buf: vec![0.0; user_hess_pat.len()],
            lam_buf: vec![0.0; m],
        })
    }

    /// Internal point from a user point (slacks set to the scaled constraint values).
    pub fn internal_point(&mut self, x_user: &[f64]) -> Vec<f64> {
        let mut x = vec![0.0; self.xl.len()];
        for (k, &j) in self.free.iter().enumerate() {
            x[k] = x_user[j];
        }
        for j in 0..self.n_user {
            self.xu_full[j] = if self.inv[j] == usize::MAX {
                self.x_l_user[j]
            } else {
                x_user[j]
            };
        }
        self.nlp.constraints(&self.xu_full, &mut self.g_buf);
        for i in 0..self.m_user {
            if self.slack[i] != usize::MAX {
                x[self.slack[i]] = self.con_scale[i] * self.g_buf[i];
            }
        }
        x
    }

    /// User point from an internal point (fixed variables at their value).
    pub fn to_user(&self, x: &[f64]) -> Vec<f64> {
        let mut out = self.x_l_user.clone();
        for (k, &j) in self.free.iter().enumerate() {
            out[j] = x[k];
        }
        out
    }

    fn load(&mut self, x: &[f64]) {
        for (k, &j) in self.free.iter().enumerate() {
            self.xu_full[j] = x[k];
        }
    }

    /// User Jacobian pattern.
    pub fn user_jac_pattern(&self) -> &[(usize, usize)] {
        &self.user_jac_pat
    }
}

impl StdProblem for Reformulated<'_> {
    fn n(&self) -> usize {
        self.xl.len()
    }
    fn m(&self) -> usize {
        self.m_user
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
    fn eval_f(&mut self, x: &[f64]) -> f64 {
        self.load(x);
        self.obj_scale * self.nlp.objective(&self.xu_full)
    }
    fn eval_grad(&mut self, x: &[f64], g: &mut [f64]) {
        self.load(x);
        self.nlp.gradient(&self.xu_full, &mut self.grad_buf);
        for (k, &j) in self.free.iter().enumerate() {
            g[k] = self.obj_scale * self.grad_buf[j];
        }
        g[self.free.len()..].iter_mut().for_each(|v| *v = 0.0);
    }
    fn eval_c(&mut self, x: &[f64], c: &mut [f64]) {
        self.load(x);
        self.nlp.constraints(&self.xu_full, &mut self.g_buf);
        for i in 0..self.m_user {
            let s = self.slack[i];
            c[i] = if s == usize::MAX {
                self.con_scale[i] * (self.g_buf[i] - self.g_l[i])
            } else {
                self.con_scale[i] * self.g_buf[i] - x[s]
            };
        }
    }
    fn eval_jac(&mut self, x: &[f64], v: &mut [f64]) {
        self.load(x);
        self.nlp.jacobian_values(&self.xu_full, &mut self.jac_buf);
        let nj = self.jac_src.len();
        for k in 0..nj {
            let src = self.jac_src[k];
            v[k] = self.con_scale[self.user_jac_pat[src].0] * self.jac_buf[src];
        }
        v[nj..].iter_mut().for_each(|e| *e = -1.0);
    }
    fn eval_hess(&mut self, x: &[f64], obj_factor: f64, y: &[f64], v: &mut [f64]) {
        self.load(x);
        for i in 0..self.m_user {
            self.lam_buf[i] = y[i] * self.con_scale[i];
        }
        debug_assert_eq!(self.hess_buf.len(), self.user_hess_len);
        self.nlp.hessian_values(
            &self.xu_full,
            obj_factor * self.obj_scale,
            &self.lam_buf,
            &mut self.hess_buf,
        );
        for (k, &src) in self.hess_src.iter().enumerate() {
            v[k] = self.hess_buf[src];
        }
    }
    fn scales(&self) -> (f64, Option<&[f64]>) {
        (self.obj_scale, Some(&self.con_scale))
    }
    fn n_own(&self) -> usize {
        self.free.len()
    }
}
