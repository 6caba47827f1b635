//! End-to-end tests of the `ball-finger` binary: `eval` through the compiled kernels must agree
//! with `eval` through the interpreter (two independent evaluation paths of the same graphs),
//! `generate` must be deterministic and produce the code compiled into `bf-generated`, and bad
//! user input must give a clear error and a non-zero exit code, never a panic.

use std::process::Output;

#[path = "common/cli.rs"]
mod cli_util;
use cli_util::{bin, ok, root, run, tmpdir};

/// [`assert_clean_failure`] of a wrong command line: exit status 2 (clap's, and the commands'
/// own checks of their options), as `optimize --help` documents.
fn assert_usage_error(out: &Output, must_mention: &[&str]) {
    assert_clean_failure(out, must_mention);
    assert_eq!(
        out.status.code(),
        Some(2),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
}

fn assert_clean_failure(out: &Output, must_mention: &[&str]) {
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(
        !out.status.success(),
        "expected failure, got success; stderr: {stderr}"
    );
    assert!(
        !stderr.contains("panicked"),
        "panic instead of an error: {stderr}"
    );
    for m in must_mention {
        assert!(stderr.contains(m), "stderr should mention {m:?}: {stderr}");
    }
}

fn eval_json(scene: &str) -> (serde_json::Value, String) {
    let out = run(&[
        "eval",
        scene,
        "--q",
        "0.3,-0.5,0.8",
        "--qd",
        "0.1,0.2,-0.3",
        "--omega",
        "0,0.5,1",
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let text = String::from_utf8(out.stdout).unwrap();
    (
        serde_json::from_str(&text).expect("eval prints one JSON object"),
        text,
    )
}

fn flatten(v: &serde_json::Value, out: &mut Vec<f64>) {
    match v {
        serde_json::Value::Number(n) => out.push(n.as_f64().unwrap()),
        serde_json::Value::Array(a) => a.iter().for_each(|x| flatten(x, out)),
        other => panic!("unexpected JSON value {other}"),
    }
}

/// All numbers of a JSON object of outputs, in key order.
fn flatten_obj(v: &serde_json::Value, out: &mut Vec<f64>) {
    for x in v.as_object().unwrap().values() {
        flatten(x, out);
    }
}

#[test]
fn eval_compiled_and_interpreted_agree_on_every_key() {
    let (compiled, compiled_text) = eval_json("scenes/paper.toml");
    // Same numbers under a name that was not compiled: the interpreter path.
    let dir = tmpdir("eval");
    let copy = dir.join("paper_copy.toml");
    let text = std::fs::read_to_string(root().join("scenes/paper.toml")).unwrap();
    let renamed = text.replacen("name = \"paper\"", "name = \"paper_copy\"", 1);
    assert_ne!(renamed, text);
    std::fs::write(&copy, format!("# a user's copy\n{renamed}")).unwrap();
    let (interpreted, _) = eval_json(copy.to_str().unwrap());
    let keys = [
        "p_e",
        "R3",
        "J_p",
        "J_o",
        "M",
        "C",
        "Cqd",
        "g",
        "alpha",
        "sat_alpha",
        "p_c",
        "h",
        "J_c",
        "sat_alpha_smooth",
        "p_c_smooth",
        "h_smooth",
        "J_c_smooth",
    ];
    // The documented key order is part of the interface.
    let positions: Vec<usize> = keys
        .iter()
        .map(|k| compiled_text.find(&format!("\"{k}\":")).expect(k))
        .collect();
    assert!(
        positions.windows(2).all(|w| w[0] < w[1]),
        "key order {positions:?}"
    );
    // …then "kernels": every kernel of the compiled module, in emission order.
    assert_eq!(compiled.as_object().unwrap().len(), keys.len() + 1);
    let kc = compiled["kernels"].as_object().unwrap();
    let ki = interpreted["kernels"].as_object().unwrap();
    let order: Vec<usize> = bf_generated::paper::KERNELS
        .iter()
        .map(|k| compiled_text.find(&format!("\"{k}\":{{")).expect(k))
        .collect();
    assert!(order.windows(2).all(|w| w[0] < w[1]), "kernel order");
    assert_eq!(kc.len(), bf_generated::paper::KERNELS.len());
    for k in bf_generated::paper::KERNELS {
        let (mut a, mut b) = (Vec::new(), Vec::new());
        flatten_obj(&kc[*k], &mut a);
        flatten_obj(&ki[*k], &mut b);
        assert_eq!(a.len(), b.len(), "{k}");
        for (x, y) in a.iter().zip(&b) {
            assert!((x - y).abs() <= 1e-12 * (1.0 + x.abs()), "{k}: {x} vs {y}");
        }
    }
    // The kernel outputs agree with the named quantities (two output paths of one module).
    let (mut m, mut mk) = (Vec::new(), Vec::new());
    flatten(&compiled["M"], &mut m);
    flatten(&compiled["kernels"]["mass_matrix"]["m"], &mut mk);
    assert_eq!(m, mk);
    for k in keys {
        let (mut a, mut b) = (Vec::new(), Vec::new());
        flatten(&compiled[k], &mut a);
        flatten(&interpreted[k], &mut b);
        assert_eq!(a.len(), b.len(), "{k}");
        for (x, y) in a.iter().zip(&b) {
            assert!((x - y).abs() <= 1e-12 * (1.0 + x.abs()), "{k}: {x} vs {y}");
        }
    }
    // Physical sanity independent of the code under test: R3 orthonormal, |n| implied by h.
    let mut r = Vec::new();
    flatten(&compiled["R3"], &mut r);
    for i in 0..3 {
        for j in 0..3 {
            let dot: f64 = (0..3).map(|k| r[3 * k + i] * r[3 * k + j]).sum();
            assert!((dot - if i == j { 1.0 } else { 0.0 }).abs() < 1e-14);
        }
    }
    std::fs::remove_dir_all(dir).ok();
}

#[test]
fn generate_is_deterministic_and_writes_atomically() {
    let dir = tmpdir("gen");
    let a = dir.join("a.rs");
    let out = run(&["generate", "scenes/paper.toml", "-o", a.to_str().unwrap()]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let stdout = run(&["generate", "scenes/paper.toml"]);
    assert!(stdout.status.success());
    let file = std::fs::read(&a).unwrap();
    assert_eq!(file, stdout.stdout, "file and stdout output differ");
    assert!(String::from_utf8_lossy(&file).contains("@generated"));
    let report = run(&[
        "generate",
        "scenes/paper.toml",
        "-o",
        a.to_str().unwrap(),
        "--report",
    ]);
    let text = String::from_utf8_lossy(&report.stdout);
    assert!(text.contains("mass_matrix"), "report lists kernels: {text}");
    let leftovers = std::fs::read_dir(&dir).unwrap().count();
    assert_eq!(leftovers, 1, "no temporary files left behind");
    std::fs::remove_dir_all(dir).ok();
}

#[test]
fn generate_emits_the_robot_kernels_in_every_variant() {
    use bf_codegen::{EmitSettings, FloatTy, Scene, generate_with, kernels::with_robot_kernels};
    let text = std::fs::read_to_string(root().join("scenes/puma560.toml")).unwrap();
    let scene = Scene::from_toml_str(&text, "scenes/puma560.toml").unwrap();
    let full = with_robot_kernels(&scene);
    for (flags, float, fma, no_std) in [
        (vec![], FloatTy::F64, false, false),
        (vec!["--float", "f32"], FloatTy::F32, false, false),
        (vec!["--fma"], FloatTy::F64, true, false),
        (vec!["--float", "f32", "--fma"], FloatTy::F32, true, false),
        (vec!["--no-std"], FloatTy::F64, false, true),
        (
            vec!["--float", "f32", "--no-std"],
            FloatTy::F32,
            false,
            true,
        ),
    ] {
        let mut args = vec!["generate", "scenes/puma560.toml"];
        args.extend(&flags);
        let out = run(&args);
        assert!(out.status.success(), "{flags:?}");
        let want = generate_with(&full, &text, &EmitSettings { float, fma, no_std })
            .unwrap()
            .code;
        assert!(
            out.stdout == want.as_bytes(),
            "{flags:?}: not the generator's output"
        );
        let code = String::from_utf8(out.stdout).unwrap();
        let ty = if float == FloatTy::F32 { "f32" } else { "f64" };
        assert!(
            code.contains(&format!("pub fn inverse_dynamics(\n    q: &[{ty}; NQ]"))
                || code.contains(&format!("pub fn inverse_dynamics(q: &[{ty}; NQ]")),
            "{flags:?}"
        );
        assert!(code.contains("pub fn regressor("), "{flags:?}");
        assert_eq!(code.contains(&format!("{ty}::mul_add(")), fma, "{flags:?}");
        // A no_std module carries its own mathematics and no allocating `eval_flat`.
        assert_eq!(code.contains("trait KernelMath"), no_std, "{flags:?}");
        assert_eq!(code.contains("pub fn eval_flat("), !no_std, "{flags:?}");
    }
    assert_clean_failure(
        &run(&["generate", "scenes/puma560.toml", "--float", "f16"]),
        &["--float", "f16"],
    );
    assert_clean_failure(
        &run(&["generate", "scenes/puma560.toml", "--no-std", "--fma"]),
        &["--no-std", "--fma"],
    );
}

/// A stream that does not end, given where a file is read, is refused once it passes the input
/// bound (`bf_scene::MAX_INPUT_BYTES`), with exit status 1, for every kind of input; it used to
/// be read until the machine's memory ran out.
#[cfg(target_os = "linux")]
#[test]
fn an_endless_input_is_refused() {
    let dir = tmpdir("endless");
    let scene = dir.join("urdf_zero.toml");
    std::fs::write(&scene, "name = \"u\"\nurdf = \"/dev/zero\"\n").unwrap();
    let out = dir.join("out");
    let out = out.to_str().unwrap();
    for args in [
        vec!["generate", "/dev/zero"],
        vec!["generate", scene.to_str().unwrap()],
        vec!["simulate", "--init", "/dev/zero", "--out", out],
        vec!["simulate", "--torques", "/dev/zero", "--out", out],
        vec![
            "optimize",
            "--problem",
            "reach",
            "--warm-start",
            "/dev/zero",
            "--out",
            out,
        ],
        vec!["track", "/dev/zero", "--out", out],
    ] {
        let o = run(&args);
        assert_clean_failure(&o, &["/dev/zero", "more than 256 MiB"]);
        assert_eq!(o.status.code(), Some(1), "{args:?}");
    }
    assert!(!dir.join("out").exists());
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn bad_cli_input_gives_clear_errors() {
    let missing = run(&["eval", "scenes/nope.toml", "--q", "0,0,0", "--qd", "0,0,0"]);
    assert_clean_failure(&missing, &["scenes/nope.toml"]);
    // Each error in the chain states only its own context, so the operating system's reason
    // (the last part of the message) appears once.
    let stderr = String::from_utf8_lossy(&missing.stderr);
    let os_reason = stderr
        .rsplit(": ")
        .next()
        .map(str::trim)
        .unwrap_or_default()
        .to_string();
    assert!(!os_reason.is_empty(), "{stderr}");
    assert_eq!(stderr.matches(&os_reason).count(), 1, "{stderr}");
    assert_usage_error(
        &run(&[
            "eval",
            "scenes/paper.toml",
            "--q",
            "0,NaN,0",
            "--qd",
            "0,0,0",
        ]),
        &["--q", "element 2"],
    );
    assert_usage_error(
        &run(&["eval", "scenes/paper.toml", "--q", "0,0", "--qd", "0,0,0"]),
        &["--q", "expected 3"],
    );
    // Beyond ±2²⁰ rad the kernels' sine and cosine are NaN: the angle is refused by name.
    assert_usage_error(
        &run(&[
            "eval",
            "scenes/paper.toml",
            "--q",
            "0,2e6,0",
            "--qd",
            "0,0,0",
        ]),
        &["--q", "q2 = 2e6 rad", "2²⁰"],
    );
    assert_usage_error(
        &run(&[
            "eval",
            "scenes/paper.toml",
            "--q",
            "0,0,0",
            "--qd",
            "0,0,0",
            "--eps",
            "-1",
        ]),
        &["--eps"],
    );
    // An arm has no ball: the ball's velocity and the contact's ε have nothing to act on.
    for (opt, value) in [("--omega", "0,0,1"), ("--eps", "0.01")] {
        let mut args = vec!["eval", "scenes/puma560.toml", "--q", "0,0,0,0,0,0"];
        args.extend(["--qd", "0,0,0,0,0,0", opt, value]);
        assert_usage_error(&run(&args), &[opt, "puma560", "no ball"]);
    }
    let dir = tmpdir("bad");
    let bad = dir.join("bad.toml");
    let text = std::fs::read_to_string(root().join("scenes/paper.toml")).unwrap();
    std::fs::write(&bad, text.replacen("mass = 0.02", "mass = -0.02", 1)).unwrap();
    assert_clean_failure(
        &run(&["generate", bad.to_str().unwrap()]),
        &["bad.toml", "mass"],
    );
    let out_file = dir.join("never.rs");
    assert_clean_failure(
        &run(&[
            "generate",
            bad.to_str().unwrap(),
            "-o",
            out_file.to_str().unwrap(),
        ]),
        &["mass"],
    );
    assert!(!out_file.exists(), "no output file on failure");
    assert_usage_error(
        &run(&["optimize", "--problem", "periodic-nope"]),
        &["--problem", "periodic-qc"],
    );
    assert_usage_error(
        &run(&[
            "optimize",
            "--problem",
            "periodic-qc",
            "--scheme",
            "chebyshev",
        ]),
        &["--scheme"],
    );
    assert_usage_error(
        &run(&["optimize", "--problem", "periodic-qc", "--epsilon", "-1"]),
        &["--epsilon"],
    );
    // An ε whose square leaves f64's range would make every smoothed quantity NaN.
    assert_usage_error(
        &run(&["optimize", "--problem", "periodic-qc", "--epsilon", "1e308"]),
        &["--epsilon", "1e150"],
    );
    assert_clean_failure(
        &run(&[
            "optimize",
            "--problem",
            "periodic-qc",
            "--warm-start",
            "/nonexistent.json",
        ]),
        &["--warm-start", "/nonexistent.json"],
    );
    let opt = |extra: &[&str]| {
        let mut a = vec!["optimize", "--problem", "periodic-qc"];
        a.extend_from_slice(extra);
        run(&a)
    };
    assert_usage_error(&opt(&["--strategy", "annealing"]), &["--strategy"]);
    assert_usage_error(
        &opt(&["--strategy", "multistart", "--starts", "0"]),
        &["--starts"],
    );
    // A multi-start option with another strategy would be ignored: refused instead.
    assert_usage_error(
        &opt(&["--strategy", "direct", "--seed", "3"]),
        &["--seed", "multi-start"],
    );
    assert_usage_error(
        &opt(&["--strategy", "continuation", "--starts", "8"]),
        &["--starts", "multi-start"],
    );
    assert_usage_error(&opt(&["--seed", "-1"]), &["--seed"]);
    assert_usage_error(&opt(&["--refine", "-1e-4"]), &["--refine"]);
    assert_usage_error(&opt(&["--refine", "nan"]), &["--refine"]);
    assert_usage_error(
        &opt(&["--scheme", "lg", "--refine", "1e-4"]),
        &["--refine", "radau"],
    );
    assert_usage_error(&opt(&["--verify-rtol", "2"]), &["--verify-rtol"]);
    for bad in ["-3e-8", "nan", "0", "0.5"] {
        assert_usage_error(
            &opt(&["--dual-regularization", bad]),
            &["--dual-regularization"],
        );
    }
    assert_usage_error(&opt(&["--print-level", "7"]), &["--print-level"]);
    std::fs::remove_dir_all(dir).ok();
}

/// The commands' own checks of their options exit with status 2 as clap's do (the documented
/// contract of `optimize --help` and `track --help`; more cases in
/// `bad_cli_input_gives_clear_errors`); a file that cannot be read, or a run that does not
/// converge, exits with 1. A script can then tell a wrong call from a failed run.
#[test]
fn wrong_command_lines_exit_with_status_2_and_failed_runs_with_1() {
    let opt = |extra: &[&str]| {
        let mut a = vec![
            "optimize",
            "--problem",
            "periodic-qc",
            "--out",
            "/nonexistent/out",
        ];
        a.extend_from_slice(extra);
        run(&a)
    };
    for (extra, flag) in [
        (&["--points", "0"][..], "--points"),
        (&["--max-iter", "0"], "--max-iter"),
        (&["--elements", "0"], "--elements"),
        (&["--scheme", "lg", "--points", "201"], "--points"),
        (&["--cone-margin", "2"], "--cone-margin"),
        (&["--torque-margin", "nan"], "--torque-margin"),
        (&["--hop-scale", "-1"], "--hop-scale"),
        (&["--param", "nothing"], "--param"),
        (&["--param", "no.such.name=1"], "--param"),
        (&["--impact-law", "elastic"], "--impact-law"),
        (&["--shard", "3/2"], "--shard"),
        // Ranges of the problem and its scene: a tenth of the ball's radius, the longest phase.
        (&["--approach-clearance", "1"], "--approach-clearance"),
        (&["--min-stick", "5"], "--min-stick"),
    ] {
        assert_usage_error(&opt(extra), &[flag]);
    }
    assert_usage_error(&run(&["simulate", "--t-end", "-1"]), &["--t-end"]);
    assert_usage_error(
        &run(&["report", "bogus"]),
        &["unknown report", "strategies"],
    );
    let plan = root().join("data/optima/periodic-qc-plan/solution.json");
    for (extra, flag) in [
        (&["--periods", "0"][..], "--periods"),
        (&["--periods", "1001"], "--periods"),
        (
            &["--replan", "--replan-iterations", "0"],
            "--replan-iterations",
        ),
        (&["--controller", "bogus"], "--controller"),
        (&["--replan", "--controller", "pd"], "--replan"),
        (&["--impact-law", "bounce"], "--impact-law"),
    ] {
        let mut args = vec!["track", plan.to_str().unwrap()];
        args.extend_from_slice(extra);
        assert_usage_error(&run(&args), &[flag]);
    }
    assert_usage_error(
        &run(&["bench", "scenes/paper.toml", "--states", "0"]),
        &["--states"],
    );
    // Not usage errors: a missing file, and a solve that stops at its iteration limit.
    let out = opt(&["--warm-start", "/nonexistent.json"]);
    assert_clean_failure(&out, &["--warm-start"]);
    assert_eq!(out.status.code(), Some(1));
    let dir = tmpdir("max-iter-1");
    let out = run(&[
        "optimize",
        "--problem",
        "reach",
        "--strategy",
        "direct",
        "--max-iter",
        "1",
        "--out",
        dir.to_str().unwrap(),
    ]);
    assert_clean_failure(&out, &["MaxIterations"]);
    assert_eq!(out.status.code(), Some(1));
}

/// `optimize` end to end on a small problem: the strategy table, the refinement rounds and the
/// verification are printed and stored in solution.json, and they agree with each other.
#[test]
fn optimize_refines_verifies_and_records_it() {
    let dir = tmpdir("opt");
    let out = run(&[
        "optimize",
        "--problem",
        "reach",
        "--strategy",
        "multistart",
        "--starts",
        "2",
        "--refine",
        "1e-6",
        "--out",
        dir.to_str().unwrap(),
    ]);
    let stdout = String::from_utf8_lossy(&out.stdout);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(stdout.contains("multistart (2 starts, seed 0)"), "{stdout}");
    assert!(stdout.contains("mesh refinement to 1e-6"), "{stdout}");
    assert!(stdout.contains("trajectory verification"), "{stdout}");
    let text = std::fs::read_to_string(dir.join("solution.json")).unwrap();
    let sol: serde_json::Value = serde_json::from_str(&text).unwrap();
    assert_eq!(sol["strategy"]["records"].as_array().unwrap().len(), 2);
    let r = &sol["refinement"];
    assert_eq!(r["tol"].as_f64(), Some(1e-6));
    let last = r["history"].as_array().unwrap().last().unwrap().clone();
    // Either the last round's error estimate is within the tolerance (converged), or the
    // refinement says which limit stopped it.
    let within = last["max_error"].as_f64().unwrap() <= 1e-6;
    assert_eq!(r["converged"].as_bool(), Some(within), "{r}");
    // An unmet tolerance is a failed check: exit 1 and a FAILED set, naming it.
    assert_eq!(out.status.success(), within, "{stdout}\n{stderr}");
    assert_eq!(dir.join("FAILED").exists(), !within);
    if !within {
        assert!(r["stop_reason"].as_str().unwrap().contains("limit"), "{r}");
        assert!(stderr.contains("did not reach --refine 1e-6"), "{stderr}");
    }
    assert_eq!(last["objective"].as_f64(), sol["objective"].as_f64());
    // The refined mesh has at least as many points as the default 30 per phase.
    let pts: usize = r["mesh"][0]["degrees"]
        .as_array()
        .unwrap()
        .iter()
        .map(|d| d.as_u64().unwrap() as usize)
        .sum();
    assert!(pts >= 30, "{pts}");
    let v = &sol["verification"];
    let max_defect = v["max_defect"].as_f64().unwrap();
    let phase_max = v["phases"]
        .as_array()
        .unwrap()
        .iter()
        .map(|p| p["defect"].as_f64().unwrap())
        .fold(0.0, f64::max);
    assert_eq!(max_defect, phase_max);
    std::fs::remove_dir_all(dir).ok();
}

/// `--refine` goes on from the mesh the verification's refinements left the optimum on: on
/// `reach` the direct solve's 30 points verify only once refined, and a `--refine` that
/// started again from the 30 points met its error estimate there and ended unverified (a
/// re-integration defect of 8e-3) where the run without it verifies.
/// A mesh refinement whose error estimate meets its tolerance on a mesh that does not
/// re-integrate within the verification's (a bang-bang torque clamped next to its switch)
/// goes on to the verification's refinements: verified, exit 0. It used to end unverified.
#[test]
fn an_unverified_refinement_is_refined_until_verified() {
    let dir = tmpdir("refine-verify");
    let out = run(&[
        "optimize",
        "--problem",
        "reach",
        "--strategy",
        "direct",
        "--points",
        "6",
        "--elements",
        "2",
        "--refine",
        "1e-6",
        "--out",
        dir.to_str().unwrap(),
    ]);
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(out.status.success(), "{stdout}");
    assert!(stdout.contains("tolerance met"), "{stdout}");
    let sol: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("solution.json")).unwrap()).unwrap();
    let defect = sol["verification"]["max_defect"].as_f64().unwrap();
    assert!(
        defect <= ball_finger::pipeline::verify::VERIFIED_DEFECT,
        "{defect}"
    );
    // Both verification refinements are stages of the solution: the search's, before the
    // mesh refinement, and the one after it.
    let stages = sol["strategy"]["refinements"].as_array().unwrap();
    assert_eq!(stages.len(), 2, "{stages:?}");
    // The mesh's rounds name the second as the refinement that made them.
    assert_eq!(sol["refinement"]["stage"], stages[1]["stage"], "{stages:?}");
    assert_eq!(stages[1]["chain"], sol["strategy"]["chosen"]);
}

#[test]
fn optimize_refine_starts_from_the_verified_mesh() {
    let points = |dir: &std::path::Path| -> usize {
        let sol: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(dir.join("solution.json")).unwrap())
                .unwrap();
        assert_eq!(sol["verified"], true, "{}", dir.display());
        sol["refinement"]["mesh"][0]["degrees"]
            .as_array()
            .unwrap()
            .iter()
            .map(|d| d.as_u64().unwrap() as usize)
            .sum()
    };
    let mut meshes = Vec::new();
    for extra in [&[][..], &["--refine", "1e-4"][..]] {
        let dir = tmpdir("refine-verified");
        let mut args = vec!["optimize", "--problem", "reach", "--strategy", "direct"];
        args.extend_from_slice(extra);
        args.extend_from_slice(&["--out", dir.to_str().unwrap()]);
        let out = run(&args);
        assert!(
            out.status.success(),
            "{extra:?}: {}\n{}",
            String::from_utf8_lossy(&out.stdout),
            String::from_utf8_lossy(&out.stderr)
        );
        meshes.push(points(&dir));
        std::fs::remove_dir_all(dir).ok();
    }
    assert!(
        meshes[0] > 30,
        "the verification refined the mesh: {meshes:?}"
    );
    assert!(meshes[1] >= meshes[0], "{meshes:?}");
}

/// `--dual-regularization` reaches the solver: on a Radau mesh finer than the default
/// (`periodic-cot`, 3 × 12) the solver, starting from its default δ_c = 1e-9, raises δ_c
/// within the solve (at iteration 42, BENCHMARKS.md); started at `--dual-regularization 3e-8`,
/// the largest value it grows to, it never raises it, so `solution-internals.json` records no
/// raise, and the solve ends Solved in one stage.
#[test]
fn optimize_dual_regularization_reaches_the_solver() {
    let (stages, counters) = direct_cot_run("dualreg", 36, 300, &["--dual-regularization", "3e-8"]);
    assert_eq!(stages.len(), 1, "{stages:?}");
    assert!(
        counters["dual_regularization_raised_at"].is_null(),
        "{counters}"
    );
}

/// Runs `optimize --problem periodic-cot --impact-law stick --strategy direct` (the paper's
/// problem, which these solver figures were measured on) on `points` Radau points with
/// `--max-iter max_iter`, no re-integration and the `extra` options, writing to `dir`.
fn direct_cot_output(
    dir: &std::path::Path,
    points: usize,
    max_iter: usize,
    extra: &[&str],
) -> std::process::Output {
    let (points, max_iter) = (points.to_string(), max_iter.to_string());
    bin()
        .current_dir(root())
        .args(["optimize", "--problem", "periodic-cot", "--points", &points])
        .args(["--impact-law", "stick"])
        .args(["--strategy", "direct", "--max-iter", &max_iter])
        .args(["--verify-rtol", "0"])
        .args(extra)
        .arg("--out")
        .arg(dir)
        .output()
        .unwrap()
}

/// [`direct_cot_output`]; asserts success and a Solved solution.json and returns its stages
/// ([guess, status, iterations] each) and the solver's counters (`solution-internals.json`).
fn direct_cot_run(
    tag: &str,
    points: usize,
    max_iter: usize,
    extra: &[&str],
) -> (Vec<serde_json::Value>, serde_json::Value) {
    let dir = tmpdir(tag);
    let out = direct_cot_output(&dir, points, max_iter, extra);
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(out.status.success(), "{stdout}");
    let read = |name: &str| -> serde_json::Value {
        serde_json::from_str(&std::fs::read_to_string(dir.join(name)).unwrap()).unwrap()
    };
    let sol = read("solution.json");
    assert_eq!(sol["status"], "Solved", "{}", sol["stages"]);
    let counters = read("solution-internals.json")["counters"].clone();
    std::fs::remove_dir_all(dir).ok();
    (sol["stages"].as_array().unwrap().clone(), counters)
}

/// `--kkt-residual-ratio` reaches the solver: `periodic-cot` on Radau 3 × 16 from the default
/// guess needs 317 iterations with the default accuracy test of the KKT solves (with the
/// filter reset; before it the iteration limit), so with `--max-iter 200` it cannot end Solved
/// in one stage; with the residual ratio it does, in 114 (BENCHMARKS.md, "Line search: Ipopt's
/// filter reset heuristic"). With `reach-arm` the option is refused by name.
#[test]
fn optimize_kkt_residual_ratio_reaches_the_solver() {
    let (stages, _) = direct_cot_run("ratio", 48, 200, &["--kkt-residual-ratio"]);
    assert_eq!(stages.len(), 1, "{stages:?}");

    reach_arm_refuses("--kkt-residual-ratio");
}

/// `--curvature-extrapolation` and `--extrapolate-every-barrier` reach the solver: on
/// `periodic-cot` Radau 3 × 16 from the default guess the early barrier problems meet negative
/// curvature, so with every barrier problem in scope some full steps are extrapolated
/// (`counters.extrapolations`), with the default scope (the barrier problems with μ ≤ tol,
/// where this solve has positive curvature) fewer, and with `--curvature-extrapolation 1` (off) none
/// whatever the scope; values below 1 are refused by name, and so are both options with
/// `reach-arm`.
#[test]
fn optimize_curvature_extrapolation_reaches_the_solver() {
    let count = |tag: &str, args: &[&str]| -> u64 {
        let (_, c) = direct_cot_run(tag, 48, 600, args);
        c["extrapolations"].as_u64().unwrap()
    };
    let every = count("extrap-every", &["--extrapolate-every-barrier"]);
    let last = count("extrap-final", &[]);
    assert!(every > 0 && last < every, "every {every}, final {last}");
    let off = ["--curvature-extrapolation", "1"];
    assert_eq!(count("extrap-off", &off), 0);
    let off_every = [&off[..], &["--extrapolate-every-barrier"]].concat();
    assert_eq!(count("extrap-off-every", &off_every), 0);
    optimize_refuses_values("--curvature-extrapolation", &["0.5", "-2", "nan", "inf"]);
    reach_arm_refuses("--curvature-extrapolation");
    reach_arm_refuses("--extrapolate-every-barrier");
}

/// `--proximal-weight` reaches the solver: the direct `periodic-cot` LG-40 solve from the
/// default guess stalls on a barrier problem above the tolerance for more than 60 iterations,
/// so by default some iterations carry the proximal term (`counters.proximal_iterations`),
/// with `--proximal-weight 0` none and the path differs (other iteration counts), both
/// Solved; negative and non-finite weights are refused by name, and so is the option with
/// `reach-arm`.
#[test]
fn optimize_proximal_weight_reaches_the_solver() {
    let lg = |tag: &str, extra: &[&str]| {
        let args = [&["--scheme", "lg"][..], extra].concat();
        let (stages, c) = direct_cot_run(tag, 40, 600, &args);
        (stages, c["proximal_iterations"].as_u64().unwrap())
    };
    let (on_stages, on) = lg("prox-on", &[]);
    let (off_stages, off) = lg("prox-off", &["--proximal-weight", "0"]);
    assert!(on > 0, "{on_stages:?}");
    assert_eq!(off, 0);
    assert_ne!(on_stages, off_stages);
    optimize_refuses_values("--proximal-weight", &["-0.1", "nan", "inf"]);
    reach_arm_refuses("--proximal-weight");
}

/// A direct solve stopped by the iteration limit fails (exit status 1) and points to the
/// extrapolation along negative curvature on every barrier problem, unless it was already on.
#[test]
fn an_iteration_limit_hints_at_the_curvature_extrapolation() {
    let dir = std::env::temp_dir().join(format!("bf-cli-maxiter-{}", std::process::id()));
    let hint = "--extrapolate-every-barrier (steps";
    for (extra, hinted) in [
        (&[][..], true),
        (&["--extrapolate-every-barrier"][..], false),
    ] {
        let out = direct_cot_output(&dir, 30, 5, extra);
        let stdout = String::from_utf8_lossy(&out.stdout);
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(1), "{stdout}{stderr}");
        assert!(stderr.contains("MaxIterations"), "{stderr}");
        assert_eq!(stdout.contains(hint), hinted, "{extra:?}: {stdout}");
    }
    std::fs::remove_dir_all(dir).ok();
}

/// `optimize --problem periodic-cot FLAG VALUE` fails as a usage error for every value of
/// `bad`, naming `flag`.
fn optimize_refuses_values(flag: &str, bad: &[&str]) {
    for value in bad {
        let out = run(&["optimize", "--problem", "periodic-cot", flag, value]);
        assert_eq!(out.status.code(), Some(2), "{flag} {value}");
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert!(stderr.contains(flag), "{flag} {value}: {stderr}");
    }
}

/// `optimize --problem reach-arm` (one direct Radau solve) refuses the solver option `flag` by
/// name.
fn reach_arm_refuses(flag: &str) {
    let args = [
        "optimize",
        "--problem",
        "reach-arm",
        "--scene",
        "scenes/puma560.toml",
        flag,
    ];
    let out = run(&args);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{stderr}");
    assert!(stderr.contains(flag), "{stderr}");
}

/// Options that the run would drop without a word are refused by name (exit status 2): they
/// were accepted and ignored (the arm's problem has no stick phase or impact, Legendre–Gauss
/// no elements, a direct solve no hops, and no `--refine` no rounds of it).
#[test]
fn options_a_run_would_drop_are_refused_by_name() {
    let arm = ["--problem", "reach-arm", "--scene", "scenes/puma560.toml"];
    for (extra, flag) in [
        // Given at its default value, an option is still given, and still dropped.
        (&["--min-stick", "0.01"][..], "--min-stick"),
        (&["--cone-margin", "0"][..], "--cone-margin"),
        (&["--impulse-cone"][..], "--impulse-cone"),
        (&["--refine-rounds", "3"][..], "--refine-rounds"),
    ] {
        let mut args = vec!["optimize"];
        args.extend_from_slice(&arm);
        args.extend_from_slice(extra);
        assert_usage_error(&run(&args), &[flag]);
    }
    for (extra, flag) in [
        (
            &["--problem", "reach", "--strategy", "direct", "--hops", "3"][..],
            "--hops",
        ),
        (
            &[
                "--problem",
                "reach",
                "--strategy",
                "continuation",
                "--hop-scale",
                "0.5",
            ][..],
            "--hop-scale",
        ),
        (
            &[
                "--problem",
                "periodic-qc",
                "--scheme",
                "lg",
                "--elements",
                "3",
            ][..],
            "--elements",
        ),
        (
            &["--problem", "periodic-qc", "--refine-rounds", "8"][..],
            "--refine-rounds",
        ),
        // `reach` ends touching the ball at rest: no impact, no stick phase.
        (
            &["--problem", "reach", "--impact-law", "newton"][..],
            "--impact-law",
        ),
        (
            &["--problem", "reach", "--impulse-cone"][..],
            "--impulse-cone",
        ),
        (
            &["--problem", "reach", "--cone-margin", "0.2"][..],
            "--cone-margin",
        ),
        // The free-stick problems' stick phase has its own bound (0.05 s), and their approach
        // no clearance.
        (
            &["--problem", "reorient", "--min-stick", "0.01"][..],
            "--min-stick",
        ),
        (
            &["--problem", "rotate-ref", "--approach-clearance", "0.001"][..],
            "--approach-clearance",
        ),
    ] {
        let mut args = vec!["optimize"];
        args.extend_from_slice(extra);
        assert_usage_error(&run(&args), &[flag]);
    }
    // Without --strategy the message names the default it met, not a flag never given.
    assert_usage_error(
        &run(&["optimize", "--problem", "reach", "--hops", "3"]),
        &[
            "--hops",
            "default strategy of --problem reach",
            "--strategy multistart",
        ],
    );
}

#[test]
fn scene_warnings_reach_stderr_and_nonphysical_inertias_are_refused() {
    fn args(scene: &str) -> [&str; 6] {
        [
            "eval",
            scene,
            "--q",
            "0.1,0.2,0.3,0.4,0.5,0.6",
            "--qd",
            "0,0,0,0,0,0",
        ]
    }
    // The shipped PUMA 560 keeps Armstrong's link 3 (0.086 > 0.0125 + 0.066) with its source:
    // accepted, one warning naming the file, the key and the values.
    let out = run(&args("scenes/puma560.toml"));
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{stderr}");
    let warnings: Vec<&str> = stderr
        .lines()
        .filter(|l| l.starts_with("warning: "))
        .collect();
    assert_eq!(warnings.len(), 1, "{stderr}");
    assert!(
        warnings[0].starts_with("warning: scenes/puma560.toml: links[2].inertia (`elbow`): ")
            && warnings[0].contains("8.6e-2 > 1.25e-2 + 6.6e-2")
            && warnings[0].contains("Armstrong"),
        "{stderr}"
    );
    // A physical scene prints no warning.
    let out = run(&["eval", "scenes/paper.toml", "--q", "0,0,0", "--qd", "0,0,0"]);
    assert!(out.status.success());
    assert!(
        !String::from_utf8_lossy(&out.stderr).contains("warning"),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    // Without the source key the same data are refused, naming the file, key and values.
    let dir = tmpdir("nonphysical");
    let bad = dir.join("puma.toml");
    let text = std::fs::read_to_string(root().join("scenes/puma560.toml")).unwrap();
    let stripped: Vec<&str> = text
        .lines()
        .filter(|l| !l.starts_with("nonphysical_inertia"))
        .collect();
    std::fs::write(&bad, stripped.join("\n")).unwrap();
    assert_clean_failure(
        &run(&args(bad.to_str().unwrap())),
        &[
            "puma.toml",
            "links[2].inertia",
            "8.6e-2 > 1.25e-2 + 6.6e-2",
            "triangle inequality",
        ],
    );
    std::fs::remove_dir_all(dir).ok();
}

/// `optimize` lists the bounds its optimum sits on, as its own solution.json shows them: the
/// default-mesh COT optimum sits on the 10 s period bound (each line names the quantity and
/// the bound), and no stick phase is listed on its minimum unless its duration is there.
#[test]
fn optimize_lists_the_active_bounds_of_its_optimum() {
    let dir = std::env::temp_dir().join(format!("bf-cli-active-{}", std::process::id()));
    let out = direct_cot_output(&dir, 30, 3000, &[]);
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(out.status.success(), "{stdout}");
    let sol: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("solution.json")).unwrap()).unwrap();
    let section = &stdout[stdout.find("active bounds").expect("active bounds listed")..];
    let on = |v: f64, b: f64| (v - b).abs() <= 1e-5 + 1e-4 * b.abs();
    let period = sol["period"].as_f64().unwrap();
    assert_eq!(
        section.contains("period (s) = ") && section.contains("on its maximum 10"),
        on(period, 10.0),
        "period {period}: {section}"
    );
    for (p, d) in sol["phase_durations"]
        .as_array()
        .unwrap()
        .iter()
        .enumerate()
    {
        let listed = section.contains(&format!("phase {} (", p + 1));
        let d = d.as_f64().unwrap();
        // The phase bounds of the COT problems: a stick phase of at least 0.01 s, every phase
        // at most the period's 10 s (docs/optima.md).
        let expect = on(d, 0.01) || on(d, 10.0);
        assert_eq!(listed, expect, "phase {}: {d} s: {section}", p + 1);
    }
    // solution.json records the same bounds, one entry per line printed.
    let recorded = sol["active_bounds"]
        .as_array()
        .expect("active_bounds recorded");
    assert_eq!(
        recorded.len(),
        section
            .lines()
            .skip(1)
            .take_while(|l| l.starts_with("  "))
            .count()
    );
    for b in recorded {
        let (value, bound) = (b["value"].as_f64().unwrap(), b["bound"].as_f64().unwrap());
        assert!(on(value, bound), "{b}");
        assert!(section.contains(b["what"].as_str().unwrap()), "{b}");
    }
    std::fs::remove_dir_all(dir).ok();
}

