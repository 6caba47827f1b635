//! Angle strings and numbers in scene files: exact multiples of π, degrees, radians.

mod common;

use bf_scene::Angle;
use common::*;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use std::f64::consts::PI;

#[test]
fn angle_strings_parse_exactly() {
    for (s, want) in [
        ("pi/2", pm(1, 2)),
        ("-pi/2", pm(-1, 2)),
        ("3*pi/4", pm(3, 4)),
        ("3pi/4", pm(3, 4)),
        ("3 * pi / 4", pm(3, 4)),
        ("pi", pm(1, 1)),
        ("-pi", pm(-1, 1)),
        ("+pi/3", pm(1, 3)),
        ("PI/6", pm(1, 6)),
        ("π/2", pm(1, 2)),
        ("2*pi/4", pm(1, 2)),
        ("0.5*pi", pm(1, 2)),
        ("0*pi", pm(0, 1)),
        ("0", pm(0, 1)),
        ("-0", pm(0, 1)),
        ("0.0", pm(0, 1)),
        ("90deg", pm(1, 2)),
        ("-90 deg", pm(-1, 2)),
        ("180deg", pm(1, 1)),
        ("360deg", pm(2, 1)),
        ("1deg", pm(1, 180)),
        ("22.5deg", pm(1, 8)),
        ("-45 degrees", pm(-1, 4)),
        ("100deg", pm(5, 9)),
        ("90°", pm(1, 2)),
    ] {
        assert_eq!(Angle::parse_str(s), Ok(want), "{s}");
    }
    for bad in [
        "", "1.5", "pi/0", "pi/x", "pie", "x deg", "pi/2.5", "1e3deg", "pi/-2", "--pi", "pi pi",
        "deg", "2 pi 3",
    ] {
        let e = Angle::parse_str(bad).unwrap_err();
        assert!(e.contains("invalid angle"), "{bad}: {e}");
    }
    // An exponent is named as the reason, whatever the number's size.
    for bad in ["1e400", "1e3deg", "2.5E2 degrees"] {
        let e = Angle::parse_str(bad).unwrap_err();
        assert!(e.contains("exponent"), "{bad}: {e}");
    }
}

#[test]
fn angle_numbers_are_radians_and_exact_multiples_evaluate_correctly() {
    #[derive(serde::Deserialize)]
    struct W {
        a: Angle,
    }
    let w: W = toml::from_str("a = 1.5").unwrap();
    assert_eq!(w.a, Angle::Radians(1.5));
    let w: W = toml::from_str("a = -2").unwrap();
    assert_eq!(w.a, Angle::Radians(-2.0));
    let w: W = toml::from_str("a = \"-3*pi/4\"").unwrap();
    assert_eq!(w.a, pm(-3, 4));

    assert_eq!(pm(1, 2).radians(), PI / 2.0);
    assert_eq!(pm(-1, 1).radians(), -PI);
    assert!((pm(-3, 4).radians() + 0.75 * PI).abs() < 1e-15);
    assert_eq!(Angle::Radians(0.3).radians(), 0.3);
    // Exact cos/sin at quarter turns (no 6e-17 residue), f64 values elsewhere.
    assert_eq!(pm(1, 2).cos_sin(), (0.0, 1.0));
    assert_eq!(pm(-1, 2).cos_sin(), (0.0, -1.0));
    assert_eq!(pm(1, 1).cos_sin(), (-1.0, 0.0));
    assert_eq!(pm(3, 2).cos_sin(), (0.0, -1.0));
    assert_eq!(pm(-5, 2).cos_sin(), (0.0, -1.0));
    assert_eq!(pm(4, 1).cos_sin(), (1.0, 0.0));
    let (c, s) = pm(1, 3).cos_sin();
    assert!((c - 0.5).abs() < 1e-15 && (s - 3f64.sqrt() / 2.0).abs() < 1e-15);
    assert_eq!(Angle::pi_multiple(6, -8), Some(pm(-3, 4)));
    assert_eq!(Angle::pi_multiple(1, 0), None);
}

#[test]
fn random_degree_and_pi_fraction_strings_round_trip() {
    let mut rng = ChaCha8Rng::seed_from_u64(7);
    for _ in 0..2000 {
        let k: i64 = rng.random_range(-100_000..100_000);
        let Ok(Angle::PiMultiple { num, den }) = Angle::parse_str(&format!("{k}deg")) else {
            panic!("{k}deg");
        };
        // num/den = k/180 exactly, in lowest terms, den > 0.
        assert_eq!(num * 180, k * den, "{k}deg");
        assert!(den > 0 && gcd(num, den) == 1);
        let (n, d): (i64, i64) = (rng.random_range(-50..50), rng.random_range(1..50));
        let a = Angle::parse_str(&format!("{n}*pi/{d}")).unwrap();
        assert!(
            (a.radians() - n as f64 * PI / d as f64).abs() <= 1e-13,
            "{n}*pi/{d}"
        );
        let Angle::PiMultiple { num, den } = a else {
            panic!()
        };
        assert_eq!(num * d, n * den);
    }
}

fn gcd(a: i64, b: i64) -> i64 {
    if b == 0 { a.abs() } else { gcd(b, a % b) }
}
