//! `ball-finger eval SCENE --q .. --qd .. [--omega ..] [--eps ..]`: one JSON object with the
//! kinematics (eq. 67–71), dynamics (eq. 72–79, Christoffel C) and contact quantities
//! (eq. 2–7, smooth variant eq. 58–59) at one state. Compiled scenes (the parsed file equals a
//! scene compiled into `bf-generated`, `bf_model::registry::compiled_match`) go through the
//! compiled kernels; any other file through the generator's interpreter (stderr names which).
//! `--param name=value` sets runtime parameters. Key order and layout are fixed (matrices
//! row-major). A non-finite entry (overflow at an extreme state or ε) is an error naming the
//! quantity and the entry (indices from 1), never a `null` in the JSON.

use crate::cli::EvalArgs;
use crate::io::parse_list;
use anyhow::{Context, Result, bail};
use bf_codegen::{EvalOutput, EvalValue, Scene};
use bf_model::KernelSource;

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
    let eps = args
        .eps
        .or(scene.contact.as_ref().map(|c| c.smooth_eps))
        .unwrap_or(0.01);
    if !(eps.is_finite() && eps > 0.0) {
        anyhow::bail!("--eps must be a finite positive number (got {eps})");
    }
    let (out, source) = match eval_builtin(&scene, &q, &qd, omega, eps) {
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
    eprintln!("evaluated {} on the {source} kernels", scene.name);
    crate::outln!("{}", serde_json::to_string(&out)?)
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
