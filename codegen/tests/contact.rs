//! Contact kernels (paper Sect. 2.2, eq. 2–13, 58–59) through the interpreter: the closest
//! point property of p_c, J_c as the velocity of the link's material point, time derivatives
//! by finite differences, the smooth saturation's limit, tip-only contact.

mod common;

use bf_codegen::kernels::contact_ids;
use bf_codegen::robot::SymbolicRobot;
use common::*;

struct Cv {
    alpha: f64,
    sat: f64,
    p_c: Vec<f64>,
    r_c: Vec<f64>,
    h: f64,
    n: Vec<f64>,
    j_c: Vec<f64>,
    v_c: Vec<f64>,
    delta_v: Vec<f64>,
    h_dot: f64,
    rc_dot: Vec<f64>,
    jc_dot_qd: Vec<f64>,
}

fn unpack(v: &[f64], nq: usize) -> Cv {
    let mut it = v.iter().copied();
    let mut take = |k: usize| (0..k).map(|_| it.next().unwrap()).collect::<Vec<f64>>();
    Cv {
        alpha: take(1)[0],
        sat: take(1)[0],
        p_c: take(3),
        r_c: take(3),
        h: take(1)[0],
        n: take(3),
        j_c: take(3 * nq),
        v_c: take(3),
        delta_v: take(3),
        h_dot: take(1)[0],
        rc_dot: take(3),
        jc_dot_qd: take(3),
    }
}

fn finger_scenes() -> Vec<(String, SymbolicRobot)> {
    ["paper", "human"]
        .iter()
        .map(|n| (n.to_string(), SymbolicRobot::new(&scene(n)).unwrap()))
        .collect()
}

#[test]
fn closest_point_and_distance() {
    for (name, mut m) in finger_scenes() {
        let c = m.contact(false).unwrap();
        let all = contact_ids(&c);
        let tip = m.tip_pose();
        let mut pe_ex: Vec<_> = tip.t.to_vec();
        pe_ex.extend([tip.r[0][0], tip.r[1][0], tip.r[2][0]]);
        let sc = m.scene().clone();
        let (ob, r) = (
            sc.ball.as_ref().unwrap().center,
            sc.ball.as_ref().unwrap().radius,
        );
        let len = sc.links.last().unwrap().a;
        let mut rng = rng(31);
        for _ in 0..200 {
            let s = State::random(&m, &mut rng);
            let v = unpack(&ev(&m, &all, &s), m.nq());
            let g = ev(&m, &pe_ex, &s);
            // Brute force over the segment p_e + t e_x, t ∈ [−len, 0].
            let mut best = f64::INFINITY;
            for k in 0..=20_000 {
                let t = -len * k as f64 / 20_000.0;
                let d: f64 = (0..3)
                    .map(|i| (g[i] + t * g[3 + i] - ob[i]).powi(2))
                    .sum::<f64>();
                best = best.min(d.sqrt() - r);
            }
            assert!(
                (v.h - best).abs() < 1e-7,
                "{name}: h {} vs brute force {best}",
                v.h
            );
            assert!(v.sat <= 0.0 && v.sat >= -len, "{name}: sat out of range");
            let alpha: f64 = (0..3).map(|i| (ob[i] - g[i]) * g[3 + i]).sum();
            assert!((v.alpha - alpha).abs() < 1e-14, "{name}: alpha (eq. 2)");
            let norm = v.r_c.iter().map(|x| x * x).sum::<f64>().sqrt();
            for i in 0..3 {
                assert!((v.p_c[i] - (g[i] + v.sat * g[3 + i])).abs() < 1e-14);
                assert!((v.r_c[i] - (v.p_c[i] - ob[i])).abs() < 1e-14);
                assert!((v.n[i] - v.r_c[i] / norm).abs() < 1e-14);
            }
            assert!((v.h - (norm - r)).abs() < 1e-14);
        }
    }
}

