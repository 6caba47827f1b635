//! "Model only what a scene requires": the generator prunes the expression graph to the kernels
//! a scene lists, and a scene whose contact can only happen at the fingertip (`kind = "tip"`,
//! sat(α) ≡ 0 in eq. 3) gets no line-contact saturation at all. This module measures that on
//! variants of the paper scene, generated in-process (op counts from the emitted code).

use anyhow::Result;
use bf_codegen::Scene;
use std::fmt::Write as _;

/// One variant: what it is for, its scene, and the generator's report.
#[derive(Debug, Clone)]
pub struct Variant {
    /// Label.
    pub label: String,
    /// Kernels emitted.
    pub kernels: Vec<String>,
    /// Total operations over the kernels.
    pub ops: usize,
    /// min/max/abs/select operations (the exact saturation of eq. 3/58).
    pub saturation_ops: usize,
    /// Square roots (the smooth saturation of eq. 59 adds two per kernel; |r_c| needs one).
    pub sqrt_ops: usize,
    /// Bytes of generated code.
    pub code_bytes: usize,
    /// Generation time (s).
    pub seconds: f64,
}

fn variant(label: &str, base: &Scene, kernels: &[&str], tip: bool) -> Result<Variant> {
    let mut scene = base.clone();
    scene.kernels = kernels.iter().map(|s| s.to_string()).collect();
    if tip && let Some(c) = scene.contact.as_mut() {
        c.kind = "tip".into();
    }
    let g = bf_codegen::generate(&scene, bf_generated::paper::SCENE_TOML)?;
    Ok(Variant {
        label: label.into(),
        kernels: scene.kernels.clone(),
        ops: g.report.kernels.iter().map(|k| k.ops.total()).sum(),
        saturation_ops: g.report.kernels.iter().map(|k| k.ops.other).sum(),
        sqrt_ops: g.report.kernels.iter().map(|k| k.ops.sqrt).sum(),
        code_bytes: g.code.len(),
        seconds: g.report.seconds,
    })
}

/// Generate the variants of the paper scene.
pub fn variants() -> Result<Vec<Variant>> {
    let base = Scene::from_toml_str(bf_generated::paper::SCENE_TOML, "scenes/paper.toml")?;
    // The first row is the module `generate scenes/paper.toml` writes (the scene's list plus
    // the inverse-dynamics family), so it agrees with the report's code-generation table.
    let emitted = bf_codegen::kernels::with_robot_kernels(&base);
    let all: Vec<&str> = emitted.kernels.iter().map(String::as_str).collect();
    Ok(vec![
        variant(
            "everything `generate scenes/paper.toml` emits",
            &base,
            &all,
            false,
        )?,
        variant(
            "free-motion simulation (M, C q̇ + g, U)",
            &base,
            &["mass_cqd_g", "potential"],
            false,
        )?,
        variant(
            "hybrid simulation, line + point contact",
            &base,
            &["mass_cqd_g", "potential", "contact"],
            false,
        )?,
        variant(
            "hybrid simulation, fingertip contact only",
            &base,
            &["mass_cqd_g", "potential", "contact"],
            true,
        )?,
        variant(
            "optimisation contact kernels, line + point contact",
            &base,
            &["mass_cqd_g", "contact_smooth"],
            false,
        )?,
        variant(
            "optimisation contact kernels, fingertip only",
            &base,
            &["mass_cqd_g", "contact_smooth"],
            true,
        )?,
    ])
}

/// The report section.
pub fn markdown(vs: &[Variant]) -> Result<String> {
    let mut s = String::from(
        "Variants of the paper scene generated in this run: the graph is pruned to the listed \
         kernels, and with `contact.kind = \"tip\"` the saturation of eq. 3/58 (min/max/abs) \
         disappears.\n\n| variant | kernels | operations | min/max/abs ops | square roots | code bytes | generation time |\n|---|---|---|---|---|---|---|\n",
    );
    for v in vs {
        writeln!(
            s,
            "| {} | {} | {} | {} | {} | {} | {:.1} ms |",
            v.label,
            v.kernels.len(),
            v.ops,
            v.saturation_ops,
            v.sqrt_ops,
            v.code_bytes,
            v.seconds * 1e3
        )?;
    }
    Ok(s)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pruning_and_tip_contact_remove_work() {
        let vs = variants().unwrap();
        let full = &vs[0];
        for v in &vs[1..] {
            assert!(v.ops < full.ops, "{} prunes", v.label);
            assert!(v.code_bytes < full.code_bytes, "{} has less code", v.label);
        }
        // Tip-only contact: no saturation at all, and fewer operations than line contact.
        let (line, tip) = (&vs[2], &vs[3]);
        assert!(line.saturation_ops > 0, "{} saturates", line.label);
        assert_eq!(tip.saturation_ops, 0, "{} has no saturation", tip.label);
        assert!(tip.ops < line.ops);
        // Smooth saturation (eq. 59) is two square roots; tip-only contact keeps only |r_c|.
        let (line, tip) = (&vs[4], &vs[5]);
        assert!(
            tip.sqrt_ops < line.sqrt_ops,
            "{} vs {}",
            tip.sqrt_ops,
            line.sqrt_ops
        );
        assert!(tip.ops < line.ops);
        // Free motion needs no contact geometry: no square roots of |r_c|, no saturation.
        assert_eq!(vs[1].saturation_ops, 0);
    }

    #[test]
    fn the_full_variant_is_the_module_generate_writes() {
        let vs = variants().unwrap();
        let scene =
            Scene::from_toml_str(bf_generated::paper::SCENE_TOML, "scenes/paper.toml").unwrap();
        let module = crate::commands::generate::generate_module(
            &scene,
            bf_generated::paper::SCENE_TOML,
            &Default::default(),
        )
        .unwrap();
        assert_eq!(vs[0].kernels.len(), module.report.kernels.len());
        assert_eq!(vs[0].code_bytes, module.code.len());
    }
}
