//! The user-facing NLP interface and a finite-difference derivative checker.
//!
//! ```text
//! min f(x)   s.t.   g_L ≤ g(x) ≤ g_U,   x_L ≤ x ≤ x_U
//! ```
//! Equalities are rows with `g_L = g_U`; ±∞ (any value with |·| ≥ 1e19, as in Ipopt) means
//! unbounded. The Lagrangian is `L = σ_f f(x) + λᵀ g(x)` (Ipopt's sign convention), so
//! [`Nlp::hessian_values`] returns the lower triangle of `σ_f ∇²f + Σ λ_i ∇²g_i`.

/// Values with magnitude at or above this are treated as infinite bounds (Ipopt's
/// `nlp_lower_bound_inf` / `nlp_upper_bound_inf`).
pub const BOUND_INF: f64 = 1e19;

/// Optional user scaling (multiplies the objective and each constraint row).
#[derive(Debug, Clone, PartialEq)]
pub struct NlpScaling {
    /// Objective factor (positive and finite, else the solve ends with
    /// [`OptimError::InvalidValue`](crate::OptimError::InvalidValue)).
    pub objective: f64,
    /// One factor per constraint (each positive and finite, as `objective`; a wrong length is
    /// [`OptimError::DimensionMismatch`](crate::OptimError::DimensionMismatch)).
    pub constraints: Vec<f64>,
}

/// A smooth nonlinear program with sparse first and second derivatives.
///
/// The objective and the constraints may return non-finite values at a trial point (e.g.
/// outside their domain): the line search then cuts the step (and a restoration point where
/// they are not finite fails the restoration phase). Elsewhere a non-finite value ends the
/// solve with [`OptimError::NonFinite`](crate::OptimError::NonFinite): the objective or a
/// constraint at the initial point (after its push into the bounds), the gradient or the
/// Jacobian at the initial point and at every point the solve moves to (an accepted trial
/// point, the end of a restoration phase), and the Hessian wherever it is evaluated (once per
/// iteration, at the current point). Sparsity patterns are queried once per solve; values are
/// requested per iteration in the order of the pattern. Duplicate triplets are summed.
pub trait Nlp {
    /// Number of variables `n`.
    fn num_variables(&self) -> usize;
    /// Number of constraints `m`.
    fn num_constraints(&self) -> usize;
    /// Writes variable bounds `x_L`, `x_U` (length `n`; use ±∞ for none).
    fn variable_bounds(&self, lower: &mut [f64], upper: &mut [f64]);
    /// Writes constraint bounds `g_L`, `g_U` (length `m`; equal values mean an equality).
    fn constraint_bounds(&self, lower: &mut [f64], upper: &mut [f64]);
    /// Writes the initial point (length `n`).
    fn initial_point(&self, x: &mut [f64]);
    /// Objective `f(x)`.
    fn objective(&self, x: &[f64]) -> f64;
    /// Gradient `∇f(x)` (length `n`).
    fn gradient(&self, x: &[f64], grad: &mut [f64]);
    /// Constraint values `g(x)` (length `m`).
    fn constraints(&self, x: &[f64], g: &mut [f64]);
    /// Jacobian pattern as `(row = constraint, col = variable)` triplets.
    fn jacobian_structure(&self) -> Vec<(usize, usize)>;
    /// Jacobian values in the order of [`jacobian_structure`](Nlp::jacobian_structure).
    fn jacobian_values(&self, x: &[f64], values: &mut [f64]);
    /// Lower-triangle (`row ≥ col`) pattern of the Hessian of the Lagrangian.
    fn hessian_structure(&self) -> Vec<(usize, usize)>;
    /// Values of `σ_f ∇²f(x) + Σ_i λ_i ∇²g_i(x)` in the order of
    /// [`hessian_structure`](Nlp::hessian_structure).
    fn hessian_values(&self, x: &[f64], obj_factor: f64, lambda: &[f64], values: &mut [f64]);
    /// Optional user scaling; used when `ScalingSettings::scaling` is `ScalingMethod::User`.
    fn scaling(&self) -> Option<NlpScaling> {
        None
    }
}

/// Worst relative errors found by [`check_derivatives`] (error = |analytic − fd| / max(1, |fd|)).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct DerivativeReport {
    /// Max error of the gradient and the variable index where it occurs.
    pub gradient: (f64, usize),
    /// Max error of the Jacobian (including entries missing from the pattern) and (row, col).
    pub jacobian: (f64, (usize, usize)),
    /// Max error of the Hessian of the Lagrangian (full symmetric matrix, with the given
    /// `obj_factor`, `lambda`) and (row, col).
    pub hessian: (f64, (usize, usize)),
    /// Pattern problems found (out of range, upper-triangle Hessian entries).
    pub pattern_errors: Vec<String>,
}

