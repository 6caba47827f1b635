//! The hybrid controller on a finger with 4 joints (`scenes/paper4.toml`, compiled in): J_c is
//! 3 × 4, so the contact law's least constraint chooses the finger's acceleration in the
//! kernel of J_c, and its joint vectors are 4 long. At zero tracking error the law must give
//! the plant, on the controller's own model:
//! * in free motion, the planned acceleration q̈* (computed torque inverts eq. 26 through the
//!   generated inverse dynamics);
//! * in stick, the planned contact force λ* (eq. 29, 33: τ = M q̈ + C q̇ + g + μ_v q̇ − J_cᵀ λ
//!   with the q̈ the sticking contact allows).

use bf_control::reference::Samples;
use bf_control::{HybridController, HybridGains, InverseDynamics, Reference};
use bf_model::registry::CompiledKernels;
use bf_model::{Kernels, Mode, Model, State, Vec3, VecN};
use bf_sim::Input;

type Paper4 = Model<CompiledKernels<4>, 4>;

fn paper4() -> Paper4 {
    let entry = bf_generated::scene("paper4").expect("paper4 is compiled in");
    let kernels = CompiledKernels::<4>::from_entry(entry, entry.param_defaults.to_vec())
        .unwrap()
        .expect("paper4's contact kernels");
    Model::from_kernels(kernels).unwrap()
}

