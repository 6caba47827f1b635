//! URDF robots end to end through the CLI, checked against physics: `simulate` of a URDF arm
//! conserves energy (unactuated, no friction: any inconsistency between the imported M and its
//! C q̇ would show as drift); `optimize --problem reach-arm --scene arm.urdf` brings the arm to
//! rest at the target within the URDF's effort limits, verified by re-integration; a TOML scene
//! that takes a 3-joint finger from a URDF and adds a ball simulates the finger striking the
//! ball (an impact on the surface that reverses the approach velocity); and a branched URDF
//! without `--tip` is refused naming the file, line and link.

#[path = "common/cli.rs"]
mod cli_util;
use cli_util::{run, tmpdir};
use std::path::Path;

const URDF: &str = "testkit/tests/urdf";

fn json(path: &Path) -> serde_json::Value {
    serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap()
}

/// The last row of a CSV file of numbers.
fn last_row(path: &Path) -> Vec<f64> {
    let text = std::fs::read_to_string(path).unwrap();
    let line = text.lines().last().unwrap();
    line.split(',').map(|x| x.parse().unwrap()).collect()
}

fn ok(o: &std::process::Output) -> String {
    let (out, err) = (
        String::from_utf8_lossy(&o.stdout),
        String::from_utf8_lossy(&o.stderr),
    );
    assert!(o.status.success(), "{out}\n{err}");
    format!("{out}{err}")
}

#[test]
fn simulate_a_urdf_arm_conserves_its_energy() {
    let dir = tmpdir("urdf-sim");
    let out = dir.join("sim");
    // The SCARA chain: revolute, revolute, prismatic (vertical quill) and continuous joints.
    let o = run(&[
        "simulate",
        "--scene",
        &format!("{URDF}/scara_continuous.urdf"),
        "--q0",
        "0.3,-0.5,0.05,1",
        "--qd0",
        "1,-2,0.3,2",
        "--t-end",
        "1",
        "--out",
        out.to_str().unwrap(),
    ]);
    let text = ok(&o);
    assert!(text.contains("scara_continuous"), "{text}");
    let s = json(&out.join("summary.json"));
    let (e0, e1) = (
        s["energy_initial"].as_f64().unwrap(),
        s["energy_final"].as_f64().unwrap(),
    );
    assert_eq!(s["work"].as_f64(), Some(0.0), "unactuated, no friction");
    assert!((e1 - e0).abs() < 1e-7 * e0.abs(), "{e0} -> {e1}");
    // The arm moved (the quill fell: gravity along −z drives the prismatic joint).
    let last = last_row(&out.join("trajectory.csv"));
    assert!((last[3] - 0.05).abs() > 0.1, "quill at {}", last[3]);
}

#[test]
fn optimize_reach_arm_on_a_urdf_reaches_the_target_within_its_effort_limits() {
    let dir = tmpdir("urdf-reach");
    let out = dir.join("opt");
    let o = run(&[
        "optimize",
        "--problem",
        "reach-arm",
        "--scene",
        &format!("{URDF}/planar2.urdf"),
        "--target",
        "0.3,0.2",
        "--out",
        out.to_str().unwrap(),
    ]);
    ok(&o);
    assert!(!out.join("FAILED").exists());
    let sol = json(&out.join("solution.json"));
    assert_eq!(sol["scene"], "planar2");
    // The URDF's <limit effort> became the torque bounds.
    assert_eq!(sol["tau_max"], serde_json::json!([50.0, 30.0]));
    let v = &sol["verification"];
    assert!(v["failure"].is_null(), "{v}");
    assert!(v["max_defect"].as_f64().unwrap() <= 1e-4, "{v}");
    // The recorded scene text stands alone (the URDF chain written out) and parses again.
    let text = sol["scene_toml"].as_str().unwrap();
    let scene = bf_codegen::Scene::from_toml_str(text, "solution").unwrap();
    assert_eq!(scene.nq(), 2);
    // The last state of the trajectory: at the target, at rest.
    let last = last_row(&out.join("trajectory.csv"));
    let (q, qd) = (&last[1..3], &last[3..5]);
    assert!(
        (q[0] - 0.3).abs() < 1e-6 && (q[1] - 0.2).abs() < 1e-6,
        "{last:?}"
    );
    assert!(qd.iter().all(|v| v.abs() < 1e-6), "{last:?}");
}

#[test]
fn a_urdf_finger_with_a_ball_strikes_it() {
    let dir = tmpdir("urdf-finger-ball");
    let out = dir.join("sim");
    let o = run(&[
        "simulate",
        "--scene",
        &format!("{URDF}/finger3_ball.toml"),
        "--q0",
        "0,1.2,0",
        "--t-end",
        "1",
        "--out",
        out.to_str().unwrap(),
    ]);
    ok(&o);
    let s = json(&out.join("summary.json"));
    let e0 = s["energy_initial"].as_f64().unwrap();
    assert!(s["energy_error"].as_f64().unwrap() < 1e-3 * e0.abs(), "{s}");
    let events = json(&out.join("events.json"));
    let list = events["events"].as_array().unwrap();
    let impact = list
        .iter()
        .find(|e| e["kind"] == "impact")
        .unwrap_or_else(|| panic!("no impact: {events}"));
    // On the ball's surface, approaching before, not approaching after.
    let (pre, post) = (&impact["pre"], &impact["post"]);
    assert!(pre["h"].as_f64().unwrap().abs() < 1e-9, "{impact}");
    assert!(pre["normal_velocity"].as_f64().unwrap() < -0.1, "{impact}");
    assert!(
        post["normal_velocity"].as_f64().unwrap() >= -1e-9,
        "{impact}"
    );
}

#[test]
fn a_branched_urdf_needs_a_tip() {
    let o = run(&[
        "eval",
        &format!("{URDF}/panda_like.urdf"),
        "--q",
        "0,0,0,0,0,0,0",
        "--qd",
        "0,0,0,0,0,0,0",
    ]);
    assert!(!o.status.success());
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        err.contains("panda_like.urdf:") && err.contains("branches at link \"panda_hand\""),
        "{err}"
    );
    let o = run(&[
        "eval",
        &format!("{URDF}/panda_like.urdf"),
        "--tip",
        "panda_hand",
        "--q",
        "0,0,0,0,0,0,0",
        "--qd",
        "0,0,0,0,0,0,0",
    ]);
    ok(&o);
}
