//! Period figures of a run (`period_metrics`): periods from impact to impact, a bounce not
//! counted, on sampled runs whose mean ω is known in closed form.

use bf_control::{MAX_PERIOD_RATIO, MIN_FLIGHT, MIN_PERIOD_RATIO, PeriodStarts, period_metrics};
use bf_model::Mode;

/// A sampled run: times, plant modes, ball angular velocities and torques.
type Run = (Vec<f64>, Vec<Mode>, Vec<[f64; 3]>, Vec<Vec<f64>>);

/// A run sampled every `dt` from 0 to `t_end`, in contact on the intervals `contact` (start,
/// end; Stick) and free elsewhere, with ω(t) = (0, 0, a + b t), which the trapezoidal rule
/// integrates exactly: the mean over [s, e) is a + b (s + e) / 2.
fn run(contact: &[(f64, f64)], dt: f64, t_end: f64, (a, b): (f64, f64)) -> Run {
    let mut t: Vec<f64> = (0..=(t_end / dt).round() as usize)
        .map(|k| k as f64 * dt)
        .collect();
    // The event times themselves are samples, as the simulator records them.
    for &(s, e) in contact {
        t.extend([s, e]);
    }
    t.sort_by(f64::total_cmp);
    t.dedup();
    let mode = t
        .iter()
        .map(|&x| {
            if contact.iter().any(|&(s, e)| s <= x && x < e) {
                Mode::Stick
            } else {
                Mode::Free
            }
        })
        .collect();
    let omega = t.iter().map(|&x| [0.0, 0.0, a + b * x]).collect();
    // |τ| grows with t: a period's largest is at its last sample, before the next period's
    // impact.
    let tau = t.iter().map(|&x| vec![0.5 + 0.1 * x, -0.5]).collect();
    (t, mode, omega, tau)
}

#[test]
fn a_bounce_is_part_of_its_contact_phase_not_a_period() {
    // Contacts at 0.3, 1.3 and 2.3 s, each 0.2 s long; the second ends in a bounce: the
    // finger leaves at 1.5 s, strikes again 5 µs later and stays 0.01 s more.
    let bounce = 1.5 + 5e-6;
    let contact = [
        (0.3, 0.5),
        (1.3, 1.5),
        (bounce, bounce + 0.01),
        (2.3, 2.5),
        (3.3, 3.5),
    ];
    let (a, b) = (1.0, 0.25);
    let (t, mode, omega, tau) = run(&contact, 1e-3, 3.6, (a, b));
    let optimum = [0.0, 0.0, 1.5];
    let periods = period_metrics(&t, &mode, &omega, &tau, optimum);
    let ends: Vec<(f64, f64)> = periods.iter().map(|p| (p.start, p.end)).collect();
    assert_eq!(ends, [(0.3, 1.3), (1.3, 2.3), (2.3, 3.3)]);
    for p in &periods {
        let mean = a + b * 0.5 * (p.start + p.end);
        assert!((p.mean_omega[2] - mean).abs() < 1e-12, "{p:?}");
        assert!(
            (p.omega_error - (mean - 1.5).abs() / 1.5).abs() < 1e-12,
            "{p:?}"
        );
        assert!(p.contact);
        // The sample at p.end is the next period's impact, not this period's.
        let last = t
            .iter()
            .copied()
            .filter(|&x| x < p.end)
            .fold(p.start, f64::max);
        assert!(last < p.end && last > p.end - 2e-3, "{last} {p:?}");
        assert!((p.max_abs_tau - (0.5 + 0.1 * last)).abs() < 1e-12, "{p:?}");
    }
    // The bounce's contact is the second period's: 0.2 + 0.01 s of stick.
    assert!(
        (periods[1].stick_time - 0.21).abs() < 1e-9,
        "{:?}",
        periods[1]
    );
    assert!(
        (periods[0].stick_time - 0.2).abs() < 1e-9,
        "{:?}",
        periods[0]
    );
}

