//! `ball-finger simulate` end to end on the hybrid ball-and-finger simulator (paper Sect. 2.4–3,
//! Fig. 3): the files of a scripted push and a passive drop agree with each other and with the
//! physics (h ≥ −tol at every sample, the Sect. 3.1 transitions, a closing energy balance),
//! RK4 agrees with DOPRI5, a 4-joint scene runs on interpreted kernels, joint counts are
//! checked. Bad inputs end with a clear error and a non-zero exit; a failure mid-run keeps the
//! partial trajectory, and a run whose energy balance fails its check is marked failed.

use bf_model::{Model, State, Vec3};
use serde_json::Value;
use std::path::Path;
use std::process::Output;

#[path = "common/cli.rs"]
mod cli_util;
use cli_util::{root, run, tmpdir};

#[path = "common/sim.rs"]
mod sim_util;
use sim_util::{PENETRATION_TOL, scripted_push};

fn json(path: &Path) -> Value {
    serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap()
}

/// The `kind` of each event of an `events.json` document, in order.
fn event_kinds(events: &Value) -> Vec<&str> {
    events["events"]
        .as_array()
        .unwrap()
        .iter()
        .map(|e| e["kind"].as_str().unwrap())
        .collect()
}

/// `simulate ARGS --out OUT_DIR`.
fn simulate_into(out_dir: &Path, args: &[&str]) -> Output {
    let mut all = vec!["simulate"];
    all.extend_from_slice(args);
    all.extend(["--out", out_dir.to_str().unwrap()]);
    run(&all)
}

/// `simulate` of the default passive drop for `t_end` s with fixed-step RK4 of `step` s.
fn passive_rk4(t_end: f64, step: &str, out_dir: &Path) -> Output {
    let t_end = t_end.to_string();
    simulate_into(
        out_dir,
        &["--t-end", &t_end, "--integrator", "rk4", "--step", step],
    )
}

fn assert_clean_failure(out: &Output, must_mention: &[&str]) {
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success(), "expected failure; stderr: {stderr}");
    assert!(!stderr.contains("panicked"), "panic: {stderr}");
    for m in must_mention {
        assert!(stderr.contains(m), "stderr should mention {m:?}: {stderr}");
    }
}

#[test]
fn cli_scripted_push_writes_consistent_files() {
    let dir = tmpdir("push");
    let (x0, series) = scripted_push();
    let tau = dir.join("tau.csv");
    series.write_csv(&tau).unwrap();
    let init = dir.join("init.json");
    std::fs::write(
        &init,
        serde_json::json!({"q": &x0[0..3], "qd": &x0[3..6], "omega": &x0[6..9]}).to_string(),
    )
    .unwrap();
    let out_dir = dir.join("out");
    let o = run(&[
        "simulate",
        "--scene",
        "scenes/paper.toml",
        "--torques",
        tau.to_str().unwrap(),
        "--init",
        init.to_str().unwrap(),
        "--t-end",
        "2.5",
        "--rtol",
        "1e-10",
        "--impact-law",
        "stick",
        "--out",
        out_dir.to_str().unwrap(),
    ]);
    let stdout = String::from_utf8_lossy(&o.stdout);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    for key in ["events: 3", "max penetration", "real-time factor", "energy"] {
        assert!(stdout.contains(key), "summary lacks {key:?}: {stdout}");
    }
    let ev = json(&out_dir.join("events.json"));
    assert_eq!(event_kinds(&ev), ["impact", "stick_to_slip", "lift_off"]);
    assert!(ev["events"][0]["pre"]["h"].as_f64().unwrap().abs() < 1e-9);
    // The CSV has the documented columns and the same number of rows as the JSON.
    let csv = std::fs::read_to_string(out_dir.join("trajectory.csv")).unwrap();
    let header = csv.lines().next().unwrap();
    assert!(header.starts_with(
        "t [s],mode,kind,q1 [rad],q2 [rad],q3 [rad],qd1 [rad/s],qd2 [rad/s],qd3 [rad/s],\
         omega_x [rad/s],omega_y [rad/s],omega_z [rad/s],tau1 [N m]"
    ));
    assert!(
        header.contains("lambda_n [N],h [m],sigma [N],dv [m/s],hdot [m/s],energy [J],drift [m]")
    );
    // One naming of modes: lowercase in the CSV as in the JSON; state components named.
    let tj0 = json(&out_dir.join("trajectory.json"));
    assert_eq!(tj0["state_names"][6], "omega_x");
    let row1 = csv.lines().nth(1).unwrap();
    assert_eq!(row1.split(',').nth(1), tj0["mode"][0].as_str());
    let evcsv = std::fs::read_to_string(out_dir.join("events.csv")).unwrap();
    assert!(evcsv.lines().next().unwrap().contains(",pre_q1 [rad],"));
    let tj = json(&out_dir.join("trajectory.json"));
    let n = tj["t"].as_array().unwrap().len();
    assert_eq!(csv.lines().count(), n + 1);
    // τ column = the series at the sample time (the file round-trips exactly).
    let t5 = tj["t"][5].as_f64().unwrap();
    let mut tau5 = [0.0; 3];
    series.eval(t5, &mut tau5);
    for j in 0..3 {
        assert_eq!(tj["derived"][5]["tau"][j].as_f64().unwrap(), tau5[j]);
    }
    let sm = json(&out_dir.join("summary.json"));
    assert_eq!(sm["t_final"].as_f64().unwrap(), 2.5);
    assert!(sm["error"].is_null());
    let shares: f64 = sm["mode_time_share"]
        .as_array()
        .unwrap()
        .iter()
        .map(|p| p[1].as_f64().unwrap())
        .sum();
    assert!((shares - 1.0).abs() < 1e-12);
    std::fs::remove_dir_all(&dir).unwrap();
}

