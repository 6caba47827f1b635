//! Newton steps along a flat valley: a problem whose Hessian has a stiff and a nearly flat
//! eigendirection (condition number 1e12) needs a step far longer than its right-hand side.
//! A backward-stable solve of such a step leaves a residual of order `ε ‖K‖ ‖step‖`, so
//! measured against `‖rhs‖` alone the exact Newton step looks inaccurate; the inertia
//! correction then damps it with δ_w, and the solve creeps along the valley and stops
//! `Acceptable` short of the optimum. Judging such a solve again by its normwise backward
//! error (`Settings::backward_error_tol`, the default), or measuring the residual against
//! `‖rhs‖ + ‖step‖` (Ipopt's residual ratio, `Settings::residual_ratio_with_solution`), takes
//! the steps undamped. The second test checks that the backward-error test changes no result
//! of the Hock–Schittkowski suite (objective as given and × 1e8, × 1e12).

mod hs;

use bf_optim::ipm::{ExperimentalSettings, LinearSolverSettings, Settings, Status, solve};
use hs::Hs;
use hs::dual::D;

const INF: f64 = f64::INFINITY;

/// Stiffness across the valley and along it: eigenvalues `2 A` and `2 B` of the Hessian.
const A: f64 = 1e6;
const B: f64 = 1e-6;

/// `f = A/2 (x₁ − x₂)² + B/2 (x₁ + x₂ − 2)²` (+ `x₃²/2` bounded below, or constrained by
/// `x₃ = x₁ − x₂`), minimum 0 at `x₁ = x₂ = 1`; the start lies on the valley floor far from it.
fn valley(constrained: bool) -> Hs {
    fn f(x: &[D]) -> D {
        let d = x[0] - x[1];
        let s = x[0] + x[1] - 2.0;
        0.5 * A * d * d + 0.5 * B * s * s + 0.5 * x[2] * x[2]
    }
    fn c(x: &[D]) -> Vec<D> {
        vec![x[2] - (x[0] - x[1])]
    }
    fn none(_: &[D]) -> Vec<D> {
        Vec::new()
    }
    Hs {
        name: "flat valley",
        tags: "",
        x0: vec![1e4, 1e4, 0.5],
        xl: vec![-INF, -INF, if constrained { -INF } else { 0.0 }],
        xu: vec![INF; 3],
        neq: usize::from(constrained),
        m: usize::from(constrained),
        f,
        g: if constrained { c } else { none },
        fstar: 0.0,
        xstar: Some(vec![1.0, 1.0, 0.0]),
    }
}

/// The default: the backward-error test at 1e-14 (decision record 0008).
fn backward() -> Settings {
    let s = Settings::default();
    assert_eq!(s.linear_solver.backward_error_tol, 1e-14);
    s
}

/// The relative-residual test alone.
fn relative_only() -> Settings {
    Settings {
        linear_solver: LinearSolverSettings {
            backward_error_tol: 0.0,
            ..Default::default()
        },
        ..Settings::default()
    }
}

#[test]
fn newton_steps_along_a_flat_valley_are_taken_undamped() {
    let ratio = Settings {
        experimental: ExperimentalSettings {
            residual_ratio_with_solution: true,
            ..Default::default()
        },
        ..Settings::default()
    };
    for constrained in [false, true] {
        for (label, settings) in [("backward error", backward()), ("ratio", ratio.clone())] {
            let sol = solve(&valley(constrained), &settings).unwrap();
            assert_eq!(
                sol.status,
                Status::Solved,
                "{label}, constrained {constrained}: {sol:?}"
            );
            // The quadratic model is exact: Newton needs a handful of steps, the barrier
            // updates of the bounded variant a few dozen, not hundreds of damped steps along
            // the valley.
            assert!(
                sol.iterations <= 40,
                "{label}, constrained {constrained}: {} iterations",
                sol.iterations
            );
            for (x, want) in sol.x.iter().zip([1.0, 1.0, 0.0]) {
                assert!(
                    (x - want).abs() < 1e-4,
                    "{label}, constrained {constrained}: x = {:?}",
                    sol.x
                );
            }
        }
    }
    // Without either, the relative test damps the exact steps of the constrained valley and
    // the solve stops short of the optimum; the default run rests on the solves only the
    // backward-error test accepts.
    let sol = solve(&valley(true), &backward()).unwrap();
    assert!(
        sol.counters.backward_error_accepts > 0,
        "{:?}",
        sol.counters
    );
    let plain = solve(&valley(true), &relative_only()).unwrap();
    assert!(
        plain.status != Status::Solved || (plain.x[0] - 1.0).abs() > 1e-4,
        "{plain:?}"
    );
}

/// Every Hock–Schittkowski problem, with its objective as given and multiplied by 1e8 and
/// 1e12, ends with the same status and optimum with and without the backward-error test.
#[test]
fn the_backward_error_test_keeps_every_hock_schittkowski_result() {
    let off = hs::sweep_scaled_objectives(&relative_only());
    let on = hs::sweep_scaled_objectives(&backward());
    assert!(
        off.iter()
            .all(|(_, _, a)| a.counters.backward_error_accepts == 0)
    );
    hs::assert_same_results(&off, &on, "with the test");
    // The comparison covers solves the test changes (2 measured).
    let accepts: usize = on
        .iter()
        .map(|(_, _, b)| b.counters.backward_error_accepts)
        .sum();
    assert!(accepts > 0, "no KKT solve accepted on its backward error");
}
