//! `ball-finger generate SCENE [-o FILE] [--report]`: run the code generator (the paper's Maple
//! step, Sect. 5) on any scene file and print or write the Rust module.

use crate::cli::GenerateArgs;
use crate::io::write_atomic;
use anyhow::{Context, Result};

/// Run `generate`.
pub fn run(args: &GenerateArgs) -> Result<()> {
    let (scene, text) = super::load_scene(&args.scene)?;
    let generated = bf_codegen::generate(&scene, &text)
        .with_context(|| format!("{}: code generation failed", args.scene.display()))?;
    match &args.output {
        Some(path) => {
            write_atomic(path, generated.code.as_bytes())?;
            if args.report {
                crate::outln!("{}", generated.report)?;
            }
            eprintln!("wrote {} ({} bytes)", path.display(), generated.code.len());
        }
        None => {
            crate::io::print_out(&generated.code)?;
            if args.report {
                eprintln!("{}", generated.report);
            }
        }
    }
    Ok(())
}
