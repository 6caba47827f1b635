//! The [`Nlp`] view of a [`Transcription`]: variable and constraint bounds, the objective c_j
//! or c_j/c_k (eq. 60) and its sparse derivatives, and the constraints and their Jacobian and
//! Hessian as the scattered sums of the phases' [`GraphFn`](super::super::GraphFn) blocks.

use super::*;

impl Nlp for Transcription {
    fn num_variables(&self) -> usize {
        self.n
    }
    fn num_constraints(&self) -> usize {
        self.m
    }
    fn variable_bounds(&self, lower: &mut [f64], upper: &mut [f64]) {
        lower.copy_from_slice(&self.xl);
        upper.copy_from_slice(&self.xu);
    }
    fn constraint_bounds(&self, lower: &mut [f64], upper: &mut [f64]) {
        lower.copy_from_slice(&self.gl);
        upper.copy_from_slice(&self.gu);
    }
    fn initial_point(&self, x: &mut [f64]) {
        x.copy_from_slice(&self.x_init);
    }
    fn objective(&self, x: &[f64]) -> f64 {
        match self.objective {
            Objective::Cost(j) => x[self.c0 + j],
            Objective::Ratio(j, k) => x[self.c0 + j] / x[self.c0 + k],
        }
    }
    fn gradient(&self, x: &[f64], grad: &mut [f64]) {
        grad.iter_mut().for_each(|v| *v = 0.0);
        match self.objective {
            Objective::Cost(j) => grad[self.c0 + j] = 1.0,
            Objective::Ratio(j, k) => {
                let (a, b) = (x[self.c0 + j], x[self.c0 + k]);
                grad[self.c0 + j] = 1.0 / b;
                grad[self.c0 + k] = -a / (b * b);
            }
        }
    }
    fn constraints(&self, x: &[f64], g: &mut [f64]) {
        g.iter_mut().for_each(|v| *v = 0.0);
        for &(r, c, v) in &self.linear {
            g[r] += v * x[c];
        }
        for it in &self.inst {
            let y = self.fns[it.f].eval(&self.locals(it, x));
            for (o, ts) in it.targets.iter().enumerate() {
                for &(r, c) in ts {
                    g[r] += c * y[o];
                }
            }
        }
    }
    fn jacobian_structure(&self) -> Vec<(usize, usize)> {
        self.jac_pattern.clone()
    }
    fn jacobian_values(&self, x: &[f64], values: &mut [f64]) {
        let mut k = 0;
        for &(_, _, v) in &self.linear {
            values[k] = v;
            k += 1;
        }
        for it in &self.inst {
            let f = &self.fns[it.f];
            let jv = f.jacobian(&self.locals(it, x));
            for (e, &(o, _)) in f.jacobian_pattern().iter().enumerate() {
                for &(_, c) in &it.targets[o] {
                    values[k] = c * jv[e];
                    k += 1;
                }
            }
        }
    }
    fn hessian_structure(&self) -> Vec<(usize, usize)> {
        self.hess_pattern.clone()
    }
    fn hessian_values(&self, x: &[f64], obj_factor: f64, lambda: &[f64], values: &mut [f64]) {
        let mut k = 0;
        for it in &self.inst {
            let f = &self.fns[it.f];
            let w: Vec<f64> = it
                .targets
                .iter()
                .map(|ts| ts.iter().map(|&(r, c)| c * lambda[r]).sum())
                .collect();
            let hv = f.hessian(&self.locals(it, x), &w);
            for v in hv {
                values[k] = v;
                k += 1;
            }
        }
        if let Objective::Ratio(j, kk) = self.objective {
            let (a, b) = (x[self.c0 + j], x[self.c0 + kk]);
            // φ = a/b: ∂²φ/∂a∂b = −1/b², ∂²φ/∂b² = 2a/b³.
            values[k] = obj_factor * (-1.0 / (b * b));
            values[k + 1] = obj_factor * (2.0 * a / (b * b * b));
        }
    }
}
