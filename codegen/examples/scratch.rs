//! scratch
fn main() {
    let path = std::env::args().nth(1).unwrap();
    let text = std::fs::read_to_string(&path).unwrap();
    let scene = bf_codegen::Scene::from_toml_str(&text, &path).unwrap();
    let g = bf_codegen::generate(&scene, &text).unwrap();
    println!("{}", g.report);
    std::fs::write("/tmp/gen_out.rs", &g.code).unwrap();
    let mut ts = Vec::new();
    for _ in 0..5 {
        let t = std::time::Instant::now();
        let mut m = bf_codegen::Model::new(&scene).unwrap();
        let defs: Vec<_> = scene.kernels.iter().map(|k| bf_codegen::kernels::build_kernel(&mut m, k).unwrap()).collect();
        let t1 = t.elapsed().as_secs_f64();
        let toks: Vec<_> = defs.iter().map(|d| bf_codegen::emit::emit_kernel(&m.g, &m.layout, d).unwrap().tokens).collect();
        let t2 = t.elapsed().as_secs_f64();
        let _ = bf_codegen::emit::emit_file(&scene.name, m.nq(), &m.params, &defs, &text, toks, true).unwrap();
        let t3 = t.elapsed().as_secs_f64();
        ts.push((t1 * 1e3, (t2 - t1) * 1e3, (t3 - t2) * 1e3));
    }
    println!("graph / tokens / parse+print (ms): {ts:.1?}");
}
