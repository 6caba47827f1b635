//! The planned gap of a reference phase against closed forms: the cubic Hermite interpolant
//! of h* (what the approach's re-timing inverts) reproduces a quadratic h*(s) and its rate
//! exactly, and `time_of_gap` returns the root of the quadratic, the time at which the plan
//! is at a given gap.

use bf_control::ReferencePhase;

/// h*(s) = A − B s − C s², falling on [0, 0.1] from 20 mm to 0.
const A: f64 = 0.02;
const B: f64 = 0.1;
const C: f64 = 1.0;

fn gap(s: f64) -> f64 {
    A - B * s - C * s * s
}

fn gap_rate(s: f64) -> f64 {
    -B - 2.0 * C * s
}

/// A free phase of 0.1 s with 5 unevenly spaced samples of the quadratic gap.
fn phase() -> ReferencePhase {
    let s = vec![0.0, 0.02, 0.05, 0.07, 0.1];
    let n = s.len();
    ReferencePhase {
        contact: false,
        duration: 0.1,
        gap: s.iter().map(|&s| gap(s)).collect(),
        gap_rate: s.iter().map(|&s| gap_rate(s)).collect(),
        s,
        q: vec![[0.0; 3]; n],
        qd: vec![[0.0; 3]; n],
        qdd: vec![[0.0; 3]; n],
        omega: vec![[0.0; 3]; n],
        omega_dot: vec![[0.0; 3]; n],
        lambda: vec![[0.0; 3]; n],
        contact_point: vec![[0.0; 3]; n],
        contact_point_dot: vec![[0.0; 3]; n],
    }
}

#[test]
fn hermite_gap_reproduces_a_quadratic_and_its_rate() {
    let ph = phase();
    for k in 0..=100 {
        let s = 0.001 * k as f64;
        let (h, hd) = ph.gap_at(s);
        assert!((h - gap(s)).abs() < 1e-15, "s {s}: {h} vs {}", gap(s));
        assert!(
            (hd - gap_rate(s)).abs() < 1e-13,
            "s {s}: {hd} vs {}",
            gap_rate(s)
        );
    }
}

#[test]
fn time_of_gap_is_the_root_of_the_planned_gap() {
    let ph = phase();
    let from = 0.03;
    for k in 1..40 {
        let h = gap(from) * k as f64 / 40.0;
        // A − B s − C s² = h.
        let root = (-B + (B * B + 4.0 * C * (A - h)).sqrt()) / (2.0 * C);
        let sigma = ph.time_of_gap(h, from);
        assert!((sigma - root).abs() < 1e-13, "h {h}: {sigma} vs {root}");
    }
    // Above the window's top: its start; below the last sample's gap: the phase's end.
    assert_eq!(ph.time_of_gap(gap(from) + 1e-3, from), from);
    assert_eq!(ph.time_of_gap(-1e-3, from), 0.1);
    assert_eq!(ph.time_of_gap(f64::NAN, from), from);
}
