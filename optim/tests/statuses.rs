//! Termination statuses and API behaviour on small problems whose answer is known by hand:
//! infeasible → `LocallyInfeasible`, unbounded → `DivergingIterates`/`Unbounded`, NaN trial
//! points are cut by the line search, callbacks, warm starts, fixed variables, range constraints,
//! scaling invariance and input validation.

mod hs;

use bf_optim::OptimError;
use bf_optim::ipm::{
    BarrierSettings, IterationInfo, LinearSolverSettings, Nlp, NlpScaling, RecoverySettings,
    ScalingMethod, ScalingSettings, Settings, Solution, Status, TerminationSettings, WarmStart,
    solve, solve_with,
};
use hs::Hs;
use hs::dual::D;

const INF: f64 = f64::INFINITY;

fn none(_: &[D]) -> Vec<D> {
    Vec::new()
}

/// Every number of a `Solution` is finite, whatever its status.
fn assert_finite(sol: &Solution) {
    let finite = sol
        .x
        .iter()
        .chain(&sol.lambda)
        .chain(&sol.z_l)
        .chain(&sol.z_u)
        .chain(&[
            sol.objective,
            sol.constraint_violation,
            sol.dual_infeasibility,
            sol.complementarity,
            sol.mu,
        ])
        .all(|v| v.is_finite());
    assert!(finite, "non-finite value in {sol:?}");
}

fn problem(
    x0: &[f64],
    xl: &[f64],
    xu: &[f64],
    neq: usize,
    m: usize,
    f: fn(&[D]) -> D,
    g: fn(&[D]) -> Vec<D>,
) -> Hs {
    Hs {
        name: "custom",
        tags: "",
        x0: x0.to_vec(),
        xl: xl.to_vec(),
        xu: xu.to_vec(),
        neq,
        m,
        f,
        g,
        fstar: f64::NAN,
        xstar: None,
    }
}

#[test]
fn infeasible_inequalities_are_detected() {
    // x₁² + x₂² ≤ 1 and x₁ + x₂ ≥ 3 cannot both hold (max of x₁+x₂ on the disc is √2).
    let p = problem(
        &[0.0, 0.0],
        &[-INF; 2],
        &[INF; 2],
        0,
        2,
        |x| x[0] * x[0] + x[1] * x[1],
        |x| vec![1.0 - x[0] * x[0] - x[1] * x[1], x[0] + x[1] - 3.0],
    );
    let sol = solve(&p, &Settings::default()).unwrap();
    assert_eq!(sol.status, Status::LocallyInfeasible, "{sol:?}");
    assert_finite(&sol);
    assert!(sol.iterations < 200);
    // The infeasibility minimiser lies on the diagonal between the disc and the half-plane.
    assert!((sol.x[0] - sol.x[1]).abs() < 1e-3, "{:?}", sol.x);
}

/// min x s.t. x² + 1 = 0 from x = 3: no real solution; the infeasibility is stationary at x = 0.
fn no_real_root() -> Hs {
    problem(
        &[3.0],
        &[-INF],
        &[INF],
        1,
        1,
        |x| x[0],
        |x| vec![x[0] * x[0] + 1.0],
    )
}

#[test]
fn infeasible_equality_is_detected() {
    // x² + 1 = 0 has no real solution; the infeasibility is stationary at x = 0.
    let p = no_real_root();
    let sol = solve(&p, &Settings::default()).unwrap();
    assert_eq!(sol.status, Status::LocallyInfeasible, "{sol:?}");
    assert_finite(&sol);
    assert!(sol.x[0].abs() < 1e-3);
    assert!(sol.iterations < 200);
}

/// The default settings with the restoration phase switched off.
fn without_restoration() -> Settings {
    Settings {
        recovery: RecoverySettings {
            restoration: false,
            ..Default::default()
        },
        ..Default::default()
    }
}