/// Without `--epsilon`, `optimize` smooths the contact with the scene's `contact.smooth_eps`,
/// as `eval` and `verify` do (it once took 0.01 whatever the scene said). The paper's scene
/// with `smooth_eps = 0.02`: 20 iterations of the direct solve record ε = 0.02 and reach the
/// same objective, bit for bit, as `--epsilon 0.02` on it, and another one than
/// `--epsilon 0.01` (ε enters the stick phases' contact point, eq. 58–59).
#[test]
fn optimize_takes_the_scenes_contact_smoothing() {
    let dir = tmpdir("scene-eps");
    let text = std::fs::read_to_string(root().join("scenes/paper.toml")).unwrap();
    assert!(
        text.contains("smooth_eps = 0.01"),
        "the paper scene's ε moved"
    );
    let scene = dir.join("eps002.toml");
    std::fs::write(
        &scene,
        text.replace("smooth_eps = 0.01", "smooth_eps = 0.02"),
    )
    .unwrap();
    let solve = |tag: &str, extra: &[&str]| -> serde_json::Value {
        let out = dir.join(tag);
        let scene = scene.to_str().unwrap();
        let args = [
            &["--max-iter", "20", "--verify-rtol", "0", "--scene", scene],
            extra,
        ];
        let o = cli_util::direct_sticking_qc(&args.concat(), &out);
        // 20 iterations end at the iteration limit: a failed run whose set is still written.
        assert_clean_failure(&o, &["MaxIterations"]);
        serde_json::from_str(&std::fs::read_to_string(out.join("solution.json")).unwrap()).unwrap()
    };
    let (scene_eps, given, other) = (
        solve("scene", &[]),
        solve("given", &["--epsilon", "0.02"]),
        solve("other", &["--epsilon", "0.01"]),
    );
    assert_eq!(scene_eps["epsilon"].as_f64(), Some(0.02));
    assert_eq!(other["epsilon"].as_f64(), Some(0.01));
    let j = |s: &serde_json::Value| s["objective"].as_f64().unwrap();
    assert_eq!(j(&scene_eps).to_bits(), j(&given).to_bits());
    assert_ne!(j(&scene_eps), j(&other));
    std::fs::remove_dir_all(dir).ok();
}

