//! Criterion benchmarks of the paper-scene kernel variants (the speed–accuracy report):
//! `mass_matrix`, `cqd_g` (Lagrangian), `cqd_g_rnea` (Newton–Euler) and `mass_cqd_g`, each as
//! `paper` (f64, constants baked), `paper_runtime` (f64, every constant a runtime parameter),
//! `paper_fma` (f64, `mul_add`) and `paper_f32` (single precision). Accuracy of the same
//! variants: `ball-finger report speed-accuracy`.
//!
//! Quick run: `cargo bench -p ball-finger --bench kernel_variants -- --warm-up-time 1 --measurement-time 2`.

use bf_generated::{paper, paper_f32, paper_fma, paper_runtime};
use criterion::{Criterion, criterion_group, criterion_main};
use std::hint::black_box;

const Q: [f64; 3] = [0.3, -1.1, 2.2];
const QD: [f64; 3] = [0.7, -0.4, 1.9];

macro_rules! bench_f64 {
    ($c:expr, $m:ident, $label:expr) => {{
        let p = &$m::PARAM_DEFAULTS;
        let mut g = $c.benchmark_group(concat!("kernel_variants/", $label));
        g.bench_function("mass_matrix", |b| {
            let mut m = [[0.0; 3]; 3];
            b.iter(|| $m::mass_matrix(black_box(&Q), p, black_box(&mut m)))
        });
        g.bench_function("cqd_g", |b| {
            let mut o = [0.0; 3];
            b.iter(|| $m::cqd_g(black_box(&Q), black_box(&QD), p, black_box(&mut o)))
        });
        g.bench_function("cqd_g_rnea", |b| {
            let mut o = [0.0; 3];
            b.iter(|| $m::cqd_g_rnea(black_box(&Q), black_box(&QD), p, black_box(&mut o)))
        });
        g.bench_function("mass_cqd_g", |b| {
            let (mut m, mut o) = ([[0.0; 3]; 3], [0.0; 3]);
            b.iter(|| {
                $m::mass_cqd_g(
                    black_box(&Q),
                    black_box(&QD),
                    p,
                    black_box(&mut m),
                    black_box(&mut o),
                )
            })
        });
        g.finish();
    }};
}

fn bench(c: &mut Criterion) {
    bench_f64!(c, paper, "f64_baked");
    bench_f64!(c, paper_runtime, "f64_runtime");
    bench_f64!(c, paper_fma, "f64_fma");
    let q = Q.map(|v| v as f32);
    let qd = QD.map(|v| v as f32);
    let p = &paper_f32::PARAM_DEFAULTS;
    let mut g = c.benchmark_group("kernel_variants/f32_baked");
    g.bench_function("mass_matrix", |b| {
        let mut m = [[0.0f32; 3]; 3];
        b.iter(|| paper_f32::mass_matrix(black_box(&q), p, black_box(&mut m)))
    });
    g.bench_function("cqd_g", |b| {
        let mut o = [0.0f32; 3];
        b.iter(|| paper_f32::cqd_g(black_box(&q), black_box(&qd), p, black_box(&mut o)))
    });
    g.bench_function("cqd_g_rnea", |b| {
        let mut o = [0.0f32; 3];
        b.iter(|| paper_f32::cqd_g_rnea(black_box(&q), black_box(&qd), p, black_box(&mut o)))
    });
    g.bench_function("mass_cqd_g", |b| {
        let (mut m, mut o) = ([[0.0f32; 3]; 3], [0.0f32; 3]);
        b.iter(|| {
            paper_f32::mass_cqd_g(
                black_box(&q),
                black_box(&qd),
                p,
                black_box(&mut m),
                black_box(&mut o),
            )
        })
    });
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
