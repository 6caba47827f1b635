//! The kernel registry: a parsed scene runs on the compiled kernels exactly when it is a
//! compiled scene (runtime-parameter values aside), and the interpreted kernels of the same
//! scene give the same numbers as the compiled ones; a changed scene gives other physics.

mod common;

use bf_codegen::spec::{Scene, SceneId};
use bf_model::registry::{self, KernelSource, compiled_match, set_parameters};
use bf_model::{
    CompiledKernels, ContactVariant, InterpretedKernels, Kernels, Mode, ModelError, State, Vec3,
    fixtures,
};
use common::{HUMAN_TOML, PAPER_TOML, RefKernels};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

fn parse(text: &str) -> Scene {
    Scene::from_toml_str(text, "test").unwrap()
}

fn random_state(rng: &mut ChaCha8Rng) -> ([f64; 3], [f64; 3], [f64; 3]) {
    let mut v = || [0; 3].map(|_| rng.random_range(-2.0..2.0));
    (v(), v(), v())
}

/// Every output of two kernel sets at random states, bit for bit.
fn assert_identical(a: &dyn Kernels, b: &dyn Kernels) {
    let mut rng = ChaCha8Rng::seed_from_u64(7);
    for _ in 0..50 {
        let (q, qd, w) = random_state(&mut rng);
        assert_eq!(a.mass_cqd_g(&q, &qd), b.mass_cqd_g(&q, &qd));
        assert_eq!(a.potential(&q).to_bits(), b.potential(&q).to_bits());
        for v in [ContactVariant::Exact, ContactVariant::Smooth(0.01)] {
            assert_eq!(a.contact(&q, &qd, &w, v), b.contact(&q, &qd, &w, v));
        }
    }
}

#[test]
fn compiled_scenes_match_themselves_and_ignore_limits_and_comments() {
    let paper = parse(PAPER_TOML);
    let (entry, p) = compiled_match(&paper).expect("paper.toml is compiled");
    assert_eq!(entry.name, "paper");
    assert!(p.is_empty());
    // limits and descriptions do not enter the model kernels
    let mut limits = paper.clone();
    limits.links[0].tau_max = Some(0.4);
    limits.description = Some("mine".into());
    assert!(compiled_match(&limits).is_some());
    let (_, source) = registry::contact_kernels(&limits).unwrap();
    assert_eq!(source, KernelSource::Compiled);
}

#[test]
fn same_name_other_numbers_is_interpreted() {
    let text = PAPER_TOML.replacen("mass = 0.02", "mass = 2000.0", 1);
    let scene = parse(&text);
    assert_eq!(scene.name, "paper");
    assert!(compiled_match(&scene).is_none());
    let (model, source) = fixtures::model_for_scene(&scene).unwrap();
    assert_eq!(source, KernelSource::Interpreted);
    // the heavy first link changes the mass matrix against the built-in's
    let x = State::new(Vec3::new(0.1, 0.5, 0.5), Vec3::zeros(), Vec3::zeros());
    let m_heavy = model.evaluate(&x).unwrap().m_f;
    let m_paper = fixtures::paper_scene().unwrap().evaluate(&x).unwrap().m_f;
    assert!((m_heavy - m_paper).norm() > 1.0, "{m_heavy} vs {m_paper}");
}

