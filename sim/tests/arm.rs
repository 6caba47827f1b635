//! Free motion of arms without a ball through the simulator: PUMA 560 falling under gravity
//! conserves its energy (no friction in the scene), and an iiwa 7 under a PD controller keeps
//! the energy balance E(t) − E(0) = ∫ τ·q̇ dt (to the accuracy of the trapezoidal quadrature of
//! the power between steps).

use bf_codegen::spec::Scene;
use bf_model::arm::ArmModel;
use bf_sim::arm::{ArmMode, FreeArm};
use bf_sim::{Input, PdController, SimError, SimSettings, simulate};

/// τ = 0.
struct Zero(usize);

impl Input for Zero {
    fn dim(&self) -> usize {
        self.0
    }
    fn tau(&self, _: f64, _: &[f64], _: &[f64], out: &mut [f64]) -> Result<(), SimError> {
        out.fill(0.0);
        Ok(())
    }
}

fn arm(text: &str) -> ArmModel {
    ArmModel::from_scene(&Scene::from_toml_str(text, "test").unwrap())
        .unwrap()
        .0
}

fn tight() -> SimSettings {
    SimSettings {
        rtol: 1e-10,
        atol: 1e-12,
        ..SimSettings::default()
    }
}

#[test]
fn puma_falling_under_gravity_conserves_energy() {
    let model = arm(include_str!("../../scenes/puma560.toml"));
    assert_eq!(model.mu_v(), 0.0);
    let sys = FreeArm::new(model, Zero(6)).unwrap();
    let x0 = [0.0, 0.3, -0.2, 0.1, 0.4, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0];
    let out = simulate(&sys, tight(), ArmMode::Free, 0.0, &x0, 1.0).unwrap();
    let rep = sys.report(&out, 0.0).unwrap();
    let s = &rep.summary;
    assert_eq!(s.t_final, 1.0);
    // it moves: the potential energy turned into kinetic energy
    let last = rep.samples.last().unwrap();
    assert!(
        last.qd.iter().map(|v| v * v).sum::<f64>() > 1e-2,
        "{:?}",
        last.qd
    );
    assert_eq!(s.work, 0.0);
    assert!(
        (s.energy_final - s.energy_initial).abs() < 1e-7 * (1.0 + s.energy_initial.abs()),
        "{s}"
    );
}

#[test]
fn iiwa_under_pd_control_keeps_the_energy_balance() {
    let model = arm(include_str!("../../scenes/iiwa7.toml"));
    let target = vec![0.5, -0.3, 0.2, 0.8, 0.0, 0.4, 0.1];
    let pd = PdController::new(vec![200.0; 7], vec![20.0; 7], target.clone()).unwrap();
    let sys = FreeArm::new(model, pd).unwrap();
    let x0 = [0.0; 14];
    let out = simulate(&sys, tight(), ArmMode::Free, 0.0, &x0, 1.0).unwrap();
    let rep = sys.report(&out, 0.0).unwrap();
    let s = &rep.summary;
    assert!(s.work.abs() > 1e-2, "the controller does work: {s}");
    // the trapezoidal ∫ P dt between accepted steps limits the balance to ~1e-6 relative
    assert!(s.energy_error < 1e-5 * (1.0 + s.work.abs()), "{s}");
    // input of the wrong size is refused
    let pd3 = PdController::new(vec![1.0; 3], vec![1.0; 3], vec![0.0; 3]).unwrap();
    let model = arm(include_str!("../../scenes/iiwa7.toml"));
    assert!(matches!(
        FreeArm::new(model, pd3),
        Err(SimError::DimensionMismatch { .. })
    ));
}
