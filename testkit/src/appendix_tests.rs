//! Appendix A/B of the paper versus the independent reference, over random states and
//! non-unit, unequal parameters. Each erratum has a test that asserts the PRINTED formula
//! disagrees and the CORRECTED one agrees (docs/appendix-errata.md lists them).

use crate::appendix::*;
use crate::reference::Reference;
use nalgebra::DVector;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

const TOL: f64 = 1e-12;

fn uni(r: &mut ChaCha8Rng, lo: f64, hi: f64) -> f64 {
    r.random_range(lo..hi)
}

fn rq(r: &mut ChaCha8Rng) -> [f64; 3] {
    [uni(r, -4.0, 4.0), uni(r, -4.0, 4.0), uni(r, -4.0, 4.0)]
}

fn param_sets() -> Vec<AppendixParams> {
    crate::appendix::param_sets(20)
}

fn states(seed: u64, n: usize) -> Vec<([f64; 3], [f64; 3])> {
    let mut r = ChaCha8Rng::seed_from_u64(seed);
    (0..n).map(|_| (rq(&mut r), rq(&mut r))).collect()
}

/// Worst relative error of `printed` and `corrected` against the reference over all states
/// and parameter sets (optionally only sets satisfying `filter`).
fn sweep(
    seed: u64,
    filter: impl Fn(&AppendixParams) -> bool,
    f: impl Fn(&AppendixParams, &Reference, &[f64; 3], &[f64; 3]) -> (f64, f64),
) -> (f64, f64) {
    let mut worst = (0.0f64, 0.0f64);
    for p in param_sets().into_iter().filter(|p| filter(p)) {
        let reference = p.reference();
        for (q, qd) in states(seed, 25) {
            let (a, b) = f(&p, &reference, &q, &qd);
            worst = (worst.0.max(a), worst.1.max(b));
        }
    }
    worst
}

/// eq. 67: the printed constant `2` (times ℓ) is the base offset 2r; it only holds for r = ℓ.
#[test]
fn eq67_tip_position_constant_is_2r_not_2l() {
    let tip = |p: &AppendixParams, rf: &Reference, q: &[f64; 3], _: &[f64; 3]| {
        let want = rf.tip_position(q);
        (
            rel_err(&p_e_printed(q, p.l), &want),
            rel_err(&p_e_corrected(q, p.l, p.r), &want),
        )
    };
    // r = ℓ (the paper's numbers): printed is right.
    let (printed, corrected) = sweep(1, |p| p.r == p.l, tip);
    assert!(
        printed < TOL && corrected < TOL,
        "{printed:e} {corrected:e}"
    );
    // r ≠ ℓ: printed is off by 2(r − ℓ) in x, corrected agrees.
    let (printed, corrected) = sweep(1, |p| (p.r - p.l).abs() > 0.05, tip);
    assert!(
        printed > 1e-2,
        "printed eq. 67 unexpectedly agrees: {printed:e}"
    );
    assert!(corrected < TOL, "corrected eq. 67: {corrected:e}");
}

/// eq. 68 is correct as printed (no erratum): columns are e_x3, e_y3, e_z3.
#[test]
fn eq68_frame3_axes_agree() {
    let (printed, _) = sweep(
        2,
        |_| true,
        |_, rf, q, _| {
            let rot = rf.frames(q).1[2];
            (rel_err(&flat3(&frame3_axes_printed(q)), &flat3(&rot)), 0.0)
        },
    );
    assert!(printed < TOL, "{printed:e}");
}

/// eq. 70: entry (3,3) has the wrong sign; everything else is right.
#[test]
fn eq70_jp_entry_33_sign() {
    let (printed, corrected) = sweep(
        3,
        |_| true,
        |p, rf, q, _| {
            let (jp, _) = rf.tip_jacobian(q);
            let want: Vec<f64> = jp.transpose().iter().copied().collect();
            (
                rel_err(&flat3(&jp_printed(q, p.l)), &want),
                rel_err(&flat3(&jp_corrected(q, p.l)), &want),
            )
        },
    );
    assert!(
        printed > 1e-2,
        "printed eq. 70 unexpectedly agrees: {printed:e}"
    );
    assert!(corrected < TOL, "corrected eq. 70: {corrected:e}");
    // Only (3,3) is wrong, and it is exactly the negation (printed + reference = 0 there).
    let p = AppendixParams::paper();
    let rf = p.reference();
    for (q, _) in states(33, 20) {
        let (jp, _) = rf.tip_jacobian(&q);
        let pr = jp_printed(&q, p.l);
        for i in 0..3 {
            for j in 0..3 {
                if (i, j) != (2, 2) {
                    assert!((pr[i][j] - jp[(i, j)]).abs() < TOL);
                }
            }
        }
        assert!((pr[2][2] + jp[(2, 2)]).abs() < TOL);
    }
    // The corrected J_p is also the derivative of the (corrected) eq. 67, independently of
    // the reference.
    let h = 1e-6;
    for (q, _) in states(34, 10) {
        let jc = jp_corrected(&q, 0.8);
        for k in 0..3 {
            let mut qp = q;
            let mut qm = q;
            qp[k] += h;
            qm[k] -= h;
            let (a, b) = (p_e_corrected(&qp, 0.8, 1.3), p_e_corrected(&qm, 0.8, 1.3));
            for i in 0..3 {
                assert!((jc[i][k] - (a[i] - b[i]) / (2.0 * h)).abs() < 1e-8);
            }
        }
    }
}

