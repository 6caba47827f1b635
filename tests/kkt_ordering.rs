//! The KKT elimination order on the periodic collocation problems: with each constraint row
//! that AMD would eliminate with the bare pivot −δ_c delayed to a variable of its own and
//! eliminated with it as a 2 × 2 pivot ([`KktOrdering::AmdPivotPairs`]), or with AMD on
//! (variable, row) pairs ([`KktOrdering::ConstraintsAfterVariables`]), and the solver's static
//! dual regularization δ_c = 1e-9 for both schemes, the periodic problems end Solved in one
//! stage on hp-Radau and Legendre–Gauss meshes where plain AMD with δ_c = 1e-9 stalls or ends
//! Acceptable (the factor reports spurious negative pivots and the inertia correction keeps
//! δ_w > 0).

use ball_finger::pipeline::verify::verify;
use ball_finger::pipeline::{build, solve};
use bf_optim::ipm::{KktOrdering, LineSearchSettings, LinearSolverSettings, Settings, Status};
use bf_optim::ocp::Scheme;
use bf_problem::{OcpSolution, Problem, ProblemSettings};
use std::time::Duration;

/// Solves `name` on `scheme` with `points` per phase, KKT `ordering` and static dual
/// regularization `delta_c` (`None` for both: the library's default handling; the residual
/// ratio with `SWEEP_RATIO=1` and the extrapolation along negative curvature up to α =
/// `SWEEP_EXTRAPOLATION`, on every barrier problem with `SWEEP_EVERY_BARRIER=1`, and the
/// proximal weight `SWEEP_PROXIMAL`, see [`mesh_sweep`]).
fn run(
    name: &str,
    scheme: Scheme,
    points: usize,
    ordering: Option<KktOrdering>,
    delta_c: Option<f64>,
) -> OcpSolution {
    let refinement_steps: Option<usize> = std::env::var("SWEEP_REFINEMENT_STEPS")
        .ok()
        .map(|v| v.parse().expect("SWEEP_REFINEMENT_STEPS"));
    let ipm = (ordering.is_some() || refinement_steps.is_some()).then(|| {
        let mut ipm = Settings::default();
        if let Some(kkt_ordering) = ordering {
            ipm.experimental.kkt_ordering = kkt_ordering;
        }
        if let Some(steps) = refinement_steps {
            ipm.linear_solver.max_refinement_steps = steps;
        }
        ipm
    });
    let s = ProblemSettings {
        points,
        scheme,
        ipm,
        dual_regularization: delta_c,
        kkt_residual_ratio: std::env::var("SWEEP_RATIO").is_ok_and(|v| v == "1"),
        curvature_extrapolation: std::env::var("SWEEP_EXTRAPOLATION")
            .ok()
            .map(|v| v.parse().expect("SWEEP_EXTRAPOLATION")),
        extrapolate_every_barrier: std::env::var("SWEEP_EVERY_BARRIER").is_ok_and(|v| v == "1"),
        proximal_weight: std::env::var("SWEEP_PROXIMAL")
            .ok()
            .map(|v| v.parse().expect("SWEEP_PROXIMAL")),
        ..ProblemSettings::default()
    };
    let problem: Problem = name.parse().unwrap();
    solve(&build(problem, &s).unwrap(), None).unwrap()
}

fn label(scheme: Scheme, points: usize) -> String {
    match scheme {
        Scheme::Radau { elements } => format!("Radau {elements}x{}", points / elements),
        Scheme::Lg => format!("LG-{points}"),
    }
}

/// ", N stages" for a solve that needed the guess fallback, else nothing (a sweep cell).
fn stages_note(sol: &OcpSolution) -> String {
    if sol.stages.len() > 1 {
        format!(", {} stages", sol.stages.len())
    } else {
        String::new()
    }
}

/// The iteration at which the solve raised its static δ_c, or "–" (a sweep cell).
fn raised_at(sol: &OcpSolution) -> String {
    sol.counters
        .dual_regularization_raised_at
        .map_or("–".to_string(), |k| k.to_string())
}

