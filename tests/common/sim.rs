//! Fixtures shared by the simulator tests (`tests/simulate.rs`, `tests/simulate_cli.rs`): the
//! documented penetration tolerance and the scripted push on the compiled paper scene.

use bf_model::{State, Vec3, fixtures};
use bf_sim::TorqueSeries;

/// Documented penetration tolerance of the simulator (m): event location to 1e-12 s and
/// guard_zero_tol = 1e-9 bound how far h can go below zero at a stored sample.
pub const PENETRATION_TOL: f64 = 1e-9;

/// The scripted push: start 0.05 rad (along ∇h) off the ball at rest; hold the gravity torque
/// g(q_c) of the contact configuration plus a push −0.05 ∇ĥ into the ball; from 0.5 s to 1 s
/// ramp in a tangential torque J_cᵀ t (t ⟂ n) of size 0.2 until static friction gives way;
/// from 1.5 s pull back. Returns (x0, torque series).
pub fn scripted_push() -> ([f64; 9], TorqueSeries) {
    let model = fixtures::paper_scene().unwrap();
    let (qc, grad) = model
        .contact_configuration_near(Vec3::new(0.1, 0.5, 0.5), 1e-14, 100)
        .unwrap();
    let kin = model
        .evaluate(&State::new(qc, Vec3::zeros(), Vec3::zeros()))
        .unwrap();
    let dir = grad / grad.norm();
    let n = kin.contact.n;
    let jt = kin.contact.j_c.transpose() * n.cross(&Vec3::z()).normalize();
    let g = kin.cqd_g;
    let tau = |push: f64, tang: f64| {
        let v = g - dir * push + jt * tang;
        vec![v[0], v[1], v[2]]
    };
    let series = TorqueSeries::new(
        vec![0.0, 0.5, 1.0, 1.5, 1.51, 3.0],
        vec![
            tau(0.05, 0.0),
            tau(0.05, 0.0),
            tau(0.05, 0.2),
            tau(0.05, 0.2),
            tau(-0.1, 0.2),
            tau(-0.1, 0.0),
        ],
    )
    .unwrap();
    let x0 = State::new(qc + dir * 0.05, Vec3::zeros(), Vec3::zeros()).to_array();
    (x0, series)
}
