//! `ball-finger paper --quick` end to end: the report is written atomically into the requested
//! directory, lists every built-in scene, and the verification numbers it states are the ones
//! required of the kernels (compiled = interpreted to 1e-12, M positive definite, Ṁ − 2C skew).

use std::process::Command;

fn numbers_after(report: &str, row_prefix: &str) -> f64 {
    let line = report
        .lines()
        .find(|l| l.starts_with(row_prefix))
        .unwrap_or_else(|| panic!("report has no row starting with {row_prefix:?}"));
    let cell = line
        .trim_end_matches('|')
        .rsplit('|')
        .next()
        .unwrap()
        .trim();
    cell.parse()
        .unwrap_or_else(|_| panic!("not a number in {line:?}"))
}

#[test]
fn paper_quick_writes_a_consistent_report() {
    let out = std::env::temp_dir().join(format!("bf-paper-{}", std::process::id()));
    let status = Command::new(env!("CARGO_BIN_EXE_ball-finger"))
        .args(["paper", "--quick", "--out", out.to_str().unwrap()])
        .output()
        .expect("binary runs");
    assert!(
        status.status.success(),
        "{}",
        String::from_utf8_lossy(&status.stderr)
    );
    let report = std::fs::read_to_string(out.join("report.md")).expect("report.md written");
    for scene in ["paper", "human", "puma560", "iiwa7"] {
        assert!(
            report.contains(&format!("| {scene} |")),
            "generation row for {scene}"
        );
    }
    for row in [
        "| compiled vs interpreter, max abs diff of M",
        "| compiled vs interpreter, max abs diff of C",
        "| compiled vs interpreter, max abs diff of g",
        "| compiled vs interpreter, max abs diff of J_c",
        "| (Ṁ − 2C) + (Ṁ − 2C)ᵀ",
    ] {
        let v = numbers_after(&report, row);
        assert!((0.0..1e-12).contains(&v), "{row}: {v}");
    }
    assert!(numbers_after(&report, "| smallest leading principal minor") > 0.0);
    std::fs::remove_dir_all(out).ok();
}
