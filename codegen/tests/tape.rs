//! The interpreter's straight-line tape (`interp::Tape`: variables, constants, one batch of
//! joint-angle sines and cosines, then runs of one operation each, scheduled out of graph
//! order) against a plain node-by-node evaluation of the same graph in graph order: random
//! graphs of every node kind, bit for bit in `f64` (the batch four lanes per `sin_cos_n` call, the node-by-node evaluation one angle at a time); and `eval_into` with one
//! scratch vector shared by tapes of different sizes gives the values of `eval`.

use bf_codegen::graph::{Graph, Id, Node};
use bf_codegen::interp::{Scalar, Tape};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

/// Every node of `g` in graph order, the way a reader of the graph's definition would.
fn reference<S: Scalar>(g: &Graph, vars: &[S]) -> Vec<S> {
    let mut v: Vec<S> = Vec::with_capacity(g.len());
    for &n in g.nodes() {
        let x = |i: Id| v[i.index()];
        let y = match n {
            Node::Const(b) => S::from_f64(f64::from_bits(b)),
            Node::Var(k) => vars.get(k as usize).copied().unwrap_or(S::from_f64(0.0)),
            Node::Add(a, b) => x(a) + x(b),
            Node::Sub(a, b) => x(a) - x(b),
            Node::Mul(a, b) => x(a) * x(b),
            Node::Div(a, b) => x(a) / x(b),
            Node::Neg(a) => -x(a),
            Node::Sin(a) => x(a).sin_cos().0,
            Node::Cos(a) => x(a).sin_cos().1,
            Node::Sqrt(a) => x(a).sqrt(),
            Node::Abs(a) => x(a).abs(),
            Node::Min(a, b) => {
                if x(b) < x(a) {
                    x(b)
                } else {
                    x(a)
                }
            }
            Node::Max(a, b) => {
                if x(b) > x(a) {
                    x(b)
                } else {
                    x(a)
                }
            }
            Node::IfLt(a, b, t, f) => {
                if x(a) < x(b) {
                    x(t)
                } else {
                    x(f)
                }
            }
        };
        v.push(y);
    }
    v
}

/// A random graph over `nv` variables with about `n` operations of every kind; returns the
/// graph and some of its nodes as outputs.
fn random_graph(rng: &mut ChaCha8Rng, nv: u32, n: usize) -> (Graph, Vec<Id>) {
    let mut g = Graph::new();
    let mut pool: Vec<Id> = (0..nv).map(|i| g.var(i)).collect();
    for i in 0..nv {
        let x = pool[i as usize];
        let s = g.sin(x);
        let c = g.cos(x);
        pool.extend([s, c]);
    }
    for _ in 0..6 {
        let c = g.constant(rng.random_range(-3.0..3.0));
        pool.push(c);
    }
    for _ in 0..n {
        let mut pick = || pool[rng.random_range(0..pool.len())];
        let (a, b, t, f) = (pick(), pick(), pick(), pick());
        let id = match rng.random_range(0..11) {
            0 | 1 => g.add(a, b),
            2 => g.sub(a, b),
            3 | 4 => g.mul(a, b),
            5 => {
                let s = g.square(b);
                let d = g.add(s, t);
                let one = g.one();
                let d = g.add(d, one);
                g.div(a, d)
            }
            6 => g.neg(a),
            7 => {
                let s = g.abs(a);
                g.sqrt(s)
            }
            8 => g.min(a, b),
            9 => g.max(a, b),
            _ => {
                // Sine of a computed value (not batched).
                let s = g.sin(a);
                g.if_lt(s, b, t, f)
            }
        };
        pool.push(id);
    }
    let outs: Vec<Id> = (0..12)
        .map(|_| pool[rng.random_range(0..pool.len())])
        .collect();
    (g, outs)
}

#[test]
fn tape_equals_node_by_node_evaluation_bit_for_bit() {
    let mut rng = ChaCha8Rng::seed_from_u64(6);
    let mut scratch: Vec<f64> = Vec::new();
    for case in 0..60 {
        let nv = rng.random_range(1..9);
        let n = rng.random_range(5..400);
        let (g, outs) = random_graph(&mut rng, nv, n);
        let tape = Tape::new(&g, &outs);
        for _ in 0..4 {
            let xs: Vec<f64> = (0..nv).map(|_| rng.random_range(-7.0..7.0)).collect();
            let want = reference::<f64>(&g, &xs);
            let got = tape.eval::<f64>(&xs);
            let mut into = vec![0.0; outs.len()];
            tape.eval_into(&xs, &mut scratch, &mut into);
            for (k, o) in outs.iter().enumerate() {
                let w = want[o.index()];
                for (v, how) in [(got[k], "eval"), (into[k], "eval_into")] {
                    assert!(
                        w.to_bits() == v.to_bits() || (w.is_nan() && v.is_nan()),
                        "case {case} output {k} ({how}): tape {v:e} vs node order {w:e}"
                    );
                }
            }
        }
    }
}

#[test]
fn outputs_that_are_variables_constants_or_angles() {
    let mut g = Graph::new();
    let x = g.var(0);
    let y = g.var(3);
    let c = g.constant(2.5);
    let s = g.sin(x);
    let cy = g.cos(y);
    let tape = Tape::new(&g, &[c, y, s, cy, x]);
    let got = tape.eval::<f64>(&[0.7, 9.0, 9.0]);
    // Variable 3 is beyond the slice: it reads as 0.
    assert_eq!(got, vec![2.5, 0.0, libm::sin(0.7f64), 1.0, 0.7]);
    assert!(Tape::new(&g, &[]).eval::<f64>(&[1.0]).is_empty());
}