/// eq. 71 is correct as printed.
#[test]
fn eq71_jo_agrees() {
    let (printed, _) = sweep(
        4,
        |_| true,
        |_, rf, q, _| {
            let (_, jo) = rf.tip_jacobian(q);
            let want: Vec<f64> = jo.transpose().iter().copied().collect();
            (rel_err(&flat3(&jo_printed(q)), &want), 0.0)
        },
    );
    assert!(printed < TOL, "{printed:e}");
}

/// eq. 72: rows 2 and 3 print `s_{11\bar1}` = sin(q1 + q2 − q3) where sin(q1 + q2 + q3) is
/// meant (row 1 = eq. 73 is right); `g_0` in eq. 72 is the scalar g > 0.
#[test]
fn eq72_gravity_s11bar1_is_s111() {
    let (printed, corrected) = sweep(
        5,
        |_| true,
        |p, rf, q, _| {
            let want = rf.gravity(q);
            (
                rel_err(&gravity_printed(q, p, p.g), want.as_slice()),
                rel_err(&gravity_corrected(q, p), want.as_slice()),
            )
        },
    );
    assert!(
        printed > 1e-3,
        "printed eq. 72 unexpectedly agrees: {printed:e}"
    );
    assert!(corrected < TOL, "corrected eq. 72: {corrected:e}");
    // Row 1 (eq. 73) is right as printed; rows 2-3 are wrong whenever q3 ≠ 0 (mod π) and
    // q2 ≠ 0 (mod π), i.e. the error is in the s_{11\bar1} terms only.
    let p = AppendixParams::paper();
    let rf = p.reference();
    for (q, _) in states(55, 20) {
        let g = rf.gravity(&q);
        let pr = gravity_printed(&q, &p, p.g);
        assert!((pr[0] - g[0]).abs() < TOL);
        let mut q0 = q;
        q0[2] = 0.0; // s_{11\bar1} = s_{111} when q3 = 0
        let g0 = rf.gravity(&q0);
        let pr0 = gravity_printed(&q0, &p, p.g);
        assert!(rel_err(&pr0, g0.as_slice()) < TOL);
    }
}

/// eq. 72 with `g_0` read as the z-component of g_0 = (0, 0, −g) of eq. 22b has the wrong
/// sign: the printed scalar g_0 must be the magnitude g.
#[test]
fn eq72_g0_is_the_magnitude() {
    let (as_vector_component, as_magnitude) = sweep(
        6,
        |_| true,
        |p, rf, q, _| {
            let want = rf.gravity(q);
            let mut fixed = gravity_corrected(q, p);
            let magnitude = rel_err(&fixed, want.as_slice());
            for x in fixed.iter_mut() {
                *x = -*x; // g_0 → −g
            }
            (rel_err(&fixed, want.as_slice()), magnitude)
        },
    );
    assert!(as_vector_component > 1e-3 && as_magnitude < TOL);
}

/// eq. 22b: U_f = Σ m_i g_0ᵀ p_i with g_0 = (0,0,−g) is minus the physical potential; eq. 72
/// (and docs/parameters.md, g = ∂U/∂q) needs U_f = −Σ m_i g_0ᵀ p_i.
#[test]
fn eq22b_potential_sign() {
    let h = 1e-6;
    let (printed, corrected) = sweep(
        7,
        |_| true,
        |p, rf, q, _| {
            let g = gravity_corrected(q, p);
            let mut dp = [0.0; 3];
            let mut dc = [0.0; 3];
            for k in 0..3 {
                let mut qp = *q;
                let mut qm = *q;
                qp[k] += h;
                qm[k] -= h;
                let (cp, cm) = (rf.com_positions_f64(&qp), rf.com_positions_f64(&qm));
                dp[k] = (potential_printed(p, &cp) - potential_printed(p, &cm)) / (2.0 * h);
                dc[k] = (potential_corrected(p, &cp) - potential_corrected(p, &cm)) / (2.0 * h);
            }
            (rel_err(&dp, &g), rel_err(&dc, &g))
        },
    );
    assert!(printed > 1e-3, "{printed:e}");
    assert!(corrected < 1e-8, "{corrected:e}");
    // The corrected U is the reference's U.
    for p in param_sets() {
        let rf = p.reference();
        for (q, _) in states(77, 5) {
            let u = potential_corrected(&p, &rf.com_positions_f64(&q));
            assert!((u - rf.potential(&q)).abs() < TOL * (1.0 + u.abs()));
        }
    }
}

