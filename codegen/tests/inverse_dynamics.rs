//! The inverse-dynamics family (`inverse_dynamics`, `inverse_dynamics_dq`,
//! `inverse_dynamics_dqd`, `forward_dynamics`, `regressor`) through the interpreter:
//! closed forms of a polar R-P arm (prismatic joint), central finite differences for ∂τ/∂q and
//! ∂τ/∂q̇, Y π = τ for random inertial parameters, the forward/inverse round trip, and
//! τ(q, q̇, 0) = C q̇ + g, τ = M q̈ + C q̇ + g against the Lagrangian kernels of every scene.

mod common;

use bf_codegen::Scene;
use bf_codegen::interp::Tape;
use bf_codegen::kernels::build_kernel;
use bf_codegen::robot::{SymbolicRobot, inertial_parameters};
use bf_codegen::spec::InertiaSpec;
use common::{all_scenes, rand_vec, rng, test_scene};
use rand::Rng;
use rand_chacha::ChaCha8Rng;

/// Every scene, including the prismatic test scenes.
fn scenes() -> Vec<(String, Scene)> {
    let mut v = all_scenes();
    for n in ["polar_rp", "prismatic_mod", "prismatic_std"] {
        v.push((n.into(), test_scene(n)));
    }
    v
}

/// Inputs of one evaluation: q, q̇, and u (q̈ or τ, whichever the kernel takes).
struct Input<'a> {
    q: &'a [f64],
    qd: &'a [f64],
    u: &'a [f64],
}

/// Evaluates kernel `name` of `model` (all outputs, row-major) with the parameters at their
/// defaults.
fn kernel(model: &mut SymbolicRobot, name: &str, x: &Input) -> Vec<f64> {
    let def = build_kernel(model, name).unwrap();
    let ids: Vec<_> = def.outputs.iter().flat_map(|o| o.ids.clone()).collect();
    let l = model.layout;
    let n = l.nq;
    let mut v = vec![0.0; l.n_vars_all()];
    v[..n].copy_from_slice(x.q);
    v[n..2 * n].copy_from_slice(x.qd);
    v[2 * n + 3] = 0.01;
    for (i, p) in model.params.iter().enumerate() {
        v[l.param(i) as usize] = p.1;
    }
    for i in 0..n {
        v[l.qdd(i) as usize] = x.u[i];
        v[l.tau(i) as usize] = x.u[i];
    }
    Tape::new(&model.g, &ids).eval::<f64>(&v)
}

/// A random state and joint acceleration: q ∈ [−3, 3]ⁿ, q̇ ∈ [−2, 2]ⁿ, q̈ ∈ [−4, 4]ⁿ (drawn in
/// that order).
struct Sample {
    q: Vec<f64>,
    qd: Vec<f64>,
    qdd: Vec<f64>,
}

impl Sample {
    fn random(r: &mut ChaCha8Rng, n: usize) -> Self {
        let q = rand_vec(r, n, -3.0, 3.0);
        let qd = rand_vec(r, n, -2.0, 2.0);
        let qdd = rand_vec(r, n, -4.0, 4.0);
        Sample { q, qd, qdd }
    }

    /// The kernel input with u = q̈.
    fn input(&self) -> Input<'_> {
        Input {
            q: &self.q,
            qd: &self.qd,
            u: &self.qdd,
        }
    }
}

/// Calls `check(scene name, model, sample)` for `per_scene` random samples of every scene
/// (rng seeded with `seed`).
fn for_random_samples(
    seed: u64,
    per_scene: usize,
    mut check: impl FnMut(&str, &mut SymbolicRobot, &Sample),
) {
    let mut r = rng(seed);
    for (name, scene) in scenes() {
        let mut model = SymbolicRobot::new(&scene).unwrap();
        let n = model.nq();
        for _ in 0..per_scene {
            let s = Sample::random(&mut r, n);
            check(&name, &mut model, &s);
        }
    }
}

fn close(a: &[f64], b: &[f64], rel: f64, what: &str) {
    let scale = b.iter().fold(1.0f64, |m, x| m.max(x.abs()));
    for (i, (x, y)) in a.iter().zip(b).enumerate() {
        assert!(
            (x - y).abs() <= rel * scale,
            "{what}[{i}]: {x} vs {y} (scale {scale})"
        );
    }
    assert_eq!(a.len(), b.len(), "{what}: length");
}

#[test]
fn polar_arm_matches_closed_form() {
    let mut model = SymbolicRobot::new(&test_scene("polar_rp")).unwrap();
    let (m2, lc, i1, i2, g) = (0.8, 0.1, 0.3, 0.05, 9.81);
    let mut r = rng(11);
    for _ in 0..30 {
        let q: [f64; 2] = [r.random_range(-3.0..3.0), r.random_range(-0.5..1.5)];
        let qd = rand_vec(&mut r, 2, -2.0, 2.0);
        let qdd = rand_vec(&mut r, 2, -5.0, 5.0);
        let rad = q[1] + lc;
        let (s1, c1) = libm::sincos(q[0]);
        let mm = [[i1 + i2 + m2 * rad * rad, 0.0], [0.0, m2]];
        let cqd = [2.0 * m2 * rad * qd[0] * qd[1], -m2 * rad * qd[0] * qd[0]];
        let grav = [m2 * g * rad * c1, m2 * g * s1];
        let tau: Vec<f64> = (0..2)
            .map(|i| mm[i][0] * qdd[0] + mm[i][1] * qdd[1] + cqd[i] + grav[i])
            .collect();
        let x = Input {
            q: &q,
            qd: &qd,
            u: &qdd,
        };
        close(
            &kernel(&mut model, "inverse_dynamics", &x),
            &tau,
            1e-13,
            "τ",
        );
        close(
            &kernel(&mut model, "mass_matrix", &x),
            &[mm[0][0], 0.0, 0.0, m2],
            1e-14,
            "M",
        );
        let h: Vec<f64> = (0..2).map(|i| cqd[i] + grav[i]).collect();
        close(&kernel(&mut model, "cqd_g", &x), &h, 1e-13, "C q̇ + g");
        close(&kernel(&mut model, "cqd_g_rnea", &x), &h, 1e-13, "RNEA");
        let pos = kernel(&mut model, "frames", &x);
        close(
            &pos[3..6],
            &[q[1] * c1, q[1] * s1, 0.0],
            1e-14,
            "tip position",
        );
        let xf = Input {
            q: &q,
            qd: &qd,
            u: &tau,
        };
        close(
            &kernel(&mut model, "forward_dynamics", &xf),
            &qdd,
            1e-12,
            "q̈",
        );
    }
}

