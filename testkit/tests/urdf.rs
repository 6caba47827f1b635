//! URDF import (bf-scene) and the generator's placement kinematics (bf-codegen) against this
//! kit's independent spatial-algebra reference on the URDF's whole tree (`urdf_tree`: its own
//! XML reader, no lumping, locked joints kept in the tree): M (generator's Jacobian form and
//! CRBA), C q̇ + g (Lagrangian and Newton–Euler paths), inverse dynamics and the tip pose, to
//! 1e-12, for URDFs written from published robot data (tests/urdf/); a chain from a base link
//! below the root against the reference and the root's chain with the joints above it locked;
//! and the DH scenes (PUMA 560, the paper's finger) against URDF equivalents of them.

use bf_codegen::Scene;
use bf_codegen::graph::Id;
use bf_codegen::robot::SymbolicRobot;
use bf_codegen::spec::read_urdf_chain;
use bf_testkit::urdf_tree::UrdfTree;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

const TOL: f64 = 1e-12;

fn dir() -> String {
    format!("{}/tests/urdf", env!("CARGO_MANIFEST_DIR"))
}

fn read(name: &str) -> String {
    std::fs::read_to_string(format!("{}/{name}", dir())).unwrap()
}

/// A scene holding the imported chain of `text` (gravity −9.81 z, no ball).
fn scene_of(text: &str, file: &str, base: Option<&str>, tip: Option<&str>) -> Scene {
    let chain = read_urdf_chain(text, file, base, tip, None).unwrap_or_else(|e| panic!("{e}"));
    scene_from_chain(&chain, file)
}

fn scene_from_chain(chain: &bf_codegen::spec::UrdfChain, file: &str) -> Scene {
    let toml = format!(
        "name = \"t\"\ngravity = [0.0, 0.0, -9.81]\nkernels = [\"mass_matrix\"]\n{}",
        bf_codegen::spec::chain_toml(chain)
    );
    Scene::from_toml_str(&toml, file).unwrap_or_else(|e| panic!("{e}\n{toml}"))
}

/// What the generator computes at (q, q̇, q̈): M (Jacobian form), M (CRBA), C q̇ + g (Lagrangian),
/// C q̇ + g (RNEA), τ (inverse dynamics), tip rotation (row-major) and position.
struct Gen {
    m: Vec<f64>,
    m_crba: Vec<f64>,
    cqd_g: Vec<f64>,
    cqd_g_rnea: Vec<f64>,
    tau: Vec<f64>,
    tip: Vec<f64>,
}

fn generated(scene: &Scene, q: &[f64], qd: &[f64], qdd: &[f64]) -> Gen {
    let mut r = SymbolicRobot::new(scene).unwrap();
    let n = r.nq();
    let flat = |m: Vec<Vec<Id>>| m.into_iter().flatten().collect::<Vec<_>>();
    let m = flat(r.mass_matrix());
    let m_crba = flat(r.mass_matrix_crba());
    let cqd_g = r.cqd_g();
    let cqd_g_rnea = r.cqd_g_rnea();
    let tau = r.inverse_dynamics();
    let p = r.tip_pose();
    let mut tip: Vec<Id> = p.r.iter().flatten().copied().collect();
    tip.extend(p.t);
    let groups = [m, m_crba, cqd_g, cqd_g_rnea, tau, tip];
    let ids: Vec<Id> = groups.iter().flatten().copied().collect();
    let l = r.layout;
    let mut v = vec![0.0; l.n_vars_all()];
    v[..n].copy_from_slice(q);
    v[n..2 * n].copy_from_slice(qd);
    for (i, x) in qdd.iter().enumerate() {
        v[l.qdd(i) as usize] = *x;
    }
    for (i, p) in r.params.iter().enumerate() {
        v[l.param(i) as usize] = p.1;
    }
    let out = bf_codegen::interp::eval(&r.g, &ids, &v);
    let mut it = out.into_iter();
    let mut take = |k: usize| (&mut it).take(k).collect::<Vec<f64>>();
    Gen {
        m: take(n * n),
        m_crba: take(n * n),
        cqd_g: take(n),
        cqd_g_rnea: take(n),
        tau: take(n),
        tip: take(12),
    }
}

