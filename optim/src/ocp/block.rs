//! Compiled graph functions with exact first and second derivatives.
//!
//! The derivative graphs come from [`bf_codegen::nodefn::Derivatives`]. The caller may hand in
//! a table of kernels emitted at build time ([`KernelUse`], a [`KernelLookup`] by structural
//! fingerprint, [`bf_codegen::nodefn::fingerprint`]); when it holds one emitted from graphs
//! with the same fingerprint, a [`GraphFn`] calls those flat Rust functions, otherwise it
//! interprets the graphs with the programs below. Both compute every node with the same `f64`
//! operation, so they agree bitwise. With [`KernelUse::Require`] the caller states that the
//! kernels must be found: a graph that changed after the kernels were emitted is then an error
//! of the transcription instead of a silent fall-back to the (slower) interpreter. A kernel
//! may come with batched variants ([`NodeKernelX4`]) that evaluate four nodes per call
//! ([`GraphFn::eval_x4`]), bitwise as four calls of the scalar kernel.
//!
//! A [`GraphFn`] takes outputs y = f(v) built on a `bf_codegen` expression graph (the paper's
//! node functions: dynamics eq. 26/29, stick constraint eq. 14/27, validity h and σ eq. 4/18,
//! cost integrands eq. 61–65, impact law eq. 40) and compiles, once, three interpreter tapes:
//! the values, the sparse Jacobian ∂y_i/∂v_j (forward mode, one sweep per local variable) and
//! the lower triangle of the Hessian of the weighted sum Σ_i w_i y_i (forward over reverse,
//! with the weights w as extra graph inputs). Structural zeros are dropped, so the patterns
//! are exactly the graph's dependencies. No finite differences are involved.
//!
//! The tapes are `Program`s: the cone of the outputs renumbered into dense slots, with the
//! constants pre-stored and the graph variables resolved at compile time to a local variable, a
//! weight or a constant, and the operations grouped into runs of one kind (level scheduling).
//! One evaluation is one pass over the runs on a buffer the size of the cone (not of the whole
//! graph, as `bf_codegen::interp::Tape` allocates), computing every node with the same `f64`
//! operation as `Tape`, so the values are bitwise those of the reference interpreter (tested).

use bf_codegen::graph::{Graph, Id, Node};
use bf_codegen::nodefn::{Derivatives, VarRole, fingerprint, var_roles};
use bf_codegen::trig::sin_cos;

/// One kernel function of an emitted node function: `f(local, fixed, w, out)` writes the
/// outputs (value), the Jacobian values (pattern order) or the lower-triangle Hessian values of
/// Σ w_i y_i (pattern order) into `out`; `w` is read by the Hessian only.
pub type NodeKernelFn = fn(local: &[f64], fixed: &[f64], w: &[f64], out: &mut [f64]);

/// The emitted kernels of one node function, as a [`KernelLookup`] hands them over (the
/// fields of a build-time kernel table such as bf-generated's, which this crate does not
/// depend on).
#[derive(Debug, Clone, Copy)]
pub struct NodeKernel {
    /// Kernel name.
    pub name: &'static str,
    /// Number of outputs.
    pub n_out: usize,
    /// Number of local variables.
    pub n_local: usize,
    /// Number of fixed inputs, in the node function's order.
    pub n_fixed: usize,
    /// Jacobian pattern (output, local).
    pub jacobian_pattern: &'static [(u32, u32)],
    /// Lower-triangle Hessian pattern (local i ≥ local j).
    pub hessian_pattern: &'static [(u32, u32)],
    /// Output values.
    pub value: NodeKernelFn,
    /// Jacobian values.
    pub jacobian: NodeKernelFn,
    /// Weighted Hessian values.
    pub hessian: NodeKernelFn,
    /// The same kernels on four nodes per call, if emitted.
    pub x4: Option<NodeKernelX4>,
}

/// The batched variants of a [`NodeKernel`]: each call evaluates four nodes, with `local`, `w`
/// and `out` holding the four nodes' entries interleaved (node `l`'s entry `k` at `4·k + l`)
/// and `fixed` shared; every node's results are bitwise those of the scalar kernel.
#[derive(Debug, Clone, Copy)]
pub struct NodeKernelX4 {
    /// Output values.
    pub value: NodeKernelFn,
    /// Jacobian values.
    pub jacobian: NodeKernelFn,
    /// Weighted Hessian values.
    pub hessian: NodeKernelFn,
}

