//! Criterion benches of the generated kernels (every kernel of `paper`; the dynamics kernels
//! of `puma560` and `iiwa7`). Each call takes the next of 1024 seeded random states (q
//! uniform in [−π, π], q̇ in [−2, 2] rad/s), so branches inside the kernels (the sine–cosine
//! helper's) are not trained on one fixed input. Time is wall time minus the time the thread
//! spent preempted (`/proc/thread-self/schedstat`; plain wall time where that is unavailable),
//! so waiting for a CPU on a loaded machine does not count.
//!
//! The optimal-control node kernels of the periodic problems (`paper_qc_*`) are timed per
//! group of four nodes, as four calls of the scalar kernel (`node/<kernel>/scalar`) and as
//! one call of its batched variant (`node/<kernel>/x4`), on the same random nodes.
//!
//! `cargo bench -p bf-generated --bench kernels -- --warm-up-time 1 --measurement-time 3`;
//! a filter such as `mass_cqd_g` or `node/` selects kernels.

use std::hint::black_box;
use std::time::{Duration, Instant};

use criterion::{Criterion, criterion_group, criterion_main};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

/// Number of states a bench cycles through.
const STATES: usize = 1024;

/// Time the calling thread has spent waiting for a CPU (runnable but preempted), from the
/// second field of `/proc/thread-self/schedstat`; `None` where that file does not exist. The
/// first field (time on the CPU) is only updated at scheduler ticks, but waits are accounted
/// when the thread is switched back in, so this one is exact whenever the thread reads it.
fn run_delay() -> Option<Duration> {
    let s = std::fs::read_to_string("/proc/thread-self/schedstat").ok()?;
    let ns: u64 = s.split_whitespace().nth(1)?.parse().ok()?;
    Some(Duration::from_nanos(ns))
}

/// Runs `f(i)` for `i` in `0..iters` and returns the wall time minus the time the thread was
/// preempted (plain wall time where that is unavailable).
fn timed(iters: u64, mut f: impl FnMut(usize)) -> Duration {
    let d0 = run_delay();
    let w0 = Instant::now();
    for i in 0..iters {
        f(i as usize % STATES);
    }
    let wall = w0.elapsed();
    match (d0, run_delay()) {
        (Some(a), Some(b)) => wall.saturating_sub(b.saturating_sub(a)),
        _ => wall,
    }
}

/// `STATES` random (q, q̇) pairs with a fixed seed per joint count.
fn states<const N: usize>() -> Vec<([f64; N], [f64; N])> {
    let mut rng = ChaCha8Rng::seed_from_u64(1000 + N as u64);
    (0..STATES)
        .map(|_| {
            (
                std::array::from_fn(|_| {
                    rng.random_range(-std::f64::consts::PI..std::f64::consts::PI)
                }),
                std::array::from_fn(|_| rng.random_range(-2.0..2.0)),
            )
        })
        .collect()
}

macro_rules! bench_dynamics {
    ($c:expr, $m:ident) => {{
        use bf_generated::$m as s;
        let name = stringify!($m);
        let st = states::<{ s::NQ }>();
        let p = s::PARAM_DEFAULTS;
        let mut m = [[0.0; s::NQ]; s::NQ];
        let mut v = [0.0; s::NQ];
        let mut t3 = [[[0.0; s::NQ]; s::NQ]; s::NQ];
        let mut u = 0.0;
        $c.bench_function(&format!("{name}/mass_matrix"), |b| {
            b.iter_custom(|n| {
                timed(n, |i| {
                    s::mass_matrix(black_box(&st[i].0), black_box(&p), &mut m);
                    black_box(&m);
                })
            })
        });
        $c.bench_function(&format!("{name}/mass_cqd_g"), |b| {
            b.iter_custom(|n| {
                timed(n, |i| {
                    let (q, qd) = &st[i];
                    s::mass_cqd_g(black_box(q), black_box(qd), black_box(&p), &mut m, &mut v);
                    black_box((&m, &v));
                })
            })
        });
        $c.bench_function(&format!("{name}/cqd_g"), |b| {
            b.iter_custom(|n| {
                timed(n, |i| {
                    let (q, qd) = &st[i];
                    s::cqd_g(black_box(q), black_box(qd), black_box(&p), &mut v);
                    black_box(&v);
                })
            })
        });
        $c.bench_function(&format!("{name}/cqd_g_rnea"), |b| {
            b.iter_custom(|n| {
                timed(n, |i| {
                    let (q, qd) = &st[i];
                    s::cqd_g_rnea(black_box(q), black_box(qd), black_box(&p), &mut v);
                    black_box(&v);
                })
            })
        });
        $c.bench_function(&format!("{name}/coriolis_qd"), |b| {
            b.iter_custom(|n| {
                timed(n, |i| {
                    let (q, qd) = &st[i];
                    s::coriolis_qd(black_box(q), black_box(qd), black_box(&p), &mut v);
                    black_box(&v);
                })
            })
        });
        $c.bench_function(&format!("{name}/coriolis_matrix"), |b| {
            b.iter_custom(|n| {
                timed(n, |i| {
                    let (q, qd) = &st[i];
                    s::coriolis_matrix(black_box(q), black_box(qd), black_box(&p), &mut m);
                    black_box(&m);
                })
            })
        });
        $c.bench_function(&format!("{name}/gravity"), |b| {
            b.iter_custom(|n| {
                timed(n, |i| {
                    s::gravity(black_box(&st[i].0), black_box(&p), &mut v);
                    black_box(&v);
                })
            })
        });
        $c.bench_function(&format!("{name}/potential"), |b| {
            b.iter_custom(|n| {
                timed(n, |i| {
                    s::potential(black_box(&st[i].0), black_box(&p), &mut u);
                    black_box(&u);
                })
            })
        });
        $c.bench_function(&format!("{name}/dmass_dq"), |b| {
            b.iter_custom(|n| {
                timed(n, |i| {
                    s::dmass_dq(black_box(&st[i].0), black_box(&p), &mut t3);
                    black_box(&t3);
                })
            })
        });
        $c.bench_function(&format!("{name}/christoffel"), |b| {
            b.iter_custom(|n| {
                timed(n, |i| {
                    s::christoffel(black_box(&st[i].0), black_box(&p), &mut t3);
                    black_box(&t3);
                })
            })
        });
    }};
}

