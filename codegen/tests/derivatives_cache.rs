//! The differentiation cache of `Derivatives::new`: a graph with the history of an earlier
//! call gets that call's nodes and result replayed, which must be exactly what differentiating
//! again gives (the same nodes with the same ids, the same patterns and entry ids); a graph
//! with another history must not get them.

use bf_codegen::graph::{Graph, Id};
use bf_codegen::nodefn::Derivatives;

/// y₀ = sin(x₀)·x₁ + ε x₂², y₁ = cos(x₀ + x₂) / (1 + x₁²), with ε the fixed variable 3,
/// and `extra` nodes interned first (another history).
fn build(extra: bool) -> (Graph, Vec<Id>) {
    let mut g = Graph::new();
    if extra {
        let v = g.var(7);
        let _ = g.sqrt(v);
    }
    let (x0, x1, x2, eps) = (g.var(0), g.var(1), g.var(2), g.var(3));
    let s = g.sin(x0);
    let a = g.mul(s, x1);
    let x2sq = g.mul(x2, x2);
    let b = g.mul(eps, x2sq);
    let y0 = g.add(a, b);
    let sum = g.add(x0, x2);
    let c = g.cos(sum);
    let one = g.one();
    let x1sq = g.mul(x1, x1);
    let den = g.add(one, x1sq);
    let y1 = g.div(c, den);
    (g, vec![y0, y1])
}

fn same(a: &Derivatives, b: &Derivatives) -> bool {
    a.weight_base == b.weight_base
        && a.jac == b.jac
        && a.jac_ids == b.jac_ids
        && a.hess == b.hess
        && a.hess_ids == b.hess_ids
}

#[test]
fn a_replayed_differentiation_is_the_differentiation() {
    let locals = [0u32, 1, 2];
    let fixed = [(3u32, 0.01)];
    for extra in [false, true] {
        let (mut plain, outputs) = build(extra);
        let expected = Derivatives::differentiate(&mut plain, &outputs, &locals, &fixed);
        // The first call may differentiate or replay (another test may have filled the
        // cache); the second replays. Both must be the plain differentiation, node for node.
        for _ in 0..2 {
            let (mut g, outputs) = build(extra);
            assert_eq!(g.history(), build(extra).0.history());
            let d = Derivatives::new(&mut g, &outputs, &locals, &fixed);
            assert!(same(&d, &expected), "extra {extra}");
            assert_eq!(g.nodes(), plain.nodes(), "extra {extra}");
            assert_eq!(g.history(), plain.history());
        }
        // ∂²(w₀y₀ + w₁y₁)/∂x₂² ≠ 0 (2εw₀ and the cosine's): the pattern is not empty.
        assert!(expected.hess.contains(&(2, 2)));
    }
    // Another history (an extra node first) is another graph: its ids differ.
    let (a, _) = build(false);
    let (b, _) = build(true);
    assert_ne!(a.history(), b.history());
    // The fixed values are not part of the key; the fixed ids are.
    let (mut g1, out1) = build(false);
    let d1 = Derivatives::new(&mut g1, &out1, &locals, &[(3, 5.0)]);
    assert!(same(&d1, &expected_for(false, &locals, &[(3, 5.0)])));
    let (mut g2, out2) = build(false);
    let d2 = Derivatives::new(&mut g2, &out2, &locals[..2], &fixed);
    assert!(same(&d2, &expected_for(false, &locals[..2], &fixed)));
    assert!(!same(&d1, &d2));
}

fn expected_for(extra: bool, locals: &[u32], fixed: &[(u32, f64)]) -> Derivatives {
    let (mut g, outputs) = build(extra);
    Derivatives::differentiate(&mut g, &outputs, locals, fixed)
}