/// Meshes where plain AMD with δ_c = 1e-9 does not end Solved (`periodic-cot` 3 × 12 stalls,
/// `periodic-qc` 3 × 16 ends Acceptable, LG-30 needed δ_c = 3e-8): with 2 × 2 pivots on the
/// rows AMD would eliminate bare each ends Solved in one stage with δ_c = 1e-9.
#[test]
fn pivot_pairs_solve_fine_meshes_with_the_default_regularization() {
    for (name, scheme, points) in [
        ("periodic-cot", Scheme::Radau { elements: 3 }, 36),
        ("periodic-qc", Scheme::Radau { elements: 3 }, 48),
        ("periodic-qc", Scheme::Lg, 30),
    ] {
        let sol = run(
            name,
            scheme,
            points,
            Some(KktOrdering::AmdPivotPairs),
            Some(1e-9),
        );
        println!(
            "{name} {}: {:?} in {} iterations, J = {:.10}",
            label(scheme, points),
            sol.status,
            sol.iterations,
            sol.objective
        );
        assert_eq!(sol.status, Status::Solved, "{name}: {:?}", sol.stages);
        assert_eq!(sol.stages.len(), 1, "{name}: {:?}", sol.stages);
    }
}

/// The pivot-pair check of a rejected AMD factor is skipped where its δ_w exceeds
/// `pivot_pairs_check_max_delta_w` (decision record 0031): on `periodic-qc` Radau 3 × 10 the
/// checks it skips would all have confirmed the rejection, so the solve is the one that checks
/// every rejection, bit for bit (objective, iterations, pivot-pair accepts), with fewer
/// factorizations.
#[test]
fn pivot_pair_checks_at_a_large_delta_w_only_confirm_the_rejection() {
    let with = |max_delta_w: f64| {
        periodic_qc(
            ProblemSettings::default(),
            LinearSolverSettings {
                pivot_pairs_check_max_delta_w: max_delta_w,
                ..Default::default()
            },
        )
    };
    let default = with(LinearSolverSettings::default().pivot_pairs_check_max_delta_w);
    let everywhere = with(f64::MAX);
    assert_eq!(default.status, Status::Solved);
    assert_eq!(default.objective.to_bits(), everywhere.objective.to_bits());
    assert_eq!(default.iterations, everywhere.iterations);
    assert_eq!(
        default.counters.dual_regularization_raised_at,
        everywhere.counters.dual_regularization_raised_at
    );
    assert!(
        default.counters.factorizations < everywhere.counters.factorizations,
        "{} factorizations, {} when every rejection is checked",
        default.counters.factorizations,
        everywhere.counters.factorizations
    );
}

/// The speculative factorization on a second core (decision record 0036) changes no path: a
/// cold `periodic-qc` solve on both meshes with it (the default) and without it ends at the
/// same objective and point (bits), after the same iterations, with the same counters
/// (factorizations, rejections, pivot-pair checks); with two or more cores the second thread
/// did factor.
#[test]
fn speculative_factorization_changes_no_path() {
    let radau = ProblemSettings::default();
    for (scheme, points) in [(radau.scheme, radau.points), (Scheme::Lg, 30)] {
        let with = |speculative: bool| {
            periodic_qc_on(
                (scheme, points),
                LinearSolverSettings {
                    speculative_factorization: speculative,
                    // The shared factorization replaces speculation on LG (record 0090).
                    parallel_factorization: false,
                    ..Default::default()
                },
            )
        };
        let (on, off) = (with(true), with(false));
        let what = label(scheme, points);
        assert_same_path(&on, &off, &what);
        assert!(
            off.counters.rejected_factorizations > 0,
            "{what}: no retry to speculate on"
        );
        assert_eq!(
            off.timing.speculative_factorization,
            Duration::ZERO,
            "{what}"
        );
        if std::thread::available_parallelism().map_or(1, usize::from) >= 2 {
            assert!(
                on.timing.speculative_factorization > Duration::ZERO,
                "{what}"
            );
        }
    }
}

