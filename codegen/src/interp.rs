//! Interpreter: evaluates graph nodes in `f64` or in double-double ([`crate::dd::Dd`]).
//! [`KernelF64`] is `f64` with the emitted kernels' sine and cosine ([`crate::trig`]), so an
//! evaluation in it is bit-identical to the emitted f64 kernels; plain `f64` uses the standard
//! library's, as the emitted optimal-control node kernels do.
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
}

impl Scalar for f64 {
    fn from_f64(v: f64) -> Self {
        v
    }
    fn sin_cos(self) -> (Self, Self) {
        f64::sin_cos(self)
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

/// `f64` whose sine and cosine are those of the emitted kernels ([`crate::trig::sin_cos_n`]);
/// all other operations are plain `f64` operations.
#[derive(Debug, Clone, Copy, PartialEq, PartialOrd, Default)]
pub struct KernelF64(pub f64);

impl Add for KernelF64 {
    type Output = Self;
    fn add(self, y: Self) -> Self {
        KernelF64(self.0 + y.0)
    }
}

impl Sub for KernelF64 {
    type Output = Self;
    fn sub(self, y: Self) -> Self {
        KernelF64(self.0 - y.0)
    }
}

impl Mul for KernelF64 {
    type Output = Self;
    fn mul(self, y: Self) -> Self {
        KernelF64(self.0 * y.0)
    }
}

impl Div for KernelF64 {
    type Output = Self;
    fn div(self, y: Self) -> Self {
        KernelF64(self.0 / y.0)
    }
}

impl Neg for KernelF64 {
    type Output = Self;
    fn neg(self) -> Self {
        KernelF64(-self.0)
    }
}

impl Scalar for KernelF64 {
    fn from_f64(v: f64) -> Self {
        KernelF64(v)
    }
    fn sin_cos(self) -> (Self, Self) {
        let ([s], [c]) = crate::trig::sin_cos_n([self.0]);
        (KernelF64(s), KernelF64(c))
    }
    fn sqrt(self) -> Self {
        KernelF64(self.0.sqrt())
    }
    fn abs(self) -> Self {
        KernelF64(self.0.abs())
    }
    fn to_f64(self) -> f64 {
        self.0
    }
}

/// A compiled evaluation order for a set of outputs (the cone, children first), with the
/// nodes renumbered densely so an evaluation touches only the cone's values.
#[derive(Debug, Clone)]
pub struct Tape {
    nodes: Vec<(usize, Node)>,
    outputs: Vec<Id>,
    size: usize,
}

impl Tape {
    /// Compile the cone of `outputs`.
    pub fn new(g: &Graph, outputs: &[Id]) -> Self {
        let mark = g.cone(outputs);
        let max = outputs.iter().map(|o| o.index() + 1).max().unwrap_or(0);
        // slot[i]: the dense index of graph node i (cone nodes only).
        let mut slot = vec![0u32; max];
        let mut nodes = Vec::new();
        for i in (0..max).filter(|&i| mark[i]) {
            let s = |c: Id| Id(slot[c.index()]);
            let n = match g.node(Id(i as u32)) {
                n @ (Node::Const(_) | Node::Var(_)) => n,
                Node::Add(a, b) => Node::Add(s(a), s(b)),
                Node::Sub(a, b) => Node::Sub(s(a), s(b)),
                Node::Mul(a, b) => Node::Mul(s(a), s(b)),
                Node::Div(a, b) => Node::Div(s(a), s(b)),
                Node::Neg(a) => Node::Neg(s(a)),
                Node::Sin(a) => Node::Sin(s(a)),
                Node::Cos(a) => Node::Cos(s(a)),
                Node::Sqrt(a) => Node::Sqrt(s(a)),
                Node::Abs(a) => Node::Abs(s(a)),
                Node::Min(a, b) => Node::Min(s(a), s(b)),
                Node::Max(a, b) => Node::Max(s(a), s(b)),
                Node::IfLt(a, b, t, f) => Node::IfLt(s(a), s(b), s(t), s(f)),
            };
            slot[i] = nodes.len() as u32;
            nodes.push((nodes.len(), n));
        }
        Tape {
            outputs: outputs.iter().map(|o| Id(slot[o.index()])).collect(),
            size: nodes.len(),
            nodes,
        }
    }

    /// Evaluate the outputs for the input variables `vars` (layout of [`crate::robot::Layout`]).
    /// Variables beyond `vars.len()` read as 0.
    pub fn eval<S: Scalar>(&self, vars: &[S]) -> Vec<S> {
        let zero = S::from_f64(0.0);
        let mut v: Vec<S> = vec![zero; self.size];
        for &(i, n) in &self.nodes {
            v[i] = match n {
                Node::Const(b) => S::from_f64(f64::from_bits(b)),
                Node::Var(k) => vars.get(k as usize).copied().unwrap_or(zero),
                Node::Add(a, b) => v[a.index()] + v[b.index()],
                Node::Sub(a, b) => v[a.index()] - v[b.index()],
                Node::Mul(a, b) => v[a.index()] * v[b.index()],
                Node::Div(a, b) => v[a.index()] / v[b.index()],
                Node::Neg(a) => -v[a.index()],
                Node::Sin(a) => v[a.index()].sin_cos().0,
                Node::Cos(a) => v[a.index()].sin_cos().1,
                Node::Sqrt(a) => v[a.index()].sqrt(),
                Node::Abs(a) => v[a.index()].abs(),
                Node::Min(a, b) => {
                    let (x, y) = (v[a.index()], v[b.index()]);
                    if y < x { y } else { x }
                }
                Node::Max(a, b) => {
                    let (x, y) = (v[a.index()], v[b.index()]);
                    if y > x { y } else { x }
                }
                Node::IfLt(a, b, t, f) => {
                    if v[a.index()] < v[b.index()] {
                        v[t.index()]
                    } else {
                        v[f.index()]
                    }
                }
            };
        }
        self.outputs.iter().map(|o| v[o.index()]).collect()
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
    pub fn eval(&self, vars: &[KernelF64]) -> Vec<f64> {
        self.tape.eval(vars).into_iter().map(|v| v.0).collect()
    }
}

/// Every kernel a scene's module holds (its `kernels` list plus
/// [`crate::kernels::ROBOT_KERNELS`]), interpreted: the run-time counterpart of the compiled
/// module, with the same f64 operations (sine and cosine of [`KernelF64`]).
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
    ) -> Vec<KernelF64> {
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
        v.into_iter().map(KernelF64).collect()
    }
}
