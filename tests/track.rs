//! Closed-loop execution of the default `periodic-qc` optimum (shared by the tests of this
//! file) with bf-control's hybrid controller:
//! * nominal plant, Newton's and the max-dissipation impact law: every one of 10 periods has
//!   contact and a mean-ω error ≤ 2 % (the target);
//! * the normal-force loop holds λ_n at the optimum's λ_n*(s) over the stick phase on a plant
//!   with a 10 % heavier ball (the controller's inversion is then wrong);
//! * event timing: a plant that starts 50 ms behind the controller's clock meets the
//!   planned impact state after its first lift-off, and the contact phase starts at the
//!   plant's impact event; the approach re-timed by the gap: a plant 20 ms late or early on
//!   the approach meets the planned impact state when its own schedule says (the
//!   clock-timed law misses it), a velocity error decays within the error dynamics' envelope;
//! * ignored (slow): the 32-start optima's (`optimize --hops 0`, what `paper` presents) nominal
//!   target over 50 periods, and the perturbed
//!   plants' target over 50 periods;
//! * with the torques saturated at the paper's 1 N m, the all-perturbations plant (which
//!   needs up to 1.9 N m unbounded) still converges, and no sample exceeds the bound;
//! * `track` writes tracking.json whose per-period figures a recomputation from
//!   trajectory.json (an independent loop over its samples) reproduces, and refuses bad
//!   arguments with a message naming the option;
//! * ignored (slow): a 300-period run of the human finger's plan, which needs more steps than
//!   the simulator's default budget, completes without a lost ball.

#[path = "common/cli.rs"]
mod cli;

use ball_finger::paper::closed_loop::{
    ControllerKind, Tracking, reference_of, robustness_row, run_tracking, solution_model,
};
use ball_finger::pipeline::SolutionIo;
use bf_control::{HybridController, HybridGains, InverseDynamics};
use bf_model::{ImpactLaw, Kernels, Mode, State, Vec3};
use bf_sim::ball_finger::{BallFinger, BallFingerSettings};
use bf_sim::{HybridSystem, SimSettings};

fn hybrid(plant_toml: Option<&str>, law: ImpactLaw, periods: usize) -> Tracking {
    tracked(ControllerKind::Hybrid, plant_toml, law, periods)
}

fn tracked(
    controller: ControllerKind,
    plant_toml: Option<&str>,
    law: ImpactLaw,
    periods: usize,
) -> Tracking {
    let sol = cli::qc_optimum();
    let plant = match plant_toml {
        None => solution_model::<3>(sol).unwrap().0,
        Some(text) => {
            let scene = bf_codegen::Scene::from_toml_str(text, "perturbed").unwrap();
            bf_model::fixtures::model_for_scene(&scene).unwrap().0
        }
    };
    run_tracking(sol, controller, periods, plant, law).unwrap()
}

#[test]
fn a_tracking_run_fails_on_a_lost_ball_or_a_failed_energy_check() {
    let mut run = hybrid(None, ImpactLaw::Newton, 1);
    let row = robustness_row("nominal".into(), &run, 1);
    assert_eq!(row.error, None);
    assert_eq!(row.completed_periods, 1);
    let tol = run.report.summary.energy_tolerance;
    assert!(
        run.report.summary.energy_error <= tol,
        "{}",
        run.report.summary.energy_error
    );
    assert_eq!(run.failure(), None);
    // The warning the simulator records when the balance misses `tol` (its kind is the
    // documented `summary.json` key).
    run.report.summary.warnings.push(bf_sim::SimWarning {
        t: 1.0,
        kind: "energy_error",
        message: format!("energy-balance error 1e-2 J from t = 0 s exceeds {tol} J"),
    });
    let failure = run.failure().expect("a failed energy check fails the run");
    assert!(failure.contains("energy balance failed"), "{failure}");
    // In the robustness table it is an error that misses the target, not a row of errors.
    let row = robustness_row("nominal".into(), &run, 1);
    assert!(!row.meets_target);
    assert!(
        row.error
            .as_deref()
            .is_some_and(|e| e.contains("energy balance failed")),
        "{row:?}"
    );
    // A lost ball is the first thing to say.
    run.lost = Some("no contact in period 1".into());
    let failure = run.failure().expect("a lost ball fails the run");
    assert!(failure.contains("lost the ball"), "{failure}");
    let row = robustness_row("nominal".into(), &run, 1);
    assert!(!row.stopped && !row.meets_target, "{row:?}");
    // A simulation that stopped (a step limit) did not complete its periods: the ball may
    // still have been in hand, and neither the verdict nor the robustness row says it fell.
    run.stopped = Some("step limit reached".into());
    let failure = run.failure().expect("a stopped run fails");
    assert!(
        failure.contains("did not complete its periods") && !failure.contains("lost the ball"),
        "{failure}"
    );
    let row = robustness_row("nominal".into(), &run, 1);
    assert!(row.stopped && !row.meets_target, "{row:?}");
}

/// The paper scene with ball mass ×1.1, μ_s and μ_k ×0.8, every link's mass and inertia ×1.05
/// and socket damping ×1.5 (the "all together" plant).
fn all_four_plant() -> String {
    let text = bf_generated::scene_toml("paper")
        .unwrap()
        .replace("mass = 0.02\ncom", "mass = 0.021\ncom")
        .replace(
            "inertia = [1.0677e-3, 2.3177e-3, 2.0833e-3]",
            "inertia = [1.121085e-3, 2.433585e-3, 2.187465e-3]",
        )
        .replace(
            "center = [0.0, 0.0, 0.0]\nmass = 0.02",
            "center = [0.0, 0.0, 0.0]\nmass = 0.022",
        )
        .replace("mu_s = 0.8", "mu_s = 0.64")
        .replace("mu_k = 0.6", "mu_k = 0.48")
        .replace("socket_damping = 0.004", "socket_damping = 0.006");
    for needle in [
        "mass = 0.021\ncom",
        "mass = 0.022",
        "mu_s = 0.64",
        "mu_k = 0.48",
        "socket_damping = 0.006",
    ] {
        assert!(text.contains(needle), "{needle}");
    }
    assert_eq!(text.matches("mass = 0.021\ncom").count(), 3);
    text
}

/// The paper scene with its first link 5 % longer: the plant meets the ball where the plan
/// does not, so the controller's phase and integrators change at the impacts.
fn longer_first_link_plant() -> String {
    let text = bf_generated::scene_toml("paper")
        .unwrap()
        .replacen("a = 1.0", "a = 1.05", 1);
    assert_eq!(text.matches("a = 1.05").count(), 1);
    text
}