/// The factorization shared with a second core (decision record 0090) changes no path: a cold
/// LG-30 `periodic-qc` solve with it (the default) and without it ends at the same objective
/// and point (bits), after the same iterations, with the same counters; with two or more
/// cores the default LG-30 solve does not speculate, which it does only where the
/// factorization is not shared. Radau 3 × 10, whose main kernel has nothing to share, keeps
/// its path either way. (That the kernel shares, bit for bit, is checked on its own:
/// `bf-optim`'s `a_factor_shared_between_two_threads_is_the_factor_of_one`.)
#[test]
fn a_shared_factorization_changes_no_path() {
    let cores = std::thread::available_parallelism().map_or(1, usize::from);
    let radau = ProblemSettings::default();
    let mut lg_off_objective = f64::NAN;
    for (scheme, points) in [(Scheme::Lg, 30), (radau.scheme, radau.points)] {
        let with = |parallel: bool| {
            periodic_qc_on(
                (scheme, points),
                LinearSolverSettings {
                    parallel_factorization: parallel,
                    speculative_factorization: false,
                    ..Default::default()
                },
            )
        };
        let (on, off) = (with(true), with(false));
        let what = label(scheme, points);
        if scheme == Scheme::Lg {
            lg_off_objective = off.objective;
        }
        assert_same_path(&on, &off, &what);
    }
    // With the defaults (both on), LG-30 shares its factorization instead of speculating
    // (Radau's speculation: `speculative_factorization_changes_no_path`).
    if cores >= 2 {
        let lg = periodic_qc_on((Scheme::Lg, 30), LinearSolverSettings::default());
        assert_eq!(lg.objective.to_bits(), lg_off_objective.to_bits(), "LG-30");
        assert_eq!(lg.timing.speculative_factorization, Duration::ZERO, "LG-30");
    }
}

/// Two solves of one problem took the same path: solved, at the same objective and joint
/// angles (bits), after the same iterations, with the same counters.
fn assert_same_path(on: &OcpSolution, off: &OcpSolution, what: &str) {
    assert_eq!(on.status, Status::Solved, "{what}");
    assert_eq!(on.objective.to_bits(), off.objective.to_bits(), "{what}");
    assert_eq!(on.iterations, off.iterations, "{what}");
    assert_eq!(on.counters, off.counters, "{what}");
    for (a, b) in on
        .nodes
        .q
        .iter()
        .flatten()
        .zip(off.nodes.q.iter().flatten())
    {
        assert_eq!(a.to_bits(), b.to_bits(), "{what}: a joint angle differs");
    }
}

/// [`periodic_qc`] on the default mesh of `(scheme, points)`.
fn periodic_qc_on(
    (scheme, points): (Scheme, usize),
    linear_solver: LinearSolverSettings,
) -> OcpSolution {
    let mesh = ProblemSettings {
        scheme,
        points,
        ..ProblemSettings::default()
    };
    periodic_qc(mesh, linear_solver)
}

/// A cold `periodic-qc` solve with the mesh of `mesh`, the cold solve's tolerance (1e-8) and
/// these linear-solver settings.
fn periodic_qc(mesh: ProblemSettings, linear_solver: LinearSolverSettings) -> OcpSolution {
    let s = ProblemSettings {
        ipm: Some(Settings {
            linear_solver,
            ..ball_finger::pipeline::solver_settings(&mesh)
        }),
        ..mesh
    };
    solve(&build(Problem::PeriodicQc, &s).unwrap(), None).unwrap()
}

/// The settings of the library before the adaptive default (plain AMD; δ_c = 3e-8 for LG,
/// 1e-9 for Radau with one retry at 3e-8 after a failed solve), for the "before" column of
/// the sweep.
fn run_before(name: &str, scheme: Scheme, points: usize) -> OcpSolution {
    let amd = Some(KktOrdering::Amd);
    match scheme {
        Scheme::Lg => run(name, scheme, points, amd, Some(3e-8)),
        Scheme::Radau { .. } => {
            let first = run(name, scheme, points, amd, Some(1e-9));
            if first.status.is_success() {
                return first;
            }
            let mut retry = run(name, scheme, points, amd, Some(3e-8));
            retry.iterations += first.iterations;
            retry.stages.splice(0..0, first.stages);
            retry
        }
    }
}