/// The recovery chain in its order: with the restoration phase switched off, an infeasible
/// problem stops at the chain's "give up" link, on the very iteration at which, with it on, the
/// chain's last link (the restoration phase) takes over and proves the problem infeasible; the
/// iterations before are the same solve.
#[test]
fn without_restoration_the_chain_gives_up_where_the_restoration_phase_would_start() {
    let p = no_real_root();
    let mut first_restoration = None;
    let mut on_log = Vec::new();
    let mut record = |info: &IterationInfo| {
        if info.restoration && first_restoration.is_none() {
            first_restoration = Some(info.iter);
        }
        if !info.restoration {
            on_log.push((info.iter, info.objective.to_bits()));
        }
        true
    };
    let on = solve_with(&p, &Settings::default(), None, Some(&mut record)).unwrap();
    assert_eq!(on.status, Status::LocallyInfeasible, "{on:?}");
    assert!(on.counters.restoration_iterations > 0);
    let first_restoration = first_restoration.expect("a restoration phase");

    let off_settings = without_restoration();
    let mut off_log = Vec::new();
    let mut record = |info: &IterationInfo| {
        off_log.push((info.iter, info.objective.to_bits()));
        true
    };
    let off = solve_with(&p, &off_settings, None, Some(&mut record)).unwrap();
    assert_eq!(off.status, Status::RestorationFailed, "{off:?}");
    assert_eq!(off.counters.restoration_iterations, 0);
    assert_eq!(off.iterations, first_restoration);
    assert_eq!(off_log[..], on_log[..off_log.len()]);
}

#[test]
fn infeasible_bounds_and_linear_constraint() {
    // 0 ≤ x ≤ 1 (both) with x₁ + x₂ = 3.
    let p = problem(
        &[0.5, 0.5],
        &[0.0; 2],
        &[1.0; 2],
        1,
        1,
        |x| x[0] * x[1],
        |x| vec![x[0] + x[1] - 3.0],
    );
    let sol = solve(&p, &Settings::default()).unwrap();
    assert_eq!(sol.status, Status::LocallyInfeasible, "{sol:?}");
    assert_finite(&sol);
    assert!(sol.iterations < 200);
}

/// min −x₁ − x₂ s.t. x₁ − x₂ = 0, x ≥ 0: unbounded below along x₁ = x₂ → ∞.
fn diagonal_unbounded() -> Hs {
    problem(
        &[1.0, 2.0],
        &[0.0; 2],
        &[INF; 2],
        1,
        1,
        |x| -x[0] - x[1],
        |x| vec![x[0] - x[1]],
    )
}

#[test]
fn unbounded_problems_report_divergence() {
    let p = diagonal_unbounded();
    let sol = solve(&p, &Settings::default()).unwrap();
    assert!(
        matches!(sol.status, Status::DivergingIterates | Status::Unbounded),
        "{:?}",
        sol.status
    );
    assert!(sol.iterations < 200);
    assert_finite(&sol);
    // Unconstrained cubic, unbounded below.
    let p = problem(&[0.0], &[-INF], &[INF], 0, 0, |x| x[0].powi(3) + x[0], none);
    let sol = solve(&p, &Settings::default()).unwrap();
    assert!(
        matches!(sol.status, Status::DivergingIterates | Status::Unbounded),
        "{:?}",
        sol.status
    );
    assert!(sol.iterations < 200);
    assert_finite(&sol);
}

/// The problem unbounded below along x₁ = x₂ → ∞ (free of any upper bound) is `Unbounded`
/// with its objective multiplied by 1, 1e-8, 1e8 or 1e12: the test is on the scaled objective,
/// which gradient-based scaling makes the same for the three scaled variants; every number
/// of the `Solution` is finite.
#[test]
fn unbounded_problems_stay_unbounded_under_objective_scaling() {
    for c in [1.0, 1e-8, 1e8, 1e12] {
        let p = diagonal_unbounded();
        let t = hs::Transformed {
            obj: c,
            ..hs::Transformed::new(p)
        };
        let sol = solve(&t, &Settings::default()).unwrap();
        assert_eq!(sol.status, Status::Unbounded, "objective × {c:e}: {sol:?}");
        assert!(sol.x[0] > 1e10 && sol.x[1] > 1e10, "{:?}", sol.x);
        assert_finite(&sol);
    }
}

#[test]
fn non_finite_trial_points_are_cut() {
    // f = x ln x is NaN for x < 0; Newton from x = 3 overshoots to x < 0 (step −(ln 3 + 1)·3).
    let p = problem(&[3.0], &[-INF], &[INF], 0, 0, |x| x[0] * x[0].ln(), none);
    let sol = solve(&p, &Settings::default()).unwrap();
    assert_eq!(sol.status, Status::Solved);
    assert_finite(&sol);
    let e = std::f64::consts::E;
    assert!((sol.x[0] - 1.0 / e).abs() < 1e-7);
    assert!((sol.objective + 1.0 / e).abs() < 1e-12);
}

