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
