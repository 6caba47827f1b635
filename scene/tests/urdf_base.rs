//! The base link of a URDF chain (`--base LINK`, `base_link`, `Builder::base`) sits where the
//! joints from the root put it, the moving ones at q = 0 (Pinocchio's `buildReducedModel`):
//! the imported scene's link frames and centres of mass in the world, at any q, are those of
//! the chain from the root with the joints above the base link locked at 0; a TOML scene's
//! `[base]` (the root in the world) comes first; the recorded scene text re-reads to the same
//! scene; and the scene's own `[base]` is still checked at its own lines.

#[path = "../../tests/common/tempdir.rs"]
mod tempdir;
use tempdir::TempDir;

use bf_scene::{ChainChoice, JointType, Scene, read_urdf_chain, rpy_matrix};

type M3 = [[f64; 3]; 3];
type Pose = (M3, [f64; 3]);

const URDF: &str = "mounted_arm.urdf";

/// The test URDF (testkit/tests/urdf/mounted_arm.urdf): root "world", then a fixed `mount`,
/// a revolute `swivel` and a prismatic `lift` (origins with xyz and rpy) down to "arm_base",
/// then the arm's `shoulder` and `elbow` to "tip"; a `side` joint branches off the pedestal.
fn urdf() -> String {
    let path = format!(
        "{}/../testkit/tests/urdf/{URDF}",
        env!("CARGO_MANIFEST_DIR")
    );
    std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{path}: {e}"))
}

fn tmpdir(name: &str) -> TempDir {
    TempDir::fresh(
        std::env::temp_dir().join(format!("bf-scene-urdf-base-{name}-{}", std::process::id())),
    )
}

fn choice(base: Option<&str>) -> ChainChoice {
    ChainChoice {
        base: base.map(str::to_string),
        tip: Some("tip".to_string()),
    }
}

fn mul(a: &M3, b: &M3) -> M3 {
    [0, 1, 2].map(|i| [0, 1, 2].map(|j| (0..3).map(|k| a[i][k] * b[k][j]).sum()))
}

fn apply(a: &M3, v: [f64; 3]) -> [f64; 3] {
    [0, 1, 2].map(|i| (0..3).map(|k| a[i][k] * v[k]).sum())
}

fn compose(a: &Pose, b: &Pose) -> Pose {
    let t = apply(&a.0, b.1);
    (mul(&a.0, &b.0), [0, 1, 2].map(|k| t[k] + a.1[k]))
}

/// Rotation by `q` about the unit vector `u` (Rodrigues).
fn axis_angle(u: [f64; 3], q: f64) -> M3 {
    let (s, c) = libm::sincos(q);
    let k = [[0.0, -u[2], u[1]], [u[2], 0.0, -u[0]], [-u[1], u[0], 0.0]];
    let kk = mul(&k, &k);
    [0, 1, 2].map(|i| {
        [0, 1, 2].map(|j| f64::from(u8::from(i == j)) + s * k[i][j] + (1.0 - c) * kk[i][j])
    })
}

fn pose_of(t: &bf_scene::TransformSpec) -> Pose {
    (t.rotation_matrix(), t.translation())
}

/// World frames of the links of a placement-form scene at `q` (written out here, apart from
/// the generator): base ∘ origin_i ∘ joint motion_i, then the tip (with the tool), and each
/// link's centre of mass in the world.
fn kinematics(scene: &Scene, q: &[f64]) -> (Vec<Pose>, Vec<[f64; 3]>) {
    let mut p = pose_of(&scene.base);
    let (mut frames, mut coms) = (Vec::new(), Vec::new());
    for (l, &qi) in scene.links.iter().zip(q) {
        let origin = l.origin.as_ref().map_or(
            (
                [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]],
                [0.0; 3],
            ),
            pose_of,
        );
        let u = l.axis.expect("placement form");
        let motion = match l.joint {
            JointType::Revolute => (axis_angle(u, qi), [0.0; 3]),
            JointType::Prismatic => (axis_angle(u, 0.0), u.map(|x| x * qi)),
        };
        p = compose(&compose(&p, &origin), &motion);
        frames.push(p);
        let c = apply(&p.0, l.com);
        coms.push([0, 1, 2].map(|k| c[k] + p.1[k]));
    }
    if let Some(t) = &scene.tool {
        frames.push(compose(&p, &pose_of(t)));
    }
    (frames, coms)
}

fn close(what: &str, a: &[f64], b: &[f64]) {
    for (k, (x, y)) in a.iter().zip(b).enumerate() {
        assert!(
            (x - y).abs() <= 1e-12,
            "{what}[{k}]: {x} vs {y}\n{a:?}\n{b:?}"
        );
    }
}

fn flat(p: &Pose) -> Vec<f64> {
    p.0.iter().flatten().chain(&p.1).copied().collect()
}

