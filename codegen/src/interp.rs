//! Interpreter: evaluates graph nodes in `f64` or in double-double ([`crate::dd::Dd`]), as a
//! straight-line [`Tape`] of runs of one operation each, without allocation per call
//! ([`Tape::eval_into`]).
//! In `f64` the sine and cosine are the emitted kernels' own ([`crate::trig`]), so an
//! evaluation is bit-identical to the emitted f64 kernels and node kernels.
//!
//! Used by `eval_all` (the CLI `eval` of scene files that are not built in), by the tests
//! that compare emitted kernels with the graph they came from, and for accuracy measurements
//! (f64 kernel vs double-double evaluation of the same graph).

use std::ops::{Add, Div, Mul, Neg, Sub};

use crate::dd::Dd;
use crate::graph::{Graph, Id, Node};

/// Arithmetic the interpreter needs.
pub trait Scalar:
    Copy
    + PartialOrd
    + Add<Output = Self>
    + Sub<Output = Self>
    + Mul<Output = Self>
    + Div<Output = Self>
    + Neg<Output = Self>
{
    /// Exact conversion from `f64`.
    fn from_f64(v: f64) -> Self;
    /// (sin x, cos x).
    fn sin_cos(self) -> (Self, Self);
    /// √x.
    fn sqrt(self) -> Self;
    /// |x|.
    fn abs(self) -> Self;
    /// Nearest `f64`.
    fn to_f64(self) -> f64;
    /// `(sin[i], x[i]) ← (sin x[i], cos x[i])` for every i: the angles are in `x` on entry,
    /// their cosines on return (the tape's batch of joint-angle sines and cosines).
    fn sin_cos_in_place(sin: &mut [Self], x: &mut [Self]) {
        for (s, c) in sin.iter_mut().zip(x.iter_mut()) {
            (*s, *c) = c.sin_cos();
        }
    }
}

impl Scalar for f64 {
    fn from_f64(v: f64) -> Self {
        v
    }
    /// The emitted kernels' one-angle sine and cosine ([`crate::trig::sin_cos`]).
    fn sin_cos(self) -> (Self, Self) {
        crate::trig::sin_cos(self)
    }
    /// Four lanes per [`crate::trig::sin_cos_n`] call, as the emitted kernels batch the joint
    /// angles; every lane's value is that of [`crate::trig::sin_cos`] of its argument alone
    /// (the helper's lanes are independent).
    fn sin_cos_in_place(sin: &mut [Self], x: &mut [Self]) {
        for (s4, c4) in sin.chunks_mut(4).zip(x.chunks_mut(4)) {
            let mut lanes = [0.0; 4];
            lanes[..c4.len()].copy_from_slice(c4);
            let (sv, cv) = crate::trig::sin_cos_n(lanes);
            s4.copy_from_slice(&sv[..s4.len()]);
            c4.copy_from_slice(&cv[..c4.len()]);
        }
    }
    fn sqrt(self) -> Self {
        f64::sqrt(self)
    }
    fn abs(self) -> Self {
        f64::abs(self)
    }
    fn to_f64(self) -> f64 {
        self
    }
}

impl Scalar for Dd {
    fn from_f64(v: f64) -> Self {
        Dd::new(v)
    }
    fn sin_cos(self) -> (Self, Self) {
        Dd::sin_cos(self)
    }
    fn sqrt(self) -> Self {
        Dd::sqrt(self)
    }
    fn abs(self) -> Self {
        Dd::abs(self)
    }
    fn to_f64(self) -> f64 {
        Dd::to_f64(self)
    }
}

/// The operation of a run of tape instructions (every instruction of a run has the same one).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Kind {
    Add,
    Sub,
    Mul,
    Div,
    Neg,
    Sqrt,
    Abs,
    Min,
    Max,
    IfLt,
    Sin,
    Cos,
}

/// Number of kinds (the ready lists of the scheduler).
const KINDS: usize = 12;

impl Kind {
    const ALL: [Kind; KINDS] = [
        Kind::Add,
        Kind::Sub,
        Kind::Mul,
        Kind::Div,
        Kind::Neg,
        Kind::Sqrt,
        Kind::Abs,
        Kind::Min,
        Kind::Max,
        Kind::IfLt,
        Kind::Sin,
        Kind::Cos,
    ];

