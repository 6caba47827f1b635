//! scratch
fn main() {
    let path = std::env::args().nth(1).unwrap();
    let text = std::fs::read_to_string(&path).unwrap();
    let scene = bf_codegen::Scene::from_toml_str(&text, &path).unwrap();
    let g = bf_codegen::generate(&scene, &text).unwrap();
    println!("{}", g.report);
    std::fs::write("/tmp/gen_out.rs", &g.code).unwrap();
}