/// The state just before an event ends the step that led to it, so its τ is the one that drove
/// that step: continuous with the samples before it in a flight (the computed-torque law is
/// smooth in time and state), and the energy balance of the step ending there closes. Taking
/// the controller's τ after its observations at the impact instead (its contact phase's law)
/// put 1 N m on the last sample of every flight and failed this plant's energy check.
#[test]
fn the_sample_before_an_impact_carries_the_torque_that_drove_its_step() {
    let plant = longer_first_link_plant();
    for run in [
        hybrid(None, ImpactLaw::Newton, 3),
        hybrid(Some(&plant), ImpactLaw::Newton, 3),
    ] {
        let tr = &run.output.trajectory;
        let tau = |i: usize| run.report.samples[i].tau;
        let mut impacts = 0;
        for i in 2..tr.len() {
            if tr.kind[i] != bf_sim::SampleKind::EventPre || tr.mode[i] != Mode::Free {
                continue;
            }
            // The two samples before it at distinct earlier times (a grid point can share a
            // step's time).
            let before = |k: usize| (0..k).rev().find(|&j| tr.t[j] < tr.t[k]).unwrap();
            let b = before(i);
            let a = before(b);
            // An impact microseconds after a lift-off (a bounce) has no flight to compare with.
            if tr.mode[a] != Mode::Free || tr.mode[b] != Mode::Free {
                continue;
            }
            // τ at the event, extrapolated linearly from the two samples before it.
            let s = (tr.t[i] - tr.t[b]) / (tr.t[b] - tr.t[a]);
            for j in 0..3 {
                let expected = tau(b)[j] + s * (tau(b)[j] - tau(a)[j]);
                assert!(
                    (tau(i)[j] - expected).abs() <= 1e-2,
                    "t = {}: tau_{} {} against {expected} extrapolated ({:?}, {:?})",
                    tr.t[i],
                    j + 1,
                    tau(i)[j],
                    tau(a),
                    tau(b)
                );
            }
            impacts += 1;
        }
        assert!(impacts >= 3, "{impacts} impacts");
        // An event chained to the one before it (stick → slip → free at one instant) starts
        // where that one's reset left the plant, with no step between: the same τ and forces.
        let events = &run.report.events;
        let mut chained = 0;
        for k in 1..events.len() {
            if events[k].chained {
                assert_eq!(events[k].x_pre, events[k - 1].x_post);
                assert_eq!(events[k].pre, events[k - 1].post, "t = {}", events[k].t);
                chained += 1;
            }
        }
        assert!(chained >= 1, "no chained event to check");
        let summary = &run.report.summary;
        assert!(
            summary.energy_error <= summary.energy_tolerance,
            "{} > {}",
            summary.energy_error,
            summary.energy_tolerance
        );
        assert_eq!(run.failure(), None);
    }
}

#[test]
fn saturated_controller_keeps_the_torque_bound_and_still_converges() {
    let plant = all_four_plant();
    let bounded = tracked(ControllerKind::Hybrid, Some(&plant), ImpactLaw::Newton, 10);
    let free = tracked(
        ControllerKind::HybridUnbounded,
        Some(&plant),
        ImpactLaw::Newton,
        10,
    );
    // Without the bound this plant needs more than the paper's 1 N m, so the bound is active.
    let peak = |t: &Tracking| {
        t.report
            .samples
            .iter()
            .flat_map(|s| s.tau.iter())
            .fold(0.0f64, |m, v| m.max(v.abs()))
    };
    eprintln!(
        "max |τ|: {} bounded, {} unbounded",
        peak(&bounded),
        peak(&free)
    );
    assert!(peak(&free) > 1.5, "{}", peak(&free));
    // Every sample the plant received, not only the per-period maxima.
    assert!(!bounded.report.samples.is_empty());
    for s in &bounded.report.samples {
        assert!(s.tau.iter().all(|v| v.abs() <= 1.0), "{:?}", s.tau);
    }
    assert!(bounded.lost.is_none(), "{:?}", bounded.lost);
    assert_eq!(bounded.periods.len(), 10);
    for (k, p) in bounded.periods.iter().enumerate() {
        assert!(p.contact, "period {k}: {p:?}");
        // The target for perturbed plants: ≤ 5 % from the 4th period on; measured
        // 1.6 % in the 4th and below 0.1 % from the 7th.
        if k >= 3 {
            assert!(p.omega_error <= 0.05, "period {k}: {p:?}");
        }
    }
    assert!(
        bounded.periods[9].omega_error <= 0.005,
        "{:?}",
        bounded.periods[9]
    );
}

#[test]
fn hybrid_control_meets_the_omega_target_for_ten_periods() {
    for law in [ImpactLaw::Newton, ImpactLaw::MaxDissipation] {
        let run = hybrid(None, law, 10);
        let errors: Vec<f64> = run.periods.iter().map(|p| p.omega_error).collect();
        eprintln!("{law:?}: {errors:?}");
        assert!(run.lost.is_none(), "{law:?}: {:?}", run.lost);
        assert_eq!(run.periods.len(), 10);
        for (k, p) in run.periods.iter().enumerate() {
            assert!(p.contact && p.stick_time > 0.0, "{law:?} period {k}: {p:?}");
            assert!(p.omega_error <= 0.02, "{law:?} period {k}: {p:?}");
            // One period of the optimum's length, re-timed by the plant's events.
            assert!(
                (p.end - p.start - cli::qc_optimum().period).abs()
                    < 0.02 * cli::qc_optimum().period,
                "{p:?}"
            );
        }
    }
}

/// Simulates the plant `plant_toml` (default: the solution's scene) with `law` under the
/// hybrid controller with `gains`, whose first phase began at `t0`, from the optimum's initial
/// state until `t_end`.
fn closed_loop(
    plant_toml: Option<&str>,
    law: ImpactLaw,
    gains: HybridGains,
    t0: f64,
    t_end: f64,
) -> (
    BallFinger<bf_model::DynKernels, HybridController<bf_model::DynKernels>>,
    bf_sim::SimOutput<Mode>,
) {
    let d = &cli::qc_optimum().nodes;
    let x0: Vec<f64> = [&d.q[0], &d.qd[0], &d.omega[0]]
        .into_iter()
        .flatten()
        .copied()
        .collect();
    closed_loop_from(plant_toml, law, gains, t0, &x0, t_end)
}

/// [`closed_loop`] from the plant state `x0` (q, q̇, ω) at time 0.
fn closed_loop_from(
    plant_toml: Option<&str>,
    law: ImpactLaw,
    gains: HybridGains,
    t0: f64,
    x0: &[f64],
    t_end: f64,
) -> (
    BallFinger<bf_model::DynKernels, HybridController<bf_model::DynKernels>>,
    bf_sim::SimOutput<Mode>,
) {
    let sol = cli::qc_optimum();
    let (model, scene) = solution_model::<3>(sol).unwrap();
    let reference = reference_of(sol, &model).unwrap();
    let id = InverseDynamics::compiled(
        &scene,
        model.kernels().param_values(),
        model.params().mu_v(),
    )
    .unwrap();
    let controller = HybridController::new(model, id, reference, gains, t0, x0).unwrap();
    let plant = match plant_toml {
        None => solution_model::<3>(sol).unwrap().0,
        Some(text) => {
            let scene = bf_codegen::Scene::from_toml_str(text, "perturbed").unwrap();
            bf_model::fixtures::model_for_scene(&scene).unwrap().0
        }
    };
    let settings = BallFingerSettings {
        impact_law: law,
        ..BallFingerSettings::default()
    };
    let sys = BallFinger::new(plant, controller, settings).unwrap();
    let sim = SimSettings {
        rtol: 1e-8,
        ..SimSettings::default()
    };
    let out = bf_sim::simulate(
        &sys as &dyn HybridSystem<Mode = Mode>,
        sim,
        Mode::Free,
        0.0,
        x0,
        t_end,
    )
    .unwrap();
    (sys, out)
}

