//! Kinematics of every scene through the interpreter: frames against an independent numeric DH
//! chain (standard and modified), Jacobians and J̇ q̇ against finite differences, and M
//! against the kinetic energy of finite-difference link velocities (eq. 22a).

mod common;

use bf_codegen::robot::{Pose, SymbolicRobot};
use bf_codegen::spec::{DhConvention, Scene};
use common::*;

type M4 = [[f64; 4]; 4];

fn mul4(a: &M4, b: &M4) -> M4 {
    let mut c = [[0.0; 4]; 4];
    for i in 0..4 {
        for j in 0..4 {
            c[i][j] = (0..4).map(|k| a[i][k] * b[k][j]).sum();
        }
    }
    c
}

fn rt(r: [[f64; 3]; 3], t: [f64; 3]) -> M4 {
    let mut m = [[0.0; 4]; 4];
    for i in 0..3 {
        for j in 0..3 {
            m[i][j] = r[i][j];
        }
        m[i][3] = t[i];
    }
    m[3][3] = 1.0;
    m
}

fn rz(th: f64) -> M4 {
    let (s, c) = libm::sincos(th);
    rt([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]], [0.0; 3])
}
fn rx(al: f64) -> M4 {
    let (s, c) = libm::sincos(al);
    rt([[1.0, 0.0, 0.0], [0.0, c, -s], [0.0, s, c]], [0.0; 3])
}
fn tz(d: f64) -> M4 {
    rt(
        [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]],
        [0.0, 0.0, d],
    )
}
fn tx(a: f64) -> M4 {
    rt(
        [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]],
        [a, 0.0, 0.0],
    )
}

/// World transforms of frames 0..=n and the tip, straight from the DH definitions.
fn reference_frames(scene: &Scene, q: &[f64]) -> (Vec<M4>, M4) {
    let mut t = rt(scene.base_rotation(), scene.base_translation());
    let mut out = vec![t];
    for (i, l) in scene.links.iter().enumerate() {
        let th = q[i] + l.offset.map_or(0.0, |o| o.radians());
        let al = l.alpha.radians();
        let a = match scene.dh {
            DhConvention::Standard => mul4(&mul4(&rz(th), &tz(l.d)), &mul4(&tx(l.a), &rx(al))),
            DhConvention::Modified => mul4(&mul4(&rx(al), &tx(l.a)), &mul4(&rz(th), &tz(l.d))),
        };
        t = mul4(&t, &a);
        out.push(t);
    }
    let tip = mul4(&t, &rt(scene.tool_rotation(), scene.tool_translation()));
    (out, tip)
}

fn pose_ids(p: &Pose) -> Vec<bf_codegen::graph::Id> {
    let mut v: Vec<_> = p.r.iter().flatten().copied().collect();
    v.extend(p.t);
    v
}

fn m4_flat(m: &M4) -> Vec<f64> {
    let mut v = Vec::new();
    for i in 0..3 {
        for j in 0..3 {
            v.push(m[i][j]);
        }
    }
    for i in 0..3 {
        v.push(m[i][3]);
    }
    v
}

#[test]
fn frames_match_numeric_dh_chain() {
    for (name, sc) in all_scenes() {
        let mut m = SymbolicRobot::new(&sc).unwrap();
        let n = m.nq();
        let frames = m.frames();
        let mut rng = rng(21);
        for _ in 0..20 {
            let s = State::random(&m, &mut rng);
            // runtime parameters at their defaults = scene values
            let (refs, tip) = reference_frames(&sc, &s.q);
            for i in 0..n {
                let got = ev(&m, &pose_ids(&frames[i]), &s);
                let want = if i + 1 == n {
                    m4_flat(&tip)
                } else {
                    m4_flat(&refs[i + 1])
                };
                let e = rel_err(&got, &want, 1.0);
                assert!(e < 1e-14, "{name}: frame {} differs by {e}", i + 1);
            }
            let wf = ev(&m, &pose_ids(&m.world_frame(n)), &s);
            assert!(
                rel_err(&wf, &m4_flat(&refs[n]), 1.0) < 1e-14,
                "{name}: last DH frame"
            );
            let _ = m.tip_jacobian();
        }
    }
}

