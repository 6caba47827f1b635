//! bf-codegen: scene file (DH table, inertias, ball) → verified flat Rust dynamics kernels.
//!
//! Pipeline (`docs/architecture.md`, "codegen"): [`spec`] (the scene types of bf-scene) → [`robot`] (kinematics eq. 67–71,
//! dynamics eq. 22a/72–79, contact eq. 2–13/58–59 as [`graph`] expressions, derivatives by
//! [`diff`]) → [`kernels`] (the catalogue of docs/kernels.md) → [`emit`] (SSA Rust code) with a
//! [`report`]; [`interp`] evaluates the same graphs in f64 or double-double ([`dd`]);
//! [`trig`] is the fast batched sine–cosine that emitted kernels carry ([`trig_nostd`]: the
//! square root and one-argument sine–cosine of `#![no_std]` modules);
//! [`nodefn`] differentiates, fingerprints and emits collocation node functions as kernels
//! (the ball-and-finger node functions themselves are built in bf-problem).
//!
//! Entry points: [`generate`] (code + report), [`Builder`] (the same from a user's build
//! script, [`builder`]) and [`eval_all`] (numbers for one state).
//!
//! Cargo feature `emit` (default): the emitter ([`emit`], [`generate`],
//! [`nodefn::emit_node_kernels`]) and its syn/quote/prettyplease dependencies. Without it the
//! crate builds, differentiates and interprets the graphs, which is all a run-time user
//! (bf-model's interpreted kernels, bf-optim's node functions) needs.

#[cfg(feature = "emit")]
pub mod builder;
pub mod dd;
pub mod diff;
#[cfg(feature = "emit")]
pub mod emit;
mod error;
pub mod graph;
pub mod interp;
pub mod kernels;
pub mod nodefn;
pub mod report;
pub mod robot;
pub mod trig;
pub mod trig_nostd;

#[cfg(feature = "emit")]
use std::time::Instant;

use serde::ser::{Serialize, SerializeMap, Serializer};

/// The scene file (bf-scene), under its historical path `bf_codegen::spec`.
pub use bf_scene as spec;
#[cfg(feature = "emit")]
pub use builder::{BuildError, Builder, Emitted};
#[cfg(feature = "emit")]
pub use emit::{EmitSettings, FloatTy, ModuleSplit};
pub use kernels::ALL_KERNELS;
pub use report::{KernelReport, OpCounts, Report};
pub use robot::SymbolicRobot;
pub use spec::Scene;

pub use error::{
    BYTES_PER_NODE, CodegenError, ExtremeValues, GraphTooLarge, InputDefect, InternalDefect,
    SceneDefect,
};

#[cfg(feature = "emit")]
/// Result of [`generate`].
#[derive(Debug, Clone)]
pub struct Generated {
    /// The Rust source of the scene module (formatted, deterministic).
    pub code: String,
    /// Operation counts per kernel and timing.
    pub report: Report,
}

#[cfg(feature = "emit")]
fn check_kernel_list(scene: &Scene) -> Result<(), CodegenError> {
    for (i, k) in scene.kernels.iter().enumerate() {
        if !ALL_KERNELS.contains(&k.as_str()) {
            return Err(SceneDefect::UnknownKernel {
                name: k.clone(),
                in_list: true,
                known: ALL_KERNELS,
            }
            .into());
        }
        if scene.kernels[..i].contains(k) {
            return Err(SceneDefect::KernelTwice { name: k.clone() }.into());
        }
    }
    Ok(())
}

#[cfg(feature = "emit")]
/// Generate the Rust module of `scene`. `source_text` is the scene file's text, embedded as
/// `SCENE_TOML`. Output is byte-identical for identical input.
pub fn generate(scene: &Scene, source_text: &str) -> Result<Generated, CodegenError> {
    generate_with(scene, source_text, &emit::EmitSettings::default())
}

