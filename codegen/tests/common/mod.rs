//! Shared helpers of the bf-codegen integration tests.
#![allow(dead_code)]

pub mod chain;

use bf_codegen::Scene;
use bf_codegen::graph::Id;
use bf_codegen::interp::{Scalar, Tape};
use bf_codegen::robot::SymbolicRobot;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

/// All scenes of `scenes/`.
pub const SCENES: [&str; 4] = ["paper", "human", "puma560", "iiwa7"];

/// Load `scenes/<name>.toml`.
pub fn scene(name: &str) -> Scene {
    Scene::load(format!(
        "{}/../scenes/{name}.toml",
        env!("CARGO_MANIFEST_DIR")
    ))
    .unwrap_or_else(|e| panic!("{e}"))
}

/// Load `codegen/tests/scenes/<name>.toml` (test-only scenes).
pub fn test_scene(name: &str) -> Scene {
    Scene::load(format!(
        "{}/tests/scenes/{name}.toml",
        env!("CARGO_MANIFEST_DIR")
    ))
    .unwrap_or_else(|e| panic!("{e}"))
}

/// Every scene: the four of `scenes/` and the test-only ones.
pub fn all_scenes() -> Vec<(String, Scene)> {
    let mut v: Vec<(String, Scene)> = SCENES.iter().map(|n| (n.to_string(), scene(n))).collect();
    v.push(("modified4".into(), test_scene("modified4")));
    v
}

/// Seeded RNG.
pub fn rng(seed: u64) -> ChaCha8Rng {
    ChaCha8Rng::seed_from_u64(seed)
}

/// Random vector with entries in [lo, hi).
pub fn rand_vec(rng: &mut ChaCha8Rng, n: usize, lo: f64, hi: f64) -> Vec<f64> {
    (0..n).map(|_| rng.random_range(lo..hi)).collect()
}

/// A state of the model's inputs.
#[derive(Clone, Debug)]
pub struct State {
    pub q: Vec<f64>,
    pub qd: Vec<f64>,
    pub omega: [f64; 3],
    pub eps: f64,
    pub p: Vec<f64>,
}

impl State {
    pub fn random(model: &SymbolicRobot, rng: &mut ChaCha8Rng) -> State {
        let n = model.nq();
        State {
            q: rand_vec(rng, n, -3.2, 3.2),
            qd: rand_vec(rng, n, -2.0, 2.0),
            omega: [
                rng.random_range(-2.0..2.0),
                rng.random_range(-2.0..2.0),
                rng.random_range(-2.0..2.0),
            ],
            eps: 0.01,
            p: model.params.iter().map(|p| p.1).collect(),
        }
    }

    pub fn vars(&self, model: &SymbolicRobot) -> Vec<f64> {
        let l = model.layout;
        let n = l.nq;
        let mut v = vec![0.0; l.n_vars()];
        v[..n].copy_from_slice(&self.q);
        v[n..2 * n].copy_from_slice(&self.qd);
        v[2 * n..2 * n + 3].copy_from_slice(&self.omega);
        v[2 * n + 3] = self.eps;
        for (i, p) in self.p.iter().enumerate() {
            v[l.param(i) as usize] = *p;
        }
        v
    }

    /// q moved by t·dq (q̇ unchanged).
    pub fn moved(&self, dq: &[f64], t: f64) -> State {
        let mut s = self.clone();
        for (q, d) in s.q.iter_mut().zip(dq) {
            *q += t * d;
        }
        s
    }
}

/// Evaluate nodes at a state in f64.
pub fn ev(model: &SymbolicRobot, ids: &[Id], s: &State) -> Vec<f64> {
    Tape::new(&model.g, ids).eval::<f64>(&s.vars(model))
}

/// Evaluate nodes at a state in any scalar type.
pub fn ev_as<S: Scalar>(model: &SymbolicRobot, ids: &[Id], s: &State) -> Vec<S> {
    let v: Vec<S> = s.vars(model).into_iter().map(S::from_f64).collect();
    Tape::new(&model.g, ids).eval::<S>(&v)
}

/// Central finite difference of `f` along `dir` at `s` (step h).
pub fn fd(model: &SymbolicRobot, ids: &[Id], s: &State, dir: &[f64], h: f64) -> Vec<f64> {
    let a = ev(model, ids, &s.moved(dir, h));
    let b = ev(model, ids, &s.moved(dir, -h));
    a.iter().zip(&b).map(|(x, y)| (x - y) / (2.0 * h)).collect()
}

/// Unit vector e_k of length n.
pub fn unit(n: usize, k: usize) -> Vec<f64> {
    let mut e = vec![0.0; n];
    e[k] = 1.0;
    e
}

/// max |a − b| / (scale), with scale = max(1e-300, max |b|, floor).
pub fn rel_err(a: &[f64], b: &[f64], floor: f64) -> f64 {
    let scale = b.iter().fold(floor, |m, x| m.max(x.abs()));
    a.iter()
        .zip(b)
        .fold(0.0f64, |m, (x, y)| m.max((x - y).abs()))
        / scale.max(1e-300)
}

pub fn flat2(m: &[Vec<Id>]) -> Vec<Id> {
    m.iter().flatten().copied().collect()
}

pub fn flat3(m: &[Vec<Vec<Id>>]) -> Vec<Id> {
    m.iter().flatten().flatten().copied().collect()
}

/// Asserts that the row-major n × n matrix `v` (a mass matrix evaluated at joint angles `q`) is
/// exactly symmetric and positive definite: a Cholesky factorization succeeds with positive
/// pivots.
pub fn assert_symmetric_positive_definite(name: &str, v: &[f64], n: usize, q: &[f64]) {
    let a = |i: usize, j: usize| v[i * n + j];
    let mut l = vec![vec![0.0; n]; n];
    for i in 0..n {
        for j in 0..n {
            assert_eq!(a(i, j), a(j, i), "{name}: M not symmetric");
        }
        for j in 0..=i {
            let mut sum = a(i, j);
            for k in 0..j {
                sum -= l[i][k] * l[j][k];
            }
            if i == j {
                assert!(sum > 0.0, "{name}: M not positive definite at {q:?}");
                l[i][i] = sum.sqrt();
            } else {
                l[i][j] = sum / l[j][j];
            }
        }
    }
}
