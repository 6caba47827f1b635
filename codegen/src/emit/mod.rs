//! Rust emitter: graph cone of a kernel → SSA `let` bindings (module `ssa`; one operation per
//! binding, which avoids the token-pasting precedence pitfall, `docs/architecture.md`,
//! "Emit"). The bindings of the dynamics kernels are printed as text in the layout
//! `prettyplease` gives them; the signatures, docs and the file's other items go through
//! `quote!` tokens → `syn::File` → `prettyplease`. The node kernels (`crate::nodefn`) print
//! their bindings the same way (`body_text`). Constants are printed with Rust's shortest
//! round-trip formatting, so every `f64` survives exactly. In `f64` kernels the sines and
//! cosines of all joint angles come from one call of the vectorised helper `sin_cos_n`
//! ([`crate::trig`], emitted once per file by [`trig_items`]); elsewhere sin/cos of one
//! argument share a `sin_cos` call. The batched node kernels put the scalar body in a loop
//! over four lanes (`body_text`).
//!
//! [`EmitSettings`] select variants for accuracy/speed studies: the float type
//! ([`FloatTy::F32`] rounds every constant and operation to single precision) and fused
//! multiply-add (`a*b ± c` as `mul_add`, one rounding instead of two) and `no_std` (the
//! module compiles in a `#![no_std]` crate: [`crate::trig_nostd`]). The defaults reproduce
//! the plain f64 output byte for byte.

use std::fmt::Write as _;
use std::str::FromStr;
use std::sync::OnceLock;

use proc_macro2::{Ident, Literal, Span, TokenStream};
use quote::quote;

use crate::graph::{Graph, Id};
use crate::kernels::{Arg, CONTACT_FIELDS, Dim, KernelDef, OutKind};
use crate::report::OpCounts;
use crate::robot::Layout;
use crate::{CodegenError, InternalDefect};

mod dispatch;
mod ssa;
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
    /// A module for a `#![no_std]` crate: it carries its own square root, sine and cosine
    /// ([`crate::trig_nostd`]; the kernel bodies are the same text) and leaves out `eval_flat`
    /// and `eval_flat_u`, which allocate. Not with `fma` (`core` has no fused multiply-add).
    pub no_std: bool,
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

/// Kernels with at most this many temporaries are marked `#[inline]`.
pub const INLINE_MAX_TEMPORARIES: usize = 1000;

/// Whether the kernels of a module are put in submodules of their own.
///
/// `rustc` assigns all functions of one module to one code-generation unit and optimises
/// units in parallel, one per core; a scene module in one piece optimises its kernels one
/// after the other (a 20-joint chain: three kernels of 14 000–18 000 operations, LLVM about
/// 80 % of its 16 s of `rustc` CPU, all on one core). A kernel in a submodule of its own (`mod kernel_NAME { use
/// super::*; … }`, re-exported by `pub use`) is a unit of its own, so the kernels of a large
/// module compile side by side. The kernel bodies are the same text either way.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum ModuleSplit {
    /// [`ModuleSplit::Large`] when the module's kernels have more than
    /// [`SPLIT_MIN_TEMPORARIES`] temporaries in all, else [`ModuleSplit::Never`]: smaller
    /// modules (every shipped scene) keep their one-unit form, and their text, since a few
    /// seconds of LLVM already run beside the other modules of the crate.
    #[default]
    Auto,
    /// Every kernel in the module's own scope (the form of the shipped scenes).
    Never,
    /// Every kernel with more than [`INLINE_MAX_TEMPORARIES`] temporaries (one not marked
    /// `#[inline]`, so compiled where it is defined) in a submodule of its own.
    Large,
    /// Every kernel in a submodule of its own.
    All,
}

/// The total of temporaries over a module's kernels above which [`ModuleSplit::Auto`] splits
/// it (the largest shipped scene module, the 7-joint iiwa, has 36 736; a random 20-joint
/// chain 56 000).
pub const SPLIT_MIN_TEMPORARIES: usize = 40_000;

impl ModuleSplit {
    /// For each kernel (given its number of temporaries), whether it gets a submodule.
    pub fn which(self, temporaries: &[usize]) -> Vec<bool> {
        let large = |t: &usize| *t > INLINE_MAX_TEMPORARIES;
        match self {
            ModuleSplit::Auto if temporaries.iter().sum::<usize>() > SPLIT_MIN_TEMPORARIES => {
                temporaries.iter().map(large).collect()
            }
            ModuleSplit::Auto | ModuleSplit::Never => vec![false; temporaries.len()],
            ModuleSplit::Large => temporaries.iter().map(large).collect(),
            ModuleSplit::All => vec![true; temporaries.len()],
        }
    }
}