#[cfg(feature = "emit")]
/// As [`generate`], with emission variants (f32, fused multiply-add); see [`emit::EmitSettings`].
pub fn generate_with(
    scene: &Scene,
    source_text: &str,
    opts: &emit::EmitSettings,
) -> Result<Generated, CodegenError> {
    generate_split(scene, source_text, opts, emit::ModuleSplit::Auto)
}

#[cfg(feature = "emit")]
/// As [`generate_with`], with the kernels put in submodules of their own as `split` says
/// ([`emit::ModuleSplit`]; [`generate_with`] uses `Auto`): the same kernels, compiled in
/// parallel code-generation units.
pub fn generate_split(
    scene: &Scene,
    source_text: &str,
    opts: &emit::EmitSettings,
    split: emit::ModuleSplit,
) -> Result<Generated, CodegenError> {
    generate_bounded(scene, source_text, opts, split, graph::node_limit())
}

#[cfg(feature = "emit")]
/// As [`generate_split`], on an expression graph of at most `max_graph_nodes` nodes: a scene
/// whose kernels need more ends with [`CodegenError::TooLarge`], naming the kernel being built
/// ([`Builder::max_graph_nodes`]; the others use the process's [`graph::node_limit`]).
pub fn generate_bounded(
    scene: &Scene,
    source_text: &str,
    opts: &emit::EmitSettings,
    split: emit::ModuleSplit,
    max_graph_nodes: usize,
) -> Result<Generated, CodegenError> {
    let start = Instant::now();
    if opts.no_std && opts.fma {
        return Err(CodegenError::Settings(
            "fused multiply-add (`fma`) needs the standard library's `mul_add`; a no_std module \
             cannot have it",
        ));
    }
    check_kernel_list(scene)?;
    let mut model = SymbolicRobot::with_node_limit(scene, max_graph_nodes)?;
    let mut defs = Vec::new();
    for k in &scene.kernels {
        defs.push(kernels::build_kernel(&mut model, k)?);
    }
    for d in &defs {
        let roots: Vec<graph::Id> = d.output_ids();
        check_finite_constants(&model.g, &roots, scene, &format!("kernel `{}`", d.name))?;
    }
    let mut kernel_code = Vec::new();
    let mut reports = Vec::new();
    let mut trig_helper = false;
    for d in &defs {
        let e = emit::emit_kernel_with(&model.g, &model.layout, d, opts)?;
        trig_helper |= e.trig;
        kernel_code.push(e.code);
        reports.push(KernelReport {
            name: d.name.clone(),
            ops: e.ops,
        });
    }
    let temporaries: Vec<usize> = reports.iter().map(|r| r.ops.temporaries).collect();
    for ((code, d), own) in kernel_code
        .iter_mut()
        .zip(&defs)
        .zip(split.which(&temporaries))
    {
        if own {
            *code = emit::own_module(&d.name, code);
        }
    }
    let with_contact = scene.kernels.iter().any(|k| k.starts_with("contact"));
    let code = emit::emit_file_with(
        &scene.name,
        model.nq(),
        &model.params,
        &defs,
        source_text,
        &kernel_code,
        with_contact,
        trig_helper,
        opts,
    )?;
    let report = Report {
        scene: scene.name.clone(),
        nq: model.nq(),
        params: model.params.iter().map(|p| p.0.clone()).collect(),
        graph_nodes: model.g.len(),
        kernels: reports,
        seconds: start.elapsed().as_secs_f64(),
        code_bytes: code.len(),
        warnings: scene.warnings(),
    };
    Ok(Generated { code, report })
}