#[test]
fn non_finite_initial_point_is_an_error() {
    let p = problem(&[-1.0], &[-INF], &[INF], 0, 0, |x| x[0].sqrt(), none);
    assert!(matches!(
        solve(&p, &Settings::default()),
        Err(OptimError::NonFinite { .. })
    ));
}

#[test]
fn invalid_input_is_rejected() {
    let p = problem(&[0.0], &[1.0], &[0.0], 0, 0, |x| x[0], none);
    assert!(matches!(
        solve(&p, &Settings::default()),
        Err(OptimError::InvalidBounds { .. })
    ));
    let p = problem(&[0.0], &[-INF], &[INF], 0, 0, |x| x[0] * x[0], none);
    let bad = Settings {
        barrier: BarrierSettings {
            tau_min: 1.5,
            ..Default::default()
        },
        ..Settings::default()
    };
    assert!(matches!(
        solve(&p, &bad),
        Err(OptimError::InvalidSetting { .. })
    ));
    // The KKT accuracy settings: each out-of-range value is named.
    for (name, bad) in [
        (
            "refinement_contraction",
            Settings {
                linear_solver: LinearSolverSettings {
                    refinement_contraction: 1.0,
                    ..Default::default()
                },
                ..Settings::default()
            },
        ),
        (
            "refinement_tol",
            Settings {
                linear_solver: LinearSolverSettings {
                    refinement_tol: f64::NAN,
                    ..Default::default()
                },
                ..Settings::default()
            },
        ),
        (
            "backward_error_tol",
            Settings {
                linear_solver: LinearSolverSettings {
                    backward_error_tol: -1e-14,
                    ..Default::default()
                },
                ..Settings::default()
            },
        ),
        (
            "backward_error_forcing",
            Settings {
                linear_solver: LinearSolverSettings {
                    backward_error_forcing: 0.0,
                    ..Default::default()
                },
                ..Settings::default()
            },
        ),
        (
            "pivot_pairs_check_max_delta_w",
            Settings {
                linear_solver: LinearSolverSettings {
                    pivot_pairs_check_max_delta_w: f64::NAN,
                    ..Default::default()
                },
                ..Settings::default()
            },
        ),
    ] {
        match solve(&p, &bad) {
            Err(OptimError::InvalidSetting { name: n, .. }) => assert_eq!(n, name),
            other => panic!("{name}: {other:?}"),
        }
    }
    let ws = WarmStart {
        x: vec![0.0; 2],
        lambda: vec![],
        z_l: vec![0.0],
        z_u: vec![0.0],
    };
    assert!(matches!(
        solve_with(&p, &Settings::default(), Some(&ws), None),
        Err(OptimError::DimensionMismatch { .. })
    ));
}

fn hs071() -> Hs {
    hs::all().into_iter().find(|p| p.name == "HS071").unwrap()
}

#[test]
fn callback_sees_every_iteration_and_can_stop() {
    let p = hs071();
    let mut seen: Vec<IterationInfo> = Vec::new();
    let mut cb = |i: &IterationInfo| {
        seen.push(*i);
        true
    };
    let sol = solve_with(&p, &Settings::default(), None, Some(&mut cb)).unwrap();
    assert_eq!(sol.status, Status::Solved);
    assert_eq!(seen.len(), sol.iterations + 1);
    assert!(seen.windows(2).all(|w| w[1].iter == w[0].iter + 1));
    let mut stop = |i: &IterationInfo| i.iter < 3;
    let sol = solve_with(&p, &Settings::default(), None, Some(&mut stop)).unwrap();
    assert_eq!(sol.status, Status::UserStop);
    assert_eq!(sol.iterations, 3);
}

#[test]
fn iteration_and_time_limits() {
    let p = hs071();
    let sol = solve(
        &p,
        &Settings {
            termination: TerminationSettings {
                max_iter: 2,
                ..Default::default()
            },
            ..Settings::default()
        },
    )
    .unwrap();
    assert_eq!(sol.status, Status::MaxIterations);
    assert_eq!(sol.iterations, 2);
    let sol = solve(
        &p,
        &Settings {
            termination: TerminationSettings {
                max_wall_time: 1e-12,
                ..Default::default()
            },
            ..Settings::default()
        },
    )
    .unwrap();
    assert_eq!(sol.status, Status::MaxTime);
}