    /// The kind and children of an operation node (`None` for constants and variables).
    fn of(n: Node) -> Option<(Kind, [Option<Id>; 4])> {
        Some(match n {
            Node::Const(_) | Node::Var(_) => return None,
            Node::Add(a, b) => (Kind::Add, [Some(a), Some(b), None, None]),
            Node::Sub(a, b) => (Kind::Sub, [Some(a), Some(b), None, None]),
            Node::Mul(a, b) => (Kind::Mul, [Some(a), Some(b), None, None]),
            Node::Div(a, b) => (Kind::Div, [Some(a), Some(b), None, None]),
            Node::Min(a, b) => (Kind::Min, [Some(a), Some(b), None, None]),
            Node::Max(a, b) => (Kind::Max, [Some(a), Some(b), None, None]),
            Node::Neg(a) => (Kind::Neg, [Some(a), None, None, None]),
            Node::Sqrt(a) => (Kind::Sqrt, [Some(a), None, None, None]),
            Node::Abs(a) => (Kind::Abs, [Some(a), None, None, None]),
            Node::Sin(a) => (Kind::Sin, [Some(a), None, None, None]),
            Node::Cos(a) => (Kind::Cos, [Some(a), None, None, None]),
            Node::IfLt(a, b, t, f) => (Kind::IfLt, [Some(a), Some(b), Some(t), Some(f)]),
        })
    }

    fn index(self) -> usize {
        self as usize
    }
}

/// A straight-line program for a set of outputs (the cone of the outputs), evaluated without
/// allocation by [`Tape::eval_into`] in a scratch vector the caller keeps.
///
/// Slots of the value vector, in order: the graph variables the cone reads, its constants, the
/// sines and cosines of variables (computed together, four lanes per
/// [`Scalar::sin_cos_in_place`] call in `f64`), then the operations in *runs*: a run is
/// a sequence of operations of one kind whose operands are all computed before the run starts
/// (a list scheduler takes, at each step, every ready operation of the kind with the most
/// ready ones). So the interpreter decides the operation once per run, not once per node,
/// and the operations of a run are independent of each other, which the processor overlaps.
/// Every node is still computed by the same single operation on the same operands, so the
/// values are those of the graph's node-by-node evaluation bit for bit.
#[derive(Debug, Clone)]
pub struct Tape {
    /// Graph variable of each variable slot.
    vars: Vec<u32>,
    /// Value of each constant slot.
    consts: Vec<f64>,
    /// Variable slot of each batched sine–cosine (sines, then cosines, follow the constants).
    angles: Vec<u32>,
    /// (kind, length) of each run.
    runs: Vec<(Kind, u32)>,
    /// Operand slots of the run instructions, in order (two per binary operation, one per
    /// unary, four per `IfLt`).
    args: Vec<u32>,
    /// Slot of each output.
    outputs: Vec<u32>,
    size: usize,
}