#[test]
fn a_flight_of_min_flight_starts_a_period_and_a_shorter_one_does_not() {
    for (gap, new_period) in [
        (1.01 * MIN_FLIGHT, true),
        (0.99 * MIN_FLIGHT, false),
        (1e-6, false),
    ] {
        let mut s = PeriodStarts::default();
        // Lead-in flight, then the first impact: a period starts whatever the flight's length.
        assert!(!s.starts(0.0, Mode::Free));
        assert!(s.starts(1e-6, Mode::Slip));
        assert!(!s.starts(0.1, Mode::Stick));
        assert!(!s.starts(0.1 + gap / 2.0, Mode::Free));
        assert_eq!(s.starts(0.1 + gap, Mode::Slip), new_period, "gap {gap}");
        // Contact after contact is never a new period.
        assert!(!s.starts(0.2, Mode::Stick));
    }
    // A run that starts in contact starts a period at its first sample.
    let mut s = PeriodStarts::default();
    assert!(s.starts(0.0, Mode::Stick));
    assert!(!s.starts(0.1, Mode::Stick));
}

#[test]
fn chattering_alone_completes_no_period() {
    // The finger strikes at 0.3 s and chatters for 22 µs (impacts every 5.7 µs, as a sticking
    // plan of the paper's finger does on the Newton plant): one period start, no period.
    let mut contact = Vec::new();
    let mut x = 0.3;
    for _ in 0..7 {
        contact.push((x, x + 1e-7));
        x += 5.7e-6;
    }
    let (t, mode, omega, tau) = run(&contact, 1e-3, 0.5, (1.0, 0.0));
    assert!(period_metrics(&t, &mode, &omega, &tau, [0.0, 0.0, 1.0]).is_empty());
    let mut s = PeriodStarts::default();
    let starts = t
        .iter()
        .zip(&mode)
        .filter(|&(&x, &m)| s.starts(x, m))
        .count();
    assert_eq!(starts, 1);
}

#[test]
fn a_period_that_misses_the_ball_or_only_touches_it_has_no_contact() {
    // A plan of period 1 s with a 0.2 s contact phase. The finger misses the contact at
    // 2.3 s, so the period from 1.3 s lasts 2 s; the others execute the plan.
    let contact = [(0.3, 0.5), (1.3, 1.5), (3.3, 3.5), (4.3, 4.5)];
    let (t, mode, omega, tau) = run(&contact, 1e-3, 4.6, (1.0, 0.0));
    let periods = period_metrics(&t, &mode, &omega, &tau, [0.0, 0.0, 1.0]);
    let ends: Vec<(f64, f64)> = periods.iter().map(|p| (p.start, p.end)).collect();
    assert_eq!(ends, [(0.3, 1.3), (1.3, 3.3), (3.3, 4.3)]);
    // Every period starts at an impact and stays on the ball for 0.2 s.
    assert!(periods.iter().all(|p| p.contact));
    let verdicts: Vec<bool> = periods
        .iter()
        .map(|p| p.contact_failure(1.0).is_some())
        .collect();
    assert_eq!(verdicts, [false, true, false]);
    let why = periods[1].contact_failure(1.0).unwrap();
    assert!(why.contains("2.00 times"), "{why}");
    // A period just below MAX_PERIOD_RATIO plans passes; one at it does not; and the same
    // the other way: one just above MIN_PERIOD_RATIO plans passes, one at it does not.
    let p = &periods[0];
    assert!(p.contact_failure(1.0 / (MAX_PERIOD_RATIO - 1e-9)).is_none());
    assert!(p.contact_failure(1.0 / MAX_PERIOD_RATIO).is_some());
    assert!(p.contact_failure(1.0 / (MIN_PERIOD_RATIO + 1e-9)).is_none());
    let why = p.contact_failure(1.0 / MIN_PERIOD_RATIO).unwrap();
    assert!(why.contains("struck the ball again"), "{why}");
    assert!(why.contains("0.33 times"), "{why}");

    // The impact at 1.3 s lets go at once: its sample in Stick is followed by a Free sample
    // at the same time (the lift-off event), so the period holds no time on the ball.
    let contact = [(0.3, 0.5), (1.3, 1.3 + 1e-3), (2.3, 2.5), (3.3, 3.5)];
    let (mut t, mut mode, mut omega, mut tau) = run(&contact, 1e-3, 3.6, (1.0, 0.0));
    let k = t.iter().position(|&x| x == 1.3).unwrap();
    assert_eq!((mode[k], mode[k + 1]), (Mode::Stick, Mode::Free));
    t[k + 1] = t[k];
    t.insert(k + 2, 1.3 + 1e-3);
    mode.insert(k + 2, Mode::Free);
    omega.insert(k + 2, omega[k + 1]);
    tau.insert(k + 2, tau[k + 1].clone());
    let periods = period_metrics(&t, &mode, &omega, &tau, [0.0, 0.0, 1.0]);
    let touched = periods.iter().find(|p| p.start == 1.3).unwrap();
    assert_eq!(touched.stick_time + touched.slip_time, 0.0);
    assert!(!touched.contact);
    let why = touched.contact_failure(1.0).unwrap();
    assert!(why.contains("only touched"), "{why}");

    // A finger that bounces on the ball (leaves and strikes again within MIN_FLIGHT, never a
    // step in contact) has a contact phase: the bounces are its contact, as on a Newton plant.
    let mut x = 1.3;
    let mut bounces = Vec::new();
    for _ in 0..5 {
        bounces.push((x, x));
        x += 0.2 * MIN_FLIGHT;
    }
    let contact = [(0.3, 0.5), (2.3, 2.5)];
    let (mut t, mut mode, mut omega, mut tau) = run(&contact, 1e-3, 2.6, (1.0, 0.0));
    for &(b, _) in &bounces {
        // Each bounce: a contact sample and a free one at the same instant.
        let k = t.iter().position(|&s| s > b).unwrap();
        for m in [Mode::Free, Mode::Stick] {
            t.insert(k, b);
            mode.insert(k, m);
            omega.insert(k, omega[k - 1]);
            tau.insert(k, tau[k - 1].clone());
        }
    }
    let periods = period_metrics(&t, &mode, &omega, &tau, [0.0, 0.0, 1.0]);
    let ends: Vec<(f64, f64)> = periods.iter().map(|p| (p.start, p.end)).collect();
    assert_eq!(ends, [(0.3, 1.3), (1.3, 2.3)]);
    let chatter = &periods[1];
    assert_eq!(chatter.stick_time + chatter.slip_time, 0.0);
    assert!(
        chatter.contact && chatter.contact_failure(1.0).is_none(),
        "{chatter:?}"
    );
    assert!(
        periods
            .iter()
            .filter(|p| p.start != 1.3)
            .all(|p| p.contact && p.contact_failure(1.0).is_none())
    );
}

