//! The node kernels emitted for the scenes with a ball and a contact: which node functions
//! ([`node_kernel_specs`], the shapes the problem catalogue uses), compiled by
//! [`compile_node`] and emitted by bf-codegen's [`bf_codegen::nodefn::emit_node_kernels`].
//! bf-generated's build script calls [`emit_node_kernels`] for every scene; at run time the
//! collocation finds those kernels by the fingerprint of the node function it builds.
//!
//! Batched variants (four collocation nodes per call) are emitted only for the shapes that the
//! catalogue's default settings build ([`NodeKernelSpec::x4`]): they double a kernel's code,
//! and the other shapes (Legendre–Gauss stick phases, the ḣ margin row) are options.

use bf_codegen::nodefn::{CompiledNode, NamedNode};
use bf_codegen::{CodegenError, Scene};

use crate::node::{CostKind, NodeSettings, PhaseMode, StickLevel, node_function};

/// One node function emitted as kernels ([`node_kernel_specs`]).
#[derive(Debug, Clone)]
pub struct NodeKernelSpec {
    /// Kernel name prefix, `<scene>_<cost>_<phase>`.
    pub name: String,
    /// The node function's settings.
    pub settings: NodeSettings,
    /// Stick-constraint level (acceleration only for Legendre–Gauss).
    pub level: StickLevel,
    /// Whether the batched (`_x4`) variants are emitted too: for the shapes of the
    /// catalogue's default settings (Radau collocation, so the velocity-level stick
    /// constraint, and no ḣ margin row).
    pub x4: bool,
}

/// The node functions emitted as kernels for a scene with a ball and a contact, for every cost
/// kind of the scene's `ocp_kernels` (default: all), shaped as the problem library uses them:
/// a free phase (h row) for every kind; for the periodic costs (QC, COT) also the free phase
/// with the Sect. 7 ḣ margin row and the stick phase at both levels; for the free–stick
/// archetypes' costs (track, reorient, spin) the stick phase with the |h| row at both levels;
/// `reach`'s time–effort cost has no stick phase. Other shapes are interpreted. Names are
/// `<scene>_<cost>_<phase>`. Empty without a ball or a contact.
pub fn node_kernel_specs(scene: &Scene) -> Vec<NodeKernelSpec> {
    let mut out = Vec::new();
    // Default settings: no ḣ margin row, velocity-level stick constraint (Radau).
    let mut push = |name: String, settings: NodeSettings, level: StickLevel| {
        let x4 = settings.hdot_bounds.is_none() && level == StickLevel::Velocity;
        out.push(NodeKernelSpec {
            name,
            settings,
            level,
            x4,
        });
    };
    if scene.ball.is_none() || scene.contact.is_none() {
        return out;
    }
    for cost in CostKind::all_kinds() {
        if let Some(list) = &scene.ocp_kernels
            && !list.iter().any(|c| c == cost.tag())
        {
            continue;
        }
        let base = NodeSettings {
            mode: PhaseMode::Free,
            cost,
            h_bounds: Some((0.0, f64::INFINITY)),
            hdot_bounds: None,
            eps: 0.01,
            cone_margin: 0.0,
        };
        let name = |s: &str| format!("{}_{}_{s}", scene.name, cost.tag());
        push(name("free"), base.clone(), StickLevel::Velocity);
        let (stick, tag) = match cost {
            CostKind::Qc { .. } | CostKind::Cot { .. } => {
                let margin = NodeSettings {
                    hdot_bounds: Some((f64::NEG_INFINITY, 0.0)),
                    ..base.clone()
                };
                push(name("free_hdot"), margin, StickLevel::Velocity);
                let stick = NodeSettings {
                    mode: PhaseMode::Stick,
                    h_bounds: None,
                    ..base
                };
                (stick, "stick")
            }
            CostKind::TimeEffort { .. } => continue,
            _ => {
                let stick = NodeSettings {
                    mode: PhaseMode::Stick,
                    ..base
                };
                (stick, "stick_h")
            }
        };
        push(name(tag), stick.clone(), StickLevel::Velocity);
        push(name(&format!("{tag}_acc")), stick, StickLevel::Acceleration);
    }
    out
}

