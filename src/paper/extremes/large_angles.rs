//! Probe 1, kernel accuracy at large |q| (eq. 22a, 24 and the contact geometry of eq. 2–7,
//! Appendix A/B): the compiled `paper` kernels M, C q̇ + g, h and J_c at |q| = 1 … 1e6 rad
//! against the double-double evaluation of the same graph at the same q, and again with q
//! reduced mod 2π in f64 (which is itself off by k·(2π − fl(2π)), so q is never reduced
//! before calling the kernels).

use std::f64::consts::TAU;
use std::time::Instant;

use bf_codegen::dd::Dd;

use super::graph_eval::GraphEval;
use super::numerics::{flat3, rel_err};
use super::report::{ExtremesRow, Rows};
use super::states::{OMEGA_PROBE, Q_DIR, QD_PROBE};
use crate::pipeline::verify::nan_max;

/// Errors of the compiled `paper` kernels at q = `q_mag` · [`Q_DIR`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct KernelAccuracy {
    /// The q evaluated.
    pub q: [f64; 3],
    /// rel. error of `mass_matrix` vs double-double at the same q.
    pub m: f64,
    /// rel. error of `cqd_g` vs double-double at the same q.
    pub cqd_g: f64,
    /// rel. error of `mass_cqd_g`'s C q̇ + g (the model's path) vs double-double.
    pub cqd_g_model: f64,
    /// |h − h_dd| / |r_c| of `contact` (h is a difference of O(r) numbers).
    pub h: f64,
    /// rel. error of `contact`'s J_c vs double-double.
    pub j_c: f64,
    /// The same four errors with the kernels evaluated at q reduced mod 2π in f64
    /// (reference: double-double at the unreduced q): M, C q̇ + g, h, J_c.
    pub reduced: [f64; 4],
    /// max over joints of |q_red − (q − 2πk)| in double-double: the rounding of the
    /// reduction itself, which bounds what `reduced` can reach.
    pub reduction_error: f64,
}

/// Compiled `paper` kernels vs the double-double interpreter at |q| = `q_mag` (probe 1).
pub fn kernel_accuracy(reference: &GraphEval, q_mag: f64) -> KernelAccuracy {
    use bf_generated::paper as k;
    let q = Q_DIR.map(|d| d * q_mag);
    let qd = QD_PROBE;
    let w = OMEGA_PROBE;
    let p = [0.0; 0];
    let dd = reference.eval_dd(&q, &qd, &w, 0.01, &[]);
    let compiled = |q: &[f64; 3]| {
        let mut m = [[0.0; 3]; 3];
        k::mass_matrix(q, &p, &mut m);
        let mut cg = [0.0; 3];
        k::cqd_g(q, &qd, &p, &mut cg);
        let mut m2 = [[0.0; 3]; 3];
        let mut cg2 = [0.0; 3];
        k::mass_cqd_g(q, &qd, &p, &mut m2, &mut cg2);
        let mut c = k::Contact::default();
        k::contact(q, &qd, &w, &p, &mut c);
        (flat3(&m), cg, cg2, c)
    };
    let (m, cg, cg2, c) = compiled(&q);
    let scale = dd.get("r_c_norm")[0];
    let h_err = |h: f64| (h - dd.get("h")[0]).abs() / scale;
    let q_red = q.map(|x| x.rem_euclid(TAU));
    let (mr, cgr, _, cr) = compiled(&q_red);
    let two_pi = Dd::new(TAU) + Dd::new(2.4492935982947064e-16);
    let reduction_error = q
        .iter()
        .zip(&q_red)
        .map(|(&x, &xr)| {
            let kf = ((x - xr) / TAU).round();
            let exact = Dd::new(x) - Dd::new(kf) * two_pi;
            (exact - Dd::new(xr)).to_f64().abs()
        })
        .fold(0.0, nan_max);
    KernelAccuracy {
        q,
        m: rel_err(&m, dd.get("M")),
        cqd_g: rel_err(&cg, dd.get("Cqd_g")),
        cqd_g_model: rel_err(&cg2, dd.get("Cqd_g")),
        h: h_err(c.h),
        j_c: rel_err(&flat3(&c.j_c), dd.get("J_c")),
        reduced: [
            rel_err(&mr, dd.get("M")),
            rel_err(&cgr, dd.get("Cqd_g")),
            h_err(cr.h),
            rel_err(&flat3(&cr.j_c), dd.get("J_c")),
        ],
        reduction_error,
    }
}

/// The report rows of probe 1 at |q| = 1, 1e3, 1e6 rad.
pub(super) fn report(paper: &GraphEval, rows: &mut Vec<ExtremesRow>) {
    for &qm in &[1.0, 1e3, 1e6] {
        let t = Instant::now();
        let mut r = Rows::new("kernel accuracy (compiled paper vs double-double)");
        let a = kernel_accuracy(paper, qm);
        let par = format!("|q| = {qm:e} rad");
        r.num(&par, "rel. err. M, same q", a.m, f64::EPSILON);
        r.num(
            &par,
            "rel. err. C q̇ + g (cqd_g), same q",
            a.cqd_g,
            f64::EPSILON,
        );
        r.num(
            &par,
            "rel. err. C q̇ + g (mass_cqd_g), same q",
            a.cqd_g_model,
            f64::EPSILON,
        );
        r.num(&par, "err. h / |r_c|, same q", a.h, f64::EPSILON);
        r.num(&par, "rel. err. J_c, same q", a.j_c, f64::EPSILON);
        r.num(
            &par,
            "rel. err. M, q mod 2π",
            a.reduced[0],
            a.reduction_error,
        );
        r.num(
            &par,
            "rel. err. C q̇ + g, q mod 2π",
            a.reduced[1],
            a.reduction_error,
        );
        r.num(
            &par,
            "err. h / |r_c|, q mod 2π",
            a.reduced[2],
            a.reduction_error,
        );
        r.finish(t, rows);
    }
}
