//! Criterion benches of the generated kernels (every kernel of `paper`; the dynamics kernels
//! of `puma560` and `iiwa7`). Target: `paper/mass_cqd_g` ≤ 70 ns.

use std::hint::black_box;

use criterion::{Criterion, criterion_group, criterion_main};

macro_rules! bench_dynamics {
    ($c:expr, $m:ident) => {{
        use bf_generated::$m as s;
        let name = stringify!($m);
        let q: [f64; s::NQ] = std::array::from_fn(|i| 0.3 + 0.17 * i as f64);
        let qd: [f64; s::NQ] = std::array::from_fn(|i| -0.5 + 0.23 * i as f64);
        let p = s::PARAM_DEFAULTS;
        let mut m = [[0.0; s::NQ]; s::NQ];
        let mut v = [0.0; s::NQ];
        let mut t3 = [[[0.0; s::NQ]; s::NQ]; s::NQ];
        let mut u = 0.0;
        $c.bench_function(&format!("{name}/mass_matrix"), |b| {
            b.iter(|| s::mass_matrix(black_box(&q), black_box(&p), &mut m))
        });
        $c.bench_function(&format!("{name}/mass_cqd_g"), |b| {
            b.iter(|| s::mass_cqd_g(black_box(&q), black_box(&qd), black_box(&p), &mut m, &mut v))
        });
        $c.bench_function(&format!("{name}/cqd_g"), |b| {
            b.iter(|| s::cqd_g(black_box(&q), black_box(&qd), black_box(&p), &mut v))
        });
        $c.bench_function(&format!("{name}/cqd_g_rnea"), |b| {
            b.iter(|| s::cqd_g_rnea(black_box(&q), black_box(&qd), black_box(&p), &mut v))
        });
        $c.bench_function(&format!("{name}/coriolis_qd"), |b| {
            b.iter(|| s::coriolis_qd(black_box(&q), black_box(&qd), black_box(&p), &mut v))
        });
        $c.bench_function(&format!("{name}/coriolis_matrix"), |b| {
            b.iter(|| s::coriolis_matrix(black_box(&q), black_box(&qd), black_box(&p), &mut m))
        });
        $c.bench_function(&format!("{name}/gravity"), |b| {
            b.iter(|| s::gravity(black_box(&q), black_box(&p), &mut v))
        });
        $c.bench_function(&format!("{name}/potential"), |b| {
            b.iter(|| s::potential(black_box(&q), black_box(&p), &mut u))
        });
        $c.bench_function(&format!("{name}/dmass_dq"), |b| {
            b.iter(|| s::dmass_dq(black_box(&q), black_box(&p), &mut t3))
        });
        $c.bench_function(&format!("{name}/christoffel"), |b| {
            b.iter(|| s::christoffel(black_box(&q), black_box(&p), &mut t3))
        });
    }};
}

fn paper_kinematics(c: &mut Criterion) {
    use bf_generated::paper as s;
    let q = [0.3, -0.7, 1.1];
    let qd = [0.4, 0.2, -0.9];
    let omega = [0.0, 0.0, 2.2];
    let p = s::PARAM_DEFAULTS;
    let mut pos = [[0.0; 3]; s::NQ];
    let mut rot = [[[0.0; 3]; 3]; s::NQ];
    let mut jp = [[0.0; s::NQ]; 3];
    let mut jo = [[0.0; s::NQ]; 3];
    let mut cjp = [[[0.0; s::NQ]; 3]; s::NQ];
    let mut cjo = [[[0.0; s::NQ]; 3]; s::NQ];
    let mut six = [0.0; 6];
    let mut ct = s::Contact::default();
    c.bench_function("paper/frames", |b| {
        b.iter(|| s::frames(black_box(&q), black_box(&p), &mut pos, &mut rot))
    });
    c.bench_function("paper/tip_jacobian", |b| {
        b.iter(|| s::tip_jacobian(black_box(&q), black_box(&p), &mut jp, &mut jo))
    });
    c.bench_function("paper/com_jacobians", |b| {
        b.iter(|| s::com_jacobians(black_box(&q), black_box(&p), &mut cjp, &mut cjo))
    });
    c.bench_function("paper/tip_jdot_qd", |b| {
        b.iter(|| s::tip_jdot_qd(black_box(&q), black_box(&qd), black_box(&p), &mut six))
    });
    c.bench_function("paper/contact", |b| {
        b.iter(|| {
            s::contact(
                black_box(&q),
                black_box(&qd),
                black_box(&omega),
                black_box(&p),
                &mut ct,
            )
        })
    });
    c.bench_function("paper/contact_smooth", |b| {
        b.iter(|| {
            s::contact_smooth(
                black_box(&q),
                black_box(&qd),
                black_box(&omega),
                black_box(0.01),
                black_box(&p),
                &mut ct,
            )
        })
    });
}

fn dynamics(c: &mut Criterion) {
    bench_dynamics!(c, paper);
    bench_dynamics!(c, puma560);
    bench_dynamics!(c, iiwa7);
}

criterion_group!(benches, paper_kinematics, dynamics);
criterion_main!(benches);
