//! The optimal-control node kernels emitted into bf-generated (by bf-problem on bf-codegen's
//! node-function engine): every node function of the problem library runs on an emitted kernel, the
//! kernels agree bitwise with the interpreted graphs they were emitted from, their derivatives
//! agree with central finite differences of their values, and a node function whose structure
//! differs from every emitted one (another friction coefficient baked into the graph) is
//! interpreted instead of being matched to a wrong kernel, and that the catalogue, which
//! requires the kernels, then refuses to build instead of silently interpreting it.
//!
//! `cargo test --release --test node_kernels`

use ball_finger::pipeline::{GENERATED, build};
use bf_optim::ocp::{GraphFn, KernelUse, Scheme};
use bf_problem::{Generated, Problem, ProblemSettings};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

fn bits(v: &[f64]) -> Vec<u64> {
    v.iter().map(|x| x.to_bits()).collect()
}

/// A random node point of realistic size: states and controls O(1), accelerations O(5),
/// duration in [0.1, 2] s (the last local).
fn random_locals(rng: &mut ChaCha8Rng, n: usize, nx: usize) -> Vec<f64> {
    let mut v: Vec<f64> = (0..n)
        .map(|i| {
            if i < nx {
                rng.random_range(-1.0..1.0)
            } else {
                rng.random_range(-5.0..5.0)
            }
        })
        .collect();
    v[n - 1] = rng.random_range(0.1..2.0);
    v
}

/// Both backends of every phase node function of `settings`' problems.
fn node_pairs(settings: &ProblemSettings) -> Vec<(String, GraphFn, GraphFn, usize)> {
    let mut out = Vec::new();
    for name in Problem::ALL {
        let p = build(name, settings).unwrap_or_else(|e| panic!("{name}: {e}"));
        for (pi, ph) in p.ocp.phases.iter().enumerate() {
            let mut c = ph.node.collocation();
            let auto = GraphFn::with_backend(
                &mut c.graph,
                &c.outputs,
                &c.locals,
                &ph.node.fixed,
                GENERATED.kernels,
            );
            let interp = GraphFn::with_backend(
                &mut c.graph,
                &c.outputs,
                &c.locals,
                &ph.node.fixed,
                KernelUse::Never,
            );
            // The transcription's own function runs on the same kernel.
            assert_eq!(
                p.nlp.phase_functions()[pi].kernel_name(),
                auto.kernel_name(),
                "{name} phase {pi}"
            );
            out.push((format!("{name} phase {pi}"), auto, interp, ph.node.x.len()));
        }
    }
    out
}

#[test]
fn every_library_node_runs_on_an_emitted_kernel_bitwise_equal_to_the_graphs() {
    let radau = ProblemSettings::default();
    let lg = ProblemSettings {
        scheme: Scheme::Lg,
        points: 10,
        ..ProblemSettings::default()
    };
    // ε continuation and other weights change fixed inputs, not the kernel.
    let other_eps = ProblemSettings {
        epsilon: Some(0.05),
        effort_scale: 0.37,
        hdot_margin: Some(0.01),
        ..ProblemSettings::default()
    };
    let mut rng = ChaCha8Rng::seed_from_u64(6);
    let mut used = std::collections::BTreeSet::new();
    for settings in [&radau, &lg, &other_eps] {
        for (what, auto, interp, nx) in node_pairs(settings) {
            let kernel = auto
                .kernel_name()
                .unwrap_or_else(|| panic!("{what}: no emitted kernel ({:?})", settings.scheme));
            used.insert(kernel);
            assert!(interp.kernel_name().is_none());
            assert_eq!(auto.jacobian_pattern(), interp.jacobian_pattern());
            assert_eq!(auto.hessian_pattern(), interp.hessian_pattern());
            for _ in 0..5 {
                let x = random_locals(&mut rng, auto.n_local(), nx);
                let w: Vec<f64> = (0..auto.n_out())
                    .map(|_| rng.random_range(-2.0..2.0))
                    .collect();
                assert_eq!(bits(&auto.eval(&x)), bits(&interp.eval(&x)), "{what}");
                assert_eq!(
                    bits(&auto.jacobian(&x)),
                    bits(&interp.jacobian(&x)),
                    "{what}"
                );
                assert_eq!(
                    bits(&auto.hessian(&x, &w)),
                    bits(&interp.hessian(&x, &w)),
                    "{what}"
                );
            }
        }
    }
    // Free, free with the ḣ margin, stick at both levels, for QC, COT, human COT; the
    // archetypes' stick phases with the |h| row.
    for k in [
        "paper_qc_free",
        "paper_qc_free_hdot",
        "paper_qc_stick",
        "paper_qc_stick_acc",
        "paper_cot_stick",
        "human_cot_free",
        "human_cot_stick_acc",
        "paper_spin_stick_h",
        "paper_reorient_stick_h_acc",
    ] {
        assert!(used.contains(k), "{k} not used: {used:?}");
    }
    // And no kernel is emitted that the library does not use (build time and binary size
    // for nothing).
    let emitted: std::collections::BTreeSet<&str> = bf_generated::ocp::NODE_KERNELS
        .iter()
        .map(|k| k.name)
        .collect();
    assert_eq!(emitted, used, "emitted vs used");
}

