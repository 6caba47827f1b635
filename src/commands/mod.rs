//! Subcommand implementations. Each `run` returns `anyhow::Result`; `main` prints the error
//! chain and exits non-zero.

pub mod eval;
pub mod generate;
pub mod openloop;
pub mod optimize;
pub mod paper;
pub mod report;
pub mod requires;
pub mod scenarios;
pub mod simulate;
pub mod verify;

use anyhow::{Result, bail};

/// The answer of a subcommand that later issues deliver: a clear error, never fake output.
pub fn not_yet(command: &str, issue: u32) -> Result<()> {
    bail!(
        "`{command}` is not implemented yet (tracked in issue {issue}); \
         see README.md \"Status\" for what works today"
    )
}

/// Load and validate a scene file; the error names the file, line and field.
pub fn load_scene(path: &std::path::Path) -> Result<(bf_codegen::Scene, String)> {
    let text = std::fs::read_to_string(path)
        .map_err(|e| anyhow::anyhow!("{}: cannot read scene file: {e}", path.display()))?;
    let scene = bf_codegen::Scene::from_toml_str(&text, &path.display().to_string())?;
    Ok((scene, text))
}
