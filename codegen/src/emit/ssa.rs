//! The SSA form of a kernel body, independent of how it is printed: [`build`] walks the cone
//! of the kernel's outputs in node order and decides every statement (which sines and cosines
//! share a call, which products fuse into `mul_add`, the temporaries' numbers);
//! [`write_stmt`] prints a statement as the text `prettyplease` would print for it (the test
//! below prints every statement form as tokens too, and compares).
//!
//! Printing kernel bodies as text directly is what keeps generation fast: a body has thousands
//! of `let` statements, and building their tokens, parsing them with `syn` and formatting
//! them with `prettyplease` cost about ten times the graph work (BENCHMARKS.md, "Generated
//! kernels: evaluation and generation times"). Statements longer than [`ONE_LINE_MAX`]
//! columns (only the `sin_cos_n` call of many angles) are formatted by `prettyplease`, which
//! then breaks them as it would in a whole file.

use std::fmt::Write as _;

use super::{EmitSettings, FloatTy};
use crate::graph::{Graph, Id, Node};
use crate::report::OpCounts;

/// A value a statement reads: a temporary, a lane of a per-lane temporary, a graph variable
/// (printed by the caller) or a constant.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) enum Operand {
    /// `t{n}`.
    Temp(u32),
    /// `t{n}[l]`: lane `l` of a temporary computed before the lane loop.
    LaneTemp(u32),
    /// Graph variable `v`.
    Var(u32),
    /// A constant (its bits are printed exactly).
    Const(f64),
}

/// The right-hand side of `let t{n} = …;`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) enum Expr {
    Add(Operand, Operand),
    Sub(Operand, Operand),
    Mul(Operand, Operand),
    Div(Operand, Operand),
    Neg(Operand),
    Sqrt(Operand),
    Abs(Operand),
    Min(Operand, Operand),
    Max(Operand, Operand),
    Sin(Operand),
    Cos(Operand),
    /// `if a < b { t } else { f }`.
    IfLt(Operand, Operand, Operand, Operand),
    /// `mul_add(±x0, x1, ±y)` = ±x0·x1 ± y with one rounding.
    MulAdd {
        x0: Operand,
        x1: Operand,
        y: Operand,
        neg_x0: bool,
        neg_y: bool,
    },
}

/// One statement of a kernel body.
#[derive(Debug, Clone, PartialEq)]
pub(crate) enum Stmt {
    /// `let t{n} = expr;`.
    Let(u32, Expr),
    /// `let (t{s}, t{c}) = ft::sin_cos(x);`.
    SinCos { s: u32, c: u32, x: Operand },
    /// `let ([t{s0}, …], [t{c0}, …]) = sin_cos_n([x0, …]);`: `sc[i]` are the temporaries of
    /// the sine and cosine of `args[i]`.
    SinCosN {
        sc: Vec<(u32, u32)>,
        args: Vec<Operand>,
    },
    /// `let (t{s}, t{c}) = sin_cos_n::<4>(std::array::from_fn(|l| x));` (before a lane loop: the
    /// angle's four lanes).
    SinCosLanes { s: u32, c: u32, x: Operand },
}

/// A kernel body in SSA form: statements before the lane loop (only with lanes), the
/// statements, the operand that names each node's value (`refs[i]`, `None` outside the cone),
/// and the operation counts.
pub(crate) struct SsaIr {
    pub(crate) pre: Vec<Stmt>,
    pub(crate) stmts: Vec<Stmt>,
    pub(crate) refs: Vec<Option<Operand>>,
    pub(crate) ops: OpCounts,
}

