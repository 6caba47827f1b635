//! Follows docs/your-robot.md verbatim: the `toml` block is written to the file the page
//! names, every `ball-finger …` line of the `sh` blocks is run in that directory. Beyond
//! "it runs", the outputs are checked against each other: the generated module holds the
//! inverse-dynamics family, and the evaluated `inverse_dynamics` equals M q̈ + C q̇ + g from
//! the `mass_matrix` and `cqd_g` kernels of the same output, `forward_dynamics` equals
//! M⁻¹(τ − C q̇ − g) (solved here by Gaussian elimination), and the prismatic joint's gravity
//! force is the weight of the link it carries; the simulation balances energy against the
//! work of its PD torques and settles where the PD law carries the quill's weight.
//! The optimal reach ends at rest on its target within the shoulder's torque bound, verified by
//! re-integration.

#[path = "common/cli.rs"]
mod cli_util;
use cli_util::{bin, root, tmpdir};

/// The fenced blocks of `text` with their info string: (info, body).
fn blocks(text: &str) -> Vec<(String, String)> {
    let mut out = Vec::new();
    let mut cur: Option<(String, String)> = None;
    for line in text.lines() {
        if let Some(rest) = line.strip_prefix("```") {
            match cur.take() {
                Some(b) => out.push(b),
                None => cur = Some((rest.trim().to_string(), String::new())),
            }
        } else if let Some((_, body)) = cur.as_mut() {
            body.push_str(line);
            body.push('\n');
        }
    }
    out
}

fn nums(v: &serde_json::Value) -> Vec<f64> {
    match v {
        serde_json::Value::Number(n) => vec![n.as_f64().unwrap()],
        serde_json::Value::Array(a) => a.iter().flat_map(nums).collect(),
        other => panic!("unexpected {other}"),
    }
}

/// Solves A x = b (small, dense) by Gaussian elimination with partial pivoting.
fn solve(mut a: Vec<Vec<f64>>, mut b: Vec<f64>) -> Vec<f64> {
    let n = b.len();
    for c in 0..n {
        let p = (c..n)
            .max_by(|&i, &j| a[i][c].abs().total_cmp(&a[j][c].abs()))
            .unwrap();
        a.swap(c, p);
        b.swap(c, p);
        for r in c + 1..n {
            let f = a[r][c] / a[c][c];
            for k in c..n {
                a[r][k] -= f * a[c][k];
            }
            b[r] -= f * b[c];
        }
    }
    let mut x = vec![0.0; n];
    for r in (0..n).rev() {
        let s: f64 = (r + 1..n).map(|k| a[r][k] * x[k]).sum();
        x[r] = (b[r] - s) / a[r][r];
    }
    x
}

/// The value after `flag` on a command line.
fn arg(cmd: &[&str], flag: &str) -> Vec<f64> {
    let i = cmd.iter().position(|a| *a == flag).unwrap();
    cmd[i + 1].split(',').map(|x| x.parse().unwrap()).collect()
}

fn arg_text<'a>(cmd: &[&'a str], flag: &str) -> &'a str {
    let i = cmd.iter().position(|a| *a == flag).unwrap();
    cmd[i + 1]
}