/// A perturbed plant (a heavier ball, less friction, more socket damping: what the model
/// applies outside its kernels) runs on the compiled kernels with its own parameters, and its
/// physics is bit for bit that of the interpreter on the same scene, which is what it ran on
/// before; a perturbed link enters the kernels and is interpreted.
#[test]
fn parameters_outside_the_kernels_keep_the_compiled_kernels() {
    let text = PAPER_TOML
        .replace(
            "[ball]\nradius = 1.0\ncenter = [0.0, 0.0, 0.0]\nmass = 0.02\n",
            "[ball]\nradius = 1.0\ncenter = [0.0, 0.0, 0.0]\nmass = 0.022\n",
        )
        .replace("mu_s = 0.8\n", "mu_s = 0.64\n")
        .replace("socket_damping = 0.004\n", "socket_damping = 0.006\n");
    assert_ne!(text, PAPER_TOML);
    let scene = parse(&text);
    assert_eq!(scene.name, "paper");
    assert!(compiled_match(&scene).is_none());
    let (plant, source) = fixtures::model_for_scene(&scene).unwrap();
    assert_eq!(source, KernelSource::Compiled);
    let interpreted =
        bf_model::Model::from_kernels(InterpretedKernels::new(&scene).unwrap()).unwrap();

    let nominal = fixtures::paper_scene().unwrap();
    assert_eq!(plant.params(), interpreted.params());
    assert_eq!(plant.params().socket_damping(), 0.006);
    assert_eq!(plant.params().mu_s(), 0.64);
    assert_ne!(
        plant.params().ball_inertia(),
        nominal.params().ball_inertia()
    );
    assert_identical(plant.kernels(), interpreted.kernels());
    let mut rng = ChaCha8Rng::seed_from_u64(11);
    for _ in 0..20 {
        let (q, qd, w) = random_state(&mut rng);
        let x = State::new(Vec3::from(q), Vec3::from(qd), Vec3::from(w));
        let tau = Vec3::new(0.3, -0.2, 0.1);
        assert_eq!(
            plant.free(&x, &tau).unwrap(),
            interpreted.free(&x, &tau).unwrap()
        );
        // and the perturbed ball and damping change the ball's acceleration
        assert_ne!(
            plant.free(&x, &tau).unwrap().omega_dot,
            nominal.free(&x, &tau).unwrap().omega_dot
        );
    }

    // The unperturbed scene: the compiled scene's own parameters.
    let (same, source) = fixtures::model_for_scene(&parse(PAPER_TOML)).unwrap();
    assert_eq!(source, KernelSource::Compiled);
    assert_eq!(same.params(), nominal.params());

    let heavier_link = PAPER_TOML.replacen("mass = 0.02\ncom", "mass = 0.021\ncom", 1);
    let (_, source) = fixtures::model_for_scene(&parse(&heavier_link)).unwrap();
    assert_eq!(source, KernelSource::Interpreted);
}

#[test]
fn interpreted_kernels_equal_compiled_kernels_bitwise() {
    let paper = InterpretedKernels::new(&parse(PAPER_TOML)).unwrap();
    let compiled = CompiledKernels::named(&SceneId::PAPER).unwrap();
    assert_identical(&paper, &compiled);
    let human = InterpretedKernels::new(&parse(HUMAN_TOML)).unwrap();
    let compiled = CompiledKernels::named(&SceneId::HUMAN).unwrap();
    assert_identical(&human, &compiled);
}

#[test]
fn interpreted_kernels_of_a_modified_finger_agree_with_the_reference() {
    // an independent implementation (bf-testkit) of a finger with other links and ball
    let text = PAPER_TOML
        .replace("a = 1.0", "a = 0.8")
        .replace("mass = 0.02", "mass = 0.03")
        .replace("com = [-0.5, 0.0, 0.0]", "com = [-0.4, 0.0, 0.0]");
    let k = InterpretedKernels::new(&parse(&text)).unwrap();
    let r = RefKernels::new(&text);
    let mut rng = ChaCha8Rng::seed_from_u64(3);
    for _ in 0..20 {
        let (q, qd, w) = random_state(&mut rng);
        let (m, c) = k.mass_cqd_g(&q, &qd);
        let (mr, cr) = r.mass_cqd_g(&q, &qd);
        for i in 0..3 {
            assert!((c[i] - cr[i]).abs() < 1e-12, "{c:?} vs {cr:?}");
            for j in 0..3 {
                assert!((m[i][j] - mr[i][j]).abs() < 1e-12, "{m:?} vs {mr:?}");
            }
        }
        assert!((k.potential(&q) - r.potential(&q)).abs() < 1e-12);
        let (a, b) = (
            k.contact(&q, &qd, &w, ContactVariant::Exact),
            r.contact(&q, &qd, &w, ContactVariant::Exact),
        );
        assert!((a.h - b.h).abs() < 1e-12, "{} vs {}", a.h, b.h);
        assert!((a.j_c - b.j_c).norm() < 1e-12);
    }
}

