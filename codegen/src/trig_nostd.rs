//! The mathematics a `#![no_std]` kernel module carries instead of the standard library's
//! (`generate --no-std`, [`crate::emit::EmitSettings::no_std`]): the square root, for `f64`
//! and `f32`, through the trait [`KernelMath`]. The kernels' calls `f64::sqrt(x)` and
//! `f32::sqrt(x)` resolve to the trait's method when `core` has no inherent method of that
//! name, so the kernel bodies are the same text in both modes. Sine and cosine need nothing
//! here: every generated file computes them with [`crate::trig`]'s own arithmetic, in either
//! mode. No paper equation: this is arithmetic (the contact quantities eq. 4, 11 and 58–59
//! need √).
//!
//! The square root [`sqrt_f64`] is computed digit by digit on the integer significand and is
//! correctly rounded, as IEEE `sqrt` is, so it equals `f64::sqrt` bit for bit. `f32` goes
//! through `f64` and rounds once: √ is then still correctly rounded (53 ≥ 2·24 + 2).
//!
//! The items below are emitted verbatim (private) into every no_std file; here they are
//! compiled and tested (`tests/trig.rs`, and `tests/no_std.rs` compiles emitted files with
//! `rustc` in a `#![no_std]` crate and compares with the standard library).

/// √x, correctly rounded (equal to IEEE `sqrt`): the significand's integer square root digit
/// by digit, one guard bit, no ties possible (an odd 54-bit root squared is odd, while the
/// radicand's low bits are zero). NaN for x < 0 and NaN; ±0 and +∞ are returned as they are.
pub fn sqrt_f64(x: f64) -> f64 {
    if x.is_nan() || x < 0.0 {
        return f64::NAN;
    }
    if x == 0.0 || x == f64::INFINITY {
        return x;
    }
    let bits = x.to_bits();
    let field = ((bits >> 52) & 0x7ff) as i64;
    let mut mant = bits & ((1u64 << 52) - 1);
    // x = mant · 2^exp with mant in [2⁵², 2⁵³).
    let mut exp = if field == 0 {
        let shift = mant.leading_zeros() as i64 - 11;
        mant <<= shift;
        -1074 - shift
    } else {
        mant |= 1 << 52;
        field - 1075
    };
    if exp & 1 != 0 {
        mant <<= 1;
        exp -= 1;
    }
    // n = mant · 2⁵⁴ in [2¹⁰⁶, 2¹⁰⁸): its root has 54 bits, one more than the result.
    let n = (mant as u128) << 54;
    let mut rem = n;
    let mut root: u128 = 0;
    let mut bit: u128 = 1 << 106;
    while bit > n {
        bit >>= 2;
    }
    while bit != 0 {
        if rem >= root + bit {
            rem -= root + bit;
            root = (root >> 1) + bit;
        } else {
            root >>= 1;
        }
        bit >>= 2;
    }
    // √x = root · 2^((exp − 54)/2) = (root/2) · 2^((exp − 52)/2); a carry of the rounding
    // into bit 53 moves into the exponent field, as it should.
    let q = (root >> 1) as u64;
    let guard = (root & 1) as u64;
    let field = ((exp - 52) / 2 + 52 + 1023) as u64;
    f64::from_bits((field << 52) + (q - (1 << 52)) + guard)
}

/// The square root for the kernels of a `#![no_std]` module (see the module documentation):
/// the kernels call it as `f64::sqrt(x)` and `f32::sqrt(x)`.
pub trait KernelMath: Sized {
    /// √x, correctly rounded.
    fn sqrt(self) -> Self;
}

impl KernelMath for f64 {
    fn sqrt(self) -> f64 {
        sqrt_f64(self)
    }
}

impl KernelMath for f32 {
    fn sqrt(self) -> f32 {
        sqrt_f64(self as f64) as f32
    }
}
