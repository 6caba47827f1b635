//! Free motion of arms without a ball (any number of joints): the forward dynamics of
//! `bf_model::arm` against bf-testkit's independent Newton–Euler inverse dynamics for PUMA 560
//! and iiwa 7, compiled against interpreted kernels, and the errors for bad input.

use bf_codegen::spec::Scene;
use bf_model::KernelSource;
use bf_model::arm::ArmModel;
use bf_testkit::Reference;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

const PUMA: &str = include_str!("../../scenes/puma560.toml");
const IIWA: &str = include_str!("../../scenes/iiwa7.toml");

fn parse(text: &str) -> Scene {
    Scene::from_toml_str(text, "test").unwrap()
}

fn random(rng: &mut ChaCha8Rng, n: usize, a: f64) -> Vec<f64> {
    (0..n).map(|_| rng.random_range(-a..a)).collect()
}

#[test]
fn forward_dynamics_inverts_independent_newton_euler() {
    for text in [PUMA, IIWA] {
        let scene = parse(text);
        let (arm, source) = ArmModel::from_scene(&scene).unwrap();
        assert_eq!(source, KernelSource::Compiled);
        let reference = Reference::new(&scene).unwrap();
        let n = arm.nq();
        let mut rng = ChaCha8Rng::seed_from_u64(11);
        for _ in 0..20 {
            let q = random(&mut rng, n, 3.0);
            let qd = random(&mut rng, n, 2.0);
            let tau = random(&mut rng, n, 20.0);
            let qdd = arm.accelerations(&q, &qd, &tau).unwrap();
            let back = reference.inverse_dynamics_ne(&q, &qd, &qdd);
            let viscous: Vec<f64> = qd.iter().map(|v| arm.mu_v() * v).collect();
            for i in 0..n {
                let err = (back[i] + viscous[i] - tau[i]).abs();
                assert!(
                    err < 1e-9 * (1.0 + tau[i].abs()),
                    "{}: joint {i}: {err:e}",
                    scene.name
                );
            }
            let u = arm.potential(&q).unwrap();
            assert!((u - reference.potential(&q)).abs() < 1e-9 * (1.0 + u.abs()));
        }
    }
}

#[test]
fn interpreted_arm_equals_compiled_arm_bitwise_and_changed_arm_differs() {
    let puma = parse(PUMA);
    let (compiled, _) = ArmModel::from_scene(&puma).unwrap();
    let renamed = parse(&PUMA.replacen("name = \"puma560\"", "name = \"my_puma\"", 1));
    let (interp, source) = ArmModel::from_scene(&renamed).unwrap();
    assert_eq!(source, KernelSource::Interpreted);
    let mut rng = ChaCha8Rng::seed_from_u64(5);
    for _ in 0..10 {
        let q = random(&mut rng, 6, 3.0);
        let qd = random(&mut rng, 6, 2.0);
        let tau = random(&mut rng, 6, 20.0);
        assert_eq!(
            compiled.accelerations(&q, &qd, &tau).unwrap(),
            interp.accelerations(&q, &qd, &tau).unwrap()
        );
        assert_eq!(
            compiled.energy(&q, &qd).unwrap().to_bits(),
            interp.energy(&q, &qd).unwrap().to_bits()
        );
    }
    let mut other = puma.clone();
    other.links[1].mass *= 2.0;
    let (changed, source) = ArmModel::from_scene(&other).unwrap();
    assert_eq!(source, KernelSource::Interpreted);
    let q = [0.1, 0.4, -0.3, 0.2, 0.5, 0.1];
    assert!(
        (changed.potential(&q).unwrap() - compiled.potential(&q).unwrap()).abs() > 1e-6,
        "a heavier link 2 changes U"
    );
}

#[test]
fn wrong_lengths_and_non_finite_inputs_are_errors() {
    let (arm, _) = ArmModel::from_scene(&parse(IIWA)).unwrap();
    let z = vec![0.0; 7];
    let e = arm.accelerations(&z[..6], &z, &z).unwrap_err().to_string();
    assert!(e.contains("6 entries") && e.contains("7 joints"), "{e}");
    let mut bad = z.clone();
    bad[2] = f64::NAN;
    assert!(arm.accelerations(&z, &z, &bad).is_err());
}
