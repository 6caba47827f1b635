//! Compiled contact kernels of a finger with another joint count than 3: `scenes/paper4.toml`
//! (4 joints) is compiled in, so the registry's slice wrappers and `CompiledKernels<4>` run.
//! They agree with bf-codegen's interpreter of the same graphs (`InterpretedKernels<4>`) at
//! random states, `optimize` verifies a 4-joint `reach` on them (which `track` refuses: it is
//! not periodic), and the hybrid controller executes a 4-joint `periodic-qc` plan (Newton's
//! law, its post-impact velocity the plant's) in closed loop where the open loop and the PD
//! lose it.

#[path = "common/cli.rs"]
mod cli_util;

use bf_codegen::Scene;
use bf_model::registry::{self, KernelSource};
use bf_model::{ContactVariant, InterpretedKernels, Kernels, State, Vec3, VecN};
use cli_util::{root, run, tmpdir};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

const PAPER4: &str = "scenes/paper4.toml";

fn paper4() -> Scene {
    Scene::load(root().join(PAPER4)).unwrap()
}

/// max |a − b| / (1 + |b|) over two flat lists.
fn rel(a: &[f64], b: &[f64]) -> f64 {
    assert_eq!(a.len(), b.len());
    a.iter()
        .zip(b)
        .map(|(x, y)| (x - y).abs() / (1.0 + y.abs()))
        .fold(0.0, f64::max)
}

#[test]
fn compiled_4_joint_kernels_agree_with_the_interpreter() {
    let scene = paper4();
    let (compiled, source) = registry::contact_kernels_n::<4>(&scene).unwrap();
    assert_eq!(source, KernelSource::Compiled);
    assert_eq!(compiled.scene_name(), "paper4");
    let interp = InterpretedKernels::<4>::for_scene(&scene).unwrap();
    // A changed link length is another scene: interpreted, never the compiled one.
    let mut other = scene.clone();
    other.links[3].a = 0.7;
    assert_eq!(
        registry::contact_kernels_n::<4>(&other).unwrap().1,
        KernelSource::Interpreted
    );
    // The wrong joint count is refused, not run on the 4-joint kernels.
    assert!(registry::contact_kernels_n::<3>(&scene).is_err());

    let mut rng = ChaCha8Rng::seed_from_u64(4);
    let mut worst: f64 = 0.0;
    for k in 0..200 {
        let q: [f64; 4] = std::array::from_fn(|_| rng.random_range(-3.0..3.0));
        let qd: [f64; 4] = std::array::from_fn(|_| rng.random_range(-3.0..3.0));
        let w: [f64; 3] = std::array::from_fn(|_| rng.random_range(-3.0..3.0));
        let x = State::<4>::new(VecN::<4>::from(q), VecN::<4>::from(qd), Vec3::from(w));
        let variant = if k % 2 == 0 {
            ContactVariant::Exact
        } else {
            ContactVariant::Smooth(0.01)
        };
        let a = compiled.evaluate(&x, variant);
        let b = interp.evaluate(&x, variant);
        let (ca, cb) = (&a.contact, &b.contact);
        let flat = |k: &bf_model::ContactKinematics<4>| -> Vec<f64> {
            let c = &k.contact;
            let mut v: Vec<f64> = k.m_f.iter().chain(k.cqd_g.iter()).copied().collect();
            v.push(k.potential);
            v.extend([c.alpha, c.sat_alpha, c.h, c.h_dot]);
            for u in [c.p_c, c.r_c, c.n, c.v_c, c.delta_v, c.rc_dot, c.jc_dot_qd] {
                v.extend(u.iter());
            }
            v.extend(c.j_c.iter());
            v
        };
        worst = worst.max(rel(&flat(&a), &flat(&b)));
        assert_eq!(ca.j_c.ncols(), 4);
        assert!(cb.h.is_finite());
    }
    assert!(worst < 1e-12, "largest relative difference {worst:e}");
}

