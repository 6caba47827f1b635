//! `reach-arm`: point-to-point optimal control of arms without a ball, checked against physics
//! rather than against the code's own numbers: the boundary conditions, the torque bounds, the
//! active bound of a torque-limited time-optimal motion (Pontryagin: with time in the cost and
//! a bound that cannot hold the arm statically, some torque sits on its bound), the monotonicity
//! of the optimum in τ_max (a larger bound only enlarges the feasible set), and an independent
//! re-integration by the simulator. The CLI writes the solution files, honours a user's scene
//! outside the repository, and refuses a contact problem on an arm.

#[path = "common/cli.rs"]
mod cli_util;
use ball_finger::study::arm::{is_verified, solve_verified, verify_arm};
use bf_problem::arm::{ArmSettings, ArmSolution};
use cli_util::{root, run, tmpdir};
use std::path::{Path, PathBuf};

fn fixture_text() -> String {
    std::fs::read_to_string(root().join("tests/fixtures/planar2_arm.toml")).unwrap()
}

fn scene_of(text: &str) -> bf_codegen::Scene {
    bf_codegen::Scene::from_toml_str(text, "planar2_arm.toml").unwrap()
}

/// The verified solution of `reach-arm` on `text` (default start and target).
fn solve(text: &str) -> ArmSolution {
    let scene = scene_of(text);
    let mut attempts =
        solve_verified(&scene, &ArmSettings::default(), 1e-10, 2, text, &[]).unwrap();
    attempts.pop().unwrap().solution
}

/// The fixture with both torque limits scaled by `f`.
fn scaled_limits(f: f64) -> String {
    let t = fixture_text();
    let out = t
        .replace("tau_max = 12.0", &format!("tau_max = {:?}", 12.0 * f))
        .replace("tau_max = 6.0", &format!("tau_max = {:?}", 6.0 * f));
    assert_eq!(out.matches("tau_max").count(), 2);
    out
}

#[test]
fn planar_arm_reaches_the_target_at_rest_within_its_torque_bounds() {
    let sol = solve(&fixture_text());
    assert_eq!(sol.status, bf_optim::ipm::Status::Solved);
    assert!(is_verified(&sol), "{:?}", sol.verification);
    let n = 2;
    let (x0, xf) = (&sol.raw.x[0], sol.raw.x.last().unwrap());
    for i in 0..n {
        assert!((x0[i] - sol.start[i]).abs() < 1e-8 && x0[n + i].abs() < 1e-8);
        assert!((xf[i] - sol.target[i]).abs() < 1e-8 && xf[n + i].abs() < 1e-8);
    }
    // The default target: the start (q = 0) plus 0.5 rad per revolute joint.
    assert_eq!(sol.start, vec![0.0, 0.0]);
    assert_eq!(sol.target, vec![0.5, 0.5]);
    let limits = [12.0, 6.0];
    let mut peak = [0.0f64; 2];
    for u in &sol.raw.u {
        for i in 0..n {
            assert!(u[i].abs() <= limits[i] * (1.0 + 1e-7), "{u:?}");
            peak[i] = peak[i].max(u[i].abs());
        }
    }
    // Holding the horizontal arm needs g-torques of about 5.3 + 8.9 N m at the shoulder, more
    // than 12 N m: a time-weighted optimum pushes at least one joint onto its bound.
    assert!(
        (0..n).any(|i| peak[i] >= limits[i] * (1.0 - 1e-6)),
        "no torque bound is active: peaks {peak:?}"
    );
    // The simulator, restarted at each element with the optimal torques, reaches the target:
    // the last element's re-integration ends within 1e-4 of (q^f, 0).
    let v = sol.verification.as_ref().unwrap();
    assert!(v.max_defect <= 1e-4, "{v:?}");
    assert!(*v.element_defects.last().unwrap() <= 1e-4);
    // And the model the simulator integrates agrees with the node function at the nodes.
    assert!(v.node_residual < 1e-6, "{v:?}");
    // An independent re-integration of the whole motion from rest also ends at the target.
    assert!(v.open_loop_end_error < 1e-4, "{v:?}");
}