/// `generate --help` says what the options do: the f32 module computes its sines and cosines
/// with its own functions (docs/kernels.md), and `--report` prints one generation time for the
/// whole module, after the per-kernel op counts.
#[test]
fn generate_help_describes_the_float_types_and_the_report_as_they_are() {
    let help = String::from_utf8(run(&["generate", "--help"]).stdout).unwrap();
    assert!(!help.contains("standard-library"), "{help}");
    assert!(help.contains("own sine–cosine, computed in f64"), "{help}");
    assert!(help.contains("total generation time"), "{help}");
    assert!(!help.contains("time per kernel"), "{help}");
    let report = run(&["generate", "tests/fixtures/finger2.toml", "--report"]);
    let text = String::from_utf8_lossy(&report.stderr);
    assert_eq!(text.matches("generated in").count(), 1, "{text}");
    assert_eq!(
        text.lines().filter(|l| l.contains(" ms")).count(),
        1,
        "{text}"
    );
    assert!(text.contains("contact_smooth"), "{text}");
}

/// A `[tool]` that turns the finger's tip frame off its last link would make segment contact
/// use another segment than the link: every command refuses the scene, naming the file, the
/// line of `[tool]` and the key.
#[test]
fn a_tool_that_moves_the_contact_segment_off_the_link_is_refused() {
    let dir = tmpdir("tool");
    let path = dir.join("finger2_tool.toml");
    let text = std::fs::read_to_string(root().join("tests/fixtures/finger2.toml")).unwrap()
        + "\n[tool]\ntranslation = [0.0, 0.0, 0.3]\nrotation = { axis = \"z\", angle = \"pi/2\" }\n";
    let line = 1 + text.lines().position(|l| l == "[tool]").unwrap();
    std::fs::write(&path, &text).unwrap();
    let p = path.to_str().unwrap();
    for args in [
        vec!["eval", p, "--q", "-2.504,2.559", "--qd", "0,0"],
        vec!["generate", p],
    ] {
        let out = run(&args);
        assert_clean_failure(&out, &[&format!("finger2_tool.toml:{line}:"), "tool: "]);
    }
}

