//! Emitted node kernels (bf-generated, `bf_problem::kernels`) against the interpreted graph
//! programs they replace, on the node functions of `periodic-qc` (paper scene, Radau 3 × 10):
//! one evaluation of the values, the Jacobian and the weighted Hessian at every collocation
//! node of the three phases (90 nodes), as the interior-point solver does once per iteration.
//! Both backends give bitwise equal results (`tests/node_kernels.rs`); the ratio of the two
//! medians measured in the same run is the speed-up of emitting the kernels.
//!
//! `cargo bench --bench node_kernels`

use std::hint::black_box;

use ball_finger::study::{GENERATED, build};
use bf_optim::ocp::{GraphFn, KernelUse};
use bf_problem::{Problem, ProblemSettings};
use criterion::{Criterion, criterion_group, criterion_main};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

fn bench(c: &mut Criterion) {
    let p = match build(Problem::PeriodicQc, &ProblemSettings::default()) {
        Ok(p) => p,
        Err(e) => {
            eprintln!("periodic-qc: cannot build: {e}");
            return;
        }
    };
    let mut rng = ChaCha8Rng::seed_from_u64(1);
    let mut sets = Vec::new();
    for (ph, layout) in p.ocp.phases.iter().zip(&p.nlp.phases) {
        let mut col = ph.node.collocation();
        let make = |g: &mut bf_codegen::graph::Graph, k| {
            GraphFn::with_backend(g, &col.outputs, &col.locals, &ph.node.fixed, k)
        };
        let auto = make(&mut col.graph, GENERATED.kernels);
        let interp = make(&mut col.graph, KernelUse::Never);
        assert!(auto.kernel_name().is_some(), "no emitted kernel");
        let nodes: Vec<Vec<f64>> = (0..layout.mesh.colloc.len())
            .map(|_| {
                (0..auto.n_local())
                    .map(|_| rng.random_range(-1.0..1.0))
                    .collect()
            })
            .collect();
        let w: Vec<f64> = (0..auto.n_out())
            .map(|_| rng.random_range(-1.0..1.0))
            .collect();
        sets.push((auto, interp, nodes, w));
    }
    let mut group = c.benchmark_group("node_functions_periodic_qc_radau3x10");
    for (label, use_kernel) in [("emitted", true), ("interpreted", false)] {
        group.bench_function(label, |b| {
            b.iter(|| {
                let mut s = 0.0;
                for (auto, interp, nodes, w) in &sets {
                    let f = if use_kernel { auto } else { interp };
                    for x in nodes {
                        s += f.eval(x)[0] + f.jacobian(x)[0] + f.hessian(x, w)[0];
                    }
                }
                black_box(s)
            })
        });
    }
    group.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
