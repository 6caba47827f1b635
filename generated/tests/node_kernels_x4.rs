//! The batched (`_x4`) node kernels against the scalar ones: on four random nodes per call,
//! every lane of the value, Jacobian and Hessian kernels is bitwise the scalar kernel's result
//! for that node, for every node kernel emitted with batched variants, with joint angles both
//! small and large (the sine–cosine path, including lanes beyond its fast range next to lanes
//! within it) and the weights of the Hessian differing per node. The batched variants exist
//! for the shapes of the catalogue's default settings (no ḣ margin row, velocity-level stick
//! constraint) and only for those.
//!
//! `cargo test --release -p bf-generated --test node_kernels_x4`

use bf_generated::ocp::NODE_KERNELS;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

/// Equal bits, or both NaN (a NaN's payload is not part of the contract).
fn same(a: f64, b: f64) -> bool {
    a.to_bits() == b.to_bits() || (a.is_nan() && b.is_nan())
}

#[test]
fn every_lane_of_a_batched_node_kernel_is_the_scalar_kernel_bitwise() {
    let mut rng = ChaCha8Rng::seed_from_u64(44);
    let mut checked = 0;
    for k in NODE_KERNELS {
        let option_shape = k.name.contains("_hdot") || k.name.ends_with("_acc");
        let Some(x4) = k.x4 else {
            assert!(option_shape, "{}: no batched kernels", k.name);
            continue;
        };
        assert!(!option_shape, "{}: batched kernels for an option", k.name);
        for round in 0..20 {
            // Angles up to 1e3 rad in some rounds: far from the first period, as after a
            // few spins of a joint in a bad iterate; in the last round up to 2e6 rad, so that
            // lanes beyond the fast sine–cosine range (2²⁰) sit next to lanes within it.
            let scale = match round {
                19 => 2e6,
                r if r % 4 == 3 => 1e3,
                _ => 3.0,
            };
            // Interleaved: node l's entry j at 4j + l.
            let local: Vec<f64> = (0..4 * k.n_local)
                .map(|i| {
                    if i / 4 == k.n_local - 1 {
                        rng.random_range(0.1..2.0)
                    } else {
                        rng.random_range(-scale..scale)
                    }
                })
                .collect();
            let fixed: Vec<f64> = (0..k.n_fixed)
                .map(|_| rng.random_range(0.005..2.0))
                .collect();
            let w: Vec<f64> = (0..4 * k.n_out)
                .map(|_| rng.random_range(-2.0..2.0))
                .collect();
            let parts = [
                (k.value, x4.value, k.n_out),
                (k.jacobian, x4.jacobian, k.jacobian_pattern.len()),
                (k.hessian, x4.hessian, k.hessian_pattern.len()),
            ];
            for (pi, (scalar, batched, n)) in parts.into_iter().enumerate() {
                let mut out4 = vec![f64::NAN; 4 * n];
                batched(&local, &fixed, &w, &mut out4);
                let lane = |v: &[f64], l: usize| -> Vec<f64> {
                    v.iter().skip(l).step_by(4).copied().collect()
                };
                for l in 0..4 {
                    let mut out = vec![f64::NAN; n];
                    scalar(&lane(&local, l), &fixed, &lane(&w, l), &mut out);
                    for (e, (a, b)) in out.iter().zip(lane(&out4, l)).enumerate() {
                        assert!(
                            same(*a, b),
                            "{} part {pi} lane {l} entry {e}: scalar {a:e} vs batched {b:e}",
                            k.name
                        );
                    }
                    checked += n;
                }
            }
        }
    }
    assert!(checked > 50_000, "only {checked} values compared");
}