#[test]
fn warm_start_converges_immediately() {
    let p = hs071();
    let sol = solve(&p, &Settings::default()).unwrap();
    let s = Settings {
        barrier: BarrierSettings {
            mu_init: 1e-9,
            warm_start_bound_push: 1e-9,
            warm_start_mult_bound_push: 1e-12,
            ..Default::default()
        },
        ..Settings::default()
    };
    let sol2 = solve_with(&p, &s, Some(&WarmStart::from(&sol)), None).unwrap();
    assert_eq!(sol2.status, Status::Solved);
    assert!(sol2.iterations <= 2, "{} iterations", sol2.iterations);
    assert!((sol2.objective - 17.0140173).abs() < 1e-6);
}

#[test]
fn fixed_variables_and_their_multipliers() {
    // HS071 with x₁ fixed at its optimal value 1 has the same optimum; the fixed variable's
    // multiplier is the reduced gradient ∂f/∂x₁ + λᵀ ∂g/∂x₁ (checked independently).
    let mut p = hs071();
    p.xl[0] = 1.0;
    p.xu[0] = 1.0;
    let sol = solve(&p, &Settings::default()).unwrap();
    assert_eq!(sol.status, Status::Solved);
    assert!((sol.objective - 17.0140173).abs() < 1e-6);
    let mut grad = vec![0.0; 4];
    p.gradient(&sol.x, &mut grad);
    let mut jv = vec![0.0; 8];
    p.jacobian_values(&sol.x, &mut jv);
    let red = grad[0] + sol.lambda[0] * jv[0] + sol.lambda[1] * jv[4];
    assert!((sol.z_l[0] - sol.z_u[0] - red).abs() < 1e-8);
    // HS071's unfixed optimum also has x₁ at its lower bound with the same multiplier.
    let free = solve(&hs071(), &Settings::default()).unwrap();
    assert!(
        (sol.z_l[0] - free.z_l[0]).abs() < 1e-5,
        "{} vs {}",
        sol.z_l[0],
        free.z_l[0]
    );
}

/// min (x−2)² + (y−1)² s.t. 0 ≤ x + y ≤ 1 (a two-sided range row): the solution is the
/// projection (1, 0) of (2, 1) onto x + y = 1, f = 2, multiplier λ = 2 on the upper side.
struct Range;
impl Nlp for Range {
    fn num_variables(&self) -> usize {
        2
    }
    fn num_constraints(&self) -> usize {
        1
    }
    fn variable_bounds(&self, l: &mut [f64], u: &mut [f64]) {
        l.fill(-1e20);
        u.fill(1e20);
    }
    fn constraint_bounds(&self, l: &mut [f64], u: &mut [f64]) {
        l[0] = 0.0;
        u[0] = 1.0;
    }
    fn initial_point(&self, x: &mut [f64]) {
        x.fill(0.0);
    }
    fn objective(&self, x: &[f64]) -> f64 {
        (x[0] - 2.0).powi(2) + (x[1] - 1.0).powi(2)
    }
    fn gradient(&self, x: &[f64], g: &mut [f64]) {
        g[0] = 2.0 * (x[0] - 2.0);
        g[1] = 2.0 * (x[1] - 1.0);
    }
    fn constraints(&self, x: &[f64], g: &mut [f64]) {
        g[0] = x[0] + x[1];
    }
    fn jacobian_structure(&self) -> Vec<(usize, usize)> {
        vec![(0, 0), (0, 1)]
    }
    fn jacobian_values(&self, _x: &[f64], v: &mut [f64]) {
        v.fill(1.0);
    }
    fn hessian_structure(&self) -> Vec<(usize, usize)> {
        vec![(0, 0), (1, 1)]
    }
    fn hessian_values(&self, _x: &[f64], s: f64, _l: &[f64], v: &mut [f64]) {
        v.fill(2.0 * s);
    }
}

