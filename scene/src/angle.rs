//! Exact angles of a scene file ([`Angle`]): parsing of `"pi/2"`, `"-pi/2"`, `"3*pi/4"`,
//! `"90deg"` and plain radians, and its serde deserialiser.
//!
//! Rational multiples of π are kept exact (`num/den`, reduced with `gcd`; decimal factors are
//! read exactly by `parse_decimal`), so the DH angles α_i and offsets of paper Table 1 such as
//! α = π/2 give cos(π/2) = 0 exactly in the generated code.

use serde::Deserialize;

use super::Angle;

fn gcd(mut a: i128, mut b: i128) -> i128 {
    a = a.abs();
    b = b.abs();
    while b != 0 {
        let t = a % b;
        a = b;
        b = t;
    }
    a
}

impl Angle {
    /// `num/den · π`, reduced to lowest terms with `den > 0`; `None` if `den == 0` or the
    /// reduced fraction does not fit in `i64`.
    pub fn pi_multiple(num: i64, den: i64) -> Option<Angle> {
        Self::pi_multiple_wide(i128::from(num), i128::from(den))
    }

    fn pi_multiple_wide(num: i128, den: i128) -> Option<Angle> {
        if den == 0 {
            return None;
        }
        let g = gcd(num, den).max(1);
        let (mut n, mut d) = (num / g, den / g);
        if d < 0 {
            n = -n;
            d = -d;
        }
        if n == 0 {
            d = 1;
        }
        Some(Angle::PiMultiple {
            num: i64::try_from(n).ok()?,
            den: i64::try_from(d).ok()?,
        })
    }

    /// The angle in radians (for `PiMultiple`, `num · π / den` rounded once per operation).
    pub fn radians(&self) -> f64 {
        match *self {
            Angle::Radians(x) => x,
            Angle::PiMultiple { num, den } => {
                if num == 0 {
                    0.0
                } else {
                    num as f64 * std::f64::consts::PI / den as f64
                }
            }
        }
    }

    /// `(cos, sin)` of the angle; exact (0, ±1) for multiples of π/2, so that a rotation by
    /// "pi/2" has exact zeros. Otherwise the f64 values of `radians()`.
    pub fn cos_sin(&self) -> (f64, f64) {
        if let Angle::PiMultiple { num, den } = *self {
            // Multiples of π/2: reduce num/den·π modulo 2π to a quarter-turn index.
            if den == 1 || den == 2 {
                let quarter = (i128::from(num) * (2 / i128::from(den))).rem_euclid(4);
                return match quarter {
                    0 => (1.0, 0.0),
                    1 => (0.0, 1.0),
                    2 => (-1.0, 0.0),
                    _ => (0.0, -1.0),
                };
            }
        }
        let x = self.radians();
        (libm::cos(x), libm::sin(x))
    }

