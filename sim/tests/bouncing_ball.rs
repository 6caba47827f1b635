//! Bouncing ball: a point mass dropped onto a plane with Newton restitution v⁺ = −e v⁻.
//!
//! Without drag the motion between impacts is a parabola, so the impact times form a geometric
//! series with a closed form (t_{k+1} = t_k + 2eᵏu₁/g) and an accumulation point t_∞. DOPRI5 is
//! exact on quadratics, so any error here is an event-location error. The reset leaves the state
//! exactly on the guard surface (y = 0), the case that made diffsol 0.18 miss the next crossing
//! (`docs/decisions/0003-own-integrators.md`): a bug there shows up as missing or duplicated impacts. With huge steps
//! (h_max = 100) several flights would fit in one step, so the masking/probing logic is what
//! finds them. e = 0 must go to Resting; e near 1 without a rest threshold must stop with the
//! Zeno error close to t_∞; with a rest threshold the number of bounces is known in closed form.

use bf_sim::toys::{BallMode, BouncingBall};
use bf_sim::{SampleKind, SimError, SimSettings, simulate, simulate_until};

const G: f64 = 9.81;

fn ball(e: f64) -> BouncingBall {
    BouncingBall {
        g: G,
        e,
        drag: 0.0,
        v_rest: None,
    }
}

fn check_impacts(b: &BouncingBall, set: SimSettings, n: usize, t_tol: f64) {
    let refs = b.reference_impacts(1.0, 0.0, n);
    let t_end = refs[n - 1].0 + 0.5 * (refs[n - 1].0 - refs[n - 2].0);
    let out = simulate(b, set, BallMode::Flight, 0.0, &[1.0, 0.0], t_end).expect("run succeeds");
    assert_eq!(out.events.len(), n, "impact count");
    for (k, (ev, &(t_ref, v_ref))) in out.events.iter().zip(&refs).enumerate() {
        assert!(
            (ev.t - t_ref).abs() <= t_tol,
            "impact {k}: t = {} vs {t_ref} (err {:e})",
            ev.t,
            ev.t - t_ref
        );
        assert!(
            (ev.x_post[1] - v_ref).abs() <= 1e-8 * v_ref.abs().max(1.0),
            "impact {k} v+"
        );
        assert_eq!(ev.x_post[0], 0.0);
        assert_eq!(ev.guard, "impact");
        // Pre-impact state is on the crossed side and within the event tolerance of y = 0.
        assert!(
            ev.x_pre[0] <= 0.0 && ev.x_pre[0] > -1e-9,
            "y- = {}",
            ev.x_pre[0]
        );
        assert!(!ev.chained);
    }
}

#[test]
fn impact_times_match_geometric_series() {
    check_impacts(&ball(0.5), SimSettings::default(), 8, 1e-11);
}

/// Steps of up to 100 s while flights last < 1 s: every flight after the first starts exactly on
/// y = 0 and lies inside the first sub-interval of its step, so only the start-on-surface logic
/// can find it (disabling the masking makes this test fail: all impacts after the first vanish).
/// A rest threshold between the 10th and 11th post-impact speeds ends the series, so t_end can
/// be far beyond the accumulation point.
#[test]
fn impacts_found_with_huge_steps_after_reset_on_surface() {
    let e: f64 = 0.7;
    let u1 = (2.0 * G).sqrt();
    let b = BouncingBall {
        v_rest: Some(libm::pow(e, 10.5) * u1),
        ..ball(e)
    };
    let set = SimSettings {
        h_max: 100.0,
        h_init: Some(50.0),
        ..SimSettings::default()
    };
    let out = simulate(&b, set, BallMode::Flight, 0.0, &[1.0, 0.0], 20.0).unwrap();
    let refs = b.reference_impacts(1.0, 0.0, 11);
    assert_eq!(out.events.len(), 11);
    for (k, (ev, &(t_ref, v_ref))) in out.events.iter().zip(&refs).enumerate() {
        assert!(
            (ev.t - t_ref).abs() < 1e-11,
            "impact {k}: {} vs {t_ref}",
            ev.t
        );
        if k < 10 {
            assert!((ev.x_post[1] - v_ref).abs() < 1e-9);
        }
    }
    assert_eq!(out.mode_final, BallMode::Resting);
    assert!(out.stats.accepted_steps < 40, "{:?}", out.stats);
}

