//! Axis ticks whose labels state exactly the value at their position.
//!
//! Linear axes: steps m·10^k with m ∈ {1, 2, 5}; tick i sits at i·m·10^k and its label is the
//! exact decimal of the integer i·m times 10^k ([`decimal`]), so a label never rounds.
//! Logarithmic (decadic) axes: major ticks at the decades 10^e, minor ticks at m·10^e
//! (m = 2…9) at their true positions log10(m) + e. Labels are "me" strings such as `1e-7`,
//! `2e-7`, or plain decimals (`0.5`, `20`, `1000`) on an axis whose values all lie in
//! 0.001 … 99 999; the densest labelling (all mantissas, then 1-2-5, then decades, then every 2nd, 5th,
//! … decade) whose labels do not collide is chosen by the caller's `fits` test. A log axis
//! spanning less than two labellable mantissas falls back to linear ticks mapped to log10.

/// One tick in plotting coordinates (log10 of the value on log axes).
#[derive(Clone, Debug, PartialEq)]
pub struct Tick {
    /// Position in plotting coordinates.
    pub pos: f64,
    /// Label text (`None`: unlabelled minor tick).
    pub label: Option<String>,
}

/// Exact decimal text of `mant · 10^exp` (no rounding): plain notation when the leading digit's
/// exponent is in −4..=5, otherwise scientific (`1.5e-7`). Zero is `0` (never `-0`).
pub fn decimal(mant: i64, exp: i32) -> String {
    if mant == 0 {
        return "0".into();
    }
    let (mut m, mut e) = (mant.unsigned_abs(), exp);
    while m % 10 == 0 {
        m /= 10;
        e += 1;
    }
    let digits = m.to_string();
    let d = digits.len() as i32;
    let lead = e + d - 1;
    let body = if (-4..=5).contains(&lead) {
        if e >= 0 {
            format!("{digits}{}", "0".repeat(e as usize))
        } else if d > -e {
            let cut = (d + e) as usize;
            format!("{}.{}", &digits[..cut], &digits[cut..])
        } else {
            format!("0.{}{digits}", "0".repeat((-e - d) as usize))
        }
    } else if d > 1 {
        format!("{}.{}e{lead}", &digits[..1], &digits[1..])
    } else {
        format!("{digits}e{lead}")
    };
    if mant < 0 { format!("-{body}") } else { body }
}

/// Linear ticks on [lo, hi]: the smallest 1-2-5 step giving at most `max_ticks` ticks whose
/// labels pass `fits` (which gets the labelled ticks in increasing order).
pub fn linear_ticks(
    lo: f64,
    hi: f64,
    max_ticks: usize,
    fits: &dyn Fn(&[Tick]) -> bool,
) -> Vec<Tick> {
    linear_ticks_of_step(lo, hi, max_ticks, i32::MIN, fits)
}

/// [`linear_ticks`] with steps of at least 10^`min_exp` (0: whole numbers, for an axis of
/// counts); empty when no such tick lies in the range.
pub fn linear_ticks_of_step(
    lo: f64,
    hi: f64,
    max_ticks: usize,
    min_exp: i32,
    fits: &dyn Fn(&[Tick]) -> bool,
) -> Vec<Tick> {
    if !(lo.is_finite() && hi.is_finite() && hi > lo) {
        return Vec::new();
    }
    let span = hi - lo;
    let max_ticks = max_ticks.max(2) as f64;
    let mut k = (libm::log10(span / max_ticks).floor() as i32 - 1).max(min_exp);
    let mut last = Vec::new();
    // A range that ends a rounding short of a tick (a period of 9.99998 s) keeps that tick:
    // it is drawn within a hundred-thousandth of the span of the axis' end.
    let slack = 1e-5 * span;
    for _ in 0..12 {
        for m in [1i64, 2, 5] {
            let step = m as f64 * 10f64.powi(k);
            let (i0, i1) = (
                ((lo - slack) / step).ceil() as i64,
                ((hi + slack) / step).floor() as i64,
            );
            if (i1 - i0 + 1) as f64 > max_ticks {
                continue;
            }
            let ticks: Vec<Tick> = (i0..=i1)
                .map(|i| Tick {
                    pos: (i * m) as f64 * 10f64.powi(k),
                    label: Some(decimal(i * m, k)),
                })
                .collect();
            if fits(&ticks) || i1 <= i0 {
                return ticks;
            }
            last = ticks;
        }
        k += 1;
    }
    last
}

