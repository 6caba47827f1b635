//! The scene a `ball-finger simulate` run uses: `--scene` (with `--param`), else the scene
//! recorded in the `--init` solution, else `scenes/paper.toml` (or, outside the repository,
//! the compiled paper scene).

use crate::cli::SimulateArgs;
use anyhow::{Context, Result, anyhow, bail};

/// The scene of the run and how to name it in messages: `--scene` (with `--param`); without
/// it, the scene recorded in the `--init` solution (its stored scene text with its runtime
/// parameters, or, in files that store none, the compiled scene it names), else
/// scenes/paper.toml.
pub fn scene_of_args(args: &SimulateArgs) -> Result<(bf_codegen::Scene, String)> {
    if let Some(path) = &args.scene {
        let (scene, _) = crate::commands::load_scene_with_params(path, &args.chain, &args.param)?;
        return Ok((scene, path.display().to_string()));
    }
    if let Some(init) = &args.init {
        let text = bf_codegen::spec::read_input_text(init)
            .with_context(|| format!("{}: cannot read initial-state file", init.display()))?;
        let v: serde_json::Value = crate::io::json_value(&text)
            .with_context(|| format!("{}: initial-state file is not valid JSON", init.display()))?;
        let label = format!("the scene recorded in {}", init.display());
        let mut scene = if let Some(toml) = v
            .get("scene_toml")
            .and_then(|t| t.as_str())
            .filter(|t| !t.is_empty())
        {
            let name = v.get("scene").and_then(|n| n.as_str()).unwrap_or("scene");
            let mut scene = bf_codegen::Scene::from_toml_str(toml, &label)?;
            let stored: Vec<(String, f64)> = v
                .get("scene_params")
                .cloned()
                .map(serde_json::from_value)
                .transpose()
                .with_context(|| format!("{}: `scene_params`", init.display()))?
                .unwrap_or_default();
            bf_model::registry::set_parameters(&mut scene, &stored)
                .map_err(|e| anyhow!("{label} (`{name}`): {e}"))?;
            scene
        } else if let Some(name) = v.get("scene").and_then(|n| n.as_str()) {
            if v.get("kernels").and_then(|k| k.as_str()) == Some("interpreted") {
                bail!(
                    "{}: the solution was posed on a scene file of its own (`{name}`, \
                     interpreted kernels) that it does not store; give it with --scene",
                    init.display()
                );
            }
            let toml = bf_generated::scene_toml(name).ok_or_else(|| {
                anyhow!(
                    "{}: the solution's scene `{name}` is not a compiled scene; give it with \
                     --scene",
                    init.display()
                )
            })?;
            bf_codegen::Scene::from_toml_str(toml, name)?
        } else {
            return default_scene(args);
        };
        let assignments = crate::commands::parse_params(&args.param)?;
        bf_model::registry::set_parameters(&mut scene, &assignments)
            .map_err(|e| crate::errors::usage(format!("--param: {label}: {e}")))?;
        return Ok((scene, label));
    }
    default_scene(args)
}

fn default_scene(args: &SimulateArgs) -> Result<(bf_codegen::Scene, String)> {
    let path = std::path::Path::new("scenes/paper.toml");
    if path.exists() {
        let (scene, _) = crate::commands::load_scene_with_params(path, &args.chain, &args.param)?;
        return Ok((scene, path.display().to_string()));
    }
    // Outside the repository: the compiled paper scene.
    let toml = bf_generated::scene_toml("paper")
        .ok_or_else(|| anyhow!("no --scene given and no compiled `paper` scene"))?;
    let mut scene = bf_codegen::Scene::from_toml_str(toml, "paper")?;
    let assignments = crate::commands::parse_params(&args.param)?;
    bf_model::registry::set_parameters(&mut scene, &assignments)
        .map_err(|e| crate::errors::usage(format!("--param: the compiled paper scene: {e}")))?;
    Ok((scene, "the compiled paper scene".into()))
}