#[test]
fn the_optimum_does_not_grow_when_the_torque_bound_is_raised() {
    // Along one branch of optima: with 0.75 τ_max the solver finds a swing-up (the arm falls,
    // pumps energy and rises, J ≈ 6.3) that the runs below do not, so the problem has distinct
    // local optima and the comparison is between runs from the same guess on one branch.
    let tight = solve(&fixture_text());
    let base = solve(&scaled_limits(2.0));
    let loose = solve(&scaled_limits(4.0));
    for s in [&tight, &base, &loose] {
        assert!(is_verified(s), "{} {:?}", s.objective, s.verification);
    }
    assert!(
        tight.objective >= base.objective - 1e-6 && base.objective >= loose.objective - 1e-6,
        "J(τ_max) = {}, J(2 τ_max) = {}, J(4 τ_max) = {}",
        tight.objective,
        base.objective,
        loose.objective
    );
    // A looser bound lets the motion end sooner or cheaper, never a bound-violating torque.
    let peak = |s: &ArmSolution, i: usize| s.raw.u.iter().map(|u| u[i].abs()).fold(0.0, f64::max);
    assert!(peak(&tight, 0) <= 12.0 * (1.0 + 1e-7));
    // The bound is active at τ_max and not at 4 τ_max (the unconstrained peaks are about
    // 19 and 11 N m), so the tight optimum is strictly worse.
    assert!(tight.objective > base.objective + 1.0);
    assert!(peak(&loose, 0) < 48.0 * 0.9);
}

#[test]
fn verification_detects_torques_that_do_not_move_the_arm_to_the_target() {
    let mut sol = solve(&fixture_text());
    for u in &mut sol.raw.u {
        for v in u.iter_mut() {
            *v *= 0.9;
        }
    }
    let v = verify_arm(&sol, 1e-10).unwrap();
    assert!(v.max_defect > 1e-3, "{v:?}");
}

#[test]
fn puma560_reach_arm_is_solved_and_verified() {
    let text = std::fs::read_to_string(root().join("scenes/puma560.toml")).unwrap();
    let scene = bf_codegen::Scene::from_toml_str(&text, "puma560.toml").unwrap();
    let start = std::time::Instant::now();
    let mut attempts =
        solve_verified(&scene, &ArmSettings::default(), 1e-10, 2, &text, &[]).unwrap();
    let sol = attempts.pop().unwrap().solution;
    eprintln!(
        "puma560 reach-arm: {:?} J = {} T = {} s in {:.2} s",
        sol.status,
        sol.objective,
        sol.duration,
        start.elapsed().as_secs_f64()
    );
    assert_eq!(sol.status, bf_optim::ipm::Status::Solved);
    assert!(is_verified(&sol), "{:?}", sol.verification);
    assert_eq!(sol.kernels, "interpreted");
    let xf = sol.raw.x.last().unwrap();
    for i in 0..6 {
        assert!((xf[i] - sol.target[i]).abs() < 1e-8 && xf[6 + i].abs() < 1e-8);
    }
}

fn json(path: &Path) -> serde_json::Value {
    serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap()
}

/// The fixture with τ_max = 4 and 2 N m, written outside the repository.
fn user_scene(dir: &Path) -> PathBuf {
    let path = dir.join("myarm.toml");
    std::fs::write(&path, scaled_limits(1.0 / 3.0)).unwrap();
    path
}