fn close(what: &str, a: &[f64], b: &[f64]) {
    assert_eq!(a.len(), b.len(), "{what}: lengths");
    for (k, (x, y)) in a.iter().zip(b).enumerate() {
        assert!(
            (x - y).abs() <= TOL * y.abs().max(1.0),
            "{what}[{k}]: {x} vs reference {y} (diff {:e})\n{a:?}\n{b:?}",
            x - y
        );
    }
}

fn states(nq: usize, count: usize, seed: u64) -> Vec<[Vec<f64>; 3]> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    (0..count)
        .map(|_| [2.0, 2.0, 3.0].map(|s| (0..nq).map(|_| rng.random_range(-s..s)).collect()))
        .collect()
}

/// The generated kernels of `scene` (imported from `text`) against the tree reference.
fn check_against_tree(name: &str, scene: &Scene, text: &str, base: &str, tip: &str) {
    let tree = UrdfTree::parse(text).unwrap();
    let chain = tree.chain(base, tip);
    assert_eq!(chain.len(), scene.nq(), "{name}: joints");
    let g0 = scene.gravity;
    for (k, [q, qd, qdd]) in states(scene.nq(), 4, 7).into_iter().enumerate() {
        let ctx = |w: &str| format!("{name} state {k}: {w}");
        let gen_ = generated(scene, &q, &qd, &qdd);
        let m_ref: Vec<f64> = tree.crba(&chain, &q).into_iter().flatten().collect();
        // The reference's CRBA and RNEA agree with each other: M e_j = RNEA(q, 0, e_j), g = 0.
        for j in 0..scene.nq() {
            let mut e = vec![0.0; scene.nq()];
            e[j] = 1.0;
            let col = tree.rnea(&chain, &q, &vec![0.0; scene.nq()], &e, [0.0; 3]);
            let want: Vec<f64> = (0..scene.nq()).map(|i| m_ref[i * scene.nq() + j]).collect();
            close(&ctx("reference CRBA vs RNEA column"), &col, &want);
        }
        let zero = vec![0.0; scene.nq()];
        let bias = tree.rnea(&chain, &q, &qd, &zero, g0);
        let tau = tree.rnea(&chain, &q, &qd, &qdd, g0);
        close(&ctx("M"), &gen_.m, &m_ref);
        close(&ctx("M (CRBA)"), &gen_.m_crba, &m_ref);
        close(&ctx("C qd + g"), &gen_.cqd_g, &bias);
        close(&ctx("C qd + g (RNEA)"), &gen_.cqd_g_rnea, &bias);
        close(&ctx("inverse dynamics"), &gen_.tau, &tau);
        let (r, t) = tree.pose(&chain, &q, tip);
        let mut want: Vec<f64> = (0..3)
            .flat_map(|i| (0..3).map(move |j| (i, j)))
            .map(|(i, j)| r[(i, j)])
            .collect();
        want.extend(t.iter());
        close(&ctx("tip pose"), &gen_.tip, &want);
    }
}

fn check_file(file: &str, base: &str, tip: Option<&str>, nq: usize) -> Scene {
    let text = read(file);
    let scene = scene_of(&text, file, None, tip);
    assert_eq!(scene.nq(), nq, "{file}");
    check_against_tree(
        file,
        &scene,
        &text,
        base,
        tip.unwrap_or_else(|| last_link(&text)),
    );
    scene
}

/// The name of the last `<link>` of the file (the tip of the single-chain test files).
fn last_link(text: &str) -> &str {
    let i = text.rfind("<link name=\"").unwrap() + 12;
    &text[i..i + text[i..].find('"').unwrap()]
}

#[test]
fn planar_two_link_arm_matches_the_tree_reference_and_the_closed_form() {
    let scene = check_file("planar2.urdf", "world", None, 2);
    // Closed form (Spong et al. eq. 7.87): M11 = m1 lc² + m2 (l² + lc² + 2 l lc c2) + I1 + I2,
    // M12 = m2 (lc² + l lc c2) + I2, M22 = m2 lc² + I2, with I the moment about z.
    let (m, l, lc, i) = (1.0, 1.0, 0.5, 0.08353);
    for [q, qd, qdd] in states(2, 3, 3) {
        let c2 = libm::cos(q[1]);
        let want = [
            m * lc * lc + m * (l * l + lc * lc + 2.0 * l * lc * c2) + 2.0 * i,
            m * (lc * lc + l * lc * c2) + i,
            m * (lc * lc + l * lc * c2) + i,
            m * lc * lc + i,
        ];
        close(
            "planar M closed form",
            &generated(&scene, &q, &qd, &qdd).m,
            &want,
        );
    }
    // The limits and efforts of the URDF became the scene's.
    assert_eq!(scene.links[0].q_min, Some(-3.0));
    assert_eq!(scene.links[1].tau_max, Some(30.0));
}

