//! Symbolic differentiation on the graph: forward mode against central finite differences,
//! reverse mode and Hessians against forward mode / finite differences, time derivatives,
//! piecewise operations (abs, min, max, sat) away from their kinks.

use bf_codegen::diff::{forward, hessian, partial, reverse, time_derivative};
use bf_codegen::graph::{Graph, Id};
use bf_codegen::interp::eval;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

const NV: u32 = 4;

/// A random smooth expression over variables 0..NV.
fn random_expr(g: &mut Graph, rng: &mut ChaCha8Rng, depth: u32) -> Id {
    if depth == 0 || rng.random_range(0..10) < 2 {
        return if rng.random_range(0..4) == 0 {
            g.constant(rng.random_range(-2.0..2.0))
        } else {
            g.var(rng.random_range(0..NV))
        };
    }
    let a = random_expr(g, rng, depth - 1);
    match rng.random_range(0..8) {
        0 => {
            let b = random_expr(g, rng, depth - 1);
            g.add(a, b)
        }
        1 => {
            let b = random_expr(g, rng, depth - 1);
            g.sub(a, b)
        }
        2 | 3 => {
            let b = random_expr(g, rng, depth - 1);
            g.mul(a, b)
        }
        4 => {
            // a / (b² + 1)
            let b = random_expr(g, rng, depth - 1);
            let b2 = g.square(b);
            let one = g.one();
            let d = g.add(b2, one);
            g.div(a, d)
        }
        5 => g.sin(a),
        6 => g.cos(a),
        _ => {
            // √(a² + 1) and −a
            let a2 = g.square(a);
            let one = g.one();
            let s = g.add(a2, one);
            let r = g.sqrt(s);
            g.neg(r)
        }
    }
}

fn point(rng: &mut ChaCha8Rng) -> Vec<f64> {
    (0..NV).map(|_| rng.random_range(-1.5..1.5)).collect()
}

fn fd_partial(g: &Graph, f: &[Id], x: &[f64], k: usize, h: f64) -> Vec<f64> {
    let mut a = x.to_vec();
    let mut b = x.to_vec();
    a[k] += h;
    b[k] -= h;
    let fa = eval::<f64>(g, f, &a);
    let fb = eval::<f64>(g, f, &b);
    fa.iter()
        .zip(&fb)
        .map(|(p, m)| (p - m) / (2.0 * h))
        .collect()
}

fn close(a: f64, b: f64, tol: f64) -> bool {
    (a - b).abs() <= tol * (1.0 + a.abs().max(b.abs()))
}

#[test]
fn forward_mode_matches_finite_differences() {
    let mut rng = ChaCha8Rng::seed_from_u64(41);
    for _ in 0..200 {
        let mut g = Graph::new();
        let f: Vec<Id> = (0..3).map(|_| random_expr(&mut g, &mut rng, 5)).collect();
        let x = point(&mut rng);
        for k in 0..NV as usize {
            let d = partial(&mut g, &f, k as u32);
            let dv = eval::<f64>(&g, &d, &x);
            let fdv = fd_partial(&g, &f, &x, k, 1e-6);
            for (a, b) in dv.iter().zip(&fdv) {
                assert!(close(*a, *b, 1e-6), "∂/∂x{k}: {a} vs FD {b}");
            }
        }
    }
}

#[test]
fn reverse_mode_equals_forward_mode() {
    let mut rng = ChaCha8Rng::seed_from_u64(42);
    let vars: Vec<u32> = (0..NV).collect();
    for _ in 0..200 {
        let mut g = Graph::new();
        let f: Vec<Id> = (0..3).map(|_| random_expr(&mut g, &mut rng, 5)).collect();
        // weights are nodes: constants and a variable
        let w = [g.constant(0.7), g.constant(-1.3), g.var(2)];
        let weighted: Vec<(Id, Id)> = f.iter().copied().zip(w).collect();
        let grad = reverse(&mut g, &weighted, &vars);
        let x = point(&mut rng);
        let gv = eval::<f64>(&g, &grad, &x);
        for k in 0..NV as usize {
            let d = partial(&mut g, &f, k as u32);
            let dv = eval::<f64>(&g, &d, &x);
            let want = 0.7 * dv[0] - 1.3 * dv[1] + x[2] * dv[2];
            assert!(close(gv[k], want, 1e-12), "grad[{k}]: {} vs {want}", gv[k]);
        }
    }
}

