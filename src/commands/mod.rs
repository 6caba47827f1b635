//! Subcommand implementations. Each `run` returns `anyhow::Result`; `main` prints the error
//! chain and exits non-zero.

pub mod bench;
pub mod eval;
pub mod generate;
pub mod optimize;
pub mod paper;
pub mod report;
pub mod requires;
pub mod simulate;
pub mod verify;

use anyhow::Result;

/// Load and validate a scene file; the error names the file, line and field. Every command
/// that reads a scene file goes through here, so each of the scene's accepted-but-doubtful
/// values ([`bf_codegen::Scene::warnings`]) is printed once to stderr, naming the file.
pub fn load_scene(path: &std::path::Path) -> Result<(bf_codegen::Scene, String)> {
    let text = std::fs::read_to_string(path)
        .map_err(|e| anyhow::anyhow!("{}: cannot read scene file: {e}", path.display()))?;
    let scene = bf_codegen::Scene::from_toml_str(&text, &path.display().to_string())?;
    for w in scene.warnings() {
        eprintln!("warning: {}: {w}", path.display());
    }
    Ok((scene, text))
}
