//! The ball problems of `optimize` on fingers other than the paper's: the 4-joint finger of
//! `tests/fixtures/finger4.toml` (interpreted kernels), and 3-joint fingers of other
//! proportions or with joint limits. Guess configurations that do not fit a finger are solved
//! for on its own geometry (checked against bf-model's h); `reach` on the 4-joint finger ends
//! Solved and verified by re-integration with the torque bounds, the touch and the rest
//! conditions holding on bf-model's kernels, a different optimum than the 3-joint finger's,
//! and corrupted torques failing the verification; the scene's joint limits bound the joint
//! angles of the problems; a finger that cannot reach the ball and one with more joints than
//! the verification runs are refused with errors naming them.

#[path = "common/cli.rs"]
mod cli_util;

use ball_finger::pipeline::verify::{VERIFIED_DEFECT, verify};
use ball_finger::pipeline::{build, solve};
use bf_codegen::Scene;
use bf_model::{Model, State, Vec3, VecN, registry};
use bf_optim::ipm::Status;
use bf_optim::ocp::Scheme;
use bf_problem::catalogue::{Q_DEEP, Q_GUESS, guess_configurations};
use bf_problem::{BuiltProblem, OcpSolution, Problem, ProblemSettings};
use cli_util::{root, run, tmpdir};
use std::sync::OnceLock;

const FINGER4: &str = "tests/fixtures/finger4.toml";

fn scene_text(path: &str) -> String {
    std::fs::read_to_string(root().join(path)).unwrap()
}

fn scene(text: &str, label: &str) -> Scene {
    Scene::from_toml_str(text, label).unwrap()
}

/// h (eq. 4) of the `N`-joint finger of `scene` at rest at `q`, on bf-model's kernels with the
/// smooth contact of the scene's ε (what the problems use).
fn h_model<const N: usize>(scene: &Scene, q: &[f64]) -> f64 {
    let (k, _) = registry::contact_kernels_n::<N>(scene).unwrap();
    let eps = scene.contact.as_ref().unwrap().smooth_eps;
    let m = Model::from_kernels(k)
        .unwrap()
        .with_contact_variant(bf_model::ContactVariant::Smooth(eps))
        .unwrap();
    let x = State::<N>::new(
        VecN::<N>::from_column_slice(q),
        VecN::<N>::zeros(),
        Vec3::zeros(),
    );
    m.evaluate(&x).unwrap().contact.h
}

#[test]
fn guess_configurations_are_the_papers_for_3_joints_and_solved_for_4() {
    let paper = scene(&scene_text("scenes/paper.toml"), "paper");
    let c3 = guess_configurations(&paper, 0.01).unwrap();
    assert_eq!(c3.free, Q_GUESS.to_vec());
    assert_eq!(c3.deep, Q_DEEP.to_vec());

    let f4 = scene(&scene_text(FINGER4), FINGER4);
    let c4 = guess_configurations(&f4, 0.01).unwrap();
    assert_eq!((c4.free.len(), c4.deep.len()), (4, 4));
    // The curl family: the first joint at the paper's q1, the others bent alike.
    for q in [&c4.free, &c4.deep] {
        assert_eq!(q[0], Q_GUESS[0]);
        assert!(q[1..].iter().all(|v| *v == q[1]), "{q:?}");
    }
    // q⁰ is halfway (in c) to the contact, clear of the ball; the deep one presses into it.
    let h_free = h_model::<4>(&f4, &c4.free);
    let h_deep = h_model::<4>(&f4, &c4.deep);
    assert!(h_free > 0.05, "h(q0) = {h_free}");
    assert!(h_deep < 0.0, "h(q_deep) = {h_deep}");
    // The contact configuration at twice q⁰'s curl touches the ball.
    let mut qc = c4.free.clone();
    for v in &mut qc[1..] {
        *v *= 2.0;
    }
    let h_c = h_model::<4>(&f4, &qc);
    assert!(h_c.abs() < 1e-9, "h(q_c) = {h_c}");
}

/// The TriFinger-like fixture: 3 joints with URDF limits, 16 cm links over a 5 cm ball.
const FINGER3_URDF: &str = "testkit/tests/urdf/finger3_ball.toml";

#[test]
fn a_3_joint_finger_the_papers_configurations_do_not_fit_gets_its_own() {
    let f3 = Scene::load(root().join(FINGER3_URDF)).unwrap();
    // The paper's pressed-in configuration does not reach this finger's ball, so the segment
    // from q⁰ to it holds no contact configuration.
    assert!(h_model::<3>(&f3, &Q_DEEP) > 0.0);
    let c = guess_configurations(&f3, f3.contact.as_ref().unwrap().smooth_eps).unwrap();
    assert_ne!(c.free, Q_GUESS.to_vec());
    let limits: Vec<(f64, f64)> = f3
        .links
        .iter()
        .map(|l| (l.q_min.unwrap(), l.q_max.unwrap()))
        .collect();
    for q in [&c.free, &c.deep] {
        assert_eq!(q.len(), 3);
        for (v, (lo, hi)) in q.iter().zip(&limits) {
            assert!((*lo..=*hi).contains(v), "{q:?} outside {limits:?}");
        }
    }
    let (h_free, h_deep) = (h_model::<3>(&f3, &c.free), h_model::<3>(&f3, &c.deep));
    let r = f3.ball.as_ref().unwrap().radius;
    assert!(h_free > 0.0 && h_free < r, "h(q0) = {h_free}");
    assert!(h_deep < 0.0, "h(q_deep) = {h_deep}");
}

