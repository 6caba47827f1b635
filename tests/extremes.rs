//! Stability at the extremes: the assertions behind every row of
//! `ball_finger::paper::extremes::run_extremes`. Each test compares against something the code
//! under test does not produce itself: a double-double evaluation (≈ 106 bits) of the same
//! expression graph, an exact scaling law of eq. 22 (M is linear in the masses and quadratic in
//! the lengths), an exact static equilibrium (a finger pressed on with force f has λ = f n), a
//! closed form (Painlevé threshold from the contact matrices, the blow-up law
//! λ_n = f / (1 − μ_k/μ_k*)), a known truncation order (eq. 59), or energy conservation.
//!
//! Tolerance notes:
//! - Kernels at |q| = 1e6 rad vs double-double at the SAME q: ≤ 1e-12 relative (sin/cos of a
//!   single joint angle with a correct argument reduction, then O(1) arithmetic).
//! - Kernels at q reduced mod 2π in f64: the reduction itself is off by k·(2π − fl(2π)) ≈
//!   1e5 · 2.4e-16 ≈ 2e-11 rad at |q| = 1e6 (the f64 `rem_euclid` is exact, fl(2π) is not), so
//!   the reduced-angle results can only agree to that level: asserted ≤ 1e-9, and ≤ 100× the
//!   measured reduction error.

use ball_finger::paper::extremes::*;
use bf_codegen::spec::Scene;
use bf_model::{ModelError, PainleveKind};

fn paper_graph() -> GraphEval {
    let scene = Scene::from_toml_str(bf_generated::paper::SCENE_TOML, "paper").unwrap();
    GraphEval::new(&scene).unwrap()
}

fn human_graph() -> GraphEval {
    let scene = Scene::from_toml_str(bf_generated::human::SCENE_TOML, "human").unwrap();
    GraphEval::new(&scene).unwrap()
}

#[test]
fn kernels_accurate_at_huge_joint_angles() {
    let g = paper_graph();
    for qm in [1.0, 1e3, 1e6] {
        let a = kernel_accuracy(&g, qm);
        for (name, e) in [
            ("M", a.m),
            ("cqd_g", a.cqd_g),
            ("mass_cqd_g", a.cqd_g_model),
            ("h", a.h),
            ("J_c", a.j_c),
        ] {
            assert!(
                e <= 1e-12,
                "|q| = {qm:e}: {name} rel. error {e:e} vs double-double"
            );
        }
        for (i, e) in a.reduced.iter().enumerate() {
            assert!(
                e.is_finite() && *e <= 1e-9,
                "|q| = {qm:e}: reduced[{i}] = {e:e}"
            );
            assert!(
                *e <= 100.0 * a.reduction_error + 1e-13,
                "|q| = {qm:e}: reduced[{i}] = {e:e} exceeds what the reduction error {:e} explains",
                a.reduction_error
            );
        }
    }
    // at 1e6 the reduction really loses digits (so the same-q comparison is the meaningful one)
    let a = kernel_accuracy(&g, 1e6);
    assert!(a.reduction_error > 1e-13, "{:e}", a.reduction_error);
}

#[test]
fn coriolis_at_tiny_and_huge_velocities() {
    let g = paper_graph();
    for v in [1e-12, 1.0, 1e3] {
        let a = velocity_extremes(&g, v);
        assert!(a.cqd <= 1e-12, "|q̇| {v:e}: rel. error {:e}", a.cqd);
        assert!(
            a.homogeneity <= 1e-13,
            "|q̇| {v:e}: homogeneity {:e}",
            a.homogeneity
        );
        assert!(a.magnitude > 0.0 && a.magnitude.is_finite());
    }
}

