//! The open-loop replay of an optimum (paper Sect. 6.2, Fig. 17) and its stabilisation by
//! joint-space PD tracking around the optimal trajectory (Sect. 7), on the cheapest solved
//! periodic optimum (`periodic-qc`, one direct solve on the default mesh):
//! * with zero gains the tracked replay is the pure open loop, bit for bit;
//! * with the default gains, acting in contact too, it stays much closer to the optimum than
//!   the open loop over the horizon (joint angles and ball angular velocity);
//! * the default tracking acts in the optimum's free phases only;
//! * `simulate --init SOLUTION --pd-track KP,KD [--pd-track-contact]` runs the same replay
//!   from the command line and rejects malformed gains and a missing solution.

#[path = "common/cli.rs"]
mod cli;

use ball_finger::paper::openloop::{
    DEFAULT_PD_TRACK, OpenLoop, PdTrack, run_open_loop, run_pd_tracked, tracking_input,
};
use ball_finger::pipeline::{build, solve};
use bf_problem::{Problem, ProblemSettings};
use bf_sim::Input;

fn worst(v: &[f64]) -> f64 {
    v.iter().fold(0.0, |m: f64, e| m.max(*e))
}

fn bits(o: &OpenLoop) -> Vec<u64> {
    let tr = &o.trajectory;
    tr.t.iter()
        .chain(tr.x.iter().flatten())
        .map(|v| v.to_bits())
        .collect()
}

#[test]
fn pd_tracking_stays_closer_to_the_optimum_than_the_open_loop() {
    let p = build(Problem::PeriodicQc, &ProblemSettings::default()).unwrap();
    let sol = solve(&p, None).unwrap();
    assert!(sol.status.is_success(), "{:?}", sol.stages);
    let dir = cli::tmpdir("open-loop");
    let periods = 2;
    let open = run_open_loop(&sol, periods, &dir.join("open-loop")).unwrap();
    let zero = PdTrack {
        kp: 0.0,
        kd: 0.0,
        during_contact: true,
    };
    let same = run_pd_tracked(&sol, periods, &zero, &dir.join("zero")).unwrap();
    // The replay loses contact after the impact (Newton's law) where the optimum sticks, so
    // the feedback must act in contact too to hold the trajectory.
    let always = PdTrack {
        during_contact: true,
        ..DEFAULT_PD_TRACK
    };
    let tracked = run_pd_tracked(&sol, periods, &always, &dir.join("pd")).unwrap();
    std::fs::remove_dir_all(&dir).ok();
    eprintln!(
        "open: ω {:?} q {:?} stopped {:?}\ntracked: ω {:?} q {:?} stopped {:?}",
        open.omega_error_per_period,
        open.q_error_per_period,
        open.stopped,
        tracked.omega_error_per_period,
        tracked.q_error_per_period,
        tracked.stopped
    );
    assert!(
        bits(&same) == bits(&open),
        "zero gains differ from the open loop"
    );
    assert_eq!(same.events, open.events);
    assert!(open.stopped.is_none() && tracked.stopped.is_none());
    let (qo, qt) = (
        worst(&open.q_error_per_period),
        worst(&tracked.q_error_per_period),
    );
    let (wo, wt) = (
        worst(&open.omega_error_per_period),
        worst(&tracked.omega_error_per_period),
    );
    assert!(qt < 0.1 * qo, "q error: PD {qt} vs open loop {qo}");
    assert!(wt < wo, "ω error: PD {wt} vs open loop {wo}");
}