/// The kernel item `code` (of function `name`) inside a private module `kernel_NAME` that
/// sees the file's items (`use super::*`: `NQ`, `Contact`, the sine–cosine helpers), plus the
/// `pub use` that puts the function back where callers look for it.
pub fn own_module(name: &str, code: &str) -> String {
    let mut out = String::with_capacity(code.len() + code.len() / 16 + 256);
    let _ = writeln!(
        out,
        "/// Kernel `{name}` in a module of its own: a code-generation unit of its own for \
         `rustc`.\n#[allow(unused_imports)]\nmod kernel_{name} {{\n    use super::*;"
    );
    for line in code.lines() {
        if !line.is_empty() {
            out.push_str("    ");
        }
        out.push_str(line);
        out.push('\n');
    }
    let _ = writeln!(out, "}}\npub use kernel_{name}::{name};");
    out
}

/// One emitted kernel: its function item as formatted text, plus its operation counts.
pub struct EmittedKernel {
    /// The function item (doc comment, attributes, signature, body), formatted as
    /// `prettyplease` formats it, ending in a newline.
    pub code: String,
    /// Operation counts.
    pub ops: OpCounts,
    /// Whether the kernel computes a sine or cosine, with the helpers of [`trig_items`]
    /// (`sin_cos_n`, `sin_cos`, `sin_cos_f32`), which the file must then define.
    pub trig: bool,
}

/// Writes the text of graph variable `v` of a dynamics kernel (`q[i]`, `qd[i]`, `omega[i]`,
/// `eps`, `p[i]`, `qdd[i]`, `tau[i]`).
fn write_var(out: &mut String, layout: &Layout, v: u32) {
    let v = v as usize;
    let nq = layout.nq;
    let (name, i) = if v < nq {
        ("q", v)
    } else if v < 2 * nq {
        ("qd", v - nq)
    } else if v < 2 * nq + 3 {
        ("omega", v - 2 * nq)
    } else if v == 2 * nq + 3 {
        out.push_str("eps");
        return;
    } else if v < layout.n_vars() {
        ("p", v - 2 * nq - 4)
    } else if v < layout.n_vars() + nq {
        ("qdd", v - layout.n_vars())
    } else {
        ("tau", v - layout.n_vars() - nq)
    };
    out.push_str(name);
    out.push('[');
    ssa::push_u32(out, i as u32);
    out.push(']');
}

/// Element access paths (`[i][j]` suffixes) of an array with `dims`, row-major, as text.
fn index_texts(dims: &[Dim], nq: usize) -> Vec<String> {
    let mut paths = vec![String::new()];
    for &d in dims {
        let n = dim_value(d, nq);
        let mut next = Vec::with_capacity(paths.len() * n);
        for p in &paths {
            for i in 0..n {
                next.push(format!("{p}[{i}]"));
            }
        }
        paths = next;
    }
    paths
}

/// The placeholder statement of a kernel's body while its signature is formatted.
pub(crate) const BODY_MARKER: &str = "__bf_codegen_body__";

/// Emit one kernel as a Rust function (standard options).
pub fn emit_kernel(
    g: &Graph,
    layout: &Layout,
    k: &KernelDef,
) -> Result<EmittedKernel, CodegenError> {
    emit_kernel_with(g, layout, k, &EmitSettings::default())
}

