//! Self-checks of the reference implementation: every quantity is tested against an invariant,
//! a finite difference of a more primitive quantity, or an independent algorithm (recursive
//! Newton–Euler, brute-force distance sampling, modified ↔ standard DH equivalence, energy
//! balance of an RK4 integration).

use crate::appendix::AppendixParams;
use crate::reference::{ContactKind, Pose, RefBall, RefLink, Reference, dual_along};
use crate::small::{axis_rotation, cross, dot, matmul, matvec, norm, sub, transpose};
use bf_codegen::spec::{DhConvention, Scene};
use nalgebra::{DMatrix, DVector};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use std::f64::consts::{FRAC_PI_2, PI};

fn rng(seed: u64) -> ChaCha8Rng {
    ChaCha8Rng::seed_from_u64(seed)
}

fn uni(r: &mut ChaCha8Rng, lo: f64, hi: f64) -> f64 {
    r.random_range(lo..hi)
}

fn rvec(r: &mut ChaCha8Rng, n: usize, s: f64) -> Vec<f64> {
    (0..n).map(|_| uni(r, -s, s)).collect()
}

fn random_rotation(r: &mut ChaCha8Rng) -> [[f64; 3]; 3] {
    let a = axis_rotation(2, uni(r, -PI, PI));
    let b = axis_rotation(1, uni(r, -PI, PI));
    let c = axis_rotation(0, uni(r, -PI, PI));
    matmul(&matmul(&a, &b), &c)
}

fn random_spd(r: &mut ChaCha8Rng) -> [[f64; 3]; 3] {
    let mut a = [[0.0; 3]; 3];
    for row in a.iter_mut() {
        for x in row.iter_mut() {
            *x = uni(r, -0.3, 0.3);
        }
    }
    let mut m = matmul(&a, &transpose(&a));
    for (i, row) in m.iter_mut().enumerate() {
        row[i] += 0.01;
    }
    m
}

/// A random serial arm: generic DH rows (some α at exact quarter turns), base and tool
/// transforms, full inertia tensors, off-axis COGs, a tilted gravity vector.
fn random_robot(r: &mut ChaCha8Rng, n: usize, conv: DhConvention) -> Reference {
    let links = (0..n)
        .map(|_| RefLink {
            a: uni(r, -0.5, 1.0),
            alpha: if r.random_bool(0.5) {
                [0.0, FRAC_PI_2, -FRAC_PI_2][r.random_range(0..3)]
            } else {
                uni(r, -PI, PI)
            },
            d: uni(r, -0.5, 0.5),
            offset: uni(r, -1.0, 1.0),
            prismatic: false,
            mass: uni(r, 0.1, 2.0),
            com: [uni(r, -0.5, 0.5), uni(r, -0.5, 0.5), uni(r, -0.5, 0.5)],
            inertia: random_spd(r),
        })
        .collect();
    Reference {
        convention: conv,
        base: Pose {
            rotation: random_rotation(r),
            translation: [uni(r, -1.0, 1.0), uni(r, -1.0, 1.0), uni(r, -1.0, 1.0)],
        },
        tool: Some(Pose {
            rotation: random_rotation(r),
            translation: [uni(r, -0.3, 0.3), uni(r, -0.3, 0.3), uni(r, -0.3, 0.3)],
        }),
        gravity: [uni(r, -3.0, 3.0), uni(r, -3.0, 3.0), -9.81],
        links,
        ball: Some(RefBall {
            center: [uni(r, -0.5, 0.5), uni(r, -0.5, 0.5), uni(r, -0.5, 0.5)],
            radius: uni(r, 0.2, 1.0),
        }),
        contact_kind: Some(ContactKind::Segment),
        mu_v: 0.01,
    }
}