#[test]
fn scaled_scenes_follow_similarity_laws_and_stay_spd() {
    let g = paper_graph();
    let base = scaled_scene(&g, 1.0, 1.0).unwrap();
    assert!(
        base.m_eig_ratio > 1e-3,
        "paper M eigen ratio {}",
        base.m_eig_ratio
    );
    for (km, kl) in [
        (1e-3, 1.0),
        (1e3, 1.0),
        (1.0, 1e-3),
        (1.0, 1e3),
        (1e-3, 1e3),
    ] {
        let s = scaled_scene(&g, km, kl).unwrap();
        for (i, e) in s.f64_vs_dd.iter().enumerate() {
            assert!(*e <= 1e-12, "({km:e}, {kl:e}) f64 vs dd [{i}] = {e:e}");
        }
        // M(k_m, k_L) = k_m k_L² M: the eigenvalue ratio is scale-free and M stays SPD
        assert!(s.m_eig_min > 0.0);
        assert!(
            (s.m_eig_ratio - base.m_eig_ratio).abs() <= 1e-10 * base.m_eig_ratio,
            "({km:e}, {kl:e}): ratio {} vs {}",
            s.m_eig_ratio,
            base.m_eig_ratio
        );
        for (i, e) in s.law_deviation.iter().enumerate() {
            assert!(
                *e <= 1e-13,
                "({km:e}, {kl:e}) scaling law [{i}] deviates by {e:e}"
            );
        }
    }
}

#[test]
fn lengths_alone_scale_the_translational_part_quadratically() {
    for k in [1e-3, 1e3] {
        let (dev, ratio) = length_only_mass_law(k).unwrap();
        assert!(
            dev <= 1e-12,
            "k = {k:e}: M(k) deviates from k²A + B by {dev:e}"
        );
        assert!(ratio > 0.0, "k = {k:e}: M not SPD (ratio {ratio})");
    }
    // the rotational part B is not negligible, so this is not just the similarity law:
    // with lengths ×1e-3 M is dominated by B, whose eigen ratio differs from the paper M's
    let (_, small) = length_only_mass_law(1e-3).unwrap();
    let (_, large) = length_only_mass_law(1e3).unwrap();
    assert!((small - large).abs() > 1e-2, "{small} vs {large}");
}

#[test]
fn compiled_human_scene_with_scaled_link3_mass() {
    let g = human_graph();
    for k in [1e-3, 1.0, 1e3] {
        let h = human_link3_mass(&g, k).unwrap();
        assert!(h.m_vs_dd <= 1e-13, "k = {k:e}: {:e}", h.m_vs_dd);
        assert!(h.cqd_g_vs_dd <= 1e-13, "k = {k:e}: {:e}", h.cqd_g_vs_dd);
        assert!(
            h.affine_deviation <= 1e-12,
            "k = {k:e}: {:e}",
            h.affine_deviation
        );
        assert!(h.m_eig_ratio > 0.0);
        assert!(h.qdd_norm.is_finite() && h.qdd_norm > 0.0);
    }
}

#[test]
fn singular_contact_is_a_typed_error_and_regular_nearby() {
    // exactly singular: links 2-3 aligned, pointing at the ball centre
    let s0 = singular_contact(0.0).unwrap();
    assert!(
        s0.jc_singular_values[0] <= 1e-14 * s0.jc_singular_values[2],
        "{:?}",
        s0.jc_singular_values
    );
    assert!(s0.normal_mobility <= 1e-20, "{:e}", s0.normal_mobility);
    assert!(
        matches!(s0.stick, Err(ModelError::SingularContact { .. })),
        "{:?}",
        s0.stick
    );
    // rank loss is first order in δ for σ_min(J_c), second order for nᵀWn
    let a = singular_contact(1e-8).unwrap();
    let b = singular_contact(1e-6).unwrap();
    let r1 = b.jc_singular_values[0] / a.jc_singular_values[0];
    let r2 = b.normal_mobility / a.normal_mobility;
    assert!((r1 / 100.0 - 1.0).abs() < 1e-3, "σ_min ratio {r1}");
    assert!((r2 / 1e4 - 1.0).abs() < 1e-2, "nᵀWn ratio {r2}");
    // regular configurations: the pressed static finger has λ = 1 N · n exactly
    for (d, tol) in [(1e-4, 1e-6), (1e-2, 1e-10), (1e-1, 1e-12)] {
        let s = singular_contact(d).unwrap();
        let (ln, err) = s.stick.clone().unwrap_or_else(|e| panic!("δ = {d:e}: {e}"));
        assert!(
            (ln - 1.0).abs() <= tol && err <= tol,
            "δ = {d:e}: λ_n {ln}, |λ − n| {err:e}"
        );
    }
    // the switch between error and number is sharp and located by bisection
    let d = singular_threshold().unwrap();
    assert!(d > 1e-7 && d < 1e-4, "δ* = {d:e}");
    assert!(matches!(
        singular_contact(0.9 * d).unwrap().stick,
        Err(ModelError::SingularContact { .. })
    ));
    let (ln, _) = singular_contact(1.1 * d).unwrap().stick.unwrap();
    assert!((ln - 1.0).abs() < 1e-3, "λ_n just above δ*: {ln}");
}