#[test]
fn kernel_derivatives_match_finite_differences() {
    let settings = ProblemSettings::default();
    let mut rng = ChaCha8Rng::seed_from_u64(61);
    for name in [Problem::PeriodicQc, Problem::PeriodicCotHuman] {
        let p = build(name, &settings).unwrap();
        for (pi, f) in p.nlp.phase_functions().iter().enumerate() {
            assert!(f.kernel_name().is_some(), "{name} phase {pi}");
            let nx = p.ocp.phases[pi].node.x.len();
            let x = random_locals(&mut rng, f.n_local(), nx);
            let w: Vec<f64> = (0..f.n_out())
                .map(|_| rng.random_range(-2.0..2.0))
                .collect();
            let jac = f.jacobian(&x);
            let hess = f.hessian(&x, &w);
            let n = f.n_local();
            // Dense J by central differences of the values.
            let h = 1e-6;
            let mut fd_j = vec![vec![0.0; n]; f.n_out()];
            for l in 0..n {
                let (mut xp, mut xm) = (x.clone(), x.clone());
                xp[l] += h;
                xm[l] -= h;
                let (yp, ym) = (f.eval(&xp), f.eval(&xm));
                for o in 0..f.n_out() {
                    fd_j[o][l] = (yp[o] - ym[o]) / (2.0 * h);
                }
            }
            let mut dense_j = vec![vec![0.0; n]; f.n_out()];
            for (k, &(o, l)) in f.jacobian_pattern().iter().enumerate() {
                dense_j[o][l] = jac[k];
            }
            for o in 0..f.n_out() {
                for l in 0..n {
                    let (a, b) = (dense_j[o][l], fd_j[o][l]);
                    assert!(
                        (a - b).abs() <= 1e-6 * (1.0 + a.abs()),
                        "{name} phase {pi}: J[{o}][{l}] = {a} vs FD {b}"
                    );
                }
            }
            // ∇²(wᵀy) by central differences of the exact gradient Jᵀw.
            let grad = |xx: &[f64]| -> Vec<f64> {
                let jv = f.jacobian(xx);
                let mut g = vec![0.0; n];
                for (k, &(o, l)) in f.jacobian_pattern().iter().enumerate() {
                    g[l] += w[o] * jv[k];
                }
                g
            };
            let mut dense_h = vec![vec![0.0; n]; n];
            for (k, &(i, j)) in f.hessian_pattern().iter().enumerate() {
                dense_h[i][j] = hess[k];
                dense_h[j][i] = hess[k];
            }
            for l in 0..n {
                let (mut xp, mut xm) = (x.clone(), x.clone());
                xp[l] += h;
                xm[l] -= h;
                let (gp, gm) = (grad(&xp), grad(&xm));
                for i in 0..n {
                    let fd = (gp[i] - gm[i]) / (2.0 * h);
                    let a = dense_h[i][l];
                    assert!(
                        (a - fd).abs() <= 1e-5 * (1.0 + a.abs()),
                        "{name} phase {pi}: H[{i}][{l}] = {a} vs FD {fd}"
                    );
                }
            }
        }
    }
}

