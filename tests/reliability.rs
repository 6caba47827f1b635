//! Reliability of the `ball-finger` binary: output directories replaced as a whole (never a
//! mixture of two runs, even when a run stops between two file writes), failed runs marked,
//! no panic on I/O errors, resource limits checked before the work, errors that name the
//! option, file or quantity, and non-finite results reported as errors.

use ball_finger::cli::{Cli, Command as Sub};
use ball_finger::commands::{optimize, simulate};
use clap::Parser;
use std::io::Read as _;
use std::path::Path;
use std::process::{Output, Stdio};

#[path = "common/cli.rs"]
mod cli_util;
use cli_util::{bin, root, run, tmpdir};

fn stderr(out: &Output) -> String {
    String::from_utf8_lossy(&out.stderr).into_owned()
}

/// Fails with exit status `code` (1, or 2 for a wrong command line), no panic, and every
/// `mention` in stderr.
fn assert_error(out: &Output, code: i32, mention: &[&str]) {
    let e = stderr(out);
    assert_eq!(out.status.code(), Some(code), "{e}");
    assert!(!e.contains("panicked"), "{e}");
    for m in mention {
        assert!(e.contains(m), "stderr should mention {m:?}: {e}");
    }
}

fn names(dir: &Path) -> Vec<String> {
    let mut v: Vec<String> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    v.sort();
    v
}

fn json(path: &Path) -> serde_json::Value {
    serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap()
}

fn parse(args: &[&str]) -> Sub {
    let mut full = vec!["ball-finger"];
    full.extend_from_slice(args);
    Cli::try_parse_from(full).unwrap().command
}

/// A simulation stopped between two writes (the trajectory files are staged, the manifest
/// write fails) leaves the previous output set as it was and no temporary directory; a
/// complete second run replaces every file of the first.
#[test]
fn simulate_output_set_is_replaced_as_a_whole() {
    let dir = tmpdir("simset");
    let out = dir.join("out");
    let out_s = out.to_str().unwrap();
    let first = run(&["simulate", "--t-end", "0.5", "--out", out_s]);
    assert!(first.status.success(), "{}", stderr(&first));
    assert_eq!(json(&out.join("summary.json"))["t_final"], 0.5);
    assert_eq!(json(&out.join(bf_output::MANIFEST))["status"], "success");
    let before: Vec<Vec<u8>> = names(&out)
        .iter()
        .map(|n| std::fs::read(out.join(n)).unwrap())
        .collect();
    // Run from inside the scene directory's root, as the binary does.
    std::env::set_current_dir(root()).unwrap();
    let Sub::Simulate(args) = parse(&["simulate", "--t-end", "1", "--out", out_s]) else {
        unreachable!()
    };
    for fault in [1, 2] {
        let e = simulate::run_with(
            &args,
            simulate::RunSettings {
                fail_at_write: Some(fault),
            },
        )
        .unwrap_err();
        assert!(format!("{e:#}").contains("injected fault"), "{e:#}");
        let after: Vec<Vec<u8>> = names(&out)
            .iter()
            .map(|n| std::fs::read(out.join(n)).unwrap())
            .collect();
        assert_eq!(
            before, after,
            "fault at write {fault} changed the previous set"
        );
        assert_eq!(names(&dir), ["out"], "temporary directories left behind");
    }
    let second = run(&["simulate", "--t-end", "1", "--out", out_s]);
    assert!(second.status.success(), "{}", stderr(&second));
    assert_eq!(json(&out.join("summary.json"))["t_final"], 1.0);
    let tj = json(&out.join("trajectory.json"));
    assert_eq!(tj["t"].as_array().unwrap().last().unwrap(), 1.0);
    assert_eq!(names(&dir), ["out"]);
    std::fs::remove_dir_all(&dir).unwrap();
}