/// Robots exercised by the generic tests: the paper finger (non-unit, unequal parameters)
/// and random 1..7-joint arms in both conventions.
fn robots() -> Vec<Reference> {
    let mut r = rng(11);
    let mut out = vec![
        AppendixParams::paper().reference(),
        AppendixParams::unequal(0.7, 1.3).reference(),
    ];
    for n in [1usize, 2, 3, 6, 7] {
        out.push(random_robot(&mut r, n, DhConvention::Standard));
        out.push(random_robot(&mut r, n, DhConvention::Modified));
    }
    out
}

fn max_abs(m: &DMatrix<f64>) -> f64 {
    m.iter().fold(0.0, |a, &b| a.max(b.abs()))
}

fn close(a: f64, b: f64, tol: f64) -> bool {
    (a - b).abs() <= tol * (1.0 + a.abs().max(b.abs()))
}

fn assert_mat_close(a: &DMatrix<f64>, b: &DMatrix<f64>, tol: f64, what: &str) {
    assert_eq!(a.shape(), b.shape(), "{what}: shape");
    let scale = 1.0 + max_abs(a).max(max_abs(b));
    let err = max_abs(&(a - b));
    assert!(
        err <= tol * scale,
        "{what}: error {err:e} (scale {scale:e})\n{a}\n{b}"
    );
}

#[test]
fn mass_matrix_is_symmetric_positive_definite() {
    let mut r = rng(1);
    for robot in robots() {
        for _ in 0..20 {
            let q = rvec(&mut r, robot.nq(), 4.0);
            let m = robot.mass_matrix(&q);
            assert_mat_close(&m, &m.transpose(), 1e-14, "M symmetric");
            let eig = m.clone().symmetric_eigen().eigenvalues;
            assert!(eig.min() > 0.0, "M not PD: {eig}");
        }
    }
}

#[test]
fn mdot_minus_2c_is_skew_symmetric() {
    let mut r = rng(2);
    for robot in robots() {
        let n = robot.nq();
        for _ in 0..10 {
            let q = rvec(&mut r, n, 4.0);
            let qd = rvec(&mut r, n, 3.0);
            let dm = robot.dmass_dq(&q);
            let mdot = (0..n).fold(DMatrix::zeros(n, n), |acc, k| acc + &dm[k] * qd[k]);
            let c = robot.coriolis_matrix(&q, &qd);
            let s = &mdot - &c * 2.0;
            assert_mat_close(&s, &-s.transpose(), 1e-12, "Mdot - 2C skew");
            // Ṁ = C + Cᵀ is the Christoffel-form identity (not true for other factorisations).
            assert_mat_close(&mdot, &(&c + c.transpose()), 1e-12, "Mdot = C + C^T");
        }
    }
}

#[test]
fn dmass_dq_matches_central_differences() {
    let mut r = rng(3);
    let h = 1e-6;
    for robot in robots() {
        let n = robot.nq();
        let q = rvec(&mut r, n, 3.0);
        let dm = robot.dmass_dq(&q);
        for k in 0..n {
            let mut qp = q.clone();
            let mut qm = q.clone();
            qp[k] += h;
            qm[k] -= h;
            let fd = (robot.mass_matrix(&qp) - robot.mass_matrix(&qm)) / (2.0 * h);
            assert_mat_close(&dm[k], &fd, 1e-8, "dM/dq");
        }
    }
}

#[test]
fn gravity_matches_central_differences_of_potential() {
    let mut r = rng(4);
    let h = 1e-6;
    for robot in robots() {
        let n = robot.nq();
        for _ in 0..5 {
            let q = rvec(&mut r, n, 4.0);
            let g = robot.gravity(&q);
            for k in 0..n {
                let mut qp = q.clone();
                let mut qm = q.clone();
                qp[k] += h;
                qm[k] -= h;
                let fd = (robot.potential(&qp) - robot.potential(&qm)) / (2.0 * h);
                assert!(close(g[k], fd, 1e-8), "g[{k}] = {} vs FD {fd}", g[k]);
            }
        }
    }
}

