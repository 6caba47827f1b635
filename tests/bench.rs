//! `bench`: the table lists every kernel of the scene's compiled module in emission order,
//! the compiled and interpreted kernels agree at the sampled states (the command checks them
//! at every state; the reported difference must be within its tolerance), the ratio column is
//! interpreted/compiled, and a scene file that is not built in is timed through the interpreter
//! only. Timings themselves are not asserted (loaded machine).

#[path = "common/cli.rs"]
mod cli_util;
use cli_util::{root, run, tmpdir};

fn bench_json(scene: &str) -> serde_json::Value {
    let out = run(&["bench", scene, "--time", "0.3", "--states", "16", "--json"]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    serde_json::from_slice(&out.stdout).expect("bench --json prints JSON")
}

#[test]
fn bench_lists_every_kernel_and_the_paths_agree() {
    let b = bench_json("scenes/puma560.toml");
    assert_eq!(b["scene"], "puma560");
    assert_eq!(b["compiled"], true);
    let rows = b["kernels"].as_array().unwrap();
    let names: Vec<&str> = rows.iter().map(|r| r["kernel"].as_str().unwrap()).collect();
    assert_eq!(names, bf_generated::puma560::KERNELS);
    for r in rows {
        let c = r["compiled_ns"].as_f64().unwrap();
        let i = r["interpreted_ns"].as_f64().unwrap();
        assert!(c > 0.0 && i > 0.0, "{r}");
        let ratio = r["ratio"].as_f64().unwrap();
        assert!((ratio - i / c).abs() <= 1e-9 * ratio, "{r}");
        let d = r["max_rel_diff"].as_f64().unwrap();
        assert!(d <= 1e-12, "compiled and interpreted differ: {r}");
    }
    // The output sizes match the compiled kernels' flat outputs.
    let q = [0.1, -0.4, 0.3, 0.9, -0.2, 0.5];
    for (r, name) in rows.iter().zip(bf_generated::puma560::KERNELS) {
        let flat = bf_generated::puma560::eval_flat(
            name,
            &q,
            &q,
            &[0.0; 3],
            0.01,
            &bf_generated::puma560::PARAM_DEFAULTS,
        )
        .unwrap();
        assert_eq!(
            r["outputs"].as_u64().unwrap() as usize,
            flat.len(),
            "{name}"
        );
    }
}

#[test]
fn bench_of_a_user_scene_is_interpreted_and_tables_every_kernel() {
    let dir = tmpdir("bench");
    let copy = dir.join("my_puma.toml");
    let text = std::fs::read_to_string(root().join("scenes/puma560.toml")).unwrap();
    std::fs::write(&copy, text.replace("mass = 17.4", "mass = 17.0")).unwrap();
    let b = bench_json(copy.to_str().unwrap());
    assert_eq!(b["compiled"], false);
    let rows = b["kernels"].as_array().unwrap();
    assert_eq!(rows.len(), bf_generated::puma560::KERNELS.len());
    assert!(
        rows.iter()
            .all(|r| r["compiled_ns"].is_null() && r["ratio"].is_null())
    );
    // The table form names every kernel once.
    let out = run(&[
        "bench",
        copy.to_str().unwrap(),
        "--time",
        "0.2",
        "--states",
        "4",
    ]);
    assert!(out.status.success());
    let table = String::from_utf8(out.stdout).unwrap();
    for name in bf_generated::puma560::KERNELS {
        let n = table
            .lines()
            .filter(|l| l.split_whitespace().next() == Some(name))
            .count();
        assert_eq!(n, 1, "{name} in\n{table}");
    }
    // A copy that differs only in what does not enter the kernels (a comment, the
    // description, the limits) runs on the compiled kernels, as `eval` decides.
    let same = dir.join("puma_copy.toml");
    std::fs::write(
        &same,
        format!(
            "# my copy\n{}",
            text.replace("q_max = \"160deg\"", "q_max = \"150deg\"")
        ),
    )
    .unwrap();
    let b = bench_json(same.to_str().unwrap());
    assert_eq!(b["compiled"], true);
    let bad = run(&["bench", "scenes/puma560.toml", "--time", "0"]);
    assert!(!bad.status.success());
    assert!(String::from_utf8_lossy(&bad.stderr).contains("--time"));
}

/// Limits as wide as a double holds (how some URDFs say "unlimited") are timed on angles of
/// one turn, not refused by the random draw (it once panicked: the width overflowed); limits
/// whose every angle is beyond 2^20 rad are an error that names the joint.
#[test]
fn bench_of_limits_beyond_one_turn() {
    let dir = tmpdir("bench-limits");
    let text = std::fs::read_to_string(root().join("scenes/puma560.toml")).unwrap();
    let limits = "q_min = \"-160deg\"\nq_max = \"160deg\"";
    assert!(text.contains(limits));
    let wide = dir.join("wide.toml");
    std::fs::write(
        &wide,
        text.replacen(limits, "q_min = -1.7e308\nq_max = 1.7e308", 1),
    )
    .unwrap();
    // Limits do not enter the kernels: the compiled ones are timed too.
    let b = bench_json(wide.to_str().unwrap());
    assert_eq!(b["compiled"], true);
    let far = dir.join("far.toml");
    std::fs::write(&far, text.replacen(limits, "q_min = 1e7\nq_max = 2e7", 1)).unwrap();
    let out = run(&["bench", far.to_str().unwrap(), "--time", "0.1"]);
    assert_eq!(out.status.code(), Some(1));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("joint 1 (q_min 1e7, q_max 2e7)"), "{err}");
    assert!(!err.contains("panicked"), "{err}");
}