/// The mesh sweep of BENCHMARKS.md: every periodic problem on hp-Radau 3 × 8 … 3 × 48 and
/// LG 10 … 60, the settings before the adaptive default ([`run_before`]) against the
/// library's default (AMD, a rejected factor checked by 2 × 2 pivot pairs, the static δ_c
/// raised from its start to 3e-8 within the solve on evidence; no retry) or, with
/// `SWEEP_DELTA_C`, against one static δ_c at the start of every solve of both schemes; the
/// latter must end Solved in one stage everywhere. `SWEEP_PROBLEMS` (comma-separated names),
/// `SWEEP_MESHES` (comma-separated `r<N>` for Radau 3 × N, `lg<N>` for LG-N) and
/// `SWEEP_BEFORE=0` (skip the "before" column) narrow a run, so that one sweep can be split
/// over several processes; `SWEEP_RATIO=1` judges the KKT solves by the residual ratio
/// ([`ProblemSettings::kkt_residual_ratio`]) and `SWEEP_EXTRAPOLATION=16` extrapolates along
/// negative curvature ([`ProblemSettings::curvature_extrapolation`]; the default, 1 turns it
/// off) on the barrier problems with μ ≤ tol, with `SWEEP_EVERY_BARRIER=1` on every one;
/// `SWEEP_PROXIMAL=0` turns the proximal term of stalled barrier problems off
/// ([`ProblemSettings::proximal_weight`], default 0.1); `SWEEP_REFINEMENT_STEPS=3` caps the
/// iterative refinement of each KKT solve at three steps (the default is ten, decision record
/// 0009). The last column is each
/// solution's re-integration defect ([`defect`]; verified at ≤ 1e-4).
#[test]
#[ignore = "slow: mesh sweep"]
fn mesh_sweep() {
    let problems = std::env::var("SWEEP_PROBLEMS")
        .unwrap_or_else(|_| "periodic-qc,periodic-cot,periodic-cot-human".into());
    let delta_c: Option<f64> = std::env::var("SWEEP_DELTA_C")
        .ok()
        .map(|v| v.parse().expect("SWEEP_DELTA_C"));
    let with_before = std::env::var("SWEEP_BEFORE").map_or(true, |v| v != "0");
    let mut failed = Vec::new();
    let column = delta_c.map_or("default".to_string(), |d| format!("δ_c {d:e}"));
    println!(
        "| problem | mesh | before: status, iterations, J | {column}: status, iterations, J | δ_c raised at iteration | seconds (before, {column}) | re-integration defect ({column}) |"
    );
    println!("|---|---|---|---|---|---|---|");
    for name in problems.split(',') {
        for (scheme, points) in sweep_meshes("r8,r12,r16,r24,r32,r48,lg10,lg20,lg30,lg40,lg60") {
            let before = with_before.then(|| run_before(name, scheme, points));
            let after = run(name, scheme, points, None, delta_c);
            let b = before.as_ref().map_or("–".to_string(), |b| {
                format!("{:?}, {}, {:.6}", b.status, b.iterations, b.objective)
            });
            println!(
                "| {name} | {} | {b} | {:?}, {}, {:.8}{} | {} | {}, {:.1} | {:.1e} |",
                label(scheme, points),
                after.status,
                after.iterations,
                after.objective,
                stages_note(&after),
                raised_at(&after),
                before
                    .as_ref()
                    .map_or("–".to_string(), |b| format!("{:.1}", b.solve_seconds)),
                after.solve_seconds,
                defect(name, scheme, points, &after)
            );
            if after.status != Status::Solved || after.stages.len() != 1 {
                failed.push(format!(
                    "{name} {}: {:?}",
                    label(scheme, points),
                    after.stages
                ));
            }
        }
    }
    assert!(failed.is_empty(), "not Solved in one stage: {failed:?}");
}

/// The re-integration defect of a sweep cell's solution (`pipeline::verify`, rtol 1e-10; NaN
/// where the re-integration fails): the sweep judges statuses, and a Solved end on a mesh too
/// coarse for its phases (e.g. one Gauss polynomial for an 8 s free phase) does not verify.
fn defect(name: &str, scheme: Scheme, points: usize, sol: &OcpSolution) -> f64 {
    let s = ProblemSettings {
        points,
        scheme,
        ..ProblemSettings::default()
    };
    let problem: Problem = name.parse().unwrap();
    let p = build(problem, &s).unwrap();
    verify(&p, sol, 1e-10).map_or(f64::NAN, |v| v.max_defect)
}