/// Which evaluation of a [`GraphFn`] a batched call makes ([`GraphFn::eval_x4`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Part {
    /// Output values ([`GraphFn::eval`]).
    Value,
    /// Jacobian values ([`GraphFn::jacobian`]).
    Jacobian,
    /// Weighted Hessian values ([`GraphFn::hessian`]).
    Hessian,
}

/// The emitted node kernel with a structural fingerprint
/// ([`bf_codegen::nodefn::fingerprint`]), if any.
pub type KernelLookup = fn(fingerprint: u128) -> Option<NodeKernel>;

/// Kind of a `Program` operation (also its position in the run order within a level).
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord)]
enum Kind {
    Local,
    Weight,
    Add,
    Sub,
    Mul,
    Div,
    Neg,
    Sin,
    Cos,
    Sqrt,
    Abs,
    Min,
    Max,
    IfLt,
}

/// A compiled straight-line evaluation of graph outputs.
///
/// Slots `0..init.len()` hold constants (including graph variables fixed at compile time); the
/// operation `k` writes slot `init.len() + k`. The operations are scheduled by level in the
/// dependency graph (a node after all its operands) and, within a level, grouped by kind, so
/// that evaluation is a sequence of runs of one kind: the interpreter dispatches once per run
/// instead of once per node (an indirect jump per node mispredicts on every change of kind and
/// cost most of the evaluation time). Every node is still computed by the same `f64`
/// operation on the same operand values, so the results are bitwise those of the node order.
#[derive(Debug, Clone)]
struct Program {
    init: Vec<f64>,
    /// Operand slots (unused ones 0); for `Local`/`Weight` the first is the input index.
    args: Vec<[u32; 4]>,
    /// `(kind, first op, end op)`.
    runs: Vec<(Kind, u32, u32)>,
    outputs: Vec<u32>,
}

impl Program {
    /// Compiles the cone of `outputs`. `var_kind(v)` says what graph variable `v` is: a local
    /// variable, a weight, or a constant value.
    fn new(g: &Graph, outputs: &[Id], var_kind: &dyn Fn(u32) -> VarKind) -> Self {
        let mark = g.cone(outputs);
        let size = outputs.iter().map(|o| o.index() + 1).max().unwrap_or(0);
        // Slot of each graph node: constants get their final slot now; operations get
        // `u32::MAX` until scheduled.
        let mut slot = vec![u32::MAX; size];
        let mut init = Vec::new();
        for i in 0..size {
            if !mark[i] {
                continue;
            }
            let c = match g.node(Id(i as u32)) {
                Node::Const(b) => Some(f64::from_bits(b)),
                Node::Var(v) => match var_kind(v) {
                    VarKind::Const(x) => Some(x),
                    _ => None,
                },
                _ => None,
            };
            if let Some(c) = c {
                slot[i] = init.len() as u32;
                init.push(c);
            }
        }
        // Operations in node order with graph-node operands (for `Local`/`Weight` the input
        // index), and their levels.
        let mut level = vec![0u32; size];
        let mut ops: Vec<(u32, Kind, usize, [usize; 4])> = Vec::new();
        for i in 0..size {
            if !mark[i] || slot[i] != u32::MAX {
                continue;
            }
            let (kind, args, n_args) = match g.node(Id(i as u32)) {
                Node::Var(v) => match var_kind(v) {
                    VarKind::Local(l) => (Kind::Local, [l as usize, 0, 0, 0], 0),
                    VarKind::Weight(w) => (Kind::Weight, [w as usize, 0, 0, 0], 0),
                    VarKind::Const(_) => unreachable!("constants have slots"),
                },
                Node::Const(_) => unreachable!("constants have slots"),
                Node::Add(a, b) => (Kind::Add, [a.index(), b.index(), 0, 0], 2),
                Node::Sub(a, b) => (Kind::Sub, [a.index(), b.index(), 0, 0], 2),
                Node::Mul(a, b) => (Kind::Mul, [a.index(), b.index(), 0, 0], 2),
                Node::Div(a, b) => (Kind::Div, [a.index(), b.index(), 0, 0], 2),
                Node::Neg(a) => (Kind::Neg, [a.index(), 0, 0, 0], 1),
                Node::Sin(a) => (Kind::Sin, [a.index(), 0, 0, 0], 1),
                Node::Cos(a) => (Kind::Cos, [a.index(), 0, 0, 0], 1),
                Node::Sqrt(a) => (Kind::Sqrt, [a.index(), 0, 0, 0], 1),
                Node::Abs(a) => (Kind::Abs, [a.index(), 0, 0, 0], 1),
                Node::Min(a, b) => (Kind::Min, [a.index(), b.index(), 0, 0], 2),
                Node::Max(a, b) => (Kind::Max, [a.index(), b.index(), 0, 0], 2),
                Node::IfLt(a, b, t, f) => {
                    (Kind::IfLt, [a.index(), b.index(), t.index(), f.index()], 4)
                }
            };
            let lv = args[..n_args]
                .iter()
                .map(|&a| level[a] + 1)
                .max()
                .unwrap_or(0);
            level[i] = lv;
            ops.push((lv, kind, i, args));
        }
        // Schedule: by level, then kind, then node order (stable and deterministic).
        ops.sort_by_key(|&(lv, kind, i, _)| (lv, kind, i));
        let base = init.len() as u32;
        for (k, &(_, _, i, _)) in ops.iter().enumerate() {
            slot[i] = base + k as u32;
        }
        let mut args = Vec::with_capacity(ops.len());
        let mut runs: Vec<(Kind, u32, u32)> = Vec::new();
        for (k, &(_, kind, _, a)) in ops.iter().enumerate() {
            let resolved = match kind {
                Kind::Local | Kind::Weight => [a[0] as u32, 0, 0, 0],
                Kind::IfLt => [slot[a[0]], slot[a[1]], slot[a[2]], slot[a[3]]],
                Kind::Add | Kind::Sub | Kind::Mul | Kind::Div | Kind::Min | Kind::Max => {
                    [slot[a[0]], slot[a[1]], 0, 0]
                }
                _ => [slot[a[0]], 0, 0, 0],
            };
            args.push(resolved);
            match runs.last_mut() {
                Some(r) if r.0 == kind => r.2 = k as u32 + 1,
                _ => runs.push((kind, k as u32, k as u32 + 1)),
            }
        }
        let outputs = outputs.iter().map(|o| slot[o.index()]).collect();
        Program {
            init,
            args,
            runs,
            outputs,
        }
    }

