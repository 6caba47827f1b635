//! The shipped scenes load with the values of the paper (Sect. 2.1, Table 1, Sect. 6),
//! docs/parameters.md and the cited robot data, written here independently of the scene
//! files; the constant registry's order and the tool transform.

mod common;

use bf_scene::{Angle, KNOWN_KERNELS, ROBOT_KERNELS, Scene, SpecErrorKind};
use common::*;
use nalgebra::{Matrix3, Matrix4, Vector3};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use std::f64::consts::PI;

/// Standard DH forward kinematics written here independently of the crate
/// (A_i = Rz(theta) Tz(d) Tx(a) Rx(alpha), docs/parameters.md): world frames 1..n.
fn dh_frames(base: Matrix4<f64>, table: &[(f64, f64, f64)], q: &[f64]) -> Vec<Matrix4<f64>> {
    let mut t = base;
    let mut out = Vec::new();
    for (&(a, alpha, d), &qi) in table.iter().zip(q) {
        let rz = Matrix4::new_rotation(Vector3::z() * qi);
        let tz = Matrix4::new_translation(&Vector3::new(0.0, 0.0, d));
        let tx = Matrix4::new_translation(&Vector3::new(a, 0.0, 0.0));
        let rx = Matrix4::new_rotation(Vector3::x() * alpha);
        t = t * rz * tz * tx * rx;
        out.push(t);
    }
    out
}

fn table(s: &Scene) -> Vec<(f64, f64, f64)> {
    s.links
        .iter()
        .map(|l| (l.a, l.alpha.radians(), l.d))
        .collect()
}

fn homogeneous(r: [[f64; 3]; 3], p: [f64; 3]) -> Matrix4<f64> {
    let mut t = Matrix4::identity();
    for i in 0..3 {
        for j in 0..3 {
            t[(i, j)] = r[i][j];
        }
        t[(i, 3)] = p[i];
    }
    t
}

fn assert_finger_common(s: &Scene) {
    // docs/parameters.md, written out independently of the scene file.
    assert_eq!(s.nq(), 3);
    assert_eq!(s.dh, bf_scene::DhConvention::Standard);
    assert_eq!(s.gravity, [0.0, 0.0, -9.81]);
    assert_eq!(s.base_translation(), [2.0, 0.0, 0.0]);
    assert_eq!(
        s.base_rotation(),
        [[0.0, 0.0, -1.0], [0.0, 1.0, 0.0], [1.0, 0.0, 0.0]],
        "R_y(-pi/2) must be exact"
    );
    let alphas = [pm(1, 2), pm(0, 1), pm(0, 1)];
    for (i, l) in s.links.iter().enumerate() {
        assert_eq!(l.a, 1.0);
        assert_eq!(l.d, 0.0);
        assert_eq!(l.alpha, alphas[i], "alpha_{} must be exact", i + 1);
        assert!(l.offset.is_none_or(|o| o.radians() == 0.0));
        assert_eq!(l.mass, 0.02);
        assert_eq!(l.com, [-0.5, 0.0, 0.0]);
        assert_eq!(
            s.link_inertia(i),
            [
                [1.0677e-3, 0.0, 0.0],
                [0.0, 2.3177e-3, 0.0],
                [0.0, 0.0, 2.0833e-3]
            ]
        );
        assert_eq!(l.tau_max, Some(1.0));
    }
    let b = s.ball.as_ref().unwrap();
    assert_eq!((b.radius, b.center, b.mass), (1.0, [0.0; 3], 0.02));
    let ib = s.ball_inertia().unwrap();
    for i in 0..3 {
        for j in 0..3 {
            let want = if i == j { 0.4 * 0.02 * 1.0 } else { 0.0 };
            assert!((ib[i][j] - want).abs() < 1e-18, "I_b = 0.008 * 1");
        }
    }
    let f = s.friction.as_ref().unwrap();
    assert_eq!(
        (f.mu_s, f.mu_k, f.mu_v, f.socket_damping),
        (0.8, 0.6, 0.001, 0.004)
    );
    let c = s.contact.as_ref().unwrap();
    assert_eq!((c.kind.as_str(), c.smooth_eps), ("segment", 0.01));
    let mut k = s.kernels.clone();
    k.sort();
    // The inverse-dynamics family is emitted for every scene without being listed.
    let mut all: Vec<String> = KNOWN_KERNELS
        .iter()
        .filter(|k| !ROBOT_KERNELS.contains(k))
        .map(|s| s.to_string())
        .collect();
    all.sort();
    assert_eq!(k, all, "the finger scenes emit every kernel");

    // Geometry: at q = 0 the finger stands upright from o_f = (2r, 0, 0): frame i at
    // (2, 0, i) with e_x3 = +z (docs/parameters.md: base R_y(-pi/2), links along x_i).
    let base = homogeneous(s.base_rotation(), s.base_translation());
    let frames = dh_frames(base, &table(s), &[0.0; 3]);
    for (i, f) in frames.iter().enumerate() {
        let p = f.fixed_view::<3, 1>(0, 3);
        assert!(
            (p - Vector3::new(2.0, 0.0, (i + 1) as f64)).norm() < 1e-12,
            "frame {}",
            i + 1
        );
    }
    let ex3 = frames[2].fixed_view::<3, 1>(0, 0);
    assert!((ex3 - Vector3::z()).norm() < 1e-12);
    // Positive q2 bends the finger towards the ball at the origin (needed for human.toml's
    // q2 >= 0 to mean flexion towards the ball).
    let bent = dh_frames(base, &table(s), &[0.0, 0.3, 0.0]);
    assert!(bent[2][(0, 3)] < 2.0);
}

