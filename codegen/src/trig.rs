//! Fast sine and cosine of several angles at once, the helper the emitted f64 kernels call for
//! the joint angles (`docs/architecture.md`, "Trig": only sin/cos of single joint coordinates appear).
//!
//! [`sin_cos_n`] is branch-free over its lanes, so the compiler vectorises it across the
//! angles of a kernel: Cody–Waite reduction x = k·π/2 + r with π/2 split into four parts (the
//! first three with at most 32 significant bits, so k·Pᵢ is exact for |k| < 2²⁰), the reduced
//! argument kept as a double-double (hi + lo, accurate to ~2⁻¹¹⁵ absolute, below the smallest
//! |r| a double of magnitude ≤ 2²⁰ can have), and the minimax polynomials of fdlibm's
//! `__kernel_sin`/`__kernel_cos` on |r| ≤ π/4 (error < 1 ulp). For |x| > 2²⁰ and for
//! non-finite x a lane falls back to the standard library's `f64::sin_cos`.
//!
//! The functions below are emitted verbatim (as private items) into every generated scene
//! file that needs them, so a generated file stays self-contained; this module is the one
//! source, compiled and tested here (`tests/trig.rs`: ulp errors against the double-double
//! reference of [`crate::dd`] and against libm, random and next to multiples of π/2).
//! The polynomial coefficients and the π/2 parts are fdlibm's (Sun Microsystems, 1993:
//! "Permission to use, copy, modify, and distribute this software is freely granted, provided
//! that this notice is preserved").

/// `(sin x[i], cos x[i])` for every lane `i`, each within about 1 ulp of the exact value
/// (measured maximum in BENCHMARKS.md); lanes with |x| > 2²⁰, next to a multiple of π/2 or
/// not finite use `f64::sin_cos`. Every lane's result depends on that lane's argument only.
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

/// The lanes of [`sin_cos_n`] outside the fast path (|x| > 2²⁰, next to a multiple of π/2,
/// or not finite), recomputed by `f64::sin_cos`.
#[cold]
#[inline(never)]
fn sin_cos_n_exact<const N: usize>(x: &[f64; N], sin: &mut [f64; N], cos: &mut [f64; N]) {
    for i in 0..N {
        if !sin_cos_lane(x[i]).2 {
            (sin[i], cos[i]) = x[i].sin_cos();
        }
    }
}
