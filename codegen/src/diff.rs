//! Symbolic differentiation on the expression graph (source transformation).
//!
//! The results are new nodes of the same [`Graph`], so derivatives share common
//! subexpressions with the values (`docs/architecture.md`, "Differentiation"). Used for ∂M/∂q (Christoffel
//! symbols c_ijk of eq. 76–79), g = ∂U/∂q (eq. 72), the time derivatives Ṁ, J̇ q̇, ṙ_c and
//! J̇_c q̇ (eq. 33) along q̇, and Hessians of weighted sums (the optimiser's Lagrangian, Sect. 4).
//!
//! * [`forward`]: tangents of many outputs for one seed direction (∂/∂x_i, or d/dt with the
//!   seed q_k ↦ q̇_k);
//! * [`reverse`]: the gradient of a weighted sum of outputs in one backward sweep;
//! * [`hessian`]: forward-over-reverse second derivatives of a weighted sum.
//!
//! A zero tangent/adjoint is represented by `None`, so structural zeros create no nodes.

use crate::graph::{Graph, Id, Node};

fn add_opt(g: &mut Graph, a: Option<Id>, b: Option<Id>) -> Option<Id> {
    match (a, b) {
        (None, x) | (x, None) => x,
        (Some(x), Some(y)) => Some(g.add(x, y)),
    }
}

fn mul_opt(g: &mut Graph, a: Option<Id>, b: Id) -> Option<Id> {
    a.map(|x| g.mul(x, b))
}

fn nonzero(g: &Graph, x: Id) -> Option<Id> {
    if g.is_zero(x) { None } else { Some(x) }
}

/// Forward mode: the directional derivative of each output along the seed direction.
///
/// `seed(var)` gives the tangent of input variable `var` (`None` = 0). Returns one node per
/// output (the constant 0 where the derivative vanishes structurally).
pub fn forward(g: &mut Graph, outputs: &[Id], seed: &dyn Fn(u32) -> Option<Id>) -> Vec<Id> {
    let n = g.len();
    let mark = g.cone(outputs);
    let mut tan: Vec<Option<Id>> = vec![None; n];
    let max = outputs.iter().map(|o| o.index() + 1).max().unwrap_or(0);
    for i in 0..max {
        if !mark[i] {
            continue;
        }
        let node = g.node(Id(i as u32));
        let me = Id(i as u32);
        let t = match node {
            Node::Const(_) => None,
            Node::Var(v) => seed(v),
            Node::Add(a, b) => add_opt(g, tan[a.index()], tan[b.index()]),
            Node::Sub(a, b) => match (tan[a.index()], tan[b.index()]) {
                (x, None) => x,
                (None, Some(y)) => Some(g.neg(y)),
                (Some(x), Some(y)) => Some(g.sub(x, y)),
            },
            Node::Mul(a, b) => {
                let l = mul_opt(g, tan[a.index()], b);
                let r = tan[b.index()].map(|db| g.mul(a, db));
                add_opt(g, l, r)
            }
            Node::Div(a, b) => {
                // d(a/b) = (da − (a/b) db) / b, reusing the quotient node.
                let num = match (tan[a.index()], tan[b.index()]) {
                    (x, None) => x,
                    (da, Some(db)) => {
                        let qdb = g.mul(me, db);
                        match da {
                            None => Some(g.neg(qdb)),
                            Some(da) => Some(g.sub(da, qdb)),
                        }
                    }
                };
                num.map(|x| g.div(x, b))
            }
            Node::Neg(a) => tan[a.index()].map(|x| g.neg(x)),
            Node::Sin(a) => tan[a.index()].map(|x| {
                let c = g.cos(a);
                g.mul(c, x)
            }),
            Node::Cos(a) => tan[a.index()].map(|x| {
                let s = g.sin(a);
                let m = g.mul(s, x);
                g.neg(m)
            }),
            Node::Sqrt(a) => tan[a.index()].map(|x| {
                let h = g.constant(0.5);
                let hx = g.mul(h, x);
                g.div(hx, me)
            }),
            Node::Abs(a) => tan[a.index()].map(|x| {
                let z = g.zero();
                let nx = g.neg(x);
                g.if_lt(a, z, nx, x)
            }),
            Node::Min(a, b) => select(g, a, b, tan[a.index()], tan[b.index()]),
            Node::Max(a, b) => select(g, a, b, tan[b.index()], tan[a.index()]),
            Node::IfLt(a, b, t, f) => select(g, a, b, tan[t.index()], tan[f.index()]),
        };
        tan[i] = t.and_then(|x| nonzero(g, x));
    }
    outputs
        .iter()
        .map(|o| tan[o.index()].unwrap_or_else(|| g.zero()))
        .collect()
}

fn select(g: &mut Graph, a: Id, b: Id, t: Option<Id>, f: Option<Id>) -> Option<Id> {
    if t.is_none() && f.is_none() {
        return None;
    }
    let z = g.zero();
    let (t, f) = (t.unwrap_or(z), f.unwrap_or(z));
    Some(g.if_lt(a, b, t, f))
}

/// ∂/∂x_var of every output.
pub fn partial(g: &mut Graph, outputs: &[Id], var: u32) -> Vec<Id> {
    let one = g.one();
    forward(g, outputs, &|v| (v == var).then_some(one))
}

