//! `ball-finger eval SCENE --q .. --qd .. [--omega ..] [--eps ..] [--qdd ..] [--tau ..]`: one
//! JSON object with the kinematics (eq. 67–71), dynamics (eq. 72–79, Christoffel C) and
//! contact quantities (eq. 2–7, smooth variant eq. 58–59) at one state, followed by
//! `"kernels"`: every kernel the scene's module holds (its `kernels` list and the
//! inverse-dynamics family), in emission order, each an object of its outputs named as the
//! kernel's arguments (`Contact` fields for the contact kernels), arrays nested row-major. The
//! inverse-dynamics kernels take q̈ from `--qdd`, `forward_dynamics` τ from `--tau` (default 0).
//! Compiled scenes (the parsed file equals a scene compiled into `bf-generated`,
//! `bf_model::registry::compiled_match`) go through the compiled kernels of the generated
//! registry (`bf_generated::SceneKernels::eval_into`, every kernel by name, so no scene module
//! is named here); any other file through the generator's interpreter. stderr names which ran
//! and lists the scene's kernels. `--param name=value` sets runtime parameters. Key order and layout
//! are fixed. A non-finite entry (overflow at an extreme state or ε) is an error naming the
//! quantity or the kernel and the entry (indices from 1), never a `null` in the JSON.

use crate::cli::EvalArgs;
use crate::errors::bail_usage;
use crate::io::parse_list;
use anyhow::{Context, Result, bail};
use bf_codegen::interp::{OutputShape, SceneKernels};
use bf_codegen::kernels::{Arg, CONTACT_FIELDS, Dim};
use bf_codegen::{EvalOutput, EvalValue, Scene};
use bf_generated::SceneKernels as CompiledScene;
use bf_model::KernelSource;
use serde::ser::{Serialize, SerializeMap, Serializer};

/// Run `eval`.
pub fn run(args: &EvalArgs) -> Result<()> {
    let (scene, _) = super::load_scene_with_params(&args.scene, &args.chain, &args.param)?;
    let n = scene.links.len();
    if scene.ball.is_none() {
        // As `simulate` refuses --omega0 for an arm: an option with nothing to act on is a
        // mistake in the command line, not a value to ignore.
        for (opt, given) in [
            ("--omega", args.omega.is_some()),
            ("--eps", args.eps.is_some()),
        ] {
            if given {
                bail_usage!(
                    "{opt}: scene `{}` has no ball, so no ball velocity or contact to evaluate",
                    scene.name
                );
            }
        }
    }
    let q = parse_list("--q", &args.q, Some(n))?;
    super::check_angles("--q", &scene, &q)?;
    let qd = parse_list("--qd", &args.qd, Some(n))?;
    let omega = match &args.omega {
        Some(s) => parse_list("--omega", s, Some(3))?,
        None => vec![0.0; 3],
    };
    let omega = [omega[0], omega[1], omega[2]];
    let qdd = match &args.qdd {
        Some(s) => parse_list("--qdd", s, Some(n))?,
        None => vec![0.0; n],
    };
    let tau = match &args.tau {
        Some(s) => parse_list("--tau", s, Some(n))?,
        None => vec![0.0; n],
    };
    let eps = args
        .eps
        .or(scene.contact.as_ref().map(|c| c.smooth_eps))
        .unwrap_or(0.01);
    if let Some(why) = bf_codegen::spec::smooth_eps_out_of_range(eps) {
        bail_usage!("--eps {why} (got {})", crate::cli::shown(eps));
    }
    let state = State {
        q: &q,
        qd: &qd,
        omega,
        eps,
        qdd: &qdd,
        tau: &tau,
    };
    let runtime = SceneKernels::new(&scene)
        .with_context(|| format!("{}: cannot build the kernels", args.scene.display()))?;
    let compiled = bf_model::registry::compiled_match(&scene);
    let compiled_flat = match &compiled {
        Some((entry, p)) => compiled_kernels(entry, p, &runtime, &state)?,
        None => None,
    };
    let (kernels, kernels_source) = match compiled_flat {
        Some(flat) => (flat, KernelSource::Compiled),
        None => (
            interpreted_kernels(&runtime, &state),
            KernelSource::Interpreted,
        ),
    };
    let compiled_out = compiled
        .as_ref()
        .and_then(|(entry, p)| compiled_quantities(&scene, entry, p, &state));
    let (out, source) = match compiled_out {
        Some(out) => (out, KernelSource::Compiled),
        None => (
            bf_codegen::eval_all(&scene, &q, &qd, omega, eps)
                .with_context(|| format!("{}: evaluation failed", args.scene.display()))?,
            KernelSource::Interpreted,
        ),
    };
    if let Some((entry, v)) = first_non_finite(&out) {
        bail!(
            "{entry} is not finite ({v}) at the given state (--q {}, --qd {}, --omega {}, \
             --eps {eps:e}); nothing was printed",
            args.q,
            args.qd,
            args.omega.as_deref().unwrap_or("0,0,0")
        );
    }
    let kernels = shape_kernels(&scene.name, &runtime, &kernels)?;
    let names: Vec<&str> = runtime.kernels.iter().map(|k| k.name.as_str()).collect();
    if source == kernels_source {
        crate::errln!(
            "evaluated {} on the {source} kernels of `{}`: {}",
            scene.name,
            scene.name,
            names.join(", ")
        );
    } else {
        crate::errln!(
            "evaluated {}: the named quantities on the {source} kernels, the kernels on the \
             {kernels_source} kernels of `{}` (the compiled scene does not emit all of them): {}",
            scene.name,
            scene.name,
            names.join(", ")
        );
    }
    let all = Full {
        quantities: &out,
        kernels: &kernels,
    };
    crate::outln!("{}", serde_json::to_string(&all)?)
}

