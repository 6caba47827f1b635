//! Generates the compiled kernels of `robot.urdf` (a UR5-like 6R arm) into `OUT_DIR/ur5.rs`.

fn main() {
    let out = std::env::var("OUT_DIR").expect("cargo sets OUT_DIR for build scripts");
    let emitted = bf_codegen::Builder::new("robot.urdf")
        .base("base_link")
        .tip("ee_link")
        .kernels(["mass_cqd_g", "forward_dynamics"])
        .file_name("ur5.rs")
        .emit_to(&out)
        .unwrap_or_else(|e| panic!("{e}"));
    // Shown by `cargo build -vv`: the kernels' operation counts.
    for k in &emitted.report.kernels {
        println!("# {}: {} operations", k.name, k.ops.total());
    }
}
