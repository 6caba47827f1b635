//! The [`Nlp`] view of a [`Transcription`]: variable and constraint bounds, the objective c_j
//! or c_j/c_k (eq. 60) and its sparse derivatives, and the constraints and their Jacobian and
//! Hessian as the scattered sums of the phases' [`GraphFn`](super::super::GraphFn) blocks.
//!
//! Instances are evaluated in order; four consecutive instances of one node function with
//! batched kernels (the collocation nodes of a phase) are evaluated in one batched call
//! ([`GraphFn::eval_x4`]), the rest one by one, with bitwise the same values either way.
//! [`Transcription::batch_nodes`] off evaluates every node one by one.

use super::super::block::Part;
use super::*;

impl Transcription {
    /// Evaluates `part` of every instance at `x` and hands each instance's values to `sink`, in
    /// instance order. For [`Part::Hessian`], the weights of an instance are its targets'
    /// multipliers Σ c·λ_r. Runs of four consecutive instances of one function with batched
    /// kernels take one batched call ([`Transcription::batch_nodes`]).
    fn eval_instances(
        &self,
        x: &[f64],
        part: Part,
        lambda: &[f64],
        mut sink: impl FnMut(&Instance, &[f64]),
    ) {
        let weights = |it: &Instance, w: &mut Vec<f64>| {
            w.extend(
                it.targets
                    .iter()
                    .map(|ts| ts.iter().map(|&(r, c)| c * lambda[r]).sum::<f64>()),
            );
        };
        let (mut loc, mut w, mut out, mut row) = (Vec::new(), Vec::new(), Vec::new(), Vec::new());
        let mut i = 0;
        while i < self.inst.len() {
            let it = &self.inst[i];
            let f = &self.fns[it.f];
            if self.batch_nodes
                && f.has_x4()
                && let Some(group) = self.inst.get(i..i + 4)
                && group
                    .iter()
                    .all(|j| j.f == it.f && j.map.len() == f.n_local())
            {
                // The batched kernels take the four nodes' entries interleaved (node l's
                // entry k at 4k + l).
                let no = f.n_out();
                loc.resize(4 * f.n_local(), 0.0);
                w.resize(if part == Part::Hessian { 4 * no } else { 0 }, 0.0);
                for (l, j) in group.iter().enumerate() {
                    for (k, &m) in j.map.iter().enumerate() {
                        loc[4 * k + l] = x[m];
                    }
                    if part == Part::Hessian {
                        row.clear();
                        weights(j, &mut row);
                        for (k, &v) in row.iter().enumerate().take(no) {
                            w[4 * k + l] = v;
                        }
                    }
                }
                let n = f.part_len(part);
                out.resize(4 * n, 0.0);
                if f.eval_x4(part, &loc, &w, &mut out) {
                    for (l, j) in group.iter().enumerate() {
                        row.clear();
                        row.extend(out.iter().skip(l).step_by(4));
                        sink(j, &row);
                    }
                    i += 4;
                    continue;
                }
            }
            let local = self.locals(it, x);
            let v = match part {
                Part::Value => f.eval(&local),
                Part::Jacobian => f.jacobian(&local),
                Part::Hessian => {
                    w.clear();
                    weights(it, &mut w);
                    f.hessian(&local, &w)
                }
            };
            sink(it, &v);
            i += 1;
        }
    }
}

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
        self.eval_instances(x, Part::Value, &[], |it, y| {
            for (o, ts) in it.targets.iter().enumerate() {
                for &(r, c) in ts {
                    g[r] += c * y[o];
                }
            }
        });
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
        self.eval_instances(x, Part::Jacobian, &[], |it, jv| {
            let f = &self.fns[it.f];
            for (e, &(o, _)) in f.jacobian_pattern().iter().enumerate() {
                for &(_, c) in &it.targets[o] {
                    values[k] = c * jv[e];
                    k += 1;
                }
            }
        });
    }
    fn hessian_structure(&self) -> Vec<(usize, usize)> {
        self.hess_pattern.clone()
    }
    fn hessian_values(&self, x: &[f64], obj_factor: f64, lambda: &[f64], values: &mut [f64]) {
        let mut k = 0;
        self.eval_instances(x, Part::Hessian, lambda, |_, hv| {
            values[k..k + hv.len()].copy_from_slice(hv);
            k += hv.len();
        });
        if let Objective::Ratio(j, kk) = self.objective {
            let (a, b) = (x[self.c0 + j], x[self.c0 + kk]);
            // φ = a/b: ∂²φ/∂a∂b = −1/b², ∂²φ/∂b² = 2a/b³.
            values[k] = obj_factor * (-1.0 / (b * b));
            values[k + 1] = obj_factor * (2.0 * a / (b * b * b));
        }
    }
}

#[cfg(test)]
mod tests {
    use std::sync::OnceLock;
    use std::sync::atomic::{AtomicUsize, Ordering};

    use super::*;
    use crate::ocp::block::{NodeKernel, NodeKernelX4};
    use crate::ocp::toys;

    /// The implicit brachistochrone on 10 Radau points: 10 collocation instances of one node
    /// function, so two batches of four and a remainder of two.
    fn ocp() -> Ocp {
        toys::brachistochrone(true, Scheme::Radau { elements: 1 }, 10)
    }

