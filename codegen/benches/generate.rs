//! Generation time per scene (targets: finger < 50 ms, 7-DOF < 1 s).
//!
//! With `BF_GENERATE_ONCE=<scene>` the binary instead generates that scene once and exits, for
//! instruction counts that do not depend on the machine's load
//! (`BF_GENERATE_ONCE=paper valgrind --tool=callgrind <bench binary>`).

use std::hint::black_box;

use criterion::{Criterion, criterion_group};

const SCENES: [&str; 4] = ["paper", "human", "puma560", "iiwa7"];

/// The scene `name` of `scenes/` and its text.
fn load(name: &str) -> (bf_codegen::Scene, String) {
    let path = format!("{}/../scenes/{name}.toml", env!("CARGO_MANIFEST_DIR"));
    let text = std::fs::read_to_string(&path).expect("scene file");
    let scene = bf_codegen::Scene::from_toml_str(&text, &path).expect("valid scene");
    (scene, text)
}

fn generation(c: &mut Criterion) {
    let mut g = c.benchmark_group("generate");
    g.sample_size(10);
    for name in SCENES {
        let (scene, text) = load(name);
        g.bench_function(name, |b| {
            b.iter(|| bf_codegen::generate(black_box(&scene), &text).expect("generates"))
        });
    }
    g.finish();
}

criterion_group!(benches, generation);

fn main() {
    if let Ok(name) = std::env::var("BF_GENERATE_ONCE") {
        let (scene, text) = load(&name);
        let code = bf_codegen::generate(&scene, &text).expect("generates").code;
        println!("{name}: {} bytes", code.len());
        return;
    }
    benches();
    Criterion::default().configure_from_args().final_summary();
}
