//! Event machinery on systems with trivially known guard roots (x = t along the flow).
//!
//! The guard (x − 1)² − 0.01 is positive, dips below zero on (0.9, 1.1) and comes back: two
//! crossings inside one large step. Direction filters must pick the right one; interior
//! sub-samples must see the dip (a scheme that only compares the step's end points sees two
//! positive values and misses both — shown by `event_subdivisions = 1`). Several guards in one
//! step must yield the earliest. Resets that keep landing beyond a guard must stop with the
//! chain limit instead of looping, and the step()/apply_reset() API must reproduce run() bit for
//! bit (determinism).

use bf_sim::{
    Direction, Guard, HybridSystem, SimError, SimSettings, Simulator, StopReason, Transition,
    simulate,
};

/// x' = 1 (x = t from x(0) = 0), guards supplied as functions of x. The mode is the bit mask
/// of directional guards that have fired: a fired directional guard is retired (its region is
/// left for good, as with a mode change), `Either` guards stay as crossing counters.
struct Line {
    guards: Vec<(Guard, GuardFn)>,
}

type GuardFn = fn(f64) -> f64;

impl Line {
    fn active(&self, mask: u32) -> Vec<usize> {
        (0..self.guards.len())
            .filter(|i| mask & (1 << i) == 0)
            .collect()
    }
}

impl HybridSystem for Line {
    type Mode = u32;
    fn dim(&self) -> usize {
        1
    }
    fn rhs(&self, _: u32, _: f64, _: &[f64], dx: &mut [f64]) -> Result<(), SimError> {
        dx[0] = 1.0;
        Ok(())
    }
    fn guards(&self, mask: u32) -> Vec<Guard> {
        self.active(mask)
            .into_iter()
            .map(|i| self.guards[i].0)
            .collect()
    }
    fn guard_values(&self, mask: u32, _: f64, x: &[f64], out: &mut [f64]) -> Result<(), SimError> {
        for (o, i) in out.iter_mut().zip(self.active(mask)) {
            *o = (self.guards[i].1)(x[0]);
        }
        Ok(())
    }
    fn reset(
        &self,
        mask: u32,
        j: usize,
        _: f64,
        _: &mut [f64],
    ) -> Result<Transition<u32>, SimError> {
        let i = self.active(mask)[j];
        Ok(Transition::To(
            if self.guards[i].0.direction == Direction::Either {
                mask
            } else {
                mask | (1 << i)
            },
        ))
    }
}

fn dip(x: f64) -> f64 {
    (x - 1.0) * (x - 1.0) - 0.01
}

/// One step covers [0, 2]: samples at 0, 0.5, 1, 1.5, 2.
fn one_big_step() -> SimSettings {
    SimSettings {
        h_init: Some(2.0),
        h_max: 2.0,
        ..SimSettings::default()
    }
}

fn event_times(sys: &Line, set: SimSettings) -> Vec<(f64, &'static str)> {
    let out = simulate(sys, set, 0, 0.0, &[0.0], 2.0).unwrap();
    out.events.iter().map(|e| (e.t, e.guard)).collect()
}

fn neg_dip(x: f64) -> f64 {
    -dip(x)
}

fn parabola(x: f64) -> f64 {
    x * (x - 1.0)
}

#[test]
fn double_crossing_in_one_step_and_direction_filters() {
    let cases: [(Guard, GuardFn, Vec<f64>); 3] = [
        (Guard::falling("dip"), dip, vec![0.9]),
        (Guard::rising("dip"), neg_dip, vec![0.9]),
        (Guard::either("dip"), dip, vec![0.9, 1.1]),
    ];
    for (guard, g, expect) in cases {
        let sys = Line {
            guards: vec![(guard, g)],
        };
        let ev = event_times(&sys, one_big_step());
        assert_eq!(ev.len(), expect.len(), "{guard:?}: {ev:?}");
        for ((t, _), te) in ev.iter().zip(&expect) {
            assert!((t - te).abs() < 1e-12, "{guard:?}: {t} vs {te}");
        }
    }
}