/// RMS of λ_n − λ_n*(s) over the Stick samples of the first contact phase, relative to the
/// phase's largest |λ*|.
fn lambda_n_rms(plant_toml: &str, gains: HybridGains) -> f64 {
    let sol = cli::qc_optimum();
    let (model, _) = solution_model::<3>(sol).unwrap();
    let reference = reference_of(sol, &model).unwrap();
    let contact = reference.phases.iter().position(|p| p.contact).unwrap();
    let phase = &reference.phases[contact];
    let scale = phase
        .lambda
        .iter()
        .map(|l| Vec3::from(*l).norm())
        .fold(0.0, f64::max);
    let t_end = reference.phases[..=contact]
        .iter()
        .map(|p| p.duration)
        .sum::<f64>();
    let (sys, out) = closed_loop(
        Some(plant_toml),
        ImpactLaw::MaxDissipation,
        gains,
        0.0,
        t_end,
    );
    let report = sys.report(&out, 0.0, 0.0);
    let tr = &out.trajectory;
    let impact = out
        .events
        .iter()
        .find(|e| e.mode_before == Mode::Free)
        .unwrap()
        .t;
    let (mut sum, mut count) = (0.0, 0);
    for i in 1..tr.t.len() {
        if tr.mode[i] != Mode::Stick {
            continue;
        }
        let x = State::from_slice(&tr.x[i]).unwrap();
        let n = model.evaluate(&x).unwrap().contact.n;
        let e = (report.samples[i].lambda_n - phase.lambda_n(tr.t[i] - impact, &n)) / scale;
        sum += e * e * (tr.t[i] - tr.t[i - 1]);
        count += 1;
    }
    assert!(count > 20, "{count} stick samples");
    (sum / (tr.t[tr.t.len() - 1] - impact)).sqrt()
}

#[test]
fn force_loop_holds_lambda_n_over_the_stick_phase() {
    // Links 20 % heavier (mass and inertia): the controller's inversion of eq. 33 is off.
    let text = bf_generated::scene_toml("paper")
        .unwrap()
        .replace("mass = 0.02\ncom", "mass = 0.024\ncom")
        .replace(
            "inertia = [1.0677e-3, 2.3177e-3, 2.0833e-3]",
            "inertia = [1.28124e-3, 2.78124e-3, 2.49996e-3]",
        );
    assert_eq!(text.matches("mass = 0.024").count(), 3);
    // The max-dissipation impact ends sticking, and no friction margin and no force boost
    // leave λ_n to the loop (the optimum rides the friction cone, so the boost would set it).
    let mut gains = HybridGains::default();
    gains.contact.friction_margin = 0.0;
    gains.contact.force_boost = 0.0;
    let with_loop = lambda_n_rms(&text, gains);
    gains.contact.force_integral = 0.0;
    let without = lambda_n_rms(&text, gains);
    eprintln!("RMS of λ_n − λ_n*: {with_loop} with the force loop, {without} without");
    // Measured: 3.1 % with the loop, 12.2 % without. What the loop leaves is mostly lag
    // behind the fast swings of λ_n* of this coarse-mesh optimum (the integral is updated
    // once per accepted step, a few ms apart).
    assert!(with_loop < 0.035, "{with_loop}");
    assert!(with_loop < 0.85 * without, "{with_loop} vs {without}");
}

#[test]
fn a_late_lift_off_still_meets_the_planned_impact_state() {
    let sol = cli::qc_optimum();
    let (model, _) = solution_model::<3>(sol).unwrap();
    let reference = reference_of(sol, &model).unwrap();
    // The optimum: free, stick, free; its impact state is the end of phase 0.
    assert_eq!(
        reference
            .phases
            .iter()
            .map(|p| p.contact)
            .collect::<Vec<_>>(),
        [false, true, false]
    );
    let plan = reference.phases[0].at(reference.phases[0].duration);
    let flight = reference.phases[2].duration + reference.phases[0].duration;
    let delay = 0.05;
    // The controller's clock runs `delay` ahead of the plant: the first approach is late and
    // off the plan, and so is the first lift-off. The second approach is timed from the
    // plant's lift-off event and must meet the planned impact state after the planned flight.
    let (sys, out) = closed_loop(
        None,
        ImpactLaw::MaxDissipation,
        HybridGains::default(),
        -delay,
        1.2 * sol.period + reference.phases[0].duration,
    );
    let impacts: Vec<_> = out
        .events
        .iter()
        .filter(|e| e.mode_before == Mode::Free)
        .collect();
    let lift_off = out
        .events
        .iter()
        .find(|e| e.mode_before != Mode::Free && e.mode_after == Some(Mode::Free))
        .expect("a lift-off");
    assert!(impacts.len() >= 2, "{} impacts", impacts.len());
    let second = impacts[1];
    eprintln!(
        "first impact {} (plan {}), lift-off {}, second impact {} (lift-off + {flight})",
        impacts[0].t,
        reference.phases[0].duration - delay,
        lift_off.t,
        second.t
    );
    assert!(
        (second.t - lift_off.t - flight).abs() < 0.01 * flight,
        "flight {} vs planned {flight}",
        second.t - lift_off.t
    );
    let qd_scale = plan.qd.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    for i in 0..3 {
        let (dq, dqd) = (
            second.x_pre[i] - plan.q[i],
            second.x_pre[3 + i] - plan.qd[i],
        );
        assert!(dq.abs() < 1e-3, "q{i}: off by {dq}");
        assert!(
            dqd.abs() < 1e-2 * qd_scale,
            "qd{i}: off by {dqd} of {qd_scale}"
        );
    }
    // Each contact phase starts at the plant's impact event.
    let switches = sys.input.switches();
    let starts: Vec<f64> = switches
        .iter()
        .filter(|s| s.phase == 1)
        .map(|s| s.t)
        .collect();
    assert_eq!(starts[..2], [impacts[0].t, second.t]);
}