impl Tape {
    /// Compile the cone of `outputs`. On an exceeded graph ([`Graph::exceeded`]) every output
    /// is NaN: its expressions are incomplete.
    pub fn new(g: &Graph, outputs: &[Id]) -> Self {
        let poisoned: Vec<Id>;
        let outputs = match g.poison() {
            Some(p) => {
                poisoned = vec![p; outputs.len()];
                &poisoned[..]
            }
            None => outputs,
        };
        let mark = g.cone(outputs);
        let max = outputs.iter().map(|o| o.index() + 1).max().unwrap_or(0);
        const NONE: u32 = u32::MAX;
        let mut slot = vec![NONE; max];
        let (mut vars, mut consts, mut angles) = (Vec::new(), Vec::new(), Vec::new());
        for i in (0..max).filter(|&i| mark[i]) {
            if let Node::Var(k) = g.node(Id(i as u32)) {
                slot[i] = vars.len() as u32;
                vars.push(k);
            }
        }
        for i in (0..max).filter(|&i| mark[i]) {
            if let Node::Const(b) = g.node(Id(i as u32)) {
                slot[i] = (vars.len() + consts.len()) as u32;
                consts.push(f64::from_bits(b));
            }
        }
        // Sines and cosines of variables (the joint angles): one batch.
        let mut angle_of = vec![NONE; max];
        for i in (0..max).filter(|&i| mark[i]) {
            if let Node::Sin(a) | Node::Cos(a) = g.node(Id(i as u32))
                && let Node::Var(_) = g.node(a)
                && angle_of[a.index()] == NONE
            {
                angle_of[a.index()] = angles.len() as u32;
                angles.push(slot[a.index()]);
            }
        }
        let trig = (vars.len() + consts.len()) as u32;
        let na = angles.len() as u32;
        for i in (0..max).filter(|&i| mark[i]) {
            match g.node(Id(i as u32)) {
                Node::Sin(a) if angle_of[a.index()] != NONE => slot[i] = trig + angle_of[a.index()],
                Node::Cos(a) if angle_of[a.index()] != NONE => {
                    slot[i] = trig + na + angle_of[a.index()]
                }
                _ => {}
            }
        }
        // List scheduling of the remaining operations into runs.
        let mut pending = vec![0u32; max];
        let mut parents: Vec<Vec<u32>> = vec![Vec::new(); max];
        let mut ready: [Vec<u32>; KINDS] = Default::default();
        let mut left = 0usize;
        for i in (0..max).filter(|&i| mark[i] && slot[i] == NONE) {
            let Some((kind, children)) = Kind::of(g.node(Id(i as u32))) else {
                continue;
            };
            left += 1;
            for c in children.into_iter().flatten() {
                if slot[c.index()] == NONE {
                    pending[i] += 1;
                    parents[c.index()].push(i as u32);
                }
            }
            if pending[i] == 0 {
                ready[kind.index()].push(i as u32);
            }
        }
        let mut next = trig + 2 * na;
        let (mut runs, mut args) = (Vec::new(), Vec::new());
        while left > 0 {
            let k = (0..KINDS)
                .max_by_key(|&k| (ready[k].len(), std::cmp::Reverse(k)))
                .unwrap_or(0);
            let mut batch = std::mem::take(&mut ready[k]);
            batch.sort_unstable();
            for &i in &batch {
                let (_, children) = Kind::of(g.node(Id(i))).unwrap_or((Kind::Add, [None; 4]));
                args.extend(children.into_iter().flatten().map(|c| slot[c.index()]));
                slot[i as usize] = next;
                next += 1;
            }
            for &i in &batch {
                for &p in &parents[i as usize] {
                    pending[p as usize] -= 1;
                    if pending[p as usize] == 0 {
                        let (kind, _) = Kind::of(g.node(Id(p))).unwrap_or((Kind::Add, [None; 4]));
                        ready[kind.index()].push(p);
                    }
                }
            }
            left -= batch.len();
            runs.push((Kind::ALL[k], batch.len() as u32));
        }
        Tape {
            outputs: outputs.iter().map(|o| slot[o.index()]).collect(),
            size: next as usize,
            vars,
            consts,
            angles,
            runs,
            args,
        }
    }

    /// Number of outputs.
    pub fn n_outputs(&self) -> usize {
        self.outputs.len()
    }

