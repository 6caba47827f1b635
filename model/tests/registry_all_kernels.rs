//! The generated registry reaches every kernel of every compiled scene: `SCENE_KERNELS` holds
//! exactly the scenes of `scenes/*.toml` (so a new file needs no hand edits), each entry lists
//! the kernels the scene's spec emits (its `kernels` list plus the inverse-dynamics family),
//! and each entry's `eval_into` agrees with bf-codegen's interpreter on the same expression
//! graphs (an independent evaluation path: a tape instead of emitted Rust) at random states and
//! random runtime-parameter values.

use bf_codegen::Scene;
use bf_codegen::interp::SceneKernels as RuntimeKernels;
use bf_generated::{SCENE_KERNELS, SceneKernels};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

/// Largest relative difference allowed between compiled and interpreted outputs.
const TOL: f64 = 1e-12;

fn parse(entry: &SceneKernels) -> Scene {
    Scene::from_toml_str(entry.toml, entry.name).expect("a compiled scene parses")
}

/// The interpreter's kernels of `scene`, built on a thread with a large stack (building the
/// graphs of a scene with runtime parameters recurses deeply).
fn runtime_kernels(scene: &Scene) -> RuntimeKernels {
    std::thread::scope(|s| {
        std::thread::Builder::new()
            .stack_size(256 << 20)
            .spawn_scoped(s, || RuntimeKernels::new(scene).expect("the graphs build"))
            .expect("spawn")
            .join()
            .expect("building the graphs")
    })
}

#[test]
fn the_registry_holds_exactly_the_scene_files() {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../scenes");
    let mut files: Vec<_> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "toml"))
        .collect();
    files.sort();
    let texts: Vec<String> = files
        .iter()
        .map(|f| std::fs::read_to_string(f).unwrap())
        .collect();
    let names: Vec<String> = files
        .iter()
        .zip(&texts)
        .map(|(f, t)| {
            Scene::from_toml_str(t, &f.display().to_string())
                .unwrap()
                .name
        })
        .collect();
    let registered: Vec<&str> = SCENE_KERNELS.iter().map(|e| e.name).collect();
    assert_eq!(registered, names);
    for (entry, text) in SCENE_KERNELS.iter().zip(&texts) {
        assert_eq!(entry.toml, text, "scene {}", entry.name);
        assert!(bf_generated::scene(entry.name).is_some_and(|e| std::ptr::eq(e, entry)));
    }
}

#[test]
fn every_entry_lists_the_kernels_its_spec_emits() {
    for entry in SCENE_KERNELS {
        let scene = parse(entry);
        let spec = bf_codegen::kernels::with_robot_kernels(&scene).kernels;
        assert_eq!(entry.kernels, spec, "scene {}", entry.name);
        assert_eq!(entry.nq, scene.links.len(), "scene {}", entry.name);
        for (i, k) in entry.kernels.iter().enumerate() {
            assert_eq!(entry.kernel_index(k), Some(i));
        }
        assert_eq!(entry.kernel_index("no_such_kernel"), None);
    }
}

#[test]
fn every_compiled_kernel_agrees_with_the_interpreter() {
    let mut rng = ChaCha8Rng::seed_from_u64(16);
    let pi = std::f64::consts::PI;
    for entry in SCENE_KERNELS {
        let scene = parse(entry);
        let rt = runtime_kernels(&scene);
        let rt_names: Vec<&str> = rt.kernels.iter().map(|k| k.name.as_str()).collect();
        assert_eq!(rt_names, entry.kernels, "scene {}", entry.name);
        let n = entry.nq;
        for _ in 0..4 {
            let q: Vec<f64> = (0..n).map(|_| rng.random_range(-pi..pi)).collect();
            let qd: Vec<f64> = (0..n).map(|_| rng.random_range(-2.0..2.0)).collect();
            let omega: [f64; 3] = std::array::from_fn(|_| rng.random_range(-2.0..2.0));
            let eps = rng.random_range(0.005..0.05);
            let u: Vec<f64> = (0..n).map(|_| rng.random_range(-5.0..5.0)).collect();
            // Runtime parameters within ±10 % of the file's values.
            let p: Vec<f64> = entry
                .param_defaults
                .iter()
                .map(|v| v * rng.random_range(0.9..1.1))
                .collect();
            let vars = rt.vars(&q, &qd, omega, eps, &u, Some(&p));
            for (k, kern) in rt.kernels.iter().enumerate() {
                let want = kern.eval(&vars);
                let mut got = vec![f64::NAN; want.len() + 3];
                let written = (entry.eval_into)(k, &q, &qd, &omega, eps, &u, &p, &mut got);
                assert_eq!(
                    written,
                    Some(want.len()),
                    "{} `{}`: output count",
                    entry.name,
                    kern.name
                );
                let scale = want.iter().fold(1.0f64, |m, x| m.max(x.abs()));
                for (i, (a, b)) in got.iter().zip(&want).enumerate() {
                    assert!(
                        (a - b).abs() <= TOL * scale,
                        "{} `{}`[{i}]: compiled {a} vs interpreted {b}",
                        entry.name,
                        kern.name
                    );
                }
                assert!(got[..want.len()].iter().all(|v| v.is_finite()));
            }
        }
    }
}

#[test]
fn eval_into_refuses_wrong_lengths_and_indices() {
    for entry in SCENE_KERNELS {
        let n = entry.nq;
        let (q, qd, u) = (vec![0.1; n], vec![0.2; n], vec![0.3; n]);
        let p = entry.param_defaults;
        let omega = [0.0, 0.5, 1.0];
        let mut out = vec![0.0; 4096];
        let call = |k, q: &[f64], qd: &[f64], u: &[f64], p: &[f64], out: &mut [f64]| {
            (entry.eval_into)(k, q, qd, &omega, 0.01, u, p, out)
        };
        assert!(
            call(0, &q, &qd, &u, p, &mut out).is_some(),
            "{}",
            entry.name
        );
        let short = vec![0.1; n - 1];
        assert_eq!(call(0, &short, &qd, &u, p, &mut out), None);
        assert_eq!(call(0, &q, &short, &u, p, &mut out), None);
        assert_eq!(call(0, &q, &qd, &short, p, &mut out), None);
        let more_p: Vec<f64> = p.iter().copied().chain([1.0]).collect();
        assert_eq!(call(0, &q, &qd, &u, &more_p, &mut out), None);
        assert_eq!(
            call(entry.kernels.len(), &q, &qd, &u, p, &mut out),
            None,
            "{}: an index past the last kernel",
            entry.name
        );
        assert_eq!(call(0, &q, &qd, &u, p, &mut out[..1]), None);
    }
}