#[test]
fn cli_reach_arm_on_a_user_scene_respects_its_torque_bounds() {
    let dir = tmpdir("reach-arm-user");
    let scene = user_scene(&dir);
    let out = dir.join("out");
    let o = run(&[
        "optimize",
        "--problem",
        "reach-arm",
        "--scene",
        scene.to_str().unwrap(),
        "--target",
        "0.3,0.2",
        "--out",
        out.to_str().unwrap(),
    ]);
    let (stdout, stderr) = (
        String::from_utf8_lossy(&o.stdout),
        String::from_utf8_lossy(&o.stderr),
    );
    assert!(o.status.success(), "{stdout}\n{stderr}");
    assert!(stderr.contains("interpreted"), "{stderr}");
    assert!(!out.join("FAILED").exists());
    let sol = json(&out.join("solution.json"));
    assert_eq!(sol["problem"], "reach-arm");
    assert_eq!(sol["kernels"], "interpreted");
    assert_eq!(sol["target"], serde_json::json!([0.3, 0.2]));
    assert_eq!(sol["tau_max"], serde_json::json!([4.0, 2.0]));
    let csv = std::fs::read_to_string(out.join("torques.csv")).unwrap();
    let mut peak = [0.0f64; 2];
    for line in csv.lines().skip(1) {
        let v: Vec<f64> = line.split(',').map(|x| x.parse().unwrap()).collect();
        peak[0] = peak[0].max(v[1].abs());
        peak[1] = peak[1].max(v[2].abs());
    }
    // Dense samples of the element polynomials: within the bound up to the interpolation
    // overshoot between nodes that the verification reports.
    let over = sol["verification"]["max_torque_overshoot"]
        .as_f64()
        .unwrap();
    assert!(
        peak[0] <= 4.0 + over + 1e-9 && peak[1] <= 2.0 + over + 1e-9,
        "{peak:?}"
    );
    // The bound binds: the built-in limits (12, 6 N m) would not be reached by this motion's
    // torques if it were run on them.
    assert!(peak[0] > 3.9 || peak[1] > 1.9, "{peak:?}");
    assert!(out.join("trajectory.csv").exists());
    // `simulate --init solution.json` without --scene, run outside the repository: the scene
    // stored in the solution is used and the optimal torques (dense samples, linear between
    // them) drive the arm from its start at rest over the motion's duration. Open loop, with
    // linear interpolation across the bang-bang corners, the swinging arm drifts from the
    // target (why the verification restarts at every element), so only the run is checked.
    let replay = dir.join("replay");
    let o = cli_util::bin()
        .current_dir(&dir)
        .args([
            "simulate",
            "--init",
            out.join("solution.json").to_str().unwrap(),
            "--out",
            replay.to_str().unwrap(),
        ])
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{err}");
    assert!(err.contains("planar2_arm"), "{err}");
    let traj = std::fs::read_to_string(replay.join("trajectory.csv")).unwrap();
    let last: Vec<f64> = traj
        .lines()
        .last()
        .unwrap()
        .split(',')
        .map(|x| x.parse().unwrap())
        .collect();
    let duration = sol["duration"].as_f64().unwrap();
    assert!((last[0] - duration).abs() < 1e-9, "{last:?}");
    assert_eq!(
        last.len(),
        1 + 3 * 2 + 1,
        "two joints: t, q, qd, tau, energy"
    );
    let first: Vec<f64> = traj
        .lines()
        .nth(1)
        .unwrap()
        .split(',')
        .map(|x| x.parse().unwrap())
        .collect();
    assert_eq!(&first[..5], &[0.0, 0.0, 0.0, 0.0, 0.0]);
}

#[test]
fn cli_contact_problem_on_an_arm_is_refused_with_the_scene_and_the_reason() {
    let dir = tmpdir("reach-arm-refuse");
    let o = run(&[
        "optimize",
        "--problem",
        "periodic-qc",
        "--scene",
        "scenes/puma560.toml",
        "--out",
        dir.join("out").to_str().unwrap(),
    ]);
    assert!(!o.status.success());
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(err.contains("scenes/puma560.toml"), "{err}");
    assert!(err.contains("ball"), "{err}");
    let o = run(&[
        "optimize",
        "--problem",
        "reach-arm",
        "--out",
        dir.join("out").to_str().unwrap(),
    ]);
    assert!(!o.status.success());
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(err.contains("--scene"), "{err}");
    // A target outside the joint limits names the joint and the limits.
    let o = run(&[
        "optimize",
        "--problem",
        "reach-arm",
        "--scene",
        "scenes/puma560.toml",
        "--target",
        "0,0,0,0,3,0",
        "--out",
        dir.join("out").to_str().unwrap(),
    ]);
    assert!(!o.status.success());
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(err.contains("joint 5") && err.contains("limits"), "{err}");
}