/// The SSA statements of the cone of `roots`, in node order. With `batch_trig`, every sine
/// and cosine of a graph variable (the joint angles) comes from one `sin_cos_n` call at the
/// top (`sin_cos_n_f32` in f32 kernels); other sin/cos call the one-angle helper (`sin_cos` or
/// `sin_cos_f32`, [`crate::trig`]), sin and cos of one argument sharing a call. With
/// `lanes` (f64 only; `batch_trig` then does not apply), the statements are the body of a
/// loop over four lanes and the sines and cosines of graph variables are computed before it
/// four lanes per `sin_cos_n` call ([`SsaIr::pre`]), read as `t{n}[l]`.
pub(crate) fn build(
    g: &Graph,
    roots: &[Id],
    opts: &EmitSettings,
    batch_trig: bool,
    lanes: bool,
) -> SsaIr {
    let lanes = lanes && opts.float == FloatTy::F64;
    let batch_trig = batch_trig && !lanes;
    // Product operands of a Mul node that a later Add/Sub may fuse (only when FMA is on).
    let as_mul = |id: Id| -> Option<(Id, Id)> {
        match g.node(id) {
            Node::Mul(a, b) if opts.fma => Some((a, b)),
            _ => None,
        }
    };
    let mark = g.cone(roots);
    let max = roots.iter().map(|r| r.index() + 1).max().unwrap_or(0);
    let mut refs: Vec<Option<Operand>> = vec![None; max];
    let mut stmts: Vec<Stmt> = Vec::with_capacity(max);
    let mut pre: Vec<Stmt> = Vec::new();
    let mut ops = OpCounts::default();
    let mut counter = 0u32;
    let mut fresh = || {
        counter += 1;
        counter - 1
    };
    if batch_trig || lanes {
        // The angles (graph variables) whose sin or cos is in the cone, in node order.
        let mut angles: Vec<Id> = Vec::new();
        let mut args: Vec<Operand> = Vec::new();
        for i in 0..max {
            if let Node::Sin(a) | Node::Cos(a) = g.node(Id(i as u32))
                && mark[i]
                && let Node::Var(v) = g.node(a)
                && !angles.contains(&a)
            {
                angles.push(a);
                args.push(Operand::Var(v));
            }
        }
        if !angles.is_empty() {
            let sc: Vec<(u32, u32)> = angles.iter().map(|_| (fresh(), fresh())).collect();
            if lanes {
                for (&(s, c), &x) in sc.iter().zip(&args) {
                    pre.push(Stmt::SinCosLanes { s, c, x });
                }
            } else {
                stmts.push(Stmt::SinCosN {
                    sc: sc.clone(),
                    args,
                });
            }
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
                    let t = if is_sin { sc[j].0 } else { sc[j].1 };
                    refs[i] = Some(if lanes {
                        Operand::LaneTemp(t)
                    } else {
                        Operand::Temp(t)
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
        let r = |id: Id, refs: &[Option<Operand>]| -> Operand {
            refs[id.index()].expect("internal: child emitted before parent")
        };
        let expr = match node {
            Node::Const(b) => {
                refs[i] = Some(Operand::Const(f64::from_bits(b)));
                continue;
            }
            Node::Var(v) => {
                refs[i] = Some(Operand::Var(v));
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
                        let (s, c) = (fresh(), fresh());
                        stmts.push(Stmt::SinCos { s, c, x });
                        ops.temporaries += 2;
                        let (si, ci) = if is_sin { (i, j) } else { (j, i) };
                        refs[si] = Some(Operand::Temp(s));
                        refs[ci] = Some(Operand::Temp(c));
                    }
                    None => {
                        let t = fresh();
                        let e = if is_sin { Expr::Sin(x) } else { Expr::Cos(x) };
                        stmts.push(Stmt::Let(t, e));
                        ops.temporaries += 1;
                        refs[i] = Some(Operand::Temp(t));
                    }
                }
                continue;
            }
            Node::Add(a, b) | Node::Sub(a, b) => {
                ops.add += 1;
                let sub = matches!(node, Node::Sub(..));
                if let Some((m0, m1)) = as_mul(a) {
                    Expr::MulAdd {
                        x0: r(m0, &refs),
                        x1: r(m1, &refs),
                        y: r(b, &refs),
                        neg_x0: false,
                        neg_y: sub,
                    }
                } else if let Some((m0, m1)) = as_mul(b) {
                    Expr::MulAdd {
                        x0: r(m0, &refs),
                        x1: r(m1, &refs),
                        y: r(a, &refs),
                        neg_x0: sub,
                        neg_y: false,
                    }
                } else if sub {
                    Expr::Sub(r(a, &refs), r(b, &refs))
                } else {
                    Expr::Add(r(a, &refs), r(b, &refs))
                }
            }
            Node::Mul(a, b) => {
                ops.mul += 1;
                Expr::Mul(r(a, &refs), r(b, &refs))
            }
            Node::Div(a, b) => {
                ops.div += 1;
                Expr::Div(r(a, &refs), r(b, &refs))
            }
            Node::Neg(a) => {
                ops.neg += 1;
                Expr::Neg(r(a, &refs))
            }
            Node::Sqrt(a) => {
                ops.sqrt += 1;
                Expr::Sqrt(r(a, &refs))
            }
            Node::Abs(a) => {
                ops.other += 1;
                Expr::Abs(r(a, &refs))
            }
            Node::Min(a, b) => {
                ops.other += 1;
                Expr::Min(r(a, &refs), r(b, &refs))
            }
            Node::Max(a, b) => {
                ops.other += 1;
                Expr::Max(r(a, &refs), r(b, &refs))
            }
            Node::IfLt(a, b, t, f) => {
                ops.other += 1;
                Expr::IfLt(r(a, &refs), r(b, &refs), r(t, &refs), r(f, &refs))
            }
        };
        let t = fresh();
        stmts.push(Stmt::Let(t, expr));
        ops.temporaries += 1;
        refs[i] = Some(Operand::Temp(t));
    }
    SsaIr {
        pre,
        stmts,
        refs,
        ops,
    }
}

impl SsaIr {
    /// Whether the body computes a sine or cosine, and so calls the helpers of
    /// [`crate::trig`] that its file must carry.
    pub(crate) fn uses_trig(&self) -> bool {
        self.pre.iter().chain(&self.stmts).any(|s| match s {
            Stmt::Let(_, e) => matches!(e, Expr::Sin(_) | Expr::Cos(_)),
            Stmt::SinCos { .. } | Stmt::SinCosN { .. } | Stmt::SinCosLanes { .. } => true,
        })
    }
}

/// Statements whose one-line text (indentation included) is longer than this are formatted by
/// `prettyplease`. Below it, `prettyplease` prints every statement form of [`Stmt`] on one line
/// (its margin is 89 columns; the test `text_is_what_prettyplease_prints` checks the forms).
pub(crate) const ONE_LINE_MAX: usize = 80;

/// The name of the float type.
fn float_name(ft: FloatTy) -> &'static str {
    match ft {
        FloatTy::F64 => "f64",
        FloatTy::F32 => "f32",
    }
}