/// The scene constants of largest and smallest nonzero magnitude (at most three of each), as
/// `key = value`: the likely sources when folding them overflows.
fn extreme_constants(scene: &Scene) -> ExtremeValues {
    let mut all = scene.constants();
    // Placement origins are baked into the code, not named constants, but overflow as well.
    for (i, l) in scene.links.iter().enumerate() {
        if let Some(o) = &l.origin {
            for (c, x) in ["x", "y", "z"].iter().zip(o.translation()) {
                all.push((format!("link{}.origin.{c}", i + 1), x));
            }
        }
    }
    let mut c: Vec<(String, f64)> = all.into_iter().filter(|c| c.1 != 0.0).collect();
    c.sort_by(|a, b| b.1.abs().total_cmp(&a.1.abs()).then(a.0.cmp(&b.0)));
    let mut shown: Vec<(String, f64)> = c.iter().take(3).cloned().collect();
    for (k, v) in c.iter().rev().take(3) {
        if !shown
            .iter()
            .any(|(k2, v2)| k2 == k && v2.to_bits() == v.to_bits())
        {
            shown.push((k.clone(), *v));
        }
    }
    ExtremeValues(shown)
}

#[cfg(feature = "emit")]
/// Errors if the cone of `roots` holds a non-finite constant (scene values whose products or
/// quotients overflow `f64` when folded): emitted code would contain `f64::INFINITY`.
fn check_finite_constants(
    g: &graph::Graph,
    roots: &[graph::Id],
    scene: &Scene,
    what: &str,
) -> Result<(), CodegenError> {
    let mark = g.cone(roots);
    for (i, &m) in mark.iter().enumerate() {
        if let graph::Node::Const(b) = g.node(graph::Id(i as u32))
            && m
            && !f64::from_bits(b).is_finite()
        {
            return Err(SceneDefect::NonFiniteConstant {
                what: what.to_string(),
                value: f64::from_bits(b),
                extremes: extreme_constants(scene),
            }
            .into());
        }
    }
    Ok(())
}

/// A named numeric output of [`eval_all`].
#[derive(Debug, Clone, PartialEq)]
pub enum EvalValue {
    /// A scalar.
    Scalar(f64),
    /// A vector.
    Vector(Vec<f64>),
    /// A row-major matrix.
    Matrix(Vec<Vec<f64>>),
}

impl Serialize for EvalValue {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        match self {
            EvalValue::Scalar(v) => v.serialize(s),
            EvalValue::Vector(v) => v.serialize(s),
            EvalValue::Matrix(v) => v.serialize(s),
        }
    }
}

/// Named outputs of [`eval_all`], in a fixed order (serialises as a JSON object in that order).
#[derive(Debug, Clone, PartialEq, Default)]
pub struct EvalOutput {
    /// (name, value) pairs: p_e, R3, J_p, J_o, M, C, Cqd, g, then for scenes with a ball
    /// alpha, sat_alpha, p_c, h, J_c, sat_alpha_smooth, p_c_smooth, h_smooth, J_c_smooth.
    pub entries: Vec<(String, EvalValue)>,
}

impl EvalOutput {
    /// The value called `name`.
    pub fn get(&self, name: &str) -> Option<&EvalValue> {
        self.entries.iter().find(|e| e.0 == name).map(|e| &e.1)
    }
}

impl Serialize for EvalOutput {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        let mut m = s.serialize_map(Some(self.entries.len()))?;
        for (k, v) in &self.entries {
            m.serialize_entry(k, v)?;
        }
        m.end()
    }
}

fn check_finite(name: &'static str, v: &[f64]) -> Result<(), CodegenError> {
    if let Some((index, value)) = v.iter().enumerate().find(|(_, x)| !x.is_finite()) {
        return Err(InputDefect::NonFinite {
            what: name,
            index,
            value: *value,
        }
        .into());
    }
    Ok(())
}