/// `optimize`: a run stopped between solution.json and torques.csv leaves the previous pair;
/// a solve that does not converge writes its set with the status and a FAILED marker and
/// exits non-zero.
#[test]
fn optimize_output_set_is_atomic_and_failures_are_marked() {
    let dir = tmpdir("optset");
    let out = dir.join("out");
    let out_s = out.to_str().unwrap();
    // A previous set of `optimize` (its manifest names the command).
    std::fs::create_dir_all(&out).unwrap();
    std::fs::write(out.join("solution.json"), "old").unwrap();
    std::fs::write(out.join("torques.csv"), "old").unwrap();
    std::fs::write(
        out.join(bf_output::MANIFEST),
        r#"{"command": "optimize", "status": "success"}"#,
    )
    .unwrap();
    std::env::set_current_dir(root()).unwrap();
    let Sub::Optimize(args) = parse(&[
        "optimize",
        "--problem",
        "reach",
        "--strategy",
        "direct",
        "--verify-rtol",
        "0",
        "--out",
        out_s,
    ]) else {
        unreachable!()
    };
    let e = optimize::run_with(
        &args,
        optimize::RunSettings {
            fail_at_write: Some(2),
        },
    )
    .unwrap_err();
    assert!(format!("{e:#}").contains("torques.csv"), "{e:#}");
    assert_eq!(
        names(&out),
        [bf_output::MANIFEST, "solution.json", "torques.csv"]
    );
    assert_eq!(
        std::fs::read_to_string(out.join("solution.json")).unwrap(),
        "old"
    );
    assert_eq!(
        std::fs::read_to_string(out.join("torques.csv")).unwrap(),
        "old"
    );
    assert_eq!(names(&dir), ["out"]);

    let o = run(&[
        "optimize",
        "--problem",
        "reach",
        "--max-iter",
        "3",
        "--out",
        out_s,
    ]);
    assert_error(&o, 1, &["did not converge"]);
    assert_eq!(
        names(&out),
        [
            bf_output::MANIFEST,
            bf_output::FAILED,
            "solution-internals.json",
            "solution.json",
            "torques.csv"
        ]
    );
    let sol = json(&out.join("solution.json"));
    assert_eq!(sol["status"], "MaxIterations");
    let failed = std::fs::read_to_string(out.join(bf_output::FAILED)).unwrap();
    assert!(failed.contains("MaxIterations"), "{failed}");
    assert_eq!(json(&out.join(bf_output::MANIFEST))["status"], "failed");
    assert!(
        std::fs::read_to_string(out.join("torques.csv"))
            .unwrap()
            .starts_with("t [s],tau1 [N m],tau2 [N m],tau3 [N m]\n")
    );

    // A warm start with a value no solution has names the file and the field.
    let mut bad = sol.clone();
    bad["objective"] = serde_json::json!(1e300);
    let bad_path = dir.join("bad.json");
    std::fs::write(&bad_path, bad.to_string()).unwrap();
    // A solution is solution.json with solution-internals.json beside it.
    std::fs::copy(
        out.join("solution-internals.json"),
        dir.join("solution-internals.json"),
    )
    .unwrap();
    let o = run(&[
        "optimize",
        "--problem",
        "reach",
        "--warm-start",
        bad_path.to_str().unwrap(),
        "--out",
        dir.join("never").to_str().unwrap(),
    ]);
    assert_error(&o, 1, &["--warm-start", "bad.json", "`objective`", "1e300"]);
    assert!(!dir.join("never").exists());
    // A replay (`simulate --init`) reads solution files through the same range check.
    let o = run(&[
        "simulate",
        "--init",
        bad_path.to_str().unwrap(),
        "--t-end",
        "0.1",
        "--out",
        dir.join("never").to_str().unwrap(),
    ]);
    assert_error(&o, 1, &["--init", "bad.json", "`objective`", "1e300"]);
    assert!(!dir.join("never").exists());

    // The internals pass the same range check (the raw collocation data the warm start is
    // built from), and internals of another shape are refused naming the file.
    let good_path = dir.join("good.json");
    std::fs::write(&good_path, sol.to_string()).unwrap();
    let internals = json(&out.join("solution-internals.json"));
    let warm = |internals: &serde_json::Value| {
        std::fs::write(dir.join("solution-internals.json"), internals.to_string()).unwrap();
        run(&[
            "optimize",
            "--problem",
            "reach",
            "--warm-start",
            good_path.to_str().unwrap(),
            "--out",
            dir.join("never").to_str().unwrap(),
        ])
    };
    let mut huge = internals.clone();
    assert!(set_first_number(&mut huge["raw"], 1e308));
    assert_error(
        &warm(&huge),
        1,
        &["--warm-start", "solution-internals.json", "raw[0]", "1e308"],
    );
    let mut fewer = internals.clone();
    let phases = fewer["raw"].as_array().unwrap().len();
    fewer["raw"].as_array_mut().unwrap().pop();
    assert_error(
        &warm(&fewer),
        1,
        &[
            "solution-internals.json",
            &format!("{} phases of raw collocation data", phases - 1),
            "good.json has",
        ],
    );
    // Collocation data cut short would index out of themselves in the warm start: refused,
    // naming the file and the field, before any solve (no panic).
    for (edit, needle) in [("x", "state rows"), ("elements", "`elements[1]`")] {
        let mut short = internals.clone();
        let rows = short["raw"][0][edit].as_array_mut().unwrap();
        if edit == "x" {
            rows.pop();
        } else {
            rows.remove(1);
        }
        assert_error(
            &warm(&short),
            1,
            &["solution-internals.json", "raw[0]", needle],
        );
    }
    // A field missing from the internals is blamed on them, not on the solution file.
    let mut missing = internals.clone();
    missing["raw"][0].as_object_mut().unwrap().remove("a");
    let o = warm(&missing);
    assert_error(
        &o,
        1,
        &["solution-internals.json", "`raw`", "missing field `a`"],
    );
    assert!(
        stderr(&o).contains("solution-internals.json: `raw`: missing field"),
        "{}",
        stderr(&o)
    );
    // Rows of another width read as data but do not fit the problem's phase: found where the
    // problem is built, and still blamed on the file.
    let mut narrow = internals.clone();
    for row in narrow["raw"][0]["x"].as_array_mut().unwrap() {
        row.as_array_mut().unwrap().truncate(5);
    }
    assert_error(
        &warm(&narrow),
        1,
        &[
            "--warm-start",
            "good.json",
            "raw[0]",
            "rows of `x` have 5 values",
        ],
    );
    let mut other = internals;
    other["problem"] = serde_json::json!("roll");
    assert_error(&warm(&other), 1, &["solution-internals.json", "`roll`"]);
    assert!(!dir.join("never").exists());
    std::fs::remove_dir_all(&dir).unwrap();
}