/// `sub` (the arm from "arm_base", joints shoulder and elbow) at q against `full` (the chain
/// from the root: swivel, lift, shoulder, elbow) at (0, 0, q): the same link frames in the
/// world, tip included, and the same centres of mass of the arm's links.
fn same_arm(what: &str, sub: &Scene, full: &Scene) {
    assert_eq!((sub.nq(), full.nq()), (2, 4), "{what}");
    for q in [[0.0, 0.0], [0.7, -1.3], [-2.1, 0.4]] {
        let (fs, cs) = kinematics(sub, &q);
        let (ff, cf) = kinematics(full, &[0.0, 0.0, q[0], q[1]]);
        assert_eq!(fs.len(), 3, "{what}: two links and the tip");
        for (k, (a, b)) in fs.iter().zip(&ff[2..]).enumerate() {
            close(
                &format!("{what}: frame {k} at q = {q:?}"),
                &flat(a),
                &flat(b),
            );
        }
        for (k, (a, b)) in cs.iter().zip(&cf[2..]).enumerate() {
            close(&format!("{what}: COG {k} at q = {q:?}"), a, b);
        }
        // The moving links carry the same bodies (the same mass below each joint).
        let masses = |s: &Scene| s.links.iter().map(|l| l.mass).collect::<Vec<_>>();
        assert_eq!(masses(sub), masses(full)[2..], "{what}");
    }
}

/// The base link's pose in the root: mount ∘ swivel origin ∘ lift origin (xyz, then rpy).
fn arm_base_in_root() -> Pose {
    let o = |xyz: [f64; 3], rpy: [f64; 3]| (rpy_matrix(rpy), xyz);
    let mount = o([0.1, -0.2, 0.5], [0.3, -0.4, 0.7]);
    let swivel = o([0.0, 0.05, 0.3], [std::f64::consts::FRAC_PI_2, 0.0, 0.2]);
    let lift = o([0.2, 0.0, 0.1], [0.0, 0.6, -0.3]);
    compose(&compose(&mount, &swivel), &lift)
}

#[test]
fn the_chain_records_where_the_base_link_sits_in_the_root() {
    let text = urdf();
    let c = read_urdf_chain(&text, URDF, Some("arm_base"), Some("tip"), None).unwrap();
    assert_eq!(
        (c.root_link.as_str(), c.base_link.as_str()),
        ("world", "arm_base")
    );
    assert_eq!(c.joint_names, ["shoulder", "elbow"]);
    let base = c
        .base
        .as_ref()
        .expect("arm_base is not at the root's frame");
    close("base", &flat(&pose_of(base)), &flat(&arm_base_in_root()));
    // From the root, the base is the root: nothing to place.
    let c = read_urdf_chain(&text, URDF, None, Some("tip"), None).unwrap();
    assert_eq!(c.base, None);
    assert_eq!(c.joint_names, ["swivel", "lift", "shoulder", "elbow"]);
    // A base link fixed to the root by a joint without an origin sits at the root as well.
    let plain = text.replace("<origin xyz=\"0.1 -0.2 0.5\" rpy=\"0.3 -0.4 0.7\"/>", "");
    let c = read_urdf_chain(&plain, URDF, Some("pedestal"), Some("tip"), None).unwrap();
    assert_eq!(c.base, None);
}

#[test]
fn a_urdf_chain_from_a_deeper_base_link_is_the_root_chain_with_its_joints_locked() {
    let dir = tmpdir("alone");
    let path = dir.join(URDF);
    std::fs::write(&path, urdf()).unwrap();
    let (sub, sub_text) = Scene::load_with_text(&path, &choice(Some("arm_base"))).unwrap();
    let (full, full_text) = Scene::load_with_text(&path, &choice(None)).unwrap();
    same_arm("URDF alone", &sub, &full);
    // The base link's placement is the scene's [base]; from the root there is none.
    close(
        "[base]",
        &flat(&pose_of(&sub.base)),
        &flat(&arm_base_in_root()),
    );
    assert!(sub_text.contains("\n[base]\n"), "{sub_text}");
    assert!(!full_text.contains("[base]"), "{full_text}");
    assert_eq!(full.base, Default::default());
    // Gravity stays the world's: the base link's turn is in the base, not in g.
    assert_eq!(sub.gravity, [0.0, 0.0, -9.81]);
    // The recorded text is self-contained and re-reads to the same scene.
    for (scene, text) in [(&sub, &sub_text), (&full, &full_text)] {
        assert_eq!(
            &Scene::from_toml_str(text, "again").unwrap(),
            scene,
            "{text}"
        );
    }
}