#[test]
fn ur5_like_arm_with_non_dh_offsets() {
    let scene = check_file("ur5_like.urdf", "base_link", None, 6);
    // The tool is the fixed ee_link, not the last joint's frame.
    assert!(scene.tool.is_some());
}

#[test]
fn seven_joint_arm_with_a_locked_two_finger_hand() {
    let text = read("panda_like.urdf");
    // The tree branches at the hand: no default tip.
    let err = read_urdf_chain(&text, "panda_like.urdf", None, None, None).unwrap_err();
    assert!(
        err.to_string().contains("branches at link \"panda_hand\""),
        "{err}"
    );
    let scene = check_file("panda_like.urdf", "panda_link0", Some("panda_hand"), 7);
    // Link 7 carries itself, the hand and both (locked) fingers.
    let m7 = scene.links[6].mass;
    assert!((m7 - (0.735522 + 0.73 + 2.0 * 0.015)).abs() < 1e-12, "{m7}");
    // A fingertip as the tip instead: the finger joint becomes the 8th (prismatic) joint.
    let tip = "panda_leftfinger";
    let scene = scene_of(&text, "panda_like.urdf", None, Some(tip));
    assert_eq!(scene.nq(), 8);
    assert_eq!(scene.links[7].joint, bf_codegen::spec::JointType::Prismatic);
    check_against_tree("panda to a finger", &scene, &text, "panda_link0", tip);
}

#[test]
fn three_joint_finger_with_a_fixed_tip_link() {
    let scene = check_file("finger3.urdf", "finger_base", None, 3);
    let tool = scene.tool.as_ref().unwrap();
    assert_eq!(tool.translation, Some([0.0, 0.0, -0.16]));
}

#[test]
fn chain_with_prismatic_and_continuous_joints() {
    let scene = check_file("scara_continuous.urdf", "base", None, 4);
    // The continuous joint has no limits; the prismatic one keeps its range.
    assert_eq!((scene.links[3].q_min, scene.links[3].q_max), (None, None));
    assert_eq!(scene.links[2].q_max, Some(0.2));
}

/// rpy (URDF: R = R_z(y) R_y(p) R_x(r)) of a rotation matrix, exact in the gimbal-lock case.
fn rpy(r: &[[f64; 3]; 3]) -> [f64; 3] {
    if r[2][0].abs() > 1.0 - 1e-12 {
        let p = if r[2][0] < 0.0 {
            std::f64::consts::FRAC_PI_2
        } else {
            -std::f64::consts::FRAC_PI_2
        };
        return [0.0, p, libm::atan2(-r[0][1], r[1][1])];
    }
    [
        libm::atan2(r[2][1], r[2][2]),
        libm::atan2(-r[2][0], libm::hypot(r[2][1], r[2][2])),
        libm::atan2(r[1][0], r[0][0]),
    ]
}

fn origin(t: [f64; 3], r: &[[f64; 3]; 3]) -> String {
    let a = rpy(r);
    format!(
        "<origin xyz=\"{:?} {:?} {:?}\" rpy=\"{:?} {:?} {:?}\"/>",
        t[0], t[1], t[2], a[0], a[1], a[2]
    )
}

