//! One evaluation of the hybrid controller's law for the paper finger (criterion): the
//! computed-torque law of a free phase (generated inverse dynamics) and the force/velocity law
//! of a contact phase in Stick and in Slip (contact kernel, mass matrix, 3 × 3 solves), the
//! free law with the clearance guard active (`free_guard`) and with the approach re-timed by
//! the gap (`free_approach`), at the
//! impact state of the default `periodic-qc` optimum. Run:
//! `cargo bench -p bf-control --bench control_law -- --warm-up-time 1 --measurement-time 3`.

use bf_control::{HybridController, HybridGains, InverseDynamics, Reference, ReferencePhase};
use bf_model::{Mode, VecN};
use bf_sim::Input;
use criterion::{Criterion, criterion_group, criterion_main};
use std::hint::black_box;

/// The pre-impact state of the default `periodic-qc` optimum (`track` on it, first impact).
const X_IMPACT: [f64; 9] = [
    -1.557358638532254,
    3.1248339966497927,
    -1.4244241225804044,
    -0.106481329973991,
    -0.8230925544814001,
    2.743615527129837,
    0.004435209233398111,
    0.0006284376849190086,
    1.8664670922707922,
];

fn phase(contact: bool, x: &[f64; 9]) -> ReferencePhase {
    let q = [x[0], x[1], x[2]];
    let qd = [x[3], x[4], x[5]];
    let w = [x[6], x[7], x[8]];
    ReferencePhase {
        contact,
        duration: 0.1,
        s: vec![0.0, 0.05, 0.1],
        q: vec![q; 3],
        qd: vec![qd; 3],
        qdd: vec![[0.1, -0.2, 0.3]; 3],
        omega: vec![w; 3],
        omega_dot: vec![[0.0, 0.0, 1.0]; 3],
        lambda: vec![[0.05, 0.02, 0.1]; 3],
        contact_point: vec![[0.0, 0.0, 1.0]; 3],
        contact_point_dot: vec![[0.0; 3]; 3],
        gap: vec![0.0; 3],
        gap_rate: vec![0.0; 3],
    }
}

fn bench(c: &mut Criterion) {
    let model = bf_model::fixtures::paper_scene().expect("paper scene");
    let (q, _) = model
        .contact_configuration_near(VecN::<3>::from_column_slice(&X_IMPACT[..3]), 1e-12, 50)
        .expect("contact configuration");
    let mut x = X_IMPACT;
    x[..3].copy_from_slice(q.as_slice());
    let id = InverseDynamics::compiled("paper", &[], model.params().mu_v()).expect("kernel");
    let reference = Reference {
        phases: vec![phase(true, &x), phase(false, &x)],
        mean_omega: [0.0, 0.0, 2.0],
    };
    // The dynamic kernels behind a trait object, as `track` runs them.
    let dyn_model = bf_model::Model::from_kernels(
        Box::new(bf_model::PaperKernels::default()) as bf_model::DynKernels
    )
    .expect("model");
    let law = HybridController::new(
        dyn_model,
        id.clone(),
        reference,
        HybridGains::default(),
        0.0,
        &x,
    )
    .expect("controller");
    // A free reference phase first: at t = 0.03 s the finger touching the ball is below the
    // clearance floor, so the free law also runs the guard (contact kernel, M_f solve).
    let guarded = HybridController::new(
        bf_model::Model::from_kernels(
            Box::new(bf_model::PaperKernels::default()) as bf_model::DynKernels
        )
        .expect("model"),
        id.clone(),
        Reference {
            phases: vec![phase(false, &x), phase(true, &x)],
            mean_omega: [0.0, 0.0, 2.0],
        },
        HybridGains::default(),
        0.0,
        &x,
    )
    .expect("controller");
    // A free phase whose planned gap falls through 0 at s = 0.067 s (the finger touches the
    // ball, h = 0): the free law re-times the reference by the gap (contact kernel, bisection
    // on h*); the clearance guard is off to time the re-timing alone.
    let mut approach = phase(false, &x);
    approach.gap = vec![0.01, 0.0025, -0.005];
    approach.gap_rate = vec![-0.15; 3];
    let mut no_guard = HybridGains::default();
    no_guard.clearance.gap = 0.0;
    let approaching = HybridController::new(
        bf_model::Model::from_kernels(
            Box::new(bf_model::PaperKernels::default()) as bf_model::DynKernels
        )
        .expect("model"),
        id,
        Reference {
            phases: vec![approach, phase(true, &x)],
            mean_omega: [0.0, 0.0, 2.0],
        },
        no_guard,
        0.0,
        &x,
    )
    .expect("controller");
    let mut tau = [0.0; 3];
    let mut g = c.benchmark_group("control_law");
    let cases = [
        ("free", &law, Mode::Free),
        ("stick", &law, Mode::Stick),
        ("slip", &law, Mode::Slip),
        ("free_guard", &guarded, Mode::Free),
        ("free_approach", &approaching, Mode::Free),
    ];
    for (name, law, mode) in cases {
        g.bench_function(name, |b| {
            b.iter(|| {
                law.tau_in_mode(
                    mode,
                    black_box(0.03),
                    black_box(&x[..3]),
                    black_box(&x[3..6]),
                    black_box(&x[6..9]),
                    &mut tau,
                )
                .expect("law");
                black_box(tau)
            })
        });
    }
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
