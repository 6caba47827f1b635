//! `ball-finger eval SCENE --q .. --qd .. [--omega ..] [--eps ..] [--qdd ..] [--tau ..]`: one
//! JSON object with the kinematics (eq. 67–71), dynamics (eq. 72–79, Christoffel C) and
//! contact quantities (eq. 2–7, smooth variant eq. 58–59) at one state, followed by
//! `"kernels"`: every kernel the scene's module holds (its `kernels` list and the
//! inverse-dynamics family), in emission order, each an object of its outputs named as the
//! kernel's arguments (`Contact` fields for the contact kernels), arrays nested row-major. The
//! inverse-dynamics kernels take q̈ from `--qdd`, `forward_dynamics` τ from `--tau` (default 0).
//! Compiled scenes (the parsed file equals a scene compiled into `bf-generated`,
//! `bf_model::registry::compiled_match`) go through the compiled kernels; any other file through
//! the generator's interpreter (stderr names which). `--param name=value` sets runtime
//! parameters. Key order and layout
//! are fixed. A non-finite entry (overflow at an extreme state or ε) is an error naming the
//! quantity or the kernel and the entry (indices from 1), never a `null` in the JSON.

use crate::cli::EvalArgs;
use crate::io::parse_list;
use anyhow::{Context, Result, bail};
use bf_codegen::interp::{OutputShape, SceneKernels};
use bf_codegen::kernels::Arg;
use bf_codegen::{EvalOutput, EvalValue, Scene};
use bf_model::KernelSource;
use serde::ser::{Serialize, SerializeMap, Serializer};