#[test]
fn simulate_and_optimize_run_the_compiled_4_joint_scene() {
    let dir = tmpdir("paper4");
    let sim = dir.join("sim");
    let o = run(&[
        "simulate",
        "--scene",
        PAPER4,
        "--t-end",
        "0.5",
        "--out",
        sim.to_str().unwrap(),
    ]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{err}");
    assert!(err.contains("on the compiled kernels"), "{err}");
    let opt = dir.join("opt");
    let o = run(&[
        "optimize",
        "--problem",
        "reach",
        "--scene",
        PAPER4,
        "--out",
        opt.to_str().unwrap(),
    ]);
    let (out, err) = (
        String::from_utf8_lossy(&o.stdout),
        String::from_utf8_lossy(&o.stderr),
    );
    assert!(o.status.success(), "{out}\n{err}");
    let sol: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(opt.join("solution.json")).unwrap()).unwrap();
    assert_eq!(sol["status"], "Solved");
    assert_eq!(sol["scene"], "paper4");
    assert_eq!(sol["verification"]["verified"], true, "{out}");
    // `track` repeats periodic optima only: the reach plan is refused before any run, with
    // exit status 1 and no output set.
    let trk = dir.join("track");
    let o = run(&[
        "track",
        opt.join("solution.json").to_str().unwrap(),
        "--periods",
        "2",
        "--out",
        trk.to_str().unwrap(),
    ]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(1), "{err}");
    assert!(
        err.contains("`reach` is not a periodic problem") && err.contains("periodic-qc"),
        "{err}"
    );
    assert!(!trk.exists());
    std::fs::remove_dir_all(&dir).ok();
}

/// The largest and the last period's ω error of `track`'s `tracking.json` in `dir`, with the
/// periods completed.
fn tracking_errors(dir: &std::path::Path) -> (f64, f64, u64) {
    let v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("tracking.json")).unwrap()).unwrap();
    let errors: Vec<f64> = v["periods"]
        .as_array()
        .unwrap()
        .iter()
        .map(|p| p["omega_error"].as_f64().unwrap_or(f64::INFINITY))
        .collect();
    let max = errors.iter().copied().fold(0.0, f64::max);
    (
        max,
        errors.last().copied().unwrap_or(f64::NAN),
        v["completed_periods"].as_u64().unwrap(),
    )
}

/// `optimize --problem periodic-qc --scene SCENE` with `extra` options into `out`.
fn optimize_qc(scene: &str, out: &std::path::Path, extra: &[&str]) -> std::process::Output {
    let mut args = vec![
        "optimize",
        "--problem",
        "periodic-qc",
        "--scene",
        scene,
        "--out",
        out.to_str().unwrap(),
    ];
    args.extend_from_slice(extra);
    run(&args)
}

