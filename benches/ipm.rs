//! Interior-point solver benchmarks on the large sparse collocation NLPs of the test suite:
//! whole solves timed by criterion, plus a per-iteration breakdown (function evaluations,
//! derivative evaluations, KKT assembly, factorization, solves, line search) printed once from
//! the solver's own `Timing`; and the `periodic-qc` KKT (hp-Radau 3 × 10 and LG 30) factored
//! and solved by the `SparseLdlt` backends (supernodal, simplicial, faer supernodal, multifrontal),
//! compared by thread CPU time round-robin and by criterion (`kkt_periodic_qc_*`).
//!
//! Quick run: `cargo bench --bench ipm -- --warm-up-time 1 --measurement-time 5`

#[path = "../optim/tests/common/cheb.rs"]
mod cheb;
#[path = "../optim/tests/common/double_integrator.rs"]
mod double_integrator;

use std::hint::black_box;
use std::time::Duration;

use ball_finger::pipeline::build;
use bf_optim::ipm::kkt::{KktPattern, Speculator};
use bf_optim::ipm::{
    KktSolver, LdltBackend, LdltOptions, LdltOrdering, Nlp, Settings, Solution, SparseLdlt,
    Workspace, solve, solve_in,
};
use bf_optim::ocp::Scheme;
use bf_problem::{Problem, ProblemSettings};
use criterion::{Criterion, criterion_group, criterion_main};

fn per_iter(d: Duration, it: usize) -> f64 {
    d.as_secs_f64() * 1e3 / it.max(1) as f64
}

fn report(name: &str, p: &dyn Nlp, sol: &Solution) {
    let t = &sol.timing;
    let it = sol.iterations;
    println!(
        "{name}: n = {}, m = {}, {:?} in {} iterations, {} factorizations, total {:.1} ms = {:.2} ms/iter",
        p.num_variables(),
        p.num_constraints(),
        sol.status,
        it,
        sol.counters.factorizations,
        t.total.as_secs_f64() * 1e3,
        per_iter(t.total, it)
    );
    println!(
        "  per iteration [ms]: function evals {:.3}, derivative evals {:.3}, KKT assembly {:.3}, factorization {:.3}, solves {:.3}, line search {:.3}",
        per_iter(t.function_evals, it),
        per_iter(t.derivative_evals, it),
        per_iter(t.kkt_assembly, it),
        per_iter(t.factorization, it),
        per_iter(t.solve, it),
        per_iter(t.line_search, it)
    );
}

fn bench_ipm(c: &mut Criterion) {
    let settings = Settings::default();
    let trap = double_integrator::DoubleIntegrator::new(4000);
    let lgr = cheb::ChebDoubleIntegrator::new(3, 80, 30);
    let mut lgr_small = cheb::ChebDoubleIntegrator::new(3, 20, 30);
    lgr_small.drag = 0.3;
    for (name, p) in [
        ("trapezoid double integrator (12k vars)", &trap as &dyn Nlp),
        ("LGR 3-axis, 80 x 30 nodes (21.6k vars)", &lgr as &dyn Nlp),
        (
            "LGR 3-axis with drag, 20 x 30 nodes (5.4k vars)",
            &lgr_small as &dyn Nlp,
        ),
    ] {
        let sol = solve(p, &settings).expect("solve");
        report(name, p, &sol);
    }
    let mut g = c.benchmark_group("ipm");
    g.sample_size(10);
    g.bench_function("trapezoid_double_integrator_12k", |b| {
        b.iter(|| black_box(solve(&trap, &settings).unwrap()))
    });
    g.bench_function("lgr_drag_5k", |b| {
        b.iter(|| black_box(solve(&lgr_small, &settings).unwrap()))
    });
    g.bench_function("lgr_21k", |b| {
        b.iter(|| black_box(solve(&lgr, &settings).unwrap()))
    });
    // Same solve with the KKT symbolic analysis kept in a reused workspace.
    let mut ws = Workspace::new();
    g.bench_function("lgr_21k_reused_workspace", |b| {
        b.iter(|| black_box(solve_in(&mut ws, &lgr, &settings, None, None).unwrap()))
    });
    g.finish();
}

