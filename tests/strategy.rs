//! Solve strategies (`ball_finger::pipeline::strategy`): the default continuation must find a
//! clearly better optimum of `periodic-qc` than the plain cold start, and one that survives
//! re-integration; multi-start must be deterministic and never worse than its start 0 (the
//! cold start); exact warm starts must restart at the optimum; bad strategy inputs are errors.

#[path = "common/cli.rs"]
mod cli_util;

use ball_finger::pipeline::strategy::{
    START_NEIGHBOURHOOD, Strategy, random_start, solve_with_strategy, start_intervals,
};
use ball_finger::pipeline::verify::verify;
use ball_finger::pipeline::{SolutionIo, build, solve, solve_warm};
use bf_codegen::spec::JointType;
use bf_optim::ipm::Status;
use bf_problem::catalogue::Q_GUESS;
use bf_problem::{OcpSolution, Problem, ProblemSettings, StartGuess};

#[test]
fn default_strategy_beats_cold_start_on_periodic_qc_and_verifies() {
    let s = ProblemSettings::default();
    let (_, direct) = solve_with_strategy(Problem::PeriodicQc, &s, Strategy::Direct, None).unwrap();
    assert!(direct.status.is_success());
    let (p, cont) =
        solve_with_strategy(Problem::PeriodicQc, &s, Strategy::default(), None).unwrap();
    assert_eq!(Strategy::default(), Strategy::Continuation);
    assert!(cont.status.is_success(), "{:?}", cont.strategy);
    let rep = cont.strategy.as_ref().unwrap();
    println!("{}", rep.table());
    // "A clear margin": at least 20 % lower cost of quadratic tracking error and effort.
    assert!(
        cont.objective < 0.8 * direct.objective,
        "continuation {} vs cold start {}",
        cont.objective,
        direct.objective
    );
    // The kept solution is of the target problem: the user's ε and a free period.
    assert_eq!(cont.epsilon, direct.epsilon);
    assert_eq!(p.settings.period_bounds, Some((0.0, f64::MAX)));
    let k = rep.chosen.unwrap();
    let last = rep.records.iter().rfind(|r| r.chain == k).unwrap();
    assert_eq!(last.objective, cont.objective);
    assert_eq!(
        rep.iterations,
        rep.records.iter().map(|r| r.iterations).sum::<usize>()
    );
    // The optimum survives re-integration with the optimal torques.
    let v = verify(&p, &cont, 1e-10).unwrap();
    println!("{}", v.summary());
    assert!(v.completed());
    assert!(v.max_defect < 1e-3, "defect {}", v.max_defect);
}

#[test]
fn multistart_is_deterministic_and_never_worse_than_its_default_start() {
    let s = ProblemSettings::default();
    let st = Strategy::Multistart {
        starts: 3,
        seed: 11,
    };
    let (_, a) = solve_with_strategy(Problem::PeriodicQc, &s, st, None).unwrap();
    let (_, b) = solve_with_strategy(Problem::PeriodicQc, &s, st, None).unwrap();
    // Parallel solves, same answer to the bit (no shared state, ordered reduction).
    assert_eq!(a.objective.to_bits(), b.objective.to_bits());
    let ra = a.strategy.as_ref().unwrap();
    assert_eq!(ra.records.len(), 3);
    assert_eq!(
        ra.records.iter().map(|r| r.chain).collect::<Vec<_>>(),
        [0, 1, 2]
    );
    let direct = solve(&build(Problem::PeriodicQc, &s).unwrap(), None).unwrap();
    // Start 0 is the cold start itself.
    assert!((ra.records[0].objective - direct.objective).abs() < 1e-9 * direct.objective);
    let best_ok = ra
        .records
        .iter()
        .filter(|r| r.status.is_success())
        .map(|r| r.objective)
        .fold(f64::INFINITY, f64::min);
    assert_eq!(a.objective, best_ok);
    assert!(a.objective <= direct.objective * (1.0 + 1e-9));
}

