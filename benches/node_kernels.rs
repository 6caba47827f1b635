//! Emitted node kernels (bf-generated, `bf_problem::kernels`) against the interpreted graph
//! programs they replace, on the node functions of `periodic-qc` (paper scene, Radau 3 × 10):
//! one evaluation of the values, the Jacobian and the weighted Hessian at every collocation
//! node of the three phases (90 nodes), as the interior-point solver does once per iteration.
//! Both backends give bitwise equal results (`tests/node_kernels.rs`); the ratio of the two
//! medians measured in the same run is the speed-up of emitting the kernels.
//!
//! A second group evaluates the whole NLP (constraints, Jacobian and Hessian values, at the
//! initial point with random multipliers) with the collocation nodes in batches of four
//! ([`Transcription::batch_nodes`](bf_optim::ocp::Transcription::batch_nodes) on, the default)
//! and node by node (off): bitwise the same values, so the ratio is what the batched kernels
//! save per solver iteration.
//!
//! `cargo bench --bench node_kernels`

use std::hint::black_box;

use ball_finger::pipeline::{GENERATED, build};
use bf_optim::ipm::Nlp;
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

    let x = p.nlp.initial().to_vec();
    let lambda: Vec<f64> = (0..p.nlp.num_constraints())
        .map(|_| rng.random_range(-1.0..1.0))
        .collect();
    let mut g = vec![0.0; p.nlp.num_constraints()];
    let mut jac = vec![0.0; p.nlp.jacobian_structure().len()];
    let mut hess = vec![0.0; p.nlp.hessian_structure().len()];
    let mut group = c.benchmark_group("nlp_periodic_qc_radau3x10");
    for (label, batch) in [("batched", true), ("node_by_node", false)] {
        let mut nlp = p.nlp.clone();
        nlp.batch_nodes = batch;
        group.bench_function(label, |b| {
            b.iter(|| {
                nlp.constraints(&x, &mut g);
                nlp.jacobian_values(&x, &mut jac);
                nlp.hessian_values(&x, 1.0, &lambda, &mut hess);
                black_box(g[0] + jac[0] + hess[0])
            })
        });
    }
    group.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
