//! Public API: `generate` errors and report, `eval_all`, runtime parameters (scaling of
//! masses and lengths by 1e±3 through parameters, measured against double-double).

mod common;

use bf_codegen::dd::Dd;
use bf_codegen::robot::SymbolicRobot;
use bf_codegen::{CodegenError, EvalValue, Scene, eval_all, generate};
use common::*;

#[test]
fn generate_reports_every_kernel() {
    let sc = scene("paper");
    let text = std::fs::read_to_string(format!(
        "{}/../scenes/paper.toml",
        env!("CARGO_MANIFEST_DIR")
    ))
    .unwrap();
    let g = generate(&sc, &text).unwrap();
    let names: Vec<&str> = g.report.kernels.iter().map(|k| k.name.as_str()).collect();
    assert_eq!(
        names,
        sc.kernels.iter().map(|s| s.as_str()).collect::<Vec<_>>()
    );
    for k in &g.report.kernels {
        assert!(g.code.contains(&format!("pub fn {}(", k.name)));
        assert!(k.ops.temporaries > 0);
    }
    // mass matrix of the finger: M depends on q2, q3 only (2 sin/cos), structural zeros emit
    // no arithmetic, and the whole kernel is small.
    let mm = g
        .report
        .kernels
        .iter()
        .find(|k| k.name == "mass_matrix")
        .unwrap();
    assert_eq!(mm.ops.sincos, 2);
    assert!(mm.ops.total() < 80, "{:?}", mm.ops);
    let text = g.report.to_string();
    assert!(text.contains("mass_matrix") && text.contains("generated in"));
    assert!(
        g.code.contains("m[0][1] = 0.0;"),
        "M_12 of the finger is a structural zero"
    );
}

#[test]
fn generate_rejects_bad_scenes() {
    let mut sc = scene("paper");
    sc.kernels.push("no_such_kernel".into());
    assert!(matches!(generate(&sc, ""), Err(CodegenError::Scene(_))));
    let mut sc = scene("puma560");
    sc.kernels = vec!["contact".into()];
    let e = generate(&sc, "").unwrap_err();
    assert!(e.to_string().contains("ball"), "{e}");
    let mut sc = scene("paper");
    sc.runtime_parameters = vec!["link9.mass".into()];
    let e = generate(&sc, "").unwrap_err();
    assert!(e.to_string().contains("link9.mass"), "{e}");
    let mut sc = scene("paper");
    sc.kernels = vec!["gravity".into(), "gravity".into()];
    assert!(generate(&sc, "").is_err());
    let mut sc = scene("paper");
    sc.links.clear();
    assert!(generate(&sc, "").is_err());
}

#[test]
fn eval_all_outputs_and_input_errors() {
    let sc = scene("paper");
    let q = [0.3, -0.4, 1.2];
    let qd = [0.1, 0.2, -0.3];
    let out = eval_all(&sc, &q, &qd, [0.0, 0.0, 2.2], 0.01).unwrap();
    let names: Vec<&str> = out.entries.iter().map(|e| e.0.as_str()).collect();
    assert_eq!(
        names,
        [
            "p_e",
            "R3",
            "J_p",
            "J_o",
            "M",
            "C",
            "Cqd",
            "g",
            "alpha",
            "sat_alpha",
            "p_c",
            "h",
            "J_c",
            "sat_alpha_smooth",
            "p_c_smooth",
            "h_smooth",
            "J_c_smooth"
        ]
    );
    // Cqd = C q̇
    let (EvalValue::Matrix(c), EvalValue::Vector(cqd)) =
        (out.get("C").unwrap(), out.get("Cqd").unwrap())
    else {
        panic!("shapes")
    };
    for i in 0..3 {
        let v: f64 = (0..3).map(|j| c[i][j] * qd[j]).sum();
        assert!((v - cqd[i]).abs() < 1e-15);
    }
    let json = serde_json::to_string(&out).unwrap();
    assert!(json.starts_with("{\"p_e\":["));
    // no contact entries without a ball
    let arm = eval_all(&scene("puma560"), &[0.1; 6], &[0.0; 6], [0.0; 3], 0.01).unwrap();
    assert!(arm.get("h").is_none() && arm.get("M").is_some());
    assert!(matches!(
        eval_all(&sc, &[0.0; 2], &[0.0; 3], [0.0; 3], 0.01),
        Err(CodegenError::Input(_))
    ));
    assert!(eval_all(&sc, &[f64::NAN, 0.0, 0.0], &[0.0; 3], [0.0; 3], 0.01).is_err());
}

