//! Generates, through bf-codegen's build-script API (`Builder`, docs/your-robot.md section 9),
//! the compiled kernels of the own-crate example's URDF (`examples/own-crate/robot.urdf`, a
//! UR5-like arm) with the example's own settings, into `$OUT_DIR/ur5.rs`, for the criterion
//! bench `benches/own_crate_kernels.rs`: so the example's compiled ns per call is measured by
//! criterion, next to the interpreter on the same URDF, without building the example crate.

use std::path::PathBuf;

fn main() {
    let manifest = PathBuf::from(
        std::env::var("CARGO_MANIFEST_DIR").expect("cargo sets CARGO_MANIFEST_DIR for builds"),
    );
    let out = std::env::var("OUT_DIR").expect("cargo sets OUT_DIR for build scripts");
    println!("cargo::rerun-if-changed=build.rs");
    bf_codegen::Builder::new(manifest.join("../examples/own-crate/robot.urdf"))
        .base("base_link")
        .tip("ee_link")
        .kernels(["mass_cqd_g", "forward_dynamics"])
        .file_name("ur5.rs")
        .emit_to(&out)
        .unwrap_or_else(|e| panic!("{e}"));
}