#[test]
fn hessian_is_symmetric_and_matches_finite_differences() {
    let mut rng = ChaCha8Rng::seed_from_u64(43);
    let vars: Vec<u32> = (0..NV).collect();
    for _ in 0..100 {
        let mut g = Graph::new();
        let f: Vec<Id> = (0..2).map(|_| random_expr(&mut g, &mut rng, 4)).collect();
        let w = [g.constant(1.5), g.constant(-0.4)];
        let weighted: Vec<(Id, Id)> = f.iter().copied().zip(w).collect();
        let h = hessian(&mut g, &weighted, &vars);
        let grad = reverse(&mut g, &weighted, &vars);
        let x = point(&mut rng);
        let hv: Vec<Vec<f64>> = h.iter().map(|r| eval::<f64>(&g, r, &x)).collect();
        for j in 0..NV as usize {
            let col = fd_partial(&g, &grad, &x, j, 1e-5);
            for i in 0..NV as usize {
                assert!(close(hv[i][j], hv[j][i], 1e-12), "H not symmetric");
                assert!(
                    close(hv[i][j], col[i], 1e-5),
                    "H[{i}][{j}] {} vs FD {}",
                    hv[i][j],
                    col[i]
                );
            }
        }
    }
}

#[test]
fn time_derivative_is_directional_derivative() {
    let mut rng = ChaCha8Rng::seed_from_u64(44);
    for _ in 0..100 {
        let mut g = Graph::new();
        let f: Vec<Id> = (0..2).map(|_| random_expr(&mut g, &mut rng, 5)).collect();
        // d/dt f(x0(t), x1(t)) with rates held in variables 2 and 3.
        let rates = [g.var(2), g.var(3)];
        let d = time_derivative(&mut g, &f, &[0, 1], &rates);
        let x = point(&mut rng);
        let dv = eval::<f64>(&g, &d, &x);
        let p0 = fd_partial(&g, &f, &x, 0, 1e-6);
        let p1 = fd_partial(&g, &f, &x, 1, 1e-6);
        for i in 0..2 {
            // f may also depend on variables 2, 3 themselves: those are not moved.
            let want = p0[i] * x[2] + p1[i] * x[3];
            assert!(close(dv[i], want, 1e-6), "{} vs {want}", dv[i]);
        }
    }
}

#[test]
fn piecewise_operations() {
    let mut g = Graph::new();
    let x = g.var(0);
    let y = g.var(1);
    let lo = g.constant(-1.0);
    let hi = g.zero();
    let xy = g.mul(x, y);
    let fs = [g.abs(xy), g.min(x, y), g.max(x, y), g.sat(xy, lo, hi)];
    let mut rng = ChaCha8Rng::seed_from_u64(45);
    let vars = [0u32, 1];
    let grad: Vec<Vec<Id>> = fs
        .iter()
        .map(|&f| {
            let one = g.one();
            reverse(&mut g, &[(f, one)], &vars)
        })
        .collect();
    let mut n = 0;
    while n < 500 {
        let p: [f64; 2] = [rng.random_range(-2.0..2.0), rng.random_range(-2.0..2.0)];
        let xyv = p[0] * p[1];
        if (p[0] - p[1]).abs() < 1e-3 || xyv.abs() < 1e-3 || (xyv + 1.0).abs() < 1e-3 {
            continue;
        }
        n += 1;
        for (fi, &f) in fs.iter().enumerate() {
            for k in 0..2 {
                let dk = partial(&mut g, &[f], k);
                let a = eval::<f64>(&g, &dk, &p)[0];
                let b = fd_partial(&g, &[f], &p, k as usize, 1e-7)[0];
                assert!(close(a, b, 1e-6), "f{fi} ∂/∂x{k}: {a} vs {b}");
                let r = eval::<f64>(&g, &grad[fi], &p)[k as usize];
                assert_eq!(a, r, "reverse vs forward");
            }
        }
    }
    // A zero seed gives structural zeros.
    let d = forward(&mut g, &fs, &|_| None);
    assert!(d.iter().all(|&i| g.is_zero(i)));
    // values
    let v = eval::<f64>(&g, &fs, &[0.5, -4.0]);
    assert_eq!(v, vec![2.0, -4.0, 0.5, -1.0]);
}