fn paper_kinematics(c: &mut Criterion) {
    use bf_generated::paper as s;
    let st = states::<{ s::NQ }>();
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
        b.iter_custom(|n| {
            timed(n, |i| {
                s::frames(black_box(&st[i].0), black_box(&p), &mut pos, &mut rot);
                black_box((&pos, &rot));
            })
        })
    });
    c.bench_function("paper/tip_jacobian", |b| {
        b.iter_custom(|n| {
            timed(n, |i| {
                s::tip_jacobian(black_box(&st[i].0), black_box(&p), &mut jp, &mut jo);
                black_box((&jp, &jo));
            })
        })
    });
    c.bench_function("paper/com_jacobians", |b| {
        b.iter_custom(|n| {
            timed(n, |i| {
                s::com_jacobians(black_box(&st[i].0), black_box(&p), &mut cjp, &mut cjo);
                black_box((&cjp, &cjo));
            })
        })
    });
    c.bench_function("paper/tip_jdot_qd", |b| {
        b.iter_custom(|n| {
            timed(n, |i| {
                let (q, qd) = &st[i];
                s::tip_jdot_qd(black_box(q), black_box(qd), black_box(&p), &mut six);
                black_box(&six);
            })
        })
    });
    c.bench_function("paper/contact", |b| {
        b.iter_custom(|n| {
            timed(n, |i| {
                let (q, qd) = &st[i];
                s::contact(
                    black_box(q),
                    black_box(qd),
                    black_box(&omega),
                    black_box(&p),
                    &mut ct,
                );
                black_box(&ct);
            })
        })
    });
    c.bench_function("paper/contact_smooth", |b| {
        b.iter_custom(|n| {
            timed(n, |i| {
                let (q, qd) = &st[i];
                s::contact_smooth(
                    black_box(q),
                    black_box(qd),
                    black_box(&omega),
                    black_box(0.01),
                    black_box(&p),
                    &mut ct,
                );
                black_box(&ct);
            })
        })
    });
}

fn dynamics(c: &mut Criterion) {
    bench_dynamics!(c, paper);
    bench_dynamics!(c, puma560);
    bench_dynamics!(c, iiwa7);
}

/// Scalar and batched node kernels of the `paper_qc_*` node functions on `STATES / 4` groups
/// of four random nodes (angles in [−π, π], other locals in [−2, 2], duration in [0.1, 2]).
fn node_kernels(c: &mut Criterion) {
    let mut rng = ChaCha8Rng::seed_from_u64(77);
    for k in bf_generated::ocp::NODE_KERNELS
        .iter()
        .filter(|k| k.name.starts_with("paper_qc_"))
    {
        let Some(x4) = k.x4 else { continue };
        let (nl, no) = (k.n_local, k.n_out);
        let groups = STATES / 4;
        let local: Vec<f64> = (0..groups * 4 * nl)
            .map(|i| match i % nl {
                j if j + 1 == nl => rng.random_range(0.1..2.0),
                j if j < 3 => rng.random_range(-std::f64::consts::PI..std::f64::consts::PI),
                _ => rng.random_range(-2.0..2.0),
            })
            .collect();
        let fixed: Vec<f64> = (0..k.n_fixed)
            .map(|_| rng.random_range(0.01..1.0))
            .collect();
        let w: Vec<f64> = (0..groups * 4 * no)
            .map(|_| rng.random_range(-1.0..1.0))
            .collect();
        let parts = [
            ("value", k.value, x4.value, no),
            (
                "jacobian",
                k.jacobian,
                x4.jacobian,
                k.jacobian_pattern.len(),
            ),
            ("hessian", k.hessian, x4.hessian, k.hessian_pattern.len()),
        ];
        for (part, scalar, batched, n) in parts {
            let mut out = vec![0.0; 4 * n];
            c.bench_function(&format!("node/{}_{part}/scalar", k.name), |b| {
                b.iter_custom(|iters| {
                    timed(iters, |i| {
                        // The scalar kernels read the nodes one after another (rows), the
                        // batched one the same memory as four interleaved nodes: equal data
                        // volume, and the values do not matter for the timing.
                        let g = i % groups;
                        for l in 0..4 {
                            let node = 4 * g + l;
                            scalar(
                                black_box(&local[node * nl..(node + 1) * nl]),
                                black_box(&fixed),
                                black_box(&w[node * no..(node + 1) * no]),
                                &mut out[l * n..(l + 1) * n],
                            );
                        }
                        black_box(&out);
                    })
                })
            });
            c.bench_function(&format!("node/{}_{part}/x4", k.name), |b| {
                b.iter_custom(|iters| {
                    timed(iters, |i| {
                        let g = i % groups;
                        batched(
                            black_box(&local[4 * g * nl..4 * (g + 1) * nl]),
                            black_box(&fixed),
                            black_box(&w[4 * g * no..4 * (g + 1) * no]),
                            &mut out,
                        );
                        black_box(&out);
                    })
                })
            });
        }
    }
}

criterion_group!(benches, paper_kinematics, dynamics, node_kernels);
criterion_main!(benches);
