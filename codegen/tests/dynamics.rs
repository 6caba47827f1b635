//! Dynamics invariants of every scene, through the interpreter: M symmetric positive definite,
//! ∂M/∂q by finite differences, Ṁ − 2C skew-symmetric, C q̇ = C·q̇, g = ∂U/∂q by finite
//! differences, Lagrange's equations by finite differences of T and U, and the symbolic
//! Newton–Euler path against the Lagrangian path.

mod common;

use bf_codegen::robot::SymbolicRobot;
use common::*;

fn models() -> Vec<(String, SymbolicRobot)> {
    all_scenes()
        .into_iter()
        .map(|(n, s)| (n, SymbolicRobot::new(&s).unwrap()))
        .collect()
}

#[test]
fn mass_matrix_is_symmetric_positive_definite() {
    for (name, mut m) in models() {
        let n = m.nq();
        let ids = flat2(&m.mass_matrix());
        let mut rng = rng(11);
        for _ in 0..30 {
            let s = State::random(&m, &mut rng);
            let v = ev(&m, &ids, &s);
            assert_symmetric_positive_definite(&name, &v, n, &s.q);
        }
    }
}

#[test]
fn dmass_dq_matches_finite_differences() {
    for (name, mut m) in models() {
        let n = m.nq();
        let mm = flat2(&m.mass_matrix());
        let dm = m.dmass_dq();
        let mut rng = rng(12);
        for _ in 0..10 {
            let s = State::random(&m, &mut rng);
            for k in 0..n {
                let exact = ev(&m, &flat2(&dm[k]), &s);
                let approx = fd(&m, &mm, &s, &unit(n, k), 1e-5);
                let e = rel_err(&exact, &approx, 1e-3);
                assert!(e < 1e-7, "{name}: dM/dq{k} error {e}");
            }
        }
    }
}

#[test]
fn mdot_minus_2c_is_skew_symmetric_and_cqd_matches() {
    for (name, mut m) in models() {
        let n = m.nq();
        let dm = flat3(&m.dmass_dq());
        let c = flat2(&m.coriolis_matrix());
        let cqd = m.coriolis_qd();
        let mut rng = rng(13);
        for _ in 0..20 {
            let s = State::random(&m, &mut rng);
            let dmv = ev(&m, &dm, &s);
            let cv = ev(&m, &c, &s);
            let scale = cv.iter().fold(1e-3f64, |a, x| a.max(x.abs()));
            let mut nmat = vec![vec![0.0; n]; n];
            for i in 0..n {
                for j in 0..n {
                    let mdot: f64 = (0..n).map(|k| dmv[k * n * n + i * n + j] * s.qd[k]).sum();
                    nmat[i][j] = mdot - 2.0 * cv[i * n + j];
                }
            }
            for i in 0..n {
                for j in 0..n {
                    let e = (nmat[i][j] + nmat[j][i]).abs() / scale;
                    assert!(e < 1e-13, "{name}: Mdot - 2C not skew ({i},{j}): {e}");
                }
            }
            let cq = ev(&m, &cqd, &s);
            let cq2: Vec<f64> = (0..n)
                .map(|i| (0..n).map(|j| cv[i * n + j] * s.qd[j]).sum())
                .collect();
            let e = rel_err(&cq, &cq2, 1e-3);
            assert!(e < 1e-12, "{name}: coriolis_qd vs C qd: {e}");
        }
    }
}

#[test]
fn gravity_is_gradient_of_potential() {
    for (name, mut m) in models() {
        let n = m.nq();
        let u = m.potential();
        let g = m.gravity();
        let mut rng = rng(14);
        for _ in 0..20 {
            let s = State::random(&m, &mut rng);
            let gv = ev(&m, &g, &s);
            let fdg: Vec<f64> = (0..n)
                .map(|k| fd(&m, &[u], &s, &unit(n, k), 1e-5)[0])
                .collect();
            let e = rel_err(&gv, &fdg, 1e-2);
            assert!(e < 1e-7, "{name}: g vs dU/dq: {e}");
        }
    }
}

/// C q̇ + g from Lagrange's equations with q̈ = 0, by finite differences of M and U only:
/// d/dt(M q̇) − ∂T/∂q + ∂U/∂q = Ṁ q̇ − ∂(½ q̇ᵀ M q̇)/∂q + ∂U/∂q.
#[test]
fn lagrange_equations_by_finite_differences() {
    for (name, mut m) in models() {
        let n = m.nq();
        let mm = flat2(&m.mass_matrix());
        let u = m.potential();
        let lag = m.cqd_g();
        let mut rng = rng(15);
        for _ in 0..10 {
            let s = State::random(&m, &mut rng);
            let t_of = |st: &State| {
                let mv = ev(&m, &mm, st);
                let mut t = 0.0;
                for i in 0..n {
                    for j in 0..n {
                        t += 0.5 * s.qd[i] * mv[i * n + j] * s.qd[j];
                    }
                }
                t
            };
            let h = 1e-5;
            let mdot = fd(&m, &mm, &s, &s.qd, h);
            let mut want = vec![0.0; n];
            for i in 0..n {
                let mdq: f64 = (0..n).map(|j| mdot[i * n + j] * s.qd[j]).sum();
                let e = unit(n, i);
                let dt = (t_of(&s.moved(&e, h)) - t_of(&s.moved(&e, -h))) / (2.0 * h);
                let du = fd(&m, &[u], &s, &e, h)[0];
                want[i] = mdq - dt + du;
            }
            let got = ev(&m, &lag, &s);
            let err = rel_err(&got, &want, 1e-2);
            assert!(err < 1e-6, "{name}: Lagrangian C qd + g vs FD: {err}");
        }
    }
}

#[test]
fn newton_euler_agrees_with_lagrangian() {
    for (name, mut m) in models() {
        let lag = m.cqd_g();
        let rnea = m.cqd_g_rnea();
        let mut rng = rng(16);
        for _ in 0..200 {
            let s = State::random(&m, &mut rng);
            let a = ev(&m, &lag, &s);
            let b = ev(&m, &rnea, &s);
            let e = rel_err(&a, &b, 1e-3);
            assert!(
                e < 1e-12,
                "{name}: RNEA vs Lagrangian: {e} ({a:?} vs {b:?})"
            );
        }
    }
}

#[test]
fn christoffel_symbols_follow_their_definition() {
    for (name, mut m) in models() {
        let n = m.nq();
        let dm = flat3(&m.dmass_dq());
        let ch = flat3(&m.christoffel());
        let mut rng = rng(17);
        let s = State::random(&m, &mut rng);
        let d = ev(&m, &dm, &s);
        let c = ev(&m, &ch, &s);
        let dmk = |k: usize, i: usize, j: usize| d[k * n * n + i * n + j];
        for i in 0..n {
            for j in 0..n {
                for k in 0..n {
                    let want = 0.5 * (dmk(k, i, j) + dmk(j, i, k) - dmk(i, j, k));
                    let got = c[i * n * n + j * n + k];
                    assert!((got - want).abs() <= 1e-15 * (1.0 + want.abs()), "{name}");
                    // c_ijk = c_ikj
                    assert!((got - c[i * n * n + k * n + j]).abs() <= 1e-15, "{name}");
                }
            }
        }
    }
}