    /// Parses the string form of an angle: `"pi/2"`, `"-pi/2"`, `"3*pi/4"`, `"3pi/4"`,
    /// `"0.5*pi"`, `"pi"`, `"π/2"`, `"0"`, `"90deg"`, `"-90 deg"`, `"22.5deg"`, `"90°"`. Every form
    /// is a rational multiple of π and is returned exactly as a reduced [`Angle::PiMultiple`].
    /// A plain non-zero number in a string is rejected (write radians as a TOML number).
    pub fn parse_str(text: &str) -> Result<Angle, String> {
        let bad = |why: &str| {
            format!(
                "invalid angle {text:?}: {why}; expected a TOML number (radians) or an exact \
                 string such as \"pi/2\", \"-3*pi/4\", \"90deg\""
            )
        };
        let mut s: String = text
            .chars()
            .filter(|c| !c.is_whitespace())
            .collect::<String>()
            .to_lowercase();
        s = s.replace('π', "pi").replace('°', "deg");
        if s.is_empty() {
            return Err(bad("empty string"));
        }
        let (negative, body) = match s.as_bytes()[0] {
            b'-' => (true, &s[1..]),
            b'+' => (false, &s[1..]),
            _ => (false, &s[..]),
        };
        let sign: i128 = if negative { -1 } else { 1 };
        let deg_body = body
            .strip_suffix("degrees")
            .or_else(|| body.strip_suffix("degree"))
            .or_else(|| body.strip_suffix("deg"));
        let (num, den) = if let Some(b) = deg_body {
            let (n, d) = parse_decimal(b).map_err(|e| bad(&e))?;
            (
                sign * n,
                d.checked_mul(180).ok_or_else(|| bad("too many digits"))?,
            )
        } else if let Some(at) = body.find("pi") {
            let before = &body[..at];
            let after = &body[at + 2..];
            let before = before.strip_suffix('*').unwrap_or(before);
            let (cn, cd) = if before.is_empty() {
                (1, 1)
            } else {
                parse_decimal(before).map_err(|e| bad(&e))?
            };
            let extra_den: i128 = if after.is_empty() {
                1
            } else if let Some(d) = after.strip_prefix('/') {
                let (dn, dd) = parse_decimal(d).map_err(|e| bad(&e))?;
                if dd != 1 {
                    return Err(bad("the denominator must be an integer"));
                }
                if dn == 0 {
                    return Err(bad("division by zero"));
                }
                dn
            } else {
                return Err(bad(&format!("unexpected {after:?} after \"pi\"")));
            };
            (
                sign * cn,
                cd.checked_mul(extra_den)
                    .ok_or_else(|| bad("too many digits"))?,
            )
        } else {
            let (n, _) = parse_decimal(body).map_err(|e| bad(&e))?;
            if n != 0 {
                return Err(bad(
                    "a plain number is not an exact multiple of pi; write radians as a TOML \
                     number without quotes",
                ));
            }
            (0, 1)
        };
        Angle::pi_multiple_wide(num, den).ok_or_else(|| bad("numbers too large"))
    }
}

/// Parses an unsigned decimal `123`, `22.5`, `.5` into an exact fraction (num, den), den > 0.
fn parse_decimal(s: &str) -> Result<(i128, i128), String> {
    if s.is_empty() {
        return Err("missing number".to_string());
    }
    let (int, frac) = match s.split_once('.') {
        Some((i, f)) => (i, f),
        None => (s, ""),
    };
    if int.is_empty() && frac.is_empty() {
        return Err(format!("{s:?} is not a number"));
    }
    if !int.chars().chain(frac.chars()).all(|c| c.is_ascii_digit()) {
        // An angle string is exact: digits and one point, so "1e400" (whatever its size) is
        // refused for its exponent, which the message says rather than blaming the number.
        if s.contains(['e', 'E']) && s.parse::<f64>().is_ok() {
            return Err(format!(
                "{s:?} has an exponent: an angle string takes digits and one point \
                 (a TOML number without quotes is radians)"
            ));
        }
        return Err(format!("{s:?} is not a decimal number"));
    }
    if int.len() + frac.len() > 18 {
        return Err("too many digits".to_string());
    }
    let mut num: i128 = 0;
    for c in int.chars().chain(frac.chars()) {
        num = num * 10 + i128::from(c as u8 - b'0');
    }
    let den = 10i128.pow(frac.len() as u32);
    Ok((num, den))
}

impl Default for Angle {
    /// Zero radians (the DH `alpha` of a link in placement form, where it is not used).
    fn default() -> Self {
        Angle::Radians(0.0)
    }
}

impl std::str::FromStr for Angle {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        Angle::parse_str(s)
    }
}

impl<'de> Deserialize<'de> for Angle {
    fn deserialize<D: serde::Deserializer<'de>>(deserializer: D) -> Result<Self, D::Error> {
        struct V;
        impl serde::de::Visitor<'_> for V {
            type Value = Angle;
            fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
                f.write_str("an angle: a number in radians or a string like \"pi/2\" or \"90deg\"")
            }
            fn visit_f64<E: serde::de::Error>(self, v: f64) -> Result<Angle, E> {
                if v.is_finite() {
                    Ok(Angle::Radians(v))
                } else {
                    Err(E::custom(format!("must be finite (got {v})")))
                }
            }
            fn visit_i64<E: serde::de::Error>(self, v: i64) -> Result<Angle, E> {
                Ok(Angle::Radians(v as f64))
            }
            fn visit_u64<E: serde::de::Error>(self, v: u64) -> Result<Angle, E> {
                Ok(Angle::Radians(v as f64))
            }
            fn visit_str<E: serde::de::Error>(self, v: &str) -> Result<Angle, E> {
                Angle::parse_str(v).map_err(E::custom)
            }
        }
        deserializer.deserialize_any(V)
    }
}