#[test]
fn slip_at_vanishing_relative_velocity() {
    let qc = paper_contact_configuration().unwrap();
    let reference = slip_small_dv(qc, 1e-9).unwrap();
    let mu_k = 0.6; // scenes/paper.toml
    for s in [1e-2, 1e-4, 1e-6, 1e-8, 1e-10, 1e-12, 1e-14] {
        let p = slip_small_dv(qc, s).unwrap();
        // eq. 20: |λ_∥| = μ_k λ_n, along Δv; λ_n > 0 (pressed on)
        assert!(p.lambda_n > 0.1, "s = {s:e}: λ_n {}", p.lambda_n);
        assert!(
            (p.lambda_t_norm - mu_k * p.lambda_n).abs() <= 1e-12 * p.lambda_n,
            "s = {s:e}: |λ_∥| {} vs μ_k λ_n {}",
            p.lambda_t_norm,
            mu_k * p.lambda_n
        );
        assert!(
            p.friction_angle <= 1e-7,
            "s = {s:e}: angle {:e}",
            p.friction_angle
        );
        // eq. 38 (division-free) holds to rounding at every |Δv|
        assert!(
            p.law_residual <= 1e-14,
            "s = {s:e}: residual {:e}",
            p.law_residual
        );
        // the force has a finite limit as |Δv| → 0 (q̇ = 0: ω enters only quadratically)
        let rel = (p.lambda_hint - reference.lambda_hint).norm() / reference.lambda_hint.norm();
        assert!(rel <= 1e-12, "s = {s:e}: λ moved by {rel:e}");
        // no hint: a number while |Δv| exceeds slip_direction_tol (1e-12), then a typed error
        match &p.lambda {
            Ok(l) => {
                assert!(s >= 1e-12, "s = {s:e} should need a hint");
                assert!((l - p.lambda_hint).norm() <= 1e-12 * l.norm());
            }
            Err(e) => {
                assert!(s < 1e-12, "s = {s:e}: {e}");
                assert!(
                    matches!(e, ModelError::UndefinedSlipDirection { .. }),
                    "{e}"
                );
            }
        }
        // Slip → Stick: fires below slip_eps = 1e-6 (|Δv| decreasing under friction)
        if s >= 1e-4 {
            assert!(!p.slip_to_stick, "s = {s:e}");
        }
        if s <= 1e-8 {
            assert!(p.slip_to_stick, "s = {s:e}");
        }
    }
}

