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
    assert!(code.contains("sin_cos_f32("));
    // No f64 left outside the embedded scene text and the trig helpers, which compute the
    // sine and cosine of an f32 angle in f64 and round once.
    let file = syn::parse_file(&code).unwrap();
    for item in &file.items {
        let helper =
            matches!(item, syn::Item::Fn(f) if f.sig.ident.to_string().starts_with("sin_cos"));
        let toml = matches!(item, syn::Item::Const(c) if c.ident == "SCENE_TOML");
        if !helper && !toml {
            let text = quote::quote!(#item).to_string();
            assert!(!text.contains("f64"), "f64 left in the f32 variant: {text}");
        }
    }
}

/// `ModuleSplit::Auto` leaves a module of at most `SPLIT_MIN_TEMPORARIES` temporaries whole
/// (so the shipped scenes keep their text) and splits off a larger module's non-inline
/// kernels; the split module holds the same kernel items, each inside `mod kernel_NAME`.
#[test]
fn auto_split_follows_module_size_and_keeps_the_kernel_text() {
    use bf_codegen::ModuleSplit;
    use bf_codegen::emit::{INLINE_MAX_TEMPORARIES, SPLIT_MIN_TEMPORARIES};
    let big = SPLIT_MIN_TEMPORARIES / 2 + 1;
    let small = INLINE_MAX_TEMPORARIES;
    assert_eq!(
        ModuleSplit::Auto.which(&[big, big - 2 - small, small]),
        [false; 3]
    );
    assert_eq!(
        ModuleSplit::Auto.which(&[big, big, small]),
        [true, true, false]
    );
    assert_eq!(ModuleSplit::Large.which(&[small + 1, small]), [true, false]);
    assert_eq!(ModuleSplit::All.which(&[1, 2]), [true, true]);
    assert_eq!(ModuleSplit::Never.which(&[big, big]), [false, false]);

    let (scene, text) = paper();
    let opts = EmitSettings::default();
    let whole = bf_codegen::generate_split(&scene, &text, &opts, ModuleSplit::Auto)
        .unwrap()
        .code;
    assert_eq!(whole, generate(&scene, &text).unwrap().code);
    assert!(!whole.contains("mod kernel_"));
    let split = bf_codegen::generate_split(&scene, &text, &opts, ModuleSplit::All)
        .unwrap()
        .code;
    for k in &scene.kernels {
        assert!(split.contains(&format!("\nmod kernel_{k} {{\n    use super::*;\n")));
        assert!(split.contains(&format!("\npub use kernel_{k}::{k};\n")));
    }
    // Undo the indentation of the submodules' bodies: the kernels' lines are the same.
    let kernel_lines = |code: &str| -> Vec<String> {
        code.lines()
            .filter(|l| l.trim_start().starts_with("let ") || l.contains(" = "))
            .map(|l| l.trim().to_string())
            .collect()
    };
    assert_eq!(kernel_lines(&whole), kernel_lines(&split));
}