/// The helper that computes `(sin x, cos x)` in kernels of type `ft`: [`crate::trig::sin_cos`]
/// or [`crate::trig::sin_cos_f32`], emitted into every file whose kernels call it, so that no
/// kernel depends on the platform's libm (whose results differ between CPUs).
fn sin_cos_name(ft: FloatTy) -> &'static str {
    match ft {
        FloatTy::F64 => "sin_cos",
        FloatTy::F32 => "sin_cos_f32",
    }
}

/// The batched helper of the joint angles' sines and cosines in kernels of type `ft`:
/// [`crate::trig::sin_cos_n`] or [`crate::trig::sin_cos_n_f32`] (each lane bitwise the
/// one-angle helper of [`sin_cos_name`]).
fn sin_cos_n_name(ft: FloatTy) -> &'static str {
    match ft {
        FloatTy::F64 => "sin_cos_n",
        FloatTy::F32 => "sin_cos_n_f32",
    }
}

/// Writes the literal of `v` as `float_tokens` prints it.
pub(crate) fn write_float(out: &mut String, v: f64, ft: FloatTy) {
    let t = float_name(ft);
    if v.is_nan() {
        let _ = write!(out, "{t}::NAN");
    } else if v.is_infinite() {
        let _ = write!(
            out,
            "{t}::{}",
            if v > 0.0 { "INFINITY" } else { "NEG_INFINITY" }
        );
    } else {
        if v < 0.0 {
            out.push('-');
        }
        let _ = write!(out, "{:?}", v.abs());
    }
}

