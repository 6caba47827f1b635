//! Cost of the mode dynamics (eq. 26, 33, 37) and of the four impact laws (eq. 39–43) on the
//! paper scene's generated kernels: per call, including the kernel evaluation, and the physics
//! layer alone (given evaluated kinematics).

use std::hint::black_box;

use bf_model::{ImpactLaw, State, Vec3, dynamics, fixtures, impact};
use criterion::{Criterion, criterion_group, criterion_main};

/// A contact configuration of the paper scene: Newton on h(q) along ∇h = J_cᵀ n.
fn contact_q(model: &bf_model::Model<bf_model::PaperKernels>) -> Vec3 {
    let mut q = Vec3::new(0.3, 0.9, 0.8);
    for _ in 0..50 {
        let k = model
            .evaluate(&State::new(q, Vec3::zeros(), Vec3::zeros()))
            .expect("finite");
        let g = k.contact.j_c.transpose() * k.contact.n;
        q -= g * (k.contact.h / g.norm_squared());
    }
    q
}

fn bench(c: &mut Criterion) {
    let model = fixtures::paper_scene().expect("paper scene");
    let q = contact_q(&model);
    let k0 = model
        .evaluate(&State::new(q, Vec3::zeros(), Vec3::zeros()))
        .expect("finite");
    assert!(k0.contact.h.abs() < 1e-12);
    let jinv = k0.contact.j_c.try_inverse().expect("J_c invertible");
    let n = k0.contact.n;
    let omega = Vec3::new(0.3, -0.2, 1.5);
    // sticking: Δv = 0
    let x_stick = State::new(q, jinv * omega.cross(&k0.contact.r_c), omega);
    // slipping: n·v_c = 0, Δv ≠ 0
    let vt = Vec3::new(0.4, -0.3, 0.2);
    let x_slip = State::new(q, jinv * (vt - n * n.dot(&vt)), omega);
    // impact: approaching
    let x_imp = State::new(q, jinv * (vt - n * (n.dot(&vt) + 0.5)), omega);
    let tau = Vec3::new(0.1, -0.2, 0.05);

    let mut g = c.benchmark_group("model");
    g.bench_function("evaluate_kernels", |b| {
        b.iter(|| model.evaluate(black_box(&x_stick)))
    });
    g.bench_function("free", |b| {
        b.iter(|| model.free(black_box(&x_slip), black_box(&tau)))
    });
    g.bench_function("stick", |b| {
        b.iter(|| model.stick(black_box(&x_stick), black_box(&tau)))
    });
    g.bench_function("slip", |b| {
        b.iter(|| model.slip(black_box(&x_slip), black_box(&tau), None))
    });
    for law in ImpactLaw::ALL {
        g.bench_function(format!("impact_{law:?}"), |b| {
            b.iter(|| model.impact(black_box(&x_imp), law))
        });
    }
    g.finish();

    let p = *model.params();
    let s = *model.settings();
    let ks = model.evaluate(&x_stick).expect("finite");
    let kl = model.evaluate(&x_slip).expect("finite");
    let ki = model.evaluate(&x_imp).expect("finite");
    let mut g = c.benchmark_group("physics_only");
    g.bench_function("free", |b| {
        b.iter(|| dynamics::free(black_box(&kl), &p, &tau))
    });
    g.bench_function("stick", |b| {
        b.iter(|| dynamics::stick(black_box(&ks), &p, &tau, &s))
    });
    g.bench_function("slip", |b| {
        b.iter(|| dynamics::slip(black_box(&kl), &p, &tau, &s, None))
    });
    for law in ImpactLaw::ALL {
        g.bench_function(format!("impact_{law:?}"), |b| {
            b.iter(|| impact::impact(black_box(&ki), &p, law, &s))
        });
    }
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