/// Sets the first number (depth first) of `v` to `x`; whether there was one.
fn set_first_number(v: &mut serde_json::Value, x: f64) -> bool {
    match v {
        serde_json::Value::Number(_) => {
            *v = serde_json::json!(x);
            true
        }
        serde_json::Value::Array(a) => a.iter_mut().any(|e| set_first_number(e, x)),
        serde_json::Value::Object(o) => o.values_mut().any(|e| set_first_number(e, x)),
        _ => false,
    }
}

/// A directory that is not an earlier output (here: a source tree) or a file is refused
/// before any work, and nothing in it changes.
#[test]
fn foreign_or_file_out_is_refused_before_the_work() {
    let dir = tmpdir("foreign");
    let src = dir.join("src");
    std::fs::create_dir_all(&src).unwrap();
    std::fs::write(src.join("main.rs"), "fn main() {}").unwrap();
    let file = dir.join("file.txt");
    std::fs::write(&file, "x").unwrap();
    for target in [&src, &file] {
        let t = target.to_str().unwrap();
        for args in [
            vec!["simulate", "--t-end", "0.1", "--out", t],
            vec!["optimize", "--problem", "periodic-cot", "--out", t],
        ] {
            let start = std::time::Instant::now();
            let o = run(&args);
            assert_error(&o, 1, &["--out", t]);
            // Refused before the solve (a periodic-cot continuation takes many seconds).
            assert!(start.elapsed().as_secs_f64() < 5.0, "{:?}", start.elapsed());
        }
    }
    assert_eq!(names(&src), ["main.rs"]);
    assert_eq!(std::fs::read_to_string(&file).unwrap(), "x");
    // A path below a file: the file in the way is named, and the reason is printed once, not
    // repeated by the error chain ("File exists" alone named no file).
    let o = run(&[
        "generate",
        "scenes/paper.toml",
        "-o",
        file.join("x.rs").to_str().unwrap(),
    ]);
    assert_error(&o, 1, &["file.txt"]);
    let why = "file.txt is a file, not a directory";
    assert_eq!(stderr(&o).matches(why).count(), 1, "{}", stderr(&o));
    std::fs::remove_dir_all(&dir).unwrap();
}

