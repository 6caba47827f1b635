//! Probe 6, the smooth saturation as ε → 0 (eq. 58–59 vs eq. 3–4): h_ε → h and p_c,ε → p_c
//! with their observed orders inside the saturation and at a tip contact; the exact saturation
//! corners α = 0 and α = −l (first-order error there); the model on bf-model's [`InterpretedKernels`] at the
//! exact corner down to ε whose square underflows (a number or the typed `NonFinite`); and
//! ε = 0, outside the model's domain (`InvalidParameter`).

use std::time::Instant;

use bf_model::{ContactVariant, InterpretedKernels, Model, ModelError, State, Vec3};

use super::graph_eval::{GraphEval, paper_scene_spec};
use super::numerics::{all_finite, rel_err};
use super::report::{ExtremesRow, Rows, model_err_outcome};
use super::states::{OMEGA_PROBE, QD_PROBE, press_torque};
use crate::pipeline::verify::nan_max;

/// Smooth vs exact contact at one ε (probe 6).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SmoothError {
    /// ε (m).
    pub eps: f64,
    /// α (m) of the exact contact (interior: −l < α < 0).
    pub alpha: f64,
    /// |sat_ε(α) − sat(α)| (m).
    pub sat: f64,
    /// |h_ε − h| (m).
    pub h: f64,
    /// max |p_c,ε − p_c| (m).
    pub p_c: f64,
    /// Whether every output of `contact_smooth` is finite.
    pub finite: bool,
}

/// Compiled `contact_smooth` vs `contact` of the paper scene at configuration `q` (probe 6).
pub fn smooth_convergence(q: [f64; 3], eps: f64) -> SmoothError {
    use bf_generated::paper as k;
    let p = [0.0; 0];
    let mut c = k::Contact::default();
    k::contact(&q, &QD_PROBE, &OMEGA_PROBE, &p, &mut c);
    let mut s = k::Contact::default();
    k::contact_smooth(&q, &QD_PROBE, &OMEGA_PROBE, eps, &p, &mut s);
    // every output of the kernel, in the emitted order
    let finite = k::eval_flat(
        "contact_smooth",
        &q,
        &QD_PROBE,
        &OMEGA_PROBE,
        eps,
        &k::PARAM_DEFAULTS,
    )
    .is_some_and(|all| all_finite(&all));
    SmoothError {
        eps,
        alpha: c.alpha,
        sat: (s.sat_alpha - c.sat_alpha).abs(),
        h: (s.h - c.h).abs(),
        p_c: rel_err(&s.p_c, &c.p_c) * c.p_c.iter().map(|v| v.abs()).fold(0.0, nan_max),
        finite,
    }
}

/// A configuration of the paper finger whose closest point to the ball is inside link 3
/// (α ≈ −0.40 m, h ≈ 0.43 m): the interior of the saturation, where sat_ε − sat = O(ε²) and,
/// because r_c ⟂ e_x3 there (eq. 1), h_ε − h = O(ε⁴).
pub const Q_INTERIOR: [f64; 3] = [0.0, 1.4, 2.2];

/// Observed convergence orders log(e_i/e_{i+1}) / log(ε_i/ε_{i+1}) between consecutive rows
/// (rows whose error is below `floor` are skipped: rounding, not truncation).
pub fn observed_orders(errs: &[(f64, f64)], floor: f64) -> Vec<f64> {
    errs.windows(2)
        .filter(|w| w[1].1 > floor && w[0].1 > floor)
        .map(|w| libm::log(w[0].1 / w[1].1) / libm::log(w[0].0 / w[1].0))
        .collect()
}

/// The interpreter graph of the paper scene with the ball centre as runtime parameters, so the
/// saturation corners can be hit exactly: at q = 0 the finger is stretched along world z with
/// p_e = (2, 0, 3) and e_x3 = (0, 0, 1) exactly, so α = c_z − 3 exactly.
pub fn corner_graph() -> anyhow::Result<GraphEval> {
    let mut s = paper_scene_spec()?;
    s.runtime_parameters = vec![
        "ball.center.x".into(),
        "ball.center.y".into(),
        "ball.center.z".into(),
        "ball.radius".into(),
    ];
    GraphEval::new(&s)
}

/// At a saturation corner: α exactly 0 (`at_tip`) or exactly −l, ε given. Returns
/// (α, |sat_ε − sat|, |h_ε − h|, all outputs finite).
pub fn smooth_corner(g: &GraphEval, at_tip: bool, eps: f64) -> (f64, f64, f64, bool) {
    let cz = if at_tip { 3.0 } else { 2.0 };
    let p = [2.0, 0.5, cz, 0.5];
    let v = g.eval_f64(&[0.0; 3], &QD_PROBE, &OMEGA_PROBE, eps, &p);
    (
        v.get("alpha")[0],
        (v.get("sat_s")[0] - v.get("sat")[0]).abs(),
        (v.get("h_s")[0] - v.get("h")[0]).abs(),
        all_finite(v.all()),
    )
}

/// Model of the paper scene with the ball moved to `centre` and its radius set to `radius`,
/// on bf-model's [`InterpretedKernels`] (a moved ball has no compiled kernels), smooth contact
/// with `eps`.
pub fn corner_model(
    centre: [f64; 3],
    radius: f64,
    eps: f64,
) -> anyhow::Result<Model<InterpretedKernels>> {
    let mut scene = bf_codegen::Scene::from_toml_str(bf_generated::paper::SCENE_TOML, "paper")?;
    let ball = scene
        .ball
        .as_mut()
        .ok_or_else(|| anyhow::anyhow!("the paper scene has no ball"))?;
    ball.center = centre;
    ball.radius = radius;
    let k = InterpretedKernels::new(&scene)?;
    Ok(Model::from_kernels(k)?.with_contact_variant(ContactVariant::Smooth(eps))?)
}