/// The closed loop on a finger with 4 joints (J_c is 3 × 4, the least constraint picks the
/// acceleration in its kernel): the default `periodic-qc` plan of `scenes/paper4.toml` is a
/// Newton plan (eq. 39 for a redundant finger, bf-problem's `points::impact`), whose
/// post-impact velocity is, within the plan's bound, the one bf-model's own Newton law gives
/// from the plan's pre-impact state (the least kinetic-energy change, solved numerically: an
/// independent implementation of the plan's lifted rows). Replayed on the default plant of
/// its own model and Newton's law, it is held within the 2 % of the 3-joint plans in every
/// period by the hybrid controller, while its optimal torques alone and the joint-space PD
/// leave it (the paper's Sect. 6.2 on another finger). A plant of another joint count, and a
/// finger with fewer than 3 joints, are refused with what the loop supports.
#[test]
fn the_hybrid_controller_executes_a_4_joint_plan() {
    use ball_finger::paper::closed_loop::solution_model;
    use ball_finger::pipeline::SolutionIo;
    use bf_model::ImpactLaw;
    use bf_problem::points::{NEWTON_APPROACH_SPEED, NEWTON_VELOCITY_LIMIT};
    let dir = tmpdir("paper4-track");
    let opt = dir.join("opt");
    let o = optimize_qc(PAPER4, &opt, &["--strategy", "direct"]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let sol = opt.join("solution.json");
    let plan = ball_finger::pipeline::OcpSolution::read_json(&sol).unwrap();
    assert_eq!(plan.impact_law, bf_problem::PlannedImpact::Newton);
    let nodes = &plan.nodes;
    let last = nodes.phase.iter().rposition(|&p| p == 0).unwrap();
    let first = nodes.phase.iter().position(|&p| p == 1).unwrap();
    let vec4 = |v: &[f64]| VecN::<4>::from_column_slice(v);
    let pre = State::new(
        vec4(&nodes.q[last]),
        vec4(&nodes.qd[last]),
        Vec3::from_column_slice(&nodes.omega[last]),
    );
    for i in 0..3 {
        assert!((nodes.omega[first][i] - nodes.omega[last][i]).abs() < 1e-7);
    }
    let (model, _) = solution_model::<4>(&plan).unwrap();
    let kin = model.evaluate(&pre).unwrap();
    let newton = model.impact(&pre, ImpactLaw::Newton).unwrap();
    let gap = (vec4(&nodes.qd[first]) - newton.qd).norm();
    // As for 3 joints (tests/newton_impact.rs): the plan's contact is the ε-smoothed one,
    // bf-model's the exact one, so the bounds hold up to that difference. A plan that ignored
    // Newton's law would be off by the order of ‖q̇⁻‖ itself.
    let allowance = NEWTON_VELOCITY_LIMIT * 1.5 + 1e-3 * pre.qd.norm();
    eprintln!(
        "ḣ⁻ = {}, ‖q̇⁺ − q̇_N‖ = {gap}, ‖q̇⁻‖ = {}",
        kin.contact.h_dot,
        pre.qd.norm()
    );
    assert!(
        gap <= allowance && pre.qd.norm() > 100.0 * allowance,
        "q̇⁺ {:?} vs the plant's {}: {gap} > {allowance} (‖q̇⁻‖ {})",
        nodes.qd[first],
        newton.qd,
        pre.qd.norm()
    );
    assert!(kin.contact.h_dot <= -NEWTON_APPROACH_SPEED * (1.0 - 1e-3));
    let track = |controller: &str, out: &str, extra: &[&str]| {
        let out = dir.join(out);
        let mut args = vec![
            "track",
            sol.to_str().unwrap(),
            "--periods",
            "5",
            "--controller",
            controller,
            "--out",
            out.to_str().unwrap(),
        ];
        args.extend_from_slice(extra);
        (run(&args), out)
    };
    let (o, out) = track("hybrid", "hybrid", &[]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{err}");
    assert!(!err.contains("planned with"), "{err}");
    let (max, _, completed) = tracking_errors(&out);
    assert_eq!(completed, 5);
    assert!(
        max <= 0.02,
        "hybrid: largest period error {:.3} %",
        100.0 * max
    );
    // Without feedback the 4-joint plan is lost as the 3-joint ones are: the open loop ends
    // early or far off, the PD in the free phases drifts off by its last period.
    let (_, out) = track("open-loop", "open", &[]);
    let (max_open, _, completed_open) = tracking_errors(&out);
    assert!(
        completed_open < 5 || max_open > 0.2,
        "open loop: {completed_open} periods, largest error {:.3} %",
        100.0 * max_open
    );
    let (_, out) = track("pd", "pd", &[]);
    let (_, last_pd, _) = tracking_errors(&out);
    assert!(
        last_pd > 10.0 * max,
        "PD: last period {:.3} % against the hybrid's largest {:.3} %",
        100.0 * last_pd,
        100.0 * max
    );
    let v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("hybrid/tracking.json")).unwrap())
            .unwrap();
    assert_eq!(v["plan_verified"], true);
    // The run ends at the impact that completes its last period, not at the horizon's margin.
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("hybrid/summary.json")).unwrap())
            .unwrap();
    let last_end = v["periods"][4]["end"].as_f64().unwrap();
    assert_eq!(summary["t_final"].as_f64().unwrap(), last_end);
    // The plant must be a finger of the plan's joint count, and of at least 3 joints.
    for (scene, expected) in [
        (
            "scenes/paper.toml",
            "it has 3 joints where the plan's finger has 4",
        ),
        ("tests/fixtures/finger2.toml", "fingers of 3 to 7 joints"),
    ] {
        let plant = root().join(scene);
        let (o, out) = track(
            "hybrid",
            "refused",
            &["--plant-scene", plant.to_str().unwrap()],
        );
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(1), "{err}");
        assert!(err.contains(expected), "{scene}: {err}");
        assert!(!out.exists());
    }
    std::fs::remove_dir_all(&dir).ok();
}