/// `--max-graph-nodes` bounds every expression graph of the run: a request that needs more
/// ends with exit status 1 and an error that names the kernel (or the problem's node function)
/// and the option, and writes no module; a limit of 0 is a wrong command line.
#[test]
fn a_graph_past_max_graph_nodes_is_refused_by_name() {
    let dir = tmpdir("graph-limit");
    let module = dir.join("paper.rs");
    let module_s = module.to_str().unwrap();
    let out = run(&[
        "--max-graph-nodes",
        "2000",
        "generate",
        "scenes/paper.toml",
        "-o",
        module_s,
    ]);
    assert_clean_failure(
        &out,
        &["scenes/paper.toml", "kernel `", "--max-graph-nodes"],
    );
    assert_eq!(out.status.code(), Some(1));
    assert!(!module.exists());
    // With the default limit the same command writes the module.
    ok(&run(&["generate", "scenes/paper.toml", "-o", module_s]));
    assert!(module.exists());

    // A user's robot is interpreted, so `eval` builds its graphs; the option goes anywhere.
    let urdf = "testkit/tests/urdf/ur5_like.urdf";
    let q = "0.1,0.2,0.3,0.4,0.5,0.6";
    let out = run(&[
        "eval",
        urdf,
        "--q",
        q,
        "--qd",
        q,
        "--max-graph-nodes",
        "500",
    ]);
    assert_clean_failure(&out, &["ur5_like.urdf", "6-joint", "--max-graph-nodes"]);
    assert_eq!(out.status.code(), Some(1));
    ok(&run(&["eval", urdf, "--q", q, "--qd", q]));

    // An optimal-control problem's node function past the limit.
    let out = run(&[
        "--max-graph-nodes",
        "1000",
        "optimize",
        "--problem",
        "reach",
        "--out",
        dir.join("reach").to_str().unwrap(),
    ]);
    assert_clean_failure(&out, &["graph nodes", "--max-graph-nodes"]);
    assert_eq!(out.status.code(), Some(1));

    assert_usage_error(
        &run(&["--max-graph-nodes", "0", "generate", "scenes/paper.toml"]),
        &["--max-graph-nodes"],
    );
}

