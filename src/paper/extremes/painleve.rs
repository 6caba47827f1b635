//! Probe 7, the Painlevé threshold in μ_k (Sect. 7, eq. 37): at a slipping contact state the
//! kinetic friction μ_k* above which slip has no consistent normal force, by bisection on the
//! model's slip and in closed form from the contact matrices; λ_n = f/(1 − μ_k/μ_k*) below
//! it and the typed `Painleve` error above it.

use std::time::Instant;

use anyhow::bail;
use bf_model::{ModelError, State, Vec3, dynamics};

use super::report::{ExtremesRow, Outcome, Rows, model_err_outcome};
use super::states::{press_torque, state_with_slip};

/// The Painlevé threshold at a fixed slipping contact state (probe 7).
#[derive(Debug, Clone, PartialEq)]
pub struct PainleveProbe {
    /// μ_k* by bisection on the model's slip (relative bracket width 1e-12).
    pub threshold_bisection: f64,
    /// μ_k* = (1 − margin) nᵀWn / (−nᵀW t̂) from the contact matrices (closed form of the
    /// model's test k = nᵀW(n + μ_k t̂) ≤ margin · nᵀWn).
    pub threshold_closed_form: f64,
    /// (μ_k / μ_k*, λ_n) below the threshold.
    pub below: Vec<(f64, f64)>,
    /// The model's errors at 1.01 μ_k* and at μ_k = 1e6.
    pub above: Vec<(f64, Result<f64, ModelError>)>,
}

/// Probe 7: slip direction t̂ = −T_n W n/|T_n W n| (the direction in which friction reduces the
/// normal mobility fastest), |Δv| = 1e-3 m/s, finger pressed on with 1 N ([`press_torque`]).
pub fn painleve_threshold(q: Vec3) -> anyhow::Result<PainleveProbe> {
    let base = bf_model::fixtures::paper_scene()?;
    let kin0 = base.evaluate(&State::new(q, Vec3::zeros(), Vec3::zeros()))?;
    let mats = dynamics::contact_matrices(&kin0, base.params())?;
    let n = kin0.contact.n;
    let wn = mats.w * n;
    let t_hat = -(wn - n * n.dot(&wn)).normalize();
    let x = state_with_slip(&base, q, &t_hat, 1e-3)?;
    let kin = base.evaluate(&x)?;
    let tau = press_torque(&kin, 1.0);
    let slip = |mu: f64| -> Result<f64, ModelError> {
        let p = base
            .params()
            .with_coulomb(base.params().mu_s().max(mu), mu)?;
        let m = base.clone().with_params(p);
        m.slip(&x, &tau, None).map(|a| a.force.lambda_n)
    };
    // the direction the model will use (T_n Δv normalised) equals t̂ up to rounding
    let dv = kin.contact.delta_v;
    let t_model = (dv - n * n.dot(&dv)).normalize();
    let margin = base.settings().painleve_margin;
    let ntw = n.dot(&(mats.w * t_model));
    if ntw >= 0.0 {
        bail!("nᵀ W t̂ = {ntw:e} ≥ 0: no Painlevé threshold in this direction");
    }
    let closed = (1.0 - margin) * mats.n_w_n / (-ntw);
    let (mut lo, mut hi) = (0.0, 1.0);
    let mut guard = 0;
    while slip(hi).is_ok() {
        lo = hi;
        hi *= 2.0;
        guard += 1;
        if guard > 60 {
            bail!("no Painlevé error up to μ_k = {hi:e}");
        }
    }
    if slip(lo).is_err() {
        bail!("slip fails already at μ_k = {lo}");
    }
    for _ in 0..200 {
        if hi - lo <= 1e-12 * hi {
            break;
        }
        let mid = 0.5 * (lo + hi);
        if slip(mid).is_ok() {
            lo = mid
        } else {
            hi = mid
        }
    }
    let star = 0.5 * (lo + hi);
    let below = [0.0, 0.5, 0.9, 0.99, 0.999]
        .iter()
        .map(|&f| slip(f * star).map(|l| (f, l)))
        .collect::<Result<Vec<_>, _>>()?;
    let above = vec![(1.01 * star, slip(1.01 * star)), (1e6, slip(1e6))];
    Ok(PainleveProbe {
        threshold_bisection: star,
        threshold_closed_form: closed,
        below,
        above,
    })
}

/// The report rows of probe 7 at the contact configuration `qc`.
pub(super) fn report(qc: Vec3, rows: &mut Vec<ExtremesRow>) {
    let t = Instant::now();
    let mut r = Rows::new("large μ_k (Painlevé, Sect. 7)");
    match painleve_threshold(qc) {
        Ok(p) => {
            r.num(
                "bisection",
                "threshold μ_k*",
                p.threshold_bisection,
                (p.threshold_bisection - p.threshold_closed_form).abs(),
            );
            r.num(
                "closed form",
                "(1 − margin) nᵀWn / (−nᵀW t̂)",
                p.threshold_closed_form,
                0.0,
            );
            for (f, l) in &p.below {
                r.num(format!("μ_k = {f} μ_k*"), "slip λ_n (N)", *l, 0.0);
            }
            for (mu, res) in &p.above {
                let par = format!("μ_k = {mu:.6e}");
                match res {
                    Ok(l) => r.push(
                        &par,
                        "slip",
                        Outcome::Failed {
                            message: format!("no Painlevé error above the threshold (λ_n = {l:e})"),
                        },
                    ),
                    Err(e) => r.push(
                        &par,
                        "slip",
                        model_err_outcome(e, |e| matches!(e, ModelError::Painleve { .. })),
                    ),
                }
            }
        }
        Err(e) => r.fail("threshold", format!("{e:#}")),
    }
    r.finish(t, rows);
}