/// g = x(x − 1) starts exactly on its surface and first goes negative. As a Rising guard the
/// state moves into its valid region, so the start root must not fire and the genuine crossing
/// at x = 1 must be found; as a Falling guard the state slides into the triggered region and
/// must fire as soon as it leaves the `guard_zero_tol` band (x ≈ 1e-9).
#[test]
fn guard_starting_on_surface_direction_decides() {
    let rising = Line {
        guards: vec![(Guard::rising("p"), parabola)],
    };
    let ev = event_times(&rising, one_big_step());
    assert_eq!(ev.len(), 1);
    assert!((ev[0].0 - 1.0).abs() < 1e-12, "{ev:?}");
    let falling = Line {
        guards: vec![(Guard::falling("p"), parabola)],
    };
    let ev = event_times(&falling, one_big_step());
    assert_eq!(ev.len(), 1);
    let tol = SimSettings::default().guard_zero_tol;
    assert!(ev[0].0 > 0.5 * tol && ev[0].0 < 2.0 * tol, "{ev:?}");
}

#[test]
fn end_point_comparison_alone_misses_the_dip() {
    let sys = Line {
        guards: vec![(Guard::either("dip"), dip)],
    };
    let set = SimSettings {
        event_subdivisions: 1,
        ..one_big_step()
    };
    assert!(event_times(&sys, set).is_empty());
}

#[test]
fn earliest_of_several_guards_wins() {
    fn g_late(x: f64) -> f64 {
        x - 1.7
    }
    fn g_early(x: f64) -> f64 {
        0.3 - x
    }
    fn wide_dip(x: f64) -> f64 {
        (x - 1.0) * (x - 1.0) - 0.04
    }
    let sys = Line {
        guards: vec![
            (Guard::rising("late"), g_late),
            (Guard::falling("early"), g_early),
            (Guard::falling("dip"), wide_dip),
        ],
    };
    let ev = event_times(&sys, one_big_step());
    let names: Vec<_> = ev.iter().map(|e| e.1).collect();
    assert_eq!(names, vec!["early", "dip", "late"]);
    for ((t, _), te) in ev.iter().zip([0.3, 0.8, 1.7]) {
        assert!((t - te).abs() < 1e-12);
    }
}

/// Mode 0 has a guard crossing at x = 0.5; every reset goes to the next mode, and modes ≥ 1 have
/// a guard that is always beyond its zero: an endless instantaneous chain.
struct Chain;

impl HybridSystem for Chain {
    type Mode = u32;
    fn dim(&self) -> usize {
        1
    }
    fn rhs(&self, _: u32, _: f64, _: &[f64], dx: &mut [f64]) -> Result<(), SimError> {
        dx[0] = 1.0;
        Ok(())
    }
    fn guards(&self, _: u32) -> Vec<Guard> {
        vec![Guard::falling("g")]
    }
    fn guard_values(&self, m: u32, _: f64, x: &[f64], out: &mut [f64]) -> Result<(), SimError> {
        out[0] = if m > 0 { -1.0 } else { 0.5 - x[0] };
        Ok(())
    }
    fn reset(&self, m: u32, _: usize, _: f64, _: &mut [f64]) -> Result<Transition<u32>, SimError> {
        Ok(Transition::To(m + 1))
    }
}

#[test]
fn reset_loop_stops_with_chain_limit() {
    let set = SimSettings {
        max_chained_events: 5,
        ..SimSettings::default()
    };
    let fail = simulate(&Chain, set, 0, 0.0, &[0.0], 1.0).expect_err("loops");
    match fail.error {
        SimError::ChainLimit { t, count, .. } => {
            assert!((t - 0.5).abs() < 1e-12);
            assert_eq!(count, 6);
        }
        ref e => panic!("expected ChainLimit, got {e}"),
    }
    assert_eq!(fail.partial.events.len(), 6);
    assert!(fail.partial.events[1..].iter().all(|e| e.chained));
}