#[test]
fn tip_jacobian_matches_finite_differences() {
    for (name, sc) in all_scenes() {
        let mut m = SymbolicRobot::new(&sc).unwrap();
        let n = m.nq();
        let (jp, jo) = m.tip_jacobian();
        let tip = m.tip_pose();
        let pos: Vec<_> = tip.t.to_vec();
        let rot: Vec<_> = tip.r.iter().flatten().copied().collect();
        let mut rng = rng(22);
        for _ in 0..10 {
            let s = State::random(&m, &mut rng);
            let jpv = ev(&m, &flat2(&jp), &s);
            let jov = ev(&m, &flat2(&jo), &s);
            let r = ev(&m, &rot, &s);
            for k in 0..n {
                let dp = fd(&m, &pos, &s, &unit(n, k), 1e-6);
                let col: Vec<f64> = (0..3).map(|i| jpv[i * n + k]).collect();
                assert!(rel_err(&col, &dp, 1.0) < 1e-8, "{name}: J_p column {k}");
                // Ṙ Rᵀ = S(ω): ω_x = (ṘRᵀ)_21, ω_y = (ṘRᵀ)_02, ω_z = (ṘRᵀ)_10.
                let dr = fd(&m, &rot, &s, &unit(n, k), 1e-6);
                let w =
                    |i: usize, j: usize| (0..3).map(|l| dr[i * 3 + l] * r[j * 3 + l]).sum::<f64>();
                let omega = [w(2, 1), w(0, 2), w(1, 0)];
                let col: Vec<f64> = (0..3).map(|i| jov[i * n + k]).collect();
                assert!(rel_err(&col, &omega, 1.0) < 1e-8, "{name}: J_o column {k}");
            }
        }
    }
}

#[test]
fn com_jacobians_match_finite_differences() {
    for (name, sc) in all_scenes() {
        let mut m = SymbolicRobot::new(&sc).unwrap();
        let n = m.nq();
        let coms = m.com_world();
        let js = m.com_jacobians();
        let mut rng = rng(23);
        let s = State::random(&m, &mut rng);
        for (i, (jp, _)) in js.iter().enumerate() {
            let jv = ev(&m, &flat2(jp), &s);
            for k in 0..n {
                let dp = fd(&m, &coms[i], &s, &unit(n, k), 1e-6);
                let col: Vec<f64> = (0..3).map(|r| jv[r * n + k]).collect();
                assert!(rel_err(&col, &dp, 1.0) < 1e-8, "{name}: COG {i} column {k}");
            }
        }
    }
}

#[test]
fn tip_jdot_qd_matches_finite_differences() {
    for (name, sc) in all_scenes() {
        let mut m = SymbolicRobot::new(&sc).unwrap();
        let n = m.nq();
        let (jp, jo) = m.tip_jacobian();
        let jdq = m.tip_jdot_qd();
        let mut j = flat2(&jp);
        j.extend(flat2(&jo));
        let mut rng = rng(24);
        for _ in 0..10 {
            let s = State::random(&m, &mut rng);
            let dj = fd(&m, &j, &s, &s.qd, 1e-6);
            let want: Vec<f64> = (0..6)
                .map(|r| (0..n).map(|c| dj[r * n + c] * s.qd[c]).sum())
                .collect();
            let got = ev(&m, &jdq, &s);
            assert!(
                rel_err(&got, &want, 1.0) < 1e-7,
                "{name}: Jdot qd {got:?} vs {want:?}"
            );
        }
    }
}

/// ½ q̇ᵀ M q̇ equals Σ ½ m_i |v_i|² + ½ ω_iᵀ R_i I_i R_iᵀ ω_i with v_i, ω_i from finite
/// differences of the link poses along q̇ (independent of the Jacobians used to build M).
#[test]
fn mass_matrix_gives_kinetic_energy_of_link_motion() {
    for (name, sc) in all_scenes() {
        let mut m = SymbolicRobot::new(&sc).unwrap();
        let n = m.nq();
        let mm = flat2(&m.mass_matrix());
        let coms = m.com_world();
        let mut rng = rng(25);
        for _ in 0..10 {
            let s = State::random(&m, &mut rng);
            let mv = ev(&m, &mm, &s);
            let mut t_m = 0.0;
            for i in 0..n {
                for j in 0..n {
                    t_m += 0.5 * s.qd[i] * mv[i * n + j] * s.qd[j];
                }
            }
            let mut t_ref = 0.0;
            for i in 0..n {
                let l = &sc.links[i];
                let v = fd(&m, &coms[i], &s, &s.qd, 1e-6);
                let rot: Vec<_> = m.world_frame(i + 1).r.iter().flatten().copied().collect();
                let r = ev(&m, &rot, &s);
                let dr = fd(&m, &rot, &s, &s.qd, 1e-6);
                let w =
                    |a: usize, b: usize| (0..3).map(|k| dr[a * 3 + k] * r[b * 3 + k]).sum::<f64>();
                let om = [w(2, 1), w(0, 2), w(1, 0)];
                // body-frame ω = Rᵀ ω
                let ob: Vec<f64> = (0..3)
                    .map(|c| (0..3).map(|k| r[k * 3 + c] * om[k]).sum())
                    .collect();
                let inertia = sc.link_inertia(i);
                let mut rot_e = 0.0;
                for a in 0..3 {
                    for b in 0..3 {
                        rot_e += 0.5 * ob[a] * inertia[a][b] * ob[b];
                    }
                }
                t_ref += 0.5 * l.mass * v.iter().map(|x| x * x).sum::<f64>() + rot_e;
            }
            let e = (t_m - t_ref).abs() / t_ref.abs().max(1e-6);
            assert!(e < 1e-8, "{name}: kinetic energy {t_m} vs {t_ref}");
        }
    }
}