#[test]
fn random_starts_are_reproducible_and_within_their_ranges() {
    let p = build(Problem::PeriodicQc, &ProblemSettings::default()).unwrap();
    let wide = start_intervals(&p.scene, &Q_GUESS);
    let d = random_start(0, 5, &Q_GUESS, Some(&wide), 3);
    assert_eq!(d.q, Q_GUESS.to_vec());
    assert_eq!(d.durations, vec![1.0; 3]);
    let a = random_start(4, 5, &Q_GUESS, Some(&wide), 3);
    assert_eq!(a, random_start(4, 5, &Q_GUESS, Some(&wide), 3));
    assert_ne!(a, random_start(4, 6, &Q_GUESS, Some(&wide), 3));
    assert_ne!(a, random_start(5, 5, &Q_GUESS, Some(&wide), 3));
    // The paper's finger has three revolute joints without limits: each start angle anywhere
    // in the joint's revolution around q⁰, and 200 starts cover each revolution.
    let pi = std::f64::consts::PI;
    let mut lo = [f64::INFINITY; 3];
    let mut hi = [f64::NEG_INFINITY; 3];
    let narrow = vec![(-0.1, 0.1); 3];
    for k in 1..200 {
        let g = random_start(k, 1, &Q_GUESS, Some(&wide), 3);
        for (i, (q, q0)) in g.q.iter().zip(Q_GUESS).enumerate() {
            assert!((q - q0).abs() <= pi, "joint {i}: {q}");
            lo[i] = lo[i].min(q - q0);
            hi[i] = hi[i].max(q - q0);
        }
        for t in &g.durations {
            assert!((0.05..1.6).contains(t), "{t}");
        }
        // The intervals move the joints only, never the durations.
        let n = random_start(k, 1, &Q_GUESS, Some(&narrow), 3);
        assert_eq!(n.durations, g.durations);
        assert!(n.q.iter().all(|q| (-0.1..=0.1).contains(q)), "{:?}", n.q);
        // Without intervals (the plain multi-start): near the default guess.
        let near = random_start(k, 1, &Q_GUESS, None, 3);
        assert_eq!(near.durations, g.durations);
        for (q, q0) in near.q.iter().zip(Q_GUESS) {
            assert!((q - q0).abs() <= START_NEIGHBOURHOOD, "{:?}", near.q);
        }
    }
    for i in 0..3 {
        assert!(
            lo[i] < -0.9 * pi && hi[i] > 0.9 * pi,
            "joint {i}: {}..{}",
            lo[i],
            hi[i]
        );
    }
}

#[test]
fn start_intervals_keep_to_the_joint_limits_and_joint_kinds() {
    let mut scene = build(Problem::PeriodicQc, &ProblemSettings::default())
        .unwrap()
        .scene;
    let pi = std::f64::consts::PI;
    let q0 = [0.1, 0.6, 0.9];
    let whole = start_intervals(&scene, &q0);
    for (&(lo, hi), q) in whole.iter().zip(q0) {
        assert_eq!((lo, hi), (q - pi, q + pi));
    }
    // A lower limit inside the revolution cuts it; a prismatic joint keeps its neighbourhood
    // in metres; limits that leave no room around q⁰ leave q⁰ alone.
    scene.links[0].q_min = Some(-0.5);
    scene.links[1].joint = JointType::Prismatic;
    scene.links[2].q_min = Some(2.0);
    scene.links[2].q_max = Some(1.0);
    let cut = start_intervals(&scene, &q0);
    assert_eq!(cut[0], (-0.5, 0.1 + pi));
    assert_eq!(
        cut[1],
        (0.6 - START_NEIGHBOURHOOD, 0.6 + START_NEIGHBOURHOOD)
    );
    assert_eq!(cut[2], (0.9, 0.9));
    for k in 1..50 {
        let g = random_start(k, 3, &q0, Some(&cut), 3);
        assert!((-0.5..=0.1 + pi).contains(&g.q[0]), "{:?}", g.q);
        assert!((g.q[1] - 0.6).abs() <= START_NEIGHBOURHOOD, "{:?}", g.q);
        assert_eq!(g.q[2], 0.9);
    }
}