/// Parses `SWEEP_MESHES` (comma-separated `r<N>` for Radau 3 × N, `lg<N>` for LG-N).
fn sweep_meshes(default: &str) -> Vec<(Scheme, usize)> {
    std::env::var("SWEEP_MESHES")
        .unwrap_or_else(|_| default.into())
        .split(',')
        .map(|m| {
            if let Some(n) = m.strip_prefix("lg") {
                (Scheme::Lg, n.parse().expect("SWEEP_MESHES: lg<N>"))
            } else {
                let n: usize = m
                    .strip_prefix('r')
                    .and_then(|n| n.parse().ok())
                    .expect("SWEEP_MESHES: r<N> or lg<N>");
                (Scheme::Radau { elements: 3 }, 3 * n)
            }
        })
        .collect()
}

/// The multifrontal LDLᵀ with threshold pivoting ([`KktOrdering::ThresholdPivoting`]) with
/// one static δ_c for both schemes (`SWEEP_DELTA_C`, default 1e-9) against the library's
/// default handling, on `SWEEP_PROBLEMS` × `SWEEP_MESHES` (default: the meshes where the
/// default needs its δ_c growth or the LG start at 3e-8). Prints a table; asserts nothing
/// beyond completing (a measurement, see BENCHMARKS.md).
#[test]
#[ignore = "slow: mesh sweep of the threshold-pivoting factorization"]
fn threshold_pivoting_sweep() {
    let problems =
        std::env::var("SWEEP_PROBLEMS").unwrap_or_else(|_| "periodic-cot,periodic-qc".into());
    let delta_c: f64 = std::env::var("SWEEP_DELTA_C")
        .ok()
        .map_or(1e-9, |v| v.parse().expect("SWEEP_DELTA_C"));
    let with_default = std::env::var("SWEEP_BEFORE").map_or(true, |v| v != "0");
    println!(
        "| problem | mesh | default: status, iterations, J (s) | threshold pivoting, δ_c {delta_c:e}: status, iterations, J (s) | δ_c raised at |"
    );
    println!("|---|---|---|---|---|");
    for name in problems.split(',') {
        for (scheme, points) in sweep_meshes("r24,r32,lg30") {
            let default = with_default.then(|| run(name, scheme, points, None, None));
            let t = run(
                name,
                scheme,
                points,
                Some(KktOrdering::ThresholdPivoting),
                Some(delta_c),
            );
            let d = default.as_ref().map_or("–".to_string(), |b| {
                format!(
                    "{:?}, {}, {:.6} ({:.1})",
                    b.status, b.iterations, b.objective, b.solve_seconds
                )
            });
            println!(
                "| {name} | {} | {d} | {:?}, {}, {:.6} ({:.1}){} | {} |",
                label(scheme, points),
                t.status,
                t.iterations,
                t.objective,
                t.solve_seconds,
                stages_note(&t),
                raised_at(&t),
            );
        }
    }
}

/// Solves `problem` on hp-Radau with 3 elements and `points` per phase, with solver
/// settings `ipm` (the tests below that change one solver option).
fn solve_radau3(problem: Problem, points: usize, ipm: Settings) -> OcpSolution {
    let s = ProblemSettings {
        points,
        scheme: Scheme::Radau { elements: 3 },
        ipm: Some(ipm),
        ..ProblemSettings::default()
    };
    solve(&build(problem, &s).unwrap(), None).unwrap()
}