    /// Evaluates the outputs into `out` (one allocation: the slot buffer).
    fn eval_into(&self, local: &[f64], weights: &[f64], out: &mut Vec<f64>) {
        let base = self.init.len();
        let mut v = vec![0.0; base + self.args.len()];
        v[..base].copy_from_slice(&self.init);
        for &(kind, s, e) in &self.runs {
            let (s, e) = (s as usize, e as usize);
            let args = &self.args[s..e];
            // Operands lie in earlier runs or, when a run spans two levels, earlier in the same
            // run; either way they are written before they are read.
            macro_rules! run {
                (|$a:ident| $f:expr) => {
                    for (k, arg) in args.iter().enumerate() {
                        let x = {
                            let $a = |j: usize| v[arg[j] as usize];
                            $f
                        };
                        v[base + s + k] = x;
                    }
                };
            }
            match kind {
                Kind::Local => {
                    for (d, arg) in v[base + s..base + e].iter_mut().zip(args) {
                        *d = local.get(arg[0] as usize).copied().unwrap_or(0.0);
                    }
                }
                Kind::Weight => {
                    for (d, arg) in v[base + s..base + e].iter_mut().zip(args) {
                        *d = weights.get(arg[0] as usize).copied().unwrap_or(0.0);
                    }
                }
                Kind::Add => run!(|a| a(0) + a(1)),
                Kind::Sub => run!(|a| a(0) - a(1)),
                Kind::Mul => run!(|a| a(0) * a(1)),
                Kind::Div => run!(|a| a(0) / a(1)),
                Kind::Neg => run!(|a| -a(0)),
                Kind::Sin => run!(|a| sin_cos(a(0)).0),
                Kind::Cos => run!(|a| sin_cos(a(0)).1),
                Kind::Sqrt => run!(|a| a(0).sqrt()),
                Kind::Abs => run!(|a| a(0).abs()),
                Kind::Min => run!(|a| {
                    let (x, y) = (a(0), a(1));
                    if y < x { y } else { x }
                }),
                Kind::Max => run!(|a| {
                    let (x, y) = (a(0), a(1));
                    if y > x { y } else { x }
                }),
                Kind::IfLt => run!(|a| if a(0) < a(1) { a(2) } else { a(3) }),
            }
        }
        out.clear();
        out.extend(self.outputs.iter().map(|&k| v[k as usize]));
    }

    fn eval(&self, local: &[f64], weights: &[f64]) -> Vec<f64> {
        let mut out = Vec::with_capacity(self.outputs.len());
        self.eval_into(local, weights, &mut out);
        out
    }
}

