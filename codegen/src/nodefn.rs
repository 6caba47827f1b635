//! Collocation node functions as an engine: what one node of a phase evaluates
//! ([`NodeFunction`], [`Collocation`]), its exact sparse derivatives ([`Derivatives`]), a
//! structural [`fingerprint`] that identifies it at build time and at run time, and its
//! emission as flat Rust kernels ([`emit_node_kernels`]).
//!
//! Nothing here is specific to a system: the ball-and-finger node functions (paper eq. 26/29,
//! 14/27, 4/12/18, 60–65) are built by bf-problem on top of this module, and bf-optim
//! evaluates any [`NodeFunction`] either through the kernels emitted here or by interpreting
//! its graphs. Both compute every node with the same `f64` operation, so they agree bitwise.
//!
//! [`NodeFunction::collocation`] forms the outputs a collocation node evaluates (ẋ and the cost
//! integrands scaled by T/2, eq. 51 mapped to τ ∈ [−1, 1]); [`Derivatives`] builds their exact
//! sparse Jacobian and the lower triangle of the weighted Lagrangian Hessian by symbolic
//! differentiation (forward mode, and forward over reverse). [`fingerprint`] hashes the
//! structure of those graphs, so that a solver can recognise, at run time, a node function
//! whose kernels were emitted at build time and fall back to interpreting the graphs
//! otherwise.

#[cfg(feature = "emit")]
use proc_macro2::{Ident, Literal, Span, TokenStream};
#[cfg(feature = "emit")]
use quote::quote;

#[cfg(feature = "emit")]
use crate::CodegenError;
use crate::diff;
#[cfg(feature = "emit")]
use crate::emit::{BODY_MARKER, BodyText, EmitSettings, body_text, splice_bodies, trig_items};
use crate::graph::{Graph, History, Id, Node};
use std::collections::HashMap;
use std::sync::{Arc, LazyLock, Mutex};

/// What a phase's dynamics, path constraints and cost integrands are, at one collocation node.
///
/// Graph variables `x`, `a`, `u` and `duration` are the node's local variables; `fixed` sets
/// other graph inputs (ε, runtime parameters, cost constants). `xdot` must have `x.len()`
/// entries (the collocation imposes ẋ = xdot); `costs` has one integrand per cost state of the
/// problem.
#[derive(Debug, Clone)]
pub struct NodeFunction {
    /// Expression graph.
    pub graph: Graph,
    /// Graph variables of the differential states.
    pub x: Vec<u32>,
    /// Graph variables of the algebraic node variables.
    pub a: Vec<u32>,
    /// Graph variables of the controls.
    pub u: Vec<u32>,
    /// A graph variable (unused by the expressions) for the phase duration.
    pub duration: u32,
    /// Values of other graph inputs.
    pub fixed: Vec<(u32, f64)>,
    /// State derivatives ẋ.
    pub xdot: Vec<Id>,
    /// Path constraints g (equalities have equal bounds).
    pub path: Vec<Id>,
    /// Bounds of `path`.
    pub path_bounds: Vec<(f64, f64)>,
    /// Cost integrands L_j (one per problem cost state).
    pub costs: Vec<Id>,
}

/// The outputs one collocation node evaluates, as a function of its local variables.
#[derive(Debug, Clone)]
pub struct Collocation {
    /// The node's graph plus the scaling nodes.
    pub graph: Graph,
    /// (T/2) ẋ (`x.len()` rows), the path constraints, (T/2) L_j.
    pub outputs: Vec<Id>,
    /// Local variables in order x, a, u, T.
    pub locals: Vec<u32>,
}

impl NodeFunction {
    /// The collocation outputs: on τ ∈ [−1, 1] the dynamics read dx/dτ = (T/2) ẋ and the cost
    /// integrals ∫ L dt = ∫ (T/2) L dτ (eq. 51 under t = t_0 + (τ + 1) T/2).
    pub fn collocation(&self) -> Collocation {
        let mut graph = self.graph.clone();
        let mut outputs = Vec::new();
        let t_var = graph.var(self.duration);
        let half = graph.constant(0.5);
        let ht = graph.mul(half, t_var);
        for &e in &self.xdot {
            outputs.push(graph.mul(ht, e));
        }
        outputs.extend(self.path.iter().copied());
        for &e in &self.costs {
            outputs.push(graph.mul(ht, e));
        }
        let mut locals = self.x.clone();
        locals.extend(&self.a);
        locals.extend(&self.u);
        locals.push(self.duration);
        Collocation {
            graph,
            outputs,
            locals,
        }
    }
}