impl DerivativeReport {
    /// Largest of the three errors (∞ if there is a pattern error).
    pub fn max_error(&self) -> f64 {
        if !self.pattern_errors.is_empty() {
            return f64::INFINITY;
        }
        self.gradient.0.max(self.jacobian.0).max(self.hessian.0)
    }
}

/// Checks gradient, Jacobian and Hessian of `nlp` at `x` by central differences with step
/// `h·max(1, |x_j|)`: gradient and Jacobian against differences of `f`, `g`; the Hessian (as a
/// full symmetric matrix built from the lower-triangle triplets) against differences of
/// `σ_f ∇f + Jᵀλ`. Costs `O(n)` function and derivative evaluations (one column at a time, no
/// dense `n × n` storage).
pub fn check_derivatives(
    nlp: &dyn Nlp,
    x: &[f64],
    obj_factor: f64,
    lambda: &[f64],
    h: f64,
) -> DerivativeReport {
    let n = nlp.num_variables();
    let m = nlp.num_constraints();
    let mut rep = DerivativeReport::default();
    if x.len() != n || lambda.len() != m {
        rep.pattern_errors.push(format!(
            "x has {} entries (n = {n}), lambda {} (m = {m})",
            x.len(),
            lambda.len()
        ));
        return rep;
    }
    let jp = nlp.jacobian_structure();
    let hp = nlp.hessian_structure();
    for (k, &(r, c)) in jp.iter().enumerate() {
        if r >= m || c >= n {
            rep.pattern_errors
                .push(format!("jacobian entry {k} = ({r}, {c}) out of range"));
        }
    }
    for (k, &(r, c)) in hp.iter().enumerate() {
        if r >= n || c >= n || r < c {
            rep.pattern_errors.push(format!(
                "hessian entry {k} = ({r}, {c}) out of range or above the diagonal"
            ));
        }
    }
    if !rep.pattern_errors.is_empty() {
        return rep;
    }
    let rel = |a: f64, b: f64| {
        let e = (a - b).abs() / b.abs().max(1.0);
        if e.is_nan() { f64::INFINITY } else { e }
    };
    let mut grad = vec![0.0; n];
    nlp.gradient(x, &mut grad);
    let mut jv = vec![0.0; jp.len()];
    nlp.jacobian_values(x, &mut jv);
    let mut hv = vec![0.0; hp.len()];
    nlp.hessian_values(x, obj_factor, lambda, &mut hv);
    // Column-wise views of J and of the full symmetric H.
    let mut jcols: Vec<Vec<(usize, f64)>> = vec![Vec::new(); n];
    for (k, &(r, c)) in jp.iter().enumerate() {
        jcols[c].push((r, jv[k]));
    }
    let mut hcols: Vec<Vec<(usize, f64)>> = vec![Vec::new(); n];
    for (k, &(r, c)) in hp.iter().enumerate() {
        hcols[c].push((r, hv[k]));
        if r != c {
            hcols[r].push((c, hv[k]));
        }
    }
    let grad_lag = |xx: &[f64], out: &mut [f64]| {
        nlp.gradient(xx, out);
        out.iter_mut().for_each(|v| *v *= obj_factor);
        let mut vals = vec![0.0; jp.len()];
        nlp.jacobian_values(xx, &mut vals);
        for (k, &(r, c)) in jp.iter().enumerate() {
            out[c] += lambda[r] * vals[k];
        }
    };
    let mut xp = x.to_vec();
    let (mut gp, mut gm) = (vec![0.0; m], vec![0.0; m]);
    let (mut lp, mut lm) = (vec![0.0; n], vec![0.0; n]);
    let mut jcol = vec![0.0; m];
    let mut hcol = vec![0.0; n];
    for j in 0..n {
        let step = h * x[j].abs().max(1.0);
        xp[j] = x[j] + step;
        let fp = nlp.objective(&xp);
        nlp.constraints(&xp, &mut gp);
        grad_lag(&xp, &mut lp);
        xp[j] = x[j] - step;
        let fm = nlp.objective(&xp);
        nlp.constraints(&xp, &mut gm);
        grad_lag(&xp, &mut lm);
        xp[j] = x[j];
        let e = rel(grad[j], (fp - fm) / (2.0 * step));
        if e > rep.gradient.0 || e.is_infinite() {
            rep.gradient = (e, j);
        }
        jcol.iter_mut().for_each(|v| *v = 0.0);
        for &(r, v) in &jcols[j] {
            jcol[r] += v;
        }
        for r in 0..m {
            let e = rel(jcol[r], (gp[r] - gm[r]) / (2.0 * step));
            if e > rep.jacobian.0 {
                rep.jacobian = (e, (r, j));
            }
        }
        hcol.iter_mut().for_each(|v| *v = 0.0);
        for &(r, v) in &hcols[j] {
            hcol[r] += v;
        }
        for i in 0..n {
            let e = rel(hcol[i], (lp[i] - lm[i]) / (2.0 * step));
            if e > rep.hessian.0 {
                rep.hessian = (e, (i, j));
            }
        }
    }
    rep
}