/// Appends the decimal digits of `n` (as `{n}` formats it, without the formatting machinery:
/// the bodies print hundreds of thousands of temporaries' numbers).
pub(crate) fn push_u32(out: &mut String, mut n: u32) {
    let mut digits = [0u8; 10];
    let mut i = digits.len();
    loop {
        i -= 1;
        digits[i] = b'0' + (n % 10) as u8;
        n /= 10;
        if n == 0 {
            break;
        }
    }
    for &d in &digits[i..] {
        out.push(d as char);
    }
}

/// Prints operands; `var` prints graph variables.
pub(crate) struct TextPrinter<'a> {
    pub(crate) ft: FloatTy,
    pub(crate) var: &'a dyn Fn(&mut String, u32),
}

impl TextPrinter<'_> {
    /// Writes operand `o`.
    pub(crate) fn operand(&self, out: &mut String, o: Operand) {
        match o {
            Operand::Temp(n) => {
                out.push('t');
                push_u32(out, n);
            }
            Operand::LaneTemp(n) => {
                out.push('t');
                push_u32(out, n);
                out.push_str("[l]");
            }
            Operand::Var(v) => (self.var)(out, v),
            Operand::Const(c) => write_float(out, c, self.ft),
        }
    }

    fn call(&self, out: &mut String, f: &str, args: &[Operand]) {
        out.push_str(float_name(self.ft));
        out.push_str("::");
        out.push_str(f);
        out.push('(');
        self.operands(out, args);
        out.push(')');
    }

    /// `args` separated by `, `.
    fn operands(&self, out: &mut String, args: &[Operand]) {
        for (k, &a) in args.iter().enumerate() {
            if k > 0 {
                out.push_str(", ");
            }
            self.operand(out, a);
        }
    }

    fn binary(&self, out: &mut String, a: Operand, op: &str, b: Operand) {
        self.operand(out, a);
        out.push_str(op);
        self.operand(out, b);
    }

    fn expr(&self, out: &mut String, e: &Expr) {
        match *e {
            Expr::Add(a, b) => self.binary(out, a, " + ", b),
            Expr::Sub(a, b) => self.binary(out, a, " - ", b),
            Expr::Mul(a, b) => self.binary(out, a, " * ", b),
            Expr::Div(a, b) => self.binary(out, a, " / ", b),
            Expr::Neg(a) => {
                out.push('-');
                self.operand(out, a);
            }
            Expr::Sqrt(a) => self.call(out, "sqrt", &[a]),
            Expr::Abs(a) => self.call(out, "abs", &[a]),
            Expr::Min(a, b) => self.call(out, "min", &[a, b]),
            Expr::Max(a, b) => self.call(out, "max", &[a, b]),
            Expr::Sin(a) | Expr::Cos(a) => {
                out.push_str(sin_cos_name(self.ft));
                out.push('(');
                self.operand(out, a);
                out.push_str(if matches!(e, Expr::Sin(_)) {
                    ").0"
                } else {
                    ").1"
                });
            }
            Expr::IfLt(a, b, t, f) => {
                out.push_str("if ");
                self.binary(out, a, " < ", b);
                out.push_str(" { ");
                self.operand(out, t);
                out.push_str(" } else { ");
                self.operand(out, f);
                out.push_str(" }");
            }
            Expr::MulAdd {
                x0,
                x1,
                y,
                neg_x0,
                neg_y,
            } => {
                let _ = write!(out, "{}::mul_add(", float_name(self.ft));
                if neg_x0 {
                    out.push('-');
                }
                self.operand(out, x0);
                out.push_str(", ");
                self.operand(out, x1);
                out.push_str(", ");
                if neg_y {
                    out.push('-');
                }
                self.operand(out, y);
                out.push(')');
            }
        }
    }

    /// Writes statement `s` on one line, without indentation or newline.
    fn stmt_line(&self, out: &mut String, s: &Stmt) {
        match s {
            Stmt::Let(t, e) => {
                out.push_str("let t");
                push_u32(out, *t);
                out.push_str(" = ");
                self.expr(out, e);
                out.push(';');
            }
            Stmt::SinCos { s, c, x } => {
                let _ = write!(out, "let (t{s}, t{c}) = {}(", sin_cos_name(self.ft));
                self.operand(out, *x);
                out.push_str(");");
            }
            Stmt::SinCosN { sc, args } => {
                out.push_str("let ([");
                for (k, (s, _)) in sc.iter().enumerate() {
                    let _ = write!(out, "{}t{s}", if k > 0 { ", " } else { "" });
                }
                out.push_str("], [");
                for (k, (_, c)) in sc.iter().enumerate() {
                    let _ = write!(out, "{}t{c}", if k > 0 { ", " } else { "" });
                }
                let _ = write!(out, "]) = {}([", sin_cos_n_name(self.ft));
                self.operands(out, args);
                out.push_str("]);");
            }
            Stmt::SinCosLanes { s, c, x } => {
                let _ = write!(
                    out,
                    "let (t{s}, t{c}) = sin_cos_n::<4>(std::array::from_fn(|l| "
                );
                self.operand(out, *x);
                out.push_str("));");
            }
        }
    }
}