/// The state every kernel is evaluated at.
struct State<'a> {
    q: &'a [f64],
    qd: &'a [f64],
    omega: [f64; 3],
    eps: f64,
    qdd: &'a [f64],
    tau: &'a [f64],
}

impl State<'_> {
    /// The `u` argument of `SceneKernels::eval_into` for a kernel with `inputs`: τ for forward dynamics,
    /// q̈ otherwise.
    fn u(&self, inputs: &[Arg]) -> &[f64] {
        if inputs.contains(&Arg::Tau) {
            self.tau
        } else {
            self.qdd
        }
    }
}

/// Every kernel's flat outputs through the interpreter.
fn interpreted_kernels(rt: &SceneKernels, s: &State) -> Vec<Vec<f64>> {
    rt.kernels
        .iter()
        .map(|k| {
            let vars = rt.vars(s.q, s.qd, s.omega, s.eps, s.u(&k.inputs), None);
            k.eval(&vars)
        })
        .collect()
}

/// Every kernel's flat outputs (the kernels of the file's spec, `rt`) through the compiled
/// kernels of `entry` (the registry entry the file matches, parameters `p`), looked up by
/// name; `None` if the compiled scene does not emit one of them (the file lists a kernel the
/// compiled file does not).
fn compiled_kernels(
    entry: &CompiledScene,
    p: &[f64],
    rt: &SceneKernels,
    s: &State,
) -> Result<Option<Vec<Vec<f64>>>> {
    let mut out = Vec::with_capacity(rt.kernels.len());
    for kern in &rt.kernels {
        let Some(k) = entry.kernel_index(&kern.name) else {
            return Ok(None);
        };
        let len: usize = kern.outputs.iter().map(OutputShape::len).sum();
        let mut v = vec![0.0; len];
        let got = (entry.eval_into)(k, s.q, s.qd, &s.omega, s.eps, s.u(&kern.inputs), p, &mut v);
        if got != Some(len) {
            bail!(
                "internal: compiled kernel `{}` of {} wrote {got:?} values, expected {len}",
                kern.name,
                entry.name
            );
        }
        out.push(v);
    }
    Ok(Some(out))
}

/// An ordered JSON object.
struct Ordered<T>(Vec<(String, T)>);

impl<T: Serialize> Serialize for Ordered<T> {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        let mut m = s.serialize_map(Some(self.0.len()))?;
        for (k, v) in &self.0 {
            m.serialize_entry(k, v)?;
        }
        m.end()
    }
}

/// The whole `eval` output: the named quantities, then `"kernels"`.
struct Full<'a> {
    quantities: &'a EvalOutput,
    kernels: &'a Ordered<Ordered<serde_json::Value>>,
}