/// The posture (0.1, c, c, c) at which the finger, bent from straight by c at each of its
/// last three joints, first touches the ball (h = 0), by a scan and bisection on c.
fn touching(model: &Paper4) -> [f64; 4] {
    let q = |c: f64| [0.1, c, c, c];
    let h = |c: f64| {
        let s = State::new(VecN::from(q(c)), VecN::zeros(), Vec3::zeros());
        model.evaluate(&s).unwrap().contact.h
    };
    let (mut lo, mut hi) = (0.0, 0.0);
    for k in 0..300 {
        let c = 0.01 * k as f64;
        if h(c) > 0.0 && k > 0 && h(c - 0.01) <= 0.0 || h(c) <= 0.0 && k > 0 && h(c - 0.01) > 0.0 {
            (lo, hi) = (c - 0.01, c);
            break;
        }
    }
    assert!(hi > 0.0, "no touching posture found");
    let below = h(lo) <= 0.0;
    for _ in 0..80 {
        let mid = 0.5 * (lo + hi);
        if (h(mid) <= 0.0) == below {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    q(0.5 * (lo + hi))
}

/// The reference of one phase of 0.05 s at rest in `q` with torques `tau` (and, in contact,
/// the force `lambda`), the ball at rest.
fn resting(model: &Paper4, q: [f64; 4], contact: bool, tau: VecN<4>, lambda: Vec3) -> Reference<4> {
    let two = |v: Vec<f64>| vec![v.clone(), v];
    Reference::from_samples(
        model,
        &[contact],
        &[0.05],
        Samples {
            t: &[0.0, 0.05],
            phase: &[0, 0],
            q: &two(q.to_vec()),
            qd: &two(vec![0.0; 4]),
            omega: &two(vec![0.0; 3]),
            tau: &two(tau.iter().copied().collect()),
            lambda: &two(lambda.iter().copied().collect()),
        },
        [0.0; 3],
    )
    .unwrap()
}

fn controller(
    model: &Paper4,
    reference: Reference<4>,
    q: [f64; 4],
) -> HybridController<CompiledKernels<4>, 4> {
    let id = InverseDynamics::compiled(
        "paper4",
        model.kernels().param_values(),
        model.params().mu_v(),
    )
    .unwrap();
    let x0: Vec<f64> = q.iter().copied().chain([0.0; 7]).collect();
    HybridController::new(
        model.clone(),
        id,
        reference,
        HybridGains::default(),
        0.0,
        &x0,
    )
    .unwrap()
}

#[test]
fn at_zero_error_a_4_joint_finger_gets_the_planned_acceleration_and_force() {
    let model = paper4();
    let q = touching(&model);
    let rest = State::new(VecN::from(q), VecN::zeros(), Vec3::zeros());
    let c = model.evaluate(&rest).unwrap().contact;
    assert!(c.h.abs() < 1e-9, "h = {}", c.h);

    // Stick: the plan presses the ball with τ* = 0.3 J_cᵀ(−n) plus gravity's torques.
    let gravity = model.evaluate(&rest).unwrap().cqd_g;
    let tau_star = gravity - (c.j_c.transpose() * c.n) * 0.3;
    let planned = model.stick(&rest, &tau_star).unwrap();
    assert!(planned.force.lambda_n > 0.0, "{:?}", planned.force);
    let law = controller(
        &model,
        resting(&model, q, true, tau_star, planned.force.lambda),
        q,
    );
    let mut tau = [0.0; 4];
    law.tau_in_mode(Mode::Stick, 0.0, &q, &[0.0; 4], &[0.0; 3], &mut tau)
        .unwrap();
    let plant = model.stick(&rest, &VecN::from(tau)).unwrap();
    let force_error =
        (plant.force.lambda - planned.force.lambda).norm() / planned.force.lambda.norm();
    // The least constraint's damping (δ² = 10⁻³ tr W / 3) is all that separates them.
    assert!(
        force_error < 1e-2,
        "λ = {}, λ* = {} ({force_error:e})",
        plant.force.lambda,
        planned.force.lambda
    );

    // Free: a posture more than the clearance guard's 5 mm off the ball (the guard would
    // push the finger away below it), falling under half its gravity torques; the computed
    // torque gives back q̈* to the rounding of the kernels.
    let q = [0.1, -0.4, -0.4, -0.4];
    let rest = State::new(VecN::from(q), VecN::zeros(), Vec3::zeros());
    let kin = model.evaluate(&rest).unwrap();
    assert!(kin.contact.h > 0.05, "h = {}", kin.contact.h);
    let tau_free = kin.cqd_g * 0.5;
    let free_plan = model.free(&rest, &tau_free).unwrap();
    let law = controller(
        &model,
        resting(&model, q, false, tau_free, Vec3::zeros()),
        q,
    );
    let mut tau = [0.0; 4];
    law.tau_in_mode(Mode::Free, 0.0, &q, &[0.0; 4], &[0.0; 3], &mut tau)
        .unwrap();
    let got = model.free(&rest, &VecN::from(tau)).unwrap().qdd;
    let err = (got - free_plan.qdd).norm() / (1.0 + free_plan.qdd.norm());
    assert!(err < 1e-9, "q̈ = {got}, q̈* = {} ({err:e})", free_plan.qdd);
}

/// [`InverseDynamics::from_model`] (M q̈ + C q̇ + g + μ_v q̇ from the controller's model, for
/// scenes without a generated `inverse_dynamics`) gives the generated kernel's torque: the
/// free law of the same controller, off the ball and off the plan, commands the same τ with
/// either, to rounding.
#[test]
fn the_model_s_inverse_dynamics_is_the_generated_kernel_s() {
    let model = paper4();
    let q = [0.1, -0.4, -0.4, -0.4];
    let rest = State::new(VecN::from(q), VecN::zeros(), Vec3::zeros());
    let gravity = model.evaluate(&rest).unwrap().cqd_g;
    let plan = || resting(&model, q, false, gravity * 0.5, Vec3::zeros());
    let compiled = controller(&model, plan(), q);
    let x0: Vec<f64> = q.iter().copied().chain([0.0; 7]).collect();
    let id = InverseDynamics::from_model(4, model.params().mu_v());
    assert!(!id.is_compiled());
    let from_model =
        HybridController::new(model.clone(), id, plan(), HybridGains::default(), 0.0, &x0).unwrap();
    // A plant off the plan: displaced and moving, so every term of ID is exercised.
    let (qp, qdp) = ([0.15, -0.35, -0.45, -0.38], [0.3, -0.2, 0.5, -0.4]);
    let (mut a, mut b) = ([0.0; 4], [0.0; 4]);
    compiled
        .tau_in_mode(Mode::Free, 0.01, &qp, &qdp, &[0.0; 3], &mut a)
        .unwrap();
    from_model
        .tau_in_mode(Mode::Free, 0.01, &qp, &qdp, &[0.0; 3], &mut b)
        .unwrap();
    let (a, b) = (VecN::<4>::from(a), VecN::<4>::from(b));
    assert!(
        (a - b).norm() <= 1e-12 * (1.0 + a.norm()),
        "generated {a}, from the model {b}"
    );
    // Not trivially equal: the torque (no bound set) is the feedback's, well away from zero.
    assert!(a.norm() > 1e-3, "τ = {a}");
}
