//! Accuracy of the integrators on smooth problems with exact solutions.
//!
//! * Harmonic oscillator: the global error of adaptive DOPRI5 must fall as rtol tightens
//!   (1e-4 … 1e-10), and the number of steps must grow like rtol^(−1/5) (a 5th-order method);
//!   a wrong tableau coefficient drops the order and breaks both.
//! * Crossing oscillator: event times (k + ½)π located on the dense output to ~rtol.
//! * Pendulum: energy ½l²θ'² − gl cosθ is conserved; DOPRI5 at rtol 1e-10 keeps it to 1e-9
//!   relative over 20 s (and 100× better than at rtol 1e-6); RK4's global error falls ≈ 16×
//!   when h halves (4th order).
//! * Uniform output grid: dense-output samples at k·dt match cos/sin.

use bf_sim::toys::{CrossingOscillator, Oscillator, Pendulum};
use bf_sim::{Method, SampleKind, SimSettings, simulate};

fn osc_run(rtol: f64) -> (f64, usize) {
    let set = SimSettings {
        rtol,
        atol: rtol * 1e-3,
        h_max: 10.0,
        ..SimSettings::default()
    };
    let t_end = 10.0;
    let out = simulate(&Oscillator { omega: 2.0 }, set, (), 0.0, &[1.0, 0.0], t_end).unwrap();
    let x = out.trajectory.x.last().unwrap();
    let err = ((x[0] - libm::cos(2.0 * t_end)).powi(2)
        + (x[1] + 2.0 * libm::sin(2.0 * t_end)).powi(2))
    .sqrt();
    (err, out.stats.accepted_steps)
}

#[test]
fn dopri5_error_decreases_with_rtol_and_steps_scale_as_fifth_order() {
    let rtols = [1e-4, 1e-6, 1e-8, 1e-10];
    let runs: Vec<_> = rtols.iter().map(|&r| osc_run(r)).collect();
    for w in runs.windows(2) {
        assert!(w[1].0 < w[0].0 / 10.0, "errors {runs:?}");
    }
    // Steps ∝ rtol^(-1/5): over 6 decades, a factor 10^(6/5) ≈ 15.8.
    let ratio = runs[3].1 as f64 / runs[0].1 as f64;
    assert!(
        ratio > 8.0 && ratio < 30.0,
        "step ratio {ratio}, runs {runs:?}"
    );
    // Work-precision slope: log(err) vs log(steps) ≈ −5.
    let slope =
        libm::log(runs[3].0 / runs[1].0) / libm::log((runs[3].1 as f64) / (runs[1].1 as f64));
    assert!(slope < -3.5 && slope > -7.0, "slope {slope}");
}

#[test]
fn crossing_times_of_oscillator() {
    let w = 3.0;
    let set = SimSettings {
        rtol: 1e-10,
        atol: 1e-12,
        ..SimSettings::default()
    };
    let out = simulate(
        &CrossingOscillator { omega: w },
        set,
        (),
        0.0,
        &[1.0, 0.0],
        10.0,
    )
    .unwrap();
    let n = (10.0 * w / std::f64::consts::PI - 0.5).floor() as usize + 1;
    assert_eq!(out.events.len(), n);
    for (k, e) in out.events.iter().enumerate() {
        let te = (k as f64 + 0.5) * std::f64::consts::PI / w;
        assert!((e.t - te).abs() < 1e-8, "crossing {k}: {} vs {te}", e.t);
    }
}

fn pendulum_drift(rtol: f64) -> f64 {
    let p = Pendulum { g: 9.81, l: 0.7 };
    let x0 = [2.5, 0.0];
    let set = SimSettings {
        rtol,
        atol: rtol * 1e-2,
        h_max: 10.0,
        ..SimSettings::default()
    };
    let out = simulate(&p, set, (), 0.0, &x0, 20.0).unwrap();
    let e0 = p.energy(&x0);
    out.trajectory
        .x
        .iter()
        .map(|x| ((p.energy(x) - e0) / e0).abs())
        .fold(0.0, f64::max)
}

#[test]
fn pendulum_energy_conserved_dopri5() {
    let (loose, tight) = (pendulum_drift(1e-6), pendulum_drift(1e-10));
    assert!(tight < 1e-8, "relative energy drift {tight}");
    assert!(
        tight < loose / 100.0,
        "drift {tight:e} not proportional to tol ({loose:e})"
    );
}

#[test]
fn rk4_global_error_is_fourth_order() {
    let p = Pendulum { g: 9.81, l: 0.7 };
    let x0 = [1.0, 0.0];
    let t_end = 5.0;
    let reference = {
        let set = SimSettings {
            rtol: 1e-13,
            atol: 1e-15,
            ..SimSettings::default()
        };
        simulate(&p, set, (), 0.0, &x0, t_end)
            .unwrap()
            .trajectory
            .x
            .last()
            .unwrap()
            .clone()
    };
    let e0 = p.energy(&x0);
    let run = |h: f64| {
        let set = SimSettings {
            method: Method::Rk4 { h },
            ..SimSettings::default()
        };
        let out = simulate(&p, set, (), 0.0, &x0, t_end).unwrap();
        assert!(out.stats.accepted_steps >= (t_end / h) as usize);
        let x = out.trajectory.x.last().unwrap().clone();
        let err = libm::hypot(x[0] - reference[0], x[1] - reference[1]);
        (err, ((p.energy(&x) - e0) / e0).abs())
    };
    let ((e1, _), (e2, en2)) = (run(0.02), run(0.01));
    let order = libm::log2(e1 / e2);
    assert!((order - 4.0).abs() < 0.3, "order {order} ({e1:e}, {e2:e})");
    assert!(en2 < 1e-7, "energy error {en2}");
}

#[test]
fn uniform_output_grid_from_dense_output() {
    let set = SimSettings {
        output_dt: Some(0.25),
        rtol: 1e-10,
        atol: 1e-12,
        ..SimSettings::default()
    };
    let out = simulate(&Oscillator { omega: 1.0 }, set, (), 0.0, &[1.0, 0.0], 3.0).unwrap();
    let idx = out.trajectory.indices_of(SampleKind::Grid);
    assert_eq!(idx.len(), 13);
    for (k, &i) in idx.iter().enumerate() {
        let t = out.trajectory.t[i];
        assert!((t - 0.25 * k as f64).abs() < 1e-15);
        let x = &out.trajectory.x[i];
        assert!((x[0] - libm::cos(t)).abs() < 1e-8 && (x[1] + libm::sin(t)).abs() < 1e-8);
    }
    for w in out.trajectory.t.windows(2) {
        assert!(w[1] >= w[0]);
    }
}