/// Compiles the node function `opt` of `scene` at `level` for collocation.
pub fn compile_node(
    scene: &Scene,
    opt: &NodeSettings,
    level: StickLevel,
) -> Result<CompiledNode, CodegenError> {
    let ph = crate::node::physics(scene)?;
    let (nf, _) = node_function(scene, &ph, opt, level)?;
    let c = nf.collocation();
    Ok(CompiledNode::new(c.graph, c.outputs, c.locals, nf.fixed))
}

/// The Rust source of the node kernels of `scenes` (those with a ball and a contact; the
/// others are skipped): one value, Jacobian and Hessian function per [`node_kernel_specs`]
/// entry (and, for the entries with [`NodeKernelSpec::x4`], their batched `_x4` variants,
/// four collocation nodes at once), and
/// `pub static NODE_KERNELS: &[NodeKernel]` sorted by fingerprint. Specs with the
/// structure of an earlier one (QC and tracking share their integrands, the constants being
/// inputs) share its kernel. The including module must define `NodeKernel` and
/// `NodeKernelX4`. Deterministic:
/// the same scenes give the same text.
pub fn emit_node_kernels(scenes: &[&Scene]) -> Result<String, CodegenError> {
    let mut nodes = Vec::new();
    for scene in scenes {
        for spec in node_kernel_specs(scene) {
            let node = compile_node(scene, &spec.settings, spec.level)?;
            let what = format!(
                "`{}` (scene `{}`, {:?} level)",
                spec.name, scene.name, spec.level
            );
            nodes.push(NamedNode {
                name: spec.name,
                what,
                node,
                x4: spec.x4,
            });
        }
    }
    // A kernel serves every spec with its fingerprint (the first one names it): batched if
    // any of them asks for it.
    for i in 0..nodes.len() {
        let fp = nodes[i].node.fingerprint;
        nodes[i].x4 |= nodes[i + 1..]
            .iter()
            .any(|n| n.x4 && n.node.fingerprint == fp);
    }
    bf_codegen::nodefn::emit_node_kernels(&nodes)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn paper() -> Scene {
        Scene::load(concat!(env!("CARGO_MANIFEST_DIR"), "/../scenes/paper.toml")).unwrap()
    }

    fn opts(mode: PhaseMode, eps: f64, w: f64) -> NodeSettings {
        NodeSettings {
            mode,
            cost: CostKind::Qc {
                w,
                omega_ref: [0.0, 0.0, 2.2],
            },
            h_bounds: Some((0.0, f64::INFINITY)),
            hdot_bounds: None,
            eps,
            cone_margin: 0.0,
        }
    }

    #[test]
    fn fingerprint_ignores_input_values_but_not_structure() {
        let s = paper();
        let fp = |o: &NodeSettings, l| compile_node(&s, o, l).unwrap().fingerprint;
        let base = fp(&opts(PhaseMode::Free, 0.01, 1.0), StickLevel::Velocity);
        // ε and the cost weight are inputs: same kernel.
        assert_eq!(
            base,
            fp(&opts(PhaseMode::Free, 0.05, 3.0), StickLevel::Velocity)
        );
        // Another mode, stick level, row set or baked constant: another function.
        let stick = fp(&opts(PhaseMode::Stick, 0.01, 1.0), StickLevel::Velocity);
        let stick_acc = fp(&opts(PhaseMode::Stick, 0.01, 1.0), StickLevel::Acceleration);
        // The cone margin scales μ_s, an input: same kernel.
        assert_eq!(
            stick,
            fp(
                &NodeSettings {
                    cone_margin: 0.2,
                    ..opts(PhaseMode::Stick, 0.01, 1.0)
                },
                StickLevel::Velocity
            )
        );
        let no_h = fp(
            &NodeSettings {
                h_bounds: None,
                ..opts(PhaseMode::Free, 0.01, 1.0)
            },
            StickLevel::Velocity,
        );
        // A nonzero where the pattern had a zero is another structure.
        let tilted = fp(
            &NodeSettings {
                cost: CostKind::Qc {
                    w: 1.0,
                    omega_ref: [0.1, 0.0, 2.2],
                },
                ..opts(PhaseMode::Free, 0.01, 1.0)
            },
            StickLevel::Velocity,
        );
        let mut other = s.clone();
        if let Some(f) = other.friction.as_mut() {
            f.mu_v *= 2.0;
        }
        let other_mu = compile_node(
            &other,
            &opts(PhaseMode::Free, 0.01, 1.0),
            StickLevel::Velocity,
        )
        .unwrap();
        let all = [base, stick, stick_acc, no_h, tilted, other_mu.fingerprint];
        for i in 0..all.len() {
            for j in 0..i {
                assert_ne!(all[i], all[j], "{i} vs {j}");
            }
        }
    }

    #[cfg(feature = "catalogue")]
    fn scene_toml(name: &str) -> Option<&'static str> {
        match name {
            "paper" => Some(include_str!("../../scenes/paper.toml")),
            "human" => Some(include_str!("../../scenes/human.toml")),
            _ => None,
        }
    }

    /// The batched variants are emitted for exactly the node functions that the catalogue's
    /// problems build with default settings (so none is missing where the transcription would
    /// batch, and none is emitted for nothing).
    #[cfg(feature = "catalogue")]
    #[test]
    fn batched_kernels_are_those_of_the_default_settings() {
        let generated = crate::Generated {
            scene_toml,
            kernels: bf_optim::ocp::KernelUse::Never,
        };
        let mut used = std::collections::BTreeSet::new();
        for problem in crate::Problem::ALL {
            let p = crate::build(problem, &crate::ProblemSettings::default(), &generated)
                .unwrap_or_else(|e| panic!("{}: {e}", problem.name()));
            for phase in &p.ocp.phases {
                let c = phase.node.collocation();
                let node =
                    CompiledNode::new(c.graph, c.outputs, c.locals, phase.node.fixed.clone());
                used.insert(node.fingerprint);
            }
        }
        let mut batched = std::collections::BTreeSet::new();
        let mut scalar_only = Vec::new();
        for name in ["paper", "human"] {
            let scene = Scene::from_toml_str(scene_toml(name).unwrap(), name).unwrap();
            for spec in node_kernel_specs(&scene) {
                let fp = compile_node(&scene, &spec.settings, spec.level)
                    .unwrap()
                    .fingerprint;
                if spec.x4 {
                    batched.insert(fp);
                } else {
                    scalar_only.push((spec.name, fp));
                }
            }
        }
        assert_eq!(used, batched);
        for (name, fp) in scalar_only {
            assert!(
                !used.contains(&fp),
                "{name} is used by default but not batched"
            );
        }
    }

    #[test]
    fn emission_is_deterministic_and_covers_the_requested_costs() {
        let mut s = paper();
        s.ocp_kernels = Some(vec!["cot".into()]);
        let a = emit_node_kernels(&[&s]).unwrap();
        let b = emit_node_kernels(&[&s]).unwrap();
        assert_eq!(a, b);
        for k in [
            "paper_cot_free",
            "paper_cot_free_hdot",
            "paper_cot_stick",
            "paper_cot_stick_acc",
        ] {
            assert!(a.contains(&format!("name: \"{k}\"")), "{k} missing");
            assert!(
                a.contains(&format!("fn {k}_hessian(")),
                "{k} hessian missing"
            );
        }
        assert!(!a.contains("paper_qc_"));
        // Entries sorted by fingerprint, as `node_kernel`'s binary search needs.
        let fps: Vec<u128> = a
            .lines()
            .filter_map(|l| l.trim().strip_prefix("fingerprint: "))
            .map(|v| v.trim_end_matches(',').parse().unwrap())
            .collect();
        assert_eq!(fps.len(), 4);
        assert!(fps.windows(2).all(|w| w[0] < w[1]));
        // An empty list emits no kernel.
        s.ocp_kernels = Some(vec![]);
        assert!(!emit_node_kernels(&[&s]).unwrap().contains("name:"));
    }
}
