//! Criterion benchmarks of the hybrid simulator on the compiled paper-scene kernels.
//!
//! * `paper_10s_contact/dopri5_rtol1e-8`: 10 s of the paper scene with contact — the finger
//!   dropped from the paper's initial guess q = (0.1, 0.5, 0.5) onto the ball (τ = 0, Newton's
//!   impact law, friction and damping on), which hits, slips, sticks and lifts off
//!   (events printed once). Target: < 10 ms (≥ 1000× real time).
//! * `paper_10s_contact/dopri5_rtol1e-8_dyn`: the same run with the system passed as a trait
//!   object (`&dyn HybridSystem`), as the CLI and the solve pipeline pass it: the cost of the
//!   virtual calls, compared in the same run.
//! * `paper_10s_contact/rk4_h1e-3`: the same with RK4 at h = 1 ms.
//! * A work-precision table (DOPRI5 rtol 1e-3 … 1e-12, RK4 h = 1e-2 … 1e-4; error of x(T)
//!   against an rtol = 1e-13 reference vs CPU time), from `bf_sim::work_precision`, printed to
//!   stderr before timing.
//!
//! Quick run: `cargo bench -p ball-finger --bench simulate -- --warm-up-time 1 --measurement-time 2`.

use ball_finger::paper::speed_accuracy::integrators::{dropped_finger, sim_settings};
use bf_model::Mode;
use bf_sim::work_precision::{RK4_LADDER, RTOL_LADDER, ladder};
use bf_sim::{
    HybridSystem, Method, SimOutput, SimSettings, format_table, simulate, work_precision,
};
use criterion::{Criterion, criterion_group, criterion_main};
use std::hint::black_box;

/// The speed–accuracy study's integrator settings, recording every step as a user would.
fn settings(method: Method, rtol: f64) -> SimSettings {
    SimSettings {
        record_steps: true,
        ..sim_settings(method, rtol)
    }
}

/// 10 s of the paper scene from `x0` with `method` (rtol 1e-8 for DOPRI5); `sys` may be a trait
/// object, so the static and dynamic dispatch variants run the same code.
fn ten_seconds<S: HybridSystem<Mode = Mode> + ?Sized>(
    sys: &S,
    method: Method,
    x0: &[f64],
) -> SimOutput<Mode> {
    simulate(
        sys,
        settings(method, 1e-8),
        Mode::Free,
        0.0,
        black_box(x0),
        10.0,
    )
    .expect("runs")
}

fn bench(c: &mut Criterion) {
    let (sys, x0) = dropped_finger().expect("paper scene");
    let out = simulate(
        &sys,
        settings(Method::Dopri5, 1e-8),
        Mode::Free,
        0.0,
        &x0,
        10.0,
    )
    .expect("10 s run");
    let kinds: Vec<String> = out
        .events
        .iter()
        .map(|e| {
            format!(
                "{:.4} {:?}->{:?}",
                e.t,
                e.mode_before,
                e.mode_after.unwrap_or(e.mode_before)
            )
        })
        .collect();
    eprintln!(
        "paper 10 s, dopri5 rtol 1e-8: {:?}; events: {}",
        out.stats,
        kinds.join(", ")
    );

    let reference = SimSettings {
        rtol: 1e-13,
        atol: 1e-15,
        ..settings(Method::Dopri5, 1e-13)
    };
    let cfg = ladder(
        &settings(Method::Dopri5, 1e-8),
        &RTOL_LADDER,
        1e-2,
        &RK4_LADDER,
    );
    match work_precision(&sys, Mode::Free, 0.0, &x0, 10.0, &reference, &cfg, 3) {
        Ok(rows) => eprintln!(
            "work-precision, paper scene 10 s with contact:\n{}",
            format_table(&rows)
        ),
        Err(e) => eprintln!("work-precision reference failed: {e}"),
    }

    let mut g = c.benchmark_group("paper_10s_contact");
    g.sample_size(20);
    let dyn_sys: &dyn HybridSystem<Mode = Mode> = &sys;
    g.bench_function("dopri5_rtol1e-8", |b| {
        b.iter(|| ten_seconds(&sys, Method::Dopri5, &x0))
    });
    g.bench_function("dopri5_rtol1e-8_dyn", |b| {
        b.iter(|| ten_seconds(dyn_sys, Method::Dopri5, &x0))
    });
    g.bench_function("rk4_h1e-3", |b| {
        b.iter(|| ten_seconds(&sys, Method::Rk4 { h: 1e-3 }, &x0))
    });
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
