//! The mathematics a `#![no_std]` kernel module carries instead of the standard library's
//! (`generate --no-std`, [`crate::emit::EmitSettings::no_std`]): square root, and sine and
//! cosine of one argument, for `f64` and `f32`, through the trait [`KernelMath`]. The kernels'
//! calls `f64::sqrt(x)`, `f64::sin_cos(x)`, `f32::sin(x)`, … resolve to the trait's methods
//! when `core` has no inherent method of that name, so the kernel bodies are the same text in
//! both modes. No paper equation: this is arithmetic (eq. 67–79 need sin/cos of the joint
//! angles, the contact quantities eq. 4, 11 and 58–59 need √).
//!
//! Sine and cosine are [`crate::trig::sin_cos_n`]'s, whose fast path needs no library; only
//! its fallback for the lanes next to a multiple of π/2 (`sin_cos_n_exact`, which calls
//! `f64::sin_cos` in the standard module) is replaced, by [`sin_cos_medium`]: fdlibm's
//! three-step Cody–Waite reduction (`__ieee754_rem_pio2` for |x| ≤ 2²⁰, 118 to 151 bits of
//! π/2), so those lanes stay within about 1 ulp; beyond |x| = 2²⁰ rad (and for non-finite x)
//! the result is NaN: no reduction without a table of 2/π, and no joint turns 10⁵ times.
//! The square root [`sqrt_f64`] is computed digit by digit on the integer significand and is
//! correctly rounded, as IEEE `sqrt` is, so it equals `f64::sqrt` bit for bit. `f32` goes
//! through `f64` and rounds once: √ is then still correctly rounded (53 ≥ 2·24 + 2), sine and
//! cosine within 1 ulp of `f32`.
//!
//! The items below are emitted verbatim (private, without the `use` lines) into every no_std
//! file; here they are compiled and tested (`tests/trig.rs`, and `tests/no_std.rs` compiles
//! emitted files with `rustc` in a `#![no_std]` crate and compares with the standard library).

use crate::trig::{sin_cos_lane, sin_cos_n};

/// The lanes of `sin_cos_n` outside its fast path, without the standard library: recomputed
/// by [`sin_cos_medium`].
#[cold]
#[inline(never)]
pub fn sin_cos_n_exact<const N: usize>(x: &[f64; N], sin: &mut [f64; N], cos: &mut [f64; N]) {
    for i in 0..N {
        if !sin_cos_lane(x[i]).2 {
            (sin[i], cos[i]) = sin_cos_medium(x[i]);
        }
    }
}

/// `(sin x, cos x)` for |x| ≤ 2²⁰ by fdlibm's medium-size reduction x = k·π/2 + (y₀ + y₁),
/// with π/2 in up to three parts so that y₀ + y₁ keeps its accuracy when x is next to a
/// multiple of π/2; NaN for larger or non-finite x.
pub fn sin_cos_medium(x: f64) -> (f64, f64) {
    const FRAC_2_PI: f64 = core::f64::consts::FRAC_2_PI;
    // fdlibm `__ieee754_rem_pio2`: pio2_1 (33 bits), pio2_1t = π/2 − pio2_1, pio2_2 (33 bits),
    // pio2_2t = π/2 − pio2_1 − pio2_2, pio2_3 (33 bits), pio2_3t.
    const PIO2_1: f64 = 1.57079632673412561417e+00;
    const PIO2_1T: f64 = 6.07710050650619224932e-11;
    const PIO2_2: f64 = 6.07710050630396597660e-11;
    const PIO2_2T: f64 = 2.02226624879595063154e-21;
    const PIO2_3: f64 = 2.02226624871116645580e-21;
    const PIO2_3T: f64 = 8.47842766036889956997e-32;
    const LIMIT: f64 = 1048576.0;
    if x.is_nan() || x.abs() > LIMIT {
        return (f64::NAN, f64::NAN);
    }
    // k = x·2/π rounded to an integer; |k| < 2²⁰, so k times a 33-bit part is exact.
    let k = {
        let shift = 6755399441055744.0;
        (x * FRAC_2_PI + shift) - shift
    };
    let exponent = |v: f64| ((v.to_bits() >> 52) & 0x7ff) as i32;
    let e = exponent(x);
    let mut r = x - k * PIO2_1;
    let mut w = k * PIO2_1T;
    let mut y0 = r - w;
    // One more part of π/2: r − k·part exactly, w the error of the tail and of that step.
    let step = |t: f64, part: f64, tail: f64| {
        let w = k * part;
        let r = t - w;
        let w = k * tail - ((t - r) - w);
        (r, w, r - w)
    };
    // Each step is needed when the previous one cancelled more than its spare bits.
    if e - exponent(y0) > 16 {
        (r, w, y0) = step(r, PIO2_2, PIO2_2T);
        if e - exponent(y0) > 49 {
            (r, w, y0) = step(r, PIO2_3, PIO2_3T);
        }
    }
    let y1 = (r - y0) - w;
    // |y0| ≤ π/4 (+ rounding of k), where the fast lane is accurate; y1 enters to first order
    // (y1² is below 2⁻¹⁰⁰ relative).
    let (s0, c0, _) = sin_cos_lane(y0);
    let (s, c) = (s0 + y1 * c0, c0 - y1 * s0);
    match (k as i64) & 3 {
        0 => (s, c),
        1 => (c, -s),
        2 => (-s, -c),
        _ => (-c, s),
    }
}

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

/// Square root, sine and cosine for the kernels of a `#![no_std]` module (see the module
/// documentation): the kernels call them as `f64::sqrt(x)`, `f32::sin_cos(x)`, ….
pub trait KernelMath: Sized {
    /// √x, correctly rounded.
    fn sqrt(self) -> Self;
    /// (sin x, cos x).
    fn sin_cos(self) -> (Self, Self);
    /// sin x.
    fn sin(self) -> Self {
        self.sin_cos().0
    }
    /// cos x.
    fn cos(self) -> Self {
        self.sin_cos().1
    }
}

impl KernelMath for f64 {
    fn sqrt(self) -> f64 {
        sqrt_f64(self)
    }
    fn sin_cos(self) -> (f64, f64) {
        let ([s], [c]) = sin_cos_n([self]);
        (s, c)
    }
}

impl KernelMath for f32 {
    fn sqrt(self) -> f32 {
        sqrt_f64(self as f64) as f32
    }
    fn sin_cos(self) -> (f32, f32) {
        let ([s], [c]) = sin_cos_n([self as f64]);
        (s as f32, c as f32)
    }
}