/// The exact sparse first and second derivatives of graph outputs y = f(v) with respect to
/// local variables v, as graph nodes.
///
/// The Jacobian comes from one forward sweep per local variable, its entries row-major with
/// structural zeros dropped; the Hessian is the lower triangle (i ≥ j) of ∇²(Σ_i w_i y_i) by
/// forward over reverse, with the weights w as extra graph variables `weight_base + i`.
#[derive(Debug, Clone)]
pub struct Derivatives {
    /// Graph variable of the first weight (after every variable the outputs, the locals or the
    /// fixed inputs use).
    pub weight_base: u32,
    /// Jacobian pattern (output, local).
    pub jac: Vec<(usize, usize)>,
    /// Jacobian entries, in `jac` order.
    pub jac_ids: Vec<Id>,
    /// Lower-triangle Hessian pattern (local i ≥ local j).
    pub hess: Vec<(usize, usize)>,
    /// Hessian entries, in `hess` order.
    pub hess_ids: Vec<Id>,
}

/// What [`Derivatives::new`] depends on: the graph's nodes so far, the outputs, the locals and
/// the ids (not the values) of the fixed inputs.
type DerivativesKey = (History, Vec<Id>, Vec<u32>, Vec<u32>);

/// What [`Derivatives::new`] made: the nodes it added to the graph, in order, and the result.
type DerivativesMade = Arc<(Vec<Node>, Derivatives)>;

/// Differentiations done so far in this process ([`Derivatives::new`]): a search builds the
/// same problem hundreds of times (every start, move, hop and refinement), and the symbolic
/// differentiation was about 5 % of its CPU time. At most [`DERIVATIVES_CACHED`] entries
/// (emptied when full: the studies that build many scenes do not grow it without bound).
static DERIVATIVES: LazyLock<Mutex<HashMap<DerivativesKey, DerivativesMade>>> =
    LazyLock::new(|| Mutex::new(HashMap::new()));

/// Entries of the differentiation cache at most.
const DERIVATIVES_CACHED: usize = 64;

impl Derivatives {
    /// Differentiates `outputs` of `g` with respect to the graph variables `locals`. The
    /// construction is deterministic, so a graph with the same [`History`] gets the nodes and
    /// the result of an earlier call replayed ([`Graph::extend_with`]): the same graph and the
    /// same result, without differentiating again.
    pub fn new(g: &mut Graph, outputs: &[Id], locals: &[u32], fixed: &[(u32, f64)]) -> Self {
        let key: DerivativesKey = (
            g.history(),
            outputs.to_vec(),
            locals.to_vec(),
            fixed.iter().map(|f| f.0).collect(),
        );
        let lock = || DERIVATIVES.lock().unwrap_or_else(|e| e.into_inner());
        let made = lock().get(&key).cloned();
        if let Some(made) = made {
            g.extend_with(&made.0);
            return match g.poison() {
                // The replayed nodes did not all fit: the ids refer to nodes that are not there.
                Some(p) => made.1.poisoned(p),
                None => made.1.clone(),
            };
        }
        let before = g.len();
        let d = Self::differentiate(g, outputs, locals, fixed);
        if g.exceeded() {
            return d;
        }
        let made = Arc::new((g.nodes()[before..].to_vec(), d.clone()));
        let mut cache = lock();
        if cache.len() >= DERIVATIVES_CACHED {
            cache.clear();
        }
        cache.insert(key, made);
        d
    }

    /// These derivatives with every entry the poison `p` of an exceeded graph.
    fn poisoned(&self, p: Id) -> Self {
        Derivatives {
            jac_ids: vec![p; self.jac_ids.len()],
            hess_ids: vec![p; self.hess_ids.len()],
            ..self.clone()
        }
    }