/// No run overwrites what it reads or what it did not write: `generate -o` refuses its own
/// scene and the URDF the scene names, `--out` refuses a directory holding that URDF, and a
/// directory that merely holds a file of the command's output name (a stored optimum) is not
/// taken for an earlier output.
#[test]
fn a_runs_inputs_and_foreign_files_are_never_overwritten() {
    let dir = tmpdir("inputs");
    let urdf_dir = dir.join("robot");
    std::fs::create_dir_all(&urdf_dir).unwrap();
    let urdf = std::fs::read_to_string(root().join("testkit/tests/urdf/planar2.urdf")).unwrap();
    std::fs::write(urdf_dir.join("arm.urdf"), &urdf).unwrap();
    let scene = dir.join("arm.toml");
    let scene_text = "name = \"arm\"\nurdf = \"robot/arm.urdf\"\nkernels = [\"mass_matrix\"]\n";
    std::fs::write(&scene, scene_text).unwrap();
    let scene_s = scene.to_str().unwrap();
    for target in [scene.clone(), urdf_dir.join("arm.urdf")] {
        let o = run(&["generate", scene_s, "-o", target.to_str().unwrap()]);
        assert_error(&o, 1, &["-o", "an input of this run"]);
    }
    assert_eq!(std::fs::read_to_string(&scene).unwrap(), scene_text);
    assert_eq!(
        std::fs::read_to_string(urdf_dir.join("arm.urdf")).unwrap(),
        urdf
    );
    // An earlier `simulate` output that now holds the URDF of the scene.
    let out = urdf_dir.to_str().unwrap();
    std::fs::write(
        urdf_dir.join(bf_output::MANIFEST),
        r#"{"command": "simulate", "status": "success"}"#,
    )
    .unwrap();
    let o = run(&[
        "simulate", "--scene", scene_s, "--q0", "0,0", "--t-end", "0.1", "--out", out,
    ]);
    assert_error(&o, 1, &["--out", "arm.urdf", "an input of this run"]);
    assert_eq!(
        std::fs::read_to_string(urdf_dir.join("arm.urdf")).unwrap(),
        urdf
    );
    // One report's set is not another's: the manifest names the report, which is checked
    // before the work.
    let strategies = dir.join("strategies");
    std::fs::create_dir_all(&strategies).unwrap();
    std::fs::write(strategies.join("strategies.md"), "# table").unwrap();
    std::fs::write(
        strategies.join(bf_output::MANIFEST),
        format!(
            r#"{{"command": "{}", "status": "success"}}"#,
            ball_finger::commands::report::output_command("strategies")
        ),
    )
    .unwrap();
    let o = run(&[
        "report",
        "speed-accuracy",
        "--quick",
        "--out",
        strategies.to_str().unwrap(),
    ]);
    assert_error(
        &o,
        1,
        &[
            "--out",
            "output of `report strategies`, not of `report speed-accuracy`",
        ],
    );
    assert_eq!(
        std::fs::read_to_string(strategies.join("strategies.md")).unwrap(),
        "# table"
    );
    // A stored solution with notes beside it, and no manifest.
    let stored = dir.join("stored");
    std::fs::create_dir_all(stored.join("notes")).unwrap();
    std::fs::write(stored.join("solution.json"), "{}").unwrap();
    std::fs::write(stored.join("notes/why.txt"), "keep").unwrap();
    let o = run(&[
        "optimize",
        "--problem",
        "reach",
        "--strategy",
        "direct",
        "--out",
        stored.to_str().unwrap(),
    ]);
    assert_error(&o, 1, &["--out", "was not written by `optimize`"]);
    assert_eq!(
        std::fs::read_to_string(stored.join("notes/why.txt")).unwrap(),
        "keep"
    );
    std::fs::remove_dir_all(&dir).unwrap();
}

/// A closed pipe ends the program quietly with the status of a process stopped by SIGPIPE; a
/// full device is an error naming it.
#[test]
fn io_errors_do_not_panic() {
    // The iiwa7 module is far larger than a pipe buffer, so the writer sees the closed pipe.
    let mut child = bin()
        .current_dir(root())
        .args(["generate", "scenes/iiwa7.toml"])
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let mut head = [0u8; 10];
    child.stdout.take().unwrap().read_exact(&mut head).unwrap();
    // The read end is dropped here.
    let out = child.wait_with_output().unwrap();
    assert_eq!(&head, b"// @genera");
    assert_eq!(out.status.code(), Some(141), "{}", stderr(&out));
    assert!(stderr(&out).is_empty(), "{}", stderr(&out));

    if Path::new("/dev/full").exists() {
        let full = || {
            std::fs::OpenOptions::new()
                .write(true)
                .open("/dev/full")
                .unwrap()
        };
        let out = bin()
            .current_dir(root())
            .args(["eval", "scenes/paper.toml", "--q", "0,0,0", "--qd", "0,0,0"])
            .stdout(full())
            .output()
            .unwrap();
        assert_error(&out, 1, &["standard output", "No space left"]);
        let out = run(&["generate", "scenes/paper.toml", "-o", "/dev/full"]);
        assert_error(&out, 1, &["/dev/full", "No space left"]);
        // Standard error on a full device: its notes are lost, the result on standard output
        // and the exit status are not (`eval` writes a note to stderr before its JSON).
        let copy = std::env::temp_dir().join(format!("bf-full-{}.toml", std::process::id()));
        std::fs::copy(root().join("scenes/paper.toml"), &copy).unwrap();
        let out = bin()
            .current_dir(root())
            .args([
                "eval",
                copy.to_str().unwrap(),
                "--q",
                "0,0,0",
                "--qd",
                "0,0,0",
            ])
            .stderr(full())
            .output()
            .unwrap();
        std::fs::remove_file(&copy).ok();
        assert_eq!(out.status.code(), Some(0));
        let json: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
        assert!(json["M"].is_array(), "{json}");
    }
}