/// J_p is the FD derivative of the tip position and J_o the vee of Ṙ Rᵀ (angular velocity).
#[test]
fn tip_jacobian_matches_finite_differences() {
    let mut r = rng(5);
    let h = 1e-6;
    for robot in robots() {
        let n = robot.nq();
        for _ in 0..5 {
            let q = rvec(&mut r, n, 4.0);
            let (jp, jo) = robot.tip_jacobian(&q);
            let (_, rot) = robot.frames(&q);
            let rt = rot[n - 1];
            for k in 0..n {
                let mut qp = q.clone();
                let mut qm = q.clone();
                qp[k] += h;
                qm[k] -= h;
                let pp = robot.tip_position(&qp);
                let pm = robot.tip_position(&qm);
                let rp = robot.frames(&qp).1[n - 1];
                let rm = robot.frames(&qm).1[n - 1];
                let mut rdot = [[0.0; 3]; 3];
                for i in 0..3 {
                    for j in 0..3 {
                        rdot[i][j] = (rp[i][j] - rm[i][j]) / (2.0 * h);
                    }
                }
                let w = matmul(&rdot, &transpose(&rt));
                let omega = [w[2][1], w[0][2], w[1][0]];
                for i in 0..3 {
                    let fd = (pp[i] - pm[i]) / (2.0 * h);
                    assert!(close(jp[(i, k)], fd, 1e-8), "Jp({i},{k})");
                    assert!(close(jo[(i, k)], omega[i], 1e-8), "Jo({i},{k})");
                }
            }
        }
    }
}

#[test]
fn com_jacobians_match_finite_differences() {
    let mut r = rng(6);
    let h = 1e-6;
    for robot in robots() {
        let n = robot.nq();
        let q = rvec(&mut r, n, 4.0);
        let jac = robot.com_jacobians(&q);
        for k in 0..n {
            let mut qp = q.clone();
            let mut qm = q.clone();
            qp[k] += h;
            qm[k] -= h;
            let cp = robot.com_positions_f64(&qp);
            let cm = robot.com_positions_f64(&qm);
            for (link, (jp, jo)) in jac.iter().enumerate() {
                for i in 0..3 {
                    let fd = (cp[link][i] - cm[link][i]) / (2.0 * h);
                    assert!(close(jp[(i, k)], fd, 1e-8), "Jp_com{link}({i},{k})");
                }
                // Joints beyond the link do not move it.
                if k > link {
                    assert_eq!(jo[(0, k)].abs() + jo[(1, k)].abs() + jo[(2, k)].abs(), 0.0);
                }
            }
        }
    }
}

/// J̇ q̇ = d/ds [J(q + s q̇) q̇] at s = 0 (the trajectory q(t) = q + t q̇ has q̈ = 0).
#[test]
fn jdot_qd_matches_finite_differences_along_a_trajectory() {
    let mut r = rng(7);
    let h = 1e-6;
    for robot in robots() {
        let n = robot.nq();
        for _ in 0..5 {
            let q = rvec(&mut r, n, 4.0);
            let qd = rvec(&mut r, n, 2.0);
            let jd = robot.tip_jdot_qd(&q, &qd);
            let jq = |s: f64| {
                let qs: Vec<f64> = q.iter().zip(&qd).map(|(a, b)| a + s * b).collect();
                let (jp, jo) = robot.tip_jacobian(&qs);
                let v = DVector::from_column_slice(&qd);
                (jp * &v, jo * &v)
            };
            let (pp, op) = jq(h);
            let (pm, om) = jq(-h);
            for i in 0..3 {
                assert!(close(jd[i], (pp[i] - pm[i]) / (2.0 * h), 1e-7), "lin {i}");
                assert!(
                    close(jd[3 + i], (op[i] - om[i]) / (2.0 * h), 1e-7),
                    "ang {i}"
                );
            }
        }
    }
}

