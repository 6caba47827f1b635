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
pub mod track;
pub mod verify;

use anyhow::Result;

/// Load and validate a scene file (TOML, or a `.urdf` with the chain `chain` chooses); the
/// error names the file, line and field (or URDF element and attribute). The text returned is
/// self-contained (a URDF's chain written out as scene links), so what a command records parses
/// again without the URDF. Every command that reads a scene file goes through here, so each of
/// the scene's accepted-but-doubtful values ([`bf_codegen::Scene::warnings`]) is printed once
/// to stderr, naming the file.
pub fn load_scene(
    path: &std::path::Path,
    chain: &crate::cli::ChainArgs,
) -> Result<(bf_codegen::Scene, String)> {
    let (scene, text) = bf_codegen::Scene::load_with_text(path, &chain.choice()).map_err(|e| {
        // A chain choice the scene cannot take is a wrong command line (exit status 2).
        if e.kind() == Some(bf_codegen::spec::SpecErrorKind::ChainChoice) {
            crate::errors::usage(e.to_string())
        } else {
            e.into()
        }
    })?;
    for w in scene.warnings() {
        crate::errln!("warning: {}: {w}", path.display());
    }
    Ok((scene, text))
}

/// A usage error unless `--verify-rtol` is 0 (no re-integration) or a relative tolerance the
/// re-integration can meet: in [`bf_sim::MIN_RTOL`], [`bf_sim::MAX_RTOL`].
pub fn check_verify_rtol(rtol: f64) -> Result<()> {
    let why = match rtol {
        0.0 => None,
        r if !(r.is_finite() && r > 0.0) => Some(format!(
            "must be 0 (skip) or a finite number > 0, got {}",
            crate::cli::shown(r)
        )),
        r => bf_sim::rtol_out_of_range(r).map(|why| format!("must be 0 (skip) or {why}")),
    };
    match why {
        Some(why) => Err(crate::errors::usage(format!("--verify-rtol {why}"))),
        None => Ok(()),
    }
}

/// A usage error naming `option` unless every revolute joint angle of `q` lies within
/// ±[`bf_codegen::trig::ANGLE_RANGE`] rad, where the kernels' sine and cosine are defined
/// (beyond it every kernel output would be NaN).
pub fn check_angles(option: &str, scene: &bf_codegen::Scene, q: &[f64]) -> Result<()> {
    match angle_beyond_range(option, scene, q) {
        Some(why) => Err(crate::errors::usage(why)),
        None => Ok(()),
    }
}

/// Why the first revolute joint angle of `q` beyond ±[`bf_codegen::trig::ANGLE_RANGE`] rad is
/// refused, naming `source` (what gave `q`); `None` if every angle is within it.
pub fn angle_beyond_range(source: &str, scene: &bf_codegen::Scene, q: &[f64]) -> Option<String> {
    let range = bf_codegen::trig::ANGLE_RANGE;
    let (i, v) = scene.angle_beyond_range(q)?;
    Some(format!(
        "{source}: q{} = {} rad is beyond ±2²⁰ = ±{range} rad, where the kernels' sine and \
         cosine are not defined; give the angle modulo 2π",
        i + 1,
        crate::cli::shown(v)
    ))
}

/// Load a scene file (as [`load_scene`]) and set its runtime parameters from `--param
/// name=value` options; the error names the option, the file and the valid names.
pub fn load_scene_with_params(
    path: &std::path::Path,
    chain: &crate::cli::ChainArgs,
    params: &[String],
) -> Result<(bf_codegen::Scene, String)> {
    let (mut scene, text) = load_scene(path, chain)?;
    let assignments = parse_params(params)?;
    bf_model::registry::set_parameters(&mut scene, &assignments)
        .map_err(|e| crate::errors::usage(format!("--param: {}: {e}", path.display())))?;
    Ok((scene, text))
}

/// `--param name=value` options as (name, value); the error names the option. A name given
/// twice is refused rather than the last value silently winning.
pub fn parse_params(params: &[String]) -> Result<Vec<(String, f64)>> {
    let mut out: Vec<(String, f64)> = Vec::with_capacity(params.len());
    for p in params {
        let (name, value) = p
            .split_once('=')
            .ok_or_else(|| crate::errors::usage(format!("--param {p}: expected NAME=VALUE")))?;
        let value: f64 = value.trim().parse().map_err(|_| {
            crate::errors::usage(format!("--param {p}: `{}` is not a number", value.trim()))
        })?;
        let name = name.trim().to_string();
        if let Some((_, first)) = out.iter().find(|(n, _)| *n == name) {
            return Err(crate::errors::usage(format!(
                "--param {p}: `{name}` is already set to {first}; give each parameter once"
            )));
        }
        out.push((name, value));
    }
    Ok(out)
}
