//! Lays out every text of the given SVG files with usvg and the embedded DejaVu Sans (the check
//! of tests/svg_text_fit.rs) and lists what does not fit; exit status 1 if anything does not.
//! `cargo run --release -p bf-plot --example check_svg_text -- out/paper/figures/*.svg`
#[path = "../tests/common/text_fit.rs"]
mod text_fit;

fn main() {
    let opt = text_fit::options();
    let mut bad = 0;
    for f in std::env::args().skip(1) {
        let svg = match std::fs::read_to_string(&f) {
            Ok(s) => s,
            Err(e) => {
                eprintln!("{f}: cannot read: {e}");
                bad += 1;
                continue;
            }
        };
        let problems = text_fit::problems(&svg, &opt);
        let n = text_fit::lay_out(&svg, &opt).0.len();
        println!("{f}: {n} texts, {} do not fit", problems.len());
        for p in &problems {
            println!("  {p}");
        }
        bad += problems.len();
    }
    std::process::exit(i32::from(bad > 0));
}
