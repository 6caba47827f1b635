//! Work-precision of the integrators: wall time per run (criterion) against the error of that
//! run (printed once before timing, to stderr).
//!
//! * smooth: harmonic oscillator ω = 2 on [0, 10], error = ‖x(10) − exact‖.
//! * bouncing ball with linear drag (k = 0.5, e = 0.7, from 1 m), error = |t₃ − t₃,ref| of the
//!   3rd impact (closed-form flight + Newton, `BouncingBall::reference_impacts`).
//!
//! DOPRI5 at rtol = 1e-3 … 1e-12 (atol = 1e-2·rtol, h_max = 10), RK4 at h = 0.1 … 0.003.
//! Quick run: `cargo bench -p bf-sim --bench integrators -- --warm-up-time 1 --measurement-time 2`.

use bf_sim::toys::{BallMode, BouncingBall, Oscillator};
use bf_sim::{Method, SimSettings, simulate};
use criterion::{BenchmarkId, Criterion, criterion_group, criterion_main};
use std::hint::black_box;

const RTOLS: [f64; 6] = [1e-3, 1e-5, 1e-7, 1e-9, 1e-11, 1e-12];
const RK4_H: [f64; 5] = [0.1, 0.03, 0.01, 0.003, 0.001];

fn dopri(rtol: f64) -> SimSettings {
    SimSettings {
        rtol,
        atol: rtol * 1e-2,
        h_max: 10.0,
        ..SimSettings::default()
    }
}

fn rk4(h: f64) -> SimSettings {
    SimSettings {
        method: Method::Rk4 { h },
        ..SimSettings::default()
    }
}

/// Returns (error, accepted steps).
fn run_smooth(set: SimSettings) -> (f64, usize) {
    let out = simulate(&Oscillator { omega: 2.0 }, set, (), 0.0, &[1.0, 0.0], 10.0)
        .expect("oscillator runs");
    let x = out.trajectory.x.last().expect("samples");
    let err = libm::hypot(x[0] - libm::cos(20f64), x[1] + 2.0 * libm::sin(20f64));
    (err, out.stats.accepted_steps)
}

fn ball() -> BouncingBall {
    BouncingBall {
        g: 9.81,
        e: 0.7,
        drag: 0.5,
        v_rest: None,
    }
}

fn run_ball(set: SimSettings, t3: f64) -> (f64, usize) {
    let out =
        simulate(&ball(), set, BallMode::Flight, 0.0, &[1.0, 0.0], t3 + 0.01).expect("ball runs");
    let err = out
        .events
        .get(2)
        .map_or(f64::INFINITY, |e| (e.t - t3).abs());
    (err, out.stats.accepted_steps)
}

fn bench(c: &mut Criterion) {
    let t3 = ball().reference_impacts(1.0, 0.0, 3)[2].0;
    eprintln!("work-precision (error, accepted steps):");
    for &r in &RTOLS {
        let (es, ns) = run_smooth(dopri(r));
        let (eb, nb) = run_ball(dopri(r), t3);
        eprintln!(
            "  dopri5 rtol {r:7.0e}: smooth {es:9.2e} ({ns:5} steps)  ball t3 {eb:9.2e} ({nb:5} steps)"
        );
    }
    for &h in &RK4_H {
        let (es, ns) = run_smooth(rk4(h));
        let (eb, nb) = run_ball(rk4(h), t3);
        eprintln!(
            "  rk4    h    {h:7.0e}: smooth {es:9.2e} ({ns:5} steps)  ball t3 {eb:9.2e} ({nb:5} steps)"
        );
    }

    let mut g = c.benchmark_group("smooth_oscillator");
    g.sample_size(10);
    for &r in &RTOLS {
        g.bench_with_input(BenchmarkId::new("dopri5_rtol", r), &r, |b, &r| {
            b.iter(|| black_box(run_smooth(black_box(dopri(r)))))
        });
    }
    for &h in &RK4_H {
        g.bench_with_input(BenchmarkId::new("rk4_h", h), &h, |b, &h| {
            b.iter(|| black_box(run_smooth(black_box(rk4(h)))))
        });
    }
    g.finish();

    let mut g = c.benchmark_group("bouncing_ball_drag");
    g.sample_size(10);
    for &r in &RTOLS {
        g.bench_with_input(BenchmarkId::new("dopri5_rtol", r), &r, |b, &r| {
            b.iter(|| black_box(run_ball(black_box(dopri(r)), t3)))
        });
    }
    for &h in &RK4_H {
        g.bench_with_input(BenchmarkId::new("rk4_h", h), &h, |b, &h| {
            b.iter(|| black_box(run_ball(black_box(rk4(h)), t3)))
        });
    }
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
