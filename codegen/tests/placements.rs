//! The kinematics front end: every DH scene (standard and modified, revolute and prismatic) and
//! its general-placement form (`Scene::placement_form`, the DH readers: fixed transform then
//! joint motion, inertias moved into the joint frames) give the same M (Jacobian form and CRBA),
//! C q̇ + g (Lagrangian and Newton–Euler), inverse dynamics, tip pose and, for segment contact,
//! the same contact geometry — two independent paths through the generator (closed-form DH link
//! transforms vs Rodrigues rotations of constant origins) to 1e-12.

use bf_codegen::Scene;
use bf_codegen::graph::Id;
use bf_codegen::robot::SymbolicRobot;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

fn scenes() -> Vec<(String, Scene)> {
    let root = env!("CARGO_MANIFEST_DIR");
    let mut paths = Vec::new();
    for n in ["paper", "paper4", "human", "puma560", "iiwa7"] {
        paths.push(format!("{root}/../scenes/{n}.toml"));
    }
    for n in ["modified4", "polar_rp", "prismatic_mod", "prismatic_std"] {
        paths.push(format!("{root}/tests/scenes/{n}.toml"));
    }
    paths
        .into_iter()
        .map(|p| {
            let mut s = Scene::load(&p).unwrap_or_else(|e| panic!("{e}"));
            s.runtime_parameters.clear();
            (p, s)
        })
        .collect()
}

fn outputs(scene: &Scene, q: &[f64], qd: &[f64], qdd: &[f64]) -> Vec<f64> {
    let mut r = SymbolicRobot::new(scene).unwrap();
    let n = r.nq();
    let mut ids: Vec<Id> = r.mass_matrix().into_iter().flatten().collect();
    ids.extend(r.mass_matrix_crba().into_iter().flatten());
    ids.extend(r.cqd_g());
    ids.extend(r.cqd_g_rnea());
    ids.extend(r.inverse_dynamics());
    let p = r.tip_pose();
    ids.extend(p.r.iter().flatten());
    ids.extend(p.t);
    if scene.contact.as_ref().is_some_and(|c| c.kind == "segment") {
        let c = r.contact(false).unwrap();
        ids.extend([c.alpha, c.sat_alpha, c.h]);
        ids.extend(c.p_c);
        ids.extend(c.j_c.into_iter().flatten());
        ids.extend(c.jc_dot_qd);
    }
    let l = r.layout;
    let mut v = vec![0.0; l.n_vars_all()];
    v[..n].copy_from_slice(q);
    v[n..2 * n].copy_from_slice(qd);
    for (i, x) in qdd.iter().enumerate() {
        v[l.qdd(i) as usize] = *x;
    }
    bf_codegen::interp::eval(&r.g, &ids, &v)
}

#[test]
fn dh_scenes_equal_their_placement_form() {
    let mut rng = ChaCha8Rng::seed_from_u64(5);
    for (path, dh) in scenes() {
        let placed = dh.placement_form();
        assert!(placed.is_placement() && !dh.is_placement(), "{path}");
        placed.validate(&path).unwrap_or_else(|e| panic!("{e}"));
        let n = dh.nq();
        for _ in 0..4 {
            let mut draw = |s: f64| {
                (0..n)
                    .map(|_| rng.random_range(-s..s))
                    .collect::<Vec<f64>>()
            };
            let (q, qd, qdd) = (draw(2.0), draw(2.0), draw(3.0));
            let (a, b) = (outputs(&dh, &q, &qd, &qdd), outputs(&placed, &q, &qd, &qdd));
            assert_eq!(a.len(), b.len());
            for (k, (x, y)) in a.iter().zip(&b).enumerate() {
                assert!(
                    (x - y).abs() <= 1e-12 * x.abs().max(1.0),
                    "{path}: output {k}: DH {x} vs placements {y} at q = {q:?}"
                );
            }
        }
    }
}

#[test]
fn segment_contact_on_placements_needs_the_joint_behind_the_tip() {
    let root = env!("CARGO_MANIFEST_DIR");
    let mut s = Scene::load(format!("{root}/../scenes/paper.toml"))
        .unwrap()
        .placement_form();
    s.runtime_parameters.clear();
    // Move the tip sideways off the last link's line: the segment would not end at the joint.
    let tool = s.tool.as_mut().unwrap();
    let t = tool.translation.as_mut().unwrap();
    t[1] += 0.01;
    let mut r = SymbolicRobot::new(&s).unwrap();
    let err = r.contact(false).unwrap_err().to_string();
    assert!(
        err.contains("on the tip frame's x axis, behind the tip") && err.contains("0.01"),
        "{err}"
    );
    // The scene's validation says so too, at the key that chooses the segment.
    let err = s.validate("paper-placed").unwrap_err();
    assert_eq!(err.path(), Some("contact.kind"), "{err}");
}

/// A placement axis written with eight digits is normalised when the scene is read, so the
/// kernels turn about the unit axis: the tip rotation stays orthonormal to rounding and equals
/// that of the exact axis (the axis as written, of norm 1 − 7e-9, would be off by ~1e-8).
#[test]
fn kernels_turn_about_the_normalised_axis() {
    let text = |axis: &str| {
        format!(
            "name = \"tilted\"\ngravity = [0.0, 0.0, -9.81]\nkernels = [\"frames\"]\n\n[[links]]\naxis = {axis}\nmass = 1.0\ncom = [0.1, 0.0, 0.0]\ninertia = [0.1, 0.1, 0.1]\n\n[tool]\ntranslation = [0.5, 0.0, 0.0]\n"
        )
    };
    let short = Scene::from_toml_str(&text("[0.0, 0.70710678, 0.70710678]"), "t.toml").unwrap();
    let h = std::f64::consts::FRAC_1_SQRT_2;
    let exact = Scene::from_toml_str(&text(&format!("[0.0, {h:?}, {h:?}]")), "t.toml").unwrap();
    let pose = |scene: &Scene, q: f64| {
        let r = SymbolicRobot::new(scene).unwrap();
        let p = r.tip_pose();
        let ids: Vec<Id> = p.r.iter().flatten().copied().chain(p.t).collect();
        let mut v = vec![0.0; r.layout.n_vars()];
        v[0] = q;
        bf_codegen::interp::eval(&r.g, &ids, &v)
    };
    for q in [0.3, 1.7, -2.9] {
        let (a, b) = (pose(&short, q), pose(&exact, q));
        for (x, y) in a.iter().zip(&b) {
            assert!((x - y).abs() < 1e-15, "q = {q}: {a:?} vs {b:?}");
        }
        for i in 0..3 {
            let col: f64 = (0..3).map(|k| a[3 * k + i] * a[3 * k + i]).sum();
            assert!((col - 1.0).abs() < 1e-15, "q = {q}: column {i} norm² {col}");
        }
    }
}