/// `periodic-cot` Radau 3 × 24 ends Acceptable with the relative-residual test alone: late in
/// the solve the iterates
/// follow a flat valley, where the exact Newton step is far longer than its right-hand side,
/// and a solve exact to rounding leaves a residual above 1e-5 ‖rhs‖, so the step is rejected
/// as inaccurate and damped by δ_w until the acceptable test stops the crawl. With the
/// normwise backward-error test (`Settings::backward_error_tol` = 1e-14, the default; decision
/// record 0008) the direct solve ends Solved in one stage, and solves accepted on their
/// backward error are part of its path.
#[test]
#[ignore = "slow: two fine-mesh solves of periodic-cot (≈ 30 s)"]
fn the_backward_error_test_solves_a_fine_cot_mesh() {
    // Three refinement steps, as when the test was introduced: with ten (the default now)
    // the accuracy test matters less often, see the next test.
    let solve_with = |backward_error_tol: f64| {
        let ipm = Settings {
            linear_solver: LinearSolverSettings {
                backward_error_tol,
                max_refinement_steps: 3,
                ..Default::default()
            },
            ..Settings::default()
        };
        solve_radau3(Problem::PeriodicCot, 72, ipm)
    };
    let plain = solve_with(0.0);
    assert_eq!(plain.status, Status::Acceptable, "{:?}", plain.stages);
    let sol = solve_with(1e-14);
    assert_eq!(sol.status, Status::Solved, "{:?}", sol.stages);
    assert_eq!(sol.stages.len(), 1, "{:?}", sol.stages);
    assert!(
        sol.counters.backward_error_accepts > 0,
        "{:?}",
        sol.counters
    );
    assert!(sol.objective < plain.objective);
}

/// Ten refinement steps per KKT solve (decision record 0009) against three: on
/// `periodic-cot-human` Radau 3 × 52 the solve with three steps ends Acceptable (258
/// iterations), with ten (the default, Ipopt's) Solved in one stage, J within 2e-4. The
/// decision was taken on 3 × 48, where late in the solve the AMD factors have the right
/// inertia but refine by only 0.1–0.3 per step (pivot growth), so that three steps left the
/// KKT solves at 1e-4…1e-3 relative, every step was rejected as inaccurate and damped by δ_w
/// until the acceptable test ended the solve; later changes of path (one libm on every
/// machine, decision record 0045, and the solver changes after it) took 3 × 48 to Solved with
/// three steps as well; 3 × 52 is a human cell that three steps still leave Acceptable
/// (BENCHMARKS.md, "Ignored tests re-aimed").
#[test]
#[ignore = "slow: two solves of a fine periodic-cot-human mesh (about 60 s)"]
fn ten_refinement_steps_solve_a_fine_human_mesh() {
    let solve_with = |max_refinement_steps: usize| {
        let ipm = Settings {
            linear_solver: LinearSolverSettings {
                max_refinement_steps,
                ..Default::default()
            },
            ..Settings::default()
        };
        solve_radau3(Problem::PeriodicCotHuman, 156, ipm)
    };
    let three = solve_with(3);
    assert_eq!(three.status, Status::Acceptable, "{:?}", three.stages);
    let ten = solve_with(Settings::default().linear_solver.max_refinement_steps);
    assert_eq!(ten.status, Status::Solved, "{:?}", ten.stages);
    assert_eq!(ten.stages.len(), 1, "{:?}", ten.stages);
}