/// Paper finger with every mass, inertia and length a runtime parameter: scaling masses and
/// inertias by s scales M, C q̇, g by s; scaling lengths by L (inertias by L²) scales M by L²
/// and g by L (and C q̇ by L²) — for s, L = 1e±3, each evaluation within 1e-13 of
/// double-double.
#[test]
fn runtime_parameters_scale_masses_and_lengths() {
    let mut sc: Scene = scene("paper");
    let mut names = Vec::new();
    for i in 1..=3 {
        for f in [
            "mass",
            "inertia.xx",
            "inertia.yy",
            "inertia.zz",
            "a",
            "com.x",
        ] {
            names.push(format!("link{i}.{f}"));
        }
    }
    names.push("base.translation.x".into());
    sc.runtime_parameters = names.clone();
    let mut m = SymbolicRobot::new(&sc).unwrap();
    let mm = flat2(&m.mass_matrix());
    let cqdg = m.cqd_g();
    let rnea = m.cqd_g_rnea();
    let grav = m.gravity();
    let base: Vec<f64> = m.params.iter().map(|p| p.1).collect();
    let mut rng = rng(61);
    for _ in 0..20 {
        let mut st = State::random(&m, &mut rng);
        st.p = base.clone();
        let m0 = ev(&m, &mm, &st);
        let c0 = ev(&m, &cqdg, &st);
        for s in [1e-3, 1e3] {
            // masses and inertias × s
            st.p = names
                .iter()
                .zip(&base)
                .map(|(n, v)| {
                    if n.contains("mass") || n.contains("inertia") {
                        v * s
                    } else {
                        *v
                    }
                })
                .collect();
            let m1 = ev(&m, &mm, &st);
            let c1 = ev(&m, &cqdg, &st);
            let r1 = ev(&m, &rnea, &st);
            for (a, b) in m1.iter().zip(&m0) {
                assert!((a / s - b).abs() <= 1e-13 * b.abs().max(1e-3));
            }
            let scale = c0.iter().fold(1e-6f64, |x, y| x.max(y.abs()));
            for ((a, b), r) in c1.iter().zip(&c0).zip(&r1) {
                assert!((a / s - b).abs() <= 1e-13 * scale);
                assert!((r / s - b).abs() <= 1e-12 * scale);
            }
            // lengths × s, inertias × s² (same masses): M × s², g × s
            st.p = names
                .iter()
                .zip(&base)
                .map(|(n, v)| {
                    if n.contains("inertia") {
                        v * s * s
                    } else if n.contains("mass") {
                        *v
                    } else {
                        v * s
                    }
                })
                .collect();
            let m2 = ev(&m, &mm, &st);
            for (a, b) in m2.iter().zip(&m0) {
                assert!((a / (s * s) - b).abs() <= 1e-13 * b.abs().max(1e-3));
            }
            let g0 = ev(&m, &grav, &{
                let mut t = st.clone();
                t.p = base.clone();
                t
            });
            let g2 = ev(&m, &grav, &st);
            for (a, b) in g2.iter().zip(&g0) {
                assert!(
                    (a / s - b).abs() <= 1e-13 * g0.iter().fold(1e-6f64, |x, y| x.max(y.abs()))
                );
            }
            // accuracy against double-double at the scaled parameters
            let exact: Vec<Dd> = ev_as::<Dd>(&m, &cqdg, &st);
            let got = ev(&m, &cqdg, &st);
            let sc2 = exact.iter().fold(1e-300f64, |x, y| x.max(y.to_f64().abs()));
            for (g, e) in got.iter().zip(&exact) {
                assert!((Dd::new(*g) - *e).to_f64().abs() <= 1e-13 * sc2);
            }
        }
    }
}

#[test]
fn overflowing_scene_values_are_refused_by_generate_and_eval() {
    let path = format!("{}/../scenes/paper.toml", env!("CARGO_MANIFEST_DIR"));
    let paper = std::fs::read_to_string(&path).unwrap();
    let text = paper.replacen("\na = 1.0\n", "\na = 1.0e308\n", 1);
    assert_ne!(text, paper);
    let scene = Scene::from_toml_str(&text, "paper.toml").unwrap();
    let err = generate(&scene, &text).unwrap_err().to_string();
    assert!(
        err.contains("non-finite") && err.contains("link1.a = 1e308"),
        "{err}"
    );
    let q = [0.1, 0.2, 0.3];
    let err = eval_all(&scene, &q, &[0.0; 3], [0.0; 3], 0.01)
        .unwrap_err()
        .to_string();
    assert!(
        err.contains("not finite") && err.contains("link1.a = 1e308"),
        "{err}"
    );
    // A huge velocity: C q̇ overflows; the quantity is named.
    let scene = Scene::from_toml_str(&paper, "paper.toml").unwrap();
    let err = eval_all(&scene, &q, &[1e200; 3], [0.0; 3], 0.01)
        .unwrap_err()
        .to_string();
    assert!(err.contains("Cqd is not finite"), "{err}");
}