/// A finger of the user's own (a scene file that is not compiled in: `scenes/paper4.toml`
/// renamed) is tracked on interpreted kernels, the free law's inverse dynamics formed from the
/// model (no generated kernel), as closely as the compiled one; a plan that failed its own
/// verification is tracked with a warning and recorded as such.
#[test]
fn a_finger_of_the_user_s_own_is_tracked_on_interpreted_kernels() {
    let dir = tmpdir("own-finger-track");
    let text = std::fs::read_to_string(root().join(PAPER4)).unwrap();
    let own = dir.join("my_finger4.toml");
    std::fs::write(
        &own,
        text.replace("name = \"paper4\"", "name = \"my_finger4\""),
    )
    .unwrap();
    let opt = dir.join("opt");
    let o = optimize_qc(
        own.to_str().unwrap(),
        &opt,
        &["--strategy", "direct", "--impact-law", "stick"],
    );
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let out = dir.join("track");
    let o = run(&[
        "track",
        opt.join("solution.json").to_str().unwrap(),
        "--periods",
        "4",
        "--impact-law",
        "stick",
        "--out",
        out.to_str().unwrap(),
    ]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{err}");
    assert!(!err.contains("failed its own verification"), "{err}");
    let (max, _, completed) = tracking_errors(&out);
    assert_eq!(completed, 4);
    assert!(max <= 0.02, "largest period error {:.3} %", 100.0 * max);
    // The same plan marked unverified: tracked, warned about, recorded.
    let sol = opt.join("solution.json");
    let mut v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&sol).unwrap()).unwrap();
    v["verification"]["verified"] = serde_json::Value::Bool(false);
    v["verification"]["defect"] = serde_json::json!(1.0);
    v["verification"]["max_defect"] = serde_json::json!(1.0);
    let unverified_dir = dir.join("unverified");
    std::fs::create_dir_all(&unverified_dir).unwrap();
    let unverified = unverified_dir.join("solution.json");
    std::fs::write(&unverified, serde_json::to_vec(&v).unwrap()).unwrap();
    std::fs::copy(
        opt.join("solution-internals.json"),
        unverified_dir.join("solution-internals.json"),
    )
    .unwrap();
    // `track` of the edited plan for `periods`: its stderr and its tracking.json.
    let track_edited = |periods: &str, tag: &str| {
        let out = dir.join(tag);
        let o = run(&[
            "track",
            unverified.to_str().unwrap(),
            "--periods",
            periods,
            "--impact-law",
            "stick",
            "--out",
            out.to_str().unwrap(),
        ]);
        let t: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(out.join("tracking.json")).unwrap())
                .unwrap();
        (String::from_utf8_lossy(&o.stderr).into_owned(), t)
    };
    let (err, t) = track_edited("2", "track-unverified");
    assert!(err.contains("failed its own verification"), "{err}");
    assert_eq!(t["plan_verified"], false);
    assert_eq!(t["plan_status"], "Solved");
    // The same plan as the end of a solve that did not converge: its re-integration passes,
    // but it is no optimum, and the run says so (it used to say nothing).
    let mut v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&sol).unwrap()).unwrap();
    v["status"] = serde_json::json!("MaxIterations");
    std::fs::write(&unverified, serde_json::to_vec(&v).unwrap()).unwrap();
    let (err, t) = track_edited("1", "track-unconverged");
    assert!(
        err.contains("ended MaxIterations") && err.contains("not an optimum"),
        "{err}"
    );
    assert!(!err.contains("failed its own verification"), "{err}");
    assert_eq!(
        (&t["plan_verified"], &t["plan_status"]),
        (
            &serde_json::json!(true),
            &serde_json::json!("MaxIterations")
        )
    );
    std::fs::remove_dir_all(&dir).ok();
}

/// `periodic-qc` on the 4-joint finger with the 32-start search (`--hops 0`; the global search
/// would take several times longer on interpreted kernels): Solved and verified (about a minute
/// of CPU on interpreted node kernels, several on a loaded machine).
#[test]
#[ignore = "slow: about a minute of CPU on interpreted node kernels"]
fn cli_periodic_qc_on_the_4_joint_finger() {
    let dir = tmpdir("qc4");
    let out = dir.join("out");
    let o = optimize_qc(PAPER4, &out, &["--hops", "0"]);
    let stdout = String::from_utf8_lossy(&o.stdout);
    assert!(o.status.success(), "{stdout}");
    let sol: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("solution.json")).unwrap()).unwrap();
    assert_eq!(sol["status"], "Solved");
    assert_eq!(sol["verification"]["verified"], true, "{stdout}");
    assert_eq!(sol["modes"], serde_json::json!(["free", "stick", "free"]));
    // The ball turns about z (ω_ref = (0, 0, 2.2)), and the optimum is not the 3-joint
    // finger's (J = 0.0877).
    assert!(
        sol["mean_omega"]["omega_z"].as_f64().unwrap() > 1.0,
        "{}",
        sol["mean_omega"]
    );
    let j = sol["objective"].as_f64().unwrap();
    assert!(j.is_finite() && (j - 0.08773464).abs() > 1e-3, "{j}");
    // |τ_i| ≤ 1 N m at the nodes.
    let nodes = sol["nodes"].as_object().unwrap();
    for i in 1..=4 {
        let col = nodes[&format!("tau{i}")].as_array().unwrap();
        assert!(col.iter().all(|t| t.as_f64().unwrap().abs() <= 1.0 + 1e-8));
    }
    std::fs::remove_dir_all(&dir).ok();
}
