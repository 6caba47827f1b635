//! The contact law where the contact Jacobian J_c is singular: on the paper finger, joint 1's
//! axis passes through the ball's centre, so with the fingertip on the ball where that axis
//! pierces it, turning joint 1 does not move the contact point (J_c e₁ = 0). Newton-planned
//! optima stick there (docs/decisions/0033-newton-impact-plan.md), and the law's former
//! q̈ = J_c⁻¹ a_c sent joint 1 to 1/σ_min(J_c): its torque grew to 10¹⁰ N m.
//!
//! At such a posture, with joint 1 turning (a motion that keeps the contact sticking), the
//! controller's torque is asserted against the plant's own stick dynamics (eq. 29, 33):
//! * it is of the order of the planned torques (not 1/σ_min);
//! * under it the plant's contact force is the planned one (the feedback is zero there);
//! * along joint 1, which the contact does not constrain, the finger accelerates as the free
//!   law's tracking asks: (M q̈)₁ − (M q̈*)₁ = M₁₁ K_d (q̇₁* − q̇₁), the computed-torque law's
//!   closed form in the one direction where the contact exerts no torque.

use bf_control::Reference;
use bf_control::reference::Samples;
use bf_model::{Mode, State, Vec3, VecN};
use bf_sim::Input;

mod common;

use common::TOUCHING as SINGULAR;

#[test]
fn joint_motion_that_keeps_the_contact_point_follows_the_free_law() {
    let model = bf_model::fixtures::paper_scene().unwrap();
    let q = SINGULAR;
    let rest = State::new(VecN::from(q), VecN::zeros(), Vec3::zeros());
    let kin = model.evaluate(&rest).unwrap();
    let c = &kin.contact;
    assert!(c.h.abs() < 1e-12, "h = {}", c.h);
    // The posture is singular: joint 1 does not move the contact point.
    let col1 = Vec3::new(c.j_c[(0, 0)], c.j_c[(1, 0)], c.j_c[(2, 0)]);
    assert!(col1.norm() < 1e-6 * c.j_c.norm(), "J_c e1 = {col1}");
    // The plan: resting there, pressing the ball with τ* = 0.3 J_cᵀ(−n) (a force into the ball).
    let tau_star = -(c.j_c.transpose() * c.n) * 0.3;
    let planned = model.stick(&rest, &tau_star).unwrap();
    assert!(planned.force.lambda_n > 0.0, "{:?}", planned.force);
    let lambda_star = planned.force.lambda;
    let sample = |v: [f64; 3]| vec![v.to_vec(), v.to_vec()];
    let (t, phase) = (vec![0.0, 0.05], vec![0, 0]);
    let (qs, zeros) = (sample(q), sample([0.0; 3]));
    let taus = sample([tau_star[0], tau_star[1], tau_star[2]]);
    let lambdas = sample([lambda_star[0], lambda_star[1], lambda_star[2]]);
    let reference = Reference::from_samples(
        &model,
        &[true],
        &[0.05],
        Samples {
            t: &t,
            phase: &phase,
            q: &qs,
            qd: &zeros,
            omega: &zeros,
            tau: &taus,
            lambda: &lambdas,
        },
        [0.0; 3],
    )
    .unwrap();
    let (law, gains) = common::controller(&model, reference, q);
    // The plant turns joint 1 at 0.3 rad/s: the contact point stays where it is (Δv = 0).
    let qd = [0.3, 0.0, 0.0];
    let moving = State::new(VecN::from(q), VecN::from(qd), Vec3::zeros());
    assert!(model.evaluate(&moving).unwrap().contact.delta_v.norm() < 1e-6);
    let mut tau = [0.0; 3];
    law.tau_in_mode(Mode::Stick, 0.0, &q, &qd, &[0.0; 3], &mut tau)
        .unwrap();
    let tau = VecN::from(tau);
    let scale = tau_star.norm() + 1.0;
    assert!(tau.norm() < 5.0 * scale, "τ = {tau} (τ* = {tau_star})");
    let plant = model.stick(&moving, &tau).unwrap();
    // The contact force is the planned one (what the normal and ω loops ask for at zero
    // error), to the damping of the least-constraint solve.
    let force_error = (plant.force.lambda - lambda_star).norm() / lambda_star.norm();
    assert!(
        force_error < 0.05,
        "λ = {}, λ* = {lambda_star}",
        plant.force.lambda
    );
    // Along joint 1 the contact exerts no torque (J_c e₁ = 0), so the first row of the
    // plant's M q̈ is τ₁ − (C q̇ + g + μ_v q̇)₁, and the free law's command is met there
    // exactly: (M q̈)₁ − (M q̈*)₁ = M₁₁ K_d (q̇₁* − q̇₁), q̈* the plan's (at rest).
    let m = &kin.m_f;
    let row = |qdd: &VecN<3>| (m * qdd)[0];
    let got = row(&plant.qdd) - row(&planned.qdd);
    let want = m[(0, 0)] * gains.free.kd() * (0.0 - qd[0]);
    assert!(
        (got - want).abs() < 1e-3 * want.abs(),
        "(M q̈)₁ − (M q̈*)₁ = {got}, the free law's {want}"
    );
}
