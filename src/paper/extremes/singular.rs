//! Probe 4, singular contact configurations (eq. 7 and Γ = G M⁻¹ Gᵀ of eq. 33): the human
//! finger with links 2–3 aligned and touching the ball along their axis, where J_c loses rank
//! and the finger cannot move along the normal: σ_min(J_c), nᵀWn and the model's typed
//! `SingularContact` error, the δ at which stick starts returning a force, and the stretched
//! paper finger far from the ball (rank loss without contact: `NotInContact`).

use std::f64::consts::PI;
use std::time::Instant;

use anyhow::{Context, anyhow, bail};
use bf_model::{HumanKernels, Model, ModelError, State, Vec3, dynamics};

use super::numerics::singular_values;
use super::report::{ExtremesRow, Rows, model_err_outcome};
use super::states::press_torque;

/// q₂ at which links 2–3 (with q₁ = q₃ = 0) point from the end of link 1 at (2, 0, 1) straight
/// at the ball centre: x₂ = (−sin q₂, 0, cos q₂) = (−2, 0, −1)/√5.
pub fn singular_q2() -> f64 {
    PI - libm::atan(2f64)
}

/// The human finger touching a ball (radius chosen through the runtime parameter `ball.radius`)
/// at its tip, q = (0, [`singular_q2`], δ): for δ = 0 links 2 and 3 are aligned and point at the
/// ball centre, so J_c loses rank (joints 2 and 3 move the tip the same way) and the finger
/// cannot move along the normal (J_cᵀ n = 0 ⇒ Γ singular, eq. 33).
#[derive(Debug, Clone, PartialEq)]
pub struct SingularProbe {
    /// δ = q₃ (rad).
    pub delta: f64,
    /// Ball radius making h = 0 (m).
    pub radius: f64,
    /// Singular values of J_c, ascending.
    pub jc_singular_values: [f64; 3],
    /// nᵀ W n / ‖W‖_F (W = J_c M_f⁻¹ J_cᵀ): the normal mobility the model thresholds.
    pub normal_mobility: f64,
    /// The model's stick result with the finger pressed on with 1 N ([`press_torque`]):
    /// (λ_n, |λ − n|), exactly (1, 0) in exact arithmetic; or the model's error.
    pub stick: Result<(f64, f64), ModelError>,
}

/// Probe 4 at q₃ = `delta`.
pub fn singular_contact(delta: f64) -> anyhow::Result<SingularProbe> {
    use bf_generated::human as hk;
    let i_r = hk::PARAM_NAMES
        .iter()
        .position(|n| *n == "ball.radius")
        .context("human scene has no runtime parameter ball.radius")?;
    let q = [0.0, singular_q2(), delta];
    let mut c = hk::Contact::default();
    let mut p = hk::PARAM_DEFAULTS;
    hk::contact(&q, &[0.0; 3], &[0.0; 3], &p, &mut c);
    // r_c does not depend on the radius: choose the radius that puts the ball on the tip.
    let radius = c.r_c.iter().map(|v| v * v).sum::<f64>().sqrt();
    p[i_r] = radius;
    let model = Model::from_kernels(HumanKernels::with_params(&p)?)?;
    let x = State::new(Vec3::from(q), Vec3::zeros(), Vec3::zeros());
    let kin = model.evaluate(&x)?;
    let sv = singular_values(&kin.contact.j_c);
    let mats = dynamics::contact_matrices(&kin, model.params())?;
    let tau = press_torque(&kin, 1.0);
    let n = kin.contact.n;
    let stick = model
        .stick(&x, &tau)
        .map(|a| (a.force.lambda_n, (a.force.lambda - n).norm()));
    Ok(SingularProbe {
        delta,
        radius,
        jc_singular_values: sv,
        normal_mobility: mats.n_w_n / mats.w.norm(),
        stick,
    })
}

/// The smallest q₃ = δ at which [`singular_contact`] still returns a force: bisection in log δ
/// on [1e-9, 1e-1] (60 halvings); error if the bracket ends are not singular / regular.
pub fn singular_threshold() -> anyhow::Result<f64> {
    let is_singular = |d: f64| -> anyhow::Result<bool> {
        match singular_contact(d)?.stick {
            Ok(_) => Ok(false),
            Err(ModelError::SingularContact { .. }) => Ok(true),
            Err(e) => Err(anyhow!("unexpected error at δ = {d:e}: {e}")),
        }
    };
    let (mut lo, mut hi) = (libm::log(1e-9f64), libm::log(1e-1f64));
    if !is_singular(libm::exp(lo))? || is_singular(libm::exp(hi))? {
        bail!("no singular → regular switch of stick on δ ∈ [1e-9, 1e-1]");
    }
    for _ in 0..60 {
        let mid = 0.5 * (lo + hi);
        if is_singular(libm::exp(mid))? {
            lo = mid
        } else {
            hi = mid
        }
    }
    Ok(libm::exp(hi))
}

/// The report rows of probe 4.
pub(super) fn report(rows: &mut Vec<ExtremesRow>) {
    let t = Instant::now();
    let mut r = Rows::new("singular contact (links 2–3 aligned, touching along their axis)");
    for &d in &[0.0, 1e-8, 1e-6, 1e-4, 1e-2, 1e-1] {
        let par = format!("q₃ = δ = {d:e}");
        match singular_contact(d) {
            Ok(s) => {
                r.num(
                    &par,
                    "σ_min(J_c) (m)",
                    s.jc_singular_values[0],
                    f64::EPSILON * s.jc_singular_values[2],
                );
                r.num(&par, "nᵀWn/‖W‖", s.normal_mobility, f64::EPSILON);
                match &s.stick {
                    Ok((l, e)) => r.num(&par, "stick λ_n (N), pressed with 1 N", *l, *e),
                    Err(e) => r.push(
                        &par,
                        "stick",
                        model_err_outcome(e, |e| matches!(e, ModelError::SingularContact { .. })),
                    ),
                }
            }
            Err(e) => r.fail(&par, format!("{e:#}")),
        }
    }
    match singular_threshold() {
        Ok(d) => r.num(
            "bisection",
            "δ* where stick stops reporting SingularContact",
            d,
            d * 1e-12,
        ),
        Err(e) => r.fail("bisection", format!("{e:#}")),
    }
    far_from_ball_rows(&mut r);
    r.finish(t, rows);
}

/// The stretched paper finger far from the ball: rank loss of J_c without contact, and the
/// model's `NotInContact` for a stick there.
fn far_from_ball_rows(r: &mut Rows) {
    let par = "paper, q = (0.3, 0, 0), no contact";
    match bf_model::fixtures::paper_scene().and_then(|m| {
        let x = State::new(Vec3::new(0.3, 0.0, 0.0), Vec3::zeros(), Vec3::zeros());
        let kin = m.evaluate(&x)?;
        Ok((
            singular_values(&kin.contact.j_c),
            m.stick(&x, &Vec3::zeros()),
        ))
    }) {
        Ok((sv, st)) => {
            r.num(par, "σ_min(J_c) (m)", sv[0], f64::EPSILON * sv[2]);
            match st {
                Ok(_) => r.fail(par, "stick accepted a state 1 m away from the ball"),
                Err(e) => r.push(
                    par,
                    "stick",
                    model_err_outcome(&e, |e| matches!(e, ModelError::NotInContact { .. })),
                ),
            }
        }
        Err(e) => r.fail(par, e.to_string()),
    }
}