    /// Computes every slot into `v` (resized to the tape's size: allocates only when a larger
    /// tape than before uses it).
    fn run<S: Scalar>(&self, vars: &[S], v: &mut Vec<S>) {
        let zero = S::from_f64(0.0);
        if v.len() < self.size {
            v.resize(self.size, zero);
        }
        let (nv, nc, na) = (self.vars.len(), self.consts.len(), self.angles.len());
        for (x, &k) in v.iter_mut().zip(&self.vars) {
            *x = vars.get(k as usize).copied().unwrap_or(zero);
        }
        for (x, &c) in v[nv..].iter_mut().zip(&self.consts) {
            *x = S::from_f64(c);
        }
        if na > 0 {
            let (head, tail) = v.split_at_mut(nv + nc);
            let (sin, tail) = tail.split_at_mut(na);
            let cos = &mut tail[..na];
            for (c, &a) in cos.iter_mut().zip(&self.angles) {
                *c = head[a as usize];
            }
            S::sin_cos_in_place(sin, cos);
        }
        let mut dst = nv + nc + 2 * na;
        let mut p = 0;
        for &(kind, len) in &self.runs {
            let len = len as usize;
            let (done, rest) = v.split_at_mut(dst);
            let out = &mut rest[..len];
            // One loop per kind over the run's operands, `f` applied to each operation's.
            macro_rules! each {
                ($arity:literal, $f:expr) => {{
                    let args = &self.args[p..p + $arity * len];
                    for (o, a) in out.iter_mut().zip(args.chunks_exact($arity)) {
                        *o = $f(a);
                    }
                    p += $arity * len;
                }};
            }
            let d = |i: u32| done[i as usize];
            match kind {
                Kind::Add => each!(2, |a: &[u32]| d(a[0]) + d(a[1])),
                Kind::Sub => each!(2, |a: &[u32]| d(a[0]) - d(a[1])),
                Kind::Mul => each!(2, |a: &[u32]| d(a[0]) * d(a[1])),
                Kind::Div => each!(2, |a: &[u32]| d(a[0]) / d(a[1])),
                Kind::Min => each!(2, |a: &[u32]| {
                    let (x, y) = (d(a[0]), d(a[1]));
                    if y < x { y } else { x }
                }),
                Kind::Max => each!(2, |a: &[u32]| {
                    let (x, y) = (d(a[0]), d(a[1]));
                    if y > x { y } else { x }
                }),
                Kind::IfLt => each!(4, |a: &[u32]| if d(a[0]) < d(a[1]) {
                    d(a[2])
                } else {
                    d(a[3])
                }),
                Kind::Neg => each!(1, |a: &[u32]| -d(a[0])),
                Kind::Sqrt => each!(1, |a: &[u32]| d(a[0]).sqrt()),
                Kind::Abs => each!(1, |a: &[u32]| d(a[0]).abs()),
                Kind::Sin => each!(1, |a: &[u32]| d(a[0]).sin_cos().0),
                Kind::Cos => each!(1, |a: &[u32]| d(a[0]).sin_cos().1),
            }
            dst += len;
        }
    }

    /// Evaluates the outputs for the input variables `vars` (layout of
    /// [`crate::robot::Layout`]; variables beyond `vars.len()` read as 0) into `out`, using
    /// `scratch` for the values: no allocation once `scratch` has grown to the largest tape it
    /// serves.
    ///
    /// # Panics
    /// If `out.len()` is not [`Tape::n_outputs`] (a programming error).
    pub fn eval_into<S: Scalar>(&self, vars: &[S], scratch: &mut Vec<S>, out: &mut [S]) {
        assert_eq!(out.len(), self.outputs.len(), "output length");
        self.run(vars, scratch);
        for (o, &s) in out.iter_mut().zip(&self.outputs) {
            *o = scratch[s as usize];
        }
    }

    /// Evaluate the outputs for the input variables `vars` (layout of [`crate::robot::Layout`]).
    /// Variables beyond `vars.len()` read as 0. Allocates; [`Tape::eval_into`] does not.
    pub fn eval<S: Scalar>(&self, vars: &[S]) -> Vec<S> {
        let mut v = Vec::new();
        self.run(vars, &mut v);
        self.outputs.iter().map(|&s| v[s as usize]).collect()
    }
}

/// Evaluate `outputs` once (compiles a [`Tape`]).
pub fn eval<S: Scalar>(g: &Graph, outputs: &[Id], vars: &[S]) -> Vec<S> {
    Tape::new(g, outputs).eval(vars)
}

/// One output array of a kernel in the layout of the emitted `eval_flat`: name and dimensions
/// (empty for a scalar). A `Contact` output contributes one entry per field.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct OutputShape {
    /// Output argument (or `Contact` field) name.
    pub name: String,
    /// Dimensions, outermost first.
    pub dims: Vec<usize>,
}

impl OutputShape {
    /// Number of elements.
    pub fn len(&self) -> usize {
        self.dims.iter().product()
    }

    /// Whether the output has no elements.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }
}

/// A kernel of a scene evaluated at run time: its definition's shape and a compiled tape.
#[derive(Debug, Clone)]
pub struct RuntimeKernel {
    /// Kernel name (as emitted).
    pub name: String,
    /// Input arguments, in emitted order.
    pub inputs: Vec<crate::kernels::Arg>,
    /// Outputs in `eval_flat` order.
    pub outputs: Vec<OutputShape>,
    tape: Tape,
}

impl RuntimeKernel {
    /// Evaluates the kernel; `vars` from [`SceneKernels::vars`]. Outputs flattened as the
    /// emitted `eval_flat_u` returns them.
    pub fn eval(&self, vars: &[f64]) -> Vec<f64> {
        self.tape.eval(vars)
    }

