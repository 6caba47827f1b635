//! Shared by the controller's integration tests: a posture of the paper finger touching the
//! ball at a singular contact Jacobian, and the hybrid controller of the paper scene.

use bf_control::{HybridController, HybridGains, InverseDynamics, Reference};
use bf_model::{Kernels, Model, PaperKernels};

/// The paper finger's posture q = (−π/2, π, −π/2): link 2 folded back onto link 1, link 3
/// across the ball's near side, touching it (h = 0) where joint 1's axis (the world x axis
/// through the ball's centre) pierces it, so J_c e₁ = 0. The Newton-planned QC optimum of the
/// global search impacted there before decision 0033's conditioning row.
pub const TOUCHING: [f64; 3] = [
    -std::f64::consts::FRAC_PI_2,
    std::f64::consts::PI,
    -std::f64::consts::FRAC_PI_2,
];

/// The hybrid controller of the paper scene `model` with the default gains on `reference`,
/// starting at rest in `q` at time 0, and those gains.
pub fn controller(
    model: &Model<PaperKernels>,
    reference: Reference,
    q: [f64; 3],
) -> (HybridController<PaperKernels>, HybridGains) {
    let id = InverseDynamics::compiled(
        "paper",
        model.kernels().param_values(),
        model.params().mu_v(),
    )
    .unwrap();
    let gains = HybridGains::default();
    let x0: Vec<f64> = q.iter().copied().chain([0.0; 6]).collect();
    let law = HybridController::new(model.clone(), id, reference, gains, 0.0, &x0).unwrap();
    (law, gains)
}
