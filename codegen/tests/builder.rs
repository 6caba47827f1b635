//! The build-script API (`bf_codegen::Builder`): with a scene's own kernel list it writes the
//! golden file byte for byte; by default it adds the inverse-dynamics family as `generate`
//! does; it imports a TOML scene's URDF and reports both files for `rerun-if-changed`; a large
//! robot's module comes split into a submodule per big kernel, as `generate` splits it; and
//! each bad setting or input is a typed error naming the file and the cause.

#[path = "../../tests/common/tempdir.rs"]
mod tempdir;
use tempdir::TempDir;

use std::path::PathBuf;

#[path = "common/chain.rs"]
mod chain;

use bf_codegen::{BuildError, Builder, CodegenError, Scene};

const GOLDEN: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/tests/golden");

fn out_dir(name: &str) -> TempDir {
    TempDir::fresh(
        std::env::temp_dir().join(format!("bf-codegen-builder-{}-{name}", std::process::id())),
    )
}

#[test]
fn scene_kernel_list_reproduces_the_golden_file() {
    let toml = format!("{GOLDEN}/planar2.toml");
    let scene = Scene::load(&toml).unwrap();
    let dir = out_dir("golden");
    let emitted = Builder::new(&toml)
        .kernels(scene.kernels.clone())
        .cargo_metadata(false)
        .emit_to(&dir)
        .unwrap();
    assert_eq!(emitted.path, dir.join("planar2.rs"));
    assert_eq!(emitted.inputs, vec![PathBuf::from(&toml)]);
    let got = std::fs::read_to_string(&emitted.path).unwrap();
    let golden = std::fs::read_to_string(format!("{GOLDEN}/planar2.rs")).unwrap();
    assert!(
        got == golden,
        "Builder output differs from tests/golden/planar2.rs"
    );
    // Emitting again leaves the identical file (and its text) in place.
    Builder::new(&toml)
        .kernels(scene.kernels)
        .cargo_metadata(false)
        .emit_to(&dir)
        .unwrap();
    assert!(std::fs::read_to_string(&emitted.path).unwrap() == golden);
    std::fs::remove_dir_all(dir).unwrap();
}

#[test]
fn default_kernels_add_the_inverse_dynamics_family() {
    let toml = format!("{GOLDEN}/planar2.toml");
    let g = Builder::new(&toml).generate().unwrap();
    let names: Vec<&str> = g.report.kernels.iter().map(|k| k.name.as_str()).collect();
    let scene = Scene::load(&toml).unwrap();
    let mut want: Vec<&str> = scene.kernels.iter().map(String::as_str).collect();
    for k in bf_codegen::kernels::ROBOT_KERNELS {
        if !want.contains(k) {
            want.push(k);
        }
    }
    assert_eq!(names, want);
}

#[test]
fn toml_scene_with_urdf_lists_both_inputs() {
    let dir = concat!(env!("CARGO_MANIFEST_DIR"), "/../testkit/tests/urdf");
    let toml = PathBuf::from(format!("{dir}/finger3_ball.toml"));
    let out = out_dir("urdf");
    let emitted = Builder::new(&toml)
        .kernels(["mass_cqd_g", "contact"])
        .file_name("finger.rs")
        .cargo_metadata(false)
        .emit_to(&out)
        .unwrap();
    assert_eq!(
        emitted.inputs,
        vec![toml.clone(), PathBuf::from(dir).join("finger3.urdf")]
    );
    assert_eq!(emitted.report.nq, 3);
    let code = std::fs::read_to_string(out.join("finger.rs")).unwrap();
    assert!(code.contains("pub const NQ: usize = 3;"));
    assert!(code.contains("pub fn contact("));
    std::fs::remove_dir_all(out).unwrap();
}

