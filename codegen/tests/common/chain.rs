//! Random standard-DH chains for the scaling measurement (`examples/scaling.rs`) and the tests
//! of the kernels whose algorithm is chosen by operation count.

use std::fmt::Write as _;

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

/// The scene file of a random standard-DH chain of `n` revolute joints (seed `n`) with the
/// given kernels: link lengths and offsets 0.05–0.4 m, twists anywhere in (−3.14, 3.14) rad,
/// masses 0.5–5 kg, COGs within 0.2 m of the frame origin, principal moments that satisfy the
/// triangle inequality.
pub fn chain_scene(n: usize, kernels: &[&str]) -> String {
    let mut rng = ChaCha8Rng::seed_from_u64(n as u64);
    let list: Vec<String> = kernels.iter().map(|k| format!("\"{k}\"")).collect();
    let mut s = format!(
        "name = \"chain{n}\"\ndh = \"standard\"\nkernels = [{}]\ngravity = [0.0, 0.0, -9.81]\n",
        list.join(", ")
    );
    for i in 0..n {
        let a: f64 = rng.random_range(0.05..0.4);
        let d: f64 = rng.random_range(0.05..0.4);
        // Not ±π: the chains of BENCHMARKS.md were drawn from this range.
        #[allow(clippy::approx_constant)]
        let alpha: f64 = rng.random_range(-3.14..3.14);
        let m: f64 = rng.random_range(0.5..5.0);
        let c: Vec<f64> = (0..3).map(|_| rng.random_range(-0.2..0.2)).collect();
        let i1: f64 = rng.random_range(0.01..0.1);
        let i2: f64 = rng.random_range(0.01..0.1);
        let i3: f64 = rng.random_range((i1 - i2).abs() + 0.001..i1 + i2);
        let _ = write!(
            s,
            "\n[[links]]\nname = \"l{i}\"\na = {a}\nalpha = {alpha}\nd = {d}\nmass = {m}\n\
             com = [{}, {}, {}]\ninertia = [{i1}, {i2}, {i3}]\n",
            c[0], c[1], c[2]
        );
    }
    s
}