/// Total time derivative along a direction: `d/dt f = Σ_k ∂f/∂x_{vars[k]} · rates[k]`.
/// With `vars` = q and `rates` = q̇ this is d/dt f(q) with q̇ held constant (so d/dt of
/// J(q) q̇ gives J̇ q̇).
pub fn time_derivative(g: &mut Graph, outputs: &[Id], vars: &[u32], rates: &[Id]) -> Vec<Id> {
    let pairs: Vec<(u32, Id)> = vars.iter().copied().zip(rates.iter().copied()).collect();
    forward(g, outputs, &|v| {
        pairs.iter().find(|(w, _)| *w == v).map(|(_, r)| *r)
    })
}

/// Reverse mode: gradient of Σ_i w_i f_i with respect to the variables `vars`
/// (`weighted` = pairs (f_i, w_i); weights are nodes, e.g. Lagrange multipliers).
pub fn reverse(g: &mut Graph, weighted: &[(Id, Id)], vars: &[u32]) -> Vec<Id> {
    let outputs: Vec<Id> = weighted.iter().map(|p| p.0).collect();
    let mark = g.cone(&outputs);
    let max = outputs.iter().map(|o| o.index() + 1).max().unwrap_or(0);
    let mut adj: Vec<Option<Id>> = vec![None; max];
    for &(f, w) in weighted {
        adj[f.index()] = add_opt(g, adj[f.index()], Some(w));
    }
    let mut var_adj: Vec<(u32, Id)> = Vec::new();
    for i in (0..max).rev() {
        if !mark[i] {
            continue;
        }
        let Some(a_bar) = adj[i].and_then(|x| nonzero(g, x)) else {
            continue;
        };
        let me = Id(i as u32);
        let push = |g: &mut Graph, adj: &mut Vec<Option<Id>>, c: Id, v: Id| {
            adj[c.index()] = add_opt(g, adj[c.index()], Some(v));
        };
        match g.node(me) {
            Node::Const(_) => {}
            Node::Var(v) => var_adj.push((v, a_bar)),
            Node::Add(a, b) => {
                push(g, &mut adj, a, a_bar);
                push(g, &mut adj, b, a_bar);
            }
            Node::Sub(a, b) => {
                push(g, &mut adj, a, a_bar);
                let n = g.neg(a_bar);
                push(g, &mut adj, b, n);
            }
            Node::Mul(a, b) => {
                let x = g.mul(a_bar, b);
                push(g, &mut adj, a, x);
                let y = g.mul(a_bar, a);
                push(g, &mut adj, b, y);
            }
            Node::Div(a, b) => {
                let x = g.div(a_bar, b);
                push(g, &mut adj, a, x);
                let y = g.mul(x, me);
                let ny = g.neg(y);
                push(g, &mut adj, b, ny);
            }
            Node::Neg(a) => {
                let n = g.neg(a_bar);
                push(g, &mut adj, a, n);
            }
            Node::Sin(a) => {
                let c = g.cos(a);
                let x = g.mul(a_bar, c);
                push(g, &mut adj, a, x);
            }
            Node::Cos(a) => {
                let s = g.sin(a);
                let x = g.mul(a_bar, s);
                let nx = g.neg(x);
                push(g, &mut adj, a, nx);
            }
            Node::Sqrt(a) => {
                let h = g.constant(0.5);
                let x = g.mul(h, a_bar);
                let y = g.div(x, me);
                push(g, &mut adj, a, y);
            }
            Node::Abs(a) => {
                let z = g.zero();
                let n = g.neg(a_bar);
                let x = g.if_lt(a, z, n, a_bar);
                push(g, &mut adj, a, x);
            }
            Node::Min(a, b) => {
                let z = g.zero();
                let x = g.if_lt(a, b, a_bar, z);
                push(g, &mut adj, a, x);
                let y = g.if_lt(a, b, z, a_bar);
                push(g, &mut adj, b, y);
            }
            Node::Max(a, b) => {
                let z = g.zero();
                let x = g.if_lt(a, b, z, a_bar);
                push(g, &mut adj, a, x);
                let y = g.if_lt(a, b, a_bar, z);
                push(g, &mut adj, b, y);
            }
            Node::IfLt(a, b, t, f) => {
                let z = g.zero();
                let x = g.if_lt(a, b, a_bar, z);
                push(g, &mut adj, t, x);
                let y = g.if_lt(a, b, z, a_bar);
                push(g, &mut adj, f, y);
            }
        }
    }
    vars.iter()
        .map(|&v| {
            let mut acc = g.zero();
            for &(w, a) in &var_adj {
                if w == v {
                    acc = g.add(acc, a);
                }
            }
            acc
        })
        .collect()
}

/// Hessian of Σ_i w_i f_i with respect to `vars` (forward over reverse); `h[i][j]` =
/// ∂²/∂x_i∂x_j. The result is symmetric by construction of the mixed partials.
pub fn hessian(g: &mut Graph, weighted: &[(Id, Id)], vars: &[u32]) -> Vec<Vec<Id>> {
    let grad = reverse(g, weighted, vars);
    let mut h = vec![Vec::with_capacity(vars.len()); vars.len()];
    for &vj in vars {
        let col = partial(g, &grad, vj);
        for (i, c) in col.into_iter().enumerate() {
            h[i].push(c);
        }
    }
    h
}