/// Run `eval`.
pub fn run(args: &EvalArgs) -> Result<()> {
    let (scene, _) = super::load_scene_with_params(&args.scene, &args.param)?;
    let n = scene.links.len();
    let q = parse_list("--q", &args.q, Some(n))?;
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
    if !(eps.is_finite() && eps > 0.0) {
        anyhow::bail!("--eps must be a finite positive number (got {eps})");
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
    let (out, kernels, source) = match eval_builtin(&scene, &q, &qd, omega, eps) {
        Some(out) => {
            let flat = compiled_kernels(&scene, &runtime, &state)
                .context("internal: a built-in scene without its compiled kernels")?;
            (out, flat, KernelSource::Compiled)
        }
        None => (
            bf_codegen::eval_all(&scene, &q, &qd, omega, eps)
                .with_context(|| format!("{}: evaluation failed", args.scene.display()))?,
            interpreted_kernels(&runtime, &state),
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
    eprintln!("evaluated {} on the {source} kernels", scene.name);
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
    /// The `u` argument of `eval_flat_u` for a kernel with `inputs`: τ for forward dynamics,
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

macro_rules! compiled_flat {
    ($m:ident, $p:expr, $rt:expr, $s:expr) => {{
        use bf_generated::$m as k;
        let p: &[f64; k::NP] = $p.try_into().ok()?;
        let q: [f64; k::NQ] = $s.q.try_into().ok()?;
        let qd: [f64; k::NQ] = $s.qd.try_into().ok()?;
        let mut out = Vec::new();
        for kern in &$rt.kernels {
            let u: [f64; k::NQ] = $s.u(&kern.inputs).try_into().ok()?;
            out.push(k::eval_flat_u(
                &kern.name, &q, &qd, &$s.omega, $s.eps, &u, p,
            )?);
        }
        Some(out)
    }};
}

/// Every kernel's flat outputs through the compiled module of a built-in scene.
fn compiled_kernels(scene: &Scene, rt: &SceneKernels, s: &State) -> Option<Vec<Vec<f64>>> {
    let (entry, p) = bf_model::registry::compiled_match(scene)?;
    let p = p.as_slice();
    match entry.name {
        "paper" => compiled_flat!(paper, p, rt, s),
        "human" => compiled_flat!(human, p, rt, s),
        "puma560" => compiled_flat!(puma560, p, rt, s),
        "iiwa7" => compiled_flat!(iiwa7, p, rt, s),
        _ => None,
    }
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

fn vec3(v: &[f64]) -> EvalValue {
    EvalValue::Vector(v.to_vec())
}

fn mat<const C: usize>(rows: &[[f64; C]]) -> EvalValue {
    EvalValue::Matrix(rows.iter().map(|r| r.to_vec()).collect())
}

macro_rules! eval_dynamics {
    ($m:ident, $p:expr, $q:expr, $qd:expr, $out:expr) => {{
        use bf_generated::$m as k;
        let p: &[f64; k::NP] = $p.try_into().ok()?;
        let q: [f64; k::NQ] = $q.try_into().ok()?;
        let qd: [f64; k::NQ] = $qd.try_into().ok()?;
        let mut pos = [[0.0; 3]; k::NQ];
        let mut rot = [[[0.0; 3]; 3]; k::NQ];
        k::frames(&q, p, &mut pos, &mut rot);
        let (mut jp, mut jo) = ([[0.0; k::NQ]; 3], [[0.0; k::NQ]; 3]);
        k::tip_jacobian(&q, p, &mut jp, &mut jo);
        let mut m = [[0.0; k::NQ]; k::NQ];
        k::mass_matrix(&q, p, &mut m);
        let mut c = [[0.0; k::NQ]; k::NQ];
        k::coriolis_matrix(&q, &qd, p, &mut c);
        let (mut cqd, mut g) = ([0.0; k::NQ], [0.0; k::NQ]);
        k::coriolis_qd(&q, &qd, p, &mut cqd);
        k::gravity(&q, p, &mut g);
        let e = &mut $out.entries;
        e.push(("p_e".into(), vec3(&pos[k::NQ - 1])));
        e.push(("R3".into(), mat(&rot[k::NQ - 1])));
        e.push(("J_p".into(), mat(&jp)));
        e.push(("J_o".into(), mat(&jo)));
        e.push(("M".into(), mat(&m)));
        e.push(("C".into(), mat(&c)));
        e.push(("Cqd".into(), EvalValue::Vector(cqd.to_vec())));
        e.push(("g".into(), EvalValue::Vector(g.to_vec())));
        (q, qd)
    }};
}

macro_rules! eval_contact {
    ($m:ident, $p:expr, $q:expr, $qd:expr, $omega:expr, $eps:expr, $out:expr) => {{
        use bf_generated::$m as k;
        let p: &[f64; k::NP] = $p.try_into().ok()?;
        let mut c = k::Contact::default();
        k::contact(&$q, &$qd, &$omega, p, &mut c);
        let mut s = k::Contact::default();
        k::contact_smooth(&$q, &$qd, &$omega, $eps, p, &mut s);
        let e = &mut $out.entries;
        e.push(("alpha".into(), EvalValue::Scalar(c.alpha)));
        e.push(("sat_alpha".into(), EvalValue::Scalar(c.sat_alpha)));
        e.push(("p_c".into(), vec3(&c.p_c)));
        e.push(("h".into(), EvalValue::Scalar(c.h)));
        e.push(("J_c".into(), mat(&c.j_c)));
        e.push(("sat_alpha_smooth".into(), EvalValue::Scalar(s.sat_alpha)));
        e.push(("p_c_smooth".into(), vec3(&s.p_c)));
        e.push(("h_smooth".into(), EvalValue::Scalar(s.h)));
        e.push(("J_c_smooth".into(), mat(&s.j_c)));
    }};
}

/// Evaluate through the compiled kernels when `scene` is a compiled scene
/// (`bf_model::registry::compiled_match`: same kernel-relevant content, runtime parameters at
/// any value).
fn eval_builtin(
    scene: &Scene,
    q: &[f64],
    qd: &[f64],
    omega: [f64; 3],
    eps: f64,
) -> Option<EvalOutput> {
    let (entry, p) = bf_model::registry::compiled_match(scene)?;
    let p = p.as_slice();
    let mut out = EvalOutput::default();
    match entry.name {
        "paper" => {
            let (q, qd) = eval_dynamics!(paper, p, q, qd, out);
            eval_contact!(paper, p, q, qd, omega, eps, out);
        }
        "human" => {
            let (q, qd) = eval_dynamics!(human, p, q, qd, out);
            eval_contact!(human, p, q, qd, omega, eps, out);
        }
        "puma560" => {
            eval_dynamics!(puma560, p, q, qd, out);
        }
        "iiwa7" => {
            eval_dynamics!(iiwa7, p, q, qd, out);
        }
        _ => return None,
    }
    Some(out)
}