/// The tracking input is the feed-forward torque plus the PD law inside the optimum's free
/// phases and the feed-forward torque alone in its stick phase.
#[test]
fn tracking_input_acts_in_free_phases_only() {
    let p = build(Problem::PeriodicQc, &ProblemSettings::default()).unwrap();
    let sol = solve(&p, None).unwrap();
    let input = tracking_input(&sol, 2, &DEFAULT_PD_TRACK).unwrap();
    let plain = ball_finger::paper::openloop::periodic_torques(&sol, 2).unwrap();
    let d = &sol.phase_durations;
    let (q, qd) = ([0.3, 0.2, 0.1], [0.0; 3]);
    let (mut a, mut b) = ([0.0; 3], [0.0; 3]);
    for (t, free) in [
        (0.5 * d[0], true),
        (d[0] + 0.5 * d[1], false),
        (d[0] + d[1] + 0.5 * d[2], true),
        (sol.period + 0.5 * d[0], true),
    ] {
        input.tau(t, &q, &qd, &mut a).unwrap();
        plain.tau(t, &q, &qd, &mut b).unwrap();
        assert_eq!(input.feedback_at(t), free, "t = {t}");
        assert_eq!(a == b, !free, "t = {t}: {a:?} vs {b:?}");
    }
}

/// The last joint angles of a `simulate` run (`trajectory.csv` columns q1..q3).
fn last_q(dir: &std::path::Path) -> Vec<f64> {
    let csv = std::fs::read_to_string(dir.join("trajectory.csv")).unwrap();
    let last = csv.lines().last().unwrap();
    last.split(',')
        .skip(3)
        .take(3)
        .map(|v| v.parse().unwrap())
        .collect()
}

#[test]
fn simulate_pd_track_replays_a_solution_file() {
    let p = build(Problem::PeriodicQc, &ProblemSettings::default()).unwrap();
    let sol = solve(&p, None).unwrap();
    let dir = cli::tmpdir("pd-track");
    ball_finger::pipeline::solution_io::write_solution(&sol, &dir.join("sol")).unwrap();
    let init = dir.join("sol").join("solution.json");
    let t_end = format!("{}", sol.period);
    let sim = |gains: &str, contact: bool, out: &str| {
        let out = dir.join(out);
        let mut args = vec![
            "simulate",
            "--init",
            init.to_str().unwrap(),
            "--t-end",
            &t_end,
            "--impact-law",
            "newton",
            "--pd-track",
            gains,
            "--out",
            out.to_str().unwrap(),
        ];
        if contact {
            args.push("--pd-track-contact");
        }
        let o = cli::run(&args);
        (o, out)
    };
    // After one period the optimum is back at its initial angles (periodicity).
    let q0 = &sol.nodes.q[0];
    let err = |q: &[f64]| {
        q.iter()
            .zip(q0)
            .map(|(a, b)| (a - b).abs())
            .fold(0.0, f64::max)
    };
    let (o, open_dir) = sim("0,0", false, "open");
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let (o, pd_dir) = sim("1,0.2", true, "pd");
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let (eo, ep) = (err(&last_q(&open_dir)), err(&last_q(&pd_dir)));
    assert!(ep < 0.1 * eo, "q(T) error: PD {ep} vs open loop {eo}");
    // Malformed gains, and no solution to track.
    let (o, _) = sim("1", false, "bad");
    assert!(!o.status.success());
    let e = String::from_utf8_lossy(&o.stderr);
    assert!(e.contains("--pd-track"), "{e}");
    let o = cli::run(&["simulate", "--pd-track", "1,0.2", "--out", "x"]);
    assert!(!o.status.success());
    let e = String::from_utf8_lossy(&o.stderr);
    assert!(e.contains("--init"), "{e}");
    // A negative gain is a wrong command line (status 2), as with `--pd-gains`.
    let (o, _) = sim("-1,0.2", false, "negative");
    assert_eq!(o.status.code(), Some(2));
    let e = String::from_utf8_lossy(&o.stderr);
    assert!(e.contains("--pd-track -1,0.2: kp is -1"), "{e}");
    // So is a run of more periods than the replay's series hold.
    let o = cli::run(&[
        "simulate",
        "--init",
        init.to_str().unwrap(),
        "--t-end",
        "1e9",
        "--pd-track",
        "1,0.2",
        "--out",
        dir.join("long").to_str().unwrap(),
    ]);
    assert_eq!(o.status.code(), Some(2));
    let e = String::from_utf8_lossy(&o.stderr);
    assert!(e.contains("--t-end") && e.contains("periods"), "{e}");
    std::fs::remove_dir_all(&dir).ok();
}
