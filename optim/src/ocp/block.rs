//! Compiled graph functions with exact first and second derivatives.
//!
//! A [`GraphFn`] takes outputs y = f(v) built on a `bf_codegen` expression graph (the paper's
//! node functions: dynamics eq. 26/29, stick constraint eq. 14/27, validity h and σ eq. 4/18,
//! cost integrands eq. 61–65, impact law eq. 40) and compiles, once, three interpreter tapes:
//! the values, the sparse Jacobian ∂y_i/∂v_j (forward mode, one sweep per local variable) and
//! the lower triangle of the Hessian of the weighted sum Σ_i w_i y_i (forward over reverse,
//! with the weights w as extra graph inputs). Structural zeros are dropped, so the patterns
//! are exactly the graph's dependencies. No finite differences are involved.

use bf_codegen::diff;
use bf_codegen::graph::{Graph, Id, Node};
use bf_codegen::interp::Tape;

/// A vector function of `n_local` local variables with exact sparse derivatives.
#[derive(Debug, Clone)]
pub struct GraphFn {
    n_out: usize,
    template: Vec<f64>,
    local_vars: Vec<u32>,
    weight_base: usize,
    value: Tape,
    jac: Vec<(usize, usize)>,
    jac_tape: Tape,
    hess: Vec<(usize, usize)>,
    hess_tape: Tape,
}

impl GraphFn {
    /// Compiles `outputs` of graph `g` as a function of the graph variables `local_vars` (in
    /// that order); `fixed` gives the values of other graph variables (ε, runtime parameters);
    /// any other variable reads as 0.
    pub fn new(g: &mut Graph, outputs: &[Id], local_vars: &[u32], fixed: &[(u32, f64)]) -> Self {
        let mark = g.cone(outputs);
        let mut max_var = 0usize;
        for (i, m) in mark.iter().enumerate() {
            if *m && let Node::Var(v) = g.node(Id(i as u32)) {
                max_var = max_var.max(v as usize + 1);
            }
        }
        for &v in local_vars.iter().chain(fixed.iter().map(|f| &f.0)) {
            max_var = max_var.max(v as usize + 1);
        }
        let weight_base = max_var;
        let n_out = outputs.len();
        let mut template = vec![0.0; weight_base + n_out];
        for &(v, x) in fixed {
            template[v as usize] = x;
        }
        let value = Tape::new(g, outputs);
        let mut jac = Vec::new();
        let mut jac_ids = Vec::new();
        for (l, &v) in local_vars.iter().enumerate() {
            let col = diff::partial(g, outputs, v);
            for (o, id) in col.into_iter().enumerate() {
                if !g.is_zero(id) {
                    jac.push((o, l));
                    jac_ids.push(id);
                }
            }
        }
        // Keep the Jacobian entries row-major for readability of patterns.
        let mut order: Vec<usize> = (0..jac.len()).collect();
        order.sort_by_key(|&k| jac[k]);
        let jac: Vec<(usize, usize)> = order.iter().map(|&k| jac[k]).collect();
        let jac_ids: Vec<Id> = order.iter().map(|&k| jac_ids[k]).collect();
        let jac_tape = Tape::new(g, &jac_ids);
        let weighted: Vec<(Id, Id)> = outputs
            .iter()
            .enumerate()
            .map(|(i, &o)| (o, g.var((weight_base + i) as u32)))
            .collect();
        let h = diff::hessian(g, &weighted, local_vars);
        let mut hess = Vec::new();
        let mut hess_ids = Vec::new();
        for i in 0..local_vars.len() {
            for j in 0..=i {
                let id = h[i][j];
                if !g.is_zero(id) {
                    hess.push((i, j));
                    hess_ids.push(id);
                }
            }
        }
        let hess_tape = Tape::new(g, &hess_ids);
        GraphFn {
            n_out,
            template,
            local_vars: local_vars.to_vec(),
            weight_base,
            value,
            jac,
            jac_tape,
            hess,
            hess_tape,
        }
    }

    /// Number of outputs.
    pub fn n_out(&self) -> usize {
        self.n_out
    }

    /// Number of local variables.
    pub fn n_local(&self) -> usize {
        self.local_vars.len()
    }

    /// Jacobian pattern: (output, local variable) pairs, in the order of [`GraphFn::jacobian`].
    pub fn jacobian_pattern(&self) -> &[(usize, usize)] {
        &self.jac
    }

    /// Lower-triangle Hessian pattern (local i ≥ local j), in the order of [`GraphFn::hessian`].
    pub fn hessian_pattern(&self) -> &[(usize, usize)] {
        &self.hess
    }

    fn inputs(&self, local: &[f64]) -> Vec<f64> {
        let mut v = self.template.clone();
        for (k, &var) in self.local_vars.iter().enumerate() {
            v[var as usize] = local[k];
        }
        v
    }

    /// Output values at `local`.
    pub fn eval(&self, local: &[f64]) -> Vec<f64> {
        self.value.eval(&self.inputs(local))
    }

    /// Jacobian values at `local` (pattern order).
    pub fn jacobian(&self, local: &[f64]) -> Vec<f64> {
        self.jac_tape.eval(&self.inputs(local))
    }

    /// Values of the lower triangle of ∇²(Σ_i w_i y_i) at `local` (pattern order).
    pub fn hessian(&self, local: &[f64], weights: &[f64]) -> Vec<f64> {
        let mut v = self.inputs(local);
        v[self.weight_base..self.weight_base + self.n_out].copy_from_slice(weights);
        self.hess_tape.eval(&v)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn derivatives_match_hand_computation() {
        // y0 = x0² sin(x1) + c, y1 = x0 x1 with c a fixed input.
        let mut g = Graph::new();
        let (x0, x1, c) = (g.var(0), g.var(1), g.var(5));
        let s = g.sin(x1);
        let sq = g.square(x0);
        let p = g.mul(sq, s);
        let y0 = g.add(p, c);
        let y1 = g.mul(x0, x1);
        let f = GraphFn::new(&mut g, &[y0, y1], &[0, 1], &[(5, 2.0)]);
        let (a, b) = (0.7, -0.4);
        let v = f.eval(&[a, b]);
        assert!((v[0] - (a * a * b.sin() + 2.0)).abs() < 1e-15 && (v[1] - a * b).abs() < 1e-15);
        let jv = f.jacobian(&[a, b]);
        for (k, &(o, l)) in f.jacobian_pattern().iter().enumerate() {
            let exact = match (o, l) {
                (0, 0) => 2.0 * a * b.sin(),
                (0, 1) => a * a * b.cos(),
                (1, 0) => b,
                (1, 1) => a,
                _ => unreachable!(),
            };
            assert!((jv[k] - exact).abs() < 1e-14);
        }
        let (w0, w1) = (1.5, -0.5);
        let hv = f.hessian(&[a, b], &[w0, w1]);
        assert_eq!(f.hessian_pattern().len(), 3);
        for (k, &(i, j)) in f.hessian_pattern().iter().enumerate() {
            let exact = match (i, j) {
                (0, 0) => w0 * 2.0 * b.sin(),
                (1, 0) => w0 * 2.0 * a * b.cos() + w1,
                (1, 1) => -w0 * a * a * b.sin(),
                _ => unreachable!(),
            };
            assert!((hv[k] - exact).abs() < 1e-14);
        }
    }
}