/// Newton–Euler (no M, C, g involved) equals M q̈ + C q̇ + g: checks eq. 22a, the Christoffel
/// construction and g = ∂U/∂q at once, for full inertias, base/tool transforms and both DH
/// conventions.
#[test]
fn newton_euler_equals_lagrangian_dynamics() {
    let mut r = rng(8);
    for robot in robots() {
        let n = robot.nq();
        for _ in 0..10 {
            let q = rvec(&mut r, n, 4.0);
            let qd = rvec(&mut r, n, 3.0);
            let qdd = rvec(&mut r, n, 5.0);
            let ne = robot.inverse_dynamics_ne(&q, &qd, &qdd);
            let lag =
                robot.mass_matrix(&q) * DVector::from_column_slice(&qdd) + robot.cqd_g(&q, &qd);
            let scale = 1.0 + ne.amax();
            assert!(
                (&ne - &lag).amax() <= 1e-12 * scale,
                "NE {ne} vs Lagrange {lag}"
            );
        }
    }
}

/// A modified-DH description of a standard-DH arm (rows shifted by one, last a, α moved into
/// the tool, COG and inertia re-expressed in the proximal frames) has identical tip pose,
/// Jacobian, M and g.
#[test]
fn modified_dh_equals_equivalent_standard_dh() {
    let mut r = rng(9);
    for n in [2usize, 3, 6] {
        let mut std_robot = random_robot(&mut r, n, DhConvention::Standard);
        std_robot.tool = None;
        let mut modi = std_robot.clone();
        modi.convention = DhConvention::Modified;
        for i in 0..n {
            let s = &std_robot.links[i];
            let (a_prev, al_prev) = if i == 0 {
                (0.0, 0.0)
            } else {
                (std_robot.links[i - 1].a, std_robot.links[i - 1].alpha)
            };
            // std frame i = mod frame i · Tx(a_i) Rx(α_i).
            let rx = axis_rotation(0, s.alpha);
            let c = matvec(&rx, s.com);
            modi.links[i] = RefLink {
                a: a_prev,
                alpha: al_prev,
                com: [c[0] + s.a, c[1], c[2]],
                inertia: matmul(&matmul(&rx, &s.inertia), &transpose(&rx)),
                ..*s
            };
        }
        let last = std_robot.links[n - 1];
        modi.tool = Some(Pose {
            rotation: axis_rotation(0, last.alpha),
            translation: [last.a, 0.0, 0.0],
        });
        for _ in 0..5 {
            let q = rvec(&mut r, n, 4.0);
            let (ps, rs) = std_robot.frames(&q);
            let (pm, rm) = modi.frames(&q);
            for i in 0..3 {
                assert!(close(ps[n - 1][i], pm[n - 1][i], 1e-13));
                for j in 0..3 {
                    assert!(close(rs[n - 1][i][j], rm[n - 1][i][j], 1e-13));
                }
            }
            let (jps, jos) = std_robot.tip_jacobian(&q);
            let (jpm, jom) = modi.tip_jacobian(&q);
            assert_mat_close(&jps, &jpm, 1e-13, "Jp std vs mod");
            assert_mat_close(&jos, &jom, 1e-13, "Jo std vs mod");
            assert_mat_close(
                &std_robot.mass_matrix(&q),
                &modi.mass_matrix(&q),
                1e-13,
                "M std vs mod",
            );
            let gs = std_robot.gravity(&q);
            let gm = modi.gravity(&q);
            assert!((gs - gm).amax() < 1e-12);
        }
    }
}

