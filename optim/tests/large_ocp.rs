//! Large sparse NLP: trapezoidal collocation of the minimum-energy double integrator with
//! 4000 intervals (12 003 variables, 8 000 equality constraints, fixed boundary variables).
//! Checked against the closed-form optimum `J* = 12`, `u*(t) = 6 − 12t`, the costates
//! `λ_p = 24`, `λ_v(t) = 12 − 24t` (discrete multipliers of the defects), and an independent
//! KKT-residual computation from the problem's own derivatives.

mod common;

use bf_optim::ipm::BarrierSettings;
use bf_optim::ipm::{
    Nlp, Settings, Solution, Status, WarmStart, check_derivatives, solve, solve_with,
};
use common::double_integrator::DoubleIntegrator;

/// ‖∇f + Jᵀλ − z_L + z_U‖_∞ and max constraint violation, computed from the problem itself.
fn kkt_residual(p: &dyn Nlp, s: &Solution) -> (f64, f64) {
    let n = p.num_variables();
    let m = p.num_constraints();
    let mut r = vec![0.0; n];
    p.gradient(&s.x, &mut r);
    let jp = p.jacobian_structure();
    let mut jv = vec![0.0; jp.len()];
    p.jacobian_values(&s.x, &mut jv);
    for (k, &(i, j)) in jp.iter().enumerate() {
        r[j] += jv[k] * s.lambda[i];
    }
    for j in 0..n {
        r[j] += -s.z_l[j] + s.z_u[j];
    }
    let mut g = vec![0.0; m];
    p.constraints(&s.x, &mut g);
    let (mut gl, mut gu) = (vec![0.0; m], vec![0.0; m]);
    p.constraint_bounds(&mut gl, &mut gu);
    let viol = (0..m).fold(0.0f64, |a, i| a.max(gl[i] - g[i]).max(g[i] - gu[i]));
    (r.iter().fold(0.0f64, |a, v| a.max(v.abs())), viol)
}

#[test]
fn double_integrator_derivatives() {
    let mut p = DoubleIntegrator::new(6);
    p.drag = 0.7;
    let x: Vec<f64> = (0..p.num_variables())
        .map(|i| 0.3 + 0.1 * libm::sin(i as f64 * 1.7))
        .collect();
    let lam: Vec<f64> = (0..p.num_constraints())
        .map(|i| libm::cos(i as f64))
        .collect();
    let rep = check_derivatives(&p, &x, 1.3, &lam, 1e-6);
    assert!(rep.max_error() < 1e-6, "{rep:?}");
}

#[test]
fn double_integrator_12k_variables_matches_closed_form() {
    let n_int = 4000;
    let p = DoubleIntegrator::new(n_int);
    assert!(p.num_variables() > 12_000);
    let sol = solve(&p, &Settings::default()).unwrap();
    assert_eq!(sol.status, Status::Solved);
    // Trapezoidal discretisation error is O(h²) = O(6e-8); J* = 12.
    assert!(
        (sol.objective - 12.0).abs() < 1e-5 * 12.0,
        "J = {}",
        sol.objective
    );
    let h = 1.0 / n_int as f64;
    // The trapezoidal scheme's endpoint controls carry an O(h) artefact (half-weighted in the
    // quadrature); interior nodes match u* to O(h²).
    for k in [0, n_int] {
        let t = k as f64 * h;
        assert!((sol.x[DoubleIntegrator::u(k)] - (6.0 - 12.0 * t)).abs() < 10.0 * h);
    }
    let mut u_err = 0.0f64;
    for k in 1..n_int {
        let t = k as f64 * h;
        u_err = u_err.max((sol.x[DoubleIntegrator::u(k)] - (6.0 - 12.0 * t)).abs());
    }
    assert!(u_err < 1e-5, "max |u − u*| = {u_err}");
    // Costates from the defect multipliers (sign convention L = f + λᵀc).
    let mut lp_err = 0.0f64;
    let mut lv_err = 0.0f64;
    for k in 0..n_int {
        let tm = (k as f64 + 0.5) * h;
        lp_err = lp_err.max((sol.lambda[2 * k] - 24.0).abs());
        lv_err = lv_err.max((sol.lambda[2 * k + 1] - (12.0 - 24.0 * tm)).abs());
    }
    assert!(
        lp_err < 1e-3 && lv_err < 1e-3,
        "costate errors {lp_err} {lv_err}"
    );
    let (du, pr) = kkt_residual(&p, &sol);
    assert!(
        du < 1e-6 && pr < 1e-8,
        "independent KKT residual: dual {du}, primal {pr}"
    );
    assert!(sol.iterations < 30, "{} iterations", sol.iterations);
}

#[test]
fn nonlinear_drag_with_active_control_bound() {
    let mut p = DoubleIntegrator::new(2000);
    p.drag = 0.5;
    p.u_max = 5.0;
    let sol = solve(&p, &Settings::default()).unwrap();
    assert_eq!(sol.status, Status::Solved);
    let (du, pr) = kkt_residual(&p, &sol);
    assert!(du < 1e-6 && pr < 1e-8, "dual {du}, primal {pr}");
    // The bound must be active at t = 0 (unconstrained u*(0) = 6 > 5) with z_U > 0.
    assert!((sol.x[DoubleIntegrator::u(0)] - 5.0).abs() < 1e-5);
    assert!(sol.z_u[DoubleIntegrator::u(0)] > 1e-6);
    // Bounding the control and adding drag can only increase the minimum energy.
    assert!(sol.objective > 12.0);
    // Warm start from the solution converges almost immediately to the same point.
    let settings = Settings {
        barrier: BarrierSettings {
            mu_init: 1e-9,
            warm_start_bound_push: 1e-9,
            warm_start_mult_bound_push: 1e-12,
            ..Default::default()
        },
        ..Settings::default()
    };
    let ws = WarmStart::from(&sol);
    let sol2 = solve_with(&p, &settings, Some(&ws), None).unwrap();
    assert_eq!(sol2.status, Status::Solved);
    assert!(
        sol2.iterations <= 3,
        "warm start took {} iterations",
        sol2.iterations
    );
    assert!((sol2.objective - sol.objective).abs() < 1e-7 * sol.objective);
}

