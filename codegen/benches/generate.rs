//! Generation time per scene (targets: finger < 50 ms, 7-DOF < 1 s), and the emitted
//! `sin_cos` against `f64::sin_cos`.

use std::hint::black_box;

use criterion::{Criterion, criterion_group, criterion_main};

fn generation(c: &mut Criterion) {
    let mut g = c.benchmark_group("generate");
    g.sample_size(10);
    for name in ["paper", "human", "puma560", "iiwa7"] {
        let path = format!("{}/../scenes/{name}.toml", env!("CARGO_MANIFEST_DIR"));
        let text = std::fs::read_to_string(&path).expect("scene file");
        let scene = bf_codegen::Scene::from_toml_str(&text, &path).expect("valid scene");
        g.bench_function(name, |b| {
            b.iter(|| bf_codegen::generate(black_box(&scene), &text).expect("generates"))
        });
    }
    g.finish();
}

fn trig(c: &mut Criterion) {
    let xs: Vec<f64> = (0..64).map(|i| -3.0 + 0.1 * i as f64).collect();
    c.bench_function("sin_cos/emitted x64", |b| {
        b.iter(|| {
            let mut acc = 0.0;
            for &x in black_box(&xs) {
                let (s, c) = bf_codegen::trig::sin_cos(x);
                acc += s + c;
            }
            acc
        })
    });
    c.bench_function("sin_cos/std x64", |b| {
        b.iter(|| {
            let mut acc = 0.0;
            for &x in black_box(&xs) {
                let (s, c) = f64::sin_cos(x);
                acc += s + c;
            }
            acc
        })
    });
}

criterion_group!(benches, trig, generation);
criterion_main!(benches);