#[test]
fn exact_warm_start_restarts_at_the_optimum_also_through_json() {
    let s = ProblemSettings::default();
    let p = build(Problem::PeriodicQc, &s).unwrap();
    let sol = solve(&p, None).unwrap();
    assert_eq!(sol.status, Status::Solved);
    let dir = cli_util::tmpdir("warm");
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("solution.json");
    sol.write_json(&path).unwrap();
    let back = OcpSolution::read_json(&path).unwrap();
    std::fs::remove_dir_all(&dir).ok();
    // serde_json reads floats to within an ulp or so (no `float_roundtrip` feature).
    let (a, b) = (
        back.nlp_warm.as_ref().unwrap(),
        sol.nlp_warm.as_ref().unwrap(),
    );
    assert_eq!(a.x.len(), b.x.len());
    let close = |u: &[f64], v: &[f64]| {
        u.iter()
            .zip(v)
            .all(|(p, q)| (p - q).abs() <= 1e-14 * p.abs().max(q.abs()).max(1e-300))
    };
    assert!(close(&a.x, &b.x) && close(&a.lambda, &b.lambda));
    assert!(close(&a.z_l, &b.z_l) && close(&a.z_u, &b.z_u));
    let s2 = ProblemSettings {
        warm_start: Some(back),
        ..ProblemSettings::default()
    };
    let p2 = build(Problem::PeriodicQc, &s2).unwrap();
    let again = solve(&p2, None).unwrap();
    assert!(again.status.is_success());
    assert!(again.stages[0].0.starts_with("exact warm start"));
    assert!(again.iterations <= 15, "{} iterations", again.iterations);
    assert!((again.objective - sol.objective).abs() < 1e-6 * sol.objective);
    // The same through the library call.
    let w = solve_warm(&p, sol.nlp_warm.as_ref().unwrap(), None).unwrap();
    assert!(w.iterations <= 15 && (w.objective - sol.objective).abs() < 1e-6 * sol.objective);
}

/// A guess of one's own goes in as a solution file whose raw collocation data hold it
/// (docs/optima.md, "A guess of your own"). While the file keeps its primal–dual point
/// (`nlp_warm`) and the mesh is the same, that point is taken as it is and edits of the raw
/// data are not seen; without it the raw data are interpolated onto the mesh, durations
/// included. The optimum's own raw data, interpolated so, solve back to the optimum.
#[test]
fn a_guess_of_ones_own_is_read_from_the_raw_data_once_the_stored_point_is_dropped() {
    let p = build(Problem::PeriodicQc, &ProblemSettings::default()).unwrap();
    let sol = solve(&p, None).unwrap();
    assert_eq!(sol.status, Status::Solved);
    let from = |guess: OcpSolution| {
        let s = ProblemSettings {
            warm_start: Some(guess),
            ..ProblemSettings::default()
        };
        build(Problem::PeriodicQc, &s).unwrap()
    };
    let mut edited = sol.clone();
    for phase in &mut edited.raw {
        phase.duration *= 1.1;
    }
    let kept = solve(&from(edited.clone()), None).unwrap();
    assert!(kept.stages[0].0.starts_with("exact warm start"));
    assert!((kept.objective - sol.objective).abs() < 1e-6 * sol.objective);

    edited.nlp_warm = None;
    let p_edit = from(edited.clone());
    for (layout, raw) in p_edit.nlp.phases.iter().zip(&edited.raw) {
        assert_eq!(p_edit.nlp.initial()[layout.t], raw.duration);
    }
    let e = solve(&p_edit, None).unwrap();
    assert!(e.stages[0].0.starts_with("interpolated warm start"));
    // The direct strategy (`optimize --strategy direct`) names the kind in its stage.
    let direct = |guess: &OcpSolution| {
        let s = ProblemSettings {
            warm_start: Some(guess.clone()),
            ..ProblemSettings::default()
        };
        let (_, sol) =
            solve_with_strategy(Problem::PeriodicQc, &s, Strategy::Direct, None).unwrap();
        sol.strategy.unwrap().records[0].stage.clone()
    };
    assert_eq!(direct(&edited), "direct, interpolated warm start");
    assert_eq!(direct(&sol), "direct, exact warm start");

    let mut own = sol.clone();
    own.nlp_warm = None;
    let back = solve(&from(own), None).unwrap();
    assert!(back.stages[0].0.starts_with("interpolated warm start"));
    assert_eq!(back.status, Status::Solved);
    assert!(
        (back.objective - sol.objective).abs() < 1e-6 * sol.objective,
        "{} against {}",
        back.objective,
        sol.objective
    );
}

