//! sin and cos of one joint coordinate, as emitted into every generated module.
//!
//! The generated kernels evaluate sin/cos only of single joint coordinates (DESIGN.md "Trig"),
//! typically 3–7 pairs per kernel, and with `f64::sin_cos` (two libm calls) those dominate
//! the cost of the small finger kernels. This is the fdlibm/musl algorithm: Cody–Waite
//! reduction by π/2 with a three-part π/2 (all three rounds, good to ~150 bits for
//! |x| < 2^20·π/2) and the fdlibm minimax kernels on [−π/4, π/4], computing both values from one
//! reduction. Error ≤ 1 ulp (tested against double-double); outside |x| < 1.6e6 and for
//! non-finite x it defers to `f64::sin_cos`. The emitter copies the item [`sin_cos`] verbatim
//! (as a private function) into each generated file, and the interpreter's f64 path calls it
//! too, so emitted kernels and the interpreter agree bit for bit.

/// (sin x, cos x) with ≤ 1 ulp error; fast path for |x| < 1.6e6.
#[inline]
pub fn sin_cos(x: f64) -> (f64, f64) {
    const TO_INT: f64 = 6755399441055744.0;
    const INV_PIO2: f64 = 6.36619772367581382433e-01;
    const PIO2_1: f64 = 1.57079632673412561417e+00;
    const PIO2_2: f64 = 6.07710050630396597660e-11;
    const PIO2_3: f64 = 2.02226624871116645580e-21;
    const PIO2_3T: f64 = 8.47842766036889956997e-32;
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
    if !(x.abs() < 1.6e6) {
        return f64::sin_cos(x);
    }
    if x.abs() < 7.450580596923828e-9 {
        // |x| < 2^-27: sin x = x and cos x = 1 to within rounding (keeps sin(−0) = −0).
        return (x, 1.0);
    }
    // n = rint(x / (π/2)) (round-to-nearest via 1.5·2^52). Then x − n·π/2 with π/2 split
    // into PIO2_1 + PIO2_2 + PIO2_3 (33 bits each, so n·PIO2_k is exact for n < 2^20) plus
    // PIO2_3T; the rounding errors of both subtractions are kept exactly (TwoSum).
    let f_n = (x * INV_PIO2 + TO_INT) - TO_INT;
    let n = f_n as i64;
    let r1 = x - f_n * PIO2_1;
    let w = -(f_n * PIO2_2);
    let r2 = r1 + w;
    let bp = r2 - r1;
    let e2 = (r1 - (r2 - bp)) + (w - bp);
    let w = -(f_n * PIO2_3);
    let r3 = r2 + w;
    let bp = r3 - r2;
    let e3 = (r2 - (r3 - bp)) + (w - bp);
    // Reduced argument = r3 + tail, as y0 + y1 with |y1| ≤ ulp(y0)/2.
    let tail = (e3 + e2) - f_n * PIO2_3T;
    let y0 = r3 + tail;
    let bp = y0 - r3;
    let y1 = (r3 - (y0 - bp)) + (tail - bp);
    // Kernels on [−π/4, π/4] with the tail y1.
    let z = y0 * y0;
    let zz = z * z;
    let rs = S2 + z * (S3 + z * S4) + z * zz * (S5 + z * S6);
    let v = z * y0;
    let s = y0 - ((z * (0.5 * y1 - v * rs) - y1) - v * S1);
    let rc = z * (C1 + z * (C2 + z * C3)) + zz * zz * (C4 + z * (C5 + z * C6));
    let hz = 0.5 * z;
    let wc = 1.0 - hz;
    let c = wc + (((1.0 - wc) - hz) + (z * rc - y0 * y1));
    match n & 3 {
        0 => (s, c),
        1 => (c, -s),
        2 => (-s, -c),
        _ => (-c, s),
    }
}