/// Runs that cannot fit their limits are refused up front with the option and the limit, as
/// wrong command lines (exit status 2); a run that reaches the sample limit stops, writes what
/// it has and marks it FAILED (exit status 1).
#[test]
fn resource_limits_are_checked() {
    let dir = tmpdir("limits");
    let out = dir.join("out");
    let out_s = out.to_str().unwrap();
    let cases: [(&[&str], &[&str]); 6] = [
        // 65 points in one Radau element: more than the mesh's 64 (the solve used to fail
        // after its start with exit status 1).
        (
            &[
                "optimize",
                "--problem",
                "reach",
                "--points",
                "130",
                "--elements",
                "2",
            ],
            &["--points 130 --elements 2", "64 per element"],
        ),
        (
            &["simulate", "--output-dt", "1e-7", "--out", out_s],
            &["--output-dt", "--max-samples 1000000"],
        ),
        // The grid k·1e-5 s over 10 s is 1 000 001 samples, and the steps add at least 200.
        (
            &["simulate", "--output-dt", "1e-5", "--out", out_s],
            &["1.000e6 grid samples", "at least 2.000e2 step samples"],
        ),
        (
            &["simulate", "--t-end", "1e300", "--out", out_s],
            &["--t-end 1e300 s", "--max-steps 10000000"],
        ),
        (
            &["optimize", "--problem", "reach", "--elements", "100000"],
            &["--elements 100000", "5000"],
        ),
        (
            &[
                "optimize",
                "--problem",
                "reach",
                "--points",
                "3000",
                "--scheme",
                "lg",
            ],
            &["--points 3000", "200", "--scheme radau"],
        ),
    ];
    for (args, mention) in cases {
        assert_error(&run(args), 2, mention);
    }
    // Refused before the states are allocated (a billion would exhaust the memory).
    assert_error(
        &run(&["bench", "scenes/paper.toml", "--states", "1000000000"]),
        2,
        &["--states", "100000"],
    );
    assert!(!out.exists(), "nothing written by refused runs");
    let o = run(&[
        "simulate",
        "--t-end",
        "1",
        "--max-samples",
        "50",
        "--out",
        out_s,
    ]);
    assert_error(&o, 1, &["--max-samples 50", "written to"]);
    let tj = json(&out.join("trajectory.json"));
    assert_eq!(tj["t"].as_array().unwrap().len(), 50);
    let sm = json(&out.join("summary.json"));
    assert!(sm["error"].as_str().unwrap().contains("--max-samples"));
    assert!(out.join(bf_output::FAILED).exists());
    // An arm (a scene without a ball) keeps the same limits.
    let arm = dir.join("arm");
    let o = run(&[
        "simulate",
        "--scene",
        "scenes/puma560.toml",
        "--t-end",
        "2",
        "--max-samples",
        "50",
        "--out",
        arm.to_str().unwrap(),
    ]);
    assert_error(&o, 1, &["--max-samples 50", "sample limit reached"]);
    let csv = std::fs::read_to_string(arm.join("trajectory.csv")).unwrap();
    assert_eq!(csv.lines().count(), 1 + 50, "a header and the 50 samples");
    assert!(arm.join(bf_output::FAILED).exists());
    std::fs::remove_dir_all(&dir).unwrap();
}