#[test]
fn velocities_and_time_derivatives() {
    for (name, mut m) in finger_scenes() {
        let nq = m.nq();
        let c = m.contact(false).unwrap();
        let all = contact_ids(&c);
        let tip = m.tip_pose();
        let mut pe_ex: Vec<_> = tip.t.to_vec();
        pe_ex.extend([tip.r[0][0], tip.r[1][0], tip.r[2][0]]);
        let len = m.scene().links.last().unwrap().a;
        let mut rng = rng(32);
        let mut checked = 0;
        while checked < 50 {
            let s = State::random(&m, &mut rng);
            let v = unpack(&ev(&m, &all, &s), nq);
            // Keep away from the kinks of sat for finite differences.
            if (v.alpha).abs() < 1e-3 || (v.alpha + len).abs() < 1e-3 {
                continue;
            }
            checked += 1;
            let h = 1e-6;
            // v_c: velocity of the material point p_e + sat·e_x with sat frozen (eq. 6).
            let a = ev(&m, &pe_ex, &s.moved(&s.qd, h));
            let b = ev(&m, &pe_ex, &s.moved(&s.qd, -h));
            let vmat: Vec<f64> = (0..3)
                .map(|i| ((a[i] + v.sat * a[3 + i]) - (b[i] + v.sat * b[3 + i])) / (2.0 * h))
                .collect();
            assert!(rel_err(&v.v_c, &vmat, 1.0) < 1e-8, "{name}: v_c");
            let jq: Vec<f64> = (0..3)
                .map(|i| (0..nq).map(|k| v.j_c[i * nq + k] * s.qd[k]).sum())
                .collect();
            assert!(rel_err(&jq, &v.v_c, 1.0) < 1e-14, "{name}: v_c = J_c qd");
            // Δv = ω × r_c − v_c (eq. 13)
            let w = s.omega;
            let rc = &v.r_c;
            let cr = [
                w[1] * rc[2] - w[2] * rc[1],
                w[2] * rc[0] - w[0] * rc[2],
                w[0] * rc[1] - w[1] * rc[0],
            ];
            for i in 0..3 {
                assert!((v.delta_v[i] - (cr[i] - v.v_c[i])).abs() < 1e-14);
            }
            // ṙ_c, ḣ, J̇_c q̇ along q(t) = q + t q̇.
            let pa = unpack(&ev(&m, &all, &s.moved(&s.qd, h)), nq);
            let pb = unpack(&ev(&m, &all, &s.moved(&s.qd, -h)), nq);
            let rcd: Vec<f64> = (0..3)
                .map(|i| (pa.r_c[i] - pb.r_c[i]) / (2.0 * h))
                .collect();
            assert!(rel_err(&v.rc_dot, &rcd, 1.0) < 1e-7, "{name}: rc_dot");
            assert!(
                (v.h_dot - (pa.h - pb.h) / (2.0 * h)).abs() < 1e-7,
                "{name}: h_dot"
            );
            // J̇_c q̇ = d/dt (J_c(q(t)) q̇) with q̇ fixed = d/dt v_c.
            let jd: Vec<f64> = (0..3)
                .map(|i| (pa.v_c[i] - pb.v_c[i]) / (2.0 * h))
                .collect();
            assert!(rel_err(&v.jc_dot_qd, &jd, 1.0) < 1e-6, "{name}: jc_dot_qd");
        }
    }
}

#[test]
fn smooth_saturation_tends_to_exact_and_is_bounded() {
    for (name, mut m) in finger_scenes() {
        let nq = m.nq();
        let exact = contact_ids(&m.contact(false).unwrap());
        let smooth = contact_ids(&m.contact(true).unwrap());
        let len = m.scene().links.last().unwrap().a;
        let mut rng = rng(33);
        for _ in 0..100 {
            let mut s = State::random(&m, &mut rng);
            let e = unpack(&ev(&m, &exact, &s), nq);
            s.eps = 1e-9;
            let sm = unpack(&ev(&m, &smooth, &s), nq);
            assert!((sm.sat - e.sat).abs() < 1e-8, "{name}: smooth sat(eps→0)");
            assert!((sm.h - e.h).abs() < 1e-8, "{name}: smooth h(eps→0)");
            s.eps = 0.01;
            let sm = unpack(&ev(&m, &smooth, &s), nq);
            // ½(L + √((α−L)²+ε²) − √(α²+ε²)) lies in (L, 0) and within ε/2 of sat.
            assert!(sm.sat < 0.0 && sm.sat > -len, "{name}");
            assert!((sm.sat - e.sat).abs() <= 0.5 * 0.01 + 1e-15, "{name}");
            let want = 0.5
                * (-len + ((e.alpha + len).powi(2) + 1e-4).sqrt()
                    - (e.alpha.powi(2) + 1e-4).sqrt());
            assert!((sm.sat - want).abs() < 1e-14, "{name}: eq. 58-59");
        }
    }
}

#[test]
fn tip_contact_has_no_saturation() {
    let mut m = SymbolicRobot::new(&test_scene("modified4")).unwrap();
    let nq = m.nq();
    let c = m.contact(false).unwrap();
    assert!(
        m.g.is_zero(c.sat_alpha),
        "tip contact: sat must be the constant 0"
    );
    let cs = m.contact(true).unwrap();
    assert!(m.g.is_zero(cs.sat_alpha));
    let (jp, _) = m.tip_jacobian();
    let tip = m.tip_pose();
    let mut rng = rng(34);
    let s = State::random(&m, &mut rng);
    let v = unpack(&ev(&m, &contact_ids(&c), &s), nq);
    let pe = ev(&m, &tip.t, &s);
    let jpv = ev(&m, &flat2(&jp), &s);
    assert!(rel_err(&v.p_c, &pe, 1.0) < 1e-15);
    assert!(rel_err(&v.j_c, &jpv, 1.0) < 1e-15);
}