#[test]
fn step_api_reproduces_run_bitwise() {
    let sys = bf_sim::toys::BouncingBall {
        g: 9.81,
        e: 0.6,
        drag: 0.2,
        v_rest: None,
    };
    let set = SimSettings::default;
    let mut sim = Simulator::new(
        &sys,
        set(),
        bf_sim::toys::BallMode::Flight,
        0.0,
        &[1.0, 0.3],
        1.2,
    )
    .unwrap();
    let mut roots = 0;
    loop {
        match sim.step().unwrap() {
            StopReason::Step => {}
            StopReason::RootFound { t, name, .. } => {
                assert_eq!(name, "impact");
                assert_eq!(sim.t(), t);
                assert!(sim.x()[0] <= 0.0);
                roots += 1;
                sim.apply_reset().unwrap();
                assert!(sim.x()[1] > 0.0);
            }
            StopReason::TEndReached | StopReason::Terminated => break,
        }
    }
    let a = sim.finish();
    let b = simulate(
        &sys,
        set(),
        bf_sim::toys::BallMode::Flight,
        0.0,
        &[1.0, 0.3],
        1.2,
    )
    .unwrap();
    assert_eq!(roots, b.events.len());
    assert_eq!(a.trajectory.t.len(), b.trajectory.t.len());
    for (xa, xb) in a.trajectory.x.iter().zip(&b.trajectory.x) {
        for (u, v) in xa.iter().zip(xb) {
            assert_eq!(u.to_bits(), v.to_bits());
        }
    }
    for (ta, tb) in a.trajectory.t.iter().zip(&b.trajectory.t) {
        assert_eq!(ta.to_bits(), tb.to_bits());
    }
}

/// Rotation x' = −y, y' = x with a projection onto the unit circle after each step.
struct Circle;

impl HybridSystem for Circle {
    type Mode = ();
    fn dim(&self) -> usize {
        2
    }
    fn rhs(&self, _: (), _: f64, x: &[f64], dx: &mut [f64]) -> Result<(), SimError> {
        dx[0] = -x[1];
        dx[1] = x[0];
        Ok(())
    }
    fn project(&self, _: (), _: f64, x: &mut [f64]) -> Result<Option<f64>, SimError> {
        let r = libm::hypot(x[0], x[1]);
        x[0] /= r;
        x[1] /= r;
        Ok(Some(r - 1.0))
    }
    fn check_valid(&self, _: (), t: f64, x: &[f64]) -> Result<(), SimError> {
        if t > 5.0 && x[0] > 0.99 {
            return Err(SimError::InvalidState {
                t,
                mode: "()".into(),
                msg: "left the allowed arc".into(),
            });
        }
        Ok(())
    }
}

#[test]
fn projection_drift_is_reported_and_removed() {
    let set = SimSettings {
        rtol: 1e-5,
        atol: 1e-7,
        ..SimSettings::default()
    };
    let out = simulate(&Circle, set, (), 0.0, &[1.0, 0.0], 5.0).unwrap();
    // Drift per step is the local error of a tol-1e-5 method: nonzero, small.
    assert!(
        out.stats.max_drift > 0.0 && out.stats.max_drift < 1e-4,
        "{}",
        out.stats.max_drift
    );
    for (i, x) in out.trajectory.x.iter().enumerate().skip(1) {
        assert!((libm::hypot(x[0], x[1]) - 1.0).abs() < 1e-15);
        assert!(out.trajectory.drift[i].is_some());
    }
    let x = out.trajectory.x.last().unwrap();
    assert!((x[0] - libm::cos(5f64)).abs() < 1e-3 && (x[1] - libm::sin(5f64)).abs() < 1e-3);
}

#[test]
fn validity_failure_returns_partial_trajectory() {
    let fail = simulate(&Circle, SimSettings::default(), (), 0.0, &[1.0, 0.0], 10.0)
        .expect_err("leaves the arc after t = 2π");
    assert!(matches!(fail.error, SimError::InvalidState { .. }));
    let tr = &fail.partial.trajectory;
    let t_last = *tr.t.last().unwrap();
    assert!(
        t_last > 5.0 && t_last < 2.0 * std::f64::consts::PI,
        "{t_last}"
    );
    assert!(fail.t > t_last);
}