#[test]
fn the_walkthrough_runs_as_written() {
    let page = std::fs::read_to_string(root().join("docs/your-robot.md")).unwrap();
    let bl = blocks(&page);
    let dir = tmpdir("walkthrough");
    // Cargo manifests (section 9, a crate of your own) are TOML too; the scene is the other one.
    let tomls: Vec<&String> = bl
        .iter()
        .filter(|b| b.0 == "toml" && !b.1.trim_start().starts_with("# Cargo.toml"))
        .map(|b| &b.1)
        .collect();
    assert_eq!(tomls.len(), 1, "one scene block");
    // The page says which file the block is saved as.
    assert!(page.contains("Save this as `myarm.toml`"));
    std::fs::write(dir.join("myarm.toml"), tomls[0]).unwrap();
    let commands: Vec<&str> = bl
        .iter()
        .filter(|b| b.0 == "sh")
        .flat_map(|b| b.1.lines())
        .filter(|l| l.starts_with("ball-finger "))
        .collect();
    assert!(commands.len() >= 3, "{commands:?}");
    let mut saw = (false, false, false, false);
    let mut saw_optimize = false;
    for line in commands {
        let words: Vec<&str> = line.split_whitespace().collect();
        let out = bin().current_dir(&dir).args(&words[1..]).output().unwrap();
        let stdout = String::from_utf8_lossy(&out.stdout).to_string();
        assert!(
            out.status.success(),
            "`{line}` failed:\n{}",
            String::from_utf8_lossy(&out.stderr)
        );
        match words[1] {
            "generate" => {
                let code = std::fs::read_to_string(dir.join("myarm.rs")).unwrap();
                for k in [
                    "inverse_dynamics",
                    "forward_dynamics",
                    "regressor",
                    "mass_matrix",
                ] {
                    assert!(code.contains(&format!("pub fn {k}(")), "{k}");
                }
                assert!(code.contains("pub const NQ: usize = 3;"));
                saw.0 = true;
            }
            "eval" => {
                let v: serde_json::Value = serde_json::from_str(&stdout).unwrap();
                let k = &v["kernels"];
                let (qd, qdd, tau_in) = (
                    arg(&words, "--qd"),
                    arg(&words, "--qdd"),
                    arg(&words, "--tau"),
                );
                let m = nums(&k["mass_matrix"]["m"]);
                let h = nums(&k["cqd_g"]["out"]);
                let tau = nums(&k["inverse_dynamics"]["tau"]);
                let n = 3;
                for i in 0..n {
                    let want = h[i] + (0..n).map(|j| m[i * n + j] * qdd[j]).sum::<f64>();
                    assert!((tau[i] - want).abs() < 1e-10 * (1.0 + want.abs()), "τ[{i}]");
                }
                let a: Vec<Vec<f64>> = (0..n).map(|i| m[i * n..(i + 1) * n].to_vec()).collect();
                let want = solve(a, (0..n).map(|i| tau_in[i] - h[i]).collect());
                let got = nums(&k["forward_dynamics"]["qdd"]);
                for i in 0..n {
                    assert!(
                        (got[i] - want[i]).abs() < 1e-9 * (1.0 + want[i].abs()),
                        "q̈[{i}]"
                    );
                }
                // Holding the quill (axis pointing down) up takes its weight upwards:
                // g_3 = −m₃ |g₀| along the axis.
                let g = nums(&v["g"]);
                assert!((g[2] + 0.5 * 9.81).abs() < 1e-12, "g = {g:?}");
                assert!(qd.len() == n);
                saw.1 = true;
            }
            "bench" => {
                for k in [
                    "inverse_dynamics",
                    "forward_dynamics",
                    "regressor",
                    "frames",
                ] {
                    assert!(
                        stdout
                            .lines()
                            .any(|l| l.split_whitespace().next() == Some(k)),
                        "{k} in\n{stdout}"
                    );
                }
                saw.2 = true;
            }
            "simulate" => {
                let out = dir.join(arg_text(&words, "--out"));
                let summary: serde_json::Value = serde_json::from_str(
                    &std::fs::read_to_string(out.join("summary.json")).unwrap(),
                )
                .unwrap();
                let f = |k: &str| summary[k].as_f64().unwrap();
                // Energy balance: ΔE = work of torques and friction, to the integration error.
                let scale = f("energy_initial").abs() + f("work").abs();
                assert!(
                    (f("energy_final") - f("energy_initial") - f("work")).abs() < 1e-4 * scale,
                    "{summary}"
                );
                // PD equilibrium: revolute joints at the target, the quill (pointing down)
                // below it by its weight over k_p.
                let target = arg(&words, "--pd");
                let kp = arg(&words, "--pd-gains")[0];
                let csv = std::fs::read_to_string(out.join("trajectory.csv")).unwrap();
                let header: Vec<&str> = csv.lines().next().unwrap().split(',').collect();
                assert_eq!(header[3], "q3 [m]", "{header:?}");
                let last: Vec<f64> = csv
                    .lines()
                    .last()
                    .unwrap()
                    .split(',')
                    .map(|v| v.parse().unwrap())
                    .collect();
                let want = [target[0], target[1], target[2] + 0.5 * 9.81 / kp];
                for i in 0..3 {
                    assert!((last[1 + i] - want[i]).abs() < 2e-3, "q{}: {last:?}", i + 1);
                }
                saw.3 = true;
            }
            "optimize" => {
                let out = dir.join(arg_text(&words, "--out"));
                assert!(!out.join("FAILED").exists());
                let sol: serde_json::Value = serde_json::from_str(
                    &std::fs::read_to_string(out.join("solution.json")).unwrap(),
                )
                .unwrap();
                // Solved, or Acceptable on the finest mesh of the verification's doublings
                // (the rest conditions on τ leave its constraint violation near 1e-7 there);
                // either way verified below.
                assert!(
                    sol["status"] == "Solved" || sol["status"] == "Acceptable",
                    "{}",
                    sol["status"]
                );
                // Rest at the start and at the target given on the command line.
                let target = arg(&words, "--target");
                let x = &sol["raw"]["x"];
                let (first, last) = (nums(&x[0]), nums(&x[x.as_array().unwrap().len() - 1]));
                for i in 0..3 {
                    assert!(
                        first[i].abs() < 1e-8 && first[3 + i].abs() < 1e-8,
                        "{first:?}"
                    );
                    assert!((last[i] - target[i]).abs() < 1e-8, "{last:?}");
                    assert!(last[3 + i].abs() < 1e-8, "{last:?}");
                }
                // Held at rest at both ends: τ = g(q), zero about the vertical axes of the
                // shoulder and elbow, the quill's weight 0.5 kg × 9.81 m/s² on the slide.
                for x in [&first, &last] {
                    assert!(x[6].abs() < 1e-6 && x[7].abs() < 1e-6, "{x:?}");
                    assert!((x[8].abs() - 0.5 * 9.81).abs() < 1e-6, "{x:?}");
                }
                // The shoulder's torque bound (20 N m) holds at every state point (τ is a
                // state), and the simulator reproduces the motion element by element.
                for x in x.as_array().unwrap() {
                    assert!(nums(x)[6].abs() <= 20.0 * (1.0 + 1e-7), "{x}");
                }
                assert!(sol["verification"]["max_defect"].as_f64().unwrap() <= 1e-4);
                saw_optimize = true;
            }
            other => panic!("the walk-through runs an unexpected command {other}"),
        }
    }
    assert_eq!(
        saw,
        (true, true, true, true),
        "generate, eval, bench and simulate all ran"
    );
    assert!(saw_optimize, "optimize ran");
}
