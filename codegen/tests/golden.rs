//! Golden file and determinism of the emitter, plus the golden file compiled and checked
//! against the textbook closed forms of a planar two-link arm (M, C q̇, g, J).
//!
//! Refresh the golden file with `BF_OVERWRITE_GOLDEN=1 cargo test --release -p bf-codegen
//! --test golden` after an intended change of the emitted code.

#[allow(clippy::all, clippy::pedantic, missing_docs, dead_code)]
mod planar2 {
    include!("golden/planar2.rs");
}

#[allow(clippy::all, clippy::pedantic, missing_docs, dead_code)]
mod planar2_f32_fma {
    include!("golden/planar2_f32_fma.rs");
}

use bf_codegen::{EmitSettings, FloatTy, Scene, generate, generate_with};

/// The options of the single-precision golden variant.
const F32_FMA: EmitSettings = EmitSettings {
    float: FloatTy::F32,
    fma: true,
    no_std: false,
};

const DIR: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/tests/golden");

fn planar2_scene() -> (Scene, String) {
    let path = format!("{DIR}/planar2.toml");
    let text = std::fs::read_to_string(&path).unwrap();
    (Scene::from_toml_str(&text, &path).unwrap(), text)
}

#[test]
fn golden_file_is_current() {
    let (scene, text) = planar2_scene();
    let code = generate(&scene, &text).unwrap().code;
    let path = format!("{DIR}/planar2.rs");
    if std::env::var("BF_OVERWRITE_GOLDEN").as_deref() == Ok("1") {
        std::fs::write(&path, &code).unwrap();
        return;
    }
    let golden = std::fs::read_to_string(&path).unwrap();
    assert!(
        golden == code,
        "emitted code differs from {path}; if intended, rerun with BF_OVERWRITE_GOLDEN=1"
    );
}

#[test]
fn f32_fma_golden_file_is_current() {
    let (scene, text) = planar2_scene();
    let code = generate_with(&scene, &text, &F32_FMA).unwrap().code;
    let path = format!("{DIR}/planar2_f32_fma.rs");
    if std::env::var("BF_OVERWRITE_GOLDEN").as_deref() == Ok("1") {
        std::fs::write(&path, &code).unwrap();
        return;
    }
    let golden = std::fs::read_to_string(&path).unwrap();
    assert!(
        golden == code,
        "emitted code differs from {path}; if intended, rerun with BF_OVERWRITE_GOLDEN=1"
    );
}

/// The f32/FMA variant agrees with the f64 kernels to single precision, kernel by kernel
/// (every output of every kernel through the two modules' `eval_flat_u`), and the
/// allocation-free `eval_index_into` returns exactly what `eval_flat_u` does.
#[test]
fn f32_fma_variant_agrees_with_f64_and_dispatchers_agree() {
    assert_eq!(planar2::KERNELS, planar2_f32_fma::KERNELS);
    for j in 0..20 {
        let t = j as f64;
        let q = [libm::sin(1.3 * t) * 3.0, libm::cos(0.7 * t + 0.2) * 3.0];
        let qd = [libm::cos(2.1 * t) * 2.0, libm::sin(0.3 * t) * 2.0];
        let u = [libm::cos(0.9 * t) * 4.0, libm::sin(1.7 * t) * 4.0];
        let p = planar2::PARAM_DEFAULTS;
        let f = |v: [f64; 2]| v.map(|x| x as f32);
        for (k, name) in planar2::KERNELS.iter().enumerate() {
            let a = planar2::eval_flat_u(name, &q, &qd, &[0.0; 3], 0.01, &u, &p).unwrap();
            let b = planar2_f32_fma::eval_flat_u(
                name,
                &f(q),
                &f(qd),
                &[0.0; 3],
                0.01,
                &f(u),
                &planar2_f32_fma::PARAM_DEFAULTS,
            )
            .unwrap();
            assert_eq!(a.len(), b.len(), "{name}");
            let scale = a.iter().fold(1.0f64, |m, x| m.max(x.abs()));
            for (i, (x, y)) in a.iter().zip(&b).enumerate() {
                assert!(
                    (x - *y as f64).abs() <= 2e-5 * scale,
                    "{name}[{i}]: f64 {x} vs f32 {y}"
                );
            }
            let mut out = vec![f64::NAN; a.len() + 3];
            let n = planar2::eval_index_into(k, &q, &qd, &[0.0; 3], 0.01, &u, &p, &mut out);
            assert_eq!(n, Some(a.len()), "{name}");
            assert_eq!(&out[..a.len()], &a[..], "{name}: eval_index_into");
            let short = &mut out[..a.len() - 1];
            assert_eq!(
                planar2::eval_index_into(k, &q, &qd, &[0.0; 3], 0.01, &u, &p, short),
                None
            );
        }
    }
}

