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

use bf_optim::ipm::kkt::KktPattern;
use bf_optim::ipm::{FaerLdlt, KktSolver, Nlp, Settings, Solution, Workspace, solve, solve_in};
use bf_optim::problems::{ProblemSettings, build};
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

/// The KKT matrix of `periodic-qc` (hp-Radau 3 × 10 per phase) at the initial guess with unit
/// multipliers and a barrier diagonal of 1: factorization variants compared on the real pattern
/// (fill of L, simplicial vs supernodal), factor and solve timed by criterion.
fn bench_kkt(c: &mut Criterion) {
    let problem = match build("periodic-qc", &ProblemSettings::default()) {
        Ok(p) => p,
        Err(e) => {
            eprintln!("periodic-qc: cannot build: {e}");
            return;
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
    let dim = n + m;
    let mut g = c.benchmark_group("kkt_periodic_qc");
    g.sample_size(20);
    for (label, sup, reuse) in [
        ("simplicial", Some(false), true),
        ("simplicial_faer_call", Some(false), false),
        ("supernodal", Some(true), true),
    ] {
        let mut s = FaerLdlt::new();
        s.supernodal = sup;
        s.reuse_permutation = reuse;
        s.analyse(dim, &pat.mat.col_ptr, &pat.mat.row_idx)
            .expect("analyse");
        let inertia = s.factor(&pat.mat.values);
        println!(
            "periodic-qc KKT {label}: dim {dim} (n {n}, m {m}), nnz(tril K) {}, nnz(L) {}, flops {:.3e}, inertia {inertia:?}",
            pat.mat.row_idx.len(),
            s.factor_nnz(),
            s.factor_flops()
        );
        g.bench_function(format!("factor_{label}"), |b| {
            b.iter(|| black_box(s.factor(&pat.mat.values)))
        });
        let rhs: Vec<f64> = (0..dim).map(|i| (i as f64 * 0.37).sin()).collect();
        g.bench_function(format!("solve_{label}"), |b| {
            b.iter(|| {
                let mut r = rhs.clone();
                s.solve(&mut r);
                black_box(r)
            })
        });
    }
    g.finish();
}

criterion_group!(benches, bench_kkt, bench_ipm);
criterion_main!(benches);
