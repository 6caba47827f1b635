//! The helper of the batched (`_x4`) node kernels: the sine and cosine of four lanes.
//!
//! A batched kernel evaluates four collocation nodes: its body is the scalar kernel's body
//! inside `for l in 0..4`, every value an `f64` of lane `l`, so each lane computes exactly the
//! scalar kernel's operations. With the nodes' entries interleaved (node `l`'s entry `k` at
//! `4·k + l`), every load and store of the loop is unit-stride in `l`, and LLVM's loop
//! vectoriser turns the loop into SIMD code (two lanes per SSE2 register on the baseline
//! x86-64 target) — stable Rust without `unsafe`. Calls inside the loop would keep it scalar,
//! so the sines and cosines of graph variables (the joint angles) are computed before the loop,
//! four lanes per angle, by [`sin_cos_lanes`]: [`crate::trig::sin_cos_n`], whose every lane
//! is bitwise [`crate::trig::sin_cos`] of that lane, as in the scalar kernels and the
//! interpreter that the node kernels must match bitwise.
//!
//! The function below is emitted verbatim into the generated file of the node kernels
//! ([`crate::nodefn::emit_node_kernels`]), beside the items of [`crate::trig`]; this module is
//! the one source, compiled and tested here.

use crate::trig::sin_cos_n;

/// [`crate::trig::sin_cos`] of each of four lanes, as arrays of sines and cosines.
#[inline(always)]
pub fn sin_cos_lanes(x: [f64; 4]) -> ([f64; 4], [f64; 4]) {
    sin_cos_n(x)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::trig::sin_cos;

    /// Each lane is the one-angle `sin_cos` of that lane, bit for bit, also next to a
    /// multiple of π/2 (the reduction's fallback) and beyond its range (NaN).
    #[test]
    fn lanes_are_the_one_angle_sin_cos_per_lane() {
        let x = [0.3, -1.7e5, f64::NAN, std::f64::consts::FRAC_PI_2];
        let (s, c) = sin_cos_lanes(x);
        for l in 0..4 {
            let (s1, c1) = sin_cos(x[l]);
            assert_eq!(s[l].to_bits(), s1.to_bits());
            assert_eq!(c[l].to_bits(), c1.to_bits());
        }
        let (s, c) = sin_cos_lanes([2e6, 1.0, -1.0, 0.0]);
        assert!(s[0].is_nan() && c[0].is_nan());
        assert_eq!((s[3], c[3]), (0.0, 1.0));
        assert!((s[1] + s[2]).abs() == 0.0 && c[1] == c[2]);
    }
}
