//! `ball-finger generate SCENE [-o FILE] [--report] [--float f64|f32] [--fma] [--no-std]`: run the code
//! generator (the paper's Maple step, Sect. 5) on any scene file and print or write the Rust
//! module: the kernels of the scene's `kernels` list plus the inverse-dynamics family, the same
//! module `bf-generated` compiles for a scene of `scenes/` (with the default options).
//! `--float f32` emits single-precision kernels, `--fma` fused multiply-adds, `--no-std` a
//! module for a `#![no_std]` crate (own √, sin, cos; no `eval_flat`); every combination but
//! `--fma --no-std` is valid.

use crate::cli::{FloatArg, GenerateArgs};
use crate::io::write_atomic;
use anyhow::{Context, Result};

/// The module `generate` emits for `scene` (source `text`): the scene's `kernels` list plus the
/// inverse-dynamics family ([`bf_codegen::kernels::with_robot_kernels`]). The `paper` report's
/// code-generation table calls this too, so the two list the same kernels.
pub fn generate_module(
    scene: &bf_codegen::Scene,
    text: &str,
    opts: &bf_codegen::EmitSettings,
) -> Result<bf_codegen::Generated, bf_codegen::CodegenError> {
    bf_codegen::generate_with(&bf_codegen::kernels::with_robot_kernels(scene), text, opts)
}

/// Run `generate`.
pub fn run(args: &GenerateArgs) -> Result<()> {
    if let Some(path) = &args.output {
        bf_output::refuse_inputs(path, "-o", &crate::cli::scene_files(&args.scene))?;
    }
    let (scene, text) = super::load_scene(&args.scene, &args.chain)?;
    let opts = bf_codegen::EmitSettings {
        float: match args.float {
            FloatArg::F64 => bf_codegen::FloatTy::F64,
            FloatArg::F32 => bf_codegen::FloatTy::F32,
        },
        fma: args.fma,
        no_std: args.no_std,
    };
    let generated = generate_module(&scene, &text, &opts)
        .with_context(|| format!("{}: code generation failed", args.scene.display()))?;
    match &args.output {
        Some(path) => {
            write_atomic(path, generated.code.as_bytes())?;
            if args.report {
                crate::outln!("{}", generated.report)?;
            }
            crate::errln!("wrote {} ({} bytes)", path.display(), generated.code.len());
        }
        None => {
            crate::io::print_out(&generated.code)?;
            if args.report {
                crate::errln!("{}", generated.report);
            }
        }
    }
    Ok(())
}