/// Evaluate kinematics, dynamics and (if the scene has a ball and contact) contact quantities
/// of `scene` at one state with the interpreter, using the scene's constant values (runtime
/// parameters at their defaults). Every quantity is computed regardless of `kernels`, with the
/// same f64 operations as the emitted kernels (sine and cosine included).
pub fn eval_all(
    scene: &Scene,
    q: &[f64],
    qd: &[f64],
    omega: [f64; 3],
    eps: f64,
) -> Result<EvalOutput, CodegenError> {
    let mut model = SymbolicRobot::new(scene)?;
    let n = model.nq();
    if q.len() != n || qd.len() != n {
        return Err(InputDefect::JointCount {
            joints: n,
            q: q.len(),
            qd: qd.len(),
        }
        .into());
    }
    check_finite("q", q)?;
    check_finite("qd", qd)?;
    check_finite("omega", &omega)?;
    check_finite("eps", &[eps])?;
    let layout = model.layout;
    let mut vars = vec![0.0; layout.n_vars()];
    vars[..n].copy_from_slice(q);
    vars[n..2 * n].copy_from_slice(qd);
    vars[2 * n..2 * n + 3].copy_from_slice(&omega);
    vars[layout.eps() as usize] = eps;
    for (i, p) in model.params.iter().enumerate() {
        vars[layout.param(i) as usize] = p.1;
    }

    // Collect (name, shape, ids), then evaluate all in one tape.
    enum Shape {
        S,
        V,
        M(usize),
    }
    let mut items: Vec<(String, Shape, Vec<graph::Id>)> = Vec::new();
    let tip = model.tip_pose();
    items.push(("p_e".into(), Shape::V, tip.t.to_vec()));
    items.push((
        "R3".into(),
        Shape::M(3),
        tip.r.iter().flatten().copied().collect(),
    ));
    let (jp, jo) = model.tip_jacobian();
    items.push(("J_p".into(), Shape::M(n), jp.concat()));
    items.push(("J_o".into(), Shape::M(n), jo.concat()));
    let m = model.mass_matrix();
    items.push(("M".into(), Shape::M(n), m.concat()));
    let c = model.coriolis_matrix();
    items.push(("C".into(), Shape::M(n), c.concat()));
    let cqd = model.coriolis_qd();
    items.push(("Cqd".into(), Shape::V, cqd));
    let g = model.gravity();
    items.push(("g".into(), Shape::V, g));
    if scene.ball.is_some() && scene.contact.is_some() {
        let ce = model.contact(false)?;
        items.push(("alpha".into(), Shape::S, vec![ce.alpha]));
        items.push(("sat_alpha".into(), Shape::S, vec![ce.sat_alpha]));
        items.push(("p_c".into(), Shape::V, ce.p_c.to_vec()));
        items.push(("h".into(), Shape::S, vec![ce.h]));
        items.push(("J_c".into(), Shape::M(n), ce.j_c.concat()));
        let cs = model.contact(true)?;
        items.push(("sat_alpha_smooth".into(), Shape::S, vec![cs.sat_alpha]));
        items.push(("p_c_smooth".into(), Shape::V, cs.p_c.to_vec()));
        items.push(("h_smooth".into(), Shape::S, vec![cs.h]));
        items.push(("J_c_smooth".into(), Shape::M(n), cs.j_c.concat()));
    }
    model.check_size("eval", robot::EVAL_ADVICE)?;
    let all: Vec<graph::Id> = items.iter().flat_map(|i| i.2.iter().copied()).collect();
    // In `f64`, whose sine and cosine are the emitted kernels' own: the numbers are those of
    // the emitted f64 kernels bit for bit.
    let vals: Vec<f64> = interp::eval(&model.g, &all, &vars);
    let mut off = 0;
    let mut out = EvalOutput::default();
    for (name, shape, ids) in items {
        let v = &vals[off..off + ids.len()];
        off += ids.len();
        if let Some(x) = v.iter().find(|x| !x.is_finite()) {
            return Err(InputDefect::NonFiniteResult {
                what: name.to_string(),
                value: *x,
                extremes: extreme_constants(scene),
            }
            .into());
        }
        let value = match shape {
            Shape::S => EvalValue::Scalar(v[0]),
            Shape::V => EvalValue::Vector(v.to_vec()),
            Shape::M(cols) => EvalValue::Matrix(v.chunks(cols).map(|r| r.to_vec()).collect()),
        };
        out.entries.push((name, value));
    }
    Ok(out)
}