/// A URDF of a DH scene: its placement form (the DH reader) written out, the base as a fixed
/// joint from a `world` link, the tool as a fixed joint to a `tip` link.
fn urdf_of(scene: &Scene) -> String {
    let p = scene.placement_form();
    let mut s =
        String::from("<robot name=\"dh\">\n<link name=\"world\"/>\n<link name=\"link0\"/>\n");
    s += &format!(
        "<joint name=\"base\" type=\"fixed\"><parent link=\"world\"/><child link=\"link0\"/>{}</joint>\n",
        origin(p.base_translation(), &p.base_rotation())
    );
    for (k, l) in p.links.iter().enumerate() {
        let i = l.inertia_matrix();
        s += &format!(
            "<link name=\"link{}\"><inertial><origin xyz=\"{:?} {:?} {:?}\"/><mass value=\"{:?}\"/>\
             <inertia ixx=\"{:?}\" ixy=\"{:?}\" ixz=\"{:?}\" iyy=\"{:?}\" iyz=\"{:?}\" izz=\"{:?}\"/>\
             </inertial></link>\n",
            k + 1,
            l.com[0],
            l.com[1],
            l.com[2],
            l.mass,
            i[0][0],
            i[0][1],
            i[0][2],
            i[1][1],
            i[1][2],
            i[2][2]
        );
        let o = l.origin.clone().unwrap_or_default();
        let a = l.axis.unwrap();
        let ty = if l.joint == bf_codegen::spec::JointType::Prismatic {
            "prismatic"
        } else {
            "revolute"
        };
        s += &format!(
            "<joint name=\"j{}\" type=\"{ty}\"><parent link=\"link{k}\"/><child link=\"link{}\"/>{}\
             <axis xyz=\"{:?} {:?} {:?}\"/></joint>\n",
            k + 1,
            k + 1,
            origin(o.translation(), &o.rotation_matrix()),
            a[0],
            a[1],
            a[2]
        );
    }
    s += &format!(
        "<link name=\"tip\"/><joint name=\"tool\" type=\"fixed\"><parent link=\"link{}\"/>\
         <child link=\"tip\"/>{}</joint>\n</robot>\n",
        p.links.len(),
        origin(p.tool_translation(), &p.tool_rotation())
    );
    s
}

/// A DH scene and its URDF equivalent: the generator's DH kernels equal the URDF import's
/// placement kernels and the tree reference on the URDF.
fn dh_equivalent(path: &str) {
    let root = env!("CARGO_MANIFEST_DIR");
    let mut dh = Scene::load(format!("{root}/../scenes/{path}")).unwrap();
    (dh.ball, dh.contact, dh.friction) = (None, None, None);
    dh.runtime_parameters.clear();
    dh.kernels = vec!["mass_matrix".to_string()];
    let text = urdf_of(&dh);
    // Published inertias kept as published (PUMA 560 link 3) are kept from the URDF too, by
    // the scene's source, and marked on the same links only.
    let source = dh
        .links
        .iter()
        .find_map(|l| l.nonphysical_inertia.as_deref());
    let chain = read_urdf_chain(&text, path, None, None, source).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(
        chain
            .links
            .iter()
            .map(|c| c.nonphysical_inertia.is_some())
            .collect::<Vec<_>>(),
        dh.links
            .iter()
            .map(|l| l.nonphysical_inertia.is_some())
            .collect::<Vec<_>>(),
        "{path}: the links kept as published"
    );
    if source.is_some() {
        let err = read_urdf_chain(&text, path, None, None, None).unwrap_err();
        assert!(err.to_string().contains("triangle inequality"), "{err}");
    }
    let urdf = scene_from_chain(&chain, path);
    assert_eq!(urdf.nq(), dh.nq());
    check_against_tree(path, &urdf, &text, "world", "tip");
    for (k, [q, qd, qdd]) in states(dh.nq(), 4, 11).into_iter().enumerate() {
        let (a, b) = (
            generated(&dh, &q, &qd, &qdd),
            generated(&urdf, &q, &qd, &qdd),
        );
        let ctx = |w: &str| format!("{path} state {k}: DH vs URDF {w}");
        close(&ctx("M"), &a.m, &b.m);
        close(&ctx("C qd + g"), &a.cqd_g, &b.cqd_g);
        close(&ctx("inverse dynamics"), &a.tau, &b.tau);
        close(&ctx("tip pose"), &a.tip, &b.tip);
    }
}

#[test]
fn puma560_equals_its_urdf() {
    dh_equivalent("puma560.toml");
}

#[test]
fn paper_finger_equals_its_urdf() {
    dh_equivalent("paper.toml");
}