#[test]
fn a_mode_passed_through_at_one_instant_adds_no_torque() {
    // Contacts at 0.3 and 1.3 s; the first lets go at 0.5 s through a slip of no length, as the
    // simulator records a chained stick → slip → free lift-off: three samples at 0.5 s.
    let (mut t, mut mode, mut omega, mut tau) =
        run(&[(0.3, 0.5), (1.3, 1.5)], 1e-3, 2.4, (1.0, 0.0));
    let k = t.iter().position(|&x| x == 0.5).unwrap();
    assert_eq!(mode[k], Mode::Free);
    for (at, m) in [(k, Mode::Stick), (k + 1, Mode::Slip)] {
        t.insert(at, 0.5);
        mode.insert(at, m);
        omega.insert(at, omega[k]);
        tau.insert(at, vec![0.5 + 0.1 * 0.5, -0.5]);
    }
    // The slip's τ (the slip law's, applied for no time) is far above every other sample's.
    tau[k + 1] = vec![9.0, -9.0];
    let periods = period_metrics(&t, &mode, &omega, &tau, [0.0, 0.0, 1.0]);
    assert_eq!(periods.len(), 1);
    let p = &periods[0];
    assert_eq!((p.start, p.end), (0.3, 1.3));
    assert!(
        (p.stick_time - 0.2).abs() < 1e-9 && p.slip_time == 0.0,
        "{p:?}"
    );
    // The period's largest |τ| is that of its last sample before 1.3 s.
    let last = t.iter().copied().filter(|&x| x < 1.3).fold(0.0, f64::max);
    assert!((p.max_abs_tau - (0.5 + 0.1 * last)).abs() < 1e-12, "{p:?}");
    // A sample at the lift-off that begins or ends a stretch of time still counts.
    tau[k] = vec![7.0, 0.0];
    let periods = period_metrics(&t, &mode, &omega, &tau, [0.0, 0.0, 1.0]);
    assert_eq!(periods[0].max_abs_tau, 7.0);
}
