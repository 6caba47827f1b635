//! Accuracy of the batched sine–cosine helper that the emitted kernels call
//! (`bf_codegen::trig::sin_cos_n`), in ulps of the exact value: against the double-double
//! reference (`dd::Dd::sin_cos`, an independent reduction by a 160-bit π/2 and Taylor
//! series) and against the `libm` crate's `sincos`, over |x| ≤ 1e6 (log-uniform
//! and uniform), next to multiples of π/2 (the cancellation cases of the argument reduction),
//! beyond the range (NaN) and at special values; the one-angle helpers are its lanes.

use bf_codegen::dd::{self, Dd};
use bf_codegen::trig::{sin_cos, sin_cos_f32, sin_cos_n, sin_cos_n_f32};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

/// |got − exact| in units of the last place of the exact value rounded to f64.
fn ulps(got: f64, exact: Dd) -> f64 {
    let e = exact.to_f64();
    let a = e.abs();
    let ulp = if a < f64::MIN_POSITIVE {
        f64::from_bits(1)
    } else {
        f64::from_bits(a.to_bits() + 1) - a
    };
    ((Dd::new(got) - exact).to_f64() / ulp).abs()
}

/// Worst (sin, cos) ulp errors of `sin_cos_n` against the double-double reference, four lanes
/// at a time; also checks that libm is within 1 ulp of the reference at the same points (so the
/// reference itself is sound).
fn worst_ulps(xs: &[f64]) -> (f64, f64, f64) {
    let (mut ws, mut wc, mut wl) = (0.0f64, 0.0f64, 0.0f64);
    for chunk in xs.chunks(4) {
        let mut lanes = [0.25; 4];
        lanes[..chunk.len()].copy_from_slice(chunk);
        let (s, c) = sin_cos_n(lanes);
        for (i, &x) in chunk.iter().enumerate() {
            let (es, ec) = Dd::new(x).sin_cos();
            let (us, uc) = (ulps(s[i], es), ulps(c[i], ec));
            assert!(
                us <= 1.0 && uc <= 1.0,
                "x = {x:e}: sin {} ({us:.2} ulp), cos {} ({uc:.2} ulp)",
                s[i],
                c[i]
            );
            ws = ws.max(us);
            wc = wc.max(uc);
            let (ls, lc) = libm::sincos(x);
            wl = wl.max(ulps(ls, es)).max(ulps(lc, ec));
        }
    }
    (ws, wc, wl)
}

/// The double nearest to k·π/2 (from the double-double π), shifted by `d` ulps.
fn near_multiple(k: f64, d: i64) -> f64 {
    let x = (Dd::new(k) * dd::PI * Dd::new(0.5)).to_f64();
    f64::from_bits((x.to_bits() as i64 + d) as u64)
}

#[test]
fn within_one_ulp_on_random_arguments_up_to_1e6() {
    let mut rng = ChaCha8Rng::seed_from_u64(19);
    let mut xs: Vec<f64> = (0..100_000)
        .map(|_| {
            let m = libm::pow(10f64, rng.random_range(-8.0..6.0));
            if rng.random_bool(0.5) { m } else { -m }
        })
        .collect();
    xs.extend((0..50_000).map(|_| rng.random_range(-1e6..1e6)));
    xs.extend((0..50_000).map(|_| rng.random_range(-4.0..4.0)));
    let (ws, wc, wl) = worst_ulps(&xs);
    eprintln!("random: worst sin {ws:.3} ulp, cos {wc:.3} ulp (libm {wl:.3})");
    assert!(wl <= 1.0, "reference disagrees with libm by {wl} ulp");
}

#[test]
fn within_one_ulp_next_to_multiples_of_half_pi() {
    let mut rng = ChaCha8Rng::seed_from_u64(20);
    let mut xs = Vec::new();
    // Every multiple up to 5000 and random ones up to |x| ≈ 1e6, each with its neighbours.
    for k in 1..5000 {
        for d in -2..=2 {
            xs.push(near_multiple(k as f64, d));
            xs.push(-near_multiple(k as f64, d));
        }
    }
    for _ in 0..20_000 {
        let k = rng.random_range(1..636_600) as f64;
        let d = rng.random_range(-3..=3);
        xs.push(near_multiple(k, d));
    }
    // Half-way points between multiples, where k·(2/π) rounds either way.
    for _ in 0..20_000 {
        let k = rng.random_range(0..636_600) as f64 + 0.5;
        xs.push(near_multiple(k, rng.random_range(-2..=2)));
    }
    let (ws, wc, wl) = worst_ulps(&xs);
    eprintln!("near k·π/2: worst sin {ws:.3} ulp, cos {wc:.3} ulp (libm {wl:.3})");
}

#[test]
fn agrees_with_libm_to_one_ulp() {
    let mut rng = ChaCha8Rng::seed_from_u64(21);
    for _ in 0..50_000 {
        let x: [f64; 7] = std::array::from_fn(|_| rng.random_range(-1e6..1e6));
        let (s, c) = sin_cos_n(x);
        for i in 0..7 {
            let (ls, lc) = libm::sincos(x[i]);
            for (got, want) in [(s[i], ls), (c[i], lc)] {
                let ulp = f64::from_bits(want.abs().to_bits() + 1) - want.abs();
                assert!(
                    (got - want).abs() <= ulp,
                    "x = {:e}: {got} vs libm {want}",
                    x[i]
                );
            }
        }
    }
}