/// What a graph variable is to a [`Program`].
#[derive(Debug, Clone, Copy)]
enum VarKind {
    Local(u32),
    Weight(u32),
    Const(f64),
}

/// The compiled programs of a graph function's values, Jacobian and Hessian.
#[derive(Debug, Clone)]
struct Programs {
    value: Program,
    jac: Program,
    hess: Program,
}

/// How a [`GraphFn`] evaluates.
#[derive(Debug, Clone)]
enum Backend {
    /// Compiled programs of the graphs (any graph).
    Programs(Box<Programs>),
    /// The kernels emitted from the same graphs at build time, with the values of the fixed
    /// inputs.
    Kernel { kernel: NodeKernel, fixed: Vec<f64> },
}

/// Whether a [`GraphFn`] (or a transcription's node functions) may or must run on emitted
/// kernels.
#[derive(Debug, Clone, Copy, Default)]
pub enum KernelUse {
    /// Always interpret the graphs.
    #[default]
    Never,
    /// Use the kernel of the lookup when one has the graphs' fingerprint, else interpret.
    Prefer(KernelLookup),
    /// As `Prefer`, but the transcription fails for a phase node function without an emitted
    /// kernel ([`crate::ocp::Transcription::with_kernels`]).
    Require(KernelLookup),
}

impl KernelUse {
    /// The lookup, if kernels may be used.
    pub fn lookup(self) -> Option<KernelLookup> {
        match self {
            KernelUse::Never => None,
            KernelUse::Prefer(f) | KernelUse::Require(f) => Some(f),
        }
    }
}

/// A vector function of `n_local` local variables with exact sparse derivatives.
#[derive(Debug, Clone)]
pub struct GraphFn {
    n_out: usize,
    n_local: usize,
    jac: Vec<(usize, usize)>,
    hess: Vec<(usize, usize)>,
    backend: Backend,
}

impl GraphFn {
    /// Compiles `outputs` of graph `g` as a function of the graph variables `local_vars` (in
    /// that order); `fixed` gives the values of other graph variables (ε, runtime parameters,
    /// cost constants); any other variable reads as 0. Interprets the graphs
    /// ([`KernelUse::Never`]).
    pub fn new(g: &mut Graph, outputs: &[Id], local_vars: &[u32], fixed: &[(u32, f64)]) -> Self {
        Self::with_backend(g, outputs, local_vars, fixed, KernelUse::Never)
    }

    /// [`GraphFn::new`] with the choice of backend: with a lookup, the emitted kernel with the
    /// graphs' fingerprint when there is one.
    pub fn with_backend(
        g: &mut Graph,
        outputs: &[Id],
        local_vars: &[u32],
        fixed: &[(u32, f64)],
        kernels: KernelUse,
    ) -> Self {
        let n_out = outputs.len();
        let d = Derivatives::new(g, outputs, local_vars, fixed);
        let roles = var_roles(local_vars, fixed, d.weight_base, n_out);
        let kernel = match kernels.lookup() {
            Some(lookup) => {
                let fp = fingerprint(g, outputs, &d, &roles);
                lookup(fp).filter(|k| {
                    // The fingerprint covers all of this; checked again so that a collision
                    // cannot go unnoticed.
                    k.n_out == n_out
                        && k.n_local == local_vars.len()
                        && k.n_fixed == fixed.len()
                        && k.jacobian_pattern.len() == d.jac.len()
                        && k.hessian_pattern.len() == d.hess.len()
                        && k.jacobian_pattern
                            .iter()
                            .zip(&d.jac)
                            .all(|(a, b)| (a.0 as usize, a.1 as usize) == *b)
                        && k.hessian_pattern
                            .iter()
                            .zip(&d.hess)
                            .all(|(a, b)| (a.0 as usize, a.1 as usize) == *b)
                })
            }
            None => None,
        };
        let backend = match kernel {
            Some(kernel) => Backend::Kernel {
                kernel,
                fixed: fixed.iter().map(|f| f.1).collect(),
            },
            None => {
                let var_kind = |v: u32| match roles.get(v as usize) {
                    Some(VarRole::Local(l)) => VarKind::Local(*l),
                    Some(VarRole::Weight(w)) => VarKind::Weight(*w),
                    Some(VarRole::Fixed(_, x)) => VarKind::Const(*x),
                    Some(VarRole::Zero) | None => VarKind::Const(0.0),
                };
                Backend::Programs(Box::new(Programs {
                    value: Program::new(g, outputs, &var_kind),
                    jac: Program::new(g, &d.jac_ids, &var_kind),
                    hess: Program::new(g, &d.hess_ids, &var_kind),
                }))
            }
        };
        GraphFn {
            n_out,
            n_local: local_vars.len(),
            jac: d.jac,
            hess: d.hess,
            backend,
        }
    }