/// The shipped URDF of the paper's finger (`tests/urdf/paper_finger.urdf`, written by hand
/// from the DH table and inertias of `scenes/paper.toml`) with the paper's ball, friction and
/// contact added by a TOML scene (`paper_finger_ball.toml`): every kernel of the paper scene —
/// dynamics, contact geometry (exact and smooth), tip kinematics, of `frames` the fingertip
/// frame, of the regressor Y the torques Y π — equals the DH scene's at
/// random states (q, q̇, ω, ε, u) to 1e-12 relative to the output's largest entry. Both
/// through the run-time interpreter, which evaluates the generator's graphs.
#[test]
fn paper_finger_urdf_scene_equals_the_dh_paper_scene_kernel_by_kernel() {
    use bf_codegen::interp::SceneKernels;
    let root = env!("CARGO_MANIFEST_DIR");
    let (dh, _) =
        Scene::load_with_text(format!("{root}/../scenes/paper.toml"), &Default::default()).unwrap();
    let (urdf, text) = Scene::load_with_text(
        format!("{}/paper_finger_ball.toml", dir()),
        &Default::default(),
    )
    .unwrap_or_else(|e| panic!("{e}"));
    assert!(text.contains("[ball]"), "{text}");
    assert_eq!(urdf.kernels, dh.kernels);
    assert_eq!(
        urdf.links.iter().map(|l| l.tau_max).collect::<Vec<_>>(),
        vec![Some(1.0); 3]
    );
    let (a, b) = (
        SceneKernels::new(&dh).unwrap(),
        SceneKernels::new(&urdf).unwrap(),
    );
    let names = |s: &SceneKernels| s.kernels.iter().map(|k| k.name.clone()).collect::<Vec<_>>();
    assert_eq!(names(&a), names(&b));
    let mut rng = ChaCha8Rng::seed_from_u64(35);
    for (k, [q, qd, u]) in states(3, 6, 27).into_iter().enumerate() {
        let omega = [0; 3].map(|_| rng.random_range(-2.0..2.0));
        let eps = [0.01, 0.001][k % 2];
        let (va, vb) = (
            a.vars(&q, &qd, omega, eps, &u, None),
            b.vars(&q, &qd, omega, eps, &u, None),
        );
        for (ka, kb) in a.kernels.iter().zip(&b.kernels) {
            let (mut x, mut y) = (ka.eval(&va), kb.eval(&vb));
            if ka.name == "frames" {
                // Positions p_1..p_3 (9 values), then rotations R_1..R_3 (27). A URDF link's
                // frame sits at its joint, DH frame i after the link's constant T_x(a) R_x(α):
                // only the last frame (the fingertip, which the contact uses) is the same.
                let tip = |v: &[f64]| [&v[6..9], &v[27..36]].concat();
                (x, y) = (tip(&x), tip(&y));
            }
            if ka.name == "regressor" {
                // Y's columns are the inertial parameters in each link's own frame, which differ
                // between the conventions as the frames do; Y π (the torques) does not.
                let torque = |y: &[f64], scene: &Scene| -> Vec<f64> {
                    let pi = bf_codegen::robot::inertial_parameters(scene);
                    y.chunks(pi.len())
                        .map(|row| row.iter().zip(&pi).map(|(a, b)| a * b).sum())
                        .collect()
                };
                (x, y) = (torque(&x, &dh), torque(&y, &urdf));
            }
            close(&format!("state {k}: `{}` DH vs URDF", ka.name), &x, &y);
        }
    }
}

/// `scene` with the kernels the locked-joint comparison evaluates.
fn with_kernels(scene: &Scene) -> Scene {
    let mut s = scene.clone();
    s.kernels = ["frames", "gravity", "mass_matrix", "cqd_g"]
        .map(String::from)
        .to_vec();
    s
}