#[test]
fn the_scenes_joint_limits_bound_every_finger_problem() {
    // The paper's `reach` overshoots q3 = 1.62 on its way to the ball (to about 1.71 rad) and
    // ends below it (about 1.55 rad); with q3 ≤ 1.62 the optimum keeps to the limit and costs
    // more.
    let paper = build(Problem::Reach, &ProblemSettings::default()).unwrap();
    let free = solve(&paper, None).unwrap();
    assert_eq!(free.status, Status::Solved);
    let peak = |sol: &OcpSolution| sol.raw[0].x.iter().map(|x| x[2]).fold(f64::MIN, f64::max);
    const Q3_MAX: f64 = 1.62;
    assert!(peak(&free) > Q3_MAX + 0.05, "{}", peak(&free));

    let mut limited = scene(&scene_text("scenes/paper.toml"), "paper-q3-limit");
    limited.links[2].q_max = Some(Q3_MAX);
    // The paper's guess configurations are within the limit, so the guess is the paper's.
    assert_eq!(guess_configurations(&limited, 0.01).unwrap().free, Q_GUESS);
    let s = ProblemSettings {
        scene: Some(limited),
        ..ProblemSettings::default()
    };
    let p = build(Problem::Reach, &s).unwrap();
    // The limits are the states' bounds in every phase; the unlimited joints stay free.
    for ph in &p.ocp.phases {
        assert_eq!(ph.x_bounds[2], (f64::NEG_INFINITY, Q3_MAX));
        assert_eq!(ph.x_bounds[1], (f64::NEG_INFINITY, f64::INFINITY));
    }
    let sol = solve(&p, None).unwrap();
    assert_eq!(sol.status, Status::Solved, "{:?}", sol.stages);
    assert!(peak(&sol) <= Q3_MAX + 1e-8, "{}", peak(&sol));
    assert!(
        peak(&sol) > Q3_MAX - 1e-6,
        "the limit is active: {}",
        peak(&sol)
    );
    assert!(
        sol.objective > free.objective,
        "{} {}",
        sol.objective,
        free.objective
    );
}

/// `reach` on the 4-joint finger, solved once for the tests below by one direct solve on 6
/// Radau elements (twice the default's: on the default mesh the direct solve's element-wise
/// defect is 3.6e-4, and `optimize` refines it).
fn reach4() -> &'static (BuiltProblem, OcpSolution) {
    static CELL: OnceLock<(BuiltProblem, OcpSolution)> = OnceLock::new();
    CELL.get_or_init(|| {
        let s = ProblemSettings {
            scene: Some(scene(&scene_text(FINGER4), FINGER4)),
            scheme: Scheme::Radau { elements: 6 },
            points: 60,
            ..ProblemSettings::default()
        };
        let p = build(Problem::Reach, &s).unwrap();
        let sol = solve(&p, None).unwrap();
        (p, sol)
    })
}

#[test]
fn reach_on_a_4_joint_finger_solves_and_verifies() {
    let (p, sol) = reach4();
    assert_eq!(sol.status, Status::Solved, "{:?}", sol.stages);
    assert_eq!(p.physics.nq, 4);
    let tr = &sol.raw[0];
    assert!(tr.x.iter().all(|x| x.len() == 2 * 4 + 3));
    // From rest at q⁰ ...
    let x0 = &tr.x[0];
    for i in 0..4 {
        assert!((x0[i] - p.guess.free[i]).abs() < 1e-9, "{x0:?}");
        assert!(x0[4 + i].abs() < 1e-9, "{x0:?}");
    }
    // ... to touching the ball at rest, on bf-model's kernels.
    let xf = tr.x.last().unwrap();
    let h = h_model::<4>(&p.scene, &xf[..4]);
    assert!((-1e-8..=1e-4 + 1e-8).contains(&h), "h(tf) = {h}");
    assert!(xf[4..8].iter().all(|v| v.abs() < 1e-8), "{xf:?}");
    // |τ_i| ≤ τ_max at every node, and the torques are not trivially small.
    let tau_max = p.physics.tau_max.clone();
    assert_eq!(tau_max, vec![1.0; 4]);
    let mut peak: f64 = 0.0;
    for u in &tr.u {
        assert_eq!(u.len(), 4);
        for (ui, m) in u.iter().zip(&tau_max) {
            assert!(ui.abs() <= m * (1.0 + 1e-8), "{u:?}");
            peak = peak.max(ui.abs());
        }
    }
    assert!(peak > 1e-3, "{peak}");

    // The re-integration of every element reproduces the collocated states.
    let v = verify(p, sol, 1e-10).unwrap();
    assert!(v.verified, "{v}");
    assert!(v.max_defect <= VERIFIED_DEFECT);
    assert!(v.max_node_residual < 1e-6, "{}", v.max_node_residual);
    let ph = &v.phases[0];
    assert!(ph.min_h.unwrap() > -1e-6, "{ph:?}");
    assert!(ph.max_torque_overshoot < 1e-3, "{ph:?}");

    // Other torques do not produce these states: 80 % of them fail the verification.
    let mut scaled = sol.clone();
    for u in scaled.raw[0].u.iter_mut().flatten() {
        *u *= 0.8;
    }
    let vs = verify(p, &scaled, 1e-10).unwrap();
    assert!(!vs.verified && vs.max_defect > 1e3 * v.max_defect, "{vs}");
}