/// The approach re-timed by the gap (bf-control's module doc): the plant starts on the plan's
/// approach, 40 ms before the planned impact of the QC optimum, with the controller's clock
/// 20 ms ahead (a late plant) or behind (an early one), on the plan's velocity or 10 % above
/// it. Indexed by the gap, the reference's position error is zero from the start, and so is
/// its velocity error on the plan's velocity: by the error dynamics the plant then stays on
/// the plan and meets the planned impact state when its own schedule says, whatever the
/// clock; what is left is the reference's interpolation (q̈* linear between samples, q*
/// Hermite). A velocity error v₀ at the start decays along the path as e^{−2ζω_n t} and, where
/// the path turns, through the critically damped cross-path mode, whose envelope
/// v₀ (1 + ω_n t) e^{−ω_n t} bounds it at the impact. The clock-timed law (re-timing off)
/// chases the clock instead: the late plant is pushed to the clock's impact time and arrives
/// off the planned state.
#[test]
fn a_late_or_early_approach_meets_the_planned_impact_state() {
    let sol = cli::qc_optimum();
    let (model, _) = solution_model::<3>(sol).unwrap();
    let reference = reference_of(sol, &model).unwrap();
    let approach = &reference.phases[0];
    assert!(!approach.contact && reference.phases[1].contact);
    let last = approach.s.len() - 1;
    let end = approach.s[last];
    // The optimum's last sample is 0.09 mm off the ball: the planned impact state is its
    // state carried on at the planned velocity to h = 0.
    let to_contact = approach.gap[last] / -approach.gap_rate[last];
    assert!((0.0..1e-3).contains(&to_contact), "{to_contact}");
    let plan = approach.at(end + to_contact);
    let lead = 0.04;
    let delay = 0.02;
    let start = approach.at(end - lead);
    let norm = |v: &[f64]| v.iter().map(|x| x * x).sum::<f64>().sqrt();
    let gains = HybridGains::default();
    let wn = gains.free.omega_n;
    assert_eq!(gains.free.zeta, 1.0);
    let mut clock_timed = gains;
    clock_timed.approach = 0.0;
    let run = |shift: f64, boost: f64, gains: HybridGains| {
        let x0: Vec<f64> = start
            .q
            .iter()
            .copied()
            .chain(start.qd.iter().map(|v| v * boost))
            .chain(start.omega)
            .collect();
        let (_, out) = closed_loop_from(
            None,
            ImpactLaw::MaxDissipation,
            gains,
            -(end - lead + shift),
            &x0,
            lead + 0.1,
        );
        let impact = out
            .events
            .into_iter()
            .find(|e| e.mode_before == Mode::Free)
            .expect("an impact");
        let dq: Vec<f64> = (0..3).map(|i| impact.x_pre[i] - plan.q[i]).collect();
        let dqd: Vec<f64> = (0..3).map(|i| impact.x_pre[3 + i] - plan.qd[i]).collect();
        (impact.t, norm(&dq), norm(&dqd) / norm(&plan.qd))
    };
    let own_schedule = lead + to_contact;
    let mut on_plan = (0.0f64, 0.0f64);
    for (label, shift) in [("late", delay), ("early", -delay)] {
        let (t, dq, dqd) = run(shift, 1.0, gains);
        on_plan = (on_plan.0.max(dq), on_plan.1.max(dqd));
        eprintln!(
            "{label}: impact at {t:.5} s (own schedule {own_schedule:.5}), |Δq| {dq:.2e} rad, |Δq̇|/|q̇*| {dqd:.2e}"
        );
        // Measured: 0.01 ms, 2e-6 rad, 8.5e-5 (the reference's interpolation).
        assert!((t - own_schedule).abs() < 5e-4, "{label}: impact at {t}");
        assert!(dq < 1e-4 && dqd < 1e-3, "{label}: {dq} {dqd}");
        let (t, dq, dqd) = run(shift, 1.1, gains);
        let envelope = 0.1 * norm(&start.qd) / norm(&plan.qd) * (1.0 + wn * t) * libm::exp(-wn * t);
        eprintln!(
            "{label} and 10 % fast: impact at {t:.5} s, |Δq| {dq:.2e} rad, |Δq̇|/|q̇*| {dqd:.2e} (envelope {envelope:.2e})"
        );
        assert!(dqd < envelope, "{label} and fast: {dqd} vs {envelope}");
    }
    let (t, dq, dqd) = run(delay, 1.0, clock_timed);
    eprintln!("late, clock-timed: impact at {t:.5} s, |Δq| {dq:.2e} rad, |Δq̇|/|q̇*| {dqd:.2e}");
    // Measured: 6 ms early (the clock's schedule is 20 ms early), 4.6e-3 rad and 1.6 % off,
    // some 200 times the re-timed law's errors.
    assert!(own_schedule - t > 0.004, "{t}");
    assert!(
        dq > 100.0 * on_plan.0 && dqd > 100.0 * on_plan.1,
        "{dq} {dqd} vs {on_plan:?}"
    );
}

/// Per-period figures recomputed from trajectory.json with their own loop.
fn recompute(traj: &serde_json::Value, optimum: [f64; 3]) -> Vec<[f64; 7]> {
    let t: Vec<f64> = serde_json::from_value(traj["t"].clone()).unwrap();
    let mode: Vec<String> = serde_json::from_value(traj["mode"].clone()).unwrap();
    let x: Vec<Vec<f64>> = serde_json::from_value(traj["x"].clone()).unwrap();
    let tau: Vec<Vec<f64>> = traj["derived"]
        .as_array()
        .unwrap()
        .iter()
        .map(|d| serde_json::from_value(d["tau"].clone()).unwrap())
        .collect();
    let free = |m: &str| m.eq_ignore_ascii_case("free");
    // An impact starts a period unless it comes less than `MIN_FLIGHT` after the last contact
    // sample (a bounce, docs/decisions/0081-a-bounce-is-not-a-period.md).
    let starts: Vec<usize> = (1..t.len())
        .filter(|&i| free(&mode[i - 1]) && !free(&mode[i]))
        .filter(|&i| {
            (0..i)
                .rev()
                .find(|&k| !free(&mode[k]))
                .is_none_or(|k| t[i] - t[k] >= bf_control::MIN_FLIGHT)
        })
        .collect();
    let on = (optimum[0].powi(2) + optimum[1].powi(2) + optimum[2].powi(2)).sqrt();
    starts
        .windows(2)
        .map(|w| {
            let (a, b) = (w[0], w[1]);
            let (mut int, mut stick, mut slip, mut tmax) = ([0.0; 3], 0.0, 0.0, 0.0f64);
            for k in a..b {
                let dt = t[k + 1] - t[k];
                for j in 0..3 {
                    int[j] += 0.5 * (x[k][6 + j] + x[k + 1][6 + j]) * dt;
                }
                match mode[k].to_ascii_lowercase().as_str() {
                    "stick" => stick += dt,
                    "slip" => slip += dt,
                    _ => {}
                }
            }
            // A sample between two at its own time (a mode passed through at one instant)
            // applies its τ for no time.
            for k in a..b {
                if !(k > 0 && t[k - 1] == t[k] && t[k + 1] == t[k]) {
                    tmax = tau[k].iter().fold(tmax, |m, x| m.max(x.abs()));
                }
            }
            let len = t[b] - t[a];
            let mean = int.map(|v| v / len);
            let err = ((mean[0] - optimum[0]).powi(2)
                + (mean[1] - optimum[1]).powi(2)
                + (mean[2] - optimum[2]).powi(2))
            .sqrt()
                / on;
            [mean[0], mean[1], mean[2], err, stick, slip, tmax]
        })
        .collect()
}