    /// The emitted kernel's name when this function runs on one (`None`: interpreted).
    pub fn kernel_name(&self) -> Option<&'static str> {
        match &self.backend {
            Backend::Kernel { kernel, .. } => Some(kernel.name),
            Backend::Programs(_) => None,
        }
    }

    /// Number of outputs.
    pub fn n_out(&self) -> usize {
        self.n_out
    }

    /// Number of local variables.
    pub fn n_local(&self) -> usize {
        self.n_local
    }

    /// Jacobian pattern: (output, local variable) pairs, in the order of [`GraphFn::jacobian`].
    pub fn jacobian_pattern(&self) -> &[(usize, usize)] {
        &self.jac
    }

    /// Lower-triangle Hessian pattern (local i ≥ local j), in the order of [`GraphFn::hessian`].
    pub fn hessian_pattern(&self) -> &[(usize, usize)] {
        &self.hess
    }

    /// Runs kernel function `f` with `local` and `w` padded with zeros to their full lengths.
    fn run_kernel(
        &self,
        f: NodeKernelFn,
        fixed: &[f64],
        local: &[f64],
        w: &[f64],
        n: usize,
    ) -> Vec<f64> {
        let pad = |v: &[f64], len: usize| -> Option<Vec<f64>> {
            (v.len() < len).then(|| {
                let mut p = v.to_vec();
                p.resize(len, 0.0);
                p
            })
        };
        let lp = pad(local, self.n_local);
        let wp = pad(w, self.n_out);
        let mut out = vec![0.0; n];
        f(
            lp.as_deref().unwrap_or(local),
            fixed,
            wp.as_deref().unwrap_or(w),
            &mut out,
        );
        out
    }

    /// Output values at `local` (missing trailing locals read as 0).
    pub fn eval(&self, local: &[f64]) -> Vec<f64> {
        match &self.backend {
            Backend::Programs(p) => p.value.eval(local, &[]),
            Backend::Kernel { kernel, fixed } => {
                self.run_kernel(kernel.value, fixed, local, &[], self.n_out)
            }
        }
    }

    /// Jacobian values at `local` (pattern order).
    pub fn jacobian(&self, local: &[f64]) -> Vec<f64> {
        match &self.backend {
            Backend::Programs(p) => p.jac.eval(local, &[]),
            Backend::Kernel { kernel, fixed } => {
                self.run_kernel(kernel.jacobian, fixed, local, &[], self.jac.len())
            }
        }
    }

    /// Whether [`GraphFn::eval_x4`] evaluates four points per call (an emitted kernel with
    /// batched variants).
    pub fn has_x4(&self) -> bool {
        matches!(&self.backend, Backend::Kernel { kernel, .. } if kernel.x4.is_some())
    }

    /// Number of values `part` yields per point.
    pub fn part_len(&self, part: Part) -> usize {
        match part {
            Part::Value => self.n_out,
            Part::Jacobian => self.jac.len(),
            Part::Hessian => self.hess.len(),
        }
    }

    /// Evaluates `part` at four points at once on the batched kernels: `local` holds the four
    /// points' locals interleaved (point `l`'s local `k` at `4·k + l`; 4 × `n_local`), `w`
    /// their weights likewise (4 × `n_out`, read for [`Part::Hessian`] only), and `out`
    /// receives 4 × [`GraphFn::part_len`] values, interleaved likewise, each bitwise what the
    /// one-point method gives for that point. Returns `false`,
    /// leaving `out` untouched, when there is no batched kernel ([`GraphFn::has_x4`]) or a
    /// length differs from those.
    pub fn eval_x4(&self, part: Part, local: &[f64], w: &[f64], out: &mut [f64]) -> bool {
        let Backend::Kernel {
            kernel: NodeKernel { x4: Some(k4), .. },
            fixed,
        } = &self.backend
        else {
            return false;
        };
        let n = self.part_len(part);
        let w_ok = part != Part::Hessian || w.len() == 4 * self.n_out;
        if local.len() != 4 * self.n_local || !w_ok || out.len() != 4 * n {
            return false;
        }
        let f = match part {
            Part::Value => k4.value,
            Part::Jacobian => k4.jacobian,
            Part::Hessian => k4.hessian,
        };
        f(local, fixed, w, out);
        true
    }

    /// Values of the lower triangle of ∇²(Σ_i w_i y_i) at `local` (pattern order; missing
    /// trailing weights read as 0).
    pub fn hessian(&self, local: &[f64], weights: &[f64]) -> Vec<f64> {
        match &self.backend {
            Backend::Programs(p) => p.hess.eval(local, weights),
            Backend::Kernel { kernel, fixed } => {
                self.run_kernel(kernel.hessian, fixed, local, weights, self.hess.len())
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use bf_codegen::diff;
    use bf_codegen::interp::Tape;

    /// The compiled programs agree bitwise with bf-codegen's reference interpreter on a graph
    /// that uses every node kind, with fixed variables, a variable that is neither local nor
    /// fixed (reads 0), both branches of min/max/if_lt, and the weighted Hessian.
    #[test]
    fn programs_match_reference_interpreter_bitwise() {
        let mut g = Graph::new();
        let (x0, x1, x2) = (g.var(0), g.var(1), g.var(2));
        let (c, unset) = (g.var(7), g.var(4));
        let s = g.sin(x0);
        let co = g.cos(x1);
        let p = g.mul(s, co);
        let q = g.div(p, c);
        let sq = g.square(x2);
        let r0 = g.add(sq, c);
        let r = g.sqrt(r0);
        let d = g.sub(x0, x2);
        let a = g.abs(d);
        let mn = g.min(x0, x1);
        let mx = g.max(x1, x2);
        let m = g.mul(mn, mx);
        let t0 = g.mul(x0, x1);
        let ng = g.neg(x2);
        let ifl = g.if_lt(x0, x1, t0, ng);
        let u = g.add(unset, x1);
        let y0 = g.add(q, r);
        let y1 = g.mul(a, m);
        let y2 = g.add(ifl, u);
        let y3 = g.constant(2.5);
        let outs = [y0, y1, y2, y3];
        let locals = [0u32, 1, 2];
        let fixed = [(7u32, 1.75)];
        let f = GraphFn::new(&mut g, &outs, &locals, &fixed);
        let weights = [0.3, -1.2, 0.7, 2.0];
        // Reference: the interpreter on the full input vector (weights at 8.., see `new`).
        let hess_ids: Vec<Id> = {
            let weighted: Vec<(Id, Id)> = outs
                .iter()
                .enumerate()
                .map(|(i, &o)| (o, g.var(8 + i as u32)))
                .collect();
            let h = diff::hessian(&mut g, &weighted, &locals);
            f.hessian_pattern().iter().map(|&(i, j)| h[i][j]).collect()
        };
        let jac_ids: Vec<Id> = f
            .jacobian_pattern()
            .iter()
            .map(|&(o, l)| diff::partial(&mut g, &outs, locals[l])[o])
            .collect();
        for pt in [[0.3, 0.9, -0.4], [1.1, -0.2, 0.8], [-0.5, -0.5, 2.0]] {
            let mut inp = vec![0.0; 12];
            inp[..3].copy_from_slice(&pt);
            inp[7] = 1.75;
            inp[8..12].copy_from_slice(&weights);
            let bits = |v: Vec<f64>| v.into_iter().map(f64::to_bits).collect::<Vec<_>>();
            assert_eq!(bits(f.eval(&pt)), bits(Tape::new(&g, &outs).eval(&inp)));
            assert_eq!(
                bits(f.jacobian(&pt)),
                bits(Tape::new(&g, &jac_ids).eval(&inp))
            );
            assert_eq!(
                bits(f.hessian(&pt, &weights)),
                bits(Tape::new(&g, &hess_ids).eval(&inp))
            );
        }
    }

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
        assert!(
            (v[0] - (a * a * libm::sin(b) + 2.0)).abs() < 1e-15 && (v[1] - a * b).abs() < 1e-15
        );
        let jv = f.jacobian(&[a, b]);
        for (k, &(o, l)) in f.jacobian_pattern().iter().enumerate() {
            let exact = match (o, l) {
                (0, 0) => 2.0 * a * libm::sin(b),
                (0, 1) => a * a * libm::cos(b),
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
                (0, 0) => w0 * 2.0 * libm::sin(b),
                (1, 0) => w0 * 2.0 * a * libm::cos(b) + w1,
                (1, 1) => -w0 * a * a * libm::sin(b),
                _ => unreachable!(),
            };
            assert!((hv[k] - exact).abs() < 1e-14);
        }
    }
}
