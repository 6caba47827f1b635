//! Rust emitter: graph cone of a kernel → SSA `let` bindings → `quote!` tokens → `syn::File`
//! → `prettyplease` (`docs/architecture.md`, "Emit": SSA avoids the token-pasting
//! precedence pitfall). Constants are printed with Rust's shortest round-trip formatting, so
//! every `f64` survives exactly. In `f64` kernels the sines and cosines of all joint angles come
//! from one call of the vectorised helper `sin_cos_n` ([`crate::trig`], emitted once per file
//! by [`trig_items`]); elsewhere sin/cos of one argument share a `sin_cos` call. The batched
//! node kernels put the scalar body in a loop over four lanes ([`lanes`]).
//!
//! [`EmitSettings`] select variants for accuracy/speed studies: the float type
//! ([`FloatTy::F32`] rounds every constant and operation to single precision) and fused
//! multiply-add (`a*b ± c` as `mul_add`, one rounding instead of two). The defaults reproduce
//! the plain f64 output byte for byte.

use std::fmt::Write as _;
use std::str::FromStr;

use proc_macro2::{Ident, Literal, Span, TokenStream};
use quote::{format_ident, quote};

use crate::CodegenError;
use crate::graph::{Graph, Id, Node};
use crate::kernels::{Arg, CONTACT_FIELDS, Dim, KernelDef, OutKind};
use crate::report::OpCounts;
use crate::robot::Layout;

mod dispatch;
pub mod lanes;
use dispatch::{eval_flat_arm, eval_into_arm};

/// Floating-point type of the emitted code.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum FloatTy {
    /// Double precision (the default).
    #[default]
    F64,
    /// Single precision: arguments, outputs, constants and arithmetic in `f32`.
    F32,
}

impl FloatTy {
    /// The type's name as tokens (`f64` / `f32`).
    pub fn tokens(self) -> TokenStream {
        match self {
            FloatTy::F64 => quote!(f64),
            FloatTy::F32 => quote!(f32),
        }
    }
}

/// Variants of the emitted code; `EmitSettings::default()` is the standard output.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct EmitSettings {
    /// Float type of arguments, outputs and arithmetic.
    pub float: FloatTy,
    /// Emit `a*b + c`, `a*b - c` and `c - a*b` as `mul_add` (fused multiply-add) whenever the
    /// product is a graph node of its own.
    pub fma: bool,
}

/// Tokens of an `f64` literal (exact: shortest representation that round-trips).
pub fn f64_tokens(v: f64) -> TokenStream {
    float_tokens(v, FloatTy::F64)
}