#[test]
fn a_node_with_other_baked_constants_is_interpreted_not_mismatched() {
    // μ_v is a constant of the graph (the joints' viscous friction), not an input: another
    // value changes the structure, so no emitted kernel may claim the stick node. μ_s is an
    // input (the σ_δ row's (1 − m) μ_s): another nonzero value runs on the same kernel.
    let edit = |from: &str, to: &str| {
        let text = bf_generated::paper::SCENE_TOML.replace(from, to);
        assert!(text != bf_generated::paper::SCENE_TOML, "{from} not found");
        bf_codegen::Scene::from_toml_str(&text, "test").unwrap()
    };
    let opt = bf_problem::node::NodeSettings {
        mode: bf_problem::PhaseMode::Stick,
        cost: bf_problem::CostKind::Qc {
            w: 1.0,
            omega_ref: [0.0, 0.0, 2.2],
        },
        h_bounds: None,
        hdot_bounds: None,
        eps: 0.01,
        cone_margin: 0.0,
    };
    // The name of the kernel the stick node of `scene` with cone margin `m` runs on, if any.
    let kernel_of = |scene: &bf_codegen::Scene, m: f64| {
        let ph = bf_problem::points::physics(scene).unwrap();
        let opt = bf_problem::node::NodeSettings {
            cone_margin: m,
            ..opt.clone()
        };
        let (nd, _) =
            bf_problem::node::node_function(scene, &ph, &opt, bf_problem::StickLevel::Velocity)
                .unwrap();
        let mut c = nd.collocation();
        GraphFn::with_backend(
            &mut c.graph,
            &c.outputs,
            &c.locals,
            &nd.fixed,
            GENERATED.kernels,
        )
        .kernel_name()
    };
    assert_eq!(
        kernel_of(&edit("\nmu_v = 0.001\n", "\nmu_v = 0.002\n"), 0.0),
        None
    );
    // The same node on the paper scene does find its kernel, with any μ_s and cone margin.
    let paper = bf_codegen::Scene::from_toml_str(bf_generated::paper::SCENE_TOML, "paper").unwrap();
    assert_eq!(kernel_of(&paper, 0.0), Some("paper_qc_stick"));
    assert_eq!(kernel_of(&paper, 0.2), Some("paper_qc_stick"));
    let other_mu = edit("\nmu_s = 0.8\n", "\nmu_s = 0.7\n");
    assert_eq!(kernel_of(&other_mu, 0.0), Some("paper_qc_stick"));
}

/// The paper scene without friction (μ_s = μ_k = 0): the cone row's μ is then a constant 0,
/// not an input (`Inputs` keeps zeros), a stick node no emitted kernel was built from.
fn paper_without_friction(name: &str) -> Option<&'static str> {
    static TEXT: std::sync::OnceLock<String> = std::sync::OnceLock::new();
    let text = TEXT.get_or_init(|| {
        bf_generated::paper::SCENE_TOML
            .replace("\nmu_s = 0.8\n", "\nmu_s = 0.0\n")
            .replace("\nmu_k = 0.6\n", "\nmu_k = 0.0\n")
    });
    (name == "paper").then_some(text.as_str())
}

#[test]
fn a_catalogue_that_requires_kernels_refuses_a_graph_without_one() {
    let settings = ProblemSettings::default();
    let required = Generated {
        scene_toml: paper_without_friction,
        ..GENERATED
    };
    let e = bf_problem::build(Problem::PeriodicQc, &settings, &required)
        .expect_err("no kernel has the stick node with mu_s = 0");
    assert!(e.to_string().contains("no emitted node kernel"), "{e}");
    // Preferring kernels, it builds and interprets exactly the stick phase (μ_s appears only
    // in the friction-cone row of the stick node function).
    let Some(lookup) = GENERATED.kernels.lookup() else {
        panic!("the solve pipeline hands in a kernel lookup")
    };
    let preferred = Generated {
        scene_toml: paper_without_friction,
        kernels: KernelUse::Prefer(lookup),
    };
    let p = bf_problem::build(Problem::PeriodicQc, &settings, &preferred).unwrap();
    let names: Vec<Option<&str>> = p
        .nlp
        .phase_functions()
        .iter()
        .map(|f| f.kernel_name())
        .collect();
    assert_eq!(names, [Some("paper_qc_free"), None, Some("paper_qc_free")]);
}