#[test]
fn smooth_saturation_converges_with_the_expected_orders() {
    let eps = [1e-1, 1e-2, 1e-3, 1e-4];
    // interior: sat_ε − sat = O(ε²); h_ε − h = O(ε⁴) since r_c ⟂ e_x3 (eq. 1)
    let e: Vec<SmoothError> = eps
        .iter()
        .map(|&x| smooth_convergence(Q_INTERIOR, x))
        .collect();
    assert!(
        e[0].alpha > -1.0 + 0.1 && e[0].alpha < -0.1,
        "α = {}",
        e[0].alpha
    );
    let oh = observed_orders(&e.iter().map(|x| (x.eps, x.h)).collect::<Vec<_>>(), 1e-13);
    let op = observed_orders(&e.iter().map(|x| (x.eps, x.p_c)).collect::<Vec<_>>(), 1e-13);
    assert!(
        !oh.is_empty() && oh.iter().all(|&o| o >= 1.9),
        "h orders {oh:?}"
    );
    assert!(
        op.len() >= 2 && op.iter().all(|&o| (o - 2.0).abs() < 0.1),
        "p_c orders {op:?}"
    );
    // sat_ε − sat for −l < α < 0, l = 1: ε²/4 (1/(α + l) − 1/|α|) to leading order (the two
    // √(y² + ε²) corrections of eq. 59 enter with opposite signs)
    let alpha: f64 = e[3].alpha;
    let predicted = (1e-8 / 4.0 * (1.0 / (alpha + 1.0) - 1.0 / alpha.abs())).abs();
    assert!(
        (e[3].sat / predicted - 1.0).abs() < 1e-3,
        "{} vs {predicted}",
        e[3].sat
    );
    // p_c moves by (sat_ε − sat) e_x3 (eq. 3): its max-norm error is at most the sat error
    assert!(e.iter().all(|x| x.p_c <= x.sat * (1.0 + 1e-12) + 1e-16));
    // saturated (tip contact, α > 0): O(ε²) for both
    let qc = paper_contact_configuration().unwrap();
    let qa: [f64; 3] = qc.into();
    let e: Vec<SmoothError> = eps.iter().map(|&x| smooth_convergence(qa, x)).collect();
    assert!(e[0].alpha > 0.0);
    let oh = observed_orders(&e.iter().map(|x| (x.eps, x.h)).collect::<Vec<_>>(), 1e-13);
    assert!(
        oh.iter().all(|&o| (o - 2.0).abs() < 0.1),
        "tip h orders {oh:?}"
    );
    // finite down to ε = 1e-12
    for x in [1e-6, 1e-8, 1e-10, 1e-12] {
        assert!(smooth_convergence(Q_INTERIOR, x).finite);
        assert!(smooth_convergence(qa, x).finite);
    }
}

#[test]
fn smooth_saturation_at_the_exact_corners() {
    let g = corner_graph().unwrap();
    for at_tip in [true, false] {
        let mut prev = None;
        for eps in [1e-1, 1e-2, 1e-4, 1e-6, 1e-8, 1e-10, 1e-12] {
            let (alpha, sat_err, h_err, finite) = smooth_corner(&g, at_tip, eps);
            assert_eq!(
                alpha,
                if at_tip { 0.0 } else { -1.0 },
                "corner not hit exactly"
            );
            assert!(finite, "NaN at the corner, ε = {eps:e}");
            // at a corner the smoothing error is first order: ½(√(l² + ε²) − l + ε) → ε/2
            let exact = 0.5 * (eps - ((1.0f64 + eps * eps).sqrt() - 1.0));
            assert!(
                (sat_err - exact).abs() <= 1e-15 + 1e-12 * exact,
                "ε {eps:e}: {sat_err:e} vs {exact:e}"
            );
            // h is second order: r_c ⟂ e_x3 at the corner (|r_c| = 0.5), so the smooth p_c
            // is off by sat_err along e_x3 and h_ε − h = √(0.25 + sat_err²) − 0.5 exactly
            let h_exact = sat_err * sat_err / ((0.25 + sat_err * sat_err).sqrt() + 0.5);
            assert!(
                (h_err - h_exact).abs() <= 2e-16 + 1e-9 * h_exact,
                "ε {eps:e}: {h_err:e} vs {h_exact:e}"
            );
            if let Some(p) = prev {
                assert!(sat_err < p);
            }
            prev = Some(sat_err);
        }
    }
    // the model at the exact corner: a number while ε² does not underflow, else a typed error
    for eps in [1e-12, 1e-100, 1e-160] {
        let (ln, err) = corner_stick(eps).unwrap().unwrap();
        assert!(
            (ln - 1.0).abs() <= 1e-12 && err <= 1e-12,
            "ε {eps:e}: λ_n {ln}, {err:e}"
        );
    }
    for eps in [1e-200, 1e-300] {
        match corner_stick(eps).unwrap() {
            Ok((ln, err)) => assert!((ln - 1.0).abs() <= 1e-12 && err <= 1e-12),
            Err(e) => assert!(matches!(e, ModelError::NonFinite { .. }), "ε {eps:e}: {e}"),
        }
    }
}