/// Logarithmic ticks on [10^lo, 10^hi] (`lo`, `hi` in log10 units); see the module docs.
pub fn log_ticks(lo: f64, hi: f64, fits: &dyn Fn(&[Tick]) -> bool) -> Vec<Tick> {
    if !(lo.is_finite() && hi.is_finite() && hi > lo) {
        return Vec::new();
    }
    let eps = 1e-9 * (hi - lo).max(1.0);
    let inside = |p: f64| p >= lo - eps && p <= hi + eps;
    let (e0, e1) = (lo.floor() as i32, hi.ceil() as i32);
    let decades = e1 - e0;
    // Every mantissa tick in range (minor ticks only up to 8 decades, else decades only).
    let mut all: Vec<(i64, i32)> = Vec::new();
    for e in e0..=e1 {
        for m in 1..=9i64 {
            if m > 1 && decades > 8 {
                break;
            }
            if inside(libm::log10(m as f64) + e as f64) {
                all.push((m, e));
            }
        }
    }
    let pos = |(m, e): (i64, i32)| libm::log10(m as f64) + e as f64;
    // An axis whose values all read plainly (0.001 to 99 999: percents, ratios, seconds) is
    // labelled in plain decimals, as its linear ticks would be; any other keeps one notation,
    // "me", for all its labels.
    let plain = all.iter().all(|&(_, e)| (-3..=4).contains(&e));
    let label = |(m, e): (i64, i32)| {
        if plain {
            decimal(m, e)
        } else {
            format!("{m}e{e}")
        }
    };
    let build = |keep: &dyn Fn((i64, i32)) -> bool| -> Vec<Tick> {
        all.iter()
            .map(|&me| Tick {
                pos: pos(me),
                label: keep(me).then(|| label(me)),
            })
            .collect()
    };
    let labelled = |t: &[Tick]| {
        t.iter()
            .filter(|t| t.label.is_some())
            .cloned()
            .collect::<Vec<_>>()
    };
    let mut candidates: Vec<Vec<Tick>> = vec![
        build(&|_| true),
        build(&|(m, _)| matches!(m, 1 | 2 | 5)),
        build(&|(m, _)| m == 1),
    ];
    for every in [2, 3, 5, 10, 20, 50, 100] {
        if every < decades {
            candidates.push(build(&|(m, e)| m == 1 && e.rem_euclid(every) == 0));
        }
    }
    let usable: Vec<Vec<Tick>> = candidates
        .into_iter()
        .filter(|c| labelled(c).len() >= 2)
        .collect();
    if usable.is_empty() {
        // Less than two labellable mantissas (a narrow range): nice linear values, placed at
        // their logarithm.
        let (a, b) = (libm::pow(10f64, lo), libm::pow(10f64, hi));
        return linear_ticks(a, b, 6, &|t: &[Tick]| {
            let moved: Vec<Tick> = t
                .iter()
                .map(|t| Tick {
                    pos: libm::log10(t.pos),
                    label: t.label.clone(),
                })
                .collect();
            fits(&moved)
        })
        .into_iter()
        .filter(|t| t.pos > 0.0)
        .map(|t| Tick {
            pos: libm::log10(t.pos),
            label: t.label,
        })
        .collect();
    }
    let n = usable.len();
    for (i, c) in usable.iter().enumerate() {
        if fits(&labelled(c)) || i + 1 == n {
            return c.clone();
        }
    }
    Vec::new()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn decimal_is_exact() {
        assert_eq!(decimal(0, -3), "0");
        assert_eq!(decimal(25, -2), "0.25");
        assert_eq!(decimal(-5, -1), "-0.5");
        assert_eq!(decimal(120, 0), "120");
        assert_eq!(decimal(2, 3), "2000");
        assert_eq!(decimal(15, -8), "1.5e-7");
        assert_eq!(decimal(2, -7), "2e-7");
        assert_eq!(decimal(3, -4), "0.0003");
        assert_eq!(decimal(12, 6), "1.2e7");
        assert_eq!(decimal(1000, -3), "1");
    }

    fn all_fit(_: &[Tick]) -> bool {
        true
    }

    #[test]
    fn linear_labels_equal_positions() {
        for (lo, hi) in [
            (0.0, 2.5),
            (-0.153, 0.149),
            (1e-9, 7.3e-9),
            (-3e6, 1e7),
            (0.77, 0.81),
        ] {
            let t = linear_ticks(lo, hi, 8, &all_fit);
            assert!((2..=8).contains(&t.len()), "{lo} {hi}: {t:?}");
            for tk in &t {
                let v: f64 = tk.label.as_deref().unwrap().parse().unwrap();
                assert!((v - tk.pos).abs() <= 1e-12 * (hi - lo), "{tk:?}");
                assert!(tk.pos >= lo && tk.pos <= hi);
            }
            // Equal spacing.
            let d = t[1].pos - t[0].pos;
            assert!(
                t.windows(2)
                    .all(|w| ((w[1].pos - w[0].pos) - d).abs() < 1e-9 * d)
            );
        }
    }

    #[test]
    fn a_range_a_rounding_short_of_a_tick_keeps_it() {
        let t = linear_ticks(0.0, 9.99998, 11, &all_fit);
        let labels: Vec<&str> = t.iter().filter_map(|t| t.label.as_deref()).collect();
        assert_eq!(labels.last(), Some(&"10"), "{labels:?}");
        // Not a tick that is really beyond the range.
        let t = linear_ticks(0.0, 9.9, 11, &all_fit);
        assert!(t.iter().all(|t| t.pos <= 9.9), "{t:?}");
    }

    #[test]
    fn log_ticks_sit_at_true_positions() {
        // 1e-7 .. 1e-6: every mantissa labelled, "2e-7" exactly at log10(2e-7).
        let t = log_ticks(-7.0, -6.0, &all_fit);
        assert_eq!(t.len(), 10);
        for tk in &t {
            let v: f64 = tk.label.as_deref().unwrap().parse().unwrap();
            assert!((libm::log10(v) - tk.pos).abs() < 1e-12, "{tk:?}");
        }
        let two = t
            .iter()
            .find(|t| t.label.as_deref() == Some("2e-7"))
            .unwrap();
        assert!((two.pos - libm::log10(2e-7f64)).abs() < 1e-12);
        // An axis of plain values (a percentage from 0.1 to 1000) reads in decimals.
        let pct = log_ticks(-1.0, 3.0, &|l: &[Tick]| l.len() <= 5);
        let labels: Vec<&str> = pct.iter().filter_map(|t| t.label.as_deref()).collect();
        assert_eq!(labels, ["0.1", "1", "10", "100", "1000"]);
        // Only decades fit: minor ticks stay, unlabelled, at m·10^e.
        let dec = log_ticks(-9.0, -3.0, &|l: &[Tick]| l.len() <= 7);
        let labels: Vec<&str> = dec.iter().filter_map(|t| t.label.as_deref()).collect();
        assert_eq!(
            labels,
            ["1e-9", "1e-8", "1e-7", "1e-6", "1e-5", "1e-4", "1e-3"]
        );
        assert!(
            dec.iter()
                .any(|t| (t.pos - libm::log10(3e-6f64)).abs() < 1e-12)
        );
        // Many decades: every 5th labelled.
        let wide = log_ticks(-16.0, 0.0, &|l: &[Tick]| l.len() <= 5);
        let labels: Vec<&str> = wide.iter().filter_map(|t| t.label.as_deref()).collect();
        assert_eq!(labels, ["1e-15", "1e-10", "1e-5", "1e0"]);
        // Narrow range inside one mantissa step: linear values at their logarithm.
        let narrow = log_ticks(libm::log10(2.1e-7f64), libm::log10(2.9e-7f64), &all_fit);
        assert!(narrow.len() >= 2);
        for tk in &narrow {
            let v: f64 = tk.label.as_deref().unwrap().parse().unwrap();
            assert!((libm::log10(v) - tk.pos).abs() < 1e-12 && (2.1e-7..=2.9e-7).contains(&v));
        }
    }
}
