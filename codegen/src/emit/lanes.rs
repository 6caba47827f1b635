//! The helper of the batched (`_x4`) node kernels: the standard library's sine and cosine of
//! four lanes.
//!
//! A batched kernel evaluates four collocation nodes: its body is the scalar kernel's body
//! inside `for l in 0..4`, every value an `f64` of lane `l`, so each lane computes exactly the
//! scalar kernel's operations. With the nodes' entries interleaved (node `l`'s entry `k` at
//! `4·k + l`), every load and store of the loop is unit-stride in `l`, and LLVM's loop
//! vectoriser turns the loop into SIMD code (two lanes per SSE2 register on the baseline
//! x86-64 target) — stable Rust without `unsafe`. Calls inside the loop would keep it scalar,
//! so the sines and cosines of graph variables (the joint angles) are computed before the loop,
//! four lanes per angle, by [`sin_cos_lanes`]: the standard library's, as in the interpreter
//! that the node kernels must match bitwise.
//!
//! The function below is emitted verbatim into the generated file of the node kernels
//! ([`crate::nodefn::emit_node_kernels`]); this module is the one source, compiled and tested
//! here.

/// `f64::sin_cos` of each of four lanes, as arrays of sines and cosines.
#[inline(always)]
pub fn sin_cos_lanes(x: [f64; 4]) -> ([f64; 4], [f64; 4]) {
    let mut s = [0.0; 4];
    let mut c = [0.0; 4];
    for l in 0..4 {
        (s[l], c[l]) = x[l].sin_cos();
    }
    (s, c)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Each lane is the standard library's `sin_cos`, and `sin`/`cos` alone give the same
    /// bits (a scalar kernel that needs only one of them calls `f64::sin` or `f64::cos`).
    #[test]
    fn lanes_are_the_standard_library_per_lane() {
        let x = [0.3, -1.7e5, f64::NAN, std::f64::consts::FRAC_PI_2];
        let (s, c) = sin_cos_lanes(x);
        for l in 0..4 {
            let (s1, c1) = x[l].sin_cos();
            assert_eq!(s[l].to_bits(), s1.to_bits());
            assert_eq!(c[l].to_bits(), c1.to_bits());
            assert_eq!(s[l].to_bits(), x[l].sin().to_bits());
            assert_eq!(c[l].to_bits(), x[l].cos().to_bits());
        }
    }
}