/// Passive drop (default initial state, τ = 0, Newton's law): the Slip → Stick events happen at
/// ‖Δv‖ = ε with ‖Δv‖ decreasing, and the velocities are updated to Δv = 0.
#[test]
fn cli_passive_drop_slip_to_stick_and_rk4_agrees_with_dopri5() {
    let dir = tmpdir("drop");
    let mut first_impact = Vec::new();
    let mut sequences = Vec::new();
    for (tag, extra) in [
        ("dopri", vec!["--rtol", "1e-10"]),
        ("rk4", vec!["--integrator", "rk4", "--step", "5e-4"]),
        // Loose tolerance: a step jumps over the ε-ball of ‖Δv‖; the slip_reversal guard must
        // still catch Slip → Stick, so the Fig. 3 event sequence is the same.
        ("loose", vec!["--rtol", "1e-4"]),
    ] {
        let out_dir = dir.join(tag);
        let mut args = vec![
            "simulate",
            "--t-end",
            "3",
            "--out",
            out_dir.to_str().unwrap(),
        ];
        args.extend(extra);
        let o = run(&args);
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        let ev = json(&out_dir.join("events.json"));
        let evs = ev["events"].as_array().unwrap();
        first_impact.push(evs[0]["t"].as_f64().unwrap());
        sequences.push(
            evs.iter()
                .map(|e| e["kind"].as_str().unwrap().to_string())
                .collect::<Vec<_>>(),
        );
        if tag == "dopri" {
            let s2s: Vec<&Value> = evs
                .iter()
                .filter(|e| e["kind"] == "slip_to_stick")
                .collect();
            assert!(!s2s.is_empty(), "no slip-to-stick event");
            let tj = json(&out_dir.join("trajectory.json"));
            for e in s2s {
                let pre = e["pre"]["slip_speed"].as_f64().unwrap();
                assert!((pre - 1e-6).abs() < 1e-9, "‖Δv‖ at slip→stick {pre:e}");
                assert!(e["post"]["slip_speed"].as_f64().unwrap() < 1e-12);
                assert_ne!(e["x_pre"], e["x_post"], "velocities must be updated");
                // Decreasing: the last step sample before the event had a larger ‖Δv‖.
                let t = e["t"].as_f64().unwrap();
                let ts = tj["t"].as_array().unwrap();
                let k = ts.iter().rposition(|v| v.as_f64().unwrap() < t).unwrap();
                assert!(tj["derived"][k]["slip_speed"].as_f64().unwrap() > pre);
            }
        }
    }
    assert_eq!(
        sequences[0], sequences[2],
        "loose rtol changed the event sequence"
    );
    assert!(
        (first_impact[0] - first_impact[1]).abs() < 1e-6,
        "first impact dopri5 {} vs rk4 {}",
        first_impact[0],
        first_impact[1]
    );
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn cli_failure_mid_run_writes_partial_trajectory() {
    let dir = tmpdir("fail");
    let out_dir = dir.join("out");
    let o = run(&[
        "simulate",
        "--t-end",
        "10",
        "--max-steps",
        "300",
        "--out",
        out_dir.to_str().unwrap(),
    ]);
    assert_clean_failure(
        &o,
        &["simulation failed at t =", "step limit", "written to"],
    );
    let tj = json(&out_dir.join("trajectory.json"));
    let ts = tj["t"].as_array().unwrap();
    assert!(
        ts.len() > 100,
        "partial trajectory has {} samples",
        ts.len()
    );
    let t_last = ts.last().unwrap().as_f64().unwrap();
    assert!(t_last > 0.0 && t_last < 10.0);
    let sm = json(&out_dir.join("summary.json"));
    assert!(sm["error"].as_str().unwrap().contains("step limit"));
    assert_eq!(sm["t_final"].as_f64().unwrap(), t_last);
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn cli_bad_inputs_give_clear_errors() {
    let dir = tmpdir("bad");
    let out = dir.join("out");
    let out = out.to_str().unwrap();
    let bad_csv = dir.join("bad.csv");
    std::fs::write(&bad_csv, "t,tau1,tau2,tau3\n0,0,0,0\n0.5,1,x,0\n").unwrap();
    let bad_csv = bad_csv.to_str().unwrap();
    let two = dir.join("two.csv");
    std::fs::write(&two, "t,tau1,tau2\n0,0,0\n").unwrap();
    let two = two.to_str().unwrap();
    // A solution of a schema this program does not know (a newer one).
    let newer = dir.join("newer.json");
    let mut sol = json(&root().join("data/optima/periodic-qc/solution.json"));
    sol["schema_version"] = serde_json::json!(99);
    std::fs::write(&newer, sol.to_string()).unwrap();
    let newer = newer.to_str().unwrap();
    // A solution whose own fields disagree (a period that is not the phases' sum) is refused
    // as `track` and `optimize --warm-start` refuse it: the replay is timed by the period.
    let edited = dir.join("edited.json");
    let mut sol = json(&root().join("data/optima/periodic-qc/solution.json"));
    sol["period"] = serde_json::json!(1.0);
    std::fs::write(&edited, sol.to_string()).unwrap();
    let edited = edited.to_str().unwrap();
    let mode_file = dir.join("mode.json");
    std::fs::write(&mode_file, r#"{"q": [0.1, 0.5, 0.5], "mode": "flying"}"#).unwrap();
    let mode_file = mode_file.to_str().unwrap();
    // A key given twice: the reader kept the last one without a word.
    let twice = dir.join("twice.json");
    std::fs::write(&twice, r#"{"q": [0.1, 0.5, 0.5], "q": [0, 0, 0]}"#).unwrap();
    let twice = twice.to_str().unwrap();
    // A state of a sticking contact (Δv = 0) started in slip: the slip direction is undefined,
    // and the model's reason must reach the user (it used to read "the energy is not finite").
    let sticking = dir.join("sticking.json");
    std::fs::write(
        &sticking,
        r#"{"q": [0.4714011146770635, 1.1162406379196423, 0.9352825204037364],
            "qd": [-0.07209944221755044, 0.0008025915078182113, -0.0018200622220615012],
            "omega": [0.0687896964370189, -0.0075820544898763985, -0.013019316170702675],
            "mode": "stick"}"#,
    )
    .unwrap();
    let sticking = sticking.to_str().unwrap();
    // (options, mentions, exit status: 2 for a wrong command line, 1 for a file or a state
    // that does not fit).
    let cases: Vec<(Vec<&str>, Vec<&str>, i32)> = vec![
        (
            vec!["--torques", "no/such/file.csv"],
            vec!["no/such/file.csv"],
            1,
        ),
        (
            vec!["--torques", bad_csv],
            vec!["bad.csv:3", "tau2", "not a number"],
            1,
        ),
        (vec!["--torques", two], vec!["3 joints"], 1),
        (vec!["--q0", "0.1,NaN,0.5"], vec!["--q0", "finite"], 2),
        (vec!["--q0", "0.1,0.5"], vec!["--q0", "expected 3"], 2),
        (
            vec!["--q0", "1100000,0,0"],
            vec!["--q0", "q1 = 1.1e6 rad", "2²⁰"],
            2,
        ),
        (vec!["--t-end", "0"], vec!["--t-end", "> 0"], 2),
        (vec!["--t-end", "-1"], vec!["--t-end"], 2),
        (
            vec!["--integrator", "euler"],
            vec!["--integrator", "unknown integrator `euler`"],
            2,
        ),
        (
            vec!["--impact-law", "bounce"],
            vec!["--impact-law", "unknown impact law `bounce`"],
            2,
        ),
        (vec!["--mode0", "roll"], vec!["--mode0", "unknown mode"], 2),
        (
            vec!["--step", "0.01"],
            vec!["--step does not apply to --integrator dopri5"],
            2,
        ),
        (
            vec!["--integrator", "rk4", "--h-max", "0.01"],
            vec!["--h-max does not apply to --integrator rk4"],
            2,
        ),
        // Given at its default value, the other integrator's option is still given, and
        // still ignored by this one.
        (
            vec!["--step", "0.001"],
            vec!["--step does not apply to --integrator dopri5"],
            2,
        ),
        (
            vec!["--integrator", "rk4", "--rtol", "1e-8"],
            vec!["--rtol does not apply to --integrator rk4"],
            2,
        ),
        (
            vec!["--integrator", "rk4", "--atol", "1e-9"],
            vec!["--atol does not apply"],
            2,
        ),
        (
            vec!["--scene", "scenes/puma560.toml", "--impact-law", "stick"],
            vec!["--impact-law", "no ball"],
            2,
        ),
        (
            vec!["--scene", "scenes/puma560.toml", "--impact-law", "newton"],
            vec!["--impact-law", "no ball"],
            2,
        ),
        (
            vec!["--scene", "scenes/puma560.toml", "--no-projection"],
            vec!["--no-projection", "no ball"],
            2,
        ),
        (vec!["--rtol", "0"], vec!["--rtol"], 2),
        (vec!["--rtol", "1000"], vec!["--rtol", "at most 0.1"], 2),
        (
            vec!["--pd", "0,0,0", "--pd-gains", "1,2,3"],
            vec!["--pd-gains"],
            2,
        ),
        (vec!["--pd-gains", "1,2"], vec!["--pd-gains", "--pd"], 2),
        (
            vec!["--q0", "0.0,1.6,0.5", "--mode0", "stick"],
            vec!["h"],
            1,
        ),
        (
            vec!["--scene", "scenes/puma560.toml", "--omega0", "0,0,1"],
            vec!["puma560", "no ball", "--omega0"],
            2,
        ),
        (vec!["--init", "missing.json"], vec!["missing.json"], 1),
        (
            vec!["--init", mode_file],
            vec!["mode.json", "`mode`", "unknown mode `flying`"],
            1,
        ),
        (
            vec!["--init", newer],
            vec!["newer.json", "schema_version 99"],
            1,
        ),
        (
            vec!["--init", edited],
            vec![
                "--init",
                "edited.json",
                "`period` is 1 s",
                "phase_durations",
            ],
            1,
        ),
        (
            vec!["--init", twice],
            vec!["twice.json", "`q` is given twice"],
            1,
        ),
        (vec!["--max-steps", "0"], vec!["--max-steps", "≥ 1"], 2),
        (
            vec![
                "--scene",
                "scenes/human.toml",
                "--param",
                "ball.radius=0.5",
                "--param",
                "ball.radius=0.6",
            ],
            vec!["--param ball.radius=0.6", "already set to 0.5"],
            2,
        ),
        (vec!["--max-samples", "0"], vec!["--max-samples", "≥ 1"], 2),
        (
            vec!["--init", sticking, "--mode0", "slip"],
            vec!["in mode slip", "slip direction undefined", "sticking.json"],
            1,
        ),
        // On the ball but moving off it and sliding: no sticking contact, which the first
        // step's projection used to remove without a word.
        (
            vec![
                "--q0",
                "0.1,1.0,1.2263822707834908",
                "--qd0",
                "0,0,-0.2",
                "--mode0",
                "stick",
            ],
            vec!["initial mode stick", "n·v_c = ", "‖Δv‖ = ", "--mode0 slip"],
            1,
        ),
    ];
    for (extra, mention, status) in cases {
        let mut args = vec!["simulate", "--out", out];
        if !extra.contains(&"--t-end") {
            args.extend(["--t-end", "0.1"]);
        }
        args.extend(extra.iter().copied());
        let o = run(&args);
        assert_clean_failure(&o, &mention);
        assert_eq!(o.status.code(), Some(status), "{extra:?}");
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

/// A coarse fixed step (RK4, h = 10 ms) makes the cubic interpolant of h dip below zero right
/// after a lift-off although the finger separates (n·v_c > 0). Such crossings must be handled
/// as grazes (q back on h = 0, still Free, velocities untouched), not as impacts on a
/// separating finger (which bf-model rightly refuses).
#[test]
fn cli_coarse_rk4_grazes_instead_of_failing() {
    let dir = tmpdir("graze");
    let out_dir = dir.join("out");
    let o = passive_rk4(2.0, "1e-2", &out_dir);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let ev = json(&out_dir.join("events.json"));
    let grazes: Vec<&Value> = ev["events"]
        .as_array()
        .unwrap()
        .iter()
        .filter(|e| e["kind"] == "graze")
        .collect();
    assert!(!grazes.is_empty(), "expected grazes with h = 10 ms");
    for g in grazes {
        assert!(g["pre"]["normal_velocity"].as_f64().unwrap() > 1e-9);
        assert!(g["post"]["h"].as_f64().unwrap().abs() < 1e-14);
        assert_eq!(
            g["x_pre"].as_array().unwrap()[3..],
            g["x_post"].as_array().unwrap()[3..]
        );
        assert_eq!(g["mode_after"], "free");
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

/// A 4-joint finger-and-ball scene outside `scenes/` (interpreted kernels), driven by a PD
/// controller whose target lies inside the ball: `simulate` touches down, stays in contact
/// (stick or slip), and its files say so consistently: h ≥ −tol at every sample, the energy
/// balance E(t) − E(0) − ∫ (q̇ᵀτ − losses) dt closes, and the trajectory has one column per
/// joint.
#[test]
fn cli_simulates_a_4_joint_finger_on_the_ball() {
    let path = "tests/fixtures/finger4.toml";
    let text = std::fs::read_to_string(cli_util::root().join(path)).unwrap();
    let scene = bf_codegen::Scene::from_toml_str(&text, path).unwrap();
    let (k, _) = bf_model::registry::contact_kernels_n::<4>(&scene).unwrap();
    let model = Model::from_kernels(k).unwrap();
    // A side contact of the last link, by Newton steps on h from a fixed guess.
    let mut x = State::new(
        bf_model::VecN::<4>::new(0.3, 0.6, 0.6, 0.6),
        bf_model::VecN::zeros(),
        Vec3::zeros(),
    );
    for _ in 0..50 {
        x.q += model.project_configuration(&x).unwrap();
    }
    let kin = model.evaluate(&x).unwrap();
    assert!(kin.contact.h.abs() < 1e-12, "h = {}", kin.contact.h);
    let grad = kin.contact.j_c.transpose() * kin.contact.n;
    let dir = grad / grad.norm();
    let q0 = x.q + dir * 0.05;
    let target = x.q - dir * 0.3;
    let list = |v: &bf_model::VecN<4>| {
        v.iter()
            .map(|x| format!("{x:.17}"))
            .collect::<Vec<_>>()
            .join(",")
    };
    let dir = tmpdir("finger4");
    let out_dir = dir.join("out");
    let o = run(&[
        "simulate",
        "--scene",
        path,
        "--q0",
        &list(&q0),
        "--pd",
        &list(&target),
        "--pd-gains",
        "0.5,0.05",
        "--rtol",
        "1e-9",
        "--h-max",
        "0.002",
        "--t-end",
        "1.0",
        "--out",
        out_dir.to_str().unwrap(),
    ]);
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{stderr}");
    assert!(stderr.contains("interpreted"), "{stderr}");
    let sm = json(&out_dir.join("summary.json"));
    assert_eq!(sm["kernels"], "interpreted");
    let count = |k: &str| {
        sm["event_counts"]
            .as_array()
            .unwrap()
            .iter()
            .find(|e| e[0] == k)
            .unwrap()[1]
            .as_u64()
            .unwrap()
    };
    assert!(count("impact") >= 1, "{sm}");
    let share = |m: &str| {
        sm["mode_time_share"]
            .as_array()
            .unwrap()
            .iter()
            .find(|e| e[0] == m)
            .unwrap()[1]
            .as_f64()
            .unwrap()
    };
    assert!(share("stick") + share("slip") > 0.5, "{sm}");
    // The balance closes to 1e-5 of the energy (short steps: the trapezoidal ∫ P dt over the
    // samples converges like h², 5e-5 J with the default steps and 3e-6 J with these).
    assert!(sm["energy_error"].as_f64().unwrap() < 1e-5, "{sm}");
    assert!(
        sm["max_penetration"].as_f64().unwrap() < PENETRATION_TOL,
        "{sm}"
    );
    assert!(sm["error"].is_null(), "{sm}");
    // One column per joint, and h ≥ −tol at every stored sample.
    let csv = std::fs::read_to_string(out_dir.join("trajectory.csv")).unwrap();
    let mut lines = csv.lines();
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    for c in ["q4 [rad]", "qd4 [rad/s]", "tau4 [N m]"] {
        assert!(header.contains(&c), "{header:?}");
    }
    assert!(!header.contains(&"q5 [rad]"));
    let h_col = header.iter().position(|c| *c == "h [m]").unwrap();
    for line in lines {
        let h: f64 = line.split(',').nth(h_col).unwrap().parse().unwrap();
        assert!(h > -PENETRATION_TOL, "h = {h}");
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

/// Finger-and-ball scenes of another number of joints: the options take that many values, and a
/// scene beyond the supported range is refused with the range.
#[test]
fn cli_joint_counts_are_checked() {
    let dir = tmpdir("joints");
    let out = dir.join("out");
    let out = out.to_str().unwrap();
    let text =
        std::fs::read_to_string(cli_util::root().join("tests/fixtures/finger4.toml")).unwrap();
    let (a, b) = (
        text.find("[[links]]").unwrap(),
        text.find("[ball]").unwrap(),
    );
    let eight = format!("{}{}{}{}", &text[..a], &text[a..b], &text[a..b], &text[b..]);
    let eight_path = dir.join("finger8.toml");
    std::fs::write(&eight_path, eight).unwrap();
    // Three torque columns: one too many for the 2-joint finger and the 2-joint arm alike.
    let three = dir.join("three.csv");
    std::fs::write(&three, "t,tau1,tau2,tau3\n0,0,0,0\n0.1,0,0,0\n").unwrap();
    let three = three.to_str().unwrap();
    let cases: Vec<(Vec<&str>, Vec<&str>)> = vec![
        (
            vec![
                "--scene",
                "tests/fixtures/finger2.toml",
                "--q0",
                "0.1,0.2,0.3",
            ],
            vec!["--q0", "expected 2"],
        ),
        (
            vec!["--scene", "tests/fixtures/finger4.toml", "--pd", "0,0,0"],
            vec!["--pd", "expected 4"],
        ),
        (
            vec!["--scene", eight_path.to_str().unwrap()],
            vec!["finger8.toml", "8 joints", "1 to 7"],
        ),
        (
            vec!["--scene", "tests/fixtures/finger2.toml", "--torques", three],
            vec!["three.csv", "2 joints", "3 columns"],
        ),
        (
            vec![
                "--scene",
                "tests/fixtures/planar2_arm.toml",
                "--torques",
                three,
            ],
            vec!["three.csv", "2 joints", "3 columns"],
        ),
    ];
    for (extra, mention) in cases {
        let mut args = vec!["simulate", "--out", out, "--t-end", "0.1"];
        args.extend(extra.iter().copied());
        assert_clean_failure(&run(&args), &mention);
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

/// A run whose energy balance misses the simulator's tolerance (1e-3 J) failed its own check:
/// RK4 with a 0.1 s step over a passive 2 s flight leaves a balance error of about 2e-2 J, and
/// the run exits 1 with the whole trajectory written and the set marked FAILED; with 0.05 s the
/// error is below the tolerance and the same run succeeds, unmarked.
#[test]
fn a_run_whose_energy_balance_fails_is_marked_failed() {
    let dir = tmpdir("energy-check");
    for (step, fails) in [("0.1", true), ("0.05", false)] {
        let out_dir = dir.join(step);
        let o = passive_rk4(2.0, step, &out_dir);
        let summary = json(&out_dir.join("summary.json"));
        let error = summary["energy_error"].as_f64().unwrap();
        assert_eq!(error > 1e-3, fails, "step {step}: balance error {error}");
        // A run shorter than the check's window is checked from t₀ as a whole.
        assert_eq!(summary["energy_drift"].as_f64(), Some(error), "step {step}");
        assert_eq!(summary["t_final"].as_f64().unwrap(), 2.0, "step {step}");
        assert_eq!(out_dir.join("FAILED").exists(), fails, "step {step}");
        // summary.json names the reason too, as an arm's does.
        assert_eq!(
            summary["error"]
                .as_str()
                .is_some_and(|e| e.contains("energy balance failed its check")),
            fails,
            "step {step}: {}",
            summary["error"]
        );
        if fails {
            assert_clean_failure(&o, &["energy balance failed its check"]);
            assert_eq!(o.status.code(), Some(1));
        } else {
            assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        }
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

/// An accurate long run (the human plan replayed with PD tracking for 150 s, twelve periods,
/// at the default tolerance) passes the energy check: the trapezoidal rule over its samples,
/// computed here from the files, leaves a residual beyond the tolerance, about 2.8e-3 J, all of
/// it quadrature; the simulator's check, whose ∫ P dt is exact to the integration's order,
/// leaves a residual over 30 times smaller.
#[test]
fn a_long_accurate_run_passes_the_energy_check() {
    let dir = tmpdir("energy-long");
    let plan = root().join("data/optima/periodic-cot-human-plan/solution.json");
    let o = simulate_into(
        &dir,
        &[
            "--init",
            plan.to_str().unwrap(),
            "--pd-track",
            "1,0.2",
            "--impact-law",
            "newton",
            "--t-end",
            "150",
        ],
    );
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let summary = json(&dir.join("summary.json"));
    let (error, drift) = (
        summary["energy_error"].as_f64().unwrap(),
        summary["energy_drift"].as_f64().unwrap(),
    );
    assert!(
        drift < 1e-4 && error <= drift,
        "error {error}, drift {drift}"
    );
    assert!(!dir.join("FAILED").exists());
    let traj = json(&dir.join("trajectory.json"));
    let (t, kind, derived) = (
        traj["t"].as_array().unwrap(),
        traj["kind"].as_array().unwrap(),
        traj["derived"].as_array().unwrap(),
    );
    let (mut trapezoid, mut worst) = (0.0f64, 0.0f64);
    for i in 1..t.len() {
        if kind[i] == "EventPost" {
            continue;
        }
        let at = |k: usize, key: &str| derived[k][key].as_f64().unwrap();
        let h = t[i].as_f64().unwrap() - t[i - 1].as_f64().unwrap();
        trapezoid +=
            at(i, "energy") - at(i - 1, "energy") - 0.5 * (at(i, "power") + at(i - 1, "power")) * h;
        worst = worst.max(trapezoid.abs());
    }
    assert!(
        worst > 1e-3 && worst > 30.0 * drift,
        "trapezoid {worst}, drift {drift}"
    );
    std::fs::remove_dir_all(&dir).unwrap();
}

/// An arm without a ball is held to the same rule, relative to the energy it moves: the
/// PUMA's passive fall with RK4 at 0.1 s fails, with everything written.
#[test]
fn an_arm_run_whose_energy_balance_fails_is_marked_failed() {
    let dir = tmpdir("energy-arm");
    let puma = root().join("scenes/puma560.toml");
    let o = simulate_into(
        &dir,
        &[
            "--scene",
            puma.to_str().unwrap(),
            "--integrator",
            "rk4",
            "--step",
            "0.1",
            "--t-end",
            "5",
        ],
    );
    assert_clean_failure(&o, &["energy balance failed its check", "too coarse"]);
    assert_eq!(o.status.code(), Some(1));
    assert!(dir.join("FAILED").exists());
    let summary = json(&dir.join("summary.json"));
    assert!(
        summary["energy_error"].as_f64().unwrap() > summary["energy_tolerance"].as_f64().unwrap(),
        "{summary}"
    );
    assert!(summary["error"].is_string(), "{summary}");
    std::fs::remove_dir_all(&dir).unwrap();
}

/// A replay of a plan that failed its own checks says so: it shows that plan, not a verified
/// optimum. The same file marked verified replays without the warning.
#[test]
fn a_replay_of_an_unverified_solution_is_flagged() {
    let dir = tmpdir("unverified-replay");
    let mut sol = json(&root().join("data/optima/periodic-qc/solution.json"));
    for (verified, warned) in [(true, false), (false, true)] {
        sol["verified"] = serde_json::json!(verified);
        let path = dir.join("solution.json");
        std::fs::write(&path, sol.to_string()).unwrap();
        let o = simulate_into(
            &dir.join("out"),
            &["--init", path.to_str().unwrap(), "--t-end", "0.05"],
        );
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(o.status.success(), "{err}");
        assert_eq!(
            err.contains("warning") && err.contains("not verified"),
            warned,
            "{err}"
        );
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

/// A ball whose centre lies on the contact link's line at q = 0 makes the contact normal
/// undefined there, where the simulator measured the contact link's length. It is measured
/// at other configurations instead: the finger's free flight from q₀ = (1, 1, 1) is then the
/// paper scene's, step for step (the ball is not reached in 0.05 s), where before every run
/// on such a scene failed with a "system error".
#[test]
fn a_scene_singular_at_q_zero_simulates_like_its_twin() {
    let dir = tmpdir("singular-q0");
    let text = std::fs::read_to_string(root().join("scenes/paper.toml")).unwrap();
    // The finger's base is at (2, 0, 0), turned about y so that at q = 0 its links lie along
    // the world's z axis through it: (2, 0, 2.5) is on the last link's line.
    let moved = text.replace("center = [0.0, 0.0, 0.0]", "center = [2.0, 0.0, 2.5]");
    assert_ne!(moved, text);
    let scene = dir.join("singular.toml");
    std::fs::write(&scene, moved).unwrap();
    let mut runs = Vec::new();
    for (tag, path) in [
        ("singular", scene.clone()),
        ("twin", root().join("scenes/paper.toml")),
    ] {
        let out = dir.join(tag);
        let o = simulate_into(
            &out,
            &[
                "--scene",
                path.to_str().unwrap(),
                "--q0",
                "1,1,1",
                "--t-end",
                "0.05",
            ],
        );
        assert!(
            o.status.success(),
            "{tag}: {}",
            String::from_utf8_lossy(&o.stderr)
        );
        let summary = json(&out.join("summary.json"));
        assert_eq!(summary["mode_final"], "free", "{tag}");
        runs.push(json(&out.join("trajectory.json")));
    }
    let (a, b) = (&runs[0]["x"], &runs[1]["x"]);
    assert_eq!(runs[0]["t"], runs[1]["t"]);
    let (a, b) = (a.as_array().unwrap(), b.as_array().unwrap());
    assert_eq!(a.len(), b.len());
    for (ra, rb) in a.iter().zip(b) {
        for (x, y) in ra
            .as_array()
            .unwrap()
            .iter()
            .zip(rb.as_array().unwrap())
            .take(6)
        {
            let (x, y) = (x.as_f64().unwrap(), y.as_f64().unwrap());
            assert!((x - y).abs() <= 1e-12 * (1.0 + x.abs()), "{x} vs {y}");
        }
    }
    std::fs::remove_dir_all(&dir).ok();
}

/// The paper's scene with every mass, inertia and damping constant ×`k` (`name` renamed): the
/// same motion, with every energy ×`k`.
fn paper_scene_scaled(k: f64) -> String {
    let text = std::fs::read_to_string(root().join("scenes/paper.toml")).unwrap();
    let scale = |v: &str| -> String {
        let x: f64 = v.trim().parse().unwrap();
        format!("{:?}", x * k)
    };
    text.lines()
        .map(|l| {
            if l.starts_with("name = \"paper\"") {
                "name = \"paper_scaled\"".to_string()
            } else if let Some((key, v)) = l.split_once(" = ")
                && ["mass", "mu_v", "socket_damping"].contains(&key)
            {
                format!("{key} = {}", scale(v))
            } else if let Some(list) = l
                .strip_prefix("inertia = [")
                .and_then(|r| r.strip_suffix(']'))
            {
                let v: Vec<String> = list.split(',').map(scale).collect();
                format!("inertia = [{}]", v.join(", "))
            } else {
                l.to_string()
            }
        })
        .collect::<Vec<_>>()
        .join("\n")
}

/// The energy-balance check is relative to the energy a run moves, so a scene's size does not
/// decide the verdict: with every mass ×1e5 the same motion's balance error and tolerance
/// both grow ×1e5 (an absolute 1e-3 J failed this accurate run), and with every mass ×1e-2 a
/// fixed RK4 step of 0.1 s still fails, as it does on the paper's scene (an absolute 1e-3 J
/// passed it, 4 % of the run's energy).
#[test]
fn the_energy_check_does_not_depend_on_the_scenes_size() {
    let dir = tmpdir("energy-scale");
    let summary = |k: f64, extra: &[&str]| -> (bool, Value) {
        let scene = dir.join(format!("scaled_{k:e}.toml"));
        std::fs::write(&scene, paper_scene_scaled(k)).unwrap();
        let out = dir.join(format!("out_{k:e}_{}", extra.len()));
        let mut args = vec!["--scene", scene.to_str().unwrap()];
        args.extend_from_slice(extra);
        let r = simulate_into(&out, &args);
        (r.status.success(), json(&out.join("summary.json")))
    };
    let ratio =
        |s: &Value| s["energy_error"].as_f64().unwrap() / s["energy_tolerance"].as_f64().unwrap();
    let (ok1, one) = summary(1.0, &[]);
    let (ok5, big) = summary(1e5, &[]);
    assert!(ok1 && ok5, "{one}\n{big}");
    let rel = |a: f64, b: f64| (a - b).abs() / b.abs();
    for key in ["energy_initial", "energy_error", "energy_tolerance"] {
        let (a, b) = (big[key].as_f64().unwrap(), one[key].as_f64().unwrap());
        assert!(rel(a, 1e5 * b) < 1e-6, "{key}: {a} against 1e5 × {b}");
    }
    assert!(rel(ratio(&big), ratio(&one)) < 1e-6);
    assert!(ratio(&one) < 1e-3, "{one}");
    let coarse = ["--integrator", "rk4", "--step", "0.1"];
    for k in [1.0, 1e-2] {
        let (ok, s) = summary(k, &coarse);
        assert!(!ok && ratio(&s) > 1.0, "×{k}: {s}");
        let warned = s["warnings"]
            .as_array()
            .unwrap()
            .iter()
            .any(|w| w["kind"] == "energy_error");
        assert!(warned, "×{k}: {s}");
    }
}

/// Every impact records the impulse the law applied (`events.json`'s `impulse`), and an
/// impulse no contact can give is warned of. Checked against the jump of the state: the
/// finger's M_f (q̇⁺ − q̇⁻) = J_cᵀ ι at the impact's position (eq. 29a), and with the
/// sticking law the ball's I_b (ω⁺ − ω⁻) = −r_c × ι. On the paper's scene the unactuated
/// finger's sticking impacts pull it onto the ball (ι·n < 0), which `summary.json` must say
/// (`pulling_impulse`), once per such impact, and so must each of its sticking impulses that
/// push but need more friction than μ_s gives (`impulse_outside_cone`, eq. 66); the default
/// run's Newton impacts push.
#[test]
fn impacts_record_their_impulse_and_an_impulse_no_contact_gives_is_warned() {
    use bf_model::{Model, PaperKernels, VecN};
    let model = Model::from_kernels(PaperKernels::new()).unwrap();
    let dir = tmpdir("impulse");
    for (law, pulls) in [("stick", true), ("newton", false)] {
        let out = dir.join(law);
        simulate_into(&out, &["--impact-law", law]);
        let events = json(&out.join("events.json"));
        let summary = json(&out.join("summary.json"));
        let (mut pulling, mut outside, mut impacts) = (0, 0, 0);
        for e in events["events"].as_array().unwrap() {
            if e["kind"] != "impact" {
                assert!(e["impulse"].is_null(), "{e}");
                continue;
            }
            impacts += 1;
            let x = |k: &str| -> Vec<f64> {
                e[k].as_array()
                    .unwrap()
                    .iter()
                    .map(|v| v.as_f64().unwrap())
                    .collect()
            };
            let (pre, post) = (x("x_pre"), x("x_post"));
            let imp = &e["impulse"];
            let iota = Vec3::from_iterator(
                imp["impulse"]
                    .as_array()
                    .unwrap()
                    .iter()
                    .map(|v| v.as_f64().unwrap()),
            );
            let s = State::new(
                VecN::<3>::from_column_slice(&post[..3]),
                VecN::<3>::from_column_slice(&post[3..6]),
                Vec3::from_column_slice(&post[6..9]),
            );
            let kin = model.evaluate(&s).unwrap();
            let dqd = VecN::<3>::from_column_slice(&post[3..6])
                - VecN::<3>::from_column_slice(&pre[3..6]);
            let lhs = kin.m_f * dqd;
            let rhs = kin.contact.j_c.transpose() * iota;
            assert!(
                (lhs - rhs).norm() <= 1e-9 * (1.0 + lhs.norm()),
                "{law} at t = {}: M_f dqd {lhs} against J_c^T iota {rhs}",
                e["t"]
            );
            if law == "stick" {
                let dw = Vec3::from_column_slice(&post[6..9]) - Vec3::from_column_slice(&pre[6..9]);
                let ball = model.params().ball_inertia() * dw;
                let reaction = -kin.contact.r_c.cross(&iota);
                assert!((ball - reaction).norm() <= 1e-9 * (1.0 + ball.norm()));
            }
            let normal = iota.dot(&kin.contact.n);
            assert!((normal - imp["normal"].as_f64().unwrap()).abs() <= 1e-9 * iota.norm());
            let tol = 1e-9 * iota.norm();
            let tangential = (iota - kin.contact.n * normal).norm();
            if normal < -tol {
                pulling += 1;
            } else if law == "stick" && model.params().mu_s() * normal - tangential < -tol {
                outside += 1;
            }
        }
        let count = |kind: &str| {
            summary["warnings"]
                .as_array()
                .unwrap()
                .iter()
                .filter(|w| w["kind"] == kind)
                .count()
        };
        assert!(impacts > 0, "{law}");
        assert_eq!(count("pulling_impulse"), pulling, "{law}: {summary}");
        assert_eq!(count("impulse_outside_cone"), outside, "{law}: {summary}");
        // The sticking law also asks more friction than μ_s gives at some impacts that push.
        assert_eq!(
            outside > 0,
            law == "stick",
            "{law}: {outside} outside the cone"
        );
        assert_eq!(
            pulling > 0,
            pulls,
            "{law}: {pulling} of {impacts} impacts pull"
        );
    }
}

/// A `--torques` run ends with its series unless `--t-end` says otherwise, and one that goes on
/// past it (or starts before it) says that it holds the last (first) torque (`torques_held`, in `summary.json` and on
/// stderr); `--no-projection` says that the drift was not projected instead of reporting a
/// projected drift of 0; a solution replayed under another impact law than it was planned with
/// says so.
#[test]
fn a_replay_says_what_it_does_not_replay() {
    let dir = tmpdir("replay");
    let tau = dir.join("tau.csv");
    std::fs::write(&tau, "t,tau1,tau2,tau3\n0,0,0.1,0\n0.3,0,0.1,0\n").unwrap();
    let tau = tau.to_str().unwrap();
    let held = |s: &Value| {
        s["warnings"]
            .as_array()
            .unwrap()
            .iter()
            .any(|w| w["kind"] == "torques_held")
    };
    let with_series = dir.join("series");
    let o = simulate_into(&with_series, &["--torques", tau]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let s = json(&with_series.join("summary.json"));
    assert_eq!(s["t_final"].as_f64(), Some(0.3));
    assert!(!held(&s), "{s}");
    let past = dir.join("past");
    let o = simulate_into(&past, &["--torques", tau, "--t-end", "0.5"]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let s = json(&past.join("summary.json"));
    assert_eq!(s["t_final"].as_f64(), Some(0.5));
    assert!(held(&s), "{s}");
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert!(stderr.contains("holds its last torque"), "{stderr}");
    // A one-row series is a constant torque: the run goes on to --t-end, holding it, and says
    // so as well.
    let one = dir.join("one.csv");
    std::fs::write(&one, "t,tau1,tau2,tau3\n0,0,0.1,0\n").unwrap();
    let constant = dir.join("constant");
    let o = simulate_into(
        &constant,
        &["--torques", one.to_str().unwrap(), "--t-end", "0.2"],
    );
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let s = json(&constant.join("summary.json"));
    assert_eq!(s["t_final"].as_f64(), Some(0.2));
    assert!(held(&s), "{s}");
    // Without --t-end it is held over the default run, and the warning names no --t-end
    // that was not given.
    let default_run = dir.join("default-run");
    let o = simulate_into(&default_run, &["--torques", one.to_str().unwrap()]);
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{stderr}");
    let s = json(&default_run.join("summary.json"));
    assert_eq!(
        s["t_final"].as_f64(),
        Some(ball_finger::cli::DEFAULT_T_END),
        "{s}"
    );
    assert!(held(&s), "{s}");
    assert!(
        stderr.contains("held to the default run's end at 10 s"),
        "{stderr}"
    );
    assert!(!stderr.contains("--t-end 10"), "{stderr}");
    // A series that starts after the run does says that its first torque is held until then.
    let late = dir.join("late.csv");
    std::fs::write(&late, "t,tau1,tau2,tau3\n0.1,0,0.1,0\n0.2,0,0.1,0\n").unwrap();
    let late_run = dir.join("late-run");
    let o = simulate_into(&late_run, &["--torques", late.to_str().unwrap()]);
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{stderr}");
    assert!(held(&json(&late_run.join("summary.json"))), "{stderr}");
    assert!(
        stderr.contains("starts at t = 0.1 s") && stderr.contains("holds its first torque"),
        "{stderr}"
    );
    // A series that ends before the run starts says so (it said "where the run starts").
    let early = dir.join("early.csv");
    std::fs::write(
        &early,
        "t,tau1,tau2,tau3
-1,0,0.1,0
-0.5,0,0.1,0
",
    )
    .unwrap();
    let o = simulate_into(&dir.join("early"), &["--torques", early.to_str().unwrap()]);
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{stderr}");
    assert!(
        stderr.contains("ends at t = -0.5 s, before the run starts at t = 0"),
        "{stderr}"
    );
    // So does a step limit that the default run's end exceeds.
    let o = simulate_into(
        &default_run,
        &["--torques", one.to_str().unwrap(), "--max-steps", "10"],
    );
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{stderr}");
    assert!(stderr.contains("the default run's end at 10 s"), "{stderr}");
    // The same for an arm without a ball (two joints).
    let two = dir.join("two.csv");
    std::fs::write(&two, "t,tau1,tau2\n0,0.1,0\n0.1,0.1,0\n").unwrap();
    let arm = dir.join("arm");
    let o = simulate_into(
        &arm,
        &[
            "--scene",
            "tests/fixtures/planar2_arm.toml",
            "--torques",
            two.to_str().unwrap(),
            "--t-end",
            "0.3",
        ],
    );
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{stderr}");
    assert!(stderr.contains("holds its last torque"), "{stderr}");
    let s = json(&arm.join("summary.json"));
    assert!(held(&s), "{s}");

    let flat = dir.join("flat");
    let o = simulate_into(&flat, &["--no-projection", "--t-end", "1"]);
    let stdout = String::from_utf8_lossy(&o.stdout);
    assert!(o.status.success(), "{stdout}");
    assert!(
        stdout.contains("not projected (--no-projection)"),
        "{stdout}"
    );
    assert!(!stdout.contains("before projection"), "{stdout}");
    let s = json(&flat.join("summary.json"));
    assert_eq!(s["projected"], Value::Bool(false));

    // The stored paper optimum was planned with the sticking law (eq. 40).
    let plan = "data/optima/periodic-qc/solution.json";
    let other = run(&["simulate", "--init", plan, "--t-end", "0.01", "--out"]
        .into_iter()
        .chain([dir.join("newton").to_str().unwrap()])
        .collect::<Vec<_>>());
    let stderr = String::from_utf8_lossy(&other.stderr);
    assert!(other.status.success(), "{stderr}");
    assert!(
        stderr.contains("planned with the stick impact law, this run uses newton"),
        "{stderr}"
    );
    let own = run(&[
        "simulate",
        "--init",
        plan,
        "--t-end",
        "0.01",
        "--impact-law",
        "stick",
    ]
    .into_iter()
    .chain(["--out", dir.join("stick").to_str().unwrap()])
    .collect::<Vec<_>>());
    let stderr = String::from_utf8_lossy(&own.stderr);
    assert!(own.status.success(), "{stderr}");
    assert!(!stderr.contains("impact law"), "{stderr}");
    std::fs::remove_dir_all(&dir).unwrap();
}

/// Fixed-step RK4 cannot resolve the end of a slip (the friction force turns within its
/// stages, and the iteration hovers at ‖Δv‖ ≈ a h / 2), so the `slip_stop` guard ends the
/// slip where it would stop within one step. Against a DOPRI5 reference at rtol 1e-11, the
/// default drop's events must come in the reference's order, and the slip → stick event at
/// most one step early, closer as the step shrinks (before the guard, h = 1e-3 never stuck
/// and h = 1e-4 stuck 51 ms late).
#[test]
fn rk4_ends_the_slip_within_one_step_of_the_reference() {
    let dir = tmpdir("rk4-stop");
    let events = |tag: &str, extra: &[&str]| -> Vec<(String, f64)> {
        let out = dir.join(tag);
        let mut args = vec!["--t-end", "1.2"];
        args.extend_from_slice(extra);
        let o = simulate_into(&out, &args);
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        json(&out.join("events.json"))["events"]
            .as_array()
            .unwrap()
            .iter()
            .map(|e| {
                (
                    e["kind"].as_str().unwrap().to_string(),
                    e["t"].as_f64().unwrap(),
                )
            })
            .collect()
    };
    let reference = events("ref", &["--rtol", "1e-11"]);
    let stick = |ev: &[(String, f64)]| {
        ev.iter()
            .find(|e| e.0 == "slip_to_stick")
            .expect("a slip_to_stick event")
            .1
    };
    let t_ref = stick(&reference);
    let mut last_error = f64::INFINITY;
    for h in [1e-3, 3e-4, 1e-4] {
        let step = h.to_string();
        let ev = events(&step, &["--integrator", "rk4", "--step", &step]);
        let kinds = |v: &[(String, f64)]| v.iter().map(|e| e.0.clone()).collect::<Vec<_>>();
        assert_eq!(kinds(&ev), kinds(&reference), "h = {h}");
        let early = t_ref - stick(&ev);
        assert!(
            (0.0..=1.05 * h).contains(&early),
            "h = {h}: slip_to_stick {early:e} s before the reference"
        );
        assert!(
            early < last_error,
            "h = {h}: {early:e} against {last_error:e}"
        );
        last_error = early;
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

/// The sticking law on the default drop makes the stick phase chatter until the Zeno fallback
/// holds the contact for one 10 ms step while the ball pulls the finger. `summary.json` lists
/// the hold (`contact_holds`, starting at the fallback's warning), and the `held_contact`
/// warning gives the hold's whole pull and time, recomputed here from `trajectory.json`: the
/// steps integrated in contact, judged at both ends inside a hold and at their start outside
/// (where a step's end may be the pre-sample of the event that ended it), against −1e-6 of the
/// largest contact force. The pull is largest at the hold's end, where the fallback lets go.
#[test]
fn a_held_contact_reports_the_pull_at_the_end_of_its_step() {
    let dir = tmpdir("held");
    let out_dir = dir.join("out");
    let o = simulate_into(&out_dir, &["--impact-law", "stick", "--t-end", "1"]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let summary = json(&out_dir.join("summary.json"));
    let warnings = summary["warnings"].as_array().unwrap();
    let held = warnings
        .iter()
        .find(|w| w["kind"] == "held_contact")
        .expect("a held contact")["message"]
        .as_str()
        .unwrap()
        .to_string();
    let holds: Vec<[f64; 2]> = serde_json::from_value(summary["contact_holds"].clone()).unwrap();
    assert!(!holds.is_empty(), "{summary}");
    for h in &holds {
        assert!(h[0] < h[1], "{h:?}");
        assert!(
            warnings
                .iter()
                .any(|w| w["kind"] == "zeno_fallback" && w["t"].as_f64() == Some(h[0])),
            "hold {h:?} without its fallback"
        );
    }
    // The event each fallback replaced says so: one per hold, at the hold's start, whose
    // `mode_after` is the stick held rather than the mode its kind names; and no other event
    // ends in a mode its kind does not name.
    let events = json(&out_dir.join("events.json"));
    let events = events["events"].as_array().unwrap();
    let replaced: Vec<f64> = events
        .iter()
        .filter(|e| e["zeno_fallback"] == true)
        .map(|e| {
            assert_eq!(e["mode_after"], "stick", "{e}");
            e["t"].as_f64().unwrap()
        })
        .collect();
    assert_eq!(replaced, holds.iter().map(|h| h[0]).collect::<Vec<_>>());
    for e in events.iter().filter(|e| e["zeno_fallback"] == false) {
        let named = match e["kind"].as_str().unwrap() {
            "stick_to_slip" => Some("slip"),
            "slip_to_stick" => Some("stick"),
            "lift_off" => Some("free"),
            _ => None,
        };
        assert!(named.is_none_or(|m| e["mode_after"] == m), "{e}");
    }
    let tj = json(&out_dir.join("trajectory.json"));
    let t: Vec<f64> = serde_json::from_value(tj["t"].clone()).unwrap();
    let mode: Vec<String> = serde_json::from_value(tj["mode"].clone()).unwrap();
    let d = tj["derived"].as_array().unwrap();
    let lambda_n = |i: usize| d[i]["lambda_n"].as_f64().unwrap_or(f64::NAN);
    let force = (0..t.len())
        .filter(|&i| mode[i] != "free")
        .map(|i| {
            let l: Vec<f64> = serde_json::from_value(d[i]["lambda"].clone()).unwrap();
            l.iter().map(|v| v * v).sum::<f64>().sqrt()
        })
        .fold(0.0, f64::max);
    let integrated = |i: usize| mode[i] != "free" && mode[i + 1] == mode[i] && t[i + 1] > t[i];
    let in_hold = |i: usize| holds.iter().any(|h| t[i] < h[1] && t[i + 1] > h[0]);
    let (mut begin, mut both, mut time) = (f64::INFINITY, f64::INFINITY, 0.0);
    for i in (0..t.len() - 1).filter(|&i| integrated(i)) {
        begin = begin.min(lambda_n(i));
        let l = if in_hold(i) {
            lambda_n(i).min(lambda_n(i + 1))
        } else {
            lambda_n(i)
        };
        both = both.min(l);
        if l < -1e-6 * force {
            time += t[i + 1] - t[i];
        }
    }
    assert!(
        both < begin,
        "the hold's end pulls harder: {both} against {begin}"
    );
    assert!(
        held.contains(&format!("λ_n down to {both:.3e} N"))
            && held.contains(&format!("for {time:.4} s")),
        "{held} against {both:.3e} N for {time:.4} s"
    );
    std::fs::remove_dir_all(&dir).unwrap();
}

/// `scenes/paper.toml` with both friction coefficients μ_s = μ_k = `mu`, written into `dir`.
fn friction_scene(dir: &Path, mu: &str) -> std::path::PathBuf {
    let text = std::fs::read_to_string(root().join("scenes/paper.toml"))
        .unwrap()
        .replace("mu_s = 0.8", &format!("mu_s = {mu}"))
        .replace("mu_k = 0.6", &format!("mu_k = {mu}"));
    assert!(
        text.contains(&format!("mu_k = {mu}")),
        "scenes/paper.toml's friction moved"
    );
    let scene = dir.join("friction.toml");
    std::fs::write(&scene, text).unwrap();
    scene
}

/// A slip with large friction ends where its slip speed reaches zero (eq. 37, Sect. 3.1), not in a
/// Painlevé error: an adaptive trial stage past the stop reverses Δv and with it t̂, which with
/// μ_k = 10 alone makes nᵀ W (n + μ_k t̂) negative (the run used to fail there, right after the
/// first impact). The adaptive run's stop agrees with fixed-step RK4 at 2 µs, whose `slip_stop`
/// guard finds it without stages beyond it, and the slip is over when its speed is nil.
#[test]
fn a_slip_with_large_friction_ends_at_its_stop() {
    let dir = tmpdir("mu10");
    let scene = friction_scene(&dir, "10.0");
    let stop = |extra: &[&str], name: &str| {
        let out_dir = dir.join(name);
        let mut args = vec!["--scene", scene.to_str().unwrap(), "--t-end", "0.56"];
        args.extend_from_slice(extra);
        let o = simulate_into(&out_dir, &args);
        let stderr = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(0), "{name}: {stderr}");
        let ev = json(&out_dir.join("events.json"));
        assert_eq!(event_kinds(&ev), ["impact", "slip_to_stick"], "{name}");
        let e = &ev["events"][1];
        (
            e["t"].as_f64().unwrap(),
            e["pre"]["slip_speed"].as_f64().unwrap(),
        )
    };
    let (t_adaptive, speed) = stop(&[], "dopri5");
    let (t_fixed, _) = stop(&["--integrator", "rk4", "--step", "2e-6"], "rk4");
    assert!(speed <= 1.01e-6, "slip speed {speed} at the stop");
    assert!(
        (t_adaptive - t_fixed).abs() <= 5e-6,
        "the slip stops at {t_adaptive} s (dopri5) against {t_fixed} s (RK4)"
    );
    std::fs::remove_dir_all(&dir).unwrap();
}

/// A run that fails at a state whose dynamics the model cannot evaluate (a Painlevé paradox of
/// a slip with μ = 10⁶, eq. 20) still writes what that state gives without accelerations: its
/// last sample has the distance h, the slip speed and the energy (recomputed here with the
/// paper's model), and `null` forces, where every field used to be `null`.
#[test]
fn a_failed_runs_last_sample_keeps_its_kinematics() {
    let dir = tmpdir("painleve");
    let scene = friction_scene(&dir, "1000000.0");
    let out_dir = dir.join("out");
    let o = simulate_into(
        &out_dir,
        &[
            "--scene",
            scene.to_str().unwrap(),
            "--impact-law",
            "stick",
            "--t-end",
            "1",
        ],
    );
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(1), "{stderr}");
    assert!(stderr.contains("Painlev"), "{stderr}");
    let tj = json(&out_dir.join("trajectory.json"));
    let x: Vec<Vec<f64>> = serde_json::from_value(tj["x"].clone()).unwrap();
    let last = tj["derived"].as_array().unwrap().last().unwrap().clone();
    assert!(last["lambda_n"].is_null(), "{last}");
    // h, Δv and the energy do not depend on the friction: the paper's model gives them.
    let model = Model::from_kernels(bf_model::PaperKernels::new()).unwrap();
    let s = State::<3>::from_slice(x.last().unwrap()).unwrap();
    let kin = model.evaluate(&s).unwrap();
    let e = model.energy(&s).unwrap();
    let close = |a: f64, b: f64| (a - b).abs() <= 1e-12 * (1.0 + b.abs());
    assert!(close(last["h"].as_f64().unwrap(), kin.contact.h), "{last}");
    assert!(close(last["energy"].as_f64().unwrap(), e.total), "{last}");
    assert!(
        close(
            last["slip_speed"].as_f64().unwrap(),
            kin.contact.delta_v.norm()
        ),
        "{last}"
    );
    std::fs::remove_dir_all(&dir).unwrap();
}
