//! Accuracy of the emitted `sin_cos` (trig.rs) and of the double-double reference.

use bf_codegen::dd::Dd;
use bf_codegen::trig::sin_cos;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

fn ulp(x: f64) -> f64 {
    let a = x.abs().max(f64::MIN_POSITIVE);
    f64::from_bits(a.to_bits() + 1) - a
}

/// Error of `got` against the double-double `exact`, in ulps of the exact value.
fn ulps(got: f64, exact: Dd) -> f64 {
    let err = (Dd::new(got) - exact).to_f64().abs();
    err / ulp(exact.to_f64())
}

#[test]
fn dd_sin_cos_agrees_with_libm() {
    // Independent check of the reference itself: libm is within ~1 ulp.
    let mut rng = ChaCha8Rng::seed_from_u64(7);
    for _ in 0..20_000 {
        let x: f64 = rng.random_range(-1e3..1e3);
        let (s, c) = Dd::new(x).sin_cos();
        let (ls, lc) = x.sin_cos();
        assert!(ulps(ls, s) <= 1.0, "sin {x}");
        assert!(ulps(lc, c) <= 1.0, "cos {x}");
        // sin² + cos² = 1 in double-double.
        let one = s * s + c * c;
        assert!((one.to_f64() - 1.0).abs() < 1e-28 || (one - Dd::new(1.0)).to_f64().abs() < 1e-28);
    }
}

#[test]
fn sin_cos_is_within_one_ulp() {
    let mut rng = ChaCha8Rng::seed_from_u64(8);
    let ranges = [1e-8, 1.0, 4.0, 100.0, 1e4, 1e6, 1.59e6, 1e9];
    let mut worst = 0.0f64;
    for &r in &ranges {
        for _ in 0..20_000 {
            let x: f64 = rng.random_range(-r..r);
            let (s, c) = sin_cos(x);
            let (es, ec) = Dd::new(x).sin_cos();
            worst = worst.max(ulps(s, es)).max(ulps(c, ec));
            assert!(ulps(s, es) <= 1.0, "sin({x}) = {s}, exact {}", es.to_f64());
            assert!(ulps(c, ec) <= 1.0, "cos({x}) = {c}, exact {}", ec.to_f64());
        }
    }
    // Hard cases: near multiples of π/2 (cancellation in the reduction).
    for k in 1..2000i64 {
        let x = (k as f64) * std::f64::consts::FRAC_PI_2;
        for d in [-2i64, -1, 0, 1, 2] {
            let y = f64::from_bits((x.to_bits() as i64 + d) as u64);
            let (s, c) = sin_cos(y);
            let (es, ec) = Dd::new(y).sin_cos();
            assert!(ulps(s, es) <= 1.0, "sin({y})");
            assert!(ulps(c, ec) <= 1.0, "cos({y})");
        }
    }
    assert!(worst <= 1.0, "worst {worst} ulp");
}

#[test]
fn sin_cos_special_values() {
    assert_eq!(sin_cos(0.0), (0.0, 1.0));
    let (s, c) = sin_cos(f64::NAN);
    assert!(s.is_nan() && c.is_nan());
    let (s, c) = sin_cos(f64::INFINITY);
    assert!(s.is_nan() && c.is_nan());
    let (s, _) = sin_cos(-0.0);
    assert!(s == 0.0 && s.is_sign_negative());
}
