//! The compiled kernels of every scene module against bf-codegen's interpreter evaluating the
//! same graphs (random states, q̈ or τ, and perturbed runtime parameters). Both perform the same f64
//! operations in the same order (sine and cosine by the emitted helper, `bf_codegen::trig`, in
//! both), so the results must be bit-identical; the tape's allocation-free `eval_into`
//! (one scratch vector shared by all tapes) gives the same bits as `eval`.

use bf_codegen::Scene;
use bf_codegen::interp::Tape;
use bf_codegen::kernels::build_kernel;
use bf_codegen::robot::SymbolicRobot;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

macro_rules! check_scene {
    ($m:ident, $seed:expr) => {{
        use bf_generated::$m as s;
        let scene = Scene::from_toml_str(s::SCENE_TOML, stringify!($m)).unwrap();
        assert_eq!(scene.name, s::SCENE_NAME);
        let mut model = SymbolicRobot::new(&scene).unwrap();
        assert_eq!(model.nq(), s::NQ);
        assert_eq!(model.params.len(), s::NP);
        for (i, (n, v)) in model.params.iter().enumerate() {
            assert_eq!(n, s::PARAM_NAMES[i]);
            assert_eq!(v.to_bits(), s::PARAM_DEFAULTS[i].to_bits());
        }
        assert_eq!(
            s::KERNELS,
            bf_codegen::kernels::with_robot_kernels(&scene)
                .kernels
                .iter()
                .map(|k| k.as_str())
                .collect::<Vec<_>>()
                .as_slice()
        );
        let mut rng = ChaCha8Rng::seed_from_u64($seed);
        let mut compared = 0usize;
        // One scratch vector for every kernel's tape, as a caller of `eval_into` keeps it.
        let mut scratch = Vec::new();
        for &k in s::KERNELS {
            let def = build_kernel(&mut model, k).unwrap();
            let ids: Vec<_> = def.output_ids();
            let tape = Tape::new(&model.g, &ids);
            for _ in 0..25 {
                let q: [f64; s::NQ] = std::array::from_fn(|_| rng.random_range(-4.0..4.0));
                let qd: [f64; s::NQ] = std::array::from_fn(|_| rng.random_range(-3.0..3.0));
                let omega: [f64; 3] = std::array::from_fn(|_| rng.random_range(-3.0..3.0));
                let eps = rng.random_range(1e-4..0.1);
                let p: [f64; s::NP] =
                    std::array::from_fn(|i| s::PARAM_DEFAULTS[i] * rng.random_range(0.8..1.25));
                let u: [f64; s::NQ] = std::array::from_fn(|_| rng.random_range(-5.0..5.0));
                let l = model.layout;
                let mut vars = vec![0.0; l.n_vars_all()];
                for (i, x) in u.iter().enumerate() {
                    vars[l.qdd(i) as usize] = *x;
                    vars[l.tau(i) as usize] = *x;
                }
                vars[..s::NQ].copy_from_slice(&q);
                vars[s::NQ..2 * s::NQ].copy_from_slice(&qd);
                vars[2 * s::NQ..2 * s::NQ + 3].copy_from_slice(&omega);
                vars[2 * s::NQ + 3] = eps;
                for (i, pi) in p.iter().enumerate() {
                    vars[l.param(i) as usize] = *pi;
                }
                let want: Vec<f64> = tape.eval::<f64>(&vars);
                let mut into = vec![0.0; want.len()];
                tape.eval_into(&vars, &mut scratch, &mut into);
                assert!(
                    into.iter()
                        .zip(&want)
                        .all(|(a, b)| a.to_bits() == b.to_bits()),
                    "{}::{k}: eval_into differs from eval",
                    stringify!($m)
                );
                let got = s::eval_flat_u(k, &q, &qd, &omega, eps, &u, &p).unwrap();
                assert_eq!(
                    got.len(),
                    want.len(),
                    "{}::{k}: output size",
                    stringify!($m)
                );
                for (j, (a, b)) in got.iter().zip(&want).enumerate() {
                    assert!(
                        a.to_bits() == b.to_bits(),
                        "{}::{k}[{j}]: emitted {a:e} vs interpreter {b:e}",
                        stringify!($m)
                    );
                }
                compared += got.len();
            }
        }
        assert!(
            s::eval_flat(
                "no_such_kernel",
                &[0.0; s::NQ],
                &[0.0; s::NQ],
                &[0.0; 3],
                0.01,
                &s::PARAM_DEFAULTS
            )
            .is_none()
        );
        assert!(compared > 0);
    }};
}

#[test]
fn paper_kernels_equal_interpreter() {
    check_scene!(paper, 1);
}

#[test]
fn human_kernels_equal_interpreter() {
    check_scene!(human, 2);
}

#[test]
fn puma560_kernels_equal_interpreter() {
    check_scene!(puma560, 3);
}

#[test]
fn iiwa7_kernels_equal_interpreter() {
    check_scene!(iiwa7, 4);
}