#[test]
fn painleve_threshold_matches_the_closed_form() {
    let qc = paper_contact_configuration().unwrap();
    let p = painleve_threshold(qc).unwrap();
    let rel = (p.threshold_bisection - p.threshold_closed_form).abs() / p.threshold_closed_form;
    assert!(
        rel <= 1e-10,
        "bisection {} vs closed form {}",
        p.threshold_bisection,
        p.threshold_closed_form
    );
    assert!(p.threshold_closed_form > 0.0 && p.threshold_closed_form < 1e3);
    // below: λ_n = f / (1 − μ_k/μ₀*) with f = 1 N, μ₀* = μ_k*/(1 − margin) (finite, blows up)
    let mu0 = p.threshold_closed_form / (1.0 - 1e-9);
    for (frac, ln) in &p.below {
        let predicted = 1.0 / (1.0 - frac * p.threshold_bisection / mu0);
        assert!(
            (ln / predicted - 1.0).abs() <= 1e-6,
            "μ/μ* = {frac}: λ_n {ln} vs {predicted}"
        );
    }
    // above: the typed error (pushed finger: no consistent force)
    for (mu, res) in &p.above {
        match res {
            Err(ModelError::Painleve {
                kind,
                effective_inverse_mass,
                ..
            }) => {
                assert_eq!(*kind, PainleveKind::Inconsistent, "μ_k = {mu}");
                assert!(*effective_inverse_mass < 0.0);
            }
            other => panic!("μ_k = {mu}: expected Painlevé, got {other:?}"),
        }
    }
}

#[test]
fn free_motion_energy_drift_shrinks_with_rtol() {
    let mut prev = f64::INFINITY;
    for rtol in [1e-6, 1e-8, 1e-10] {
        let h = long_horizon(10.0, rtol).unwrap();
        assert_eq!(h.events, 0, "the finger must not reach the ball");
        assert!(
            h.drift.is_finite() && h.drift < 100.0 * rtol,
            "rtol {rtol:e}: drift {:e}",
            h.drift
        );
        assert!(
            h.drift < prev,
            "drift must decrease with rtol: {:e} !< {prev:e}",
            h.drift
        );
        assert!(h.steps > 10 && h.steps < 100_000, "steps {}", h.steps);
        prev = h.drift;
    }
}

#[test]
#[ignore = "slow: 100 s horizon"]
fn free_motion_energy_drift_over_100_s() {
    let mut prev = f64::INFINITY;
    for rtol in [1e-6, 1e-8, 1e-10] {
        let h = long_horizon(100.0, rtol).unwrap();
        assert_eq!(h.events, 0);
        assert!(h.drift < 1e3 * rtol, "rtol {rtol:e}: drift {:e}", h.drift);
        assert!(h.drift < prev);
        prev = h.drift;
    }
}

#[test]
fn report_has_no_failures_and_renders() {
    let r = run_extremes(true).unwrap();
    let md = r.to_markdown();
    assert!(r.failures().is_empty(), "{md}");
    assert!(
        md.contains("All probes returned a finite number or a clear error"),
        "{md}"
    );
    let table = &md[md.find("| case |").expect("table header")..];
    assert!(!table.contains("NaN") && !table.contains("FAILED"), "{md}");
    // every table row has exactly the 6 columns (all '|' inside cells are escaped)
    for line in table.lines() {
        let cells = line.replace("\\|", "").matches('|').count();
        assert_eq!(cells, 7, "broken row: {line}");
    }
    for case in [
        "kernel accuracy",
        "joint velocity",
        "scaled scene",
        "scaled link3.mass",
        "singular contact",
        "slip with",
        "smooth sat",
        "large μ_k",
        "long horizon",
    ] {
        assert!(
            r.rows.iter().any(|row| row.case.starts_with(case)),
            "no rows for {case}"
        );
    }
    // the documented clear errors are present
    let errors = r
        .rows
        .iter()
        .filter(|row| matches!(row.outcome, Outcome::ClearError { .. }))
        .count();
    assert!(errors >= 6, "{errors} clear-error rows");
    assert!(r.seconds < 60.0);
}