#[test]
fn track_writes_tracking_json_that_trajectory_json_reproduces() {
    let dir = cli::tmpdir("track");
    let sol_path = dir.join("solution.json");
    cli::qc_optimum().write_json(&sol_path).unwrap();
    let out = dir.join("out");
    let r = cli::run(&[
        "track",
        sol_path.to_str().unwrap(),
        "--controller",
        "hybrid",
        "--periods",
        "3",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(r.status.success(), "{}", String::from_utf8_lossy(&r.stderr));
    let read = |name: &str| -> serde_json::Value {
        serde_json::from_str(&std::fs::read_to_string(out.join(name)).unwrap()).unwrap()
    };
    let tracking = read("tracking.json");
    let traj = read("trajectory.json");
    assert_eq!(tracking["controller"], "hybrid");
    assert_eq!(tracking["completed_periods"], 3);
    assert_eq!(tracking["lost_ball"], false);
    assert!(tracking["energy_check_failure"].is_null(), "{tracking}");
    // The optimum was planned with the sticking law, the plant is Newton's (the default).
    assert_eq!(tracking["planned_impact_law"], "stick");
    assert_eq!(tracking["impact_law"], "newton");
    let optimum: [f64; 3] = serde_json::from_value(tracking["optimum_mean_omega"].clone()).unwrap();
    let m = cli::qc_optimum().mean_omega;
    assert_eq!(optimum, m);
    let expect = recompute(&traj, optimum);
    let periods = tracking["periods"].as_array().unwrap();
    assert_eq!(periods.len(), 3);
    assert!(expect.len() >= 3);
    for (p, e) in periods.iter().zip(&expect) {
        let mean: [f64; 3] = serde_json::from_value(p["mean_omega"].clone()).unwrap();
        let got = [
            mean[0],
            mean[1],
            mean[2],
            p["omega_error"].as_f64().unwrap(),
            p["stick_time"].as_f64().unwrap(),
            p["slip_time"].as_f64().unwrap(),
            p["max_abs_tau"].as_f64().unwrap(),
        ];
        for k in 0..7 {
            assert!(
                (got[k] - e[k]).abs() <= 1e-12 * (1.0 + e[k].abs()),
                "field {k}: {got:?} vs {e:?}"
            );
        }
        assert_eq!(p["contact"], true);
    }
    // Bad arguments: named in the message, non-zero exit, nothing written. A robustness
    // table judges each plant from the 4th period on, so it needs 4 periods at least.
    for (args, needle) in [
        (vec!["--controller", "pid"], "--controller"),
        (vec!["--impact-law", "elastic"], "--impact-law"),
        (vec!["--periods", "0"], "--periods"),
        (vec!["--robustness", "--periods", "3"], "--periods 3"),
    ] {
        let bad = dir.join("bad");
        let mut a = vec![
            "track",
            sol_path.to_str().unwrap(),
            "--out",
            bad.to_str().unwrap(),
        ];
        a.extend(args);
        let r = cli::run(&a);
        let err = String::from_utf8_lossy(&r.stderr);
        assert!(!r.status.success() && err.contains(needle), "{a:?}: {err}");
        assert!(!bad.join("tracking.json").exists());
    }
    let r = cli::run(&[
        "track",
        dir.join("missing.json").to_str().unwrap(),
        "--out",
        dir.join("m").to_str().unwrap(),
    ]);
    assert!(!r.status.success() && String::from_utf8_lossy(&r.stderr).contains("missing.json"));
    // A value no optimum has is refused by name, as `simulate --init` refuses it, rather than
    // run into a lost ball.
    let mut doc: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&sol_path).unwrap()).unwrap();
    doc["nodes"]["q1"][0] = serde_json::json!(1e300);
    std::fs::write(&sol_path, doc.to_string()).unwrap();
    let r = cli::run(&[
        "track",
        sol_path.to_str().unwrap(),
        "--out",
        dir.join("huge").to_str().unwrap(),
    ]);
    let err = String::from_utf8_lossy(&r.stderr);
    assert_eq!(r.status.code(), Some(1), "{err}");
    assert!(
        err.contains("nodes.q1[0]") && err.contains("out of range"),
        "{err}"
    );
    assert!(!dir.join("huge").exists());
    // Every period's error is relative to the plan's mean ω: a zero or altered `mean_omega`
    // is refused against the mean of the plan's own dense ω, not reported as an infinite or
    // wrong error.
    doc["nodes"]["q1"][0] = serde_json::json!(0.1);
    let stated = doc["mean_omega"].clone();
    for (scale, needle) in [(0.0, "mean_omega"), (1.5, "not the mean of its own ω")] {
        for k in ["omega_x", "omega_y", "omega_z"] {
            doc["mean_omega"][k] = serde_json::json!(stated[k].as_f64().unwrap() * scale);
        }
        std::fs::write(&sol_path, doc.to_string()).unwrap();
        let r = cli::run(&[
            "track",
            sol_path.to_str().unwrap(),
            "--out",
            dir.join("omega").to_str().unwrap(),
        ]);
        let err = String::from_utf8_lossy(&r.stderr);
        assert_eq!(r.status.code(), Some(1), "{err}");
        assert!(err.contains(needle), "{err}");
        assert!(!dir.join("omega").exists());
    }
    std::fs::remove_dir_all(&dir).ok();
}