/// Appends statement `s` to a function body at indentation `indent` (spaces), one line and a
/// newline, as `prettyplease` prints it.
pub(crate) fn write_stmt(out: &mut String, p: &TextPrinter, s: &Stmt, indent: usize) {
    let start = out.len();
    for _ in 0..indent {
        out.push(' ');
    }
    p.stmt_line(out, s);
    if out.len() - start > ONE_LINE_MAX {
        let line = out.split_off(start + indent);
        out.truncate(start);
        push_formatted_stmt(out, &line, indent);
    } else {
        out.push('\n');
    }
}

/// Appends the statement `line` (one line) at indentation `indent`, as [`write_stmt`] does.
pub(crate) fn push_line(out: &mut String, line: &str, indent: usize) {
    if line.len() + indent > ONE_LINE_MAX {
        push_formatted_stmt(out, line, indent);
    } else {
        for _ in 0..indent {
            out.push(' ');
        }
        out.push_str(line);
        out.push('\n');
    }
}

/// Appends the statement `line` (one line, valid Rust) formatted by `prettyplease` inside a
/// function body at indentation `indent`.
pub(crate) fn push_formatted_stmt(out: &mut String, line: &str, indent: usize) {
    // Nested blocks give the indentation; their lines are stripped below.
    let depth = indent / 4;
    let mut src = String::from("fn f() {");
    for _ in 1..depth {
        src.push('{');
    }
    src.push_str(line);
    for _ in 0..depth {
        src.push('}');
    }
    let formatted = syn::parse_file(&src)
        .map(|f| prettyplease::unparse(&f))
        .expect("internal: an emitted statement does not parse");
    let lines: Vec<&str> = formatted.lines().collect();
    // Strip `fn f() {` and the nested `{` lines, and their closing lines.
    for l in &lines[depth..lines.len() - depth] {
        out.push_str(l);
        out.push('\n');
    }
}

