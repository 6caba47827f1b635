//! Expression graph: constant folding, algebraic identities, exact π multiples, hash-consing.

use bf_codegen::graph::{Graph, Node, cos_pi_value, sin_pi_value};
use bf_codegen::interp::eval;

#[test]
fn exact_pi_multiples() {
    assert_eq!(cos_pi_value(1, 2), 0.0);
    assert_eq!(cos_pi_value(-1, 2), 0.0);
    assert_eq!(cos_pi_value(3, 2), 0.0);
    assert_eq!(cos_pi_value(1, 1), -1.0);
    assert_eq!(cos_pi_value(0, 1), 1.0);
    assert_eq!(cos_pi_value(4, 2), 1.0);
    assert_eq!(cos_pi_value(1, 3), 0.5);
    assert_eq!(cos_pi_value(-2, 3), -0.5);
    assert_eq!(sin_pi_value(1, 2), 1.0);
    assert_eq!(sin_pi_value(-1, 2), -1.0);
    assert_eq!(sin_pi_value(1, 1), 0.0);
    assert_eq!(sin_pi_value(1, 6), 0.5);
    assert_eq!(sin_pi_value(7, 6), -0.5);
    assert_eq!(sin_pi_value(-5, 2), -1.0);
    // Non-special multiples agree with the library to rounding.
    for (n, d) in [(1, 5), (3, 7), (-2, 9), (1, 4), (5, 6)] {
        let x = n as f64 / d as f64 * std::f64::consts::PI;
        assert!((cos_pi_value(n, d) - libm::cos(x)).abs() < 1e-15);
        assert!((sin_pi_value(n, d) - libm::sin(x)).abs() < 1e-15);
    }
    // cos(π/2)·x folds to a structural zero.
    let mut g = Graph::new();
    let x = g.var(0);
    let c = g.cos_pi(1, 2);
    let p = g.mul(c, x);
    assert!(g.is_zero(p));
    let s = g.sin_pi(1, 2);
    assert_eq!(g.mul(s, x), x);
}

#[test]
fn identities_fold_at_construction() {
    let mut g = Graph::new();
    let x = g.var(0);
    let y = g.var(1);
    let zero = g.zero();
    let one = g.one();
    assert_eq!(g.mul(x, zero), zero);
    assert_eq!(g.mul(zero, x), zero);
    assert_eq!(g.mul(x, one), x);
    assert_eq!(g.add(x, zero), x);
    assert_eq!(g.sub(x, zero), x);
    assert_eq!(g.sub(x, x), zero);
    let nx = g.neg(x);
    assert_eq!(g.neg(nx), x);
    assert_eq!(g.div(x, one), x);
    assert_eq!(g.div(x, x), one);
    let xy = g.sub(x, y);
    let yx = g.sub(y, x);
    assert_eq!(g.neg(xy), yx);
    // x + (−y) is x − y; (−x)·(−y) is x·y
    let ny = g.neg(y);
    assert_eq!(g.add(x, ny), xy);
    let a = g.mul(nx, ny);
    let b = g.mul(x, y);
    assert_eq!(a, b);
    // constants fold
    let two = g.constant(2.0);
    let three = g.constant(3.0);
    let p = g.mul(two, three);
    assert_eq!(g.as_const(p), Some(6.0));
    let s = g.add(two, three);
    assert_eq!(g.as_const(s), Some(5.0));
    // constants are pulled outward: −0.5 − (−1 − x) = 0.5 + x
    let m1 = g.constant(-1.0);
    let t = g.sub(m1, x);
    let mh = g.constant(-0.5);
    let r = g.sub(mh, t);
    let half = g.constant(0.5);
    assert_eq!(r, g.add(x, half));
    // 2·(3·x) = 6·x
    let tx = g.mul(three, x);
    let six = g.constant(6.0);
    assert_eq!(g.mul(two, tx), g.mul(six, x));
    // −0.0 is stored as 0.0
    assert_eq!(g.constant(-0.0), zero);
    // sin(−x) = −sin x, cos(−x) = cos x
    let snx = g.sin(nx);
    let sx = g.sin(x);
    assert_eq!(snx, g.neg(sx));
    let cnx = g.cos(nx);
    assert_eq!(cnx, g.cos(x));
    // sat of constants folds
    let lo = g.constant(-1.0);
    let c = g.constant(-3.0);
    let sat = g.sat(c, lo, zero);
    assert_eq!(g.as_const(sat), Some(-1.0));
}

#[test]
fn hash_consing_shares_subexpressions() {
    let mut g = Graph::new();
    let x = g.var(0);
    let y = g.var(1);
    let a = g.add(x, y);
    let b = g.add(y, x);
    assert_eq!(a, b, "commutative operands are canonicalised");
    let n = g.len();
    let p1 = g.mul(a, a);
    let p2 = g.mul(b, b);
    assert_eq!(p1, p2);
    assert_eq!(g.len(), n + 1, "only one new node");
    let s1 = g.sin(x);
    let s2 = g.sin(x);
    assert_eq!(s1, s2);
    // children before parents
    for (i, node) in g.nodes().iter().enumerate() {
        for c in node.children() {
            assert!(c.index() < i);
        }
    }
    assert!(matches!(g.node(p1), Node::Mul(_, _)));
}

#[test]
fn folded_expressions_evaluate_correctly() {
    // A random mix of operations: the folded graph evaluates like the plain formula.
    let mut g = Graph::new();
    let x = g.var(0);
    let y = g.var(1);
    let m1 = g.constant(-1.0);
    let h = g.constant(0.5);
    let t1 = g.sub(m1, x); // −1 − x
    let t2 = g.sub(h, t1); // 0.5 + 1 + x
    let t3 = g.mul(t2, y);
    let ny = g.neg(y);
    let t4 = g.add(t3, ny); // (1.5 + x) y − y
    let t5 = g.sin(x);
    let t6 = g.cos(x);
    let t7 = g.mul(t5, t5);
    let t8 = g.mul(t6, t6);
    let t9 = g.add(t7, t8); // 1
    let t10 = g.div(t4, t9);
    let sq = g.sqrt(t9);
    let r = g.sub(t10, sq);
    for &(xv, yv) in &[(0.3, -1.2), (2.0, 0.7), (-5.0, 3.0)] {
        let v = eval::<f64>(&g, &[r], &[xv, yv])[0];
        let want = (1.5 + xv) * yv - yv - 1.0;
        assert!((v - want).abs() < 1e-14, "{v} vs {want}");
    }
}
