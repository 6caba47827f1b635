//! A result does not depend on the machine's CPU. glibc's libm picks, at load time, the variant
//! of `sin`, `cos`, `exp`, `log`, `pow`, … that the CPU supports best (with FMA or without), and
//! the variants differ in the last bit for some arguments; a solve that called them took 307
//! iterations on one variant and 180 on another from the same start, and three tests of the
//! suite failed with the non-FMA variant. Every transcendental function of the workspace is now
//! the pure-Rust `libm` crate's, or the emitted kernels' own sine and cosine
//! (`bf_codegen::trig`), and clippy.toml forbids the standard library's
//! (docs/decisions/0045-one-libm-on-every-machine.md).
//!
//! The check runs the same commands with glibc's CPU dispatch as the machine offers it and with
//! AVX2 and FMA hidden (`GLIBC_TUNABLES=glibc.cpu.hwcaps=-AVX2,-FMA`, the variant an older CPU
//! gets) and asserts bit-identical results. On a platform whose libc ignores the variable both
//! runs are the same run, and the test asserts nothing it could fail.

#[path = "common/cli.rs"]
mod cli;

use cli::{bin, root, tmpdir};

/// The hardware capabilities glibc may use, as the machine offers them and with AVX2 and FMA
/// masked.
const CPUS: [&str; 2] = ["", "glibc.cpu.hwcaps=-AVX2,-FMA"];

/// Runs `args` (output into `dir/out-<k>`) under each of [`CPUS`]; the output directories.
fn run_on_each_cpu(dir: &std::path::Path, args: &[&str]) -> Vec<std::path::PathBuf> {
    CPUS.iter()
        .enumerate()
        .map(|(k, tunables)| {
            let out = dir.join(format!("out-{k}"));
            let o = bin()
                .current_dir(root())
                .env("GLIBC_TUNABLES", tunables)
                .args(args)
                .arg("--out")
                .arg(&out)
                .output()
                .expect("binary runs");
            // Exit status 1 (an unverified optimum) still writes the output set.
            assert!(
                matches!(o.status.code(), Some(0 | 1)),
                "{args:?} with GLIBC_TUNABLES={tunables}: {}",
                String::from_utf8_lossy(&o.stderr)
            );
            out
        })
        .collect()
}

/// The fields of solution.json that a path decides: objective, iterations, period, the
/// re-integration defect (the verification's DOPRI5 run) and the stage records.
fn path_fields(dir: &std::path::Path) -> Vec<String> {
    let text = std::fs::read_to_string(dir.join("solution.json")).unwrap();
    let v: serde_json::Value = serde_json::from_str(&text).unwrap();
    [
        "objective",
        "iterations",
        "period",
        "phase_durations",
        "stages",
    ]
    .iter()
    .map(|k| v[k].to_string())
    .chain([v["verification"]["max_defect"].to_string()])
    .collect()
}

/// A cold direct solve of the paper's COT problem (codegen kernels, the interior-point
/// solver's barrier and line search, the verification's integrator) gives the same torques,
/// bit for bit, and the same path on both variants.
#[test]
fn a_solve_is_the_same_on_every_libm_variant() {
    let dir = tmpdir("cpus");
    let args = [
        "optimize",
        "--problem",
        "periodic-cot",
        "--impact-law",
        "stick",
        "--strategy",
        "direct",
    ];
    let outs = run_on_each_cpu(&dir, &args);
    let torques: Vec<Vec<u8>> = outs
        .iter()
        .map(|o| std::fs::read(o.join("torques.csv")).unwrap())
        .collect();
    assert!(torques[0] == torques[1], "torques.csv differs between CPUs");
    assert_eq!(path_fields(&outs[0]), path_fields(&outs[1]));
    std::fs::remove_dir_all(&dir).ok();
}
