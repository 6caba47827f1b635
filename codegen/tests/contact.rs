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

/// The text of `tests/fixtures/finger2.toml` (standard DH, links 1 m and 2.5 m, segment
/// contact) with `extra` appended.
fn finger2_text(extra: &str) -> String {
    let path = format!(
        "{}/../tests/fixtures/finger2.toml",
        env!("CARGO_MANIFEST_DIR")
    );
    std::fs::read_to_string(path).unwrap() + extra
}

/// A tool that turns the tip frame about z and lifts it: the segment p_e − ℓ e_x … p_e is no
/// longer the last link (at q = (−2.504, 2.559) it reached into the ball, h = −0.36, while the
/// link is 0.12 m clear). Every command refuses the scene at `[tool]`; the generator refuses
/// such a scene built without validation.
#[test]
fn a_tool_that_turns_the_tip_frame_off_the_link_is_refused() {
    let tool =
        "\n[tool]\ntranslation = [0.0, 0.0, 0.3]\nrotation = { axis = \"z\", angle = \"pi/2\" }\n";
    let text = finger2_text(tool);
    let line = 1 + text.lines().position(|l| l == "[tool]").unwrap();
    let err = bf_codegen::Scene::from_toml_str(&text, "finger2_tool.toml").unwrap_err();
    let shown = err.to_string();
    assert!(
        shown.starts_with(&format!("finger2_tool.toml:{line}:")) && shown.contains(": tool: "),
        "{shown}"
    );
    let mut s = bf_codegen::Scene::from_toml_str(&finger2_text(""), "finger2.toml").unwrap();
    s.tool = bf_codegen::Scene::from_toml_str(
        &text.replace("kind = \"segment\"", "kind = \"tip\""),
        "t",
    )
    .unwrap()
    .tool;
    let err = SymbolicRobot::new(&s).unwrap().contact(false).unwrap_err();
    match err {
        bf_codegen::CodegenError::Scene(bf_codegen::SceneDefect::SegmentContactGeometry {
            start,
        }) => {
            assert!(rel_err(&start, &[0.0, 2.5, -0.3], 1.0) < 1e-15, "{start:?}")
        }
        other => panic!("{other}"),
    }
}

/// 4×4 homogeneous transforms for the reference kinematics below.
type T4 = nalgebra::Matrix4<f64>;

fn rot(axis: usize, a: f64) -> T4 {
    let (s, c) = libm::sincos(a);
    let (i, j) = ((axis + 1) % 3, (axis + 2) % 3);
    let mut m = T4::identity();
    m[(i, i)] = c;
    m[(i, j)] = -s;
    m[(j, i)] = s;
    m[(j, j)] = c;
    m
}

fn trans(v: [f64; 3]) -> T4 {
    let mut m = T4::identity();
    for k in 0..3 {
        m[(k, 3)] = v[k];
    }
    m
}

fn origin(t: &T4) -> nalgebra::Vector3<f64> {
    nalgebra::Vector3::new(t[(0, 3)], t[(1, 3)], t[(2, 3)])
}