#[test]
fn chebyshev_collocation_derivatives() {
    let mut p = common::cheb::ChebDoubleIntegrator::new(2, 2, 5);
    p.drag = 0.4;
    let x: Vec<f64> = (0..p.num_variables())
        .map(|i| 0.2 + 0.3 * libm::sin(i as f64 * 0.77))
        .collect();
    let lam: Vec<f64> = (0..p.num_constraints())
        .map(|i| libm::cos(i as f64 * 1.3))
        .collect();
    let rep = check_derivatives(&p, &x, 0.9, &lam, 1e-6);
    assert!(rep.max_error() < 1e-6, "{rep:?}");
}

/// 3 axes × 80 segments × 30 LGR nodes: 21 609 variables, 14 400 constraints with dense
/// 30 × 31 differentiation blocks. The optimal states are cubic polynomials, which the
/// LGR collocation represents exactly, so J matches the closed form to near machine precision.
#[test]
fn chebyshev_collocation_21k_variables_matches_closed_form() {
    let p = common::cheb::ChebDoubleIntegrator::new(3, 80, 30);
    assert!(p.num_variables() > 20_000);
    let sol = solve(&p, &Settings::default()).unwrap();
    assert_eq!(sol.status, Status::Solved);
    let jstar = p.closed_form();
    assert!(
        (sol.objective - jstar).abs() < 1e-7 * jstar,
        "J = {}, J* = {jstar}",
        sol.objective
    );
    let mut u_err = 0.0f64;
    for node in 0..p.nodes() - 1 {
        let t = p.time(node);
        for a in 0..3 {
            u_err = u_err.max((sol.x[p.u(node, a)] - 6.0 * p.distance[a] * (1.0 - 2.0 * t)).abs());
        }
    }
    // The first LGR weight of each segment is 2/N² (times h/2), so the dual-infeasibility
    // tolerance allows ~1e-4 errors in those controls; J itself is accurate to ~1e-12.
    assert!(u_err < 1e-3, "max |u − u*| = {u_err}");
    let (du, pr) = kkt_residual(&p, &sol);
    assert!(
        du < 1e-6 && pr < 1e-8,
        "independent KKT residual: dual {du}, primal {pr}"
    );
}

#[test]
fn chebyshev_exact_solution_is_feasible() {
    let p = common::cheb::ChebDoubleIntegrator::new(3, 4, 30);
    let mut x = vec![0.0; p.num_variables()];
    for node in 0..p.nodes() {
        let t = p.time(node);
        for a in 0..3 {
            let d = p.distance[a];
            x[p.p(node, a)] = d * (3.0 * t * t - 2.0 * t * t * t);
            x[p.v(node, a)] = 6.0 * d * (t - t * t);
            // the final node's control enters no equation (see cheb.rs): optimal value 0
            x[p.u(node, a)] = if node + 1 == p.nodes() {
                0.0
            } else {
                6.0 * d * (1.0 - 2.0 * t)
            };
        }
    }
    let mut g = vec![0.0; p.num_constraints()];
    p.constraints(&x, &mut g);
    let viol = g.iter().fold(0.0f64, |a, v| a.max(v.abs()));
    assert!(viol < 1e-10, "{viol}");
    assert!(
        (p.objective(&x) - p.closed_form()).abs() < 1e-10,
        "{}",
        p.objective(&x)
    );
}

/// `solve` keeps the KKT solver of the thread's last solve (its symbolic analysis is reused
/// for the same pattern): a solve after one of the same structure, and one after a solve of
/// another structure, give bit for bit the solution of a solve with a fresh workspace, so
/// results do not depend on what the thread solved before.
#[test]
fn reused_analysis_changes_no_result() {
    use bf_optim::ipm::{Workspace, solve_in};
    let settings = Settings::default();
    let (small, large) = (DoubleIntegrator::new(40), DoubleIntegrator::new(60));
    let fresh = solve_in(&mut Workspace::new(), &small, &settings, None, None).unwrap();
    assert_eq!(fresh.status, Status::Solved);
    let first = solve(&small, &settings).unwrap();
    let again = solve(&small, &settings).unwrap();
    solve(&large, &settings).unwrap();
    let after_other = solve(&small, &settings).unwrap();
    for s in [&first, &again, &after_other] {
        assert_eq!(s.iterations, fresh.iterations);
        assert_eq!(s.objective.to_bits(), fresh.objective.to_bits());
        assert!(
            s.x.iter()
                .zip(&fresh.x)
                .all(|(a, b)| a.to_bits() == b.to_bits())
        );
        assert!(
            s.lambda
                .iter()
                .zip(&fresh.lambda)
                .all(|(a, b)| a.to_bits() == b.to_bits())
        );
    }
}