#[test]
fn two_sided_range_constraint_and_infinite_bounds() {
    let sol = solve(&Range, &Settings::default()).unwrap();
    assert_eq!(sol.status, Status::Solved);
    assert!(
        (sol.x[0] - 1.0).abs() < 1e-7 && sol.x[1].abs() < 1e-7,
        "{:?}",
        sol.x
    );
    assert!((sol.objective - 2.0).abs() < 1e-7);
    // ∇f + λ∇g = 0 at (1, 0): (−2, −2) + λ(1, 1) = 0 → λ = 2.
    assert!((sol.lambda[0] - 2.0).abs() < 1e-6, "{:?}", sol.lambda);
    assert!(sol.dual_infeasibility < 1e-7 && sol.constraint_violation < 1e-8);
}

/// HS071 with the objective multiplied by 1e4 and constraints by 1e3 (same minimiser).
fn scaled(hs: Hs) -> hs::Transformed {
    hs::Transformed {
        obj: 1e4,
        con: 1e3,
        ..hs::Transformed::new(hs)
    }
}

#[test]
fn gradient_scaling_handles_badly_scaled_functions() {
    let base = solve(&hs071(), &Settings::default()).unwrap();
    for scaling in [ScalingMethod::GradientBased, ScalingMethod::None] {
        let sol = solve(
            &scaled(hs071()),
            &Settings {
                scaling: ScalingSettings {
                    method: scaling,
                    ..Default::default()
                },
                ..Settings::default()
            },
        )
        .unwrap();
        assert!(sol.status.is_success(), "{scaling:?}: {:?}", sol.status);
        for j in 0..4 {
            assert!(
                (sol.x[j] - base.x[j]).abs() < 1e-5,
                "{scaling:?}: {:?} vs {:?}",
                sol.x,
                base.x
            );
        }
        // multipliers scale back: λ_scaled = λ · 1e4 / 1e3
        assert!(
            (sol.lambda[0] - 10.0 * base.lambda[0]).abs() < 1e-4 * base.lambda[0].abs().max(1.0)
        );
    }
}

#[test]
fn workspace_reuse_gives_identical_results_and_handles_pattern_changes() {
    use bf_optim::ipm::{Workspace, solve_in};
    let mut ws = Workspace::new();
    let p = hs071();
    let a = solve_in(&mut ws, &p, &Settings::default(), None, None).unwrap();
    let b = solve_in(&mut ws, &p, &Settings::default(), None, None).unwrap();
    assert_eq!(a.x, b.x);
    assert_eq!(a.iterations, b.iterations);
    // a different structure through the same workspace is re-analysed
    let q = hs::all().into_iter().find(|p| p.name == "HS100").unwrap();
    let c = solve_in(&mut ws, &q, &Settings::default(), None, None).unwrap();
    assert_eq!(c.status, Status::Solved);
    assert!((c.objective - 680.6300573).abs() < 1e-6 * 680.0);
    let d = solve_in(&mut ws, &p, &Settings::default(), None, None).unwrap();
    assert_eq!(a.x, d.x);
}

/// A restoration phase starts with the solvers the last one handed back (decision record
/// 0072): the workspace keeps the restoration problem's analysis (a pattern the outer run's
/// solver never sees), a second solve through it analyses nothing, and both are bit for bit
/// the solve with a fresh workspace.
#[test]
fn restoration_phases_take_their_analyses_back() {
    use bf_optim::ipm::{Workspace, solve_in};
    let p = no_real_root();
    let settings = Settings::default();
    let fresh = solve_in(&mut Workspace::new(), &p, &settings, None, None).unwrap();
    assert!(fresh.counters.restoration_iterations > 0, "{fresh:?}");
    // The same solve up to the restoration phase analyses the problem's patterns only.
    let without = without_restoration();
    let mut outer_only = Workspace::new();
    solve_in(&mut outer_only, &p, &without, None, None).unwrap();
    let mut ws = Workspace::new();
    let first = solve_in(&mut ws, &p, &settings, None, None).unwrap();
    let analysed = ws.analyses();
    // ... and the restoration problem's pattern (three times the variables) is kept besides.
    assert!(
        analysed > outer_only.analyses(),
        "{analysed} analyses kept, {} without restoration",
        outer_only.analyses()
    );
    let second = solve_in(&mut ws, &p, &settings, None, None).unwrap();
    assert_eq!(ws.analyses(), analysed, "the second solve analysed again");
    // Everything but the timings: status, point, multipliers, iterations and counters.
    let untimed = |s: &Solution| Solution {
        timing: Default::default(),
        ..s.clone()
    };
    assert_eq!(untimed(&first), untimed(&fresh));
    assert_eq!(untimed(&second), untimed(&fresh));
}