    /// [`Derivatives::new`] without the cache.
    pub fn differentiate(
        g: &mut Graph,
        outputs: &[Id],
        locals: &[u32],
        fixed: &[(u32, f64)],
    ) -> Self {
        let mark = g.cone(outputs);
        let mut max_var = 0usize;
        for (i, m) in mark.iter().enumerate() {
            if *m && let Node::Var(v) = g.node(Id(i as u32)) {
                max_var = max_var.max(v as usize + 1);
            }
        }
        for &v in locals.iter().chain(fixed.iter().map(|f| &f.0)) {
            max_var = max_var.max(v as usize + 1);
        }
        let weight_base = max_var as u32;
        let mut jac = Vec::new();
        let mut jac_ids = Vec::new();
        for (l, &v) in locals.iter().enumerate() {
            let col = diff::partial(g, outputs, v);
            for (o, id) in col.into_iter().enumerate() {
                if !g.is_zero(id) {
                    jac.push((o, l));
                    jac_ids.push(id);
                }
            }
        }
        // Row-major entries, for readable patterns.
        let mut order: Vec<usize> = (0..jac.len()).collect();
        order.sort_by_key(|&k| jac[k]);
        let jac: Vec<(usize, usize)> = order.iter().map(|&k| jac[k]).collect();
        let jac_ids: Vec<Id> = order.iter().map(|&k| jac_ids[k]).collect();
        let weighted: Vec<(Id, Id)> = outputs
            .iter()
            .enumerate()
            .map(|(i, &o)| (o, g.var(weight_base + i as u32)))
            .collect();
        let h = diff::hessian(g, &weighted, locals);
        let mut hess = Vec::new();
        let mut hess_ids = Vec::new();
        for i in 0..locals.len() {
            for j in 0..=i {
                let id = h[i][j];
                if !g.is_zero(id) {
                    hess.push((i, j));
                    hess_ids.push(id);
                }
            }
        }
        Derivatives {
            weight_base,
            jac,
            jac_ids,
            hess,
            hess_ids,
        }
    }
}

/// What a graph variable is to a compiled node function.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum VarRole {
    /// Local variable `l` (an argument).
    Local(u32),
    /// Fixed input `k` (position in the `fixed` list; its value is an argument of a kernel
    /// and a constant of an interpreted program).
    Fixed(u32, f64),
    /// Hessian weight `w`.
    Weight(u32),
    /// Anything else: reads as 0.
    Zero,
}

/// The role of every graph variable below `weight_base + n_out`: fixed inputs first, then
/// locals (a variable that is both is local), then the weights.
pub fn var_roles(
    locals: &[u32],
    fixed: &[(u32, f64)],
    weight_base: u32,
    n_out: usize,
) -> Vec<VarRole> {
    let mut role = vec![VarRole::Zero; weight_base as usize + n_out];
    for (k, &(v, x)) in fixed.iter().enumerate() {
        role[v as usize] = VarRole::Fixed(k as u32, x);
    }
    for (l, &v) in locals.iter().enumerate() {
        role[v as usize] = VarRole::Local(l as u32);
    }
    for w in 0..n_out {
        role[weight_base as usize + w] = VarRole::Weight(w as u32);
    }
    role
}

/// 128-bit FNV-1a (two independent 64-bit streams): stable across platforms and compiler
/// versions, unlike `std`'s hashers, so build time and run time agree.
struct Fnv([u64; 2]);

impl Fnv {
    fn new() -> Self {
        Fnv([0xcbf2_9ce4_8422_2325, 0x6c62_272e_07bb_0142])
    }
    fn byte(&mut self, b: u8) {
        self.0[0] = (self.0[0] ^ b as u64).wrapping_mul(0x0000_0100_0000_01b3);
        self.0[1] = (self.0[1] ^ b as u64).wrapping_mul(0x0000_0100_0000_0193);
    }
    fn u64(&mut self, x: u64) {
        for b in x.to_le_bytes() {
            self.byte(b);
        }
    }
    fn finish(&self) -> u128 {
        ((self.0[0] as u128) << 64) | self.0[1] as u128
    }
}

