//! Probe 2, extreme joint velocities (eq. 24, C q̇ in Christoffel form): the compiled
//! `coriolis_qd` at |q̇| = 1e-12 … 1e3 rad/s against double-double, and the exact quadratic
//! homogeneity C(q, k q̇) k q̇ = k² C(q, q̇) q̇.

use std::time::Instant;

use super::graph_eval::GraphEval;
use super::numerics::rel_err;
use super::report::{ExtremesRow, Rows};
use super::states::QD_PROBE;
use crate::pipeline::verify::nan_max;

/// C q̇ at extreme |q̇| (probe 2).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct VelocityExtreme {
    /// |q̇| scale.
    pub qd_mag: f64,
    /// rel. error of the compiled `coriolis_qd` vs double-double.
    pub cqd: f64,
    /// rel. deviation of C(q, k q̇) k q̇ from k² C(q, q̇) q̇ with q̇ = [`QD_PROBE`], k = `qd_mag`
    /// (exact quadratic homogeneity of the Christoffel form).
    pub homogeneity: f64,
    /// max |C q̇| (N m).
    pub magnitude: f64,
}

/// Compiled `coriolis_qd` at |q̇| = `qd_mag` (probe 2).
pub fn velocity_extremes(reference: &GraphEval, qd_mag: f64) -> VelocityExtreme {
    use bf_generated::paper as k;
    let q = [0.4, -0.7, 1.1];
    let qd = QD_PROBE.map(|v| v * qd_mag);
    let p = [0.0; 0];
    let mut c = [0.0; 3];
    k::coriolis_qd(&q, &qd, &p, &mut c);
    let mut c1 = [0.0; 3];
    k::coriolis_qd(&q, &QD_PROBE, &p, &mut c1);
    let dd = reference.eval_dd(&q, &qd, &[0.0; 3], 0.01, &[]);
    let predicted = c1.map(|v| v * qd_mag * qd_mag);
    VelocityExtreme {
        qd_mag,
        cqd: rel_err(&c, dd.get("Cqd")),
        homogeneity: rel_err(&c, &predicted),
        magnitude: c.iter().map(|v| v.abs()).fold(0.0, nan_max),
    }
}

/// The report rows of probe 2 at |q̇| ~ 1e-12, 1, 1e3 rad/s.
pub(super) fn report(paper: &GraphEval, rows: &mut Vec<ExtremesRow>) {
    for &v in &[1e-12, 1.0, 1e3] {
        let t = Instant::now();
        let mut r = Rows::new("joint velocity (C q̇)");
        let a = velocity_extremes(paper, v);
        let par = format!("|q̇| ~ {v:e} rad/s");
        r.num(&par, "rel. err. C q̇ vs double-double", a.cqd, f64::EPSILON);
        r.num(
            &par,
            "rel. dev. from k² homogeneity",
            a.homogeneity,
            f64::EPSILON,
        );
        r.finish(t, rows);
    }
}