/// A plan whose finger chatters on the plant: the paper's sticking plan from a single solve
/// (`optimize --problem periodic-qc --impact-law stick --strategy direct`, period 2.57 s) on
/// the Newton plant strikes the ball again 0.48 s after its first impact and chatters there,
/// an impact every few microseconds. Those bounces are not periods (decision record 0081): the
/// run goes on past them, every period it reports lasts longer than a plan's shortest flight,
/// the figures are what trajectory.json gives, and the run, whose first impact is a touch the
/// finger flies on from and whose chatter the simulator held while the ball pulled the finger,
/// is flagged (exit status 1, `FAILED`). Before, six bounces completed "6 of 6 periods" at
/// 0.56 s.
#[test]
fn a_chattering_finger_completes_no_period_by_its_bounces() {
    let dir = cli::tmpdir("track-chatter");
    let opt = dir.join("opt");
    cli::ok(&cli::direct_sticking_qc(&[], &opt));
    let out = dir.join("out");
    let r = cli::run(&[
        "track",
        opt.join("solution.json").to_str().unwrap(),
        "--periods",
        "3",
        "--out",
        out.to_str().unwrap(),
    ]);
    let read = |name: &str| -> serde_json::Value {
        serde_json::from_str(&std::fs::read_to_string(out.join(name)).unwrap()).unwrap()
    };
    let (tracking, traj) = (read("tracking.json"), read("trajectory.json"));
    // The chatter: impacts less than MIN_FLIGHT after a lift-off.
    let t: Vec<f64> = serde_json::from_value(traj["t"].clone()).unwrap();
    let mode: Vec<String> = serde_json::from_value(traj["mode"].clone()).unwrap();
    let contact = |i: usize| !mode[i].eq_ignore_ascii_case("free");
    let bounces = (1..t.len())
        .filter(|&i| contact(i) && !contact(i - 1))
        .filter(|&i| {
            (0..i)
                .rev()
                .find(|&k| contact(k))
                .is_some_and(|k| t[i] - t[k] < bf_control::MIN_FLIGHT)
        })
        .count();
    assert!(
        bounces >= 6,
        "{bounces} bounces: the plan no longer chatters"
    );
    let periods = tracking["periods"].as_array().unwrap();
    assert_eq!(periods.len(), 3, "{tracking}");
    let optimum: [f64; 3] = serde_json::from_value(tracking["optimum_mean_omega"].clone()).unwrap();
    let expect = recompute(&traj, optimum);
    for (p, e) in periods.iter().zip(&expect) {
        let (start, end) = (p["start"].as_f64().unwrap(), p["end"].as_f64().unwrap());
        assert!(end - start > 2.0 * bf_control::MIN_FLIGHT, "{p}");
        let err = p["omega_error"].as_f64().unwrap();
        assert!((err - e[3]).abs() <= 1e-12 * (1.0 + e[3]), "{p} vs {e:?}");
    }
    assert!(*t.last().unwrap() >= periods[2]["end"].as_f64().unwrap());
    // The run does not execute the plan, and says so: its first impact is a touch that the
    // finger flies on from, and the simulator held the chattering contact while the ball
    // pulled the finger (the Zeno fallback).
    assert_eq!(tracking["lost_ball"], true, "{tracking}");
    assert_eq!(periods[0]["contact"], false, "{tracking}");
    assert!(!tracking["held_contact"].is_null(), "{tracking}");
    assert_eq!(r.status.code(), Some(1));
    assert!(out.join("FAILED").exists());
    std::fs::remove_dir_all(&dir).ok();
}

/// `optimize --hops 0 --problem NAME --impact-law stick` (the 32-start search of the paper's
/// problem that `paper` runs; the global
/// search's lower optima are taps that a Newton plant cannot execute, BENCHMARKS.md "Closed
/// loop: a continuous saturated command") then `track --controller hybrid --periods 50`
/// on its solution, as a user runs them; returns tracking.json.
fn default_optimum_tracked(
    problem: &str,
    controllers: &[&str],
    periods: usize,
) -> Vec<serde_json::Value> {
    let dir = cli::tmpdir(&format!("target-{problem}"));
    let sol = dir.join("opt");
    let r = cli::run(&[
        "optimize",
        "--hops",
        "0",
        "--problem",
        problem,
        "--impact-law",
        "stick",
        "--out",
        sol.to_str().unwrap(),
    ]);
    assert!(r.status.success(), "{}", String::from_utf8_lossy(&r.stderr));
    let out = dir.join("track");
    let periods = periods.to_string();
    let mut records = Vec::new();
    for controller in controllers {
        let r = cli::run(&[
            "track",
            sol.join("solution.json").to_str().unwrap(),
            "--controller",
            controller,
            "--periods",
            &periods,
            "--out",
            out.to_str().unwrap(),
        ]);
        assert!(
            r.status.success(),
            "{problem} {controller}: {}",
            String::from_utf8_lossy(&r.stderr)
        );
        let text = std::fs::read_to_string(out.join("tracking.json")).unwrap();
        records.push(serde_json::from_str(&text).unwrap());
    }
    std::fs::remove_dir_all(&dir).ok();
    records
}