#[test]
fn paper_scene_matches_params_md() {
    let s = scene("paper");
    assert_eq!(s.name, "paper");
    assert_finger_common(&s);
    assert!(
        s.runtime_parameters.is_empty(),
        "paper scene is fully baked"
    );
    assert!(
        s.links
            .iter()
            .all(|l| l.q_min.is_none() && l.q_max.is_none())
    );
}

#[test]
fn human_scene_differs_only_in_limits_runtime_parameters_and_ocp_kernels() {
    let s = scene("human");
    assert_eq!(s.name, "human");
    assert_finger_common(&s);
    // Paper Sect. 6: q_i >= 0 for i in {2, 3}; upper limits 90 and 100 degrees.
    assert_eq!((s.links[0].q_min, s.links[0].q_max), (None, None));
    assert_eq!(s.links[1].q_min, Some(0.0));
    assert_eq!(s.links[2].q_min, Some(0.0));
    assert!((s.links[1].q_max.unwrap() - 90.0 * PI / 180.0).abs() < 1e-15);
    assert!((s.links[2].q_max.unwrap() - 100.0 * PI / 180.0).abs() < 1e-15);
    assert_eq!(
        s.runtime_parameter_values(),
        vec![
            ("ball.radius".to_string(), 1.0),
            ("link3.mass".to_string(), 0.02)
        ]
    );
    // Only the COT objective's optimal-control node kernels (periodic-cot-human).
    assert_eq!(s.ocp_kernels, Some(vec!["cot".to_string()]));
    // Apart from these, identical to the paper scene.
    let mut p = scene("paper");
    p.name = s.name.clone();
    p.description = s.description.clone();
    p.runtime_parameters = s.runtime_parameters.clone();
    p.ocp_kernels = s.ocp_kernels.clone();
    for i in 1..3 {
        p.links[i].q_min = s.links[i].q_min;
        p.links[i].q_max = s.links[i].q_max;
    }
    assert_eq!(p, s);
}

#[test]
fn puma560_scene_matches_corke_rtb() {
    let s = scene("puma560");
    assert_eq!(s.nq(), 6);
    assert!(s.ball.is_none() && s.contact.is_none());
    assert!(!s.wants("contact") && !s.wants("contact_smooth"));
    assert!(s.wants("mass_matrix") && s.wants("gravity") && s.wants("cqd_g_rnea"));
    // mdl_puma560.m (standard DH): (a, alpha, d), written independently.
    let want = [
        (0.0, PI / 2.0, 0.0),
        (0.4318, 0.0, 0.0),
        (0.0203, -PI / 2.0, 0.15005),
        (0.0, PI / 2.0, 0.4318),
        (0.0, -PI / 2.0, 0.0),
        (0.0, 0.0, 0.0),
    ];
    for (l, w) in s.links.iter().zip(want) {
        assert_eq!((l.a, l.alpha.radians(), l.d), w);
        assert!(matches!(l.alpha, Angle::PiMultiple { .. }), "alpha exact");
    }
    let masses: Vec<f64> = s.links[1..].iter().map(|l| l.mass).collect();
    assert_eq!(masses, [17.4, 4.8, 0.82, 0.34, 0.09]);
    assert_eq!(s.links[1].com, [-0.3638, 0.006, 0.2275]);
    assert_eq!(s.links[2].com, [-0.0203, -0.0141, 0.070]);
    assert_eq!(s.links[5].com, [0.0, 0.0, 0.032]);
    assert_eq!(s.link_inertia(1)[2][2], 0.539);
    assert_eq!(s.link_inertia(2)[1][1], 0.086);
    // Link 1: only I_yy = 0.35 matters; its COG is on the fixed joint-1 axis.
    assert_eq!(s.link_inertia(0)[1][1], 0.35);
    assert_eq!(s.links[0].com, [0.0; 3]);
    let deg = PI / 180.0;
    let lim = [
        (-160.0, 160.0),
        (-45.0, 225.0),
        (-225.0, 45.0),
        (-110.0, 170.0),
        (-100.0, 100.0),
        (-266.0, 266.0),
    ];
    for (l, (lo, hi)) in s.links.iter().zip(lim) {
        assert!((l.q_min.unwrap() - lo * deg).abs() < 1e-14);
        assert!((l.q_max.unwrap() - hi * deg).abs() < 1e-14);
    }
    // z0 (joint 1) coincides with y1: the property that makes m1, I1xx, I1zz irrelevant.
    let f = dh_frames(
        Matrix4::identity(),
        &table(&s),
        &[0.7, 0.0, 0.0, 0.0, 0.0, 0.0],
    );
    let y1 = f[0].fixed_view::<3, 1>(0, 1);
    assert!((y1 - Vector3::z()).norm() < 1e-12);
    assert!(f[0].fixed_view::<3, 1>(0, 3).norm() < 1e-12);
}