/// eq. 23 prints d/dt(∂L/∂q̇) + ∂L/∂q; the Euler–Lagrange operator is d/dt(∂L/∂q̇) − ∂L/∂q.
/// With the printed sign the velocity terms are Ṁq̇ + ½∂(q̇ᵀMq̇)/∂q instead of C q̇; the
/// gravity term happens to come out right only because eq. 22b's sign error cancels it.
#[test]
fn eq23_euler_lagrange_sign() {
    let (printed, corrected) = sweep(
        8,
        |_| true,
        |p, rf, q, qd| {
            let dm = rf.dmass_dq(q);
            let v = DVector::from_column_slice(qd);
            let mdot_qd = (0..3).fold(DVector::zeros(3), |acc, k| acc + &dm[k] * &v * qd[k]);
            let half_grad = DVector::from_fn(3, |k, _| 0.5 * v.dot(&(&dm[k] * &v)));
            let c = coriolis_printed(q, qd, p);
            let want = DVector::from_fn(3, |i, _| (0..3).map(|j| c[i][j] * qd[j]).sum::<f64>());
            // d/dt ∂T/∂q̇ ∓ ∂T/∂q, without the q̈ and gravity terms (identical either way).
            let plus = &mdot_qd + &half_grad;
            let minus = &mdot_qd - &half_grad;
            (
                rel_err(plus.as_slice(), want.as_slice()),
                rel_err(minus.as_slice(), want.as_slice()),
            )
        },
    );
    assert!(printed > 1e-3, "{printed:e}");
    assert!(corrected < 1e-11, "{corrected:e}");
}

/// eq. 74–75 are correct as printed, for any ℓ, masses and (diagonal) inertias.
#[test]
fn eq74_75_mass_matrix_agrees() {
    let (printed, _) = sweep(
        9,
        |_| true,
        |p, rf, q, _| {
            let m = rf.mass_matrix(q);
            let want: Vec<f64> = m.transpose().iter().copied().collect();
            (rel_err(&flat3(&mass_matrix_printed(q, p)), &want), 0.0)
        },
    );
    assert!(printed < TOL, "{printed:e}");
}

/// eq. 76–79: ψ_ijk are exactly the Christoffel symbols c_ijk of docs/parameters.md (including the
/// listed zeros), so C of eq. 76 is the Christoffel-form C (Ṁ − 2C skew-symmetric).
#[test]
fn eq76_79_psi_are_christoffel_symbols() {
    let (printed, c_err) = sweep(
        10,
        |_| true,
        |p, rf, q, qd| {
            let c = rf.christoffel(q);
            let psi = psi_printed(q, p);
            let want: Vec<f64> = c.iter().flatten().flatten().copied().collect();
            let got: Vec<f64> = psi.iter().flatten().flatten().copied().collect();
            let cm = rf.coriolis_matrix(q, qd);
            let cw: Vec<f64> = cm.transpose().iter().copied().collect();
            (
                rel_err(&got, &want),
                rel_err(&flat3(&coriolis_printed(q, qd, p)), &cw),
            )
        },
    );
    assert!(printed < TOL && c_err < TOL, "{printed:e} {c_err:e}");
}

/// Appendix B's subscripts are coefficient lists (s_{xyz} = sin(x q1 + y q2 + z q3), trailing
/// zeros omitted), NOT Appendix A's joint lists: read the Appendix-A way, s_{11} would be
/// sin(2 q1) and eq. 73 would be wrong.
#[test]
fn appendix_b_subscripts_are_coefficients() {
    let p = AppendixParams::paper();
    let rf = p.reference();
    let mut worst = 0.0f64;
    for (q, _) in states(11, 20) {
        let [m1, m2, m3] = p.m;
        // Appendix-A reading: s_{11} = sin(q1 + q1), s_{1\bar1} = sin(q1 − q1) = 0,
        // s_{111} = sin(3 q1), s_{1\bar1\bar1} = sin(−q1).
        let s = |x: f64| libm::sin(x);
        let g11 = 2.0 * m1 * s(q[0])
            + (s(2.0 * q[0]) + 0.0 + 4.0 * s(q[0])) * m2
            + (s(3.0 * q[0]) + s(-q[0]) + 2.0 * s(2.0 * q[0]) + 0.0 + 4.0 * s(q[0])) * m3;
        let g1 = -p.l / 4.0 * p.g * g11;
        worst = worst.max((g1 - rf.gravity(&q)[0]).abs());
    }
    assert!(worst > 1e-3, "{worst:e}");
}