/// Tokens of a literal of type `ft` with value `v` (unsuffixed: the compiler rounds it to `ft`).
fn float_tokens(v: f64, ft: FloatTy) -> TokenStream {
    let t = ft.tokens();
    if v.is_nan() {
        return quote!(#t::NAN);
    }
    if v.is_infinite() {
        return if v > 0.0 {
            quote!(#t::INFINITY)
        } else {
            quote!(#t::NEG_INFINITY)
        };
    }
    let s = format!("{:?}", v.abs());
    let lit = Literal::from_str(&s).unwrap_or_else(|_| Literal::f64_unsuffixed(v.abs()));
    if v < 0.0 { quote!(-#lit) } else { quote!(#lit) }
}

fn dim_tokens(d: Dim) -> TokenStream {
    match d {
        Dim::Nq => quote!(NQ),
        Dim::Lit(n) => {
            let l = Literal::usize_unsuffixed(n);
            quote!(#l)
        }
    }
}

fn array_type(dims: &[Dim], ft: FloatTy) -> TokenStream {
    let mut t = ft.tokens();
    for &d in dims.iter().rev() {
        let dt = dim_tokens(d);
        t = quote!([#t; #dt]);
    }
    t
}

fn dim_value(d: Dim, nq: usize) -> usize {
    match d {
        Dim::Nq => nq,
        Dim::Lit(n) => n,
    }
}

/// Element access paths (`[i][j]` suffixes) of an array with `dims`, row-major.
fn index_paths(dims: &[Dim], nq: usize) -> Vec<TokenStream> {
    let mut paths = vec![TokenStream::new()];
    for &d in dims {
        let n = dim_value(d, nq);
        let mut next = Vec::with_capacity(paths.len() * n);
        for p in &paths {
            for i in 0..n {
                let l = Literal::usize_unsuffixed(i);
                next.push(quote!(#p[#l]));
            }
        }
        paths = next;
    }
    paths
}

/// Kernels with at most this many temporaries are marked `#[inline]`.
pub const INLINE_MAX_TEMPORARIES: usize = 1000;

/// Emitted body of one kernel plus its operation counts.
pub struct EmittedKernel {
    /// The function item tokens.
    pub tokens: TokenStream,
    /// Operation counts.
    pub ops: OpCounts,
    /// Whether the kernel calls the batched sine–cosine helper (`sin_cos_n`, see
    /// [`trig_items`]), which the file must then define.
    pub fast_trig: bool,
}

fn var_tokens(layout: &Layout, v: u32) -> TokenStream {
    let v = v as usize;
    let nq = layout.nq;
    let lit = |i: usize| Literal::usize_unsuffixed(i);
    if v < nq {
        let i = lit(v);
        quote!(q[#i])
    } else if v < 2 * nq {
        let i = lit(v - nq);
        quote!(qd[#i])
    } else if v < 2 * nq + 3 {
        let i = lit(v - 2 * nq);
        quote!(omega[#i])
    } else if v == 2 * nq + 3 {
        quote!(eps)
    } else if v < layout.n_vars() {
        let i = lit(v - 2 * nq - 4);
        quote!(p[#i])
    } else if v < layout.n_vars() + nq {
        let i = lit(v - layout.n_vars());
        quote!(qdd[#i])
    } else {
        let i = lit(v - layout.n_vars() - nq);
        quote!(tau[#i])
    }
}

/// Emit one kernel as a Rust function (standard options).
pub fn emit_kernel(
    g: &Graph,
    layout: &Layout,
    k: &KernelDef,
) -> Result<EmittedKernel, CodegenError> {
    emit_kernel_with(g, layout, k, &EmitSettings::default())
}

/// Emit one kernel as a Rust function with the variant `opts`.
pub fn emit_kernel_with(
    g: &Graph,
    layout: &Layout,
    k: &KernelDef,
    opts: &EmitSettings,
) -> Result<EmittedKernel, CodegenError> {
    let ft = opts.float.tokens();
    let roots: Vec<Id> = k
        .outputs
        .iter()
        .flat_map(|o| o.ids.iter().copied())
        .collect();
    let (
        Ssa {
            mut stmts,
            refs,
            ops,
            ..
        },
        fast_trig,
    ) = ssa_inner(g, &roots, &|v| var_tokens(layout, v), opts, true, false);

    // Output assignments.
    let mut params: Vec<TokenStream> = Vec::new();
    for a in &k.inputs {
        params.push(match a {
            Arg::Q => quote!(q: &[#ft; NQ]),
            Arg::Qd => quote!(qd: &[#ft; NQ]),
            Arg::Omega => quote!(omega: &[#ft; 3]),
            Arg::Eps => quote!(eps: #ft),
            Arg::Qdd => quote!(qdd: &[#ft; NQ]),
            Arg::Tau => quote!(tau: &[#ft; NQ]),
            Arg::P => quote!(p: &[#ft; NP]),
        });
    }
    for o in &k.outputs {
        let name = Ident::new(&o.name, Span::call_site());
        let val = |id: Id| {
            refs[id.index()]
                .clone()
                .expect("internal: output not emitted")
        };
        match &o.kind {
            OutKind::Scalar => {
                params.push(quote!(#name: &mut #ft));
                let v = val(o.ids[0]);
                stmts.push(quote!(*#name = #v;));
            }
            OutKind::Array(dims) => {
                let ty = array_type(dims, opts.float);
                params.push(quote!(#name: &mut #ty));
                for (path, &id) in index_paths(dims, layout.nq).iter().zip(&o.ids) {
                    let v = val(id);
                    stmts.push(quote!(#name #path = #v;));
                }
            }
            OutKind::Contact => {
                params.push(quote!(#name: &mut Contact));
                let mut it = o.ids.iter();
                for (field, dims, _) in CONTACT_FIELDS {
                    let f = Ident::new(field, Span::call_site());
                    for path in index_paths(dims, layout.nq) {
                        let id = *it.next().ok_or_else(|| {
                            CodegenError::Internal("contact output size mismatch".into())
                        })?;
                        let v = val(id);
                        stmts.push(quote!(#name.#f #path = #v;));
                    }
                }
            }
        }
    }
    let fname = Ident::new(&k.name, Span::call_site());
    let mut doc = String::new();
    let _ = write!(doc, " {}", k.doc);
    let mut doc_lines = vec![doc, String::new(), " Arguments, in order:".to_string()];
    for a in &k.inputs {
        doc_lines.push(
            match a {
                Arg::Q => " * `q`: joint angles (rad)",
                Arg::Qd => " * `qd`: joint velocities (rad/s)",
                Arg::Omega => " * `omega`: ball angular velocity, world axes (rad/s)",
                Arg::Eps => " * `eps`: smoothing width ε of |x| ≈ √(x² + ε²) (m)",
                Arg::Qdd => " * `qdd`: joint accelerations (rad/s²; m/s² for prismatic joints)",
                Arg::Tau => " * `tau`: joint torques (N m; N for prismatic joints)",
                Arg::P => {
                    " * `p`: runtime parameters, layout `PARAM_NAMES` (pass `&PARAM_DEFAULTS`)"
                }
            }
            .to_string(),
        );
    }
    for o in &k.outputs {
        doc_lines.push(format!(
            " * `{}`: output (see above), fully overwritten",
            o.name
        ));
    }
    doc_lines.push(String::new());
    doc_lines.push(format!(
        " Cost: {} add/sub, {} mul, {} div, {} sqrt, {} sin/cos, {} neg, {} other; {} temporaries.",
        ops.add, ops.mul, ops.div, ops.sqrt, ops.sincos, ops.neg, ops.other, ops.temporaries
    ));
    let docs = doc_lines.iter().map(|l| quote!(#[doc = #l]));
    // `#[inline]` lets small kernels be inlined across crates; very large kernels (7-DOF
    // Christoffel symbols: thousands of operations) would only be re-compiled in every
    // calling crate, so they are left to normal linkage.
    let inline = if ops.temporaries <= INLINE_MAX_TEMPORARIES {
        quote!(#[inline])
    } else {
        TokenStream::new()
    };
    let tokens = quote! {
        #(#docs)*
        #inline
        #[allow(unused_variables)]
        pub fn #fname(#(#params),*) {
            #(#stmts)*
        }
    };
    Ok(EmittedKernel {
        tokens,
        ops,
        fast_trig,
    })
}

/// SSA statements computing every node of the cone of `roots` (in node order), and the
/// tokens that name each node's value (`refs[i]`, `None` outside the cone).
pub(crate) struct Ssa {
    /// Statements before the lane loop (only with `lanes`).
    pub(crate) pre: Vec<TokenStream>,
    pub(crate) stmts: Vec<TokenStream>,
    pub(crate) refs: Vec<Option<TokenStream>>,
    pub(crate) ops: OpCounts,
}

/// The helper items that code from [`ssa_inner`] with `batch_trig` calls (`sin_cos_n` and its exact fallback,
/// from [`crate::trig`]), as private items for a generated file; emitted once per file.
pub fn trig_items() -> Result<TokenStream, CodegenError> {
    let mut file: syn::File =
        syn::parse_str(include_str!("../trig.rs")).map_err(CodegenError::unparsable("trig.rs"))?;
    file.attrs.clear();
    let mut out = TokenStream::new();
    for item in &mut file.items {
        if let syn::Item::Fn(f) = item {
            f.vis = syn::Visibility::Inherited;
        }
        out.extend(quote!(#item));
    }
    Ok(out)
}

/// The items of [`lanes`] (`sin_cos_lanes`, which the batched node kernels call) for a
/// generated file, without the module's tests; emitted once per file.
pub fn lanes_items() -> Result<TokenStream, CodegenError> {
    let file: syn::File =
        syn::parse_str(include_str!("lanes.rs")).map_err(CodegenError::unparsable("lanes.rs"))?;
    let mut out = TokenStream::new();
    for item in &file.items {
        if let syn::Item::Fn(f) = item {
            let mut f = f.clone();
            f.vis = syn::Visibility::Inherited;
            out.extend(quote!(#f));
        }
    }
    Ok(out)
}

/// The `let` bindings of the cone of `roots`; graph variables are printed by `var_tokens`.
/// Shared by the dynamics kernels and the OCP node kernels (`crate::nodefn`), so both compute
/// every node with the same `f64` operation. Without `batch_trig`, sin/cos are computed by the
/// standard library (`sin_cos` per angle); with `batch_trig` and `f64`, every sine and cosine
/// of a graph variable (the joint angles) is taken from one call `sin_cos_n([…])` at the top
/// of the body, and the returned flag says whether that call was emitted (the file must then
/// contain [`trig_items`]). Other sin/cos arguments and `f32` use the standard library.
///
/// With `lanes` (f64 only), the statements are the body of a loop over four lanes `l`
/// ([`lanes`]; `var_tokens` must then name lane `l`'s value): every sine and cosine of a graph
/// variable is instead computed before the loop, four lanes at once (`sin_cos_n` with
/// `batch_trig`, else `sin_cos_lanes`), in [`Ssa::pre`], and read as `name[l]` in the loop.
pub(crate) fn ssa_inner(
    g: &Graph,
    roots: &[Id],
    var_tokens: &dyn Fn(u32) -> TokenStream,
    opts: &EmitSettings,
    batch_trig: bool,
    lanes: bool,
) -> (Ssa, bool) {
    let batch_trig = batch_trig && opts.float == FloatTy::F64;
    let lanes = lanes && opts.float == FloatTy::F64;
    let mut batched = false;
    let ft = opts.float.tokens();
    // Product operands of a Mul node that a later Add/Sub may fuse (only when FMA is on).
    let as_mul = |id: Id| -> Option<(Id, Id)> {
        match g.node(id) {
            Node::Mul(a, b) if opts.fma => Some((a, b)),
            _ => None,
        }
    };
    let mark = g.cone(roots);
    let max = roots.iter().map(|r| r.index() + 1).max().unwrap_or(0);
    let mut refs: Vec<Option<TokenStream>> = vec![None; max];
    let mut stmts: Vec<TokenStream> = Vec::new();
    let mut pre: Vec<TokenStream> = Vec::new();
    let mut ops = OpCounts::default();
    let mut counter = 0usize;
    let fresh = |counter: &mut usize| {
        let id = format_ident!("t{}", *counter);
        *counter += 1;
        id
    };
    if batch_trig || lanes {
        // The angles (graph variables) whose sin or cos is in the cone, in node order.
        let mut angles: Vec<Id> = Vec::new();
        let mut args: Vec<TokenStream> = Vec::new();
        for i in 0..max {
            if let Node::Sin(a) | Node::Cos(a) = g.node(Id(i as u32))
                && mark[i]
                && let Node::Var(v) = g.node(a)
                && !angles.contains(&a)
            {
                angles.push(a);
                args.push(var_tokens(v));
            }
        }
        if !angles.is_empty() {
            let mut sins = Vec::new();
            let mut coss = Vec::new();
            for _ in &angles {
                sins.push(fresh(&mut counter));
                coss.push(fresh(&mut counter));
            }
            if lanes {
                let helper = if batch_trig {
                    quote!(sin_cos_n::<4>)
                } else {
                    quote!(sin_cos_lanes)
                };
                for ((s, c), x) in sins.iter().zip(&coss).zip(&args) {
                    pre.push(quote!(let (#s, #c) = #helper(std::array::from_fn(|l| #x));));
                }
            } else {
                stmts.push(quote!(let ([#(#sins),*], [#(#coss),*]) = sin_cos_n([#(#args),*]);));
            }
            batched = batch_trig;
            ops.sincos += angles.len();
            ops.temporaries += 2 * angles.len();
            for i in 0..max {
                let (a, is_sin) = match g.node(Id(i as u32)) {
                    Node::Sin(a) => (a, true),
                    Node::Cos(a) => (a, false),
                    _ => continue,
                };
                if !mark[i] {
                    continue;
                }
                if let Some(j) = angles.iter().position(|&b| b == a) {
                    let name = if is_sin { &sins[j] } else { &coss[j] };
                    refs[i] = Some(if lanes {
                        quote!(#name[l])
                    } else {
                        quote!(#name)
                    });
                }
            }
        }
    }
    for i in 0..max {
        if !mark[i] || refs[i].is_some() {
            continue;
        }
        let node = g.node(Id(i as u32));
        let r = |id: Id, refs: &Vec<Option<TokenStream>>| -> TokenStream {
            refs[id.index()]
                .clone()
                .expect("internal: child emitted before parent")
        };
        let expr: TokenStream = match node {
            Node::Const(b) => {
                refs[i] = Some(float_tokens(f64::from_bits(b), opts.float));
                continue;
            }
            Node::Var(v) => {
                refs[i] = Some(var_tokens(v));
                continue;
            }
            Node::Sin(a) | Node::Cos(a) => {
                let x = r(a, &refs);
                let is_sin = matches!(node, Node::Sin(_));
                // The partner node (cos for sin and vice versa), if it is in the cone.
                let partner = (i + 1..max).find(|&j| {
                    mark[j]
                        && match g.node(Id(j as u32)) {
                            Node::Cos(b) if is_sin => b == a,
                            Node::Sin(b) if !is_sin => b == a,
                            _ => false,
                        }
                });
                ops.sincos += 1;
                match partner {
                    Some(j) => {
                        let s = fresh(&mut counter);
                        let c = fresh(&mut counter);
                        stmts.push(quote!(let (#s, #c) = #ft::sin_cos(#x);));
                        ops.temporaries += 2;
                        let (si, ci) = if is_sin { (i, j) } else { (j, i) };
                        refs[si] = Some(quote!(#s));
                        refs[ci] = Some(quote!(#c));
                    }
                    None => {
                        let t = fresh(&mut counter);
                        if is_sin {
                            stmts.push(quote!(let #t = #ft::sin(#x);));
                        } else {
                            stmts.push(quote!(let #t = #ft::cos(#x);));
                        }
                        ops.temporaries += 1;
                        refs[i] = Some(quote!(#t));
                    }
                }
                continue;
            }
            Node::Add(a, b) => {
                ops.add += 1;
                if let Some((m0, m1)) = as_mul(a) {
                    let (x0, x1, y) = (r(m0, &refs), r(m1, &refs), r(b, &refs));
                    quote!(#ft::mul_add(#x0, #x1, #y))
                } else if let Some((m0, m1)) = as_mul(b) {
                    let (x0, x1, y) = (r(m0, &refs), r(m1, &refs), r(a, &refs));
                    quote!(#ft::mul_add(#x0, #x1, #y))
                } else {
                    let (x, y) = (r(a, &refs), r(b, &refs));
                    quote!(#x + #y)
                }
            }
            Node::Sub(a, b) => {
                ops.add += 1;
                if let Some((m0, m1)) = as_mul(a) {
                    let (x0, x1, y) = (r(m0, &refs), r(m1, &refs), r(b, &refs));
                    quote!(#ft::mul_add(#x0, #x1, -#y))
                } else if let Some((m0, m1)) = as_mul(b) {
                    let (x0, x1, y) = (r(m0, &refs), r(m1, &refs), r(a, &refs));
                    quote!(#ft::mul_add(-#x0, #x1, #y))
                } else {
                    let (x, y) = (r(a, &refs), r(b, &refs));
                    quote!(#x - #y)
                }
            }
            Node::Mul(a, b) => {
                ops.mul += 1;
                let (x, y) = (r(a, &refs), r(b, &refs));
                quote!(#x * #y)
            }
            Node::Div(a, b) => {
                ops.div += 1;
                let (x, y) = (r(a, &refs), r(b, &refs));
                quote!(#x / #y)
            }
            Node::Neg(a) => {
                ops.neg += 1;
                let x = r(a, &refs);
                quote!(-#x)
            }
            Node::Sqrt(a) => {
                ops.sqrt += 1;
                let x = r(a, &refs);
                quote!(#ft::sqrt(#x))
            }
            Node::Abs(a) => {
                ops.other += 1;
                let x = r(a, &refs);
                quote!(#ft::abs(#x))
            }
            Node::Min(a, b) => {
                ops.other += 1;
                let (x, y) = (r(a, &refs), r(b, &refs));
                quote!(#ft::min(#x, #y))
            }
            Node::Max(a, b) => {
                ops.other += 1;
                let (x, y) = (r(a, &refs), r(b, &refs));
                quote!(#ft::max(#x, #y))
            }
            Node::IfLt(a, b, t, f) => {
                ops.other += 1;
                let (x, y, tt, ff) = (r(a, &refs), r(b, &refs), r(t, &refs), r(f, &refs));
                quote!(if #x < #y { #tt } else { #ff })
            }
        };
        let t = fresh(&mut counter);
        stmts.push(quote!(let #t = #expr;));
        ops.temporaries += 1;
        refs[i] = Some(quote!(#t));
    }

    (
        Ssa {
            pre,
            stmts,
            refs,
            ops,
        },
        batched,
    )
}

/// Emit the whole scene module file (standard options).
#[allow(clippy::too_many_arguments)]
pub fn emit_file(
    scene_name: &str,
    nq: usize,
    params: &[(String, f64)],
    defs: &[KernelDef],
    source_text: &str,
    kernel_tokens: Vec<TokenStream>,
    with_contact: bool,
    trig_helper: bool,
) -> Result<String, CodegenError> {
    emit_file_with(
        scene_name,
        nq,
        params,
        defs,
        source_text,
        kernel_tokens,
        with_contact,
        trig_helper,
        &EmitSettings::default(),
    )
}

/// Emit the whole scene module file; `opts.float` sets the type of `PARAM_DEFAULTS`, of the
/// `Contact` fields and of `eval_flat` (the kernel tokens must use the same options);
/// `trig_helper` adds [`trig_items`] (needed when a kernel has [`EmittedKernel::fast_trig`]).
#[allow(clippy::too_many_arguments)]
pub fn emit_file_with(
    scene_name: &str,
    nq: usize,
    params: &[(String, f64)],
    defs: &[KernelDef],
    source_text: &str,
    kernel_tokens: Vec<TokenStream>,
    with_contact: bool,
    trig_helper: bool,
    opts: &EmitSettings,
) -> Result<String, CodegenError> {
    let ft = opts.float.tokens();
    let kernel_names: Vec<&str> = defs.iter().map(|d| d.name.as_str()).collect();
    let arms = defs.iter().map(eval_flat_arm);
    let into_arms = defs
        .iter()
        .enumerate()
        .map(|(i, d)| eval_into_arm(i, d, nq));
    let nq_l = Literal::usize_unsuffixed(nq);
    let np_l = Literal::usize_unsuffixed(params.len());
    let pnames = params.iter().map(|p| p.0.as_str());
    let pdefs = params.iter().map(|p| float_tokens(p.1, opts.float));
    let knames = kernel_names.iter();
    let contact = if with_contact {
        let fields = CONTACT_FIELDS.iter().map(|(f, dims, doc)| {
            let id = Ident::new(f, Span::call_site());
            let ty = array_type(dims, opts.float);
            let d = format!(" {doc}");
            quote!(#[doc = #d] pub #id: #ty,)
        });
        quote! {
            /// Contact geometry between the last link and the ball (paper Sect. 2.2),
            /// world axes, SI units. Filled by `contact` / `contact_smooth`.
            #[derive(Debug, Clone, Copy, Default, PartialEq)]
            pub struct Contact {
                #(#fields)*
            }
        }
    } else {
        TokenStream::new()
    };
    let trig = if trig_helper {
        trig_items()?
    } else {
        TokenStream::new()
    };
    let tokens = quote! {
        /// Number of joints.
        pub const NQ: usize = #nq_l;
        /// Number of runtime parameters.
        pub const NP: usize = #np_l;
        /// Names of the runtime parameters, in the order of `p`.
        pub const PARAM_NAMES: [&str; NP] = [#(#pnames),*];
        /// Default values of the runtime parameters (the values in the scene file).
        pub const PARAM_DEFAULTS: [#ft; NP] = [#(#pdefs),*];
        /// Names of the kernels emitted for this scene.
        pub const KERNELS: &[&str] = &[#(#knames),*];
        /// Name of the scene.
        pub const SCENE_NAME: &str = #scene_name;
        /// The scene file's text.
        pub const SCENE_TOML: &str = #source_text;
        #contact
        #trig
        #(#kernel_tokens)*
        /// Calls kernel `name` and returns all its outputs flattened row-major, in argument
        /// order (`Contact` fields in declaration order); `None` if `name` is not in `KERNELS`.
        /// Kernels taking `qdd` or `tau` get zeros (see `eval_flat_u`).
        /// For tests and the CLI: unlike the kernels, this allocates.
        pub fn eval_flat(
            name: &str,
            q: &[#ft; NQ],
            qd: &[#ft; NQ],
            omega: &[#ft; 3],
            eps: #ft,
            p: &[#ft; NP],
        ) -> Option<Vec<#ft>> {
            eval_flat_u(name, q, qd, omega, eps, &[0.0; NQ], p)
        }
        /// As `eval_flat`, with `u` passed as the `qdd` (inverse dynamics, its derivatives and
        /// the regressor) or `tau` (forward dynamics) argument of the kernels that take one.
        #[allow(unused_variables)]
        pub fn eval_flat_u(
            name: &str,
            q: &[#ft; NQ],
            qd: &[#ft; NQ],
            omega: &[#ft; 3],
            eps: #ft,
            u: &[#ft; NQ],
            p: &[#ft; NP],
        ) -> Option<Vec<#ft>> {
            let mut v = Vec::new();
            match name {
                #(#arms)*
                _ => return None,
            }
            Some(v)
        }
        /// Calls kernel `KERNELS[k]` with outputs on the stack and copies them, flattened as by
        /// `eval_flat_u`, into the front of `out`; returns their number, or `None` if `k` is out
        /// of range or `out` too short. Does not allocate (for benchmarks).
        #[allow(unused_variables, clippy::too_many_arguments)]
        pub fn eval_index_into(
            k: usize,
            q: &[#ft; NQ],
            qd: &[#ft; NQ],
            omega: &[#ft; 3],
            eps: #ft,
            u: &[#ft; NQ],
            p: &[#ft; NP],
            out: &mut [#ft],
        ) -> Option<usize> {
            match k {
                #(#into_arms)*
                _ => None,
            }
        }
    };
    let file: syn::File = syn::parse2(tokens).map_err(CodegenError::unparsable("emitted code"))?;
    let body = prettyplease::unparse(&file);
    let mut out = String::new();
    out.push_str("// @generated by bf-codegen from scene `");
    out.push_str(scene_name);
    out.push_str("`. Do not edit: regenerate with `ball-finger generate`.\n");
    out.push_str(
        "// Conventions: standard DH unless the scene says otherwise, world axes, SI units,\n\
         // matrices row-major (see docs/kernels.md).\n",
    );
    out.push_str(&body);
    Ok(out)
}