/// The KKT matrix of a paper problem at the initial guess with unit multipliers and a barrier
/// diagonal of 1, as `(pattern with values, dim, bounded variables)`.
fn kkt_of(name: Problem, settings: &ProblemSettings) -> Option<(KktPattern, usize, Vec<bool>)> {
    let problem = match build(name, settings) {
        Ok(p) => p,
        Err(e) => {
            eprintln!("{name}: cannot build: {e}");
            return None;
        }
    };
    let nlp = &problem.nlp;
    let (n, m) = (nlp.num_variables(), nlp.num_constraints());
    let jp = nlp.jacobian_structure();
    let hp = nlp.hessian_structure();
    let mut x = vec![0.0; n];
    nlp.initial_point(&mut x);
    let mut jv = vec![0.0; jp.len()];
    nlp.jacobian_values(&x, &mut jv);
    let mut hv = vec![0.0; hp.len()];
    nlp.hessian_values(&x, 1.0, &vec![1.0; m], &mut hv);
    let mut pat = KktPattern::new(n, m, &hp, &jp);
    pat.assemble(&hv, &jv, &vec![1.0; n], -1e-8);
    let (mut xl, mut xu) = (vec![0.0; n], vec![0.0; n]);
    nlp.variable_bounds(&mut xl, &mut xu);
    let bounded = (0..n)
        .map(|j| xl[j] > -bf_optim::ipm::BOUND_INF || xu[j] < bf_optim::ipm::BOUND_INF)
        .collect();
    Some((pat, n + m, bounded))
}

/// CPU time of the calling thread in seconds (Linux `schedstat`; wall clock elsewhere).
fn thread_cpu_seconds() -> f64 {
    std::fs::read_to_string("/proc/thread-self/schedstat")
        .ok()
        .and_then(|s| s.split_whitespace().next()?.parse::<f64>().ok())
        .map(|ns| ns * 1e-9)
        .unwrap_or_else(|| {
            use std::sync::OnceLock;
            static T0: OnceLock<std::time::Instant> = OnceLock::new();
            T0.get_or_init(std::time::Instant::now)
                .elapsed()
                .as_secs_f64()
        })
}

/// Backends and orderings of `SparseLdlt` compared on one KKT pattern: `(label, backend,
/// constraint-aware order, 2 × 2 pivot pairs, pivot threshold)` (`block` = the supernodal
/// kernel, `simplicial` = the prepared faer-identical up-looking path, `auto` = the default
/// choice; `_amd` = plain AMD, `_cav` = AMD on (variable, row) pairs, `_pairs` = AMD with the
/// rows it would eliminate bare delayed into 2 × 2 (variable, row) pivots; `multifrontal_u*` =
/// threshold Bunch–Kaufman pivoting with delayed pivots on AMD's order with threshold u, the
/// threshold used by the other backends is irrelevant).
const VARIANTS: [(&str, LdltBackend, bool, bool, f64); 9] = [
    ("auto_amd", LdltBackend::Auto, false, false, 0.0),
    ("auto_pairs", LdltBackend::Auto, true, true, 0.0),
    ("auto_cav", LdltBackend::Auto, true, false, 0.0),
    ("block", LdltBackend::Supernodal, false, false, 0.0),
    ("simplicial", LdltBackend::Simplicial, false, false, 0.0),
    (
        "faer_supernodal",
        LdltBackend::FaerSupernodal,
        false,
        false,
        0.0,
    ),
    (
        "multifrontal_u1e-2",
        LdltBackend::Multifrontal,
        false,
        false,
        1e-2,
    ),
    (
        "multifrontal_u1e-4",
        LdltBackend::Multifrontal,
        false,
        false,
        1e-4,
    ),
    (
        "multifrontal_u1e-8",
        LdltBackend::Multifrontal,
        false,
        false,
        1e-8,
    ),
];