/// Emit one kernel as a Rust function with the variant `opts`.
///
/// The body is printed as text (module `ssa`); the doc comment, attributes and signature are
/// formatted by `prettyplease` around a placeholder statement that the body then replaces.
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
    let ir = ssa::build(g, &roots, opts, true, false);
    let ops = ir.ops;
    let var = |out: &mut String, v: u32| write_var(out, layout, v);
    let printer = ssa::TextPrinter {
        ft: opts.float,
        var: &var,
    };
    let mut body = String::with_capacity(32 * (ir.stmts.len() + roots.len()));
    for s in &ir.stmts {
        ssa::write_stmt(&mut body, &printer, s, 4);
    }

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
    let mut line = String::new();
    let mut assign = |body: &mut String, lhs: std::fmt::Arguments, id: Id| {
        let v = ir.refs[id.index()].expect("internal: output not emitted");
        line.clear();
        let _ = write!(line, "{lhs} = ");
        printer.operand(&mut line, v);
        line.push(';');
        ssa::push_line(body, &line, 4);
    };
    for o in &k.outputs {
        let name = Ident::new(&o.name, Span::call_site());
        match &o.kind {
            OutKind::Scalar => {
                params.push(quote!(#name: &mut #ft));
                assign(&mut body, format_args!("*{}", o.name), o.ids[0]);
            }
            OutKind::Array(dims) => {
                let ty = array_type(dims, opts.float);
                params.push(quote!(#name: &mut #ty));
                for (path, &id) in index_texts(dims, layout.nq).iter().zip(&o.ids) {
                    assign(&mut body, format_args!("{}{path}", o.name), id);
                }
            }
            OutKind::Contact => {
                params.push(quote!(#name: &mut Contact));
                let mut it = o.ids.iter();
                for (field, dims, _) in CONTACT_FIELDS {
                    for path in index_texts(dims, layout.nq) {
                        let id =
                            *it.next()
                                .ok_or(CodegenError::Internal(InternalDefect::Other(
                                    "contact output size mismatch",
                                )))?;
                        assign(&mut body, format_args!("{}.{field}{path}", o.name), id);
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
    let marker = Ident::new(BODY_MARKER, Span::call_site());
    let tokens = quote! {
        #(#docs)*
        #inline
        #[allow(unused_variables)]
        pub fn #fname(#(#params),*) {
            #marker;
        }
    };
    let code = splice_bodies(tokens, "emitted kernel", &[(BODY_MARKER, 4, &body)])?;
    Ok(EmittedKernel {
        code,
        ops,
        trig: ir.uses_trig(),
    })
}

/// Parses `tokens` as items and formats them with `prettyplease`; `what` names them in the
/// error.
fn unparse(tokens: TokenStream, what: &'static str) -> Result<String, CodegenError> {
    let file: syn::File = syn::parse2(tokens).map_err(CodegenError::unparsable(what))?;
    Ok(prettyplease::unparse(&file))
}

/// The helper items that kernels with [`EmittedKernel::trig`] call (`sin_cos_n`, `sin_cos`
/// and the reductions behind them, and in an f32 file `sin_cos_n_f32` and `sin_cos_f32`, from
/// [`crate::trig`]), as
/// private items for a generated file of kernels of type `ft`, each allowed to be unused;
/// emitted once per file. They are plain arithmetic: no kernel calls the platform's libm.
pub fn trig_items(ft: FloatTy) -> Result<TokenStream, CodegenError> {
    Ok(trig_fns(ft, true)?
        .into_iter()
        .map(|f| quote!(#f))
        .collect())
}

/// The functions of [`crate::trig`] for a file of type `ft`, private and allowed to be unused,
/// with their doc comments if `docs`.
fn trig_fns(ft: FloatTy, docs: bool) -> Result<Vec<syn::ItemFn>, CodegenError> {
    let file: syn::File =
        syn::parse_str(include_str!("../trig.rs")).map_err(CodegenError::unparsable("trig.rs"))?;
    let allow: syn::Attribute = syn::parse_quote!(#[allow(dead_code)]);
    Ok(file
        .items
        .into_iter()
        .filter_map(|item| match item {
            // The f32 helpers are named `*_f32`; an f64 file has no use for them.
            syn::Item::Fn(f)
                if ft == FloatTy::F32 || !f.sig.ident.to_string().ends_with("_f32") =>
            {
                Some(f)
            }
            _ => None,
        })
        .map(|mut f| {
            f.vis = syn::Visibility::Inherited;
            if !docs {
                f.attrs.retain(|a| !a.path().is_ident("doc"));
            }
            f.attrs.push(allow.clone());
            f
        })
        .collect())
}

/// [`trig_items`] formatted by `prettyplease`; the same text for every file of one float
/// type, so formatted once per process.
fn trig_text(ft: FloatTy) -> Result<&'static str, CodegenError> {
    static TEXT: [OnceLock<Result<String, String>>; 2] = [OnceLock::new(), OnceLock::new()];
    TEXT[ft as usize]
        .get_or_init(|| {
            trig_items(ft)
                .and_then(|t| unparse(t, "trig.rs"))
                .map_err(|e| e.to_string())
        })
        .as_deref()
        .map_err(|_| CodegenError::Internal(InternalDefect::Other("trig.rs does not format")))
}

/// The helper items of a `#![no_std]` file of type `ft`, formatted: [`trig_items`] and
/// [`crate::trig_nostd`]'s items (the square root and the trait
/// [`crate::trig_nostd::KernelMath`] the kernels call it through), all private and allowed to
/// be unused (a kernel without square roots leaves some of them unused), without the doc
/// comments of [`crate::trig`].
fn nostd_text(ft: FloatTy) -> Result<&'static str, CodegenError> {
    static TEXT: [OnceLock<Result<String, String>>; 2] = [OnceLock::new(), OnceLock::new()];
    TEXT[ft as usize]
        .get_or_init(|| nostd_items(ft).map_err(|e| e.to_string()))
        .as_deref()
        .map_err(|_| CodegenError::Internal(InternalDefect::Other("trig_nostd.rs does not format")))
}

fn nostd_items(ft: FloatTy) -> Result<String, CodegenError> {
    let nostd: syn::File = syn::parse_str(include_str!("../trig_nostd.rs"))
        .map_err(CodegenError::unparsable("trig_nostd.rs"))?;
    let allow: syn::Attribute = syn::parse_quote!(#[allow(dead_code)]);
    let mut out: TokenStream = trig_fns(ft, false)?
        .into_iter()
        .map(|f| quote!(#f))
        .collect();
    for mut item in nostd.items {
        match &mut item {
            syn::Item::Fn(f) => {
                f.vis = syn::Visibility::Inherited;
                f.attrs.push(allow.clone());
            }
            syn::Item::Trait(t) => {
                t.vis = syn::Visibility::Inherited;
                t.attrs.push(allow.clone());
            }
            syn::Item::Impl(_) => {}
            _ => continue,
        }
        out.extend(quote!(#item));
    }
    Ok(unparse(out, "trig_nostd.rs")?.replace("std::f64::consts::", "core::f64::consts::"))
}

/// A kernel body as text: statements before the lane loop (only with `lanes`), the
/// statements and output assignments, and the operation counts.
pub(crate) struct BodyText {
    /// Statements before the lane loop, indented for the function body.
    pub(crate) pre: String,
    /// Statements and output assignments, indented for the function body (or, with
    /// `lanes`, for the loop's body).
    pub(crate) body: String,
    /// Operation counts.
    pub(crate) ops: OpCounts,
}

/// The `let` bindings of the cone of `roots` and the assignment of every root, as text;
/// graph variables are printed by `var`, and `lhs(out, k)` writes the place root `k` is
/// assigned to. For the OCP node kernels (`crate::nodefn`): every node is computed with the
/// same `f64` operation as in the dynamics kernels and the interpreter, sin/cos by the file's
/// one-angle `sin_cos` ([`crate::trig`]).
///
/// With `lanes` (f64 only), the statements are the body of a loop over four lanes `l` (`var`
/// must then name lane `l`'s value): the batched (`_x4`) node kernels evaluate four
/// collocation nodes with the nodes' entries interleaved (node `l`'s entry `k` at `4·k + l`),
/// so every load and store of the loop is unit-stride in `l` and LLVM's loop vectoriser turns
/// it into SIMD code (SSE2 on the baseline x86-64 target, no `unsafe`), each lane computing
/// exactly the scalar kernel's operations. Calls inside the loop would keep it scalar, so
/// every sine and cosine of a graph variable is computed before the loop, four lanes per angle
/// by one `sin_cos_n` call (each lane bitwise the one-angle `sin_cos`), in [`BodyText::pre`],
/// and read as `name[l]` in the loop.
pub(crate) fn body_text(
    g: &Graph,
    roots: &[Id],
    var: &dyn Fn(&mut String, u32),
    lhs: &dyn Fn(&mut String, usize),
    opts: &EmitSettings,
    lanes: bool,
) -> BodyText {
    let ir = ssa::build(g, roots, opts, false, lanes);
    let printer = ssa::TextPrinter {
        ft: opts.float,
        var,
    };
    let lanes = lanes && opts.float == FloatTy::F64;
    let indent = if lanes { 8 } else { 4 };
    let mut pre = String::new();
    for s in &ir.pre {
        ssa::write_stmt(&mut pre, &printer, s, 4);
    }
    let mut body = String::with_capacity(32 * (ir.stmts.len() + roots.len()));
    for s in &ir.stmts {
        ssa::write_stmt(&mut body, &printer, s, indent);
    }
    let mut line = String::new();
    for (k, id) in roots.iter().enumerate() {
        line.clear();
        lhs(&mut line, k);
        line.push_str(" = ");
        match ir.refs[id.index()] {
            Some(v) => printer.operand(&mut line, v),
            None => ssa::write_float(&mut line, 0.0, opts.float),
        }
        line.push(';');
        ssa::push_line(&mut body, &line, indent);
    }
    BodyText {
        pre,
        body,
        ops: ir.ops,
    }
}

/// Formats the item `tokens` with `prettyplease` and replaces each placeholder statement
/// `marker;` of its body (a path expression statement, at the given indentation) by the text
/// that goes with it: so that large bodies printed as text need no round trip through `syn`.
pub(crate) fn splice_bodies(
    tokens: TokenStream,
    what: &'static str,
    bodies: &[(&str, usize, &str)],
) -> Result<String, CodegenError> {
    let mut item = unparse(tokens, what)?;
    for &(marker, indent, text) in bodies {
        let line = format!("{:indent$}{marker};\n", "");
        let at = item.find(&line).ok_or_else(|| {
            CodegenError::Internal(InternalDefect::MissingPlaceholder {
                what,
                marker: marker.to_string(),
            })
        })?;
        item.replace_range(at..at + line.len(), text);
    }
    Ok(item)
}

/// Emit the whole scene module file (standard options).
#[allow(clippy::too_many_arguments)]
pub fn emit_file(
    scene_name: &str,
    nq: usize,
    params: &[(String, f64)],
    defs: &[KernelDef],
    source_text: &str,
    kernel_code: &[String],
    with_contact: bool,
    trig_helper: bool,
) -> Result<String, CodegenError> {
    emit_file_with(
        scene_name,
        nq,
        params,
        defs,
        source_text,
        kernel_code,
        with_contact,
        trig_helper,
        &EmitSettings::default(),
    )
}

/// Emit the whole scene module file around the kernels' items `kernel_code`
/// ([`EmittedKernel::code`]); `opts.float` sets the type of `PARAM_DEFAULTS`, of the
/// `Contact` fields and of `eval_flat` (the kernels must use the same options);
/// `trig_helper` adds [`trig_items`] (needed when a kernel has [`EmittedKernel::trig`]).
#[allow(clippy::too_many_arguments)]
pub fn emit_file_with(
    scene_name: &str,
    nq: usize,
    params: &[(String, f64)],
    defs: &[KernelDef],
    source_text: &str,
    kernel_code: &[String],
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
    let trig = if opts.no_std {
        nostd_text(opts.float)?
    } else if trig_helper {
        trig_text(opts.float)?
    } else {
        ""
    };
    // The items before and after the kernels are formatted separately: `prettyplease` prints
    // the items of a file one after the other, so the kernels' text fits between them.
    let head = quote! {
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
    };
    let flat = quote! {
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
    };
    // `eval_flat` allocates: a no_std module has only `eval_index_into`.
    let flat = if opts.no_std {
        TokenStream::new()
    } else {
        flat
    };
    let tail = quote! {
        #flat
        /// Calls kernel `KERNELS[k]` with outputs on the stack and copies them, flattened
        /// row-major in argument order (`Contact` fields in declaration order), into the front
        /// of `out`; returns their number, or `None` if `k` is out of range or `out` too short.
        /// Does not allocate (for benchmarks).
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
    let head = unparse(head, "emitted code")?;
    let tail = unparse(tail, "emitted code")?;
    let kernels_len: usize = kernel_code.iter().map(String::len).sum();
    let mut out = String::with_capacity(head.len() + trig.len() + kernels_len + tail.len() + 256);
    out.push_str("// @generated by bf-codegen from scene `");
    out.push_str(scene_name);
    out.push_str("`. Do not edit: regenerate with `ball-finger generate`.\n");
    out.push_str(
        "// Conventions: standard DH unless the scene says otherwise, world axes, SI units,\n\
         // matrices row-major (see docs/kernels.md).\n",
    );
    if opts.no_std {
        out.push_str(
            "// For #![no_std] crates: own square root (trait `KernelMath`), no allocation.\n",
        );
    }
    out.push_str(&head);
    out.push_str(trig);
    for k in kernel_code {
        out.push_str(k);
    }
    out.push_str(&tail);
    Ok(out)
}