#[cfg(test)]
mod tests {
    use proc_macro2::{Ident, Span, TokenStream};
    use quote::quote;

    use super::*;
    use crate::emit::float_tokens;

    /// Prints statements as tokens; `var` gives the tokens of graph variables.
    struct TokenPrinter<'a> {
        ft: FloatTy,
        var: &'a dyn Fn(u32) -> TokenStream,
    }

    fn temp_ident(n: u32) -> Ident {
        Ident::new(&format!("t{n}"), Span::call_site())
    }

    impl TokenPrinter<'_> {
        /// Tokens of operand `o`.
        fn operand(&self, o: Operand) -> TokenStream {
            match o {
                Operand::Temp(n) => {
                    let t = temp_ident(n);
                    quote!(#t)
                }
                Operand::LaneTemp(n) => {
                    let t = temp_ident(n);
                    quote!(#t[l])
                }
                Operand::Var(v) => (self.var)(v),
                Operand::Const(c) => float_tokens(c, self.ft),
            }
        }

        fn expr(&self, e: &Expr) -> TokenStream {
            let ft = self.ft.tokens();
            let o = |a: Operand| self.operand(a);
            match *e {
                Expr::Add(a, b) => {
                    let (x, y) = (o(a), o(b));
                    quote!(#x + #y)
                }
                Expr::Sub(a, b) => {
                    let (x, y) = (o(a), o(b));
                    quote!(#x - #y)
                }
                Expr::Mul(a, b) => {
                    let (x, y) = (o(a), o(b));
                    quote!(#x * #y)
                }
                Expr::Div(a, b) => {
                    let (x, y) = (o(a), o(b));
                    quote!(#x / #y)
                }
                Expr::Neg(a) => {
                    let x = o(a);
                    quote!(-#x)
                }
                Expr::Sqrt(a) => {
                    let x = o(a);
                    quote!(#ft::sqrt(#x))
                }
                Expr::Abs(a) => {
                    let x = o(a);
                    quote!(#ft::abs(#x))
                }
                Expr::Min(a, b) => {
                    let (x, y) = (o(a), o(b));
                    quote!(#ft::min(#x, #y))
                }
                Expr::Max(a, b) => {
                    let (x, y) = (o(a), o(b));
                    quote!(#ft::max(#x, #y))
                }
                Expr::Sin(a) => {
                    let (f, x) = (Ident::new(sin_cos_name(self.ft), Span::call_site()), o(a));
                    quote!(#f(#x).0)
                }
                Expr::Cos(a) => {
                    let (f, x) = (Ident::new(sin_cos_name(self.ft), Span::call_site()), o(a));
                    quote!(#f(#x).1)
                }
                Expr::IfLt(a, b, t, f) => {
                    let (x, y, tt, ff) = (o(a), o(b), o(t), o(f));
                    quote!(if #x < #y { #tt } else { #ff })
                }
                Expr::MulAdd {
                    x0,
                    x1,
                    y,
                    neg_x0,
                    neg_y,
                } => {
                    let (x0, x1, y) = (o(x0), o(x1), o(y));
                    let x0 = if neg_x0 { quote!(-#x0) } else { x0 };
                    let y = if neg_y { quote!(-#y) } else { y };
                    quote!(#ft::mul_add(#x0, #x1, #y))
                }
            }
        }

        /// Tokens of statement `s`.
        fn stmt(&self, s: &Stmt) -> TokenStream {
            match s {
                Stmt::Let(t, e) => {
                    let t = temp_ident(*t);
                    let e = self.expr(e);
                    quote!(let #t = #e;)
                }
                Stmt::SinCos { s, c, x } => {
                    let (s, c, x) = (temp_ident(*s), temp_ident(*c), self.operand(*x));
                    let f = Ident::new(sin_cos_name(self.ft), Span::call_site());
                    quote!(let (#s, #c) = #f(#x);)
                }
                Stmt::SinCosN { sc, args } => {
                    let sins = sc.iter().map(|p| temp_ident(p.0));
                    let coss = sc.iter().map(|p| temp_ident(p.1));
                    let args = args.iter().map(|&a| self.operand(a));
                    let f = Ident::new(sin_cos_n_name(self.ft), Span::call_site());
                    quote!(let ([#(#sins),*], [#(#coss),*]) = #f([#(#args),*]);)
                }
                Stmt::SinCosLanes { s, c, x } => {
                    let (s, c, x) = (temp_ident(*s), temp_ident(*c), self.operand(*x));
                    quote!(let (#s, #c) = sin_cos_n::<4>(std::array::from_fn(|l| #x));)
                }
            }
        }
    }

    /// Every statement form, with the operands that print differently (negative and
    /// non-finite constants, lanes, variables with indices), printed as text equals the
    /// token form formatted by `prettyplease` — in a function body and in a loop inside one,
    /// and for statements long enough to be broken.
    #[test]
    fn text_is_what_prettyplease_prints() {
        let ops = [
            Operand::Temp(7),
            Operand::LaneTemp(12),
            Operand::Var(1),
            Operand::Const(-0.25),
            Operand::Const(1.5e-300),
            Operand::Const(f64::NAN),
            Operand::Const(f64::NEG_INFINITY),
            Operand::Const(3.0),
        ];
        let mut stmts = Vec::new();
        for &a in &ops {
            for e in [
                Expr::Neg(a),
                Expr::Sqrt(a),
                Expr::Abs(a),
                Expr::Sin(a),
                Expr::Cos(a),
            ] {
                stmts.push(Stmt::Let(3, e));
            }
            stmts.push(Stmt::SinCos { s: 1, c: 2, x: a });
            stmts.push(Stmt::SinCosLanes { s: 1, c: 2, x: a });
            for &b in &ops {
                for e in [
                    Expr::Add(a, b),
                    Expr::Sub(a, b),
                    Expr::Mul(a, b),
                    Expr::Div(a, b),
                    Expr::Min(a, b),
                    Expr::Max(a, b),
                    Expr::IfLt(a, b, b, a),
                ] {
                    stmts.push(Stmt::Let(1234, e));
                }
                for (neg_x0, neg_y) in [(false, false), (true, false), (false, true)] {
                    stmts.push(Stmt::Let(
                        99,
                        Expr::MulAdd {
                            x0: a,
                            x1: b,
                            y: a,
                            neg_x0,
                            neg_y,
                        },
                    ));
                }
            }
        }
        for n in [1, 3, 4, 6, 7, 12, 30] {
            stmts.push(Stmt::SinCosN {
                sc: (0..n).map(|k| (2 * k, 2 * k + 1)).collect(),
                args: (0..n).map(|k| Operand::Var(k + 10)).collect(),
            });
        }
        let var_text = |out: &mut String, v: u32| {
            let _ = write!(out, "local[{v}][l]");
        };
        let var_tokens = |v: u32| {
            let v = proc_macro2::Literal::u32_unsuffixed(v);
            quote!(local[#v][l])
        };
        for ft in [FloatTy::F64, FloatTy::F32] {
            let text = TextPrinter { ft, var: &var_text };
            let toks = TokenPrinter {
                ft,
                var: &var_tokens,
            };
            for s in &stmts {
                let t = toks.stmt(s);
                let file: syn::File = syn::parse2(quote!(fn f() { #t for l in 0..4 { #t } }))
                    .expect("statement tokens parse");
                let expected = prettyplease::unparse(&file);
                let mut body = String::new();
                write_stmt(&mut body, &text, s, 4);
                let mut inner = String::new();
                write_stmt(&mut inner, &text, s, 8);
                let got = format!("fn f() {{\n{body}    for l in 0..4 {{\n{inner}    }}\n}}\n");
                assert_eq!(got, expected, "{s:?}");
            }
        }
    }
}