    /// As [`RuntimeKernel::eval`] without allocation: the outputs go to `out` (its length is
    /// the sum of the outputs' lengths), the values to `scratch`, which the caller keeps
    /// between calls.
    ///
    /// # Panics
    /// If `out` has the wrong length (a programming error).
    pub fn eval_into(&self, vars: &[f64], scratch: &mut Vec<f64>, out: &mut [f64]) {
        assert_eq!(out.len(), self.tape.n_outputs(), "output length");
        self.tape.eval_into(vars, scratch, out);
    }
}

/// Every kernel a scene's module holds (its `kernels` list plus
/// [`crate::kernels::ROBOT_KERNELS`]), interpreted: the run-time counterpart of the compiled
/// module, with the same f64 operations (sine and cosine of [`crate::trig`]).
#[derive(Debug, Clone)]
pub struct SceneKernels {
    /// Input layout of the scene's graph.
    pub layout: crate::robot::Layout,
    /// Runtime parameters (name, default value).
    pub params: Vec<(String, f64)>,
    /// The kernels, in emission order.
    pub kernels: Vec<RuntimeKernel>,
}

impl SceneKernels {
    /// Builds the graphs of every kernel of `scene` and compiles their tapes.
    pub fn new(scene: &crate::Scene) -> Result<Self, crate::CodegenError> {
        use crate::kernels::{CONTACT_FIELDS, Dim, OutKind};
        let full = crate::kernels::with_robot_kernels(scene);
        let mut model = crate::SymbolicRobot::new(&full)?;
        let nq = model.nq();
        let dim = |d: &Dim| match d {
            Dim::Nq => nq,
            Dim::Lit(n) => *n,
        };
        let mut kernels = Vec::new();
        for k in &full.kernels {
            let def = crate::kernels::build_kernel(&mut model, k)?;
            let mut outputs = Vec::new();
            for o in &def.outputs {
                match &o.kind {
                    OutKind::Scalar => outputs.push(OutputShape {
                        name: o.name.clone(),
                        dims: Vec::new(),
                    }),
                    OutKind::Array(dims) => outputs.push(OutputShape {
                        name: o.name.clone(),
                        dims: dims.iter().map(dim).collect(),
                    }),
                    OutKind::Contact => {
                        for (f, dims, _) in CONTACT_FIELDS {
                            outputs.push(OutputShape {
                                name: f.to_string(),
                                dims: dims.iter().map(dim).collect(),
                            });
                        }
                    }
                }
            }
            let ids: Vec<Id> = def.outputs.iter().flat_map(|o| o.ids.clone()).collect();
            kernels.push(RuntimeKernel {
                name: def.name.clone(),
                inputs: def.inputs.clone(),
                outputs,
                tape: Tape::new(&model.g, &ids),
            });
        }
        Ok(SceneKernels {
            layout: model.layout,
            params: model.params.clone(),
            kernels,
        })
    }

    /// The variable vector of one state: `u` is q̈ for the kernels that take `qdd` and τ for
    /// those that take `tau`; `p` the runtime parameters (their defaults if `None`).
    ///
    /// # Panics
    /// If a slice has the wrong length (a programming error; the CLI checks user input).
    pub fn vars(
        &self,
        q: &[f64],
        qd: &[f64],
        omega: [f64; 3],
        eps: f64,
        u: &[f64],
        p: Option<&[f64]>,
    ) -> Vec<f64> {
        let l = self.layout;
        let n = l.nq;
        assert!(
            q.len() == n && qd.len() == n && u.len() == n,
            "state length"
        );
        let mut v = vec![0.0; l.n_vars_all()];
        v[..n].copy_from_slice(q);
        v[n..2 * n].copy_from_slice(qd);
        v[2 * n..2 * n + 3].copy_from_slice(&omega);
        v[l.eps() as usize] = eps;
        for (i, d) in self.params.iter().enumerate() {
            v[l.param(i) as usize] = p.map_or(d.1, |p| p[i]);
        }
        for (i, x) in u.iter().enumerate() {
            v[l.qdd(i) as usize] = *x;
            v[l.tau(i) as usize] = *x;
        }
        v
    }
}
