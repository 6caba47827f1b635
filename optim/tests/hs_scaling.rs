//! Termination under objective scaling and the statuses it may produce, on Hock–Schittkowski
//! problems: objectives multiplied by 1e-8, 1e8 and 1e12 end at the unscaled solution (with
//! the unscaled status at 1e±8), an all-boxed
//! problem is never `Unbounded` however large its objective, and a `Solved` run reports a
//! complementarity within `compl_inf_tol` (measured, as the test is, against the relaxed
//! bounds).

mod hs;

use bf_optim::ipm::{Settings, Status, solve};
use hs::{Hs, Transformed};

/// An HS problem with its objective multiplied by `c`.
fn obj_scaled(hs: Hs, c: f64) -> Transformed {
    Transformed {
        obj: c,
        ..Transformed::new(hs)
    }
}

fn by_name(name: &str) -> Hs {
    hs::all().into_iter().find(|p| p.name == name).unwrap()
}

/// A problem with every variable boxed cannot be unbounded: each all-boxed HS problem with a
/// negative optimum, its objective scaled so that f* becomes −1e17 (far below the −1e15 of
/// the unboundedness test), must not end `Unbounded`.
#[test]
fn boxed_problems_with_a_huge_objective_are_not_unbounded() {
    let mut checked = 0;
    for p in hs::all() {
        let boxed = p.xl.iter().chain(&p.xu).all(|v| v.is_finite());
        if !boxed || p.fstar >= -1e-3 {
            continue;
        }
        let (name, c) = (p.name, 1e17 / p.fstar.abs());
        let sol = solve(&obj_scaled(p, c), &Settings::default()).unwrap();
        assert_ne!(sol.status, Status::Unbounded, "{name}: {sol:?}");
        checked += 1;
    }
    assert!(checked >= 2, "{checked} all-boxed problems with f* < 0");
}

/// Every `Solved` HS run reports a complementarity within the tolerance it was tested
/// against.
#[test]
fn solved_runs_report_complementarity_within_tolerance() {
    let settings = Settings::default();
    let mut solved = 0;
    for p in hs::all() {
        let sol = solve(&p, &settings).unwrap();
        if sol.status == Status::Solved {
            solved += 1;
            assert!(
                sol.complementarity <= settings.compl_inf_tol,
                "{}: complementarity {:e}",
                p.name,
                sol.complementarity
            );
        }
    }
    assert!(solved >= 40, "{solved} Solved");
}

/// Objective multiplied by 1e-8, 1e8 or 1e12: the gradient-based objective scaling brings a
/// large objective down without a floor and a tiny one up (gradient ∞-norm below
/// `scaling_min_gradient` → 1), and the μ floor follows the scaled complementarity tolerance,
/// so every run ends at the unscaled solution, with the unscaled run's status at 1e±8 and
/// successful at 1e12. HS083 and HS106 are all-boxed, badly scaled problems (objective ≈ 3e4
/// and 7e3 at the optimum).
#[test]
fn objective_scales_keep_status_and_solution() {
    for name in ["HS014", "HS043", "HS065", "HS071", "HS083", "HS106"] {
        let base = solve(&by_name(name), &Settings::default()).unwrap();
        assert_eq!(base.status, Status::Solved, "{name}");
        for c in [1e-8, 1e8, 1e12] {
            let sol = solve(&obj_scaled(by_name(name), c), &Settings::default()).unwrap();
            if c < 1e12 {
                assert_eq!(sol.status, base.status, "{name} x{c:e}");
            } else {
                // The unscaled complementarity test (`compl_inf_tol` = 1e-4, absolute in the
                // user's units, as Ipopt's) asks for s z ≤ 1e-4 with multipliers ~1e13: on
                // HS071 the slack of the active bound x₁ ≥ 1 would have to fall below 1e-16,
                // under the spacing of doubles at 1, so it rounds to 0 at the μ floor and the
                // run ends Acceptable (with z_L = inf reported for that bound).
                assert!(sol.status.is_success(), "{name} x{c:e}: {:?}", sol.status);
            }
            let dx = sol
                .x
                .iter()
                .zip(&base.x)
                .map(|(a, b)| (a - b).abs() / (1.0 + b.abs()))
                .fold(0.0, f64::max);
            assert!(dx < 1e-6, "{name} x{c:e}: x differs by {dx:e}");
            let rel = (sol.objective / c - base.objective).abs() / base.objective.abs().max(1.0);
            // f is flat to first order at the optimum only along the constraints: an x within
            // 1e-8 of the unscaled one moves f by up to ~1e-7 on these problems.
            assert!(
                rel < 1e-7,
                "{name} x{c:e}: f/c = {}, unscaled {} (x differs by {dx:e})",
                sol.objective / c,
                base.objective
            );
        }
    }
}