#[test]
fn reach_on_a_4_joint_finger_differs_from_the_3_joint_optimum() {
    let (_, sol4) = reach4();
    let p3 = build(Problem::Reach, &ProblemSettings::default()).unwrap();
    let sol3 = solve(&p3, None).unwrap();
    assert_eq!(sol3.status, Status::Solved);
    assert_eq!(sol3.raw[0].u[0].len(), 3);
    let (j3, j4) = (sol3.objective, sol4.objective);
    assert!(j3.is_finite() && j4.is_finite());
    assert!((j3 - j4).abs() > 1e-3 * j3, "J3 = {j3}, J4 = {j4}");
}

fn json(path: &std::path::Path) -> serde_json::Value {
    serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap()
}

/// `optimize --problem NAME --scene finger4.toml`: Solved, verified, interpreted kernels, four
/// joints in the output, |τ| within the scene's bound.
fn optimize_finger4(problem: &str, tag: &str) -> serde_json::Value {
    let dir = tmpdir(tag);
    let out = dir.join("out");
    let o = run(&[
        "optimize",
        "--problem",
        problem,
        "--scene",
        FINGER4,
        "--out",
        out.to_str().unwrap(),
    ]);
    let (stdout, stderr) = (
        String::from_utf8_lossy(&o.stdout),
        String::from_utf8_lossy(&o.stderr),
    );
    assert!(o.status.success(), "stdout:\n{stdout}\nstderr:\n{stderr}");
    assert!(!out.join("FAILED").exists());
    let sol = json(&out.join("solution.json"));
    assert_eq!(sol["status"], "Solved", "{stdout}");
    assert_eq!(sol["scene"], "finger4");
    assert_eq!(sol["kernels"], "interpreted");
    let v = &sol["verification"];
    assert_eq!(v["verified"], true, "{stdout}");
    assert!(v["max_defect"].as_f64().unwrap() <= VERIFIED_DEFECT);
    let names: Vec<&str> = sol["state_names"]
        .as_array()
        .unwrap()
        .iter()
        .map(|v| v.as_str().unwrap())
        .collect();
    assert_eq!(names.len(), 11);
    assert_eq!(&names[..4], ["q1", "q2", "q3", "q4"]);
    let nodes = sol["nodes"].as_object().unwrap();
    for i in 1..=4 {
        let col = nodes[&format!("tau{i}")].as_array().unwrap();
        assert!(col.iter().all(|t| t.as_f64().unwrap().abs() <= 1.0 + 1e-8));
    }
    assert!(!nodes.contains_key("tau5"));
    std::fs::remove_dir_all(&dir).ok();
    sol
}

#[test]
fn cli_reach_on_a_4_joint_finger() {
    optimize_finger4("reach", "reach4");
}

#[test]
fn fingers_the_problems_cannot_use_are_refused_by_name() {
    let dir = tmpdir("refused");
    let text = scene_text(FINGER4);
    // Eight joints: beyond what the verification re-integrates.
    let (a, b) = (
        text.find("[[links]]").unwrap(),
        text.find("[ball]").unwrap(),
    );
    let eight = format!("{}{}{}{}", &text[..a], &text[a..b], &text[a..b], &text[b..]);
    let eight_path = dir.join("finger8.toml");
    std::fs::write(&eight_path, eight).unwrap();
    // A ball out of reach: no contact configuration for the guess.
    let far = text.replace("center = [0.0, 0.0, 0.0]", "center = [-20.0, 0.0, 0.0]");
    assert_ne!(far, text);
    let far_path = dir.join("far.toml");
    std::fs::write(&far_path, far).unwrap();
    let out = dir.join("out");
    for (path, mention) in [
        (&eight_path, vec!["finger8.toml", "8", "1 to 7 joints"]),
        (
            &far_path,
            vec!["finger4", "4 joints", "no contact configuration"],
        ),
    ] {
        let o = run(&[
            "optimize",
            "--problem",
            "reach",
            "--scene",
            path.to_str().unwrap(),
            "--out",
            out.to_str().unwrap(),
        ]);
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(!o.status.success(), "{err}");
        for m in mention {
            assert!(err.contains(m), "`{m}` not in:\n{err}");
        }
        assert!(!err.contains("panicked"), "{err}");
    }
    std::fs::remove_dir_all(&dir).ok();
}