/// Negative values reach the option's own check; non-finite failures name the option or file.
#[test]
fn errors_name_the_option_file_or_quantity() {
    let dir = tmpdir("names");
    let out = dir.join("out");
    let out_s = out.to_str().unwrap();
    let usage: [(&[&str], &[&str]); 11] = [
        (
            &["simulate", "--rtol", "-1e-8"],
            &["--rtol", "must be a finite number > 0", "-1e-8"],
        ),
        // Tolerances below the f64 rounding that the error estimate can measure, and a largest
        // step below the adaptive step's floor, are the command line's (they ended as a
        // "stiff dynamics" failure, an internal `h_min` setting, or an unverified optimum).
        (
            &["simulate", "--rtol", "1e-30"],
            &["--rtol", "at least 1e-14", "1e-30"],
        ),
        (
            &["simulate", "--h-max", "1e-15"],
            &["--h-max", "at least 1e-14", "1e-15"],
        ),
        (
            &["optimize", "--problem", "reach", "--verify-rtol", "1e-308"],
            &["--verify-rtol", "1e-14", "1e-308"],
        ),
        // An arm's configuration beyond the kernels' angle range names its option (it was
        // blamed on --scene, as "invalid bounds" of a constraint).
        (
            &[
                "optimize",
                "--problem",
                "reach-arm",
                "--scene",
                "tests/fixtures/planar2_arm.toml",
                "--start",
                "1e20,0",
            ],
            &["--start", "beyond ±2²⁰"],
        ),
        (
            &["optimize", "--problem", "reach", "--verify-rtol", "0.5"],
            &["--verify-rtol", "10 % per step", "0.5"],
        ),
        // A step count beyond f64 is said as such, the step plainly.
        (
            &["simulate", "--integrator", "rk4", "--step", "1e-308"],
            &["--step 1e-308 s"],
        ),
        (
            &["simulate", "--t-end", "1e308"],
            &["needs more than 1e308 steps"],
        ),
        (
            &["simulate", "--step", "-0.001"],
            &["--step", "must be a finite number > 0"],
        ),
        (
            &["optimize", "--problem", "reach", "--points", "-5"],
            &["--points", "not negative"],
        ),
        (
            &["optimize", "--problem", "reach", "--starts", "-1"],
            &["--starts", "not negative"],
        ),
    ];
    for (args, mention) in usage {
        let o = run(args);
        assert_error(&o, 2, mention);
        assert!(
            !stderr(&o).contains("unexpected argument"),
            "{}",
            stderr(&o)
        );
    }
    let o = run(&["simulate", "--qd0", "1e300,0,0", "--out", out_s]);
    // The model's own reason: "non-finite C q̇ + g or potential".
    assert_error(&o, 1, &["--qd0 1e300,0,0", "non-finite"]);
    assert!(!out.exists());
    // Finite torques whose accelerations overflow name the torque options.
    let o = run(&["simulate", "--pd", "1e308,0,0", "--out", out_s]);
    assert_error(&o, 1, &["cannot start", "--pd 1e308,0,0"]);
    assert!(!out.exists());
    let tau = dir.join("huge.csv");
    std::fs::write(&tau, "t,tau1,tau2,tau3\n0,1e300,0,0\n1,1e300,0,0\n").unwrap();
    let o = run(&[
        "simulate",
        "--torques",
        tau.to_str().unwrap(),
        "--t-end",
        "1",
        "--out",
        out_s,
    ]);
    assert_error(&o, 1, &["huge.csv", "1e300"]);

    // What gave a value is what the message names: a series' end is not a `--t-end` never
    // given, a missing series is `--torques`'s, an angle of an `--init` file is that file's
    // (exit 1, not a command-line error), and a huge value is shown as a number, not as 309
    // digits.
    let long = dir.join("long.csv");
    std::fs::write(
        &long,
        "t,tau1,tau2,tau3
0,0,0,0
1e308,0,0,0
",
    )
    .unwrap();
    let o = run(&[
        "simulate",
        "--torques",
        long.to_str().unwrap(),
        "--out",
        out_s,
    ]);
    assert_error(&o, 2, &["--torques series ends", "1e308 s", "--max-steps"]);
    assert!(!stderr(&o).contains("--t-end 1e308"), "{}", stderr(&o));
    let o = run(&["simulate", "--torques", "no-such.csv", "--out", out_s]);
    assert_error(&o, 1, &["--torques no-such.csv"]);
    let wound = dir.join("wound.json");
    std::fs::write(&wound, r#"{"q": [1e10, 0.5, 0.5]}"#).unwrap();
    let o = run(&[
        "simulate",
        "--init",
        wound.to_str().unwrap(),
        "--out",
        out_s,
    ]);
    assert_error(&o, 1, &["wound.json", "initial state", "q1 = 1e10"]);
    // A cost weight that makes the objective overflow is named beside the scene.
    let o = run(&[
        "optimize",
        "--problem",
        "reach-arm",
        "--scene",
        "scenes/puma560.toml",
        "--effort-weight",
        "1e308",
        "--out",
        dir.join("arm").to_str().unwrap(),
    ]);
    assert_error(&o, 1, &["--effort-weight 1e308", "non-finite objective"]);
    assert!(!dir.join("arm").exists());
    for args in [
        &["simulate", "--rtol", "1e308", "--out", out_s][..],
        &["optimize", "--problem", "reach", "--hop-scale", "1e308"][..],
        &["optimize", "--problem", "reach", "--verify-rtol", "1e308"][..],
    ] {
        let o = run(args);
        assert_error(&o, 2, &["got 1e308"]);
    }
    let tiny = dir.join("tiny");
    let o = run(&[
        "simulate",
        "--t-end",
        "1e-300",
        "--out",
        tiny.to_str().unwrap(),
    ]);
    let shown = String::from_utf8_lossy(&o.stdout);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(shown.contains("simulated t = 0 .. 1e-300 s"), "{shown}");
    std::fs::remove_dir_all(&dir).unwrap();
}

/// `eval` at states where a kernel overflows: an error naming the entry, exit 1, and nothing
/// on stdout (previously `null` in the JSON and exit 0); an ε that would overflow is a usage
/// error (exit 2), found before any kernel runs.
#[test]
fn non_finite_eval_results_are_errors() {
    // A velocity that overflows a kernel is found after the evaluation; an ε whose square
    // would overflow, or be 0, is refused before it, as an option out of its range
    // (`bf_scene::MAX_SMOOTH_EPS`, `MIN_SMOOTH_EPS`).
    for (extra, status, mention) in [
        (["--qd", "1e200,0,0"], 1, ["not finite", "--qd 1e200,0,0"]),
        (["--eps", "1e308"], 2, ["--eps", "[1e-150, 1e150]"]),
        (["--eps", "1e-320"], 2, ["--eps", "[1e-150, 1e150]"]),
    ] {
        let mut args = vec!["eval", "scenes/paper.toml", "--q", "0.3,-0.5,0.8"];
        if extra[0] != "--qd" {
            args.extend(["--qd", "0,0,0"]);
        }
        args.extend(extra);
        let o = run(&args);
        assert_error(&o, status, &mention);
        assert!(
            o.stdout.is_empty(),
            "{}",
            String::from_utf8_lossy(&o.stdout)
        );
    }
    // The same state with ordinary values is finite everywhere.
    let o = run(&[
        "eval",
        "scenes/paper.toml",
        "--q",
        "0.3,-0.5,0.8",
        "--qd",
        "1,0,0",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    // A URDF joint origin that overflows is among the extreme values the error names (the
    // placement origins are baked into the kernels, not named constants).
    let dir = tmpdir("origin");
    let urdf = std::fs::read_to_string(root().join("testkit/tests/urdf/planar2.urdf")).unwrap();
    let huge = urdf.replacen(
        r#"<origin xyz="1 0 0"/>"#,
        r#"<origin xyz="1e308 0 0"/>"#,
        1,
    );
    assert_ne!(huge, urdf);
    let path = dir.join("huge.urdf");
    std::fs::write(&path, huge).unwrap();
    let o = run(&[
        "eval",
        path.to_str().unwrap(),
        "--q",
        "0.3,0.2",
        "--qd",
        "0,0",
    ]);
    assert_error(&o, 1, &["not finite", "link2.origin.x = 1e308"]);
    std::fs::remove_dir_all(&dir).unwrap();
}

/// `--param` values pass the scene file's checks: a negative ball radius or a zero link mass is
/// a wrong command line (exit status 2) naming the parameter, its value and the rule, before
/// anything is computed (previously both ran and printed numbers).
#[test]
fn param_values_are_validated_as_the_scene_file_is() {
    let o = run(&[
        "eval",
        "scenes/human.toml",
        "--q",
        "0.3,-0.5,0.8",
        "--qd",
        "0,0,0",
        "--param",
        "ball.radius=-1",
    ]);
    assert_error(&o, 2, &["ball.radius", "-1", "must be > 0"]);
    assert!(
        o.stdout.is_empty(),
        "{}",
        String::from_utf8_lossy(&o.stdout)
    );
    let dir = tmpdir("param");
    let out = dir.join("out");
    let o = run(&[
        "simulate",
        "--scene",
        "scenes/human.toml",
        "--param",
        "link3.mass=0",
        "--t-end",
        "0.1",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert_error(
        &o,
        2,
        &["link3.mass", "= 0", "links[2].mass", "must be > 0"],
    );
    assert!(!out.exists());
    // A mass negligible next to the others' (the scale floor) is refused the same way.
    let o = run(&[
        "simulate",
        "--scene",
        "scenes/human.toml",
        "--param",
        "link3.mass=1e-300",
        "--t-end",
        "0.1",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert_error(&o, 2, &["link3.mass", "1e-300"]);
    std::fs::remove_dir_all(&dir).unwrap();
}

/// Unclear messages and unbounded runs: each error names the option or file, the quantity and
/// the value, before any work; a wrong command line exits with status 2, a state or file that
/// does not fit with 1.
#[test]
fn errors_name_the_cause_and_runs_are_bounded() {
    let dir = tmpdir("cause");
    let out = dir.join("out");
    let out_s = out.to_str().unwrap();
    // bench: a budget beyond the documented maximum.
    let o = run(&["bench", "scenes/paper.toml", "--time", "1e300"]);
    assert_error(&o, 2, &["--time", "at most 3600", "1e300"]);
    // simulate: a contact mode away from the ball names h(q0) and its value.
    let o = run(&[
        "simulate", "--mode0", "stick", "--t-end", "0.1", "--out", out_s,
    ]);
    assert_error(&o, 1, &["stick", "h(q0) = ", "contact tolerance"]);
    // --init with the wrong number of joint angles names the option, the count and the scene's.
    let init = dir.join("init.json");
    std::fs::write(&init, r#"{"q": [0.1, 0.2]}"#).unwrap();
    let init_s = init.to_str().unwrap();
    let o = run(&[
        "simulate", "--init", init_s, "--t-end", "0.1", "--out", out_s,
    ]);
    assert_error(
        &o,
        1,
        &["--init", "init.json", "`q` has 2 values", "3 joints"],
    );
    // An arm solution given to a ball scene says what it is.
    std::fs::write(
        &init,
        r#"{"problem": "reach-arm", "scene": "planar2_arm", "start": [0.0, 0.0]}"#,
    )
    .unwrap();
    let o = run(&[
        "simulate",
        "--scene",
        "scenes/paper.toml",
        "--init",
        init_s,
        "--t-end",
        "0.1",
        "--out",
        out_s,
    ]);
    assert_error(
        &o,
        1,
        &["--init", "an arm solution", "reach-arm", "planar2_arm"],
    );
    // Destabilising PD gains are refused before the run.
    let o = run(&[
        "simulate",
        "--pd",
        "0.5,0.5,0.5",
        "--pd-gains=-100,0",
        "--t-end",
        "0.1",
        "--out",
        out_s,
    ]);
    assert_error(&o, 2, &["--pd-gains", "kp of joint 1 is -100", ">= 0"]);
    // A negative shard index is --shard's error, not clap's "unexpected argument".
    let o = run(&[
        "optimize",
        "--problem",
        "periodic-qc",
        "--shard",
        "-1/2",
        "--out",
        out_s,
    ]);
    assert_error(&o, 2, &["--shard", "-1/2", "1 <= k <= m"]);
    assert!(!out.exists());
    std::fs::remove_dir_all(&dir).unwrap();
}

/// A solution file whose own fields disagree is refused when it is read (by `track`,
/// `simulate --init` and `--warm-start` alike), naming the file and the field: a `period`
/// that is not the sum of the phases' durations (`track` times the plan by the one, the
/// verification by the other), a non-positive duration, trajectory columns of other lengths
/// (once read as a shorter trajectory), and times that go back.
#[test]
fn a_solution_whose_fields_disagree_is_refused_when_read() {
    use ball_finger::pipeline::{OcpSolution, SolutionIo};
    let dir = tmpdir("disagreeing-solution");
    let stored = root().join("data/optima/periodic-qc");
    std::fs::copy(
        stored.join("solution-internals.json"),
        dir.join("solution-internals.json"),
    )
    .unwrap();
    let text = std::fs::read_to_string(stored.join("solution.json")).unwrap();
    let good: serde_json::Value = serde_json::from_str(&text).unwrap();
    let read = |edit: &dyn Fn(&mut serde_json::Value)| {
        let mut v = good.clone();
        edit(&mut v);
        let path = dir.join("solution.json");
        std::fs::write(&path, v.to_string()).unwrap();
        OcpSolution::read_json(&path)
            .map(drop)
            .map_err(|e| e.to_string())
    };
    assert_eq!(read(&|_| {}), Ok(()));
    let period = good["period"].as_f64().unwrap();
    for (edit, needle) in [
        (
            Box::new(|v: &mut serde_json::Value| v["period"] = (2.0 * period).into())
                as Box<dyn Fn(&mut serde_json::Value)>,
            "`period` is",
        ),
        (
            Box::new(|v: &mut serde_json::Value| v["phase_durations"][1] = (-0.01).into()),
            "`phase_durations[1]` is -0.01",
        ),
        (
            Box::new(|v: &mut serde_json::Value| {
                v["nodes"]["q1"].as_array_mut().unwrap().truncate(10);
            }),
            "column `nodes.q1` has 10 samples",
        ),
        // Not the first column of its group: rows are built by index and once ran past it.
        (
            Box::new(|v: &mut serde_json::Value| {
                v["dense"]["omega_y"].as_array_mut().unwrap().truncate(10);
            }),
            "column `dense.omega_y` has 10 samples",
        ),
        (
            Box::new(|v: &mut serde_json::Value| {
                v["nodes"]["tau3"].as_array_mut().unwrap().push(0.0.into());
            }),
            "column `nodes.tau3` has",
        ),
        (
            Box::new(|v: &mut serde_json::Value| {
                v["dense"]["t"].as_array_mut().unwrap().swap(0, 1);
            }),
            "`dense`: `t[1]`",
        ),
        // The stick phase relabelled: its collocation data still hold the contact force.
        (
            Box::new(|v: &mut serde_json::Value| v["modes"][1] = "free".into()),
            "`modes[1]` is `free`, but its collocation data",
        ),
        // The internals are the file beside the solution that it names; a path in that name
        // was followed wherever it led (and its error blamed the wrong file).
        (
            Box::new(|v: &mut serde_json::Value| v["internals"] = "/etc/passwd".into()),
            "its `internals` (\"/etc/passwd\") is not the name of a file beside it",
        ),
        (
            Box::new(|v: &mut serde_json::Value| {
                v["internals"] = "../periodic-qc/solution-internals.json".into();
            }),
            "its `internals`",
        ),
        (
            Box::new(|v: &mut serde_json::Value| v["internals"] = 3.into()),
            "its `internals` (3)",
        ),
    ] {
        let err = read(&*edit).unwrap_err();
        assert!(
            err.contains("solution.json") && err.contains(needle),
            "{needle}: {err}"
        );
    }
}