/// URDF rotation from roll-pitch-yaw: Rz(yaw) Ry(pitch) Rx(roll).
fn rpy(r: f64, p: f64, y: f64) -> Matrix3<f64> {
    *(nalgebra::Rotation3::from_axis_angle(&Vector3::z_axis(), y)
        * nalgebra::Rotation3::from_axis_angle(&Vector3::y_axis(), p)
        * nalgebra::Rotation3::from_axis_angle(&Vector3::x_axis(), r))
    .matrix()
}

#[test]
fn iiwa7_scene_reproduces_the_iiwa_stack_urdf() {
    let s = scene("iiwa7");
    assert_eq!(s.nq(), 7);
    assert!(s.ball.is_none() && s.contact.is_none());
    let d: Vec<f64> = s.links.iter().map(|l| l.d).collect();
    assert_eq!(d, [0.34, 0.0, 0.4, 0.0, 0.4, 0.0, 0.126]);
    assert!(s.links.iter().all(|l| l.a == 0.0));
    let taus: Vec<f64> = s.links.iter().map(|l| l.tau_max.unwrap()).collect();
    assert_eq!(taus, [176.0, 176.0, 110.0, 110.0, 110.0, 40.0, 40.0]);
    let total: f64 = s.links.iter().map(|l| l.mass).sum();
    assert!((total - 17.5).abs() < 1e-12);

    // iiwa_stack iiwa7.xacro: joint origins (xyz, rpy), axes z; inertials in link frames.
    let h = PI / 2.0;
    let joints = [
        ([0.0, 0.0, 0.15], [0.0, 0.0, 0.0]),
        ([0.0, 0.0, 0.19], [h, 0.0, PI]),
        ([0.0, 0.21, 0.0], [h, 0.0, PI]),
        ([0.0, 0.0, 0.19], [h, 0.0, 0.0]),
        ([0.0, 0.21, 0.0], [-h, PI, 0.0]),
        ([0.0, 0.0607, 0.19], [h, 0.0, 0.0]),
        ([0.0, 0.081, 0.0607], [-h, PI, 0.0]),
    ];
    let inertials = [
        (4.0, [0.0, -0.03, 0.12], [0.1, 0.09, 0.02]),
        (4.0, [0.0003, 0.059, 0.042], [0.05, 0.018, 0.044]),
        (3.0, [0.0, 0.03, 0.13], [0.08, 0.075, 0.01]),
        (2.7, [0.0, 0.067, 0.034], [0.03, 0.01, 0.029]),
        (1.7, [0.0001, 0.021, 0.076], [0.02, 0.018, 0.005]),
        (1.8, [0.0, 0.0006, 0.0004], [0.005, 0.0036, 0.0047]),
        (0.3, [0.0, 0.0, 0.02], [0.001, 0.001, 0.001]),
    ];
    let mut rng = ChaCha8Rng::seed_from_u64(11);
    for _ in 0..20 {
        let q: Vec<f64> = (0..7).map(|_| rng.random_range(-3.0..3.0)).collect();
        let dh = dh_frames(
            homogeneous(s.base_rotation(), s.base_translation()),
            &table(&s),
            &q,
        );
        let mut t = Matrix4::<f64>::identity();
        for i in 0..7 {
            let (xyz, r) = joints[i];
            let mut j = Matrix4::identity();
            j.fixed_view_mut::<3, 3>(0, 0)
                .copy_from(&rpy(r[0], r[1], r[2]));
            j[(0, 3)] = xyz[0];
            j[(1, 3)] = xyz[1];
            j[(2, 3)] = xyz[2];
            t = t * j * Matrix4::new_rotation(Vector3::z() * q[i]);
            // Same joint axis and direction (q has KUKA's sign).
            let zu = t.fixed_view::<3, 1>(0, 2).into_owned();
            let zd = if i == 0 {
                Vector3::z()
            } else {
                dh[i - 1].fixed_view::<3, 1>(0, 2).into_owned()
            };
            assert!((zu - zd).norm() < 1e-9, "joint {} axis", i + 1);
            // World COG and world inertia of link i+1 agree.
            let (m, c, diag) = inertials[i];
            assert_eq!(s.links[i].mass, m);
            let cu = t.transform_point(&nalgebra::Point3::from(Vector3::from(c)));
            let cd = dh[i].transform_point(&nalgebra::Point3::from(Vector3::from(s.links[i].com)));
            assert!((cu - cd).norm() < 1e-9, "link {} COG", i + 1);
            let ru = t.fixed_view::<3, 3>(0, 0).into_owned();
            let rd = dh[i].fixed_view::<3, 3>(0, 0).into_owned();
            let iu = ru * Matrix3::from_diagonal(&Vector3::from(diag)) * ru.transpose();
            let li = s.link_inertia(i);
            let id = rd * Matrix3::from_fn(|r, k| li[r][k]) * rd.transpose();
            assert!((iu - id).norm() < 1e-9, "link {} inertia", i + 1);
        }
        // The flange (DH frame 7) is 0.045 m past the URDF link_7 frame along its z axis.
        let flange = t * Matrix4::new_translation(&Vector3::new(0.0, 0.0, 0.045));
        assert!((flange.fixed_view::<3, 1>(0, 3) - dh[6].fixed_view::<3, 1>(0, 3)).norm() < 1e-9);
    }
}