#[test]
fn bad_settings_and_inputs_are_typed_errors_naming_the_file() {
    let toml = format!("{GOLDEN}/planar2.toml");
    let e = Builder::new(&toml)
        .kernels(["mass"])
        .generate()
        .unwrap_err();
    assert!(
        matches!(
            e,
            BuildError::Codegen {
                source: CodegenError::Scene(_),
                ..
            }
        ),
        "{e:?}"
    );
    let msg = e.to_string();
    assert!(
        msg.contains("planar2.toml") && msg.contains("unknown kernel `mass`"),
        "{msg}"
    );

    let e = Builder::new(&toml)
        .kernels(Vec::<String>::new())
        .generate()
        .unwrap_err();
    assert!(matches!(e, BuildError::Setting { .. }), "{e:?}");
    assert!(e.to_string().contains("kernel list is empty"));

    let e = Builder::new(&toml)
        .fma(true)
        .no_std(true)
        .generate()
        .unwrap_err();
    assert!(
        matches!(
            e,
            BuildError::Codegen {
                source: CodegenError::Settings(_),
                ..
            }
        ),
        "{e:?}"
    );

    let e = Builder::new(&toml)
        .file_name("../escape.rs")
        .cargo_metadata(false)
        .emit_to(std::env::temp_dir())
        .unwrap_err();
    assert!(e.to_string().contains("\"../escape.rs\""), "{e}");

    let missing = format!("{GOLDEN}/no_such_robot.urdf");
    let e = Builder::new(&missing).generate().unwrap_err();
    assert!(matches!(e, BuildError::Scene(_)), "{e:?}");
    assert!(e.to_string().contains("no_such_robot.urdf"), "{e}");

    let urdf = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../testkit/tests/urdf/ur5_like.urdf"
    );
    let e = Builder::new(urdf).tip("no_link").generate().unwrap_err();
    assert!(e.to_string().contains("no_link"), "{e}");
}

/// A 20-joint chain (its module has more than `SPLIT_MIN_TEMPORARIES` temporaries): the
/// Builder's module is `generate`'s, with every kernel of more than
/// `INLINE_MAX_TEMPORARIES` temporaries, and only those, in a submodule of its own.
#[test]
fn a_large_robot_comes_split_per_kernel() {
    use bf_codegen::emit::INLINE_MAX_TEMPORARIES;
    let kernels = ["gravity", "mass_matrix", "mass_cqd_g", "forward_dynamics"];
    let text = chain::chain_scene(20, &kernels);
    let dir = out_dir("split");
    let path = dir.join("chain20.toml");
    std::fs::write(&path, &text).unwrap();
    let built = Builder::new(&path)
        .kernels(kernels)
        .cargo_metadata(false)
        .generate()
        .unwrap();
    let scene = Scene::from_toml_str(&text, &path.display().to_string()).unwrap();
    let direct = bf_codegen::generate(&scene, &text).unwrap();
    assert_eq!(built.code, direct.code);
    let mut split = 0;
    for k in &built.report.kernels {
        let own = built.code.contains(&format!("\nmod kernel_{} {{", k.name));
        assert_eq!(
            own,
            k.ops.temporaries > INLINE_MAX_TEMPORARIES,
            "{}",
            k.name
        );
        split += usize::from(own);
    }
    assert_eq!(split, 3, "all but gravity");
    std::fs::remove_dir_all(&dir).ok();
}

/// A robot whose kernels need more graph nodes than the builder allows ends with an error that
/// names the file and the kernel, and writes nothing; with room it is `generate`'s module.
#[test]
fn a_robot_past_the_node_limit_is_refused_by_name() {
    let kernels = ["gravity", "christoffel"];
    let text = chain::chain_scene(8, &kernels);
    let dir = out_dir("limit");
    let path = dir.join("chain8.toml");
    std::fs::write(&path, &text).unwrap();
    let builder = Builder::new(&path).kernels(kernels).cargo_metadata(false);
    let full = builder.generate().unwrap();
    let nodes = full.report.graph_nodes;
    let fits = builder.clone().max_graph_nodes(nodes).generate().unwrap();
    assert_eq!(fits.code, full.code);
    let out = dir.join("out");
    std::fs::create_dir_all(&out).unwrap();
    let e = builder
        .max_graph_nodes(nodes / 2)
        .emit_to(&out)
        .unwrap_err();
    let BuildError::Codegen {
        file,
        source: CodegenError::TooLarge(t),
    } = &e
    else {
        panic!("{e}");
    };
    assert!(file.ends_with("chain8.toml"), "{file}");
    assert_eq!(
        (t.what.as_str(), t.limit),
        ("kernel `christoffel`", nodes / 2)
    );
    assert!(e.to_string().contains("max_graph_nodes"), "{e}");
    assert_eq!(std::fs::read_dir(&out).unwrap().count(), 0);
    std::fs::remove_dir_all(&dir).ok();
}