#[test]
fn impacts_with_rk4_fixed_step() {
    // RK4 is exact on the parabola too; the Hermite interpolant is exact for cubics.
    let set = SimSettings {
        method: bf_sim::Method::Rk4 { h: 0.05 },
        ..SimSettings::default()
    };
    check_impacts(&ball(0.6), set, 6, 1e-11);
}

#[test]
fn zero_restitution_comes_to_rest() {
    let b = ball(0.0);
    let out = simulate(
        &b,
        SimSettings::default(),
        BallMode::Flight,
        0.0,
        &[2.0, 1.0],
        3.0,
    )
    .expect("run succeeds");
    let (t_ref, _) = b.flight(2.0, 1.0);
    assert_eq!(out.events.len(), 1);
    assert!((out.events[0].t - t_ref).abs() < 1e-11);
    assert_eq!(out.events[0].mode_after, Some(BallMode::Resting));
    assert_eq!(out.mode_final, BallMode::Resting);
    let last = out.trajectory.x.last().unwrap();
    assert_eq!(last, &vec![0.0, 0.0]);
    assert!((out.t_final - 3.0).abs() < 1e-15);
}

#[test]
fn zeno_accumulation_is_reported_near_t_infinity() {
    let b = ball(0.8);
    let t_inf = b.accumulation_time(1.0, 0.0);
    let fail = simulate(
        &b,
        SimSettings::default(),
        BallMode::Flight,
        0.0,
        &[1.0, 0.0],
        10.0,
    )
    .expect_err("must stop with Zeno");
    match fail.error {
        SimError::Zeno { t, count, .. } => {
            assert!(count > SimSettings::default().zeno_max_events);
            assert!(
                t < t_inf + 1e-3 && t > t_inf - 1e-2,
                "t = {t}, t_inf = {t_inf}"
            );
        }
        ref e => panic!("expected Zeno, got {e}"),
    }
    // The partial event log is right as long as flights are resolvable. Each located time is
    // on the crossed side, up to event_tol late, and the lateness accumulates over impacts.
    let refs = b.reference_impacts(1.0, 0.0, 60);
    let tol = SimSettings::default().event_tol;
    for (k, (ev, &(t_ref, _))) in fail.partial.events.iter().zip(&refs).enumerate() {
        let err = ev.t - t_ref;
        assert!(
            err > -tol && err < 5.0 * tol * (k + 1) as f64,
            "impact {k}: err {err:e}"
        );
    }
    assert!(fail.partial.events.len() > 60);
    assert!(fail.to_string().contains("Zeno"));
}

#[test]
fn rest_threshold_handles_accumulation() {
    let v_rest = 0.05;
    let b = BouncingBall {
        v_rest: Some(v_rest),
        ..ball(0.8)
    };
    // Impact k (0-based) has post-impact speed e^(k+1) u1; the first one below v_rest rests.
    let u1 = (2.0 * G).sqrt();
    let mut n = 1;
    while 0.8f64.powi(n) * u1 >= v_rest {
        n += 1;
    }
    let refs = b.reference_impacts(1.0, 0.0, n as usize);
    let out = simulate(
        &b,
        SimSettings::default(),
        BallMode::Flight,
        0.0,
        &[1.0, 0.0],
        6.0,
    )
    .expect("no Zeno with rest threshold");
    assert_eq!(out.events.len(), n as usize);
    assert_eq!(out.mode_final, BallMode::Resting);
    let last = out.events.last().unwrap();
    assert!((last.t - refs[n as usize - 1].0).abs() < 1e-10);
    assert_eq!(last.mode_after, Some(BallMode::Resting));
}

#[test]
fn drag_ball_impacts_match_reference() {
    let b = BouncingBall {
        drag: 0.3,
        ..ball(0.6)
    };
    let refs = b.reference_impacts(1.5, 0.5, 5);
    let set = SimSettings {
        rtol: 1e-12,
        atol: 1e-14,
        ..SimSettings::default()
    };
    let out = simulate(
        &b,
        set,
        BallMode::Flight,
        0.0,
        &[1.5, 0.5],
        refs[4].0 + 0.01,
    )
    .unwrap();
    assert_eq!(out.events.len(), 5);
    for (ev, &(t_ref, v_ref)) in out.events.iter().zip(&refs) {
        assert!((ev.t - t_ref).abs() < 1e-10, "{} vs {t_ref}", ev.t);
        assert!((ev.x_post[1] - v_ref).abs() < 1e-9);
    }
}

