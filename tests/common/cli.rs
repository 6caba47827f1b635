//! Helpers of the tests that run the `ball-finger` binary: the binary, the repository root it
//! runs in, a fresh per-test temporary directory, and a run with captured output.
#![allow(dead_code)] // each test file uses its own subset

use std::path::PathBuf;

#[path = "tempdir.rs"]
mod tempdir;
pub use tempdir::TempDir;

use std::process::{Command, Output};

/// The built `ball-finger` binary.
pub fn bin() -> Command {
    Command::new(env!("CARGO_BIN_EXE_ball-finger"))
}

/// The repository root (the binary runs there, so `scenes/…` paths resolve).
pub fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// An empty temporary directory for `tag`, unique per test file and process, removed with
/// its contents when the returned guard is dropped ([`TempDir`]).
pub fn tmpdir(tag: &str) -> TempDir {
    let d = std::env::temp_dir().join(format!(
        "bf-{}-{tag}-{}",
        env!("CARGO_CRATE_NAME"),
        std::process::id()
    ));
    TempDir::fresh(d)
}

/// Runs the binary with `args` in the repository root and captures its output.
pub fn run(args: &[&str]) -> Output {
    bin()
        .current_dir(root())
        .args(args)
        .output()
        .expect("binary runs")
}

/// The standard output of a run that must have succeeded (the assertion shows both streams).
pub fn ok(o: &Output) -> String {
    let stdout = String::from_utf8_lossy(&o.stdout).into_owned();
    assert!(
        o.status.success(),
        "{stdout}\n{}",
        String::from_utf8_lossy(&o.stderr)
    );
    stdout
}

/// `optimize --problem periodic-qc --impact-law stick --strategy direct` with the `extra`
/// options, writing to `out`: the paper's problem in one solve from its guess (about 2 s), a
/// sticking plan whose stick phase lasts, unlike the global search's taps.
pub fn direct_sticking_qc(extra: &[&str], out: &std::path::Path) -> Output {
    bin()
        .current_dir(root())
        .args([
            "optimize",
            "--problem",
            "periodic-qc",
            "--impact-law",
            "stick",
        ])
        .args(["--strategy", "direct"])
        .args(extra)
        .arg("--out")
        .arg(out)
        .output()
        .expect("binary runs")
}

/// The optimum of `problem` from the 32-start search (`optimize --hops 0 --problem NAME`, with
/// `extra` options such as `--starts 4`), planned with the sticking law (eq. 40) unless
/// `extra` names `--impact-law`: the paper's problem by the cheaper search, whose optima have
/// stick phases of real duration (the global search's lower optima are taps that a Newton
/// plant cannot execute, docs/optima.md).
pub fn multistart_optimum(problem: &str, extra: &[&str]) -> ball_finger::pipeline::OcpSolution {
    use ball_finger::pipeline::SolutionIo;
    let dir = tmpdir(&format!("multistart-{problem}-{}", extra.join("")));
    let out = dir.to_str().unwrap();
    let mut args = vec![
        "optimize",
        "--hops",
        "0",
        "--problem",
        problem,
        "--out",
        out,
    ];
    args.extend_from_slice(extra);
    if !extra.contains(&"--impact-law") {
        args.extend_from_slice(&["--impact-law", "stick"]);
    }
    let r = run(&args);
    assert!(r.status.success(), "{}", String::from_utf8_lossy(&r.stderr));
    let sol = ball_finger::pipeline::OcpSolution::read_json(&dir.join("solution.json")).unwrap();
    std::fs::remove_dir_all(&dir).ok();
    sol
}

/// The sticking `periodic-qc` optimum of the 32-start search with 4 starts (`optimize --hops 0
/// --starts 4 --impact-law stick`, which reach the 32 starts' optimum), solved once per test
/// binary.
pub fn qc_optimum() -> &'static ball_finger::pipeline::OcpSolution {
    static SOL: std::sync::OnceLock<ball_finger::pipeline::OcpSolution> =
        std::sync::OnceLock::new();
    SOL.get_or_init(|| {
        let sol = multistart_optimum("periodic-qc", &["--starts", "4"]);
        assert!(sol.status.is_success(), "{:?}", sol.stages);
        sol
    })
}