    /// The toy's interpreted node function, which the test "kernels" below run.
    fn interpreted() -> &'static GraphFn {
        static F: OnceLock<GraphFn> = OnceLock::new();
        F.get_or_init(|| {
            let ocp = ocp();
            let ph = &ocp.phases[0];
            let mut c = ph.node.collocation();
            GraphFn::new(&mut c.graph, &c.outputs, &c.locals, &ph.node.fixed)
        })
    }

    static BATCHED_CALLS: AtomicUsize = AtomicUsize::new(0);

    fn one(part: Part, l: &[f64], w: &[f64], out: &mut [f64]) {
        let f = interpreted();
        out.copy_from_slice(&match part {
            Part::Value => f.eval(l),
            Part::Jacobian => f.jacobian(l),
            Part::Hessian => f.hessian(l, w),
        });
    }

    fn four(part: Part, l: &[f64], w: &[f64], out: &mut [f64]) {
        BATCHED_CALLS.fetch_add(1, Ordering::Relaxed);
        let f = interpreted();
        let n = f.part_len(part);
        let lane = |v: &[f64], k: usize| v.iter().skip(k).step_by(4).copied().collect::<Vec<_>>();
        for k in 0..4 {
            let mut o = vec![0.0; n];
            one(part, &lane(l, k), &lane(w, k), &mut o);
            for (e, v) in o.into_iter().enumerate() {
                out[4 * e + k] = v;
            }
        }
    }

    /// A kernel table holding the toy's node function with batched variants, whatever the
    /// fingerprint.
    fn lookup(_fingerprint: u128) -> Option<NodeKernel> {
        type Pattern = Vec<(u32, u32)>;
        static PATTERNS: OnceLock<(Pattern, Pattern)> = OnceLock::new();
        let f = interpreted();
        let (jp, hp) = PATTERNS.get_or_init(|| {
            let u = |p: &[(usize, usize)]| p.iter().map(|&(a, b)| (a as u32, b as u32)).collect();
            (u(f.jacobian_pattern()), u(f.hessian_pattern()))
        });
        Some(NodeKernel {
            name: "toy",
            n_out: f.n_out(),
            n_local: f.n_local(),
            n_fixed: 0,
            jacobian_pattern: jp,
            hessian_pattern: hp,
            value: |l, _, w, o| one(Part::Value, l, w, o),
            jacobian: |l, _, w, o| one(Part::Jacobian, l, w, o),
            hessian: |l, _, w, o| one(Part::Hessian, l, w, o),
            x4: Some(NodeKernelX4 {
                value: |l, _, w, o| four(Part::Value, l, w, o),
                jacobian: |l, _, w, o| four(Part::Jacobian, l, w, o),
                hessian: |l, _, w, o| four(Part::Hessian, l, w, o),
            }),
        })
    }

    /// The NLP's constraints, Jacobian and Hessian values with the nodes evaluated in batches of
    /// four (and the remainder one by one) are bitwise those of node-by-node evaluation, at a
    /// point and multipliers that differ from node to node.
    #[test]
    fn batched_node_evaluation_equals_node_by_node() {
        let ocp = ocp();
        let plain = Transcription::new(&ocp).unwrap();
        let batched = Transcription::with_kernels(&ocp, &[], KernelUse::Prefer(lookup)).unwrap();
        assert_eq!(batched.phase_functions()[0].kernel_name(), Some("toy"));
        assert!(plain.phase_functions()[0].kernel_name().is_none());
        let (n, m) = (plain.num_variables(), plain.num_constraints());
        let x: Vec<f64> = (0..n).map(|i| 0.3 + libm::sin(1.7 * i as f64)).collect();
        let lambda: Vec<f64> = (0..m).map(|i| libm::cos(0.9 * i as f64)).collect();
        let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
        let before = BATCHED_CALLS.load(Ordering::Relaxed);
        let (mut g0, mut g1) = (vec![0.0; m], vec![0.0; m]);
        plain.constraints(&x, &mut g0);
        batched.constraints(&x, &mut g1);
        assert_eq!(bits(&g0), bits(&g1));
        let nj = plain.jacobian_structure().len();
        assert_eq!(batched.jacobian_structure(), plain.jacobian_structure());
        let (mut j0, mut j1) = (vec![0.0; nj], vec![0.0; nj]);
        plain.jacobian_values(&x, &mut j0);
        batched.jacobian_values(&x, &mut j1);
        assert_eq!(bits(&j0), bits(&j1));
        let nh = plain.hessian_structure().len();
        let (mut h0, mut h1) = (vec![0.0; nh], vec![0.0; nh]);
        plain.hessian_values(&x, 0.7, &lambda, &mut h0);
        batched.hessian_values(&x, 0.7, &lambda, &mut h1);
        assert_eq!(bits(&h0), bits(&h1));
        // Two batches per evaluation (10 nodes), three evaluations.
        assert_eq!(BATCHED_CALLS.load(Ordering::Relaxed) - before, 6);
        // The values are not all zero (the comparison compares something).
        assert!(h0.iter().any(|&v| v != 0.0) && g0.iter().any(|&v| v != 0.0));
        // With `batch_nodes` off the same kernels run node by node: no batched call, the
        // same values.
        let mut single = batched.clone();
        single.batch_nodes = false;
        let before = BATCHED_CALLS.load(Ordering::Relaxed);
        let (mut g2, mut h2) = (vec![0.0; m], vec![0.0; nh]);
        single.constraints(&x, &mut g2);
        single.hessian_values(&x, 0.7, &lambda, &mut h2);
        assert_eq!(bits(&g0), bits(&g2));
        assert_eq!(bits(&h0), bits(&h2));
        assert_eq!(BATCHED_CALLS.load(Ordering::Relaxed), before);
    }
}