#[test]
fn generation_is_deterministic() {
    for name in ["paper", "human", "puma560", "iiwa7"] {
        let path = format!("{}/../scenes/{name}.toml", env!("CARGO_MANIFEST_DIR"));
        let text = std::fs::read_to_string(&path).unwrap();
        let scene = Scene::from_toml_str(&text, &path).unwrap();
        let a = generate(&scene, &text).unwrap();
        // A second run in another thread (fresh hash seeds for every HashMap).
        let (s2, t2) = (scene.clone(), text.clone());
        let b = std::thread::spawn(move || generate(&s2, &t2).unwrap())
            .join()
            .unwrap();
        assert!(a.code == b.code, "{name}: output differs between runs");
        assert_eq!(a.report.kernels, b.report.kernels);
        assert!(a.code.starts_with("// @generated"));
    }
}

#[test]
fn planar_arm_matches_textbook_closed_forms() {
    let (l1, l2, lc1, lc2) = (1.0, 0.8, 0.45, 0.3);
    let (i1, i2, m1) = (0.1, 0.05, 1.2);
    let g0 = 9.81;
    for (k, m2) in [0.7, 1.9, 1e-3].into_iter().enumerate() {
        let p = [m2];
        for j in 0..20 {
            let t = (k * 20 + j) as f64;
            let q = [libm::sin(1.3 * t) * 3.0, libm::cos(0.7 * t + 0.2) * 3.0];
            let qd = [libm::cos(2.1 * t) * 2.0, libm::sin(0.3 * t) * 2.0];
            let (s2, c2) = libm::sincos(q[1]);
            let c1 = libm::cos(q[0]);
            let c12 = libm::cos(q[0] + q[1]);
            let mm = [
                [
                    m1 * lc1 * lc1 + i1 + m2 * (l1 * l1 + lc2 * lc2 + 2.0 * l1 * lc2 * c2) + i2,
                    m2 * (lc2 * lc2 + l1 * lc2 * c2) + i2,
                ],
                [m2 * (lc2 * lc2 + l1 * lc2 * c2) + i2, m2 * lc2 * lc2 + i2],
            ];
            let h = m2 * l1 * lc2 * s2;
            let cqd = [
                -h * (2.0 * qd[0] * qd[1] + qd[1] * qd[1]),
                h * qd[0] * qd[0],
            ];
            let g = [
                (m1 * lc1 + m2 * l1) * g0 * c1 + m2 * lc2 * g0 * c12,
                m2 * lc2 * g0 * c12,
            ];
            let mut m = [[0.0; 2]; 2];
            let mut v = [0.0; 2];
            planar2::mass_cqd_g(&q, &qd, &p, &mut m, &mut v);
            let mut gv = [0.0; 2];
            planar2::gravity(&q, &p, &mut gv);
            let mut cv = [0.0; 2];
            planar2::coriolis_qd(&q, &qd, &p, &mut cv);
            let mut lag = [0.0; 2];
            planar2::cqd_g(&q, &qd, &p, &mut lag);
            for a in 0..2 {
                for b in 0..2 {
                    assert!((m[a][b] - mm[a][b]).abs() < 1e-13, "M[{a}][{b}]");
                }
                assert!((gv[a] - g[a]).abs() < 1e-12, "g[{a}]");
                assert!((cv[a] - cqd[a]).abs() < 1e-12, "C qd[{a}]");
                assert!((v[a] - cqd[a] - g[a]).abs() < 1e-12, "RNEA C qd + g[{a}]");
                assert!(
                    (lag[a] - cqd[a] - g[a]).abs() < 1e-12,
                    "Lagrangian C qd + g[{a}]"
                );
            }
            // The emitted inverse dynamics τ = M q̈ + C q̇ + g, its round trip through the
            // emitted forward dynamics, and Y π = τ with π from the closed-form parameters.
            let qdd = [libm::cos(0.9 * t) * 4.0, libm::sin(1.7 * t) * 4.0];
            let tau_cf: Vec<f64> = (0..2)
                .map(|a| mm[a][0] * qdd[0] + mm[a][1] * qdd[1] + cqd[a] + g[a])
                .collect();
            let mut tau = [0.0; 2];
            planar2::inverse_dynamics(&q, &qd, &qdd, &p, &mut tau);
            let mut back = [0.0; 2];
            planar2::forward_dynamics(&q, &qd, &tau, &p, &mut back);
            let mut y = [[[0.0; 10]; 2]; 2];
            planar2::regressor(&q, &qd, &qdd, &p, &mut y);
            // π per link: m, m c (c = (lc − l, 0, 0) in the link frame), I_o about the origin.
            let pis = [(m1, lc1 - l1, i1), (m2, lc2 - l2, i2)].map(|(m, cx, izz)| {
                [
                    m,
                    m * cx,
                    0.0,
                    0.0,
                    0.0,
                    0.0,
                    0.0,
                    0.0,
                    0.0,
                    izz + m * cx * cx,
                ]
            });
            for a in 0..2 {
                let scale = 1.0 + tau_cf[a].abs();
                assert!((tau[a] - tau_cf[a]).abs() < 1e-12 * scale, "τ[{a}]");
                assert!(
                    (back[a] - qdd[a]).abs() < 1e-12 * (1.0 + qdd[a].abs()),
                    "q̈[{a}]"
                );
                let ypi: f64 = (0..2)
                    .map(|l| (0..10).map(|c| y[a][l][c] * pis[l][c]).sum::<f64>())
                    .sum();
                assert!((ypi - tau_cf[a]).abs() < 1e-12 * scale, "Y π[{a}]");
            }
            // Tip Jacobian of the planar arm.
            let s1 = libm::sin(q[0]);
            let s12 = libm::sin(q[0] + q[1]);
            let mut jp = [[0.0; 2]; 3];
            let mut jo = [[0.0; 2]; 3];
            planar2::tip_jacobian(&q, &p, &mut jp, &mut jo);
            let want = [
                [-l1 * s1 - l2 * s12, -l2 * s12],
                [l1 * c1 + l2 * c12, l2 * c12],
            ];
            for a in 0..2 {
                for b in 0..2 {
                    assert!((jp[a][b] - want[a][b]).abs() < 1e-14);
                }
            }
            assert_eq!(jo, [[0.0, 0.0], [0.0, 0.0], [1.0, 1.0]]);
            assert_eq!(jp[2], [0.0, 0.0]);
        }
    }
    assert_eq!(planar2::NQ, 2);
    assert_eq!(planar2::PARAM_NAMES, ["link2.mass"]);
    assert_eq!(planar2::PARAM_DEFAULTS, [0.7]);
}