/// The KKT of `periodic-qc` (hp-Radau 3 × 10 per phase, and LG with 30 points per phase):
/// fill of L and flops per variant, then all variants factored and solved round-robin (each
/// round runs every variant once, so that the load of a shared machine hits all alike; the
/// minimum printed), then criterion on the default backend with both orderings, the supernodal
/// and simplicial kernels and the multifrontal one.
fn bench_kkt(c: &mut Criterion) {
    let lg = ProblemSettings {
        scheme: Scheme::Lg,
        points: 30,
        ..ProblemSettings::default()
    };
    for (label, settings) in [("radau3x10", ProblemSettings::default()), ("lg30", lg)] {
        let Some((pat, dim, bounded)) = kkt_of(Problem::PeriodicQc, &settings) else {
            continue;
        };
        let mut solvers: Vec<SparseLdlt> = VARIANTS
            .iter()
            .map(|&(_, backend, cav, pairs, u)| {
                let defaults = LdltOptions::default();
                let ordering = match (cav, pairs) {
                    (false, _) => LdltOrdering::Amd,
                    (true, true) => LdltOrdering::AmdPivotPairs {
                        constraint_rows_from: pat.n,
                    },
                    (true, false) => LdltOrdering::PairedAmd {
                        constraint_rows_from: pat.n,
                        preferred_primal: bounded.clone(),
                    },
                };
                let mut s = SparseLdlt::with_options(LdltOptions {
                    backend,
                    ordering,
                    pivot_threshold: if u > 0.0 { u } else { defaults.pivot_threshold },
                    ..defaults
                });
                s.analyse(dim, &pat.mat.col_ptr, &pat.mat.row_idx)
                    .expect("analyse");
                s
            })
            .collect();
        let rhs0: Vec<f64> = (0..dim).map(|i| libm::sin(i as f64 * 0.37)).collect();
        // Batches timed by this thread's CPU time (unaffected by preemption on a loaded machine;
        // schedstat advances in scheduler ticks, hence ≥ 0.1 s per batch), round-robin over the
        // variants; the minimum per call over 5 rounds.
        let mut best = vec![(f64::INFINITY, f64::INFINITY); solvers.len()];
        for _ in 0..5 {
            for (s, b) in solvers.iter_mut().zip(best.iter_mut()) {
                let t = thread_cpu_seconds();
                for _ in 0..50 {
                    black_box(s.factor(&pat.mat.values)).ok();
                }
                b.0 = b.0.min((thread_cpu_seconds() - t) / 50.0 * 1e6);
                let t = thread_cpu_seconds();
                for _ in 0..500 {
                    let mut r = rhs0.clone();
                    black_box(s.solve(&mut r)).ok();
                    black_box(r);
                }
                b.1 = b.1.min((thread_cpu_seconds() - t) / 500.0 * 1e6);
            }
        }
        for ((v, s), b) in VARIANTS.iter().zip(&mut solvers).zip(&best) {
            let inertia = s.factor(&pat.mat.values);
            let (delayed, two, stat) = s.pivot_statistics();
            println!(
                "periodic-qc/{label} KKT {}: dim {dim}, nnz(tril K) {}, nnz(L) {}, flops {:.3e}, inertia {:?}; \
                 CPU time per factor {:.0} us, per solve {:.1} us; delayed {delayed}, 2x2 {two}, static {stat}",
                v.0,
                pat.mat.row_idx.len(),
                s.factor_nnz(),
                s.factor_flops(),
                inertia,
                b.0,
                b.1
            );
        }
        let mut g = c.benchmark_group(format!("kkt_periodic_qc_{label}"));
        g.sample_size(20);
        // The symbolic phase alone (ordering, elimination tree, plan), as each cold solve runs
        // it once: against `factor_auto`, what sharing it between solves could save.
        g.bench_function("analyse_auto", |b| {
            b.iter(|| {
                let mut s = SparseLdlt::new();
                s.analyse(dim, &pat.mat.col_ptr, &pat.mat.row_idx)
                    .expect("analyse");
                black_box(s)
            })
        });
        for (v, s) in VARIANTS.iter().zip(&mut solvers) {
            if !["auto", "multifrontal", "block", "simplicial"]
                .iter()
                .any(|p| v.0.starts_with(p))
            {
                continue;
            }
            g.bench_function(format!("factor_{}", v.0), |b| {
                b.iter(|| black_box(s.factor(&pat.mat.values)))
            });
            g.bench_function(format!("solve_{}", v.0), |b| {
                b.iter(|| {
                    let mut r = rhs0.clone();
                    black_box(s.solve(&mut r)).ok();
                    black_box(r)
                })
            });
        }
        // The supernodal kernel on the calling thread alone, against `factor_block` (shared
        // with a second thread where its supernodes are wide enough, decision record 0090).
        let mut alone = SparseLdlt::with_options(LdltOptions {
            backend: LdltBackend::Supernodal,
            parallel: false,
            ..LdltOptions::default()
        });
        alone
            .analyse(dim, &pat.mat.col_ptr, &pat.mat.row_idx)
            .expect("analyse");
        g.bench_function("factor_block_one_thread", |b| {
            b.iter(|| black_box(alone.factor(&pat.mat.values)))
        });
        // Two matrices of an inertia-correction chain (δ_w and 8 δ_w): factored one after the
        // other on this thread, and at once with the second on the speculative factorization's
        // thread (decision record 0036), which is what a rejected first trial costs without
        // and with it.
        let mut first = SparseLdlt::new();
        first
            .analyse(dim, &pat.mat.col_ptr, &pat.mat.row_idx)
            .expect("analyse");
        let mut second = Vec::new();
        pat.shifted_values(8.0, 0.0, &mut second);
        let mut spec = Speculator::new();
        g.bench_function("factor_auto_two_in_turn", |b| {
            b.iter(|| {
                black_box(first.factor(&pat.mat.values)).ok();
                black_box(first.factor(&second)).ok();
            })
        });
        g.bench_function("factor_auto_two_at_once", |b| {
            b.iter(|| {
                spec.start(&first, |out| out.clone_from(&second));
                black_box(first.factor(&pat.mat.values)).ok();
                black_box(spec.take(&mut first, &second)).map(|(r, _)| r.ok())
            })
        });
        g.finish();
    }
}

criterion_group!(benches, bench_kkt, bench_ipm);
criterion_main!(benches);