#[test]
fn outside_the_range_is_nan_lane_by_lane() {
    // A lane out of range (or not finite) is NaN; the other lanes keep the values they have
    // alone (a lane's result depends on its argument only).
    for bad in [
        1048576.5,
        -1048577.0,
        2e6,
        -1e300,
        f64::MAX,
        f64::INFINITY,
        f64::NEG_INFINITY,
        f64::NAN,
    ] {
        let x = [0.3, bad, -2.5, 1e5];
        let (s, c) = sin_cos_n(x);
        for i in 0..4 {
            if i == 1 {
                assert!(s[1].is_nan() && c[1].is_nan(), "x = {bad:e}");
            } else {
                let ([s1], [c1]) = sin_cos_n([x[i]]);
                assert_eq!((s[i], c[i]), (s1, c1), "x = {:e}", x[i]);
            }
        }
        let (s, c) = sin_cos(bad);
        assert!(s.is_nan() && c.is_nan(), "x = {bad:e}");
    }
    // Up to 2²⁰ and tiny or zero arguments: within 1 ulp of the double-double reference.
    let x = [1048576.0, -1048575.5, 0.0, -0.0, 1e-300, -5e-324];
    let (s, c) = sin_cos_n(x);
    for i in 0..x.len() {
        let (es, ec) = Dd::new(x[i]).sin_cos();
        assert!(
            ulps(s[i], es) <= 1.0 && ulps(c[i], ec) <= 1.0,
            "x = {:e}",
            x[i]
        );
    }
    assert_eq!((s[2], c[2]), (0.0, 1.0));
}

/// The one-angle helpers against the double-double reference, random and next to multiples
/// of π/2 (where the fallback reduction takes over): `sin_cos` within 1 ulp, `sin_cos_f32`
/// within 1 ulp of f32. A batch of four gives each lane what the helper gives it alone (in
/// f64 and f32), whatever the other lanes hold (one near a multiple of π/2 sends the batch
/// through the fallback).
#[test]
fn one_angle_helpers_are_accurate_and_batches_are_lane_by_lane() {
    let ulps_f32 = |got: f32, exact: Dd| {
        let e = exact.to_f64();
        let a = (e as f32).abs();
        let ulp = f32::from_bits(a.to_bits() + 1) - a;
        ((got as f64 - e) / ulp as f64).abs()
    };
    let mut rng = ChaCha8Rng::seed_from_u64(23);
    for k in 0..20_000 {
        let near = |rng: &mut ChaCha8Rng| {
            let m = rng.random_range(-60_000i64..60_000) as f64;
            m * std::f64::consts::FRAC_PI_2 + rng.random_range(-1e-9..1e-9)
        };
        let x = if k % 2 == 0 {
            rng.random_range(-1e5..1e5)
        } else {
            near(&mut rng)
        };
        let (s, c) = sin_cos(x);
        let (es, ec) = Dd::new(x).sin_cos();
        assert!(ulps(s, es) <= 1.0 && ulps(c, ec) <= 1.0, "x = {x:e}");
        let x32 = x as f32;
        let (s, c) = sin_cos_f32(x32);
        let (es, ec) = Dd::new(x32 as f64).sin_cos();
        assert!(
            ulps_f32(s, es) <= 1.0 && ulps_f32(c, ec) <= 1.0,
            "x = {x32:e}"
        );
        let lanes = [x, 0.5, -x, near(&mut rng)];
        let (s4, c4) = sin_cos_n(lanes);
        let (s4f, c4f) = sin_cos_n_f32(lanes.map(|v| v as f32));
        for l in 0..4 {
            assert_eq!((s4[l], c4[l]), sin_cos(lanes[l]), "x = {:e}", lanes[l]);
            let v = lanes[l] as f32;
            assert_eq!((s4f[l], c4f[l]), sin_cos_f32(v), "x = {v:e}");
        }
    }
}

#[test]
fn periodic_and_odd_even() {
    let mut rng = ChaCha8Rng::seed_from_u64(22);
    for _ in 0..10_000 {
        let x: [f64; 3] = std::array::from_fn(|_| rng.random_range(-1e4..1e4));
        let (s, c) = sin_cos_n(x);
        let (sn, cn) = sin_cos_n(x.map(|v| -v));
        for i in 0..3 {
            assert_eq!(sn[i], -s[i]);
            assert_eq!(cn[i], c[i]);
            assert!((s[i] * s[i] + c[i] * c[i] - 1.0).abs() < 4e-16);
        }
    }
}

/// `ANGLE_RANGE` is the kernels' range: the sine and cosine (one lane and four) are finite up
/// to it and NaN just beyond, which the CLI's range check of joint angles relies on.
#[test]
fn the_angle_range_is_where_sine_and_cosine_end() {
    let r = bf_codegen::trig::ANGLE_RANGE;
    // The scene's validation refuses DH angles beyond the same range.
    assert_eq!(r, bf_scene::MAX_ANGLE);
    for x in [r, -r] {
        let (s, c) = sin_cos(x);
        assert!(s.is_finite() && c.is_finite(), "{x}");
    }
    let beyond = r * (1.0 + f64::EPSILON);
    for x in [beyond, -beyond] {
        let (s, c) = sin_cos(x);
        assert!(s.is_nan() && c.is_nan(), "{x}");
        let (s4, c4) = sin_cos_n([x, 0.5, x, 1.0]);
        assert!(s4[0].is_nan() && c4[2].is_nan() && s4[1].is_finite(), "{x}");
    }
}