/// Contact geometry: h is the exact sphere-to-segment distance (brute force over 20 001
/// samples of the segment), p_c is the closest segment point, and n, J_c, v_c behave.
#[test]
fn contact_distance_matches_brute_force_sampling() {
    let mut r = rng(10);
    let mut robots = robots();
    robots.retain(|x| x.ball.is_some());
    for robot in robots {
        let n = robot.nq();
        let ball = robot.ball.unwrap_or(RefBall {
            center: [0.0; 3],
            radius: 1.0,
        });
        let a_n = robot.links[n - 1].a;
        if a_n <= 0.0 {
            continue;
        }
        for _ in 0..20 {
            let q = rvec(&mut r, n, 4.0);
            let qd = rvec(&mut r, n, 2.0);
            let c = robot.contact(&q, &qd, &[0.1, -0.2, 0.3], None).unwrap();
            let (pos, rot) = robot.frames(&q);
            let p_e = pos[n - 1];
            let e_x = [rot[n - 1][0][0], rot[n - 1][1][0], rot[n - 1][2][0]];
            let samples = 20_000;
            let mut best = f64::INFINITY;
            for s in 0..=samples {
                let t = -a_n * s as f64 / samples as f64;
                let x = [
                    p_e[0] + t * e_x[0],
                    p_e[1] + t * e_x[1],
                    p_e[2] + t * e_x[2],
                ];
                best = best.min(norm(sub(x, ball.center)) - ball.radius);
            }
            assert!(c.h <= best + 1e-14, "h = {} above sampled min {best}", c.h);
            assert!(best - c.h <= a_n / samples as f64 + 1e-14, "h too small");
            // p_c lies on the segment, r_c = p_c − o_b, |n| = 1, n ∥ r_c.
            let along = dot(sub(c.p_c, p_e), e_x);
            assert!(along <= 1e-14 && along >= -a_n - 1e-14);
            assert!(close(along, c.sat_alpha, 1e-12));
            assert!(close(norm(c.n), 1.0, 1e-14));
            assert!(norm(cross(c.n, c.r_c)) < 1e-12 * (1.0 + norm(c.r_c)));
            let dv = sub(cross([0.1, -0.2, 0.3], c.r_c), c.v_c);
            assert!(norm(sub(dv, c.delta_v)) < 1e-14);
        }
    }
}

/// Time derivatives of the contact quantities against central differences along q(t) = q + t q̇
/// (away from the sat kinks), and v_c against the velocity of the material point of link n
/// at p_c (sat frozen).
#[test]
fn contact_derivatives_match_finite_differences() {
    let mut r = rng(12);
    let h = 1e-6;
    let mut checked = [0usize; 2];
    for robot in robots() {
        if robot.ball.is_none() {
            continue;
        }
        let n = robot.nq();
        let a_n = robot.links[n - 1].a;
        for smooth in [None, Some(0.05)] {
            for _ in 0..30 {
                let q = rvec(&mut r, n, 4.0);
                let qd = rvec(&mut r, n, 2.0);
                let c = robot.contact(&q, &qd, &[0.0; 3], smooth).unwrap();
                if smooth.is_none() && (c.alpha.abs() < 1e-3 || (c.alpha + a_n).abs() < 1e-3) {
                    continue;
                }
                let side = c.alpha < 0.0 && c.alpha > -a_n;
                checked[usize::from(side)] += 1;
                let at = |s: f64| {
                    let qs: Vec<f64> = q.iter().zip(&qd).map(|(a, b)| a + s * b).collect();
                    robot.contact(&qs, &qd, &[0.0; 3], smooth).unwrap()
                };
                let (cp, cm) = (at(h), at(-h));
                assert!(close(c.h_dot, (cp.h - cm.h) / (2.0 * h), 1e-7), "h_dot");
                let jcq =
                    |x: &crate::reference::RefContact| &x.j_c * DVector::from_column_slice(&qd);
                let (jp, jm) = (jcq(&cp), jcq(&cm));
                for i in 0..3 {
                    let fd = (cp.r_c[i] - cm.r_c[i]) / (2.0 * h);
                    assert!(close(c.rc_dot[i], fd, 1e-7), "rc_dot {i}");
                    let fd = (jp[i] - jm[i]) / (2.0 * h);
                    assert!(
                        close(c.jc_dot_qd[i], fd, 1e-6),
                        "jc_dot_qd {i}: {} vs {fd}",
                        c.jc_dot_qd[i]
                    );
                }
                // v_c: velocity of the link-n point at distance sat(α) along e_x (sat frozen).
                let material = |s: f64| {
                    let qs: Vec<f64> = q.iter().zip(&qd).map(|(a, b)| a + s * b).collect();
                    let (pos, rot) = robot.frames(&qs);
                    let e_x = [rot[n - 1][0][0], rot[n - 1][1][0], rot[n - 1][2][0]];
                    [0, 1, 2].map(|i| pos[n - 1][i] + c.sat_alpha * e_x[i])
                };
                let (mp, mm) = (material(h), material(-h));
                for i in 0..3 {
                    assert!(
                        close(c.v_c[i], (mp[i] - mm[i]) / (2.0 * h), 1e-7),
                        "v_c {i}"
                    );
                }
            }
        }
    }
    assert!(
        checked[0] > 10 && checked[1] > 10,
        "both branches covered: {checked:?}"
    );
}

