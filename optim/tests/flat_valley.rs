//! Newton steps along a flat valley: a problem whose Hessian has a stiff and a nearly flat
//! eigendirection (condition number 1e12) needs a step far longer than its right-hand side.
//! A backward-stable solve of such a step leaves a residual of order `ε ‖K‖ ‖step‖`, so the
//! accuracy test of the KKT solve must measure the residual against `‖rhs‖ + ‖step‖`
//! (`Settings::residual_ratio_with_solution`, Ipopt's residual ratio); measured against
//! `‖rhs‖` alone, the exact Newton step is rejected as inaccurate, the inertia correction
//! damps it with δ_w, and the solve creeps along the valley and can stop `Acceptable` short
//! of the optimum.

mod hs;

use bf_optim::ipm::{Settings, Status, solve};
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

#[test]
fn newton_steps_along_a_flat_valley_are_taken_undamped() {
    for constrained in [false, true] {
        let settings = Settings {
            residual_ratio_with_solution: true,
            ..Settings::default()
        };
        let sol = solve(&valley(constrained), &settings).unwrap();
        assert_eq!(
            sol.status,
            Status::Solved,
            "constrained {constrained}: {sol:?}"
        );
        // The quadratic model is exact: Newton needs a handful of steps, the barrier updates
        // of the bounded variant a few dozen, not hundreds of damped steps along the valley.
        assert!(
            sol.iterations <= 40,
            "constrained {constrained}: {} iterations",
            sol.iterations
        );
        for (x, want) in sol.x.iter().zip([1.0, 1.0, 0.0]) {
            assert!(
                (x - want).abs() < 1e-4,
                "constrained {constrained}: x = {:?}",
                sol.x
            );
        }
    }
}
