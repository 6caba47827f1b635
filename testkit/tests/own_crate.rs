//! The build-script API end to end: builds `examples/own-crate` (a user's crate, outside the
//! workspace, whose `build.rs` generates the kernels of the URDF it ships through
//! `bf_codegen::Builder`), runs it at random states given as JSON, and compares the M(q),
//! C q̇ + g and q̈ it prints with this kit's spatial-algebra reference on the URDF's tree
//! (CRBA, RNEA, and q̈ solved from them), to 1e-10 relative; and checks that a bad state is
//! refused with a message naming the key and a non-zero exit.
//!
//! The build takes about a minute from scratch (the generator and its syn/prettyplease stack
//! are compiled for the build script of a crate with its own target directory), so the test
//! is ignored by default; run it with
//! `cargo test --release -p bf-testkit --test own_crate -- --ignored`.

use std::path::{Path, PathBuf};
use std::process::Command;

use bf_testkit::urdf_tree::UrdfTree;
use nalgebra::{DMatrix, DVector};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("..")
}

/// Builds the example in `target/own-crate` (its own target directory: the workspace's is
/// locked by the `cargo test` running this) and returns its binary.
fn build() -> PathBuf {
    let target = root().join("target").join("own-crate");
    let cargo = std::env::var("CARGO").unwrap_or_else(|_| "cargo".into());
    let out = Command::new(cargo)
        .args(["build", "--release", "--offline", "--manifest-path"])
        .arg(root().join("examples/own-crate/Cargo.toml"))
        .env("CARGO_TARGET_DIR", &target)
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "building examples/own-crate failed:\n{}",
        String::from_utf8_lossy(&out.stderr)
    );
    target.join("release").join("own-crate")
}

fn run(bin: &Path, state: &str) -> std::process::Output {
    Command::new(bin).arg(state).output().unwrap()
}

fn numbers(v: &serde_json::Value) -> Vec<f64> {
    match v {
        serde_json::Value::Array(a) => a.iter().flat_map(numbers).collect(),
        x => vec![x.as_f64().unwrap()],
    }
}

fn close(what: &str, got: &[f64], want: &[f64]) {
    assert_eq!(got.len(), want.len(), "{what}: lengths");
    let scale = want.iter().fold(1.0f64, |m, x| m.max(x.abs()));
    for (k, (x, y)) in got.iter().zip(want).enumerate() {
        assert!(
            (x - y).abs() <= 1e-10 * scale,
            "{what}[{k}]: {x} vs reference {y}\n{got:?}\n{want:?}"
        );
    }
}

#[test]
#[ignore = "builds a crate from scratch (about a minute); run with --ignored"]
fn own_crate_kernels_match_the_tree_reference() {
    let bin = build();
    let urdf = std::fs::read_to_string(root().join("examples/own-crate/robot.urdf")).unwrap();
    let tree = UrdfTree::parse(&urdf).unwrap();
    let chain = tree.chain("base_link", "ee_link");
    let n = chain.len();
    assert_eq!(n, 6);
    let mut rng = ChaCha8Rng::seed_from_u64(35);
    for k in 0..5 {
        let mut draw = |s: f64| -> Vec<f64> { (0..n).map(|_| rng.random_range(-s..s)).collect() };
        let (q, qd, tau) = (draw(3.0), draw(2.0), draw(20.0));
        let state = serde_json::json!({"q": q, "qd": qd, "tau": tau}).to_string();
        let out = run(&bin, &state);
        assert!(
            out.status.success(),
            "{state}: {}",
            String::from_utf8_lossy(&out.stderr)
        );
        let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
        let m = numbers(&v["mass_cqd_g"]["m"]);
        let bias = numbers(&v["mass_cqd_g"]["cqd_g"]);
        let qdd = numbers(&v["forward_dynamics"]["qdd"]);
        let m_ref: Vec<f64> = tree.crba(&chain, &q).into_iter().flatten().collect();
        let bias_ref = tree.rnea(&chain, &q, &qd, &vec![0.0; n], [0.0, 0.0, -9.81]);
        close(&format!("state {k}: M"), &m, &m_ref);
        close(&format!("state {k}: C qd + g"), &bias, &bias_ref);
        let rhs = DVector::from_iterator(n, tau.iter().zip(&bias_ref).map(|(t, b)| t - b));
        let qdd_ref = DMatrix::from_row_slice(n, n, &m_ref)
            .lu()
            .solve(&rhs)
            .unwrap();
        // τ = M q̈ + C q̇ + g once more through the reference's RNEA: q̈ is the reference's.
        let tau_back = tree.rnea(&chain, &q, &qd, qdd_ref.as_slice(), [0.0, 0.0, -9.81]);
        close(&format!("state {k}: RNEA(qdd_ref)"), &tau_back, &tau);
        close(&format!("state {k}: qdd"), &qdd, qdd_ref.as_slice());
    }
    // A state with the wrong number of joints is refused, naming the key.
    let out = run(&bin, r#"{"q": [0.1, 0.2], "qd": [0, 0, 0, 0, 0, 0]}"#);
    assert_eq!(out.status.code(), Some(1));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("`q` has 2 entries"), "{err}");
    let out = run(&bin, r#"{"q": [0, 0, 0, 0, 0, 0]}"#);
    assert_eq!(out.status.code(), Some(1));
    assert!(String::from_utf8_lossy(&out.stderr).contains("no `qd`"));
}