impl Serialize for Full<'_> {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        let e = &self.quantities.entries;
        let mut m = s.serialize_map(Some(e.len() + 1))?;
        for (k, v) in e {
            m.serialize_entry(k, v)?;
        }
        m.serialize_entry("kernels", self.kernels)?;
        m.end()
    }
}

/// Nested row-major arrays of `dims` from `flat`.
fn nest(flat: &[f64], dims: &[usize]) -> serde_json::Value {
    match dims.split_first() {
        None => serde_json::json!(flat[0]),
        Some((_, rest)) => {
            let step: usize = rest.iter().product();
            serde_json::Value::Array(flat.chunks(step.max(1)).map(|c| nest(c, rest)).collect())
        }
    }
}

/// Index `i` of a row-major array of `dims`, from 1: `[2][3]`.
fn index_text(mut i: usize, dims: &[usize]) -> String {
    let mut idx = vec![0; dims.len()];
    for (k, d) in dims.iter().enumerate().rev() {
        idx[k] = i % d + 1;
        i /= d;
    }
    idx.iter().map(|x| format!("[{x}]")).collect()
}

/// Shapes the flat kernel outputs; a non-finite entry is an error naming the kernel, the
/// output and the entry.
fn shape_kernels(
    scene: &str,
    rt: &SceneKernels,
    flat: &[Vec<f64>],
) -> Result<Ordered<Ordered<serde_json::Value>>> {
    let mut out = Vec::new();
    for (k, values) in rt.kernels.iter().zip(flat) {
        let total: usize = k.outputs.iter().map(OutputShape::len).sum();
        if values.len() != total {
            bail!(
                "internal: kernel `{}` of {scene} returned {} values, expected {total}",
                k.name,
                values.len()
            );
        }
        let mut off = 0;
        let mut outs = Vec::new();
        for o in &k.outputs {
            let v = &values[off..off + o.len()];
            off += o.len();
            if let Some(i) = v.iter().position(|x| !x.is_finite()) {
                bail!(
                    "kernel `{}` of {scene}: output {}{} is not finite ({}) at the given state; \
                     nothing was printed",
                    k.name,
                    o.name,
                    index_text(i, &o.dims),
                    v[i]
                );
            }
            outs.push((o.name.clone(), nest(v, &o.dims)));
        }
        out.push((k.name.clone(), Ordered(outs)));
    }
    Ok(Ordered(out))
}

/// What a key of the `eval` output is, for error messages.
fn describe(key: &str) -> &'static str {
    match key {
        "p_e" => "fingertip position",
        "R3" => "fingertip orientation",
        "J_p" => "positional Jacobian",
        "J_o" => "rotational Jacobian",
        "M" => "mass matrix",
        "C" => "Coriolis matrix",
        "Cqd" => "Coriolis torque",
        "g" => "gravity torque",
        "alpha" => "contact coordinate",
        "sat_alpha" | "sat_alpha_smooth" => "saturated contact coordinate",
        "p_c" | "p_c_smooth" => "contact point",
        "h" | "h_smooth" => "distance",
        "J_c" | "J_c_smooth" => "contact Jacobian",
        _ => "quantity",
    }
}

/// The first non-finite entry of `out`, as `"mass matrix M[1][2]"` (indices from 1), with its
/// value.
pub fn first_non_finite(out: &EvalOutput) -> Option<(String, f64)> {
    for (key, value) in &out.entries {
        let name = format!("{} {key}", describe(key));
        match value {
            EvalValue::Scalar(v) if !v.is_finite() => return Some((name, *v)),
            EvalValue::Vector(xs) => {
                if let Some(i) = xs.iter().position(|v| !v.is_finite()) {
                    return Some((format!("{name}[{}]", i + 1), xs[i]));
                }
            }
            EvalValue::Matrix(rows) => {
                for (i, r) in rows.iter().enumerate() {
                    if let Some(j) = r.iter().position(|v| !v.is_finite()) {
                        return Some((format!("{name}[{}][{}]", i + 1, j + 1), r[j]));
                    }
                }
            }
            EvalValue::Scalar(_) => {}
        }
    }
    None
}

