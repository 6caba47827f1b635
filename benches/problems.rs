//! The paper's periodic problems (Sect. 6.1) solved end to end by criterion: transcription
//! build excluded, cold solve from the default guess included; the time split (function
//! evaluations, derivatives, KKT factorization, ...) of one solve is printed once from the
//! solver's own `Timing`. Every problem runs with hp-Radau 3 × 10 (`{name}/radau3x10`) and with
//! Legendre–Gauss, 30 points per phase as in the paper (`{name}/lg30`: integral-form Gauss
//! defects, stick phases at the acceleration level, δ_c = 3e-8), and `periodic-qc`
//! also with Radau 3 × 12, the mesh that matches LG-30's objective error, and on Radau 3 × 10
//! and LG-30 with every rejected KKT factor checked by the pivot pairs (`*_check_all`, the
//! default before decision record 0031: the same path with more factorizations) and
//! without the speculative factorization on a second core (`*_sequential`, decision record
//! 0036: the same path, every factor on the solve's own thread).
//!
//! Quick run: `cargo bench --bench problems -- --warm-up-time 1 --measurement-time 5`

use std::hint::black_box;

use ball_finger::pipeline::{build, solve};
use bf_optim::ipm::{LinearSolverSettings, Settings};
use bf_optim::ocp::Scheme;
use bf_problem::{Problem, ProblemSettings};
use criterion::{Criterion, criterion_group, criterion_main};

fn bench(c: &mut Criterion) {
    let mut group = c.benchmark_group("periodic_problems");
    group.sample_size(10);
    let radau = ProblemSettings::default();
    let lg = ProblemSettings {
        scheme: Scheme::Lg,
        points: 30,
        ..ProblemSettings::default()
    };
    // Radau 3 × 12 reaches LG-30's objective error on periodic-qc (≈ 3e-6 against the refined
    // optimum, where 3 × 10 is 5e-5): the "equal accuracy" comparison.
    let radau36 = ProblemSettings {
        points: 36,
        ..ProblemSettings::default()
    };
    // The cold solve's settings (tolerance 1e-8) with other linear-solver settings.
    let with = |s: &ProblemSettings, linear_solver: LinearSolverSettings| ProblemSettings {
        ipm: Some(Settings {
            linear_solver,
            ..ball_finger::pipeline::solver_settings(s)
        }),
        ..s.clone()
    };
    // Every rejected AMD factor checked by the pivot pairs, whatever its δ_w (the default
    // before decision record 0031; the same path, more factorizations).
    let check_all = |s| {
        with(
            s,
            LinearSolverSettings {
                pivot_pairs_check_max_delta_w: f64::MAX,
                ..Default::default()
            },
        )
    };
    let (radau_check_all, lg_check_all) = (check_all(&radau), check_all(&lg));
    // Without the second core (decision records 0036 and 0090: the same path, every factor
    // on the solve's own thread), and with speculation where the default shares the
    // factorization instead (LG).
    let second_core = |s, speculative, parallel| {
        with(
            s,
            LinearSolverSettings {
                speculative_factorization: speculative,
                parallel_factorization: parallel,
                ..Default::default()
            },
        )
    };
    let (radau_sequential, lg_sequential) = (
        second_core(&radau, false, false),
        second_core(&lg, false, false),
    );
    let lg_speculative = second_core(&lg, true, false);
    for (name, label, settings) in [
        (Problem::PeriodicQc, "radau3x10", &radau),
        (Problem::PeriodicQc, "radau3x10_check_all", &radau_check_all),
        (
            Problem::PeriodicQc,
            "radau3x10_sequential",
            &radau_sequential,
        ),
        (Problem::PeriodicQc, "radau3x12", &radau36),
        (Problem::PeriodicQc, "lg30", &lg),
        (Problem::PeriodicQc, "lg30_check_all", &lg_check_all),
        (Problem::PeriodicQc, "lg30_sequential", &lg_sequential),
        (Problem::PeriodicQc, "lg30_speculative", &lg_speculative),
        (Problem::PeriodicCot, "radau3x10", &radau),
        (Problem::PeriodicCot, "lg30", &lg),
        (Problem::PeriodicCotHuman, "radau3x10", &radau),
        (Problem::PeriodicCotHuman, "lg30", &lg),
    ] {
        let problem = match build(name, settings) {
            Ok(p) => p,
            Err(e) => {
                eprintln!("{name}: cannot build: {e}");
                continue;
            }
        };
        match solve(&problem, None) {
            Ok(sol) => {
                let t = &sol.timing;
                println!(
                    "{name}/{label}: {:?}, {} iterations, total {:.1} ms: functions {:.1}, derivatives {:.1}, \
                     KKT assembly {:.1}, factorization {:.1}, solves {:.1}, line search {:.1} ms",
                    sol.status,
                    sol.iterations,
                    t.total.as_secs_f64() * 1e3,
                    t.function_evals.as_secs_f64() * 1e3,
                    t.derivative_evals.as_secs_f64() * 1e3,
                    t.kkt_assembly.as_secs_f64() * 1e3,
                    t.factorization.as_secs_f64() * 1e3,
                    t.solve.as_secs_f64() * 1e3,
                    t.line_search.as_secs_f64() * 1e3
                );
                println!(
                    "{name}/{label}: second thread (speculative factorizations) {:.1} ms",
                    t.speculative_factorization.as_secs_f64() * 1e3
                );
                println!(
                    "{name}/{label}: {} factorizations, {} of them rejected (inertia correction), {} pivot-pair checks",
                    sol.counters.factorizations,
                    sol.counters.rejected_factorizations,
                    sol.counters.pivot_pair_checks
                );
            }
            Err(e) => eprintln!("{name}/{label}: solve failed: {e}"),
        }
        group.bench_function(format!("{name}/{label}"), |b| {
            b.iter(|| black_box(solve(&problem, None).map(|s| s.objective).ok()))
        });
    }
    group.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