#[test]
fn constant_registry_has_fixed_order_and_matches_fields() {
    let s = scene("paper");
    let c = s.constants();
    let names: Vec<&str> = c.iter().map(|(n, _)| n.as_str()).collect();
    assert_eq!(
        &names[..12],
        [
            "gravity.x",
            "gravity.y",
            "gravity.z",
            "base.translation.x",
            "base.translation.y",
            "base.translation.z",
            "link1.a",
            "link1.alpha",
            "link1.d",
            "link1.offset",
            "link1.mass",
            "link1.com.x",
        ]
    );
    // 3 gravity + 3 base + 14 per link (a, alpha, d, offset, mass, 3 com, 6 inertia)
    // + 11 ball (radius, 3 centre, mass, 6 inertia) + 4 friction.
    assert_eq!(c.len(), 6 + 14 * 3 + 11 + 4);
    let mut sorted = names.clone();
    sorted.sort();
    sorted.dedup();
    assert_eq!(sorted.len(), names.len(), "names are unique");
    let get = |n: &str| s.constant(n).unwrap_or_else(|| panic!("{n}"));
    assert_eq!(get("link2.inertia.yy"), 2.3177e-3);
    assert_eq!(get("link3.inertia.xz"), 0.0);
    assert_eq!(get("link1.alpha"), PI / 2.0);
    assert_eq!(get("link3.com.x"), -0.5);
    assert_eq!(get("base.translation.x"), 2.0);
    assert_eq!(get("ball.radius"), 1.0);
    assert!((get("ball.inertia.zz") - 0.008).abs() < 1e-18);
    assert_eq!(get("friction.socket_damping"), 0.004);
    assert_eq!(s.constant("link4.mass"), None);
    assert_eq!(
        s.constant("tool.translation.x"),
        None,
        "no tool in the paper scene"
    );
    // Arms without ball or friction have only the kinematic/inertial constants.
    let p = scene("iiwa7");
    assert_eq!(p.constants().len(), 6 + 14 * 7);
    assert_eq!(p.constant("link7.d"), Some(0.126));
}

#[test]
fn tool_transform_is_in_the_registry() {
    // Tip contact: a tool turned by π about z points the tip frame's x axis back along the
    // link, which segment contact refuses.
    let tip = BASE.replace("kind = \"segment\"", "kind = \"tip\"");
    let text = format!(
        "{tip}\n[tool]\ntranslation = [0.0, 0.0, 0.1]\nrotation = {{ axis = \"z\", angle = \"pi\" }}\n"
    );
    let s = Scene::from_toml_str(&text, FILE).unwrap();
    assert_eq!(s.tool_translation(), [0.0, 0.0, 0.1]);
    assert_eq!(
        s.tool_rotation(),
        [[-1.0, 0.0, 0.0], [0.0, -1.0, 0.0], [0.0, 0.0, 1.0]]
    );
    assert_eq!(s.constant("tool.translation.z"), Some(0.1));
    let text = format!("{BASE}\n[tool]\ntranslation = [0.0, 0.0]\n");
    let line = line_no(&text, "translation = [0.0, 0.0]", 0);
    expect_err(
        &text,
        SpecErrorKind::WrongType,
        line,
        "tool.translation",
        "invalid length 2",
    );
}