/// Structural fingerprint of a compiled node function: the cone of the outputs and of their
/// derivatives, node by node in graph order, with operands renumbered within the cone,
/// constants by their bits and variables by their [`VarRole`] (fixed inputs by position, not
/// value), plus the output lists and patterns. Two node functions with the same fingerprint
/// compute the same values with the same operations for the same locals, fixed values and
/// weights.
pub fn fingerprint(g: &Graph, outputs: &[Id], d: &Derivatives, roles: &[VarRole]) -> u128 {
    let mut roots: Vec<Id> = outputs.to_vec();
    roots.extend(&d.jac_ids);
    roots.extend(&d.hess_ids);
    let mark = g.cone(&roots);
    let mut pos = vec![u32::MAX; mark.len()];
    let mut h = Fnv::new();
    let mut count = 0u32;
    for (i, &m) in mark.iter().enumerate() {
        if !m {
            continue;
        }
        pos[i] = count;
        count += 1;
        let node = g.node(Id(i as u32));
        let ops = |tag: u8, args: &[Id], h: &mut Fnv| {
            h.byte(tag);
            for a in args {
                h.u64(pos[a.index()] as u64);
            }
        };
        match node {
            Node::Const(b) => {
                h.byte(0);
                h.u64(b);
            }
            Node::Var(v) => {
                h.byte(1);
                match roles.get(v as usize).copied().unwrap_or(VarRole::Zero) {
                    VarRole::Local(l) => {
                        h.byte(0);
                        h.u64(l as u64);
                    }
                    VarRole::Fixed(k, _) => {
                        h.byte(1);
                        h.u64(k as u64);
                    }
                    VarRole::Weight(w) => {
                        h.byte(2);
                        h.u64(w as u64);
                    }
                    VarRole::Zero => h.byte(3),
                }
            }
            Node::Add(a, b) => ops(2, &[a, b], &mut h),
            Node::Sub(a, b) => ops(3, &[a, b], &mut h),
            Node::Mul(a, b) => ops(4, &[a, b], &mut h),
            Node::Div(a, b) => ops(5, &[a, b], &mut h),
            Node::Neg(a) => ops(6, &[a], &mut h),
            Node::Sin(a) => ops(7, &[a], &mut h),
            Node::Cos(a) => ops(8, &[a], &mut h),
            Node::Sqrt(a) => ops(9, &[a], &mut h),
            Node::Abs(a) => ops(10, &[a], &mut h),
            Node::Min(a, b) => ops(11, &[a, b], &mut h),
            Node::Max(a, b) => ops(12, &[a, b], &mut h),
            Node::IfLt(a, b, t, f) => ops(13, &[a, b, t, f], &mut h),
        }
    }
    for list in [outputs, &d.jac_ids[..], &d.hess_ids[..]] {
        h.byte(0xff);
        h.u64(list.len() as u64);
        for id in list {
            h.u64(pos[id.index()] as u64);
        }
    }
    for pattern in [&d.jac, &d.hess] {
        h.byte(0xfe);
        for &(a, b) in pattern.iter() {
            h.u64(a as u64);
            h.u64(b as u64);
        }
    }
    h.finish()
}

/// A node function ready for emission: its collocation outputs, derivatives, roles and
/// fingerprint.
#[derive(Debug, Clone)]
pub struct CompiledNode {
    /// Graph holding outputs and derivatives.
    pub graph: Graph,
    /// Collocation outputs.
    pub outputs: Vec<Id>,
    /// Local variables.
    pub locals: Vec<u32>,
    /// Fixed inputs (values are those of the build; kernels take them as arguments).
    pub fixed: Vec<(u32, f64)>,
    /// Derivative graphs.
    pub derivs: Derivatives,
    /// Role of every graph variable.
    pub roles: Vec<VarRole>,
    /// [`fingerprint`].
    pub fingerprint: u128,
}

impl CompiledNode {
    /// Differentiates and fingerprints `outputs` of `graph` over `locals`.
    pub fn new(
        mut graph: Graph,
        outputs: Vec<Id>,
        locals: Vec<u32>,
        fixed: Vec<(u32, f64)>,
    ) -> Self {
        let derivs = Derivatives::new(&mut graph, &outputs, &locals, &fixed);
        let roles = var_roles(&locals, &fixed, derivs.weight_base, outputs.len());
        let fingerprint = fingerprint(&graph, &outputs, &derivs, &roles);
        CompiledNode {
            graph,
            outputs,
            locals,
            fixed,
            derivs,
            roles,
            fingerprint,
        }
    }
}

