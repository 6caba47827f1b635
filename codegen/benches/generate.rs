//! Generation time per scene (targets: finger < 50 ms, 7-DOF < 1 s).

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

criterion_group!(benches, generation);
criterion_main!(benches);