/// sat: exact clamps to [−a_n, 0]; the smooth version tends to it as ε → 0 with error ≤ ε/2
/// (|√(x²+ε²) − |x|| ≤ ε); `kind = "tip"` gives sat ≡ 0 and J_c = J_p.
#[test]
fn saturation_variants() {
    let mut robot = AppendixParams::paper().reference();
    let mut r = rng(13);
    for _ in 0..200 {
        let q = rvec(&mut r, 3, 4.0);
        let ex = robot.contact(&q, &[0.0; 3], &[0.0; 3], None).unwrap();
        assert_eq!(ex.sat_alpha, ex.alpha.clamp(-1.0, 0.0));
        for eps in [1e-2, 1e-4, 1e-6] {
            let sm = robot.contact(&q, &[0.0; 3], &[0.0; 3], Some(eps)).unwrap();
            assert!((sm.sat_alpha - ex.sat_alpha).abs() <= eps / 2.0 + 1e-15);
            assert_eq!(sm.alpha, ex.alpha);
        }
    }
    robot.contact_kind = Some(ContactKind::Tip);
    for _ in 0..20 {
        let q = rvec(&mut r, 3, 4.0);
        let qd = rvec(&mut r, 3, 2.0);
        let c = robot.contact(&q, &qd, &[0.0; 3], Some(0.01)).unwrap();
        assert_eq!(c.sat_alpha, 0.0);
        assert_eq!(c.p_c, robot.tip_position(&q));
        let (jp, _) = robot.tip_jacobian(&q);
        assert_mat_close(&c.j_c, &jp, 0.0, "tip: J_c = J_p");
        let jd = robot.tip_jdot_qd(&q, &qd);
        for i in 0..3 {
            assert!(close(c.jc_dot_qd[i], jd[i], 1e-14));
        }
    }
}