/// The inertia correction ends only when δ_w exceeds `max_hessian_perturbation`, so an
/// increase factor ≤ 1, or a smallest δ_w of 0 (from which δ_w may restart at 0), would
/// factor the same matrix forever; the KKT regularizations must be finite and ≥ 0. Each out-of-range value is refused by name before the solve starts.
#[test]
fn recovery_and_regularization_settings_are_refused_by_name() {
    let p = problem(&[0.0], &[-INF], &[INF], 0, 0, |x| x[0] * x[0], none);
    let recovery = |r: RecoverySettings| Settings {
        recovery: r,
        ..Settings::default()
    };
    let mut cases: Vec<(&str, f64, Settings)> = Vec::new();
    for v in [1.0, 0.5, 0.0, -8.0, f64::NAN, f64::INFINITY] {
        let r = RecoverySettings {
            perturb_inc_fact: v,
            ..Default::default()
        };
        cases.push(("perturb_inc_fact", v, recovery(r)));
        let r = RecoverySettings {
            perturb_inc_fact_first: v,
            ..Default::default()
        };
        cases.push(("perturb_inc_fact_first", v, recovery(r)));
    }
    for v in [0.0, -1e-20, f64::NAN, f64::INFINITY] {
        let r = RecoverySettings {
            min_hessian_perturbation: v,
            ..Default::default()
        };
        cases.push(("min_hessian_perturbation", v, recovery(r)));
    }
    for v in [-1e-9, f64::NAN, f64::INFINITY] {
        let l = LinearSolverSettings {
            static_dual_regularization: v,
            ..Default::default()
        };
        let s = Settings {
            linear_solver: l,
            ..Settings::default()
        };
        cases.push(("static_dual_regularization", v, s));
        let r = RecoverySettings {
            jacobian_regularization_value: v,
            ..Default::default()
        };
        cases.push(("jacobian_regularization_value", v, recovery(r)));
        let r = RecoverySettings {
            jacobian_regularization_exponent: v,
            ..Default::default()
        };
        cases.push(("jacobian_regularization_exponent", v, recovery(r)));
    }
    for (name, v, s) in &cases {
        match s.validate() {
            Err(OptimError::InvalidSetting { name: n, .. }) => assert_eq!(n, *name, "{v}"),
            other => panic!("{name} = {v}: {other:?}"),
        }
        match solve(&p, s) {
            Err(OptimError::InvalidSetting { name: n, .. }) => assert_eq!(n, *name, "{v}"),
            other => panic!("{name} = {v}: {other:?}"),
        }
    }
    // The limits themselves: any factor above 1, and regularizations of 0.
    let s = Settings {
        recovery: RecoverySettings {
            perturb_inc_fact: 1.0 + 1e-12,
            perturb_inc_fact_first: 1.5,
            jacobian_regularization_value: 0.0,
            jacobian_regularization_exponent: 0.0,
            ..Default::default()
        },
        linear_solver: LinearSolverSettings {
            static_dual_regularization: 0.0,
            ..Default::default()
        },
        ..Settings::default()
    };
    assert_eq!(s.validate(), Ok(()));
}

/// A warm start with a non-finite entry is refused, naming the vector and the entry. On a
/// problem with a linear constraint the Hessian does not see the multipliers, so a NaN λ
/// would otherwise reach the dual infeasibility unchecked.
#[test]
fn a_non_finite_warm_start_is_refused_by_entry() {
    let sol = solve(&Range, &Settings::default()).unwrap();
    assert_eq!(sol.status, Status::Solved);
    // Which entry to spoil, and how.
    type Spoil = fn(&mut WarmStart);
    let cases: [(&str, usize, Spoil); 4] = [
        ("warm-start lambda", 0, |w| w.lambda[0] = f64::NAN),
        ("warm-start x", 1, |w| w.x[1] = f64::INFINITY),
        ("warm-start z_l", 1, |w| w.z_l[1] = f64::NAN),
        ("warm-start z_u", 0, |w| w.z_u[0] = f64::NEG_INFINITY),
    ];
    for (what, index, spoil) in cases {
        let mut warm = WarmStart::from(&sol);
        spoil(&mut warm);
        match solve_with(&Range, &Settings::default(), Some(&warm), None) {
            Err(OptimError::InvalidValue {
                what: w,
                index: i,
                value,
                ..
            }) => {
                assert_eq!((w, i), (what, index));
                assert!(!value.is_finite());
            }
            other => panic!("{what}[{index}]: {other:?}"),
        }
    }
    // The unspoilt warm start is accepted.
    let warm = WarmStart::from(&sol);
    let again = solve_with(&Range, &Settings::default(), Some(&warm), None).unwrap();
    assert_eq!(again.status, Status::Solved);
}