/// Error of the 3rd impact time of the drag ball decreases as rtol tightens.
#[test]
fn event_accuracy_improves_with_tolerance() {
    let b = BouncingBall {
        drag: 0.5,
        ..ball(0.7)
    };
    let t_ref = b.reference_impacts(1.0, 0.0, 3)[2].0;
    let mut errs = Vec::new();
    for rtol in [1e-4, 1e-6, 1e-8, 1e-10] {
        let set = SimSettings {
            rtol,
            atol: rtol * 1e-2,
            ..SimSettings::default()
        };
        let out = simulate(&b, set, BallMode::Flight, 0.0, &[1.0, 0.0], t_ref + 0.01).unwrap();
        assert_eq!(out.events.len(), 3);
        errs.push((out.events[2].t - t_ref).abs());
    }
    for w in errs.windows(2) {
        assert!(
            w[1] < w[0] || w[1] < 1e-12,
            "errors not decreasing: {errs:?}"
        );
    }
    assert!(errs[3] < 1e-9 && errs[0] > 10.0 * errs[3], "{errs:?}");
}

#[test]
fn trajectory_has_pre_and_post_samples_and_no_penetration() {
    let b = ball(0.5);
    let t_end = 0.99 * b.accumulation_time(1.0, 0.0);
    let out = simulate(
        &b,
        SimSettings::default(),
        BallMode::Flight,
        0.0,
        &[1.0, 0.0],
        t_end,
    )
    .unwrap();
    let pre = out.trajectory.indices_of(SampleKind::EventPre);
    let post = out.trajectory.indices_of(SampleKind::EventPost);
    assert_eq!(pre.len(), out.events.len());
    assert_eq!(post.len(), out.events.len());
    for (&i, &j) in pre.iter().zip(&post) {
        assert_eq!(j, i + 1);
        assert_eq!(out.trajectory.t[i], out.trajectory.t[j]);
    }
    for w in out.trajectory.t.windows(2) {
        assert!(w[1] >= w[0]);
    }
    for x in &out.trajectory.x {
        assert!(x[0] > -1e-9, "penetration y = {}", x[0]);
    }
}

/// A run ended by `simulate_until` is the whole run up to there: asked to stop once the
/// trajectory holds its third impact, the run ends right after it (the closed-form impact
/// times), without error, with the whole run's samples and events up to that point, bit for
/// bit; a condition that never holds gives the whole run.
#[test]
fn a_run_ended_early_is_a_prefix_of_the_whole_run() {
    let b = ball(0.5);
    let refs = b.reference_impacts(1.0, 0.0, 6);
    let t_end = refs[5].0 + 0.5 * (refs[5].0 - refs[4].0);
    let run = |stop_after: usize| {
        simulate_until(
            &b,
            SimSettings::default(),
            BallMode::Flight,
            0.0,
            &[1.0, 0.0],
            t_end,
            |tr| {
                tr.kind
                    .iter()
                    .filter(|k| **k == SampleKind::EventPre)
                    .count()
                    >= stop_after
            },
        )
        .expect("run succeeds")
    };
    let whole = simulate(
        &b,
        SimSettings::default(),
        BallMode::Flight,
        0.0,
        &[1.0, 0.0],
        t_end,
    )
    .expect("run succeeds");
    let ended = run(3);
    assert_eq!(ended.events.len(), 3);
    assert!(
        (ended.t_final - refs[2].0).abs() < 1e-9,
        "{} vs {}",
        ended.t_final,
        refs[2].0
    );
    assert!(!ended.terminated && whole.events.len() == 6);
    let n = ended.trajectory.t.len();
    assert!(n < whole.trajectory.t.len());
    assert_eq!(ended.trajectory.t[..], whole.trajectory.t[..n]);
    assert_eq!(ended.trajectory.x[..], whole.trajectory.x[..n]);
    assert_eq!(ended.events[..], whole.events[..3]);
    let never = run(usize::MAX);
    assert_eq!(never.trajectory.x, whole.trajectory.x);
    assert_eq!(never.t_final, whole.t_final);
}