/// Energy balance of the free finger (eq. 26a): along an RK4 solution with constant τ,
/// T + U − ∫ q̇ᵀ(τ − μ_v q̇) dt stays constant, and the work term is far from negligible.
#[test]
fn energy_balance_along_rk4_free_dynamics() {
    let mut r = rng(14);
    let mut robots = vec![AppendixParams::paper().reference()];
    robots.push(random_robot(&mut r, 4, DhConvention::Modified));
    for mut robot in robots {
        robot.mu_v = 0.005;
        let n = robot.nq();
        let tau: Vec<f64> = rvec(&mut r, n, 0.05);
        // State: q, q̇, W (work of τ and friction).
        let f = |x: &[f64]| -> Vec<f64> {
            let (q, qd) = (&x[..n], &x[n..2 * n]);
            let qdd = robot.forward_dynamics(q, qd, &tau).unwrap();
            let mut out = Vec::with_capacity(2 * n + 1);
            out.extend_from_slice(qd);
            out.extend(qdd.iter());
            out.push((0..n).map(|i| qd[i] * (tau[i] - robot.mu_v * qd[i])).sum());
            out
        };
        let mut x: Vec<f64> = rvec(&mut r, n, 2.0);
        x.extend(rvec(&mut r, n, 1.0));
        x.push(0.0);
        let energy =
            |x: &[f64]| robot.kinetic_energy(&x[..n], &x[n..2 * n]) + robot.potential(&x[..n]);
        let e0 = energy(&x);
        let dt = 1e-3;
        for _ in 0..500 {
            let k1 = f(&x);
            let x2: Vec<f64> = x.iter().zip(&k1).map(|(a, b)| a + 0.5 * dt * b).collect();
            let k2 = f(&x2);
            let x3: Vec<f64> = x.iter().zip(&k2).map(|(a, b)| a + 0.5 * dt * b).collect();
            let k3 = f(&x3);
            let x4: Vec<f64> = x.iter().zip(&k3).map(|(a, b)| a + dt * b).collect();
            let k4 = f(&x4);
            for i in 0..x.len() {
                x[i] += dt / 6.0 * (k1[i] + 2.0 * k2[i] + 2.0 * k3[i] + k4[i]);
            }
        }
        let w = x[2 * n];
        let drift = energy(&x) - e0 - w;
        let scale = e0.abs().max(w.abs()).max(1e-3);
        assert!(w.abs() > 1e-4 * scale, "work term negligible: {w}");
        assert!(
            drift.abs() < 1e-9 * scale,
            "energy drift {drift:e} (E0 {e0}, W {w})"
        );
    }
}

/// The scene file path: `Reference::new` on the paper scene text equals the hand-built paper
/// finger, and every registry constant name is accepted by `set_param` and changes the
/// matching field.
#[test]
fn scene_conversion_and_parameter_names() {
    let text =
        std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/../scenes/paper.toml"))
            .expect("scenes/paper.toml");
    let scene = Scene::from_toml_str(&text, "paper.toml").expect("paper scene parses");
    let mut from_scene = Reference::new(&scene).expect("reference");
    let mut hand = AppendixParams::paper().reference();
    hand.mu_v = 0.001;
    assert_eq!(from_scene, hand);
    let before = from_scene.clone();
    for (name, value) in scene.constants() {
        from_scene
            .set_param(&name, value + 0.125)
            .unwrap_or_else(|e| panic!("{name}: {e}"));
    }
    assert_ne!(from_scene, before);
    assert_eq!(from_scene.links[2].mass, 0.02 + 0.125);
    assert_eq!(from_scene.links[1].inertia[0][1], 0.125);
    assert_eq!(from_scene.links[1].inertia[1][0], 0.125);
    assert_eq!(from_scene.ball.map(|b| b.radius), Some(1.125));
    assert_eq!(from_scene.base.translation, [2.125, 0.125, 0.125]);
    assert!(from_scene.set_param("link4.mass", 1.0).is_err());
    assert!(from_scene.set_param("nonsense", 1.0).is_err());
    // Dual seeding helper: value part is q, derivative part the direction.
    let d = dual_along(&[1.0, 2.0], &[3.0, 4.0]);
    assert_eq!((d[1].re, d[1].eps), (2.0, 4.0));
}

/// Error paths: a massless arm has a singular M, contact needs a ball, bad TOML is reported.
#[test]
fn error_paths() {
    let mut robot = AppendixParams::paper().reference();
    for l in robot.links.iter_mut() {
        l.mass = 0.0;
        l.inertia = [[0.0; 3]; 3];
    }
    let err = robot.forward_dynamics(&[0.1, 0.2, 0.3], &[0.0; 3], &[0.0; 3]);
    assert_eq!(err, Err(crate::TestkitError::SingularMassMatrix));
    robot.ball = None;
    assert_eq!(
        robot.contact(&[0.0; 3], &[0.0; 3], &[0.0; 3], None),
        Err(crate::TestkitError::NoBall)
    );
    assert!(matches!(
        Reference::from_scene_toml("name = 3", "bad.toml"),
        Err(crate::TestkitError::InvalidScene(_))
    ));
}