/// A matrix of `cols` columns from row-major `v`.
fn rows(v: &[f64], cols: usize) -> EvalValue {
    EvalValue::Matrix(v.chunks(cols.max(1)).map(<[f64]>::to_vec).collect())
}

/// The named quantities (the keys of [`bf_codegen::eval_all`], in its order) through the
/// compiled kernels of `entry` with parameters `p`; `None` if the compiled scene does not emit
/// one of the kernels they come from (`frames`, `tip_jacobian`, `mass_matrix`,
/// `coriolis_matrix`, `coriolis_qd`, `gravity`, and for a scene with a ball and a contact
/// `contact` and `contact_smooth`).
fn compiled_quantities(
    scene: &Scene,
    entry: &CompiledScene,
    p: &[f64],
    s: &State,
) -> Option<EvalOutput> {
    let n = s.q.len();
    let run = |name: &str, len: usize| -> Option<Vec<f64>> {
        let k = entry.kernel_index(name)?;
        let mut v = vec![0.0; len];
        let got = (entry.eval_into)(k, s.q, s.qd, &s.omega, s.eps, s.qdd, p, &mut v)?;
        (got == len).then_some(v)
    };
    let frames = run("frames", 12 * n)?;
    let jac = run("tip_jacobian", 6 * n)?;
    let m = run("mass_matrix", n * n)?;
    let c = run("coriolis_matrix", n * n)?;
    let cqd = run("coriolis_qd", n)?;
    let g = run("gravity", n)?;
    let mut out = EvalOutput::default();
    let e = &mut out.entries;
    // `frames`: pos (NQ × 3), then rot (NQ × 3 × 3); the tip is frame NQ.
    let last = n.checked_sub(1)?;
    e.push((
        "p_e".into(),
        EvalValue::Vector(frames[3 * last..3 * n].to_vec()),
    ));
    let rot = &frames[3 * n + 9 * last..12 * n];
    e.push(("R3".into(), rows(rot, 3)));
    e.push(("J_p".into(), rows(&jac[..3 * n], n)));
    e.push(("J_o".into(), rows(&jac[3 * n..], n)));
    e.push(("M".into(), rows(&m, n)));
    e.push(("C".into(), rows(&c, n)));
    e.push(("Cqd".into(), EvalValue::Vector(cqd)));
    e.push(("g".into(), EvalValue::Vector(g)));
    if scene.ball.is_some() && scene.contact.is_some() {
        let mut at = std::collections::BTreeMap::new();
        let mut len = 0;
        for (name, dims, _) in CONTACT_FIELDS {
            let size: usize = dims
                .iter()
                .map(|d| match d {
                    Dim::Nq => n,
                    Dim::Lit(k) => *k,
                })
                .product();
            at.insert(*name, (len, size));
            len += size;
        }
        let field = |v: &[f64], name: &str| -> Option<Vec<f64>> {
            let &(o, size) = at.get(name)?;
            Some(v[o..o + size].to_vec())
        };
        let exact = run("contact", len)?;
        let smooth = run("contact_smooth", len)?;
        let alpha = field(&exact, "alpha")?[0];
        let sat_alpha = field(&exact, "sat_alpha")?[0];
        e.push(("alpha".into(), EvalValue::Scalar(alpha)));
        e.push(("sat_alpha".into(), EvalValue::Scalar(sat_alpha)));
        e.push(("p_c".into(), EvalValue::Vector(field(&exact, "p_c")?)));
        e.push(("h".into(), EvalValue::Scalar(field(&exact, "h")?[0])));
        e.push(("J_c".into(), rows(&field(&exact, "j_c")?, n)));
        let sat_smooth = field(&smooth, "sat_alpha")?[0];
        e.push(("sat_alpha_smooth".into(), EvalValue::Scalar(sat_smooth)));
        e.push((
            "p_c_smooth".into(),
            EvalValue::Vector(field(&smooth, "p_c")?),
        ));
        e.push((
            "h_smooth".into(),
            EvalValue::Scalar(field(&smooth, "h")?[0]),
        ));
        e.push(("J_c_smooth".into(), rows(&field(&smooth, "j_c")?, n)));
    }
    Some(out)
}
