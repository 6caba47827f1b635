//! Fast sine and cosine of several angles at once, the helper the emitted f64 kernels call for
//! the joint angles (`docs/architecture.md`, "Trig": only sin/cos of single joint coordinates appear).
//!
//! [`sin_cos_n`] is branch-free over its lanes, so the compiler vectorises it across the
//! angles of a kernel: Cody–Waite reduction x = k·π/2 + r with π/2 split into four parts (the
//! first three with at most 32 significant bits, so k·Pᵢ is exact for |k| < 2²⁰), the reduced
//! argument kept as a double-double (hi + lo, accurate to ~2⁻¹¹⁵ absolute, below the smallest
//! |r| a double of magnitude ≤ 2²⁰ can have), and the minimax polynomials of fdlibm's
//! `__kernel_sin`/`__kernel_cos` on |r| ≤ π/4 (error < 1 ulp). Lanes next to a multiple of
//! π/2 fall back to fdlibm's three-step reduction ([`sin_cos_medium`]); beyond |x| = 2²⁰ rad
//! (no joint turns 10⁵ times) and for non-finite x the result is NaN.
//!
//! Every sine and cosine of the emitted kernels and of the interpreter is computed here
//! ([`sin_cos_n`] for the batched joint angles, [`sin_cos`] and [`sin_cos_f32`] for one
//! angle), with plain arithmetic: the platform's libm picks its variant by CPU (glibc uses FMA
//! where the CPU has it), and a kernel that called it would give other bits on another
//! machine.
//!
//! The functions below are emitted verbatim (as private items) into every generated scene
//! file that needs them, so a generated file stays self-contained; this module is the one
//! source, compiled and tested here (`tests/trig.rs`: ulp errors against the double-double
//! reference of [`crate::dd`] and against libm, random and next to multiples of π/2).
//! The polynomial coefficients and the π/2 parts are fdlibm's (Sun Microsystems, 1993:
//! "Permission to use, copy, modify, and distribute this software is freely granted, provided
//! that this notice is preserved").

/// `(sin x[i], cos x[i])` for every lane `i`, each within about 1 ulp of the exact value
/// (measured maximum in BENCHMARKS.md); lanes next to a multiple of π/2 are recomputed by
/// [`sin_cos_medium`], lanes with |x| > 2²⁰ or not finite are NaN. Every lane's result depends
/// on that lane's argument only.
#[inline(always)]
pub fn sin_cos_n<const N: usize>(x: [f64; N]) -> ([f64; N], [f64; N]) {
    let mut sin = [0.0; N];
    let mut cos = [0.0; N];
    let mut outside = false;
    for i in 0..N {
        let (s, c, fast) = sin_cos_lane(x[i]);
        sin[i] = s;
        cos[i] = c;
        outside |= !fast;
    }
    if outside {
        sin_cos_n_exact(&x, &mut sin, &mut cos);
    }
    (sin, cos)
}