/// `sub`, the chain from a base link below the root, against `full`, the chain from the root
/// through `locked` more joints above it, at q_full = (0, …, 0, q) (and q̇, q̈ likewise),
/// kernel by kernel: the same frames of the sub-chain's links in the world (tip included),
/// and the sub-chain's rows of g, M, C q̇ + g, the inverse dynamics and its derivatives.
fn same_as_locked(what: &str, sub: &Scene, full: &Scene, locked: usize) {
    use bf_codegen::interp::SceneKernels;
    let (a, b) = (
        SceneKernels::new(&with_kernels(sub)).unwrap(),
        SceneKernels::new(&with_kernels(full)).unwrap(),
    );
    let (n, nf) = (sub.nq(), full.nq());
    assert_eq!(n + locked, nf, "{what}");
    let pad = |v: &[f64]| [vec![0.0; locked], v.to_vec()].concat();
    for (k, [q, qd, u]) in states(n, 5, 41).into_iter().enumerate() {
        let (va, vb) = (
            a.vars(&q, &qd, [0.0; 3], 0.01, &u, None),
            b.vars(&pad(&q), &pad(&qd), [0.0; 3], 0.01, &pad(&u), None),
        );
        for (ka, kb) in a.kernels.iter().zip(&b.kernels) {
            assert_eq!(ka.name, kb.name);
            let (x, y) = (ka.eval(&va), kb.eval(&vb));
            // The sub-chain's part of the full chain's output.
            let y: Vec<f64> = match ka.name.as_str() {
                // Positions p_1..p_n, then rotations R_1..R_n (row-major).
                "frames" => [&y[3 * locked..3 * nf], &y[3 * nf + 9 * locked..]].concat(),
                "mass_matrix" | "inverse_dynamics_dq" | "inverse_dynamics_dqd" => (locked..nf)
                    .flat_map(|i| y[i * nf + locked..(i + 1) * nf].to_vec())
                    .collect(),
                "gravity" | "cqd_g" | "inverse_dynamics" => y[locked..].to_vec(),
                // The full chain's free upper joints take part in its accelerations, and the
                // regressor's columns are the parameters of its own links.
                _ => continue,
            };
            close(&format!("{what}, state {k}: `{}`", ka.name), &x, &y);
        }
    }
}

/// A base link below the root (`--base arm_base`: under a fixed joint, a revolute and a
/// prismatic one, all with turned and offset origins) sits where those joints put it at q = 0,
/// as Pinocchio's `buildReducedModel` places it: the imported kernels match the tree reference
/// with those joints locked (gravity at the root, the tip in the root's frame), and, kernel by
/// kernel, the chain from the root at (0, 0, q). Before, the base link was put at the world
/// origin with its own axes, which turned gravity with the choice of base.
#[test]
fn a_base_link_below_the_root_sits_where_the_locked_joints_put_it() {
    let file = "mounted_arm.urdf";
    let text = read(file);
    let sub = scene_of(&text, file, Some("arm_base"), Some("tip"));
    let full = scene_of(&text, file, None, Some("tip"));
    check_against_tree("mounted arm from arm_base", &sub, &text, "arm_base", "tip");
    assert!(sub.base != Default::default(), "the base link is placed");
    check_against_tree("mounted arm from the root", &full, &text, "world", "tip");
    same_as_locked("--base arm_base", &sub, &full, 2);
    // The shipped planar arm's base link is turned 90° about x on a fixed mount: chosen as the
    // base, the arm still hangs in the vertical plane (gravity does work on it).
    let text = read("planar2.urdf");
    let sub = scene_of(&text, "planar2.urdf", Some("base"), None);
    let full = scene_of(&text, "planar2.urdf", None, None);
    same_as_locked("planar2 --base base", &sub, &full, 0);
}

/// A TOML scene's `[base]` places the URDF's root in the world, and the base link follows it
/// where the joints from the root put it (world ← [base] ← root ← base link): the scene with
/// `base_link` matches the scene from the root, with the same `[base]`, at (0, 0, q); and
/// the recorded text re-reads to the same kernels.
#[test]
fn a_scene_base_and_the_base_links_placement_compose() {
    let dir = std::path::PathBuf::from(dir());
    let scene = |base_link: &str| {
        let text = format!(
            "name = \"mounted\"\nurdf = \"mounted_arm.urdf\"\n{base_link}tip_link = \"tip\"\n\
             kernels = [\"gravity\"]\ngravity = [0.5, -1.0, -9.7]\n\n[base]\n\
             translation = [1.0, -0.5, 0.25]\nrotation = {{ axis = \"y\", angle = \"-pi/3\" }}\n"
        );
        let text = bf_codegen::spec::expand_toml(&text, "mounted.toml", &dir, &Default::default())
            .unwrap_or_else(|e| panic!("{e}"));
        let scene = Scene::from_toml_str(&text, "mounted.toml").unwrap_or_else(|e| panic!("{e}"));
        (scene, text)
    };
    let (sub, text) = scene("base_link = \"arm_base\"\n");
    let (full, _) = scene("");
    same_as_locked("[base] with base_link arm_base", &sub, &full, 2);
    assert_eq!(Scene::from_toml_str(&text, "again").unwrap(), sub, "{text}");
}