#[cfg(feature = "emit")]
/// The formatted text of one kernel function `fn name(local, fixed, w, out)` computing `roots`
/// into `out[0..roots.len()]`; with `x4`, the batched variant computing four nodes at once:
/// `local`, `w` and `out` then hold the four nodes' entries interleaved (node `l`'s entry `k`
/// at `4·k + l`), `fixed` is shared, and the body is the scalar body in a loop over the lanes
/// `l` ([`crate::emit::body_text`]). `uses_w`: whether `roots` read the weights (only then the
/// batched kernel checks their length). The body is printed as text
/// ([`crate::emit::body_text`]), the rest formatted by `prettyplease`.
fn kernel_fn(
    name: &Ident,
    doc: &str,
    node: &CompiledNode,
    roots: &[Id],
    x4: bool,
    uses_w: bool,
) -> Result<String, CodegenError> {
    use std::fmt::Write as _;
    let var = |out: &mut String, v: u32| {
        let lane = if x4 { "[l]" } else { "" };
        let _ = match node.roles.get(v as usize).copied().unwrap_or(VarRole::Zero) {
            VarRole::Local(l) => write!(out, "local[{l}]{lane}"),
            VarRole::Fixed(k, _) => write!(out, "fixed[{k}]"),
            VarRole::Weight(w) => write!(out, "w[{w}]{lane}"),
            VarRole::Zero => write!(out, "0.0"),
        };
    };
    let lhs = |out: &mut String, k: usize| {
        let _ = write!(out, "out[{k}]{}", if x4 { "[l]" } else { "" });
    };
    let BodyText { pre, body, ops } =
        body_text(&node.graph, roots, &var, &lhs, &EmitSettings::default(), x4);
    let nl = Literal::usize_unsuffixed(node.locals.len());
    let nf = Literal::usize_unsuffixed(node.fixed.len());
    let no = Literal::usize_unsuffixed(roots.len());
    let marker = Ident::new(BODY_MARKER, Span::call_site());
    let pre_marker = Ident::new(PRE_MARKER, Span::call_site());
    let tokens_body = if x4 {
        // Arrays of `[f64; 4]` (one per entry, its four lanes) make every index below
        // provably in bounds, so the loop has no exit but its end and vectorises.
        let nw = Literal::usize_unsuffixed(node.outputs.len());
        let load_w = if uses_w {
            quote!(let w: &[[f64; 4]; #nw] = w.as_chunks::<4>().0[..#nw].try_into().unwrap();)
        } else {
            TokenStream::new()
        };
        quote! {
            let local: &[[f64; 4]; #nl] = local.as_chunks::<4>().0[..#nl].try_into().unwrap();
            let fixed = &fixed[..#nf];
            #load_w
            let out: &mut [[f64; 4]; #no] =
                (&mut out.as_chunks_mut::<4>().0[..#no]).try_into().unwrap();
            #pre_marker;
            for l in 0..4 {
                #marker;
            }
        }
    } else {
        // Lengths are checked once so that every constant index below is in bounds without a
        // per-access check.
        quote! {
            let local = &local[..#nl];
            let fixed = &fixed[..#nf];
            let out = &mut out[..#no];
            #marker;
        }
    };
    let doc = if x4 {
        format!(
            " {doc} Four nodes at once (`local`, `w` and `out` interleaved: node `l`'s entry \
             `k` at `4·k + l`), each bitwise as the scalar kernel. Cost: 4 × {} operations.",
            ops.total()
        )
    } else {
        format!(
            " {doc} Cost: {} operations, {} temporaries.",
            ops.total(),
            ops.temporaries
        )
    };
    let tokens = quote! {
        #[doc = #doc]
        #[allow(unused_variables, clippy::all)]
        fn #name(local: &[f64], fixed: &[f64], w: &[f64], out: &mut [f64]) {
            #tokens_body
        }
    };
    let bodies = if x4 {
        vec![
            (PRE_MARKER, 4, pre.as_str()),
            (BODY_MARKER, 8, body.as_str()),
        ]
    } else {
        vec![(BODY_MARKER, 4, body.as_str())]
    };
    splice_bodies(tokens, "emitted node kernel", &bodies)
}

#[cfg(feature = "emit")]
/// The placeholder statement of a batched kernel's statements before its lane loop.
const PRE_MARKER: &str = "__bf_codegen_pre__";

#[cfg(feature = "emit")]
/// The text of the three kernels of `node` (and, with `x4`, of their batched variants) and
/// the tokens of its `NodeKernel` table entry.
fn node_tokens(
    name: &str,
    what: &str,
    node: &CompiledNode,
    x4: bool,
) -> Result<(String, TokenStream), CodegenError> {
    let id = |s: &str| Ident::new(&format!("{name}_{s}"), Span::call_site());
    let (fv, fj, fh) = (id("value"), id("jacobian"), id("hessian"));
    let d = &node.derivs;
    let docs = [
        format!("Outputs of the {what} node function (T/2·ẋ, path rows, T/2·L)."),
        format!("Jacobian values of the {what} node function, pattern order."),
        format!("Lower-triangle Lagrangian Hessian values of the {what} node function."),
    ];
    let mut code = kernel_fn(&fv, &docs[0], node, &node.outputs, false, false)?;
    code += &kernel_fn(&fj, &docs[1], node, &d.jac_ids, false, false)?;
    code += &kernel_fn(&fh, &docs[2], node, &d.hess_ids, false, true)?;
    let batched_entry = if x4 {
        let (bv, bj, bh) = (id("value_x4"), id("jacobian_x4"), id("hessian_x4"));
        code += &kernel_fn(&bv, &docs[0], node, &node.outputs, true, false)?;
        code += &kernel_fn(&bj, &docs[1], node, &d.jac_ids, true, false)?;
        code += &kernel_fn(&bh, &docs[2], node, &d.hess_ids, true, true)?;
        quote!(Some(NodeKernelX4 { value: #bv, jacobian: #bj, hessian: #bh }))
    } else {
        quote!(None)
    };
    let pairs = |p: &[(usize, usize)]| {
        let items = p.iter().map(|&(a, b)| {
            let (a, b) = (
                Literal::u32_unsuffixed(a as u32),
                Literal::u32_unsuffixed(b as u32),
            );
            quote!((#a, #b))
        });
        quote!(&[#(#items),*])
    };
    let (jp, hp) = (pairs(&d.jac), pairs(&d.hess));
    let fp = Literal::u128_unsuffixed(node.fingerprint);
    let n_out = Literal::usize_unsuffixed(node.outputs.len());
    let n_local = Literal::usize_unsuffixed(node.locals.len());
    let n_fixed = Literal::usize_unsuffixed(node.fixed.len());
    let entry = quote! {
        NodeKernel {
            name: #name,
            fingerprint: #fp,
            n_out: #n_out,
            n_local: #n_local,
            n_fixed: #n_fixed,
            jacobian_pattern: #jp,
            hessian_pattern: #hp,
            value: #fv,
            jacobian: #fj,
            hessian: #fh,
            x4: #batched_entry,
        },
    };
    Ok((code, entry))
}

/// One node function to emit: its kernel name prefix, a phrase for the docs, and the compiled
/// node.
#[derive(Debug, Clone)]
pub struct NamedNode {
    /// Kernel name (`<name>_value`, `<name>_jacobian`, `<name>_hessian`).
    pub name: String,
    /// What the node function is (docs of the emitted functions).
    pub what: String,
    /// The compiled node function.
    pub node: CompiledNode,
    /// Whether to emit the batched (four nodes at once) variants of its kernels as well.
    pub x4: bool,
}

#[cfg(feature = "emit")]
/// The Rust source of the node kernels of `nodes`: one value, Jacobian and Hessian function
/// per node (plus their batched `_x4` variants for the nodes with [`NamedNode::x4`], and the
/// sine–cosine helper they call), and `pub static NODE_KERNELS:
/// &[NodeKernel]` sorted by fingerprint. A node with the fingerprint of an earlier one is
/// skipped (that kernel serves both). The including module must define `NodeKernel` and
/// `NodeKernelX4`. Deterministic: the same nodes give the same text.
pub fn emit_node_kernels(nodes: &[NamedNode]) -> Result<String, CodegenError> {
    let mut fns = Vec::new();
    let mut entries: Vec<(u128, TokenStream)> = Vec::new();
    for n in nodes {
        if entries.iter().any(|e| e.0 == n.node.fingerprint) {
            continue;
        }
        let (f, e) = node_tokens(&n.name, &n.what, &n.node, n.x4)?;
        fns.push(f);
        entries.push((n.node.fingerprint, e));
    }
    entries.sort_by_key(|e| e.0);
    let items = entries.iter().map(|e| &e.1);
    // Every kernel's sine and cosine come from the trig helpers, emitted once (unused ones are
    // allowed).
    let helpers = if nodes.is_empty() {
        TokenStream::new()
    } else {
        trig_items(crate::emit::FloatTy::F64)?
    };
    let tokens = quote! {
        /// Every emitted node kernel, sorted by fingerprint (binary search).
        pub static NODE_KERNELS: &[NodeKernel] = &[#(#items)*];
        #helpers
    };
    let file: syn::File =
        syn::parse2(tokens).map_err(CodegenError::unparsable("emitted node kernels"))?;
    let mut out =
        String::from("// @generated by bf-codegen (nodefn::emit_node_kernels). Do not edit.\n");
    out.push_str(&prettyplease::unparse(&file));
    // The kernels are formatted items already; `prettyplease` prints a file's items one after
    // the other, so they follow the table as they would in one formatted file.
    for f in &fns {
        out.push_str(f);
    }
    Ok(out)
}