#[test]
fn inverse_dynamics_is_m_qdd_plus_cqd_g_and_round_trips() {
    for_random_samples(12, 10, |name, model, s| {
        let n = model.nq();
        let x = s.input();
        let tau = kernel(model, "inverse_dynamics", &x);
        let m = kernel(model, "mass_matrix", &x);
        let h = kernel(model, "cqd_g", &x);
        let want: Vec<f64> = (0..n)
            .map(|i| h[i] + (0..n).map(|j| m[i * n + j] * s.qdd[j]).sum::<f64>())
            .collect();
        close(&tau, &want, 1e-11, &format!("{name}: τ vs M q̈ + C q̇ + g"));
        let xf = Input {
            q: &s.q,
            qd: &s.qd,
            u: &tau,
        };
        let back = kernel(model, "forward_dynamics", &xf);
        close(
            &back,
            &s.qdd,
            1e-12,
            &format!("{name}: forward(inverse(q̈))"),
        );
    });
}

#[test]
fn derivatives_match_central_differences() {
    for_random_samples(13, 3, |name, model, s| {
        let n = model.nq();
        let x = s.input();
        let dq = kernel(model, "inverse_dynamics_dq", &x);
        let dqd = kernel(model, "inverse_dynamics_dqd", &x);
        let h = 1e-5;
        for k in 0..n {
            for (which, exact) in [("q", &dq), ("q̇", &dqd)] {
                let shifted = |d: f64| {
                    let (mut q2, mut qd2) = (s.q.clone(), s.qd.clone());
                    if which == "q" {
                        q2[k] += d;
                    } else {
                        qd2[k] += d;
                    }
                    (q2, qd2)
                };
                let (qa, qda) = shifted(h);
                let (qb, qdb) = shifted(-h);
                let fa = kernel(
                    model,
                    "inverse_dynamics",
                    &Input {
                        q: &qa,
                        qd: &qda,
                        u: &s.qdd,
                    },
                );
                let fb = kernel(
                    model,
                    "inverse_dynamics",
                    &Input {
                        q: &qb,
                        qd: &qdb,
                        u: &s.qdd,
                    },
                );
                let fdv: Vec<f64> = (0..n).map(|i| (fa[i] - fb[i]) / (2.0 * h)).collect();
                let col: Vec<f64> = (0..n).map(|i| exact[i * n + k]).collect();
                close(&col, &fdv, 1e-7, &format!("{name}: ∂τ/∂{which}_{k}"));
            }
        }
    });
}

/// A copy of `scene` with random masses, COGs and (positive definite, full) inertia tensors.
fn randomised(scene: &Scene, r: &mut impl Rng) -> Scene {
    let mut s = scene.clone();
    s.runtime_parameters.clear();
    for l in &mut s.links {
        l.mass = r.random_range(0.1..5.0);
        l.com = std::array::from_fn(|_| r.random_range(-0.3..0.3));
        let a: [[f64; 3]; 3] =
            std::array::from_fn(|_| std::array::from_fn(|_| r.random_range(-0.3..0.3)));
        let mut m = [[0.0; 3]; 3];
        for i in 0..3 {
            for j in 0..3 {
                m[i][j] = (0..3).map(|k| a[i][k] * a[j][k]).sum::<f64>()
                    + if i == j { 0.01 } else { 0.0 };
            }
        }
        l.inertia = InertiaSpec::Full(m);
    }
    s
}

#[test]
fn regressor_times_parameters_is_tau() {
    let mut r = rng(14);
    for (name, scene) in scenes() {
        for _ in 0..3 {
            let s = randomised(&scene, &mut r);
            let pi = inertial_parameters(&s);
            let mut model = SymbolicRobot::new(&s).unwrap();
            let n = model.nq();
            let sample = Sample::random(&mut r, n);
            let x = sample.input();
            let y = kernel(&mut model, "regressor", &x);
            assert_eq!(y.len(), n * 10 * n);
            let tau = kernel(&mut model, "inverse_dynamics", &x);
            let ypi: Vec<f64> = (0..n)
                .map(|i| (0..10 * n).map(|c| y[i * 10 * n + c] * pi[c]).sum())
                .collect();
            close(&ypi, &tau, 1e-11, &format!("{name}: Y π"));
            // Y holds no inertial parameter: the same Y serves every π.
            let s2 = randomised(&scene, &mut r);
            let mut m2 = SymbolicRobot::new(&s2).unwrap();
            close(
                &kernel(&mut m2, "regressor", &x),
                &y,
                1e-15,
                &format!("{name}: Y independent of π"),
            );
        }
    }
}
