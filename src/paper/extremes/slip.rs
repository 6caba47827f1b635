//! Probe 5, slip as |Δv| → 0 (eq. 20, 38, Sect. 3.1): the finger at rest pressed onto a ball
//! spinning so that |Δv| = 1e-2 … 1e-14 m/s: the slip force with and without a direction hint
//! (`UndefinedSlipDirection` below the model's tolerance), the residual of the division-free
//! slip law (eq. 38), the friction direction (eq. 20) and the Slip→Stick predicate.

use std::time::Instant;

use bf_model::{ModelError, Vec3, dynamics, transitions};

use super::report::{ExtremesRow, Rows, model_err_outcome};
use super::states::{press_torque, some_tangent, state_with_slip};

/// Slip at |Δv| = `s` (probe 5).
#[derive(Debug, Clone, PartialEq)]
pub struct SlipProbe {
    /// |Δv| (m/s).
    pub s: f64,
    /// λ without a direction hint, or the model's error (`UndefinedSlipDirection` below
    /// `slip_direction_tol`).
    pub lambda: Result<Vec3, ModelError>,
    /// λ with the direction hint t̂ (always defined).
    pub lambda_hint: Vec3,
    /// λ_n of `lambda_hint` (N).
    pub lambda_n: f64,
    /// |λ_∥| of `lambda_hint` (N); eq. 20: μ_k λ_n.
    pub lambda_t_norm: f64,
    /// |eq. 38 residual| / (|λ| |Δv|) (division-free slip law; 0 up to rounding).
    pub law_residual: f64,
    /// Angle (rad) between the friction force λ_∥ and Δv (eq. 20: 0).
    pub friction_angle: f64,
    /// The Slip→Stick predicate (‖Δv‖ ≤ ε and decreasing).
    pub slip_to_stick: bool,
}

/// Probe 5: finger at rest on the ball, pressed on with 1 N ([`press_torque`]), ball spinning
/// so that |Δv| = `s`.
pub fn slip_small_dv(q: Vec3, s: f64) -> anyhow::Result<SlipProbe> {
    let model = bf_model::fixtures::paper_scene()?;
    let t_hat = some_tangent(&model, q)?;
    let x = state_with_slip(&model, q, &t_hat, s)?;
    let kin = model.evaluate(&x)?;
    let tau = press_torque(&kin, 1.0);
    let lambda = model.slip(&x, &tau, None).map(|a| a.force.lambda);
    let acc = model.slip(&x, &tau, Some(&t_hat))?;
    let lam = acc.force.lambda;
    let dv = kin.contact.delta_v;
    let res = dynamics::slip_law_residual(&lam, &kin.contact.n, &dv, model.params().mu_k());
    let law_residual = res[0].abs().max(res[1].abs()) / (lam.norm() * dv.norm());
    let lt = acc.force.lambda_t;
    let cosang = (lt.dot(&t_hat) / lt.norm()).clamp(-1.0, 1.0);
    let slip_to_stick = transitions::slip_to_stick(&kin, &acc, model.settings());
    Ok(SlipProbe {
        s,
        lambda,
        lambda_hint: lam,
        lambda_n: acc.force.lambda_n,
        lambda_t_norm: acc.force.lambda_t.norm(),
        law_residual,
        friction_angle: libm::acos(cosang),
        slip_to_stick,
    })
}

/// The report rows of probe 5 at the contact configuration `qc`.
pub(super) fn report(qc: Vec3, rows: &mut Vec<ExtremesRow>) {
    let t = Instant::now();
    let mut r = Rows::new("slip with |Δv| → 0 (paper, eq. 20/38)");
    let reference = slip_small_dv(qc, 1e-9).map(|p| p.lambda_hint);
    for &s in &[1e-2, 1e-4, 1e-6, 1e-8, 1e-10, 1e-12, 1e-14] {
        let par = format!("|Δv| = {s:e} m/s");
        match (slip_small_dv(qc, s), &reference) {
            (Ok(p), Ok(lref)) => {
                match &p.lambda {
                    Ok(l) => r.num(
                        &par,
                        "|λ| (N), no hint",
                        l.norm(),
                        (l - p.lambda_hint).norm(),
                    ),
                    Err(e) => r.push(
                        &par,
                        "λ, no hint",
                        model_err_outcome(e, |e| {
                            matches!(e, ModelError::UndefinedSlipDirection { .. })
                        }),
                    ),
                }
                r.num(
                    &par,
                    "|λ − λ(1e-9)|/|λ|, with hint",
                    (p.lambda_hint - lref).norm() / lref.norm(),
                    f64::EPSILON,
                );
                r.num(
                    &par,
                    "eq. 38 residual/(|λ||Δv|)",
                    p.law_residual,
                    f64::EPSILON,
                );
                r.num(
                    &par,
                    "angle(λ_∥, Δv) (rad)",
                    p.friction_angle,
                    f64::EPSILON.sqrt(),
                );
                r.num(
                    &par,
                    "Slip→Stick fires (1/0)",
                    f64::from(u8::from(p.slip_to_stick)),
                    0.0,
                );
            }
            (Err(e), _) => r.fail(&par, format!("{e:#}")),
            (_, Err(e)) => r.fail(&par, format!("{e:#}")),
        }
    }
    r.finish(t, rows);
}