/// `torques.csv` is clamped to the limits of the scene the solution was posed on: a user's copy
/// of `scenes/paper.toml` with τ_max = 2 N m lets the reach optimum's τ₂ beyond the compiled
/// scene's 1 N m, and the file keeps it there (it used to clamp to the compiled scene's limits
/// found by name, and its replay then missed the planned end by 0.29 in the state).
#[test]
fn torques_csv_keeps_the_limits_of_the_solutions_own_scene() {
    let dir = tmpdir("own-limits");
    let text = std::fs::read_to_string(root().join("scenes/paper.toml")).unwrap();
    let wide = text.replace("tau_max = 1.0", "tau_max = 2.0");
    assert_eq!(wide.matches("tau_max = 2.0").count(), 3);
    let scene = dir.join("paper.toml");
    std::fs::write(&scene, wide).unwrap();
    let out = dir.join("out");
    ok(&run(&[
        "optimize",
        "--problem",
        "reach",
        "--strategy",
        "direct",
        "--scene",
        scene.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
    ]));
    let sol: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("solution.json")).unwrap()).unwrap();
    let peak = |col: &[f64]| col.iter().fold(0.0f64, |a, v| a.max(v.abs()));
    let dense: Vec<f64> = sol["dense"]["tau2"]
        .as_array()
        .unwrap()
        .iter()
        .map(|v| v.as_f64().unwrap())
        .collect();
    assert!(peak(&dense) > 1.05, "τ₂ of the optimum: {}", peak(&dense));
    let csv = std::fs::read_to_string(out.join("torques.csv")).unwrap();
    let rows: Vec<Vec<f64>> = csv
        .lines()
        .skip(1)
        .map(|l| l.split(',').map(|v| v.parse().unwrap()).collect())
        .collect();
    // The polynomial samples (1000 per phase), not the 100 dense ones.
    assert!(rows.len() > 900, "{} rows", rows.len());
    let tau2: Vec<f64> = rows.iter().map(|r| r[2]).collect();
    assert!(
        peak(&tau2) >= peak(&dense) - 1e-6,
        "{} against {}",
        peak(&tau2),
        peak(&dense)
    );
    assert!(peak(&tau2) <= 2.0, "{}", peak(&tau2));
}

/// A `--refine` tolerance that the rounds do not reach is a check the result failed: with one
/// round, 1e-12 is out of reach on `reach`; the set is written, marked FAILED, and the run
/// exits 1 naming the tolerance and the largest element error reached.
#[test]
fn an_unmet_refine_tolerance_fails_the_run() {
    let dir = tmpdir("refine-unmet");
    let out = run(&[
        "optimize",
        "--problem",
        "reach",
        "--strategy",
        "direct",
        "--refine",
        "1e-12",
        "--refine-rounds",
        "1",
        "--out",
        dir.to_str().unwrap(),
    ]);
    let stderr = String::from_utf8_lossy(&out.stderr);
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert_eq!(out.status.code(), Some(1), "{stderr}");
    assert!(
        stderr.contains("did not reach --refine 1e-12") && stderr.contains("largest element error"),
        "{stderr}"
    );
    assert!(stdout.contains("(marked FAILED)"), "{stdout}");
    assert!(dir.join("FAILED").exists() && dir.join("solution.json").exists());
    let sol: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("solution.json")).unwrap()).unwrap();
    assert_eq!(sol["refinement"]["converged"], false);
}