/// A tool that moves the tip 0.1 m further along the last link: the contact segment runs from
/// joint 2 to the new tip, ℓ = a₂ + 0.1 = 2.6. The kernels' distance h and closest point p_c
/// equal an independent computation: the DH chain by 4×4 matrices, the closest point of the
/// segment joint 2 → tip to the ball's centre by projection.
#[test]
fn a_tool_along_the_last_link_lengthens_the_contact_segment() {
    let text = finger2_text("\n[tool]\ntranslation = [0.1, 0.0, 0.0]\n");
    let scene = bf_codegen::Scene::from_toml_str(&text, "finger2_x.toml").unwrap();
    assert_eq!(scene.contact_segment_length(), Some(Ok(2.6)));
    let mut m = SymbolicRobot::new(&scene).unwrap();
    let (c, cs) = (m.contact(false).unwrap(), m.contact(true).unwrap());
    let ids = contact_ids(&c);
    let smooth = [cs.sat_alpha, cs.h];
    let (ob, r) = (nalgebra::Vector3::new(0.0, 0.0, 0.0), 1.0);
    let mut rng = rng(35);
    let mut states: Vec<State> = (0..300).map(|_| State::random(&m, &mut rng)).collect();
    states[0].q = vec![-2.504, 2.559];
    // The states cover closest points inside the segment and at the joint end, where a
    // segment of length a₂ (ending 0.1 m short of the joint) would give another h.
    let (mut inside, mut at_joint) = (0, 0);
    for s in &states {
        // Reference: T = base · A₁ · A₂ · tool, A = R_z(q) T_x(a) R_x(α) (d = 0 here).
        let base = trans([2.0, 0.0, 0.0]) * rot(1, -std::f64::consts::FRAC_PI_2);
        let t1 =
            base * rot(2, s.q[0]) * trans([1.0, 0.0, 0.0]) * rot(0, std::f64::consts::FRAC_PI_2);
        let t2 = t1 * rot(2, s.q[1]) * trans([2.5, 0.0, 0.0]);
        let tip = t2 * trans([0.1, 0.0, 0.0]);
        let (joint, pe) = (origin(&t1), origin(&tip));
        let u = pe - joint;
        let t = ((ob - joint).dot(&u) / u.dot(&u)).clamp(0.0, 1.0);
        if t == 0.0 {
            at_joint += 1;
        } else if t < 1.0 {
            inside += 1;
        }
        let p_ref = joint + t * u;
        let h_ref = (ob - p_ref).norm() - r;
        let ex = u / u.norm();
        let sat_ref = (ob - pe).dot(&ex).clamp(-2.6, 0.0);
        let v = unpack(&ev(&m, &ids, s), 2);
        assert!(
            (v.h - h_ref).abs() < 1e-12,
            "q = {:?}: h {} vs {h_ref}",
            s.q,
            v.h
        );
        assert!((v.sat - sat_ref).abs() < 1e-12, "q = {:?}", s.q);
        assert!(
            rel_err(&v.p_c, p_ref.as_slice(), 1.0) < 1e-12,
            "q = {:?}",
            s.q
        );
        // The smooth saturation is within ε of the exact one.
        let w = ev(&m, &smooth, s);
        assert!((w[0] - sat_ref).abs() <= s.eps, "q = {:?}", s.q);
    }
    // At the audit's configuration the link is clear of the ball.
    let v = unpack(&ev(&m, &ids, &states[0]), 2);
    assert!(v.h > 0.1, "h = {}", v.h);
    assert!(inside > 10 && at_joint > 10, "{inside} {at_joint}");
}

/// A standard DH table without a tool keeps ℓ = a_n as it is, a runtime parameter included;
/// with a tool ℓ is baked, so a runtime a_n (or tool translation) is refused by the generator
/// too, for scenes built without validation.
#[test]
fn the_segment_length_is_a_runtime_a_n_only_without_a_tool() {
    let text = finger2_text("").replace(
        "gravity = [0.0, 0.0, -9.81]",
        "gravity = [0.0, 0.0, -9.81]\nruntime_parameters = [\"link2.a\"]",
    );
    let scene = bf_codegen::Scene::from_toml_str(&text, "finger2_p.toml").unwrap();
    let mut m = SymbolicRobot::new(&scene).unwrap();
    let c = m.contact(false).unwrap();
    // Far from the ball along the link's backward line, sat(α) = −a₂ whatever a₂ is set to.
    let mut s = State::random(&m, &mut rng(36));
    s.q = vec![0.0, 0.0];
    for a in [2.5, 1.7] {
        s.p = vec![a];
        let sat = ev(&m, &[c.sat_alpha, c.alpha], &s);
        assert!(sat[1] < -a && sat[0] == -a, "a = {a}: {sat:?}");
    }
    for (tool, name) in [
        ("\n[tool]\ntranslation = [0.1, 0.0, 0.0]\n", "link2.a"),
        (
            "\n[tool]\ntranslation = [0.0, 0.0, 0.0]\n",
            "tool.translation.x",
        ),
    ] {
        let mut s = bf_codegen::Scene::from_toml_str(&finger2_text(tool), "t").unwrap();
        s.runtime_parameters = vec![name.to_string()];
        let err = SymbolicRobot::new(&s).unwrap().contact(false).unwrap_err();
        assert!(
            matches!(&err, bf_codegen::CodegenError::Scene(bf_codegen::SceneDefect::SegmentLengthRuntime { name: n }) if n == name),
            "{err}"
        );
    }
}