/// The nominal target: 50 periods of the default `periodic-qc` and
/// `periodic-cot-human` optima on their own scene with Newton's impact law, every period with
/// contact and an ω error ≤ 2 %. Before the contact-point loop the human finger's optimum
/// stayed at 4.9–5.8 % (the slip after each Newton impact displaces the contact point, and the
/// ball leaves with ω ⊥ the wrong r_c); before the clearance guard the finger touched the ball
/// again 86 ms after lift-off, where the optimum passes within 0.8 mm of it. The QC optimum
/// meets the target inside the paper's torque bound; the human finger's COT optimum only
/// without it (the slip after its Newton impacts, 5 m/s, needs up to 7 N m to recover from;
/// saturated at 1 N m the finger cannot stay on the ball). Slow (two default searches, about
/// 1–2 min).
#[test]
#[ignore = "two default searches and 50-period runs, about 1-2 min; run with `cargo test \
            --release --test track default_optima_meet -- --ignored`"]
fn default_optima_meet_the_nominal_target_for_fifty_periods() {
    let runs = default_optimum_tracked("periodic-qc", &["hybrid", "hybrid-unbounded"], 50)
        .into_iter()
        .map(|t| ("periodic-qc", t))
        .chain(
            default_optimum_tracked("periodic-cot-human", &["hybrid-unbounded"], 50)
                .into_iter()
                .map(|t| ("periodic-cot-human", t)),
        );
    for (problem, t) in runs {
        assert_eq!(t["impact_law"], "newton");
        assert_eq!(t["lost_ball"], false, "{problem}: {}", t["lost_reason"]);
        let periods = t["periods"].as_array().unwrap();
        assert_eq!(periods.len(), 50, "{problem}");
        for (k, p) in periods.iter().enumerate() {
            let e = p["omega_error"].as_f64().unwrap();
            eprintln!("{problem} period {}: {:.3} %", k + 1, 100.0 * e);
            assert!(
                p["contact"] == true && e <= 0.02,
                "{problem} period {k}: {p}"
            );
        }
    }
}

/// The perturbed-plant target over 50 periods: every plant of the robustness table
/// (ball mass ×1.1, μ_s and μ_k ×0.8, socket damping ×1.5, link masses ×1.05, all four, the
/// max-dissipation impact law), contact in every period and an ω error ≤ 5 % from the 4th
/// period to the 50th, for the default `periodic-qc` optimum with the bounded hybrid
/// controller and the default `periodic-cot-human` optimum with the unbounded one (under the
/// 1 N m bound it cannot survive even the nominal plant's Newton impacts, decision 0017).
/// The human finger's plants that change the flight's decay time I_b / D (ball mass, socket
/// damping, all four) met it only once the outer loop measured its sensitivity ρ and its
/// offset rolled the contact point (decision 0026; before: 9.4 %, 28 %, 22 %); the damping
/// plant's 4th period is the closest, measured 4.90 %. The bounded `periodic-cot-human` and
/// the unbounded `periodic-cot` runs are printed for BENCHMARKS.md, not asserted. Slow
/// (three default searches, 24 runs of 50 periods, about 8 min).
#[test]
#[ignore = "three default searches and 24 runs of 50 periods, about 8 min; run with \
            `cargo test --release --test track perturbed_plants -- --ignored --nocapture`"]
fn perturbed_plants_meet_the_robustness_target_for_fifty_periods() {
    use ball_finger::paper::closed_loop::robustness_rows;
    let mut failures = Vec::new();
    for (problem, controller, asserted) in [
        ("periodic-qc", ControllerKind::Hybrid, true),
        ("periodic-cot-human", ControllerKind::HybridUnbounded, true),
        ("periodic-cot-human", ControllerKind::Hybrid, false),
        ("periodic-cot", ControllerKind::HybridUnbounded, false),
    ] {
        let sol = cli::multistart_optimum(problem, &[]);
        for r in robustness_rows(&sol, controller, 50, None) {
            eprintln!("{problem} {}: {r:?}", controller.name());
            if asserted && !r.meets_target {
                failures.push(format!("{problem} {}", r.plant));
            }
        }
    }
    assert!(failures.is_empty(), "{failures:?}");
}

/// The report's closed-loop parts on the QC optimum: the robustness table (`track
/// --robustness`) applies every perturbation (an edit that no longer matches the paper scene
/// is an error, so a changed scene file cannot silently turn a row into the nominal plant) and
/// meets the target in every row, its JSON verdict agreeing with its own figures and
/// its markdown table; the comparison writes the Fig. 17 counterpart with one series per
/// controller run.
#[test]
fn report_tables_run_every_plant_and_controller() {
    use ball_finger::paper::closed_loop::comparison_markdown;
    use ball_finger::pipeline::SolutionIo;
    let work = cli::tmpdir("robustness");
    let sol_path = work.join("solution.json");
    cli::qc_optimum().write_json(&sol_path).unwrap();
    let robustness = |periods: &str, out: &std::path::Path| {
        cli::run(&[
            "track",
            sol_path.to_str().unwrap(),
            "--robustness",
            "--periods",
            periods,
            "--out",
            out.to_str().unwrap(),
        ])
    };
    let out = work.join("out");
    let r = robustness("5", &out);
    assert!(r.status.success(), "{}", String::from_utf8_lossy(&r.stderr));
    let md = std::fs::read_to_string(out.join("robustness.md")).unwrap();
    let json: serde_json::Value =
        serde_json::from_slice(&std::fs::read(out.join("robustness.json")).unwrap()).unwrap();
    let rows = json.as_array().unwrap();
    assert_eq!(rows.len(), 6, "{json}");
    for row in rows {
        let f = |k: &str| row[k].as_f64().unwrap_or(f64::NAN);
        assert_eq!(row["completed_periods"], 5, "{row}");
        assert_eq!(row["contact_every_period"], true, "{row}");
        assert!(f("max_error_from_fourth") <= 0.05, "{row}");
        assert_eq!(row["meets_target"], true, "{row}");
        assert!(f("max_abs_tau") <= 1.0, "{row}");
        let plant = row["plant"].as_str().unwrap();
        let line = md
            .lines()
            .find(|l| l.starts_with(&format!("| {plant} |")))
            .unwrap_or_else(|| panic!("{plant} not in {md}"));
        assert!(
            line.contains("5 of 5") && line.contains("| yes |"),
            "{line}"
        );
        assert!(!line.contains('⚑'), "{line}");
    }
    // A robustness run with too few periods for the 4th-period window is refused before any
    // work: a usage error, and nothing written.
    let short = work.join("short");
    let r = robustness("2", &short);
    assert_eq!(r.status.code(), Some(2));
    assert!(!short.exists());
    std::fs::remove_dir_all(&work).ok();
    let dir = cli::tmpdir("fig17-closed");
    let md = comparison_markdown("periodic-qc", cli::qc_optimum(), 3, Some(&dir)).unwrap();
    for name in ["open-loop", "pd", "hybrid", "hybrid-unbounded"] {
        assert!(md.contains(&format!("| {name} |")), "{md}");
    }
    let svg = std::fs::read_to_string(dir.join("fig17_closed_loop_periodic-qc.svg")).unwrap();
    assert!(svg.contains("hybrid-unbounded") && svg.contains("open-loop"));
    std::fs::remove_dir_all(&dir).ok();
}

/// The robustness table's six plants and the comparison's four controllers run in parallel;
/// both tables are the same, bit for bit, on one thread and on two (each row an independent
/// run, collected in the table's order).
#[test]
fn the_report_tables_are_the_same_on_one_thread_and_on_two() {
    use ball_finger::paper::closed_loop::{comparison_markdown, robustness_rows};
    let tables = |threads: usize| {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        pool.install(|| {
            let rows = robustness_rows(cli::qc_optimum(), ControllerKind::Hybrid, 3, None);
            let comparison = comparison_markdown("periodic-qc", cli::qc_optimum(), 3, None);
            (serde_json::to_string(&rows).unwrap(), comparison.unwrap())
        })
    };
    let one = tables(1);
    assert!(one.0.contains("all four"), "{}", one.0);
    assert!(one.1.contains("| hybrid-unbounded |"), "{}", one.1);
    assert_eq!(one, tables(2));
}

