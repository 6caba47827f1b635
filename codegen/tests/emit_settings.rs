//! Emission variants (speed–accuracy report): the default settings reproduce
//! `generate` byte for byte, FMA fuses products into `mul_add`, f32 changes every type.
//! Numerical accuracy of the variants is measured against double-double in the root
//! package's `tests/speed_accuracy.rs` (compiled variant modules of `bf-generated`).

use bf_codegen::{EmitSettings, FloatTy, Scene, generate, generate_with};

fn paper() -> (Scene, String) {
    let path = format!("{}/../scenes/paper.toml", env!("CARGO_MANIFEST_DIR"));
    let text = std::fs::read_to_string(&path).unwrap();
    let mut scene = Scene::from_toml_str(&text, &path).unwrap();
    scene.kernels = vec!["mass_matrix".into(), "cqd_g".into()];
    (scene, text)
}

#[test]
fn default_settings_are_the_standard_output() {
    let (scene, text) = paper();
    let a = generate(&scene, &text).unwrap().code;
    let b = generate_with(&scene, &text, &EmitSettings::default())
        .unwrap()
        .code;
    assert_eq!(a, b);
    assert!(!a.contains("mul_add") && !a.contains("f32"));
}

#[test]
fn fma_fuses_products_and_keeps_the_operation_count() {
    let (scene, text) = paper();
    let plain = generate(&scene, &text).unwrap();
    let opts = EmitSettings {
        float: FloatTy::F64,
        fma: true,
        no_std: false,
    };
    let fused = generate_with(&scene, &text, &opts).unwrap();
    let n_fused = fused.code.matches("f64::mul_add(").count();
    // M and C q̇ + g are sums of products: many additions must have been fused.
    assert!(n_fused > 10, "{n_fused} mul_add");
    assert_eq!(
        plain.report.kernels, fused.report.kernels,
        "same graph, same op counts"
    );
    assert!(!fused.code.contains("f32"));
}

#[test]
fn f32_changes_every_float_type() {
    let (scene, text) = paper();
    let opts = EmitSettings {
        float: FloatTy::F32,
        fma: false,
        no_std: false,
    };
    let code = generate_with(&scene, &text, &opts).unwrap().code;
    assert!(code.contains("pub fn mass_matrix(q: &[f32; NQ]"), "{code}");
    assert!(code.contains("f32::sin_cos("));
    // No f64 left outside the embedded scene text (which is an `r#"..."#`/escaped string).
    let without_toml: String = code
        .lines()
        .filter(|l| !l.contains("SCENE_TOML"))
        .collect::<Vec<_>>()
        .join("\n");
    assert!(!without_toml.contains("f64"), "f64 left in the f32 variant");
}
