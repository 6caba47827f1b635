//! The paper's periodic problems (Sect. 6.1) solved end to end by criterion: transcription
//! build excluded, cold solve from the default guess included; the time split (function
//! evaluations, derivatives, KKT factorization, ...) of one solve is printed once from the
//! solver's own `Timing`. Only the hp-Radau transcription is benchmarked: Legendre–Gauss does not
//! converge on these problems yet (issue 6), and a 3000-iteration failure is not a benchmark.
//!
//! Quick run: `cargo bench -p bf-optim --bench problems -- --warm-up-time 1 --measurement-time 5`

use std::hint::black_box;

use bf_optim::problems::{ProblemSettings, build, solve};
use criterion::{Criterion, criterion_group, criterion_main};

fn bench(c: &mut Criterion) {
    let mut group = c.benchmark_group("periodic_problems");
    group.sample_size(10);
    for name in ["periodic-qc", "periodic-cot", "periodic-cot-human"] {
        let problem = match build(name, &ProblemSettings::default()) {
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
                    "{name}: {:?}, {} iterations, total {:.1} ms: functions {:.1}, derivatives {:.1}, \
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
            }
            Err(e) => eprintln!("{name}: solve failed: {e}"),
        }
        group.bench_function(format!("{name}/radau3x10"), |b| {
            b.iter(|| black_box(solve(&problem, None).map(|s| s.objective).ok()))
        });
    }
    group.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