/// A long run is not cut short by the simulator's step budget: the stored human-finger plan
/// takes some 3 300–3 900 attempted steps a period in closed loop, so 300 periods and their
/// horizon's margin need more than the simulator's default budget of 10⁶ steps, and get
/// [`tracking_step_budget`]'s instead. With the default budget `track --periods 300` stopped
/// at t = 3 469 s, after all 300 periods but before the end of its horizon, and reported the
/// run as a lost ball. Slow (about half a minute, some 1.4 GB of samples).
#[test]
#[ignore = "a 300-period run, about 30 s; run with `cargo test --release --test track \
            a_long_run -- --ignored`"]
fn a_long_run_is_not_cut_by_the_step_budget() {
    use ball_finger::paper::closed_loop::tracking_step_budget;
    let path = cli::root().join("data/optima/periodic-cot-human-plan/solution.json");
    let sol = ball_finger::pipeline::OcpSolution::read_json(&path).unwrap();
    let plant = solution_model::<3>(&sol).unwrap().0;
    let periods = 300;
    let t = run_tracking(
        &sol,
        ControllerKind::Hybrid,
        periods,
        plant,
        ImpactLaw::Newton,
    )
    .unwrap();
    let stats = &t.output.stats;
    let steps = stats.accepted_steps + stats.rejected_steps;
    assert!(
        steps > SimSettings::default().max_steps && steps <= tracking_step_budget(periods),
        "{steps} steps"
    );
    assert_eq!(t.lost, None);
    assert_eq!(t.periods.len(), periods);
    assert!(t.periods.iter().all(|p| p.contact));
}

/// A plant with less friction (μ_s = μ_k = 0.5) makes the `periodic-qc` plan's stick phase
/// chatter, and the simulator's Zeno fallback holds the contact, at times while the ball pulls
/// the finger. `track` must not report that as tracking (decision record 0086): it exits 1, and
/// its `held_contact` time is what `trajectory.json` shows, recomputed here as the steps
/// integrated in contact with λ_n below −1e-6 of the largest contact force: at either end
/// inside the holds `summary.json` lists (`contact_holds`), at their start outside them.
#[test]
fn a_contact_held_while_the_ball_pulls_the_finger_is_no_result() {
    let dir = cli::tmpdir("held-contact");
    let text = std::fs::read_to_string(cli::root().join("scenes/paper.toml")).unwrap();
    let text = text
        .replace("mu_s = 0.8", "mu_s = 0.5")
        .replace("mu_k = 0.6", "mu_k = 0.5");
    let plant = dir.join("paper_mu05.toml");
    std::fs::write(&plant, text).unwrap();
    let out = dir.join("out");
    let r = cli::run(&[
        "track",
        "data/optima/periodic-qc-plan/solution.json",
        "--plant-scene",
        plant.to_str().unwrap(),
        "--periods",
        "3",
        "--out",
        out.to_str().unwrap(),
    ]);
    let stderr = String::from_utf8_lossy(&r.stderr);
    assert_eq!(r.status.code(), Some(1), "{stderr}");
    assert!(stderr.contains("contact was held"), "{stderr}");
    let read = |name: &str| -> serde_json::Value {
        serde_json::from_str(&std::fs::read_to_string(out.join(name)).unwrap()).unwrap()
    };
    let (tracking, traj) = (read("tracking.json"), read("trajectory.json"));
    // Friction is a parameter the model applies outside the kernels: the compiled ones run.
    assert_eq!(read("summary.json")["kernels"], "compiled");
    let message = tracking["held_contact"].as_str().expect("held_contact");
    let t: Vec<f64> = serde_json::from_value(traj["t"].clone()).unwrap();
    let mode: Vec<String> = serde_json::from_value(traj["mode"].clone()).unwrap();
    let d = traj["derived"].as_array().unwrap();
    let lambda_n = |i: usize| d[i]["lambda_n"].as_f64().unwrap_or(f64::NAN);
    let contact = |i: usize| !mode[i].eq_ignore_ascii_case("free");
    let force = (0..t.len())
        .filter(|&i| contact(i))
        .map(|i| {
            let l: Vec<f64> = serde_json::from_value(d[i]["lambda"].clone()).unwrap();
            l.iter().map(|v| v * v).sum::<f64>().sqrt()
        })
        .fold(0.0, f64::max);
    let holds: Vec<[f64; 2]> =
        serde_json::from_value(read("summary.json")["contact_holds"].clone()).unwrap();
    let in_hold = |i: usize| holds.iter().any(|h| t[i] < h[1] && t[i + 1] > h[0]);
    let pull = |i: usize| {
        if in_hold(i) {
            lambda_n(i).min(lambda_n(i + 1))
        } else {
            lambda_n(i)
        }
    };
    let held: f64 = (0..t.len().saturating_sub(1))
        .filter(|&i| contact(i) && mode[i + 1] == mode[i] && t[i + 1] > t[i])
        .filter(|&i| pull(i) < -1e-6 * force)
        .map(|i| t[i + 1] - t[i])
        .sum();
    assert!(held > 1e-3, "{held} s held: the plant no longer pulls");
    assert!(
        message.contains(&format!("for {held:.4} s")),
        "{message} against {held:.4} s"
    );
    std::fs::remove_dir_all(&dir).ok();
}

/// `track` says which kernels its plant ran on, as `simulate` does: the compiled ones for the
/// plan's own scene, interpreted ones for a plant whose geometry differs (a larger ball), in
/// `summary.json` (`kernels`) and on stdout.
#[test]
fn track_says_which_kernels_the_plant_ran_on() {
    let dir = cli::tmpdir("track-kernels");
    let plan = "data/optima/periodic-qc-plan/solution.json";
    let own = dir.join("own");
    let r = cli::run(&[
        "track",
        plan,
        "--periods",
        "1",
        "--out",
        own.to_str().unwrap(),
    ]);
    let stdout = String::from_utf8_lossy(&r.stdout);
    assert!(r.status.success(), "{}", String::from_utf8_lossy(&r.stderr));
    assert!(stdout.contains("(compiled kernels)"), "{stdout}");
    let kernels = |dir: &std::path::Path| -> serde_json::Value {
        let s: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(dir.join("summary.json")).unwrap())
                .unwrap();
        s["kernels"].clone()
    };
    assert_eq!(kernels(&own), "compiled");
    let text = std::fs::read_to_string(cli::root().join("scenes/paper.toml")).unwrap();
    assert!(text.contains("radius = 1.0"));
    let plant = dir.join("paper_r105.toml");
    std::fs::write(&plant, text.replace("radius = 1.0", "radius = 1.05")).unwrap();
    let other = dir.join("other");
    let r = cli::run(&[
        "track",
        plan,
        "--plant-scene",
        plant.to_str().unwrap(),
        "--periods",
        "1",
        "--out",
        other.to_str().unwrap(),
    ]);
    // The larger ball may well be missed; the set is written either way.
    let stdout = String::from_utf8_lossy(&r.stdout);
    assert!(
        stdout.contains("(interpreted kernels)"),
        "{stdout}\n{}",
        String::from_utf8_lossy(&r.stderr)
    );
    assert_eq!(kernels(&other), "interpreted");
    std::fs::remove_dir_all(&dir).ok();
}

/// `track --robustness` of a plan whose solve stopped before converging says so, on stderr and
/// at the head of robustness.md, as a plain `track` run does: the table measures where that
/// solve stopped, not an optimum.
#[test]
fn robustness_of_an_unconverged_plan_is_flagged() {
    let dir = cli::tmpdir("track-unconverged");
    let plan = dir.join("plan");
    std::fs::create_dir_all(&plan).unwrap();
    let stored = cli::root().join("data/optima/periodic-qc-plan");
    for f in ["solution.json", "solution-internals.json"] {
        std::fs::copy(stored.join(f), plan.join(f)).unwrap();
    }
    let path = plan.join("solution.json");
    let mut sol: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&path).unwrap()).unwrap();
    assert_eq!(sol["status"], "Solved");
    sol["status"] = serde_json::json!("MaxIterations");
    std::fs::write(&path, sol.to_string()).unwrap();
    let out = dir.join("rob");
    let r = cli::run(&[
        "track",
        path.to_str().unwrap(),
        "--robustness",
        "--periods",
        "4",
        "--out",
        out.to_str().unwrap(),
    ]);
    let stderr = String::from_utf8_lossy(&r.stderr);
    assert!(
        stderr.contains("MaxIterations") && stderr.contains("not an optimum"),
        "{stderr}"
    );
    let md = std::fs::read_to_string(out.join("robustness.md")).unwrap();
    assert!(
        md.starts_with("**Warning**") && md.contains("MaxIterations"),
        "{md}"
    );
}