/// One lane of [`sin_cos_n`]: `(sin x, cos x, fast)`, where `fast` is false if `x` is outside
/// the range in which the reduction below is accurate (the values are then meaningless).
#[inline(always)]
pub(crate) fn sin_cos_lane(xi: f64) -> (f64, f64, bool) {
    // 2/π and π/2 = PIO2_1 + PIO2_1T + O(2⁻⁸⁷) (fdlibm `__ieee754_rem_pio2`: pio2_1, pio2_1t).
    const FRAC_2_PI: f64 = std::f64::consts::FRAC_2_PI;
    const PIO2_1: f64 = 1.57079632673412561417e+00;
    const PIO2_1T: f64 = 6.07710050650619224932e-11;
    // 1.5·2⁵²: adding it rounds to an integer whose low mantissa bits are k (two's complement).
    const SHIFT: f64 = 6755399441055744.0;
    // Largest |x| of the fast path: |k| < 2²⁰, so k·PIO2_1 is exact.
    const LIMIT: f64 = 1048576.0;
    // 2⁻²⁸: lanes with |r| < |k|·CLOSE take the fallback.
    const CLOSE: f64 = 3.725290298461914e-9;
    const S1: f64 = -1.66666666666666324348e-01;
    const S2: f64 = 8.33333333332248946124e-03;
    const S3: f64 = -1.98412698298579493134e-04;
    const S4: f64 = 2.75573137070700676789e-06;
    const S5: f64 = -2.50507602534068634195e-08;
    const S6: f64 = 1.58969099521155010221e-10;
    const C1: f64 = 4.16666666666666019037e-02;
    const C2: f64 = -1.38888888888741095749e-03;
    const C3: f64 = 2.48015872894767294178e-05;
    const C4: f64 = -2.75573143513906633035e-07;
    const C5: f64 = 2.08757232129817482790e-09;
    const C6: f64 = -1.13596475577881948265e-11;
    // NaN compares false: not fast.
    let mut fast = xi.abs() <= LIMIT;
    let shifted = xi * FRAC_2_PI + SHIFT;
    let quadrant = shifted.to_bits();
    let k = shifted - SHIFT;
    // r = x − k·π/2 as hi + lo (fdlibm's first reduction step). x − k·PIO2_1 is exact
    // (for k ≠ 0 both are multiples of ulp(x) and the difference is below 1); the error of
    // hi + lo is that of k·PIO2_1T and of the tail of π/2 beyond it, < |k|·1.4e-26,
    // i.e. < 0.03 ulp of r unless |r| < |k|·2⁻²⁸: such lanes (next to a multiple of π/2)
    // go to the exact fallback.
    let a = xi - k * PIO2_1;
    let w = k * PIO2_1T;
    let hi = a - w;
    let lo = (a - hi) - w;
    fast &= hi.abs() >= k.abs() * CLOSE;
    // fdlibm __kernel_sin(hi, lo) and __kernel_cos(hi, lo), |hi| ≤ π/4 (+ rounding of k).
    let z = hi * hi;
    let w = z * z;
    let rs = S2 + z * (S3 + z * S4) + z * w * (S5 + z * S6);
    let v = z * hi;
    let sr = hi - ((z * (0.5 * lo - v * rs) - lo) - v * S1);
    let rc = z * (C1 + z * (C2 + z * C3)) + w * w * (C4 + z * (C5 + z * C6));
    let hz = 0.5 * z;
    let wc = 1.0 - hz;
    let cr = wc + (((1.0 - wc) - hz) + (z * rc - hi * lo));
    // Quadrant k mod 4: odd k swaps sin and cos; sin is negative for k ≡ 2, 3 and cos for
    // k ≡ 1, 2. Bit operations instead of branches keep the loop vectorisable.
    let swap = (quadrant & 1).wrapping_neg();
    let (sb, cb) = (sr.to_bits(), cr.to_bits());
    let sin_sign = (quadrant & 2) << 62;
    let cos_sign = (quadrant.wrapping_add(1) & 2) << 62;
    (
        f64::from_bits(((sb & !swap) | (cb & swap)) ^ sin_sign),
        f64::from_bits(((cb & !swap) | (sb & swap)) ^ cos_sign),
        fast,
    )
}

/// Largest |x| (rad) at which the kernels' sine and cosine are defined, 2²⁰: beyond it they
/// are NaN (the reduction by π/2 would lose its accuracy), so joint angles must lie within it.
pub const ANGLE_RANGE: f64 = 1048576.0;

/// The lanes of [`sin_cos_n`] outside the fast path (|x| > 2²⁰, next to a multiple of π/2,
/// or not finite), recomputed by [`sin_cos_medium`].
#[cold]
#[inline(never)]
fn sin_cos_n_exact<const N: usize>(x: &[f64; N], sin: &mut [f64; N], cos: &mut [f64; N]) {
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

/// `(sin x, cos x)` of one angle: the one lane of [`sin_cos_n`] (the kernels' sine and cosine
/// of anything but the batched joint angles, and the interpreter's).
#[inline(always)]
pub fn sin_cos(x: f64) -> (f64, f64) {
    let ([s], [c]) = sin_cos_n([x]);
    (s, c)
}

/// `(sin x[i], cos x[i])` in single precision for every lane: [`sin_cos_n`] of the lanes
/// widened, each result rounded once, so every lane is bitwise [`sin_cos_f32`] of that lane
/// (the f32 kernels' batch of joint angles).
#[inline(always)]
pub fn sin_cos_n_f32<const N: usize>(x: [f32; N]) -> ([f32; N], [f32; N]) {
    let (s, c) = sin_cos_n(x.map(|v| v as f64));
    (s.map(|v| v as f32), c.map(|v| v as f32))
}

/// `(sin x, cos x)` in single precision: [`sin_cos`] of `x` widened, each result rounded once
/// (within 1 ulp of `f32`).
#[inline(always)]
pub fn sin_cos_f32(x: f32) -> (f32, f32) {
    let (s, c) = sin_cos(x as f64);
    (s as f32, c as f32)
}