/// Ipopt's filter reset heuristic (docs/decisions/0007-filter-reset.md) is what solves the
/// crawling `periodic-cot` meshes: late in a solve an old filter entry can block every step
/// that raises the constraint violation, so that the filter admits only steps of ~1e-4. On
/// Radau with 31 points per phase and on LG-26 (three refinement steps of the KKT solves, as
/// when the test was introduced) the direct solves from the default guess end Solved in one
/// stage with resets; with the heuristic off (`max_filter_resets` 0) the Radau solve reaches
/// the iteration limit in both stages of its guess fallback and the LG one takes more than
/// three times the iterations. (Which meshes crawl depends on the path: with ten refinement
/// steps, decision record 0009, or other rounding, others do.)
#[test]
fn the_filter_reset_solves_the_crawling_cot_meshes() {
    let solve_with = |scheme: Scheme, points: usize, resets: usize| {
        let s = ProblemSettings {
            points,
            scheme,
            ipm: Some(Settings {
                linear_solver: LinearSolverSettings {
                    max_refinement_steps: 3,
                    ..Default::default()
                },
                line_search: LineSearchSettings {
                    max_filter_resets: resets,
                    ..Default::default()
                },
                ..Settings::default()
            }),
            ..ProblemSettings::default()
        };
        let problem: Problem = "periodic-cot".parse().unwrap();
        solve(&build(problem, &s).unwrap(), None).unwrap()
    };
    let default_resets = LineSearchSettings::default().max_filter_resets;
    for (scheme, points) in [(Scheme::Radau { elements: 3 }, 31), (Scheme::Lg, 26)] {
        let sol = solve_with(scheme, points, default_resets);
        assert_eq!(
            sol.status,
            Status::Solved,
            "{scheme:?} {points}: {:?}",
            sol.stages
        );
        assert_eq!(sol.stages.len(), 1, "{scheme:?} {points}: {:?}", sol.stages);
        assert!(sol.counters.filter_resets > 0, "{scheme:?} {points}");
        assert!(
            sol.iterations < 500,
            "{scheme:?} {points}: {} iterations",
            sol.iterations
        );
        let off = solve_with(scheme, points, 0);
        assert_eq!(off.counters.filter_resets, 0);
        let crawled = off.stages.len() > 1 || off.iterations > 3 * sol.iterations;
        assert!(
            crawled,
            "{scheme:?} {points} without resets: {:?}",
            off.stages
        );
    }
}

/// The two sweep cells that the solver without the proximal term and the extrapolation did not
/// solve in one stage end Solved in one stage with the defaults: `periodic-cot` Radau 3 × 48 (a
/// crawl along a descending valley of negative curvature at μ ≤ tol, MaxIterations in both
/// stages without the extrapolation; decision record 0010) and LG-40 (a wander along a flat
/// direction at μ = 1.6e-4 that ended in a restoration phase and a damped crawl, where the
/// proximal term of the stalled barrier problem bounds the steps; decision record 0011). The
/// term acts on LG-40's stalled barrier problems and never on the ones that decide the answer,
/// so without it (`proximal_weight: Some(0.0)`) the solve ends at the same optimum: since later
/// decisions changed the solves' paths, LG-40 no longer stalls into the fallback without the
/// term, and no cell of the sweep does (BENCHMARKS.md, "Ignored tests re-aimed").
#[test]
#[ignore = "about 90 s: the 3 × 48 solve takes some 500 iterations"]
fn the_defaults_solve_the_two_sweep_cells_left_unsolved_before_them() {
    let problem: Problem = "periodic-cot".parse().unwrap();
    let mut with_term = None;
    for (scheme, points, proximal) in [
        (Scheme::Radau { elements: 3 }, 144, None),
        (Scheme::Lg, 40, None),
        (Scheme::Lg, 40, Some(0.0)),
    ] {
        let s = ProblemSettings {
            points,
            scheme,
            proximal_weight: proximal,
            ..ProblemSettings::default()
        };
        let sol = solve(&build(problem, &s).unwrap(), None).unwrap();
        let label = label(scheme, points);
        println!(
            "periodic-cot {label} (proximal {proximal:?}): {:?} in {} iterations, {} stages, \
             {} extrapolated steps, {} proximal iterations, J = {:.8}",
            sol.status,
            sol.iterations,
            sol.stages.len(),
            sol.counters.extrapolations,
            sol.counters.proximal_iterations,
            sol.objective
        );
        assert_eq!(sol.status, Status::Solved, "{label}: {:?}", sol.stages);
        assert_eq!(sol.stages.len(), 1, "{label}: {:?}", sol.stages);
        match (scheme, proximal) {
            (Scheme::Lg, None) => {
                assert!(sol.counters.proximal_iterations > 0);
                with_term = Some(sol.objective);
            }
            (Scheme::Lg, Some(_)) => {
                assert_eq!(sol.counters.proximal_iterations, 0);
                let j = with_term.expect("the default LG-40 solve runs first");
                assert!(
                    (sol.objective - j).abs() <= 1e-8 * j.abs(),
                    "{label}: J {} without the term, {j} with it",
                    sol.objective
                );
            }
            _ => assert!(sol.counters.extrapolations > 0, "{label}"),
        }
    }
}