/// Stick at the exact saturation corner α = 0 (q = 0, ball centre (2, 0.5, 3), radius 0.5, so
/// h = 0 and n = −y) with the smooth contact of width `eps`, finger pressed on with 1 N:
/// `Ok(Ok((λ_n, |λ − n|)))` (exactly (1, 0) in exact arithmetic), or the model's error.
pub fn corner_stick(eps: f64) -> anyhow::Result<Result<(f64, f64), ModelError>> {
    let model = corner_model([2.0, 0.5, 3.0], 0.5, eps)?;
    let x = State::new(Vec3::zeros(), Vec3::zeros(), Vec3::zeros());
    let kin = match model.evaluate(&x) {
        Ok(k) => k,
        Err(e) => return Ok(Err(e)),
    };
    let tau = press_torque(&kin, 1.0);
    let n = kin.contact.n;
    Ok(model
        .stick(&x, &tau)
        .map(|a| (a.force.lambda_n, (a.force.lambda - n).norm())))
}

/// The ε ladder of the report rows.
const EPS_LIST: [f64; 8] = [1e-1, 1e-2, 1e-3, 1e-4, 1e-6, 1e-8, 1e-10, 1e-12];

/// The report rows of probe 6 (interior and tip contact at `qc`, corners, model at a corner).
pub(super) fn report(qc: Vec3, rows: &mut Vec<ExtremesRow>) {
    let t = Instant::now();
    let mut r = Rows::new("smooth sat ε → 0 (eq. 58–59)");
    convergence_rows(&mut r, qc);
    corner_rows(&mut r);
    model_corner_rows(&mut r);
    r.finish(t, rows);
}

/// h_ε → h and p_c,ε → p_c inside the saturation and at the tip contact `qc`, with orders.
fn convergence_rows(r: &mut Rows, qc: Vec3) {
    let qa: [f64; 3] = qc.into();
    for (label, q) in [
        ("interior α", Q_INTERIOR),
        ("saturated α (tip contact)", qa),
    ] {
        let errs: Vec<SmoothError> = EPS_LIST.iter().map(|&e| smooth_convergence(q, e)).collect();
        for e in &errs {
            let par = format!("{label} (α = {:.3}), ε = {:e}", e.alpha, e.eps);
            if !e.finite {
                r.fail(&par, "contact_smooth returned NaN/inf");
            }
            r.num(&par, "|h_ε − h| (m)", e.h, f64::EPSILON);
            r.num(&par, "|p_c,ε − p_c| (m)", e.p_c, f64::EPSILON);
        }
        let hs: Vec<(f64, f64)> = errs.iter().map(|e| (e.eps, e.h)).collect();
        let ps: Vec<(f64, f64)> = errs.iter().map(|e| (e.eps, e.p_c)).collect();
        let min = |v: Vec<f64>| v.into_iter().fold(f64::INFINITY, f64::min);
        r.num(
            label,
            "observed order of h_ε → h (min)",
            min(observed_orders(&hs, 1e-13)),
            0.0,
        );
        r.num(
            label,
            "observed order of p_c,ε → p_c (min)",
            min(observed_orders(&ps, 1e-13)),
            0.0,
        );
    }
}

/// sat_ε → sat and h_ε → h at the exact corners α = 0 and α = −l, with the order.
fn corner_rows(r: &mut Rows) {
    let g = match corner_graph() {
        Ok(g) => g,
        Err(e) => return r.fail("corners", format!("{e:#}")),
    };
    for (tip, name) in [(true, "α = 0"), (false, "α = −l")] {
        let mut corner = Vec::new();
        for &e in &EPS_LIST {
            let (alpha, sat_err, h_err, finite) = smooth_corner(&g, tip, e);
            let par = format!("{name} (α = {alpha:e} exactly), ε = {e:e}");
            if !finite {
                r.fail(
                    &par,
                    "contact_smooth graph returned NaN/inf at a saturation corner",
                );
            } else {
                r.num(&par, "|sat_ε − sat| (m)", sat_err, f64::EPSILON);
                r.num(&par, "|h_ε − h| (m)", h_err, f64::EPSILON);
            }
            corner.push((e, sat_err));
        }
        let o = observed_orders(&corner, 1e-13);
        r.num(
            name,
            "observed order of sat_ε → sat (min)",
            o.iter().copied().fold(f64::INFINITY, f64::min),
            0.0,
        );
    }
}

/// The model at the exact corner α = 0 down to ε whose square underflows, and at ε = 0.
fn model_corner_rows(r: &mut Rows) {
    // a number (λ_n = 1 for the pressed, static finger) or a typed error
    for &e in &[1e-12, 1e-100, 1e-160, 1e-200, 1e-300] {
        let par = format!("model at α = 0 exactly, ε = {e:e}");
        match corner_stick(e) {
            Ok(Ok((l, err))) => r.num(&par, "stick λ_n (N), pressed with 1 N", l, err),
            Ok(Err(me)) => r.push(
                &par,
                "stick",
                model_err_outcome(&me, |e| matches!(e, ModelError::NonFinite { .. })),
            ),
            Err(err) => r.fail(&par, format!("{err:#}")),
        }
    }
    // ε = 0 is outside the model's domain: a typed error, not NaN
    match bf_model::fixtures::paper_scene()
        .and_then(|m| m.with_contact_variant(ContactVariant::Smooth(0.0)))
    {
        Ok(_) => r.fail("ε = 0 (model)", "the model accepted ε = 0"),
        Err(e) => r.push(
            "ε = 0 (model)",
            "with_contact_variant",
            model_err_outcome(&e, |e| matches!(e, ModelError::InvalidParameter { .. })),
        ),
    }
}
