//! Free motion of arms without a ball through the simulator: PUMA 560 falling under gravity
//! conserves its energy (no friction in the scene), and an iiwa 7 under a PD controller keeps
//! the energy balance E(t) − E(0) = ∫ τ·q̇ dt (to the accuracy of the trapezoidal quadrature of
//! the power between steps).

use bf_codegen::spec::Scene;
use bf_model::arm::ArmModel;
use bf_sim::arm::{ArmMode, FreeArm};
use bf_sim::{Input, Method, PdController, SimError, SimSettings, simulate};

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
    assert_eq!(s.energy_check_failure(), None, "{s}");
}

/// The energy check holds an arm run to a share of the energy it moves: the PUMA's passive fall
/// passes with DOPRI5 at the default tolerance, and fails with RK4 at a step of 0.1 s, whose
/// balance error is of the order of that energy; the tolerance is the same for both runs up
/// to the motion they compute.
#[test]
fn a_coarse_arm_run_fails_its_energy_check() {
    let x0 = [0.0, 0.3, -0.2, 0.1, 0.4, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0];
    let run = |settings: SimSettings| {
        let sys = FreeArm::new(arm(include_str!("../../scenes/puma560.toml")), Zero(6)).unwrap();
        let out = simulate(&sys, settings, ArmMode::Free, 0.0, &x0, 5.0).unwrap();
        sys.report(&out, 0.0).unwrap().summary
    };
    let fine = run(SimSettings::default());
    let coarse = run(SimSettings {
        method: Method::Rk4 { h: 0.1 },
        ..SimSettings::default()
    });
    assert_eq!(fine.energy_check_failure(), None, "{fine}");
    assert!(fine.energy_error < 1e-3 * fine.energy_tolerance, "{fine}");
    assert!(
        coarse
            .energy_check_failure()
            .is_some_and(|w| w.contains("too coarse")),
        "{coarse}"
    );
    // The energy the fall moves (its kinetic energy) sets the tolerance: about the same for
    // both runs, and far below the coarse run's error.
    assert!(
        coarse.energy_error > 10.0 * coarse.energy_tolerance,
        "{coarse}"
    );
    let ratio = coarse.energy_tolerance / fine.energy_tolerance;
    assert!((0.5..2.0).contains(&ratio), "{coarse} / {fine}");
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
    assert_eq!(s.energy_check_failure(), None, "{s}");
    // input of the wrong size is refused
    let pd3 = PdController::new(vec![1.0; 3], vec![1.0; 3], vec![0.0; 3]).unwrap();
    let model = arm(include_str!("../../scenes/iiwa7.toml"));
    assert!(matches!(
        FreeArm::new(model, pd3),
        Err(SimError::DimensionMismatch { .. })
    ));
}