/// The kernels' bodies are printed as text, not formatted: the code of every scene (and of
/// the f32 and fused multiply-add variants) must still be exactly what `prettyplease` prints
/// for it, so that the emitted text reads as formatted Rust and stays deterministic.
#[test]
fn every_scene_is_formatted_as_prettyplease_formats_it() {
    let dir = concat!(env!("CARGO_MANIFEST_DIR"), "/../scenes");
    let mut paths: Vec<_> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "toml"))
        .collect();
    paths.push(format!("{DIR}/planar2.toml").into());
    assert!(paths.len() > 3, "scenes found: {paths:?}");
    for path in paths {
        let text = std::fs::read_to_string(&path).unwrap();
        let scene = Scene::from_toml_str(&text, path.to_str().unwrap()).unwrap();
        for opts in [
            EmitSettings::default(),
            F32_FMA,
            EmitSettings {
                float: FloatTy::F64,
                fma: true,
                no_std: false,
            },
        ] {
            let code = generate_with(&scene, &text, &opts).unwrap().code;
            // The header comments (which syn drops) end at the first item.
            let at = code.find("\n/// Number of joints.").unwrap() + 1;
            let file = syn::parse_file(&code).unwrap();
            let formatted = prettyplease::unparse(&file);
            assert!(
                formatted == code[at..],
                "{}, {opts:?}: emitted code is not what prettyplease prints",
                path.display()
            );
        }
    }
}
