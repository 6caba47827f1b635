//! The KKT elimination order on the periodic collocation problems: with each constraint row
//! eliminated right after a primal variable of its own
//! ([`KktOrdering::ConstraintsAfterVariables`]) and the solver's static dual regularization
//! δ_c = 1e-9 for both schemes, the periodic problems end Solved on hp-Radau and
//! Legendre–Gauss meshes where plain AMD with δ_c = 1e-9 stalls or ends Acceptable (the factor
//! reports spurious negative pivots and the inertia correction keeps δ_w > 0).

use ball_finger::study::{build, solve};
use bf_optim::ipm::{KktOrdering, Settings, Status};
use bf_optim::ocp::Scheme;
use bf_problem::{OcpSolution, Problem, ProblemSettings};

/// Solves `name` on `scheme` with `points` per phase, KKT `ordering` and static dual
/// regularization `delta_c` (`None`: the library's default handling).
fn run(
    name: &str,
    scheme: Scheme,
    points: usize,
    ordering: KktOrdering,
    delta_c: Option<f64>,
) -> OcpSolution {
    let s = ProblemSettings {
        points,
        scheme,
        ipm: Some(Settings {
            kkt_ordering: ordering,
            ..Settings::default()
        }),
        dual_regularization: delta_c,
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

/// Meshes where plain AMD with δ_c = 1e-9 does not end Solved (`periodic-cot` 3 × 12 stalls,
/// `periodic-qc` 3 × 16 ends Acceptable, LG-30 needed δ_c = 3e-8); with the constraint-aware
/// order each ends Solved in one stage.
#[test]
fn constraint_aware_order_solves_fine_meshes_with_the_default_regularization() {
    for (name, scheme, points) in [
        ("periodic-cot", Scheme::Radau { elements: 3 }, 36),
        ("periodic-qc", Scheme::Radau { elements: 3 }, 48),
        ("periodic-qc", Scheme::Lg, 30),
    ] {
        let sol = run(
            name,
            scheme,
            points,
            KktOrdering::ConstraintsAfterVariables,
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

/// The mesh sweep of BENCHMARKS.md: every periodic problem on hp-Radau 3 × 8 … 3 × 48 and
/// LG 10 … 60, before (plain AMD; δ_c = 3e-8 for LG, 1e-9 for Radau with the library's retry
/// at 3e-8) and after (constraint-aware order, δ_c = 1e-9 for both, no retry).
#[test]
#[ignore = "slow: mesh sweep"]
fn mesh_sweep() {
    let mut failed = Vec::new();
    println!("| problem | mesh | before: status, iterations, J | after: status, iterations, J |");
    println!("|---|---|---|---|");
    for name in ["periodic-qc", "periodic-cot", "periodic-cot-human"] {
        let radau = [8, 10, 12, 16, 24, 32, 40, 48].map(|n| (Scheme::Radau { elements: 3 }, 3 * n));
        let lg = [10, 20, 30, 40, 50, 60].map(|n| (Scheme::Lg, n));
        for (scheme, points) in radau.into_iter().chain(lg) {
            let before_dc = match scheme {
                Scheme::Lg => Some(3e-8),
                Scheme::Radau { .. } => None,
            };
            let before = run(name, scheme, points, KktOrdering::Amd, before_dc);
            let after = run(
                name,
                scheme,
                points,
                KktOrdering::ConstraintsAfterVariables,
                Some(1e-9),
            );
            println!(
                "| {name} | {} | {:?}, {}, {:.6} | {:?}, {}, {:.6} |",
                label(scheme, points),
                before.status,
                before.iterations,
                before.objective,
                after.status,
                after.iterations,
                after.objective
            );
            if after.status != Status::Solved {
                failed.push(format!("{name} {}", label(scheme, points)));
            }
        }
    }
    assert!(failed.is_empty(), "not Solved: {failed:?}");
}
