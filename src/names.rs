//! The names user output gives enum values (modes, solver statuses, guesses, integrators):
//! the same text as their serde name in the JSON files, so a mode is `stick` in the report,
//! the CSV files and the JSON alike, and no Rust `Debug` text (`Some(Slip)`,
//! `Rk4 { h: 0.01 }`) reaches a user.

use bf_sim::Method;
use serde::Serialize;

/// The serde name of a unit enum value (e.g. `Mode::Stick` → `stick`,
/// `Status::Solved` → `Solved`); for anything that is not serialised as a string, its JSON
/// text.
pub fn name<T: Serialize>(v: &T) -> String {
    match serde_json::to_value(v) {
        Ok(serde_json::Value::String(s)) => s,
        Ok(other) => other.to_string(),
        Err(e) => format!("<unnamed: {e}>"),
    }
}

/// The names of a list of enum values, comma-separated.
pub fn names<T: Serialize>(v: &[T]) -> String {
    v.iter().map(name).collect::<Vec<_>>().join(", ")
}

/// `before → after` of a transition; `end` when the reset terminated the run.
pub fn transition<T: Serialize>(before: &T, after: Option<&T>) -> String {
    format!(
        "{} → {}",
        name(before),
        after.map_or("end".to_string(), name)
    )
}

/// An integrator with its settings: `dopri5`, `rk4 (h = 0.01 s)`.
pub fn method(m: &Method) -> String {
    match m {
        Method::Dopri5 => "dopri5".to_string(),
        Method::Rk4 { h } => format!("rk4 (h = {h} s)"),
    }
}

/// Significant digits [`tidy`] keeps of a long number.
pub const TIDY_DIGITS: usize = 6;

/// Significant digits from which [`tidy`] counts a decimal number as long: the full-precision
/// text of an f64 (16–17 digits), not a number someone wrote with 7 on purpose.
pub const LONG_DIGITS: usize = 8;

/// `text` (an error message of a lower layer, written for a log) made fit for a table cell:
/// every decimal number (with a point or an exponent) of [`LONG_DIGITS`] or more significant
/// digits rounded to [`TIDY_DIGITS`]
/// (`105.45815353035756` → `105.458`, `-5.459312364956617e-1` → `-5.45931e-1`), and a mode
/// named in Rust's spelling written as the files write it (`mode Free` → `mode free`). Short
/// numbers, integers and digits inside names (`q2`, `link3`) are left as they are.
pub fn tidy(text: &str) -> String {
    let mut out = String::with_capacity(text.len());
    let b = text.as_bytes();
    let mut i = 0;
    while i < b.len() {
        let starts_number = b[i].is_ascii_digit()
            && (i == 0
                || !(b[i - 1].is_ascii_alphanumeric() || b[i - 1] == b'_' || b[i - 1] == b'.'));
        if !starts_number {
            let c = text[i..].chars().next().unwrap_or(' ');
            out.push(c);
            i += c.len_utf8();
            continue;
        }
        let start = i;
        while i < b.len() && b[i].is_ascii_digit() {
            i += 1;
        }
        if i + 1 < b.len() && b[i] == b'.' && b[i + 1].is_ascii_digit() {
            i += 1;
            while i < b.len() && b[i].is_ascii_digit() {
                i += 1;
            }
        }
        let mantissa_end = i;
        let point = text[start..mantissa_end].contains('.');
        let mut exponent = false;
        if i < b.len() && (b[i] == b'e' || b[i] == b'E') {
            let mut j = i + 1;
            if j < b.len() && (b[j] == b'-' || b[j] == b'+') {
                j += 1;
            }
            if j < b.len() && b[j].is_ascii_digit() {
                while j < b.len() && b[j].is_ascii_digit() {
                    j += 1;
                }
                i = j;
                exponent = true;
            }
        }
        let token = &text[start..i];
        let digits = text[start..mantissa_end]
            .bytes()
            .filter(u8::is_ascii_digit)
            .skip_while(|&d| d == b'0')
            .count();
        match token.parse::<f64>() {
            Ok(v) if (point || exponent) && digits >= LONG_DIGITS && v.is_finite() => {
                out.push_str(&round(v, exponent))
            }
            _ => out.push_str(token),
        }
    }
    for m in ["Free", "Stick", "Slip"] {
        out = out.replace(&format!("mode {m}"), &format!("mode {}", m.to_lowercase()));
    }
    out
}

/// `v` with [`TIDY_DIGITS`] significant digits, trailing zeros dropped; in exponent form
/// where the original was, or where the fixed form would be long.
fn round(v: f64, exponent: bool) -> String {
    let mag = if v == 0.0 {
        0
    } else {
        libm::log10(v.abs()).floor() as i32
    };
    if exponent || !(-3..6).contains(&mag) {
        let s = format!("{v:.*e}", TIDY_DIGITS - 1);
        let (m, e) = s.split_once('e').unwrap_or((&s, "0"));
        let m = if m.contains('.') {
            m.trim_end_matches('0').trim_end_matches('.')
        } else {
            m
        };
        format!("{m}e{e}")
    } else {
        let decimals = (TIDY_DIGITS as i32 - 1 - mag).max(0) as usize;
        let s = format!("{v:.decimals$}");
        if s.contains('.') {
            s.trim_end_matches('0').trim_end_matches('.').to_string()
        } else {
            s
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use bf_model::Mode;
    use bf_optim::ipm::Status;

    #[test]
    fn tidy_rounds_long_numbers_and_lowercases_modes() {
        assert_eq!(
            tidy(
                "17 chained instantaneous transitions at t = 105.45815353035756 (mode Free); \
                 reset loop"
            ),
            "17 chained instantaneous transitions at t = 105.458 (mode free); reset loop"
        );
        assert_eq!(
            tidy(
                "slip normal inverse mass -5.459312364956617e-1 <= 0, free normal acceleration -5.459312916272243e1"
            ),
            "slip normal inverse mass -5.45931e-1 <= 0, free normal acceleration -5.45931e1"
        );
        // Short numbers, integers, names with digits and versions stay as written.
        let kept = "q2 = 0.01, link3.mass ×1e-3, 1234567 steps, v0.1.0, h = 2.5e-3";
        assert_eq!(tidy(kept), kept);
        assert_eq!(tidy("t = 0.000123456789 s"), "t = 1.23457e-4 s");
        assert_eq!(tidy("μ_k = 1.383737e0"), "μ_k = 1.383737e0");
    }

    #[test]
    fn names_are_the_json_names_without_debug_text() {
        assert_eq!(name(&Mode::Stick), "stick");
        assert_eq!(name(&Status::MaxIterations), "MaxIterations");
        assert_eq!(transition(&Mode::Free, Some(&Mode::Slip)), "free → slip");
        assert_eq!(transition(&Mode::Stick, None), "stick → end");
        let rk = method(&Method::Rk4 { h: 0.01 });
        assert_eq!(rk, "rk4 (h = 0.01 s)");
        // JSON of the same values: the text above is what a reader finds in the files.
        assert_eq!(serde_json::to_string(&Mode::Stick).unwrap(), "\"stick\"");
        for s in [method(&Method::Dopri5), rk] {
            assert!(!s.contains("{ ") && !s.contains("Some("), "{s}");
        }
    }
}
