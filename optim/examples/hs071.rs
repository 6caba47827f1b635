//! Solving your own NLP with `bf_optim::ipm`: Hock–Schittkowski problem 71, the example Ipopt's
//! documentation uses.
//!
//! ```text
//! min  x₁ x₄ (x₁ + x₂ + x₃) + x₃
//! s.t. x₁ x₂ x₃ x₄ ≥ 25
//!      x₁² + x₂² + x₃² + x₄² = 40
//!      1 ≤ xᵢ ≤ 5,   x⁰ = (1, 5, 5, 1)
//! ```
//!
//! The optimum is x* ≈ (1, 4.743, 3.821, 1.379), f* ≈ 17.014017. A problem is a type that
//! implements [`Nlp`]: sizes, bounds, the starting point, f, ∇f, g, the sparse Jacobian of g
//! (pattern once, values per call) and the lower triangle of the Hessian of the Lagrangian
//! σ_f ∇²f + Σ λᵢ ∇²gᵢ. `check_derivatives` compares all three against central differences
//! before you trust a hand-written derivative.
//!
//! Run it: `cargo run --release -p bf-optim --example hs071`.

use bf_optim::OptimError;
use bf_optim::ipm::{DerivativeReport, Nlp, Settings, Solution, Status, check_derivatives, solve};

/// HS071 as an [`Nlp`]: 4 variables, 2 constraints, dense 2 × 4 Jacobian, dense 4 × 4 Hessian.
pub struct Hs071;

impl Nlp for Hs071 {
    fn num_variables(&self) -> usize {
        4
    }
    fn num_constraints(&self) -> usize {
        2
    }
    fn variable_bounds(&self, lower: &mut [f64], upper: &mut [f64]) {
        lower.fill(1.0);
        upper.fill(5.0);
    }
    fn constraint_bounds(&self, lower: &mut [f64], upper: &mut [f64]) {
        // g₁ ≥ 25 (no upper bound: any |value| ≥ 1e19 is infinite), g₂ = 40 (equal bounds).
        lower.copy_from_slice(&[25.0, 40.0]);
        upper.copy_from_slice(&[2e19, 40.0]);
    }
    fn initial_point(&self, x: &mut [f64]) {
        x.copy_from_slice(&[1.0, 5.0, 5.0, 1.0]);
    }
    fn objective(&self, x: &[f64]) -> f64 {
        x[0] * x[3] * (x[0] + x[1] + x[2]) + x[2]
    }
    fn gradient(&self, x: &[f64], grad: &mut [f64]) {
        let s = x[0] + x[1] + x[2];
        grad[0] = x[3] * (s + x[0]);
        grad[1] = x[0] * x[3];
        grad[2] = x[0] * x[3] + 1.0;
        grad[3] = x[0] * s;
    }
    fn constraints(&self, x: &[f64], g: &mut [f64]) {
        g[0] = x[0] * x[1] * x[2] * x[3];
        g[1] = x.iter().map(|v| v * v).sum();
    }
    fn jacobian_structure(&self) -> Vec<(usize, usize)> {
        (0..2).flat_map(|r| (0..4).map(move |c| (r, c))).collect()
    }
    fn jacobian_values(&self, x: &[f64], values: &mut [f64]) {
        let p = |skip: usize| (0..4).filter(|&i| i != skip).map(|i| x[i]).product::<f64>();
        for c in 0..4 {
            values[c] = p(c);
            values[4 + c] = 2.0 * x[c];
        }
    }
    fn hessian_structure(&self) -> Vec<(usize, usize)> {
        (0..4).flat_map(|r| (0..=r).map(move |c| (r, c))).collect()
    }
    fn hessian_values(&self, x: &[f64], obj_factor: f64, lambda: &[f64], values: &mut [f64]) {
        // ∂²(x_r x_c Π_others)/∂x_r∂x_c = product of the two remaining variables.
        let pair = |r: usize, c: usize| {
            (0..4)
                .filter(|&i| i != r && i != c)
                .map(|i| x[i])
                .product::<f64>()
        };
        let mut k = 0;
        for r in 0..4 {
            for c in 0..=r {
                let f = match (r, c) {
                    (0, 0) => 2.0 * x[3],
                    (1, 0) | (2, 0) => x[3],
                    (3, 0) => 2.0 * x[0] + x[1] + x[2],
                    (3, 1) | (3, 2) => x[0],
                    _ => 0.0,
                };
                let g1 = if r == c { 0.0 } else { pair(r, c) };
                let g2 = if r == c { 2.0 } else { 0.0 };
                values[k] = obj_factor * f + lambda[0] * g1 + lambda[1] * g2;
                k += 1;
            }
        }
    }
}

/// Checks the hand-written derivatives at an interior point (against central differences),
/// then solves HS071 with the default settings.
pub fn run() -> Result<(DerivativeReport, Solution), OptimError> {
    let report = check_derivatives(&Hs071, &[1.5, 4.0, 3.5, 1.2], 1.0, &[0.7, -0.3], 1e-6);
    Ok((report, solve(&Hs071, &Settings::default())?))
}

#[allow(dead_code)] // `main` is unused when a test includes this file as a module.
fn main() -> Result<(), OptimError> {
    let (report, sol) = run()?;
    println!(
        "derivative check: worst relative error {:.1e}",
        report.max_error()
    );
    println!(
        "{:?} after {} iterations: f = {:.9}, x = {:?}",
        sol.status, sol.iterations, sol.objective, sol.x
    );
    println!("multipliers of g (L = f + λᵀg): {:?}", sol.lambda);
    if sol.status != Status::Solved || report.max_error() > 1e-6 {
        std::process::exit(1);
    }
    Ok(())
}
