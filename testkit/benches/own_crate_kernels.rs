//! Criterion benchmark of the own-crate example's kernels (`examples/own-crate/`: a UR5-like
//! 6R arm from its URDF, kernels generated in a build script by `bf_codegen::Builder`; this
//! package's `build.rs` generates the same module with the same settings): `mass_cqd_g` and
//! `forward_dynamics` compiled (`compiled/…`) and through the run-time interpreter on the same
//! URDF (`interpreted/…`, `bf_codegen::interp`, what `ball-finger bench robot.urdf` times),
//! at one state. Before timing, the two paths are checked to agree (1e-12 relative).
//!
//! `cargo bench -p bf-testkit --bench own_crate_kernels -- --warm-up-time 1 --measurement-time 3`

#[allow(clippy::all, unused_variables, unused_parens, dead_code, missing_docs)]
mod ur5 {
    include!(concat!(env!("OUT_DIR"), "/ur5.rs"));
}

use bf_codegen::Scene;
use bf_codegen::interp::SceneKernels;
use criterion::{Criterion, criterion_group, criterion_main};
use std::hint::black_box;

const Q: [f64; 6] = [0.1, -0.5, 0.9, 0.2, -0.3, 0.4];
const QD: [f64; 6] = [0.5, 0.0, -0.2, 0.1, 0.0, 0.3];
const TAU: [f64; 6] = [1.0, 2.0, 3.0, 0.1, 0.2, 0.3];

fn bench(c: &mut Criterion) {
    let path = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../examples/own-crate/robot.urdf"
    );
    let (scene, _) = Scene::load_with_text(path, &Default::default()).unwrap();
    let rt = SceneKernels::new(&scene).unwrap();
    let vars = rt.vars(&Q, &QD, [0.0; 3], 0.0, &TAU, None);
    let kernel = |name: &str| rt.kernels.iter().find(|k| k.name == name).unwrap();
    let (mcg, fd) = (kernel("mass_cqd_g"), kernel("forward_dynamics"));
    let p = &ur5::PARAM_DEFAULTS;

    // The compiled module is the interpreter's graphs: same numbers (or the timing is moot).
    let (mut m, mut v, mut qdd) = ([[0.0; 6]; 6], [0.0; 6], [0.0; 6]);
    ur5::mass_cqd_g(&Q, &QD, p, &mut m, &mut v);
    ur5::forward_dynamics(&Q, &QD, &TAU, p, &mut qdd);
    let compiled: Vec<f64> = m.iter().flatten().chain(&v).copied().collect();
    for (got, want) in [(compiled, mcg.eval(&vars)), (qdd.to_vec(), fd.eval(&vars))] {
        let scale = want.iter().fold(1.0f64, |a, x| a.max(x.abs()));
        for (g, w) in got.iter().zip(&want) {
            assert!(
                (g - w).abs() <= 1e-12 * scale,
                "compiled {g} vs interpreted {w}"
            );
        }
    }

    let mut g = c.benchmark_group("own_crate_ur5/compiled");
    g.bench_function("mass_cqd_g", |b| {
        b.iter(|| {
            ur5::mass_cqd_g(
                black_box(&Q),
                black_box(&QD),
                p,
                black_box(&mut m),
                black_box(&mut v),
            )
        })
    });
    g.bench_function("forward_dynamics", |b| {
        b.iter(|| {
            ur5::forward_dynamics(
                black_box(&Q),
                black_box(&QD),
                black_box(&TAU),
                p,
                black_box(&mut qdd),
            )
        })
    });
    g.finish();
    let mut g = c.benchmark_group("own_crate_ur5/interpreted");
    for k in [mcg, fd] {
        let mut out = vec![0.0; k.outputs.iter().map(|o| o.len()).sum()];
        let mut scratch = Vec::new();
        g.bench_function(k.name.as_str(), |b| {
            b.iter(|| k.eval_into(black_box(&vars), &mut scratch, black_box(&mut out)))
        });
    }
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