/// A TOML scene's `[base]` places the URDF's root in the world; the base link follows where
/// the joints from the root put it: world ← [base] ← root ← base link, whichever way the user
/// spells `[base]`, and the recorded text carries the composition as its one `[base]`.
#[test]
fn a_scene_base_places_the_root_and_the_base_link_follows() {
    let dir = tmpdir("toml");
    std::fs::write(dir.join(URDF), urdf()).unwrap();
    let head = format!(
        "name = \"mounted\"\nurdf = \"{URDF}\"\ntip_link = \"tip\"\nkernels = [\"gravity\"]\n"
    );
    let bases = [
        "\n[base]\ntranslation = [1.0, -0.5, 0.25]\nrotation = { axis = \"x\", angle = \"pi/2\" }\n",
        "base = { translation = [1.0, -0.5, 0.25], rotation = { axis = \"x\", angle = \"90deg\" } }\n",
        "base.translation = [1.0, -0.5, 0.25]\nbase.rotation = { axis = \"x\", angle = \"pi/2\" }\n",
        "\n[base]\ntranslation = [\n  1.0,\n  -0.5,\n  0.25,\n]\n\n[base.rotation]\naxis = \"x\"\nangle = \"pi/2\"\n",
    ];
    let user: Pose = (
        [[1.0, 0.0, 0.0], [0.0, 0.0, -1.0], [0.0, 1.0, 0.0]],
        [1.0, -0.5, 0.25],
    );
    let tail = "\n[friction]\nmu_s = 0.8\nmu_k = 0.6\n";
    let path = dir.join("mounted.toml");
    let mut texts = Vec::new();
    for base in bases {
        std::fs::write(&path, format!("{head}{base}{tail}")).unwrap();
        let (full, full_text) = Scene::load_with_text(&path, &choice(None)).unwrap();
        let (sub, sub_text) = Scene::load_with_text(&path, &choice(Some("arm_base"))).unwrap();
        same_arm(base, &sub, &full);
        close(base, &flat(&pose_of(&full.base)), &flat(&user));
        let want = compose(&user, &arm_base_in_root());
        close(base, &flat(&pose_of(&sub.base)), &flat(&want));
        // The same key in the scene file chooses the same chain as the option.
        std::fs::write(
            &path,
            format!("{head}base_link = \"arm_base\"\n{base}{tail}"),
        )
        .unwrap();
        let (keyed, _) = Scene::load_with_text(&path, &ChainChoice::default()).unwrap();
        assert_eq!(keyed, sub, "{base}");
        // The user's [base] became comments, line for line; the rest is still there.
        let lines = |t: &str| t.lines().count();
        assert!(lines(&sub_text) > lines(&format!("{head}{base}{tail}")));
        assert!(
            sub_text.contains("\n[friction]\nmu_s = 0.8\n"),
            "{sub_text}"
        );
        for (scene, text) in [(&sub, &sub_text), (&full, &full_text)] {
            assert_eq!(
                &Scene::from_toml_str(text, "again").unwrap(),
                scene,
                "{text}"
            );
        }
        // With the base at the root the user's text is kept as written.
        assert!(full_text.contains(base), "{full_text}");
        texts.push(sub);
    }
    for s in &texts[1..] {
        close(
            "spellings",
            &flat(&pose_of(&s.base)),
            &flat(&pose_of(&texts[0].base)),
        );
    }
}

/// The scene's own `[base]`, which the recorded text replaces by the composition, is checked
/// where the user wrote it; so are the lines after it.
#[test]
fn errors_in_a_scene_base_point_at_the_users_lines() {
    let dir = tmpdir("errors");
    std::fs::write(dir.join(URDF), urdf()).unwrap();
    let head = format!(
        "name = \"mounted\"\nurdf = \"{URDF}\"\nbase_link = \"arm_base\"\ntip_link = \"tip\"\nkernels = [\"gravity\"]\n\n[base]\n"
    );
    let path = dir.join("mounted.toml");
    let cases = [
        (
            "rotation = { axis = \"w\", angle = 1.0 }\n",
            8,
            "base.rotation.axis",
        ),
        (
            "rotation = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, -1.0]]\n",
            8,
            "base.rotation",
        ),
        ("translation = [0.0, nan, 0.0]\n", 8, "base.translation[1]"),
        ("translation = \"up\"\n", 8, "base.translation"),
        ("scale = 2.0\n", 8, "base.scale"),
        (
            "translation = [0.0, 0.0, 0.0]\n\n[friction]\nmu_s = -1.0\nmu_k = 0.5\n",
            11,
            "friction.mu_s",
        ),
    ];
    for (body, line, key) in cases {
        std::fs::write(&path, format!("{head}{body}")).unwrap();
        let err = Scene::load(&path).unwrap_err();
        let shown = err.to_string();
        assert_eq!(
            (err.line(), err.path()),
            (Some(line), Some(key)),
            "{body}: {shown}"
        );
        assert!(shown.starts_with(&path.display().to_string()), "{shown}");
    }
    // `base` must be a table.
    std::fs::write(
        &path,
        format!(
            "name = \"mounted\"\nurdf = \"{URDF}\"\nbase_link = \"arm_base\"\ntip_link = \"tip\"\nbase = 3\nkernels = [\"gravity\"]\n"
        ),
    )
    .unwrap();
    let err = Scene::load(&path).unwrap_err();
    assert_eq!((err.line(), err.path()), (Some(5), Some("base")), "{err}");
}
