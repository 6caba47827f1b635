//! Interior-point solver benchmarks on the large sparse collocation NLPs of the test suite:
//! whole solves timed by criterion, plus a per-iteration breakdown (function evaluations,
//! derivative evaluations, KKT assembly, factorization, solves, line search) printed once from
//! the solver's own `Timing`.
//!
//! Quick run: `cargo bench -p bf-optim --bench ipm -- --warm-up-time 1 --measurement-time 5`

#[path = "../tests/common/cheb.rs"]
mod cheb;
#[path = "../tests/common/double_integrator.rs"]
mod double_integrator;

use std::hint::black_box;
use std::time::Duration;

use bf_optim::ipm::{Nlp, Settings, Solution, Workspace, solve, solve_in};
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

criterion_group!(benches, bench_ipm);
criterion_main!(benches);