/// A constraint that is NaN everywhere but at the initial point: every trial point is cut,
/// and the solve ends without success at the only point where it is finite (never `Solved`).
/// The steps that leave x where it is (α ≈ 1e-16) are taken until the line search fails;
/// then each restoration phase stops at once (its start is acceptable to the filter) and hands
/// the run back where it was, which without the repetition test looped forever, with no
/// iteration for `max_iter` to count.
#[test]
fn a_constraint_that_turns_nan_is_never_solved() {
    let p = problem(
        &[0.5],
        &[-INF],
        &[INF],
        0,
        1,
        |x| (x[0] - 2.0).powi(2),
        |x| {
            vec![if x[0].a == 0.5 {
                1.0 - x[0]
            } else {
                D::cst(f64::NAN)
            }]
        },
    );
    for settings in [Settings::default(), without_restoration()] {
        let sol = solve(&p, &settings).unwrap();
        assert_eq!(sol.status, Status::RestorationFailed, "{sol:?}");
        assert_eq!(sol.x, [0.5]);
        assert!(sol.iterations < settings.termination.max_iter);
        assert_finite(&sol);
    }
}

/// The reported constraint violation is measured at the returned x, the final iterate
/// projected onto the bounds. Here the iterates approach the bound x ≥ 0 from inside its
/// relaxation (x > −1e-8) and the projection lands on x = 0, where g is NaN: the violation is
/// NaN, not the 0 that `f64::max` would leave after dropping it.
#[test]
fn a_nan_constraint_at_the_returned_point_is_a_nan_violation() {
    let p = problem(
        &[1.0],
        &[0.0],
        &[INF],
        0,
        1,
        |x| x[0],
        |x| {
            vec![if x[0].a == 0.0 {
                D::cst(f64::NAN)
            } else {
                x[0] + 1.0
            }]
        },
    );
    let sol = solve(&p, &Settings::default()).unwrap();
    assert_eq!(sol.x, [0.0], "{sol:?}");
    assert!(sol.constraint_violation.is_nan(), "{sol:?}");
    // Where g is finite at the returned point, the violation is a number as before.
    let q = problem(&[1.0], &[0.0], &[INF], 0, 1, |x| x[0], |x| vec![x[0] + 1.0]);
    let sol = solve(&q, &Settings::default()).unwrap();
    assert_eq!(sol.status, Status::Solved);
    assert_eq!(sol.constraint_violation, 0.0);
}

/// A user scaling factor that is not positive and finite is an error naming it, as a wrong
/// length is, instead of being replaced by 1.
#[test]
fn an_invalid_user_scaling_factor_is_refused_by_index() {
    let user = Settings {
        scaling: ScalingSettings {
            method: ScalingMethod::User,
            ..Default::default()
        },
        ..Settings::default()
    };
    let with = |objective: f64, constraints: Vec<f64>| hs::Transformed {
        scaling: Some(NlpScaling {
            objective,
            constraints,
        }),
        ..hs::Transformed::new(hs071())
    };
    for (what, index, p) in [
        ("constraint scaling", 1, with(1.0, vec![1.0, 0.0])),
        ("constraint scaling", 0, with(1.0, vec![-2.0, 1.0])),
        ("constraint scaling", 1, with(1.0, vec![1.0, f64::NAN])),
        ("objective scaling", 0, with(f64::INFINITY, vec![1.0, 1.0])),
        ("objective scaling", 0, with(0.0, vec![1.0, 1.0])),
    ] {
        match solve(&p, &user) {
            Err(OptimError::InvalidValue {
                what: w, index: i, ..
            }) => assert_eq!((w, i), (what, index)),
            other => panic!("{what}[{index}]: {other:?}"),
        }
    }
    let good = with(0.5, vec![2.0, 1e-3]);
    assert_eq!(solve(&good, &user).unwrap().status, Status::Solved);
}