#[test]
fn continuation_of_a_problem_without_period_is_an_eps_homotopy() {
    let s = ProblemSettings::default();
    let (_, d) = solve_with_strategy(Problem::Reach, &s, Strategy::Direct, None).unwrap();
    let (p, c) = solve_with_strategy(Problem::Reach, &s, Strategy::Continuation, None).unwrap();
    let rep = c.strategy.as_ref().unwrap();
    assert_eq!(rep.records.len(), 2);
    assert!(rep.records[0].stage.starts_with("eps 0.1"));
    assert_eq!(p.epsilon, d.epsilon);
    assert!(c.status.is_success() && d.status.is_success());
    // Reaching the ball is a benign problem: both end at the same optimum.
    assert!((c.objective - d.objective).abs() < 1e-5 * d.objective.abs());
}

#[test]
fn bad_strategy_inputs_are_errors() {
    let s = ProblemSettings::default();
    let zero = Strategy::Multistart { starts: 0, seed: 0 };
    assert!(solve_with_strategy(Problem::PeriodicQc, &s, zero, None).is_err());
    for sg in [
        StartGuess {
            q: vec![0.1, 0.2],
            durations: vec![1.0; 3],
        },
        StartGuess {
            q: vec![0.1, f64::NAN, 0.3],
            durations: vec![1.0; 3],
        },
        StartGuess {
            q: Q_GUESS.to_vec(),
            durations: vec![1.0, -1.0, 1.0],
        },
    ] {
        let bad = ProblemSettings {
            start: Some(sg.clone()),
            ..ProblemSettings::default()
        };
        let e = build(Problem::PeriodicQc, &bad).expect_err("must fail");
        assert!(e.to_string().contains("start guess"), "{e}");
    }
    for es in [0.0, -1.0, f64::NAN, f64::INFINITY] {
        let bad = ProblemSettings {
            effort_scale: es,
            ..ProblemSettings::default()
        };
        assert!(build(Problem::PeriodicQc, &bad).is_err());
    }
    let bad = ProblemSettings {
        period_bounds: Some((2.0, 1.0)),
        ..ProblemSettings::default()
    };
    assert!(build(Problem::PeriodicQc, &bad).is_err());
}

/// A warm start from a solution of another problem is taken as a start (a continuation a user
/// may want), but `optimize` says so; one of the same problem and scene is taken silently.
#[test]
fn a_warm_start_of_another_problem_is_said_to_be_one() {
    let dir = cli_util::tmpdir("warm-other");
    let qc = dir.join("qc.json");
    cli_util::qc_optimum().write_json(&qc).unwrap();
    let warning = |problem: &str| {
        let out = dir.join(format!("out-{problem}"));
        let r = cli_util::run(&[
            "optimize",
            "--problem",
            problem,
            "--impact-law",
            "stick",
            "--strategy",
            "direct",
            "--max-iter",
            "3",
            "--verify-rtol",
            "0",
            "--warm-start",
            qc.to_str().unwrap(),
            "--out",
            out.to_str().unwrap(),
        ]);
        let stderr = String::from_utf8_lossy(&r.stderr).to_string();
        assert!(!stderr.contains("panicked"), "{stderr}");
        stderr
            .lines()
            .find(|l| l.starts_with("warning: --warm-start"))
            .map(str::to_string)
    };
    let other = warning("periodic-cot").expect("a warning for another problem");
    assert!(
        other.contains("a solution of `periodic-qc` on scene `paper`")
            && other.contains("the start of `periodic-cot` on scene `paper`"),
        "{other}"
    );
    assert_eq!(warning("periodic-qc"), None);
}