#[test]
fn runtime_parameters_keep_the_compiled_kernels_and_reach_the_physics() {
    let mut human = parse(HUMAN_TOML);
    set_parameters(&mut human, &[("ball.radius".into(), 0.8)]).unwrap();
    let (entry, p) = compiled_match(&human).expect("still the compiled human scene");
    let ir = entry
        .param_names
        .iter()
        .position(|n| *n == "ball.radius")
        .unwrap();
    assert_eq!(p[ir], 0.8);
    let (model, source) = fixtures::model_for_scene(&human).unwrap();
    assert_eq!(source, KernelSource::Compiled);
    assert_eq!(model.params().ball_radius(), 0.8);
    // The default ball inertia (2/5) m r² is that of the new radius, as in a scene file that
    // gives r = 0.8 m (it used to stay the file's r = 1 m), through the scene and through the
    // compiled kernels' own parameter vector alike.
    let base = fixtures::human_scene().unwrap();
    let small = parse(&HUMAN_TOML.replacen("radius = 1.0", "radius = 0.8", 1));
    let file = bf_model::Model::from_kernels(InterpretedKernels::new(&small).unwrap()).unwrap();
    assert_eq!(model.params().ball_inertia(), file.params().ball_inertia());
    let by_p =
        bf_model::Model::from_kernels(bf_model::HumanKernels::with_params(&p).unwrap()).unwrap();
    assert_eq!(by_p.params(), model.params());
    let ratio = model.params().ball_inertia()[(0, 0)] / base.params().ball_inertia()[(0, 0)];
    assert!((ratio - 0.64).abs() < 1e-12, "{ratio}");
    // the interpreter on the same modified scene gives the same contact
    let interp = InterpretedKernels::new(&human).unwrap();
    assert_identical(&interp, model.kernels());
    // and the gap grows by the 0.2 m the radius shrank
    let x = State::new(Vec3::new(0.3, 0.9, 0.7), Vec3::zeros(), Vec3::zeros());
    let h = model.evaluate(&x).unwrap().contact.h;
    let h0 = base.evaluate(&x).unwrap().contact.h;
    assert!((h - h0 - 0.2).abs() < 1e-12, "{h} vs {h0}");
}

#[test]
fn bad_parameters_and_scenes_are_errors_naming_them() {
    let mut human = parse(HUMAN_TOML);
    let e = set_parameters(&mut human, &[("link1.mass".into(), 1.0)]).unwrap_err();
    let msg = e.to_string();
    assert!(
        msg.contains("link1.mass") && msg.contains("ball.radius") && msg.contains("link3.mass"),
        "{msg}"
    );
    let e = set_parameters(&mut human, &[("ball.radius".into(), f64::NAN)]).unwrap_err();
    assert!(e.to_string().contains("finite"), "{e}");
    // A radius whose default inertia (2/5) m r² underflows is refused as in a scene file.
    let e = set_parameters(&mut human, &[("ball.radius".into(), 1e-200)]).unwrap_err();
    assert!(
        e.to_string().contains("ball.radius") && e.to_string().contains("inertia"),
        "{e}"
    );
    let mut paper = parse(PAPER_TOML);
    let e = set_parameters(&mut paper, &[("ball.radius".into(), 1.0)]).unwrap_err();
    assert!(e.to_string().contains("no runtime parameters"), "{e}");
    let puma = parse(include_str!("../../scenes/puma560.toml"));
    let e = fixtures::model_for_scene(&puma).unwrap_err();
    assert!(matches!(e, ModelError::Scene { .. }));
    let msg = e.to_string();
    assert!(
        msg.contains("puma560") && msg.contains("no [ball]") && msg.contains("6 joints"),
        "{msg}"
    );
    let e = CompiledKernels::named(&puma.id()).unwrap_err().to_string();
    assert!(e.contains("paper") && e.contains("human"), "{e}");
}

#[test]
fn interpreted_model_runs_the_contact_physics() {
    // a modified finger: its free motion conserves energy up to the joint and socket damping
    let text = PAPER_TOML.replace("a = 1.0", "a = 0.8");
    let (model, _) = fixtures::model_for_scene(&parse(&text)).unwrap();
    let x = State::new(
        Vec3::new(0.0, -1.0, 0.0),
        Vec3::zeros(),
        Vec3::new(0.0, 0.0, 2.0),
    );
    let acc = model
        .accelerations(Mode::Free, &x, &Vec3::new(0.1, 0.0, 0.0))
        .unwrap();
    let power = model
        .power_balance(&x, &Vec3::new(0.1, 0.0, 0.0), &acc.force)
        .unwrap();
    assert!(power.total < 0.0, "{power:?}");
}

#[test]
fn parameter_values_pass_the_scene_files_checks() {
    let mut human = parse(HUMAN_TOML);
    for (name, value, rule) in [
        ("ball.radius", -1.0, "ball.radius: must be > 0"),
        ("link3.mass", 0.0, "links[2].mass: must be > 0"),
        (
            "link3.mass",
            1e-300,
            "links[2].mass: mass 1e-300 kg is below",
        ),
    ] {
        let msg = set_parameters(&mut human, &[(name.into(), value)])
            .unwrap_err()
            .to_string();
        assert!(
            msg.contains(&format!("`{name}` = {value:?}")) && msg.contains(rule),
            "{msg}"
        );
    }
    // A valid value still passes, and the scene carries it.
    set_parameters(&mut human, &[("link3.mass".into(), 0.03)]).unwrap();
    assert_eq!(human.links[2].mass, 0.03);
}
